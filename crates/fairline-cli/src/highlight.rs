//! `fairline highlight`: highlight lines of a linear light array (Yong et
//! al. §2) or of concentric circular lights (Nishiyama et al. §2) on a
//! triangle mesh, written as JSON or OBJ polylines.

use crate::common::{Report, bad_input, parse_list, parse_vec3, read_json, spinner};
use anyhow::{Context, Result};
use fairline::highlight::{
    CircularLight, CircularLights, HighlightBands, HighlightError, HighlightLine, HighlightLines,
    HighlightModel, HighlightOptions, LightArray, Readability, UpAxis, circular_highlight_bands,
    circular_highlight_lines,
};
use fairline::mesh::FaceId;
use fairline::{SurfaceMesh, Vec3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The `--up` choice of the default lights.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Up {
    /// From the part's principal axes.
    Auto,
    /// +x.
    X,
    /// +y.
    Y,
    /// +z.
    Z,
}

impl Up {
    /// The library's axis choice.
    pub fn axis(self) -> UpAxis {
        match self {
            Up::Auto => UpAxis::Auto,
            Up::X => UpAxis::X,
            Up::Y => UpAxis::Y,
            Up::Z => UpAxis::Z,
        }
    }
    /// The axis vector, `None` for auto.
    pub fn vector(self) -> Option<Vec3> {
        match self {
            Up::Auto => None,
            Up::X => Some(Vec3::X),
            Up::Y => Some(Vec3::Y),
            Up::Z => Some(Vec3::Z),
        }
    }
}

/// Options describing the linear light array (shared with `detect`).
#[derive(clap::Args, Debug, Clone)]
pub struct LightArgs {
    /// Light direction H (made orthogonal to the plane normal).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub direction: Option<Vec3>,
    /// Normal Z of the light plane (default: from --up).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub plane_normal: Option<Vec3>,
    /// Which side the lights are on when --plane-normal is not given: auto
    /// (the part's principal axis of least extent, turned to the side most
    /// of the surface faces; lights run along its longest axis), or +x, +y,
    /// +z (e.g. --up y for y-up models).
    #[arg(long, value_enum, default_value_t = Up::Auto)]
    pub up: Up,
    /// Point A0 on light 0 (default: one bounding-box diagonal above the
    /// centre along the plane normal).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub plane_point: Option<Vec3>,
    /// Spacing s between lights (default: about 20 lights across a panel;
    /// for drawing, wider on round parts so the lines stay readable).
    #[arg(long)]
    pub spacing: Option<f64>,
    /// Lights from JSON (DESIGN.md §5): a linear array
    /// {"plane_point","plane_normal","direction","spacing"}, or (for
    /// `highlight` only) circular lights {"center","axis","radii"}.
    #[arg(long, value_name = "FILE.json", conflicts_with_all = ["direction", "plane_normal", "plane_point", "spacing"])]
    pub lights: Option<PathBuf>,
    /// Smallest |Z·N| at which a vertex gets a highlight distance.
    #[arg(long, default_value_t = HighlightOptions::default().min_normal_cos)]
    pub min_normal_cos: f64,
}

impl LightArgs {
    /// The light array: from the file, or the bounding-box defaults with
    /// the given fields overridden.
    pub fn light_array(&self, mesh: &SurfaceMesh) -> Result<LightArray> {
        if let Some(path) = &self.lights {
            if circular_file(path)?.is_some() {
                return Err(bad_input(format!(
                    "{}: circular lights are drawn by `fairline highlight` only; this command needs a linear light array {{\"plane_point\",\"plane_normal\",\"direction\",\"spacing\"}}",
                    path.display()
                )));
            }
            return read_json::<LightArray>(path);
        }
        let (lo, hi) = fairline::mesh::bounding_box(mesh.positions())
            .ok_or_else(|| bad_input("the mesh has no vertices"))?;
        if self.plane_normal.is_some() {
            return self.light_array_in_box(lo, hi);
        }
        let base = LightArray::default_for_mesh(mesh, self.up.axis())
            .ok_or_else(|| bad_input("the mesh has no finite vertices"))?;
        LightArray::new(
            self.plane_point.unwrap_or(base.plane_point()),
            base.plane_normal(),
            self.direction.unwrap_or(base.direction()),
            self.spacing.unwrap_or(base.spacing()),
        )
        .map_err(to_input_error)
    }

    /// The light array: from the file, or the defaults for the bounding box
    /// `lo`–`hi` with the given fields overridden.
    pub fn light_array_in_box(&self, lo: Vec3, hi: Vec3) -> Result<LightArray> {
        if let Some(path) = &self.lights {
            return read_json::<LightArray>(path);
        }
        let base = LightArray::default_for(lo, hi, self.plane_normal.or(self.up.vector()));
        LightArray::new(
            self.plane_point.unwrap_or(base.plane_point()),
            self.plane_normal.unwrap_or(base.plane_normal()),
            self.direction.unwrap_or(base.direction()),
            self.spacing.unwrap_or(base.spacing()),
        )
        .map_err(to_input_error)
    }

    /// The lights to draw and read lines with: `light` itself when the
    /// spacing was given (--spacing or --lights), else `light` with its
    /// spacing multiplied by [`LightArray::readable_multiple`] (round parts
    /// get fewer, readable lines; panels keep about 20 across).
    pub fn readable(&self, mesh: &SurfaceMesh, light: LightArray) -> Result<LightArray> {
        if self.spacing.is_some() || self.lights.is_some() {
            return Ok(light);
        }
        let k = light.readable_multiple(mesh);
        light
            .with_spacing(light.spacing() * f64::from(k))
            .map_err(to_input_error)
    }

    /// Model options.
    pub fn options(&self) -> HighlightOptions {
        HighlightOptions::default().min_normal_cos(self.min_normal_cos)
    }
}

/// The circular lights of a `--lights` file when it holds the circular form
/// {"center","axis","radii"} of DESIGN.md §5 (recognised by its "center"
/// key); `None` for any other JSON object (read as a linear array).
pub fn circular_file(path: &Path) -> Result<Option<CircularLights>> {
    let v: Value = read_json(path)?;
    if v.get("center").is_some() {
        let c: CircularLights =
            serde_json::from_value(v).map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        Ok(Some(c))
    } else {
        Ok(None)
    }
}

/// The circular lights `--circular` derived from the part, printed on
/// stderr as one line in the LIGHTS.json form; an input error when the part
/// has no area to derive them from.
pub fn derived_circular_lights(spec: Option<CircularLights>) -> Result<CircularLights> {
    let spec = spec.ok_or_else(|| {
        bad_input("cannot derive circular lights: the part has no area with a defined normal")
    })?;
    eprintln!(
        "default circular lights (save as LIGHTS.json to reuse): {}",
        serde_json::to_string(&spec)?
    );
    Ok(spec)
}

/// Maps library errors about the input (bad light, bad option, bad mesh)
/// to exit status 2.
pub fn to_input_error(e: HighlightError) -> anyhow::Error {
    bad_input(e.to_string())
}

/// Reads a mesh and triangulates polygons; also returns, for each
/// triangle, the input face it came from (None when nothing changed).
pub fn read_triangles(path: &Path) -> Result<(SurfaceMesh, Option<Vec<FaceId>>)> {
    if crate::surface::is_surface_path(path) {
        return Err(bad_input(format!(
            "{}: B-spline surfaces are not handled by this command yet; give a mesh (.obj .ply .off .stl)",
            path.display()
        )));
    }
    let mesh = fairline::io::read_mesh(path)?;
    crate::repair::note_split_vertices(path, &mesh);
    if mesh.is_triangle_mesh() {
        Ok((mesh, None))
    } else {
        let t = fairline::mesh::triangulate(&mesh)
            .with_context(|| format!("{}: triangulating its polygons", path.display()))?;
        Ok((t.mesh, Some(t.source_face)))
    }
}

/// Highlight lines of a triangle mesh (polygons are triangulated first)
/// under a linear light array (Yong et al. Algorithm 1, Eq. (1) and (4) as
/// corrected in DESIGN.md §3), or, with --circle-center/--circle-axis/--radii,
/// under concentric circular lights (Nishiyama et al. Eq. (2.18), zero level
/// per radius). Lights default to a plane one bounding-box diagonal above the
/// part, facing its thinnest principal direction (--up), about 20 lights
/// across a panel; on round parts the spacing grows so the lines stay
/// readable (every k-th line, k from the median highlight-distance
/// gradient), and the picture leaves out lines crowded toward silhouettes
/// and tiny pieces (the output keeps all lines). --band ρ adds the band
/// boundaries at ±ρ. Output JSON {"lines":[{"index":m,"closed":b,"points":[[x,y,z],..]}]}
/// (circular lines also carry "radius"; bands under "bands"), or OBJ `l`
/// polylines (groups lines, band_lower, band_upper).
///
/// B-spline surfaces (.json, .igs/.iges, .step/.stp) are handled as in Nishiyama et al.
/// §2: d_s sampled on a --grid × --grid (u, v) grid, contoured by marching
/// squares, refined onto the true zero; JSON lines carry "uv" and "points".
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline highlight fairline-demo/sphere.ply -o sphere-lines.json --png sphere-lines.png\n  fairline highlight fairline-demo/dented-panel.obj --direction 0,1,0 --plane-normal 0,0,1 --plane-point 0,0,5 --spacing 0.1 -o lines.obj\n  fairline highlight fairline-demo/dented-panel.obj --circle-center 0,0,5 --circle-axis 0,0,1 --radii 1,2,3 --band 0.05 -o circles.json\n  fairline highlight fairline-demo/bspline-panel-dented.json --circle-center 2,1.5,2.5 --circle-axis 0,0,1 --radii 2.4,2.6,2.8,3.0 --grid 300 -o surface-lines.json --png surface-lines.png --svg uv.svg"
)]
pub struct Args {
    /// Input triangle (or polygon) mesh.
    pub mesh: PathBuf,
    #[command(flatten)]
    pub light: LightArgs,
    /// Centre of the circular lights.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z", requires_all = ["circle_axis", "radii"], conflicts_with = "lights")]
    pub circle_center: Option<Vec3>,
    /// Axis of the circular lights.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z", requires_all = ["circle_center", "radii"])]
    pub circle_axis: Option<Vec3>,
    /// Radii of the circular lights, comma separated.
    #[arg(long, value_parser = parse_radii, allow_hyphen_values = true, value_name = "R1,R2,..", requires_all = ["circle_center", "circle_axis"])]
    pub radii: Option<Radii>,
    /// Circular lights derived from the part instead of given: axis along
    /// the part's area-weighted mean normal (+z for a closed body; --up x|y|z
    /// sets it), centre on that axis above the part, 10 radii whose lines
    /// span the part. They are printed on stderr in the LIGHTS.json form
    /// {"center","axis","radii"}, ready for --lights.
    #[arg(long, conflicts_with_all = ["circle_center", "lights"])]
    pub circular: bool,
    /// Also compute highlight bands of this radius (mesh units).
    #[arg(long, value_name = "RHO")]
    pub band: Option<f64>,
    /// Output polylines (.json or .obj).
    #[arg(short, long, value_name = "LINES.json|.obj")]
    pub output: PathBuf,
    /// Picture of the lines on the shaded mesh (or surface).
    #[arg(long, value_name = "IMG.png")]
    pub png: Option<PathBuf>,
    /// Viewing direction of the picture X,Y,Z (from the eye towards the
    /// object; default: down the light-plane normal, slightly tilted).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub view: Option<Vec3>,
    /// B-spline surfaces: grid points per parameter direction on which d_s
    /// is sampled before contouring (one surface); for a file of several
    /// patches, grid points along the part's diagonal, each patch sampled
    /// in proportion to its size (at least 12 per direction).
    #[arg(long, default_value_t = 200, value_name = "N")]
    pub grid: usize,
    /// B-spline surfaces: SVG of the (u, v) pre-images (of surface
    /// --surface, default 0).
    #[arg(long, value_name = "UV.svg")]
    pub svg: Option<PathBuf>,
    /// B-spline surfaces: use only this surface of the file (default: all).
    #[arg(long, value_name = "K")]
    pub surface: Option<usize>,
    /// Size of the --png picture, WxH.
    #[arg(long, value_parser = crate::common::parse_size, default_value = "1200x900", requires = "png")]
    pub size: (u32, u32),
    /// Write a JSON report.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

/// A comma-separated list of radii.
#[derive(Clone, Debug)]
pub struct Radii(pub Vec<f64>);

fn parse_radii(s: &str) -> Result<Radii, String> {
    parse_list(s).map(Radii)
}

/// Output format of polylines.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum LinesFormat {
    /// JSON of DESIGN.md §4.
    Json,
    /// Wavefront OBJ `l` elements.
    Obj,
}

