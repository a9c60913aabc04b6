//! The command-line arguments that more than one command shares: vectors,
//! lists and sizes, the lights of highlight lines (`LightArgs`), and the
//! arguments of `fairline highlight`, whose mesh and B-spline surface
//! paths are two modules (`highlight`, `surface_highlight`).

use crate::common::read_json;
use crate::error::bad_input;
use anyhow::Result;
use fairline::highlight::{CircularLights, HighlightError, HighlightOptions, LightArray, UpAxis};
use fairline::{SurfaceMesh, Vec3};
use fairline_commands::Lights;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Refuses a zero `--view` direction (exit 2): a picture needs a direction
/// to look in.
pub fn check_view(view: Option<Vec3>) -> Result<()> {
    if view.is_some_and(|v| v.length() == 0.0) {
        return Err(bad_input("--view must not be the zero vector"));
    }
    Ok(())
}

/// Parses `X,Y,Z` into a vector.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got `{s}`"));
    }
    let mut v = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p
            .parse::<f64>()
            .map_err(|_| format!("`{p}` is not a number in `{s}`"))?;
        if !v[k].is_finite() {
            return Err(format!("`{p}` is not finite in `{s}`"));
        }
    }
    Ok(Vec3::from_array(v))
}

/// Parses a comma-separated list of numbers.
pub fn parse_list(s: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|p| {
            let v = p
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("`{p}` is not a number"))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!("`{p}` is not finite"))
            }
        })
        .collect()
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in `{s}`"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in `{s}`"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!(
            "image size `{s}` must be between 1 and 16384 pixels"
        ));
    }
    Ok((w, h))
}

/// Largest `--zebra-period`, degrees: beyond half a turn fewer than two
/// stripes are left.
pub const MAX_ZEBRA_PERIOD_DEG: f64 = 180.0;

/// Parses `--zebra-period DEG`: an angle in (0, [`MAX_ZEBRA_PERIOD_DEG`]].
fn parse_zebra_period(s: &str) -> Result<f64, String> {
    let p: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if p.is_finite() && p > 0.0 && p <= MAX_ZEBRA_PERIOD_DEG {
        Ok(p)
    } else {
        Err(format!(
            "give an angle in (0, {MAX_ZEBRA_PERIOD_DEG}] degrees, got {s}"
        ))
    }
}

/// The reflection zebra of a command's `--png` picture (every command whose
/// picture shades the part without a colour map).
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct ZebraArgs {
    /// Draw a reflection zebra on the part in the --png picture, under its
    /// lines: stripes of parallel tube lights (along the light array's
    /// direction, its plane normal the zenith; without light options the
    /// part's default lights) seen in the surface as in a mirror; where
    /// they get denser than about three pixels they fade to grey.
    #[arg(long, requires = "png")]
    pub zebra: bool,
    /// With --zebra: the angle of one stripe period, degrees, in (0, 180]
    /// (default: chosen so that the stripes lie about 20 px apart on the
    /// picture).
    #[arg(long, value_name = "DEG", requires = "zebra", value_parser = parse_zebra_period, allow_hyphen_values = true)]
    pub zebra_period: Option<f64>,
}

impl ZebraArgs {
    /// The zebra of a picture of `mesh` drawn with `opts`, `None` without
    /// --zebra: tubes along `light` (the command's light array), else along
    /// the part's default lights ([`Lights::light_array`]), one stripe per
    /// --zebra-period or per [`fairline::picture::zebra_period`].
    pub fn reflection_zebra(
        &self,
        mesh: &SurfaceMesh,
        light: Option<&LightArray>,
        opts: &fairline::render::RenderOptions,
    ) -> Result<Option<fairline::render::ReflectionZebra>> {
        if !self.zebra {
            return Ok(None);
        }
        let light = match light {
            Some(l) => *l,
            None => Lights::default().light_array(mesh)?,
        };
        Ok(fairline::picture::reflection_zebra(
            mesh,
            &light,
            opts,
            self.zebra_period,
        ))
    }
}

/// The words a picture's title adds for its zebra: the period.
pub fn zebra_title(zebra: &fairline::render::ReflectionZebra) -> String {
    format!("reflection zebra, {:.3} deg per stripe", zebra.period_deg)
}

