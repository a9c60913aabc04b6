//! The report of an inspection run: `summary.json`, `summary.csv`,
//! `index.html` (a sortable table of the parts, worst first, with
//! thumbnails) and one `parts/ID/index.html` per part — static pages that
//! open from disk with no server and no network. The same records give
//! the same bytes: nothing here depends on time, order of completion or
//! the number of workers.

use super::part::{PartRecord, Status};
use serde_json::{Value, json};
use std::cmp::Ordering;
use std::fmt::Write as _;
use std::path::Path;

/// The records ranked as the report lists them: failed parts first, then
/// by worst severity (highest first), then by number of regions, then by
/// path.
pub fn ranked(records: &[PartRecord]) -> Vec<&PartRecord> {
    let mut v: Vec<&PartRecord> = records.iter().collect();
    v.sort_by(|a, b| {
        let failed = |r: &PartRecord| r.status != Status::Ok;
        failed(b)
            .cmp(&failed(a))
            .then_with(|| {
                let s = |r: &PartRecord| r.numbers.worst_severity.unwrap_or(f64::NEG_INFINITY);
                s(b).partial_cmp(&s(a)).unwrap_or(Ordering::Equal)
            })
            .then_with(|| b.numbers.regions.cmp(&a.numbers.regions))
            .then_with(|| a.spec.path.cmp(&b.spec.path))
    });
    v
}

/// The verdict of a part in a few words, what the table's first column
/// and the terminal say.
pub fn verdict(r: &PartRecord) -> String {
    match r.status {
        Status::Error => return "error".into(),
        Status::Timeout => return "timed out".into(),
        Status::OutOfMemory => return "out of memory".into(),
        Status::Ok => {}
    }
    let n = &r.numbers;
    let not_judged = n.not_judged.unwrap_or(0.0);
    let regions = n.regions.unwrap_or(0);
    let mut v = if regions > 0 {
        format!("{regions} region(s)")
    } else {
        "no region".to_string()
    };
    if not_judged >= 0.5 {
        v = format!("not judged: {:.0} % of the part; {v}", 100.0 * not_judged);
    } else if not_judged >= 0.05 {
        v.push_str(&format!(" ({:.0} % not judged)", 100.0 * not_judged));
    }
    v
}

/// Counts of the run for the summary and the terminal.
pub fn totals(records: &[PartRecord]) -> Value {
    let count = |f: &dyn Fn(&PartRecord) -> bool| records.iter().filter(|r| f(r)).count();
    json!({
        "parts": records.len(),
        "with_regions": count(&|r| r.status == Status::Ok && r.numbers.regions.unwrap_or(0) > 0),
        "mostly_not_judged": count(&|r| r.status == Status::Ok && r.numbers.not_judged.unwrap_or(0.0) >= 0.5),
        "failed": count(&|r| r.status != Status::Ok),
        "warnings": records.iter().map(|r| r.numbers.warnings).sum::<u64>(),
    })
}