/// The format of `path` from its extension.
pub fn lines_format(path: &Path) -> Result<LinesFormat> {
    crate::output::require_extension("-o", path, &["json", "obj"])?;
    let obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    Ok(if obj {
        LinesFormat::Obj
    } else {
        LinesFormat::Json
    })
}

fn line_json(l: &HighlightLine, radii: Option<&[f64]>) -> Value {
    let pts: Vec<[f64; 3]> = l.points.iter().map(|p| p.to_array()).collect();
    let mut v = json!({"index": l.index, "closed": l.closed, "points": pts});
    if let Some(r) = radii.and_then(|r| r.get(l.index as usize)) {
        v["radius"] = json!(r);
    }
    v
}

fn lines_json(lines: &HighlightLines, radii: Option<&[f64]>) -> Vec<Value> {
    lines.lines.iter().map(|l| line_json(l, radii)).collect()
}

/// Writes lines (and bands) as JSON or OBJ, atomically.
pub fn write_lines(
    path: &Path,
    lines: &HighlightLines,
    bands: Option<&HighlightBands>,
    radii: Option<&[f64]>,
) -> Result<()> {
    match lines_format(path)? {
        LinesFormat::Json => {
            let mut v = json!({"lines": lines_json(lines, radii)});
            if let Some(b) = bands {
                v["bands"] = json!({
                    "radius": b.radius,
                    "lower": lines_json(&b.lower, radii),
                    "upper": lines_json(&b.upper, radii),
                });
            }
            crate::common::write_json(path, &v)
        }
        LinesFormat::Obj => {
            let mut groups: Vec<(&str, &HighlightLines)> = vec![("lines", lines)];
            if let Some(b) = bands {
                groups.push(("band_lower", &b.lower));
                groups.push(("band_upper", &b.upper));
            }
            let mut text = String::from("# fairline highlight lines\n");
            let mut next = 1usize;
            for (name, ls) in groups {
                text.push_str(&format!("g {name}\n"));
                for l in &ls.lines {
                    let first = next;
                    for p in &l.points {
                        text.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
                    }
                    text.push('l');
                    for k in 0..l.points.len() {
                        text.push_str(&format!(" {}", first + k));
                    }
                    if l.closed {
                        text.push_str(&format!(" {first}"));
                    }
                    text.push('\n');
                    next += l.points.len();
                }
            }
            fairline::io::atomic_write(path, |w| {
                use std::io::Write;
                w.write_all(text.as_bytes())
            })?;
            Ok(())
        }
    }
}

