//! Which parts an inspection run judges, with which settings: files given
//! on the command line, folders searched recursively by extension, and
//! manifests (CSV or JSON) that list paths with per-part settings.

use crate::error::bad_input;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// Extensions of the mesh files an inspection judges.
pub const MESH_EXTENSIONS: &[&str] = &["obj", "ply", "off", "stl"];
/// Extensions of the CAD (surface) files an inspection judges.
pub const CAD_EXTENSIONS: &[&str] = &["igs", "iges", "step", "stp", "json"];

/// What kind of file a part is, from its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PartKind {
    /// A triangle or polygon mesh (.obj .ply .off .stl).
    Mesh,
    /// B-spline surfaces (.igs .iges .step .stp, fairline's .json).
    Cad,
}

impl PartKind {
    /// The kind's name in reports (`mesh`, `cad`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Mesh => "mesh",
            Self::Cad => "cad",
        }
    }

    /// The kind as the report page shows it.
    pub fn label(self) -> &'static str {
        match self {
            Self::Mesh => "mesh",
            Self::Cad => "CAD",
        }
    }
}

/// Per-part settings a manifest may give; every field left out keeps the
/// single-file commands' default.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSettings {
    /// The part's up axis, `x`, `y` or `z` (the light plane lies above
    /// the part along it): `--up` of `detect`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<String>,
    /// A lights file (`--lights` of `detect`), relative to the manifest.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lights: Option<PathBuf>,
    /// The detection threshold (`--threshold` of `detect`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
    /// The G0 gap tolerance of CAD parts (`--tolerance` of `continuity`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
}

impl PartSettings {
    /// Refuses settings the commands would refuse, naming `origin`.
    fn check(&self, origin: &str) -> Result<()> {
        if let Some(up) = &self.up
            && !matches!(up.as_str(), "x" | "y" | "z")
        {
            return Err(bad_input(format!(
                "{origin}: up `{up}` is not an axis (x, y or z)"
            )));
        }
        for (name, v) in [("threshold", self.threshold), ("tolerance", self.tolerance)] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(bad_input(format!(
                    "{origin}: {name} {v} is not a positive number"
                )));
            }
        }
        Ok(())
    }
}

/// One part of a run: the file, its kind, its settings and the name of its
/// folder in the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartSpec {
    /// The file as given (or as found under a given folder, or as listed
    /// in a manifest, joined to the manifest's folder).
    pub path: PathBuf,
    /// Folder name in the report (`parts/ID`): the path made safe for a
    /// file name, plus a short hash of the whole path so two parts never
    /// share a folder.
    pub id: String,
    /// Mesh or CAD part.
    pub kind: PartKind,
    /// Settings beyond the defaults.
    pub settings: PartSettings,
}

impl PartSpec {
    fn new(path: PathBuf, kind: PartKind, settings: PartSettings) -> Self {
        let id = part_id(&path);
        PartSpec {
            path,
            id,
            kind,
            settings,
        }
    }
}

/// The kind of a file by its extension, or None for a file an inspection
/// does not judge.
pub fn kind_of(path: &Path) -> Option<PartKind> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    if MESH_EXTENSIONS.contains(&ext.as_str()) {
        Some(PartKind::Mesh)
    } else if CAD_EXTENSIONS.contains(&ext.as_str()) {
        Some(PartKind::Cad)
    } else {
        None
    }
}

/// The parts of `inputs` (files, folders, manifests given with
/// `manifest`), in a deterministic order (sorted by path) with no part
/// twice. A given file of an unknown extension, a missing path or a bad
/// manifest is bad input; files of unknown extensions inside folders are
/// left out (counted in the second value).
pub fn plan(inputs: &[PathBuf], manifests: &[PathBuf]) -> Result<(Vec<PartSpec>, usize)> {
    let mut parts = Vec::new();
    let mut ignored = 0;
    for input in inputs {
        let meta =
            std::fs::metadata(input).map_err(|e| bad_input(format!("{}: {e}", input.display())))?;
        if meta.is_dir() {
            ignored += walk(input, &mut parts)?;
        } else {
            let kind = kind_of(input).ok_or_else(|| {
                bad_input(format!(
                    "{}: not a part file (meshes: .{}; CAD: .{}); a manifest is given with --manifest",
                    input.display(),
                    MESH_EXTENSIONS.join(" ."),
                    CAD_EXTENSIONS.join(" .")
                ))
            })?;
            parts.push(PartSpec::new(input.clone(), kind, PartSettings::default()));
        }
    }
    for m in manifests {
        parts.extend(read_manifest(m)?);
    }
    parts.sort_by(|a, b| a.path.cmp(&b.path));
    parts.dedup_by(|a, b| a.path == b.path);
    Ok((parts, ignored))
}