/// Writes `summary.json`, `summary.csv`, `index.html` and each part's
/// page into `dir` (atomically, file by file).
pub fn write_report(dir: &Path, records: &[PartRecord], ignored: usize) -> anyhow::Result<()> {
    let ranked = ranked(records);
    let summary = json!({
        "fairline": env!("CARGO_PKG_VERSION"),
        "schema": super::SCHEMA,
        "totals": totals(records),
        "files_left_out": ignored,
        "parts": ranked.iter().map(|r| summary_row(r)).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&summary)? + "\n";
    write_file(&dir.join("summary.json"), text.as_bytes())?;
    write_file(&dir.join("summary.csv"), csv(&ranked).as_bytes())?;
    write_file(
        &dir.join("index.html"),
        index_html(&ranked, records, ignored).as_bytes(),
    )?;
    for r in records {
        let page = part_html(dir, r);
        write_file(
            &dir.join("parts").join(&r.spec.id).join("index.html"),
            page.as_bytes(),
        )?;
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically.
fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    use std::io::Write;
    fairline::io::atomic_write(path, |w| w.write_all(bytes))?;
    Ok(())
}

fn summary_row(r: &PartRecord) -> Value {
    json!({
        "path": r.spec.path,
        "id": r.spec.id,
        "kind": r.spec.kind,
        "status": r.status,
        "verdict": verdict(r),
        "error": r.error,
        "numbers": r.numbers,
        "report": format!("parts/{}/part.json", r.spec.id),
    })
}

const CSV_COLUMNS: &str = "path,kind,status,verdict,regions,worst_severity,best_score,not_judged_percent,vertices,faces,surfaces,repaired,warnings,report,error";

fn csv(ranked: &[&PartRecord]) -> String {
    let mut out = String::from(CSV_COLUMNS);
    out.push('\n');
    for r in ranked {
        let n = &r.numbers;
        let num = |v: Option<f64>| v.map(|x| format!("{x:.4}")).unwrap_or_default();
        let int = |v: Option<u64>| v.map(|x| x.to_string()).unwrap_or_default();
        let cells = [
            csv_cell(&r.spec.path.to_string_lossy()),
            r.spec.kind.name().to_string(),
            status_name(r.status).into(),
            csv_cell(&verdict(r)),
            int(n.regions),
            num(n.worst_severity),
            num(n.best_score),
            num(n.not_judged.map(|x| 100.0 * x)),
            int(n.vertices),
            int(n.faces),
            int(n.surfaces),
            n.repaired.to_string(),
            n.warnings.to_string(),
            format!("parts/{}/part.json", r.spec.id),
            csv_cell(r.error.as_deref().unwrap_or("")),
        ];
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

fn status_name(s: Status) -> &'static str {
    match s {
        Status::Ok => "ok",
        Status::Error => "error",
        Status::Timeout => "timeout",
        Status::OutOfMemory => "out-of-memory",
    }
}

fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `s` escaped for HTML text and attribute values.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

const STYLE: &str = "body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;color:#222}\
table{border-collapse:collapse}th,td{padding:4px 8px;border-bottom:1px solid #ddd;text-align:left;vertical-align:middle}\
th{cursor:pointer;background:#f4f4f4;position:sticky;top:0}th:hover{background:#e8e8e8}\
td.n{text-align:right;font-variant-numeric:tabular-nums}.bad{color:#b00;font-weight:600}.warn{color:#a60}.ok{color:#070}\
img.t{width:160px;border:1px solid #ccc}img.p{max-width:100%;border:1px solid #ccc}code{background:#f4f4f4;padding:1px 3px}\
pre{background:#f4f4f4;padding:8px;overflow-x:auto}";

/// Sorting by a click on a column head; numbers sort as numbers.
const SORT_SCRIPT: &str = "document.querySelectorAll('th').forEach((th,i)=>th.addEventListener('click',()=>{\
const tb=th.closest('table').tBodies[0];const rows=[...tb.rows];const dir=th.dataset.dir==='a'?'d':'a';th.dataset.dir=dir;\
const key=r=>{const c=r.cells[i];const v=c.dataset.v!==undefined?c.dataset.v:c.textContent;const x=parseFloat(v);return isNaN(x)?v.toLowerCase():x};\
rows.sort((a,b)=>{const x=key(a),y=key(b);const c=(typeof x==='number'&&typeof y==='number')?x-y:String(x).localeCompare(String(y));return dir==='a'?c:-c});\
rows.forEach(r=>tb.appendChild(r))}));";

fn class_of(r: &PartRecord) -> &'static str {
    if r.status != Status::Ok {
        "bad"
    } else if r.numbers.regions.unwrap_or(0) > 0 || r.numbers.not_judged.unwrap_or(0.0) >= 0.5 {
        "warn"
    } else {
        "ok"
    }
}

fn index_html(ranked: &[&PartRecord], records: &[PartRecord], ignored: usize) -> String {
    let t = totals(records);
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>fairline inspection</title><style>{STYLE}</style></head><body>\n\
<h1>fairline inspection: {} part(s)</h1>\n<p>{} with suggested fairing regions, {} mostly not judged, {} failed, {} warning(s){}. \
Worst first; click a column head to sort. Severity: how far a region's strongest site exceeds its measure's threshold \
(1 = at the threshold). Not judged: share of the part's area that detection could not judge (shape finer than the scale of its finest light array, mesh boundary).</p>\n",
        t["parts"],
        t["with_regions"],
        t["mostly_not_judged"],
        t["failed"],
        t["warnings"],
        if ignored > 0 {
            format!("; {ignored} file(s) of other types in the folders left out")
        } else {
            String::new()
        }
    );
    h.push_str("<table><thead><tr><th>picture</th><th>part</th><th>kind</th><th>verdict</th><th>regions</th><th>worst severity</th><th>best score</th><th>not judged %</th><th>vertices</th><th>faces</th><th>warnings</th></tr></thead><tbody>\n");
    for (rank, r) in ranked.iter().enumerate() {
        let n = &r.numbers;
        let link = format!("parts/{}/index.html", esc(&r.spec.id));
        let thumb = if r.pictures.iter().any(|p| p == "thumb.png") {
            format!(
                "<a href=\"{link}\"><img class=\"t\" src=\"parts/{}/thumb.png\" alt=\"\"></a>",
                esc(&r.spec.id)
            )
        } else {
            String::new()
        };
        let num = |v: Option<f64>, d: usize| {
            v.map(|x| format!("<td class=\"n\" data-v=\"{x}\">{x:.d$}</td>"))
                .unwrap_or_else(|| "<td class=\"n\" data-v=\"-1\">–</td>".into())
        };
        let int = |v: Option<u64>| {
            v.map(|x| format!("<td class=\"n\">{x}</td>"))
                .unwrap_or_else(|| "<td class=\"n\" data-v=\"-1\">–</td>".into())
        };
        let _ = writeln!(
            h,
            "<tr><td data-v=\"{rank}\">{thumb}</td><td><a href=\"{link}\">{}</a></td><td>{}</td><td class=\"{}\">{}</td>{}{}{}{}{}{}{}</tr>",
            esc(&r.spec.path.to_string_lossy()),
            r.spec.kind.label(),
            class_of(r),
            esc(&verdict(r)),
            int(n.regions),
            num(n.worst_severity, 2),
            num(n.best_score, 2),
            num(n.not_judged.map(|x| 100.0 * x), 0),
            int(n.vertices),
            int(n.faces),
            int(Some(n.warnings)),
        );
    }
    let _ = write!(
        h,
        "</tbody></table>\n<p>Machine-readable: <a href=\"summary.json\">summary.json</a>, <a href=\"summary.csv\">summary.csv</a>; each part's numbers in its <code>part.json</code>.</p>\n<script>{SORT_SCRIPT}</script></body></html>\n"
    );
    h
}

fn part_html(dir: &Path, r: &PartRecord) -> String {
    let part_dir = dir.join("parts").join(&r.spec.id);
    let read = |f: &str| -> Option<Value> {
        serde_json::from_slice(&std::fs::read(part_dir.join(f)).ok()?).ok()
    };
    let mut h = String::new();
    let name = esc(&r.spec.path.to_string_lossy());
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{name}</title><style>{STYLE}</style></head><body>\n\
<p><a href=\"../../index.html\">← all parts</a></p>\n<h1>{name}</h1>\n<p class=\"{}\">{}</p>\n",
        class_of(r),
        esc(&verdict(r))
    );
    if let Some(e) = &r.error {
        let _ = writeln!(h, "<p class=\"bad\">{}</p>", esc(e));
    }
    for p in r.pictures.iter().filter(|p| *p != "thumb.png") {
        let _ = writeln!(
            h,
            "<p><img class=\"p\" src=\"{}\" alt=\"{}\"></p>",
            esc(p),
            esc(p)
        );
    }
    if let Some(regions) = read("detect.json")
        .and_then(|d| d.get("regions").cloned())
        .and_then(|r| r.as_array().cloned())
        .filter(|r| !r.is_empty())
    {
        h.push_str("<h2>Suggested fairing regions</h2>\n<table><thead><tr><th>#</th><th>severity</th><th>score</th><th>flat spot</th><th>faces</th><th>area</th><th>centre</th></tr></thead><tbody>\n");
        for (k, reg) in regions.iter().enumerate() {
            let f = |key: &str| {
                reg.get(key)
                    .and_then(Value::as_f64)
                    .map(|x| format!("{x:.3}"))
                    .unwrap_or_default()
            };
            let centre = reg
                .get("center")
                .and_then(Value::as_array)
                .map(|c| {
                    c.iter()
                        .filter_map(Value::as_f64)
                        .map(|x| format!("{x:.4}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                })
                .unwrap_or_default();
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>({centre})</td></tr>",
                k + 1,
                f("severity"),
                f("score"),
                f("flat_spot"),
                reg.get("faces").map(|x| x.to_string()).unwrap_or_default(),
                f("area"),
            );
        }
        h.push_str("</tbody></table>\n");
    }
    let n = serde_json::to_string_pretty(&r.numbers).unwrap_or_default();
    let _ = writeln!(h, "<h2>Numbers</h2>\n<pre>{}</pre>", esc(&n));
    if !r.messages.is_empty() {
        h.push_str("<h2>What the commands said</h2>\n<pre>");
        for m in &r.messages {
            let _ = writeln!(h, "{}", esc(m));
        }
        h.push_str("</pre>\n");
    }
    h.push_str("<h2>Reproduce</h2>\n<p>In this folder (the input as given to <code>fairline inspect</code>, relative to where it ran):</p>\n<pre>");
    for s in &r.steps {
        let _ = writeln!(h, "{}", esc(&s.command));
    }
    h.push_str("</pre>\n<p>Files: ");
    let mut files: Vec<String> = std::fs::read_dir(&part_dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|f| !f.starts_with('.') && f != "index.html")
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    let links: Vec<String> = files
        .iter()
        .map(|f| format!("<a href=\"{0}\">{0}</a>", esc(f)))
        .collect();
    h.push_str(&links.join(", "));
    h.push_str("</p>\n</body></html>\n");
    h
}