/// The report's account of a picture's zebra: its period, tube axis and
/// zenith.
pub fn zebra_json(zebra: &fairline::render::ReflectionZebra) -> Value {
    serde_json::json!({
        "period_deg": zebra.period_deg,
        "axis": zebra.axis.to_array(),
        "zenith": zebra.zenith.to_array(),
    })
}

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
        self.axis().vector()
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
    /// The lights as the command layer takes them: the `--lights` file's
    /// linear array, or the fields given (the readable-light policy and the
    /// defaults are [`Lights`]'). A circular lights file is refused here:
    /// only `highlight` draws circular lights.
    pub fn lights(&self) -> Result<Lights> {
        let given = match &self.lights {
            Some(path) => {
                if circular_file(path)?.is_some() {
                    return Err(bad_input(format!(
                        "{}: circular lights are drawn by `fairline highlight` only; this command needs a linear light array {{\"plane_point\",\"plane_normal\",\"direction\",\"spacing\"}}",
                        path.display()
                    )));
                }
                Some(read_json::<LightArray>(path)?)
            }
            None => None,
        };
        Ok(self.fields(given))
    }

    /// The lights with `given` as the whole array (no file read).
    fn fields(&self, given: Option<LightArray>) -> Lights {
        Lights {
            direction: self.direction,
            plane_normal: self.plane_normal,
            up: self.up.axis(),
            plane_point: self.plane_point,
            spacing: self.spacing,
            given,
            min_normal_cos: self.min_normal_cos,
        }
    }

    /// The light array ([`Lights::light_array`]).
    pub fn light_array(&self, mesh: &SurfaceMesh) -> Result<LightArray> {
        Ok(self.lights()?.light_array(mesh)?)
    }

    /// The lights to draw and read lines with ([`Lights::readable`]).
    pub fn readable(&self, mesh: &SurfaceMesh, light: LightArray) -> Result<LightArray> {
        let given = self.lights.is_some().then_some(light);
        Ok(self.fields(given).readable(mesh, light)?)
    }

    /// Model options.
    pub fn options(&self) -> HighlightOptions {
        self.fields(None).options()
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

/// Maps library errors about the input (bad light, bad option, bad mesh)
/// to exit status 2.
pub fn to_input_error(e: HighlightError) -> anyhow::Error {
    bad_input(e.to_string())
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
/// B-spline surfaces (.json, .igs/.iges, .step/.stp, .g2) are handled as in Nishiyama et al.
/// §2: d_s sampled on a --grid × --grid (u, v) grid, contoured by marching
/// squares, refined onto the true zero; JSON lines carry "uv" and "points".
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples (on the files `fairline demo` writes into fairline-demo/):\n  fairline highlight fairline-demo/sphere.ply -o sphere-lines.json --png sphere-lines.png\n  fairline highlight fairline-demo/dented-panel.obj --direction 0,1,0 --plane-normal 0,0,1 --plane-point 0,0,5 --spacing 0.1 -o lines.obj\n  fairline highlight fairline-demo/dented-panel.obj --circle-center 0,0,5 --circle-axis 0,0,1 --radii 1,2,3 --band 0.05 -o circles.json\n  fairline highlight fairline-demo/bspline-panel-dented.json -o lines.igs --curve-tolerance 1e-4\n  fairline highlight fairline-demo/bspline-panel-dented.json --circle-center 2,1.5,2.5 --circle-axis 0,0,1 --radii 2.4,2.6,2.8,3.0 --grid 300 -o surface-lines.json --png surface-lines.png --svg uv.svg"
)]
pub struct HighlightArgs {
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
    /// Output: polylines (.json or .obj), or B-spline curves for CAD
    /// (.igs/.iges: one cubic entity 126 per line within
    /// --curve-tolerance, named HLm by its light m, or PkLj on patch k of a
    /// surface file; the surface file's length unit, millimetres for a
    /// mesh).
    #[arg(short, long, value_name = "LINES.json|.obj|.igs")]
    pub output: PathBuf,
    /// With -o LINES.igs: the largest distance from a curve to its line
    /// (default 1e-4 of the part's bounding-box diagonal; for a mesh at
    /// least a tenth of its mean edge length, the scale at which its lines
    /// bend at every edge). Lines no cubic follows within it are written as
    /// exact polylines (degree 1). The report's `curves` key gives the
    /// distance reached, the control points and the polylines.
    #[arg(long, value_name = "DISTANCE")]
    pub curve_tolerance: Option<f64>,
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
    #[arg(long, value_parser = parse_size, default_value = "1200x900", requires = "png")]
    pub size: (u32, u32),
    #[command(flatten)]
    pub zebra: ZebraArgs,
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

/// The value parser of a choice of the command layer: its names (with
/// their help) listed in `--help`, the value parsed by
/// [`fairline_commands::Choice`].
pub fn choice<T>() -> impl clap::builder::TypedValueParser<Value = T>
where
    T: fairline_commands::Choice + Send + Sync,
{
    use clap::builder::TypedValueParser;
    let values = T::ALL
        .iter()
        .map(|n| clap::builder::PossibleValue::new(n.name).help(n.help));
    clap::builder::PossibleValuesParser::new(values)
        .map(|name: String| T::parse(&name).unwrap_or(T::ALL[0].value))
}

/// Parses `--range LO,HI`: two finite numbers, LO < HI.
pub fn parse_range(s: &str) -> std::result::Result<(f64, f64), String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| format!("expected LO,HI (two numbers), got {s:?}: {e}"))?;
    match v.as_slice() {
        [lo, hi] if lo.is_finite() && hi.is_finite() && lo < hi => Ok((*lo, *hi)),
        _ => Err(format!("expected LO,HI with LO < HI, got {s:?}")),
    }
}