/// Adds the part files under `dir` (recursively, symbolic links not
/// followed into folders, hidden entries and JSON files that are not
/// surface files left out); returns how many other files were left out.
fn walk(dir: &Path, parts: &mut Vec<PartSpec>) -> Result<usize> {
    let mut ignored = 0;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries =
            std::fs::read_dir(&d).map_err(|e| bad_input(format!("{}: {e}", d.display())))?;
        for entry in entries {
            let entry = entry.map_err(|e| bad_input(format!("{}: {e}", d.display())))?;
            let path = entry.path();
            if entry.file_name().to_string_lossy().starts_with('.') {
                continue;
            }
            let Ok(ft) = entry.file_type() else {
                ignored += 1;
                continue;
            };
            if ft.is_dir() {
                stack.push(path);
            } else if let Some(kind) = kind_of(&path)
                && !is_other_json(&path)
            {
                parts.push(PartSpec::new(path, kind, PartSettings::default()));
            } else {
                ignored += 1;
            }
        }
    }
    Ok(ignored)
}

/// True for a `.json` file that is well-formed JSON but not a surface file
/// (a lights file, a region, a report: neither `surfaces` nor
/// `control_points` at its top level), which a folder search leaves out.
/// A file that cannot be read or parsed stays a part, so that its row
/// says why. Reads the file once, streaming, without keeping its values.
fn is_other_json(path: &Path) -> bool {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return false;
    }
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    // an object's top-level keys (values skipped); an array is valid JSON
    // of another shape
    type TopKeys = std::collections::BTreeMap<String, serde::de::IgnoredAny>;
    match serde_json::from_reader::<_, TopKeys>(std::io::BufReader::new(file)) {
        Ok(top) => !top.contains_key("surfaces") && !top.contains_key("control_points"),
        Err(e) => e.is_data(), // valid JSON of another shape (an array, a number)
    }
}

/// One row of a JSON manifest.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestRow {
    path: PathBuf,
    #[serde(flatten)]
    settings: PartSettings,
}

/// The parts a manifest lists: JSON (`[{"path": "a.ply", "up": "y"}, …]`
/// or `{"parts": [...]}`) or CSV with a header row naming `path` and any
/// of `up`, `lights`, `threshold`, `tolerance` (an empty cell keeps the
/// default). Paths are relative to the manifest's folder.
pub fn read_manifest(path: &Path) -> Result<Vec<PartSpec>> {
    let bytes = fairline::io::read_input_file(path, fairline::io::MAX_INPUT_FILE_BYTES)
        .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| bad_input(format!("{}: not UTF-8 text: {e}", path.display())))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let is_json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let rows = if is_json {
        json_rows(path, &text)?
    } else {
        csv_rows(path, &text)?
    };
    let mut parts = Vec::with_capacity(rows.len());
    for (k, row) in rows.into_iter().enumerate() {
        let origin = format!("{}: part {}", path.display(), k + 1);
        row.settings.check(&origin)?;
        let file = base.join(&row.path);
        let kind = kind_of(&file).ok_or_else(|| {
            bad_input(format!(
                "{origin}: {} is not a part file (.{} .{})",
                row.path.display(),
                MESH_EXTENSIONS.join(" ."),
                CAD_EXTENSIONS.join(" .")
            ))
        })?;
        let mut settings = row.settings;
        settings.lights = settings.lights.map(|l| base.join(l));
        parts.push(PartSpec::new(file, kind, settings));
    }
    Ok(parts)
}

fn json_rows(path: &Path, text: &str) -> Result<Vec<ManifestRow>> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Manifest {
        List(Vec<ManifestRow>),
        Parts { parts: Vec<ManifestRow> },
    }
    let m: Manifest = serde_json::from_str(text).map_err(|e| {
        bad_input(format!(
            "{}: not a manifest ({e}); expected [{{\"path\": \"part.ply\", \"up\": \"z\"}}, …]",
            path.display()
        ))
    })?;
    Ok(match m {
        Manifest::List(rows) | Manifest::Parts { parts: rows } => rows,
    })
}