/// Summary statistics of a line set for reports.
pub fn line_summary(lines: &HighlightLines) -> Value {
    json!({
        "lines": lines.lines.len(),
        "closed_lines": lines.lines.iter().filter(|l| l.closed).count(),
        "nodes": lines.node_count(),
    })
}

pub fn run(args: Args) -> Result<()> {
    if crate::surface::is_surface_path(&args.mesh) {
        return crate::surface_highlight::run(args);
    }
    lines_format(&args.output)?;
    if let Some(p) = &args.png {
        crate::output::require_extension("--png", p, &["png"])?;
    }
    let job = crate::output::Job::new("highlight")
        .input(&args.mesh)
        .input_opt(args.light.lights.as_deref())
        .output("-o", &args.output)
        .output_opt("--png", args.png.as_deref())
        .output_opt("--report", args.report.as_deref())
        .check()?;
    if args.view.is_some_and(|v| v.length() == 0.0) {
        return Err(bad_input("--view must not be the zero vector"));
    }
    if let Some(b) = args.band
        && !(b > 0.0 && b.is_finite())
    {
        return Err(bad_input(format!(
            "--band must be a positive number, got {b}"
        )));
    }
    let (mesh, _) = read_triangles(&args.mesh)?;
    let mut report = Report::new("highlight");
    report.set("vertices", mesh.vertex_count());
    report.set("faces", mesh.face_count());
    let bar = spinner("highlight lines");
    let view_up: (Vec3, Vec3);
    // the readable drawing of linear lights (None: draw all lines)
    let mut drawn: Option<HighlightLines> = None;
    let mut spacing = None;
    let circular = match (args.circle_center, args.circle_axis, args.radii.clone()) {
        (Some(c), Some(t), Some(Radii(radii))) => Some(CircularLights {
            center: c.to_array(),
            axis: t.to_array(),
            radii,
        }),
        _ => match &args.light.lights {
            Some(path) => circular_file(path)?,
            None if args.circular => Some(derived_circular_lights(
                fairline::highlight::default_circular_lights_for_mesh(
                    &mesh,
                    args.light.up.vector(),
                    fairline::highlight::DEFAULT_CIRCULAR_RADII,
                ),
            )?),
            None => None,
        },
    };
    let (lines, bands, radii) = if let Some(spec) = circular {
        let radii = spec.radii.clone();
        let from_file = args.circle_center.is_none() || args.circle_axis.is_none();
        let lights: Vec<CircularLight> =
            spec.lights()
                .map_err(|e| match (&args.light.lights, from_file) {
                    (Some(path), true) => crate::output::name_file(path, to_input_error(e)),
                    _ => to_input_error(e),
                })?;
        if lights.is_empty() {
            return Err(bad_input("circular lights need at least one radius"));
        }
        let (lines, bands) = report
            .time(|| -> Result<_, HighlightError> {
                let lines = circular_highlight_lines(&mesh, &lights)?;
                let bands = match args.band {
                    Some(rho) => Some(circular_highlight_bands(&mesh, &lights, rho)?),
                    None => None,
                };
                Ok((lines, bands))
            })
            .map_err(to_input_error)?;
        let axis = lights[0].axis();
        view_up = (
            -axis + 0.35 * axis.any_orthonormal_vector(),
            axis.any_orthonormal_vector(),
        );
        let mut light = json!({"kind": "circular", "center": spec.center, "axis": spec.axis, "radii": spec.radii});
        if args.circular {
            light["derived"] = json!(true);
        }
        report.set("light", light);
        (lines, bands, Some(radii))
    } else {
        let light = args.light.light_array(&mesh)?;
        let light = args.light.readable(&mesh, light)?;
        let opts = args.light.options();
        let (lines, bands, shown) = report
            .time(|| -> Result<_, HighlightError> {
                let model = HighlightModel::new(&mesh, light, opts)?;
                let lines = model.lines(&mesh);
                let bands = match args.band {
                    Some(rho) => Some(model.bands(&mesh, rho)?),
                    None => None,
                };
                let shown =
                    model.readable_lines(&mesh, &lines, &Readability::for_part(&mesh, &light));
                Ok((lines, bands, shown))
            })
            .map_err(to_input_error)?;
        report.set("light", json!({"kind": "linear", "array": light}));
        report.set(
            "drawn",
            crate::highlight_png::stats_json(&mesh, &light, &shown),
        );
        if let Some(w) = crate::highlight_png::line_warning(
            &args.mesh,
            &lines,
            &shown,
            &light,
            fairline::highlight::readable::part_width(mesh.positions(), light.across()),
        ) {
            eprintln!("{w}");
        }
        drawn = Some(shown);
        view_up = crate::highlight_png::default_camera(&light);
        spacing = Some(light.spacing());
        (lines, bands, None)
    };
    bar.finish_and_clear();
    write_lines(&args.output, &lines, bands.as_ref(), radii.as_deref())?;
    report.set("summary", line_summary(&lines));
    report.set("lines", lines.lines.len());
    report.set(
        "closed_lines",
        lines.lines.iter().filter(|l| l.closed).count(),
    );
    report.set("nodes", lines.node_count());
    if let Some(b) = &bands {
        report.set("band", json!({"radius": b.radius, "lower_lines": b.lower.lines.len(), "upper_lines": b.upper.lines.len()}));
    }
    if let Some(png) = &args.png {
        let band_lines = bands.as_ref().map(|b| {
            let mut all = b.lower.clone();
            all.lines.extend(b.upper.lines.iter().cloned());
            all
        });
        let view = args.view.unwrap_or(view_up.0);
        let name = args
            .mesh
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let title = match &drawn {
            Some(d) if d.lines.len() != lines.lines.len() => format!(
                "{name}: {} of {} line pieces drawn",
                d.lines.len(),
                lines.lines.len()
            ),
            _ => format!("{name}: {} highlight lines", lines.lines.len()),
        };
        crate::highlight_png::write(
            args.size,
            png,
            &mesh,
            crate::highlight_png::Overlay {
                lines: drawn.as_ref().unwrap_or(&lines),
                bands: band_lines.as_ref(),
                flagged: &[],
                region: None,
                view: (view, view_up.1),
                title,
                spacing,
            },
        )?;
    }
    if lines.lines.is_empty() {
        report.warn("no highlight line crosses the mesh; try other light options (--plane-normal, --direction, --spacing)");
    }
    report.write(args.report.as_deref())?;
    job.finish(format_args!(
        "{} highlight line(s) ({} closed, {} nodes) on {} vertices",
        lines.lines.len(),
        lines.lines.iter().filter(|l| l.closed).count(),
        lines.node_count(),
        mesh.vertex_count()
    ));
    Ok(())
}