fn csv_rows(path: &Path, text: &str) -> Result<Vec<ManifestRow>> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(bad_input(format!("{}: empty manifest", path.display())));
    };
    let columns: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
    if !columns.iter().any(|c| c == "path") {
        return Err(bad_input(format!(
            "{}: line 1: the header names no `path` column (columns: path, up, lights, threshold, tolerance)",
            path.display()
        )));
    }
    let mut rows = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != columns.len() {
            return Err(bad_input(format!(
                "{}: line {}: {} cells, the header has {}",
                path.display(),
                n + 1,
                cells.len(),
                columns.len()
            )));
        }
        let mut object = serde_json::Map::new();
        for (c, v) in columns.iter().zip(cells) {
            if v.is_empty() {
                continue;
            }
            let value = match c.as_str() {
                "threshold" | "tolerance" => match v.parse::<f64>() {
                    Ok(x) => serde_json::json!(x),
                    Err(_) => {
                        return Err(bad_input(format!(
                            "{}: line {}: {c} `{v}` is not a number",
                            path.display(),
                            n + 1
                        )));
                    }
                },
                _ => serde_json::json!(v),
            };
            object.insert(c.clone(), value);
        }
        let row: ManifestRow = serde_json::from_value(serde_json::Value::Object(object))
            .map_err(|e| bad_input(format!("{}: line {}: {e}", path.display(), n + 1)))?;
        rows.push(row);
    }
    Ok(rows)
}

/// The report folder name of a part: its path with every character that
/// is not a letter, digit, `.`, `_` or `-` replaced by `_` (at most 60
/// characters, from the end), then `-` and 8 hex digits of the SHA-256 of
/// the whole path.
pub fn part_id(path: &Path) -> String {
    let text = path.to_string_lossy();
    let safe: String = text
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let safe = safe.trim_start_matches(['.', '_']);
    let tail: String = {
        let chars: Vec<char> = safe.chars().collect();
        chars[chars.len().saturating_sub(60)..].iter().collect()
    };
    let digest = Sha256::digest(text.as_bytes());
    format!("{tail}-{}", hex(&digest[..4]))
}

/// Lower-case hex of `bytes`.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The content key of a part: SHA-256 over the fairline version, the
/// part's file bytes, its settings and the bytes of its lights file. A
/// re-run redoes a part exactly when its key changed.
pub fn content_key(spec: &PartSpec) -> std::io::Result<String> {
    let mut h = Sha256::new();
    h.update(concat!("fairline ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
    h.update(crate::inspect::SCHEMA.as_bytes());
    hash_file(&mut h, &spec.path)?;
    h.update(
        serde_json::to_string(&spec.settings)
            .unwrap_or_default()
            .as_bytes(),
    );
    if let Some(l) = &spec.settings.lights {
        hash_file(&mut h, l)?;
    }
    Ok(hex(&h.finalize()))
}

fn hash_file(h: &mut Sha256, path: &Path) -> std::io::Result<()> {
    use std::io::Read;
    fairline::io::require_regular_file(path)?;
    let mut f = std::fs::File::open(path)?;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            return Ok(());
        }
        h.update(&buf[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_safe_and_distinct() {
        let a = part_id(Path::new("run 1/body/panel.ply"));
        let b = part_id(Path::new("run_1/body/panel.ply"));
        assert!(a.starts_with("run_1_body_panel.ply-"), "{a}");
        assert_ne!(a, b, "same safe name, different paths");
        assert!(
            a.chars()
                .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c))
        );
        let long = part_id(Path::new(&"x/".repeat(100)));
        assert!(long.len() <= 60 + 9, "{long}");
    }

    #[test]
    fn a_folder_search_leaves_out_json_that_is_not_a_surface_file() {
        let dir = std::env::temp_dir().join(format!("fl-walk-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let write = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
        write("panel.json", r#"{"surfaces": []}"#);
        write("one.json", r#"{"degree_u": 3, "control_points": []}"#);
        write("lights.json", r#"{"center": [0, 0, 0], "axis": [0, 0, 1]}"#);
        write("list.json", "[1, 2]");
        write("broken.json", r#"{"surfaces": [ "#);
        write("notes.txt", "x");
        let mut parts = Vec::new();
        let ignored = walk(&dir, &mut parts).unwrap();
        let mut names: Vec<String> = parts
            .iter()
            .map(|p| p.path.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["broken.json", "one.json", "panel.json"]);
        assert_eq!(ignored, 3);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn csv_manifest_rows_and_errors() {
        let dir = std::env::temp_dir().join(format!("fl-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = dir.join("m.csv");
        std::fs::write(&m, "path,up,threshold\na.ply,y,\nsub/b.igs,,2.5\n").unwrap();
        let parts = read_manifest(&m).unwrap();
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].settings.up.as_deref(), Some("y"));
        assert_eq!(parts[0].kind, PartKind::Mesh);
        assert_eq!(parts[1].settings.threshold, Some(2.5));
        assert_eq!(parts[1].kind, PartKind::Cad);
        assert_eq!(parts[1].path, dir.join("sub/b.igs"));
        std::fs::write(&m, "path,up\na.ply,w\n").unwrap();
        let e = read_manifest(&m).unwrap_err().to_string();
        assert!(e.contains("m.csv: part 1") && e.contains("`w`"), "{e}");
        std::fs::write(&m, "file\na.ply\n").unwrap();
        assert!(read_manifest(&m).unwrap_err().to_string().contains("path"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
