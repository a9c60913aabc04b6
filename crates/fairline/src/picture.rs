//! Pictures of meshes: the glue between [`crate::mesh`], [`crate::geom`] and
//! the software renderer of [`crate::render`]. Polygon meshes are
//! triangulated for drawing; vertices are smooth-shaded with area-weighted
//! normals; scalar fields are colour-mapped with a legend.

use crate::Vec3;
use crate::geom::vertex_normals;
use crate::highlight::LightArray;
use crate::mesh::{SurfaceMesh, triangle_list};
use crate::render::{
    Colormap, Image, Legend, MeshLayer, PlacedLabel, PolylineLayer, ReflectionZebra, RegionLabels,
    RenderError, RenderOptions, Scene, render, render_labelled, scalar_colors,
};

/// A mesh prepared for drawing: triangles and smooth vertex normals.
#[derive(Clone, Debug)]
pub struct MeshView {
    /// Vertex positions (those of the mesh).
    pub positions: Vec<Vec3>,
    /// Triangles (polygons triangulated).
    pub triangles: Vec<[u32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Polygon edges (for wireframes of quad meshes), as vertex pairs.
    pub edges: Vec<[u32; 2]>,
}

impl MeshView {
    /// Prepares `mesh` for drawing.
    pub fn new(mesh: &SurfaceMesh) -> MeshView {
        let triangles = if mesh.is_triangle_mesh() {
            mesh.faces()
                .map(|f| mesh.triangle(f).map(|v| v.0))
                .collect()
        } else {
            triangle_list(mesh)
        };
        let edges = mesh
            .edges()
            .map(|e| {
                let (a, b) = mesh.edge_vertices(e);
                [a.0, b.0]
            })
            .collect();
        MeshView {
            positions: mesh.positions().to_vec(),
            triangles,
            normals: vertex_normals(mesh),
            edges,
        }
    }

    /// A smooth-shaded layer of this mesh.
    pub fn layer(&self) -> MeshLayer<'_> {
        MeshLayer::new(&self.positions, &self.triangles).with_normals(&self.normals)
    }

    /// The polygon edges as thin polylines (a wireframe that shows quads as
    /// quads), in `color`.
    pub fn edge_polylines(&self, color: [f32; 3], width_px: f32) -> Vec<PolylineLayer> {
        self.edges
            .iter()
            .map(|&[a, b]| PolylineLayer {
                points: vec![self.positions[a as usize], self.positions[b as usize]],
                closed: false,
                color,
                width_px,
            })
            .collect()
    }
}

/// The camera rule's view of `mesh` ([`crate::render::part_view`] over its
/// triangles, polygons triangulated): the view every picture of the part
/// starts from.
pub fn part_view(mesh: &SurfaceMesh) -> crate::render::PartView {
    let triangles: Vec<[u32; 3]> = if mesh.is_triangle_mesh() {
        mesh.faces()
            .map(|f| mesh.triangle(f).map(|v| v.0))
            .collect()
    } else {
        triangle_list(mesh)
    };
    crate::render::part_view(mesh.positions(), &triangles)
}

/// Stripe spacing on the picture, pixels, that [`zebra_period`] aims at.
pub const ZEBRA_STRIPE_PX: f64 = 20.0;

/// The reflection zebra of a picture of `mesh` drawn with `opts`: tubes
/// along the direction of `light`, its plane normal the zenith
/// ([`ReflectionZebra::new`]), one stripe per `period_deg` degrees, or when
/// `None` per the [`zebra_period`] of the picture. `None` when the light's
/// direction lies along its plane normal or the period is not a positive
/// number.
pub fn reflection_zebra(
    mesh: &SurfaceMesh,
    light: &LightArray,
    opts: &RenderOptions,
    period_deg: Option<f64>,
) -> Option<ReflectionZebra> {
    let period = period_deg.unwrap_or_else(|| zebra_period(mesh, light, opts));
    ReflectionZebra::new(light.direction(), light.plane_normal(), period)
}

/// The default period (degrees) of a reflection zebra under `light` on a
/// picture of `mesh` drawn with `opts`: stripes about [`ZEBRA_STRIPE_PX`]
/// apart. The reflected angle ([`ReflectionZebra::stripe`]) is taken at
/// every vertex, its normal turned towards the camera (the ray along the
/// view direction; open panels are seen from either side); its spread (the
/// 5th to 95th percentile, the shorter way round the turn) over the part's
/// size on the picture (about 80 % of the shorter side) gives degrees per
/// pixel. Clamped to 0.5°–45°; 10° when fewer than two vertices have a
/// normal.
pub fn zebra_period(mesh: &SurfaceMesh, light: &LightArray, opts: &RenderOptions) -> f64 {
    let Some(probe) = ReflectionZebra::new(light.direction(), light.plane_normal(), 1.0) else {
        return 10.0;
    };
    let ray = opts.view_dir.try_normalize().unwrap_or(-Vec3::Z);
    let normals = vertex_normals(mesh);
    let mut angles: Vec<f64> = normals
        .iter()
        .filter(|n| n.length_squared() > 0.0)
        .map(|n| if n.dot(ray) > 0.0 { -*n } else { *n })
        .map(|n| probe.stripe(ray, n))
        .filter(|a| a.is_finite())
        .collect();
    if angles.len() < 2 {
        return 10.0;
    }
    let spread = |a: &mut Vec<f64>| {
        a.sort_by(f64::total_cmp);
        let q = |p: f64| a[((a.len() - 1) as f64 * p).round() as usize];
        q(0.95) - q(0.05)
    };
    let direct = spread(&mut angles);
    let mut turned: Vec<f64> = angles.iter().map(|a| a.rem_euclid(360.0)).collect();
    let spread_deg = direct.min(spread(&mut turned)).max(1e-6);
    let pixels = 0.8 * f64::from(opts.width.min(opts.height)).max(1.0);
    (ZEBRA_STRIPE_PX * spread_deg / pixels).clamp(0.5, 45.0)
}

/// Colour of the halo [`zebra_halos`] lays under lines (linear light).
pub const ZEBRA_HALO_COLOR: [f32; 3] = [0.85, 0.86, 0.88];
/// How much wider than its line a halo is, pixels (both sides together).
pub const ZEBRA_HALO_PX: f32 = 2.4;

/// `polylines` as drawn over a reflection zebra: each with a light halo
/// ([`ZEBRA_HALO_COLOR`], [`ZEBRA_HALO_PX`] wider) under it, every halo
/// before every line, so that dark lines stay readable across the zebra's
/// dark stripes and no halo covers another line.
pub fn zebra_halos(polylines: &[PolylineLayer]) -> Vec<PolylineLayer> {
    let halos = polylines.iter().map(|l| PolylineLayer {
        color: ZEBRA_HALO_COLOR,
        width_px: l.width_px + ZEBRA_HALO_PX,
        ..l.clone()
    });
    halos.chain(polylines.iter().cloned()).collect()
}

/// A per-vertex scalar field to colour a mesh with.
#[derive(Clone, Debug)]
pub struct ScalarField<'a> {
    /// Legend title, e.g. "mean curvature".
    pub name: String,
    /// One value per vertex.
    pub values: &'a [f64],
    /// Colour map (diverging maps are centred on 0).
    pub colormap: Colormap,
    /// Fixed range, or `None` for the robust automatic range.
    pub range: Option<(f64, f64)>,
}

/// What to draw over one mesh.
#[derive(Clone, Debug, Default)]
pub struct Picture<'a> {
    /// Optional colour-mapped scalar field.
    pub scalar: Option<ScalarField<'a>>,
    /// Polylines drawn over the surface (highlight lines, outlines).
    pub polylines: Vec<PolylineLayer>,
    /// Draw the polygon edges.
    pub wireframe: bool,
    /// Title at the top.
    pub title: Option<String>,
    /// A reflection zebra over the shading, under the polylines.
    pub zebra: Option<ReflectionZebra>,
}

/// Renders one mesh with an optional scalar field, polylines and wireframe.
pub fn mesh_picture(
    mesh: &SurfaceMesh,
    picture: &Picture<'_>,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    mesh_picture_impl(mesh, picture, None, opts).map(|(img, _)| img)
}

/// [`mesh_picture`] with text labels on regions of faces (e.g. the patch
/// index of every face of a tessellated part of many patches):
/// `labels.triangle_region[f]` is the region of face `f` of a triangle mesh
/// (polygon meshes: of the triangles of [`MeshView::new`], in order); each
/// visible region is labelled at its visible centre
/// ([`crate::render::render_labelled`]). Returns the labels drawn too.
pub fn labelled_mesh_picture(
    mesh: &SurfaceMesh,
    picture: &Picture<'_>,
    labels: &RegionLabels,
    opts: &RenderOptions,
) -> Result<(Image, Vec<PlacedLabel>), RenderError> {
    mesh_picture_impl(mesh, picture, Some(labels), opts)
}

fn mesh_picture_impl(
    mesh: &SurfaceMesh,
    picture: &Picture<'_>,
    labels: Option<&RegionLabels>,
    opts: &RenderOptions,
) -> Result<(Image, Vec<PlacedLabel>), RenderError> {
    let view = MeshView::new(mesh);
    let mut legend = None;
    let colors;
    let mut layer = view.layer().with_zebra(picture.zebra);
    if let Some(field) = &picture.scalar {
        let (c, (lo, hi)) = scalar_colors(field.values, field.colormap, field.range);
        colors = c;
        layer = layer.with_colors(&colors);
        legend = Some(Legend {
            title: field.name.clone(),
            colormap: field.colormap,
            min: lo,
            max: hi,
            clipped: crate::render::clipped(field.values, (lo, hi)),
        });
    }
    let mut polylines = Vec::new();
    if picture.wireframe {
        polylines.extend(view.edge_polylines([0.08, 0.08, 0.1], 0.8));
    }
    if picture.zebra.is_some() {
        polylines.extend(zebra_halos(&picture.polylines));
    } else {
        polylines.extend(picture.polylines.iter().cloned());
    }
    let scene = Scene {
        meshes: vec![layer],
        polylines,
        points: Vec::new(),
        legend,
        title: picture.title.clone(),
    };
    match labels {
        Some(l) => render_labelled(&scene, opts, l),
        None => render(&scene, opts).map(|img| (img, Vec::new())),
    }
}

/// Colour of the highlight lines in [`fairing_picture`] (near black).
pub const FAIRING_LINE_COLOR: [f32; 3] = [0.02, 0.02, 0.02];
/// Colour of the region outline in [`fairing_picture`] (red).
pub const FAIRING_OUTLINE_COLOR: [f32; 3] = [0.85, 0.05, 0.05];
/// Colour of the desired OGH curves in [`fairing_picture`] (blue).
pub const FAIRING_DESIRED_COLOR: [f32; 3] = [0.05, 0.25, 0.95];

/// Before/after picture of a highlight-line fairing run (Yong et al.
/// Fig. 7): on the left `before` with its highlight lines (dark), the region
/// outline (red) and the desired OGH curves (blue) of the report; on the
/// right `after` (the input with the output's positions) with its highlight
/// lines and the outline. A `zebra` is drawn under both panels' lines.
pub fn fairing_picture(
    before: &SurfaceMesh,
    after: &SurfaceMesh,
    report: &crate::fair::FairReport,
    zebra: Option<ReflectionZebra>,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    use crate::fair::FairMethod;
    use crate::highlight::HighlightLines;
    use crate::render::side_by_side;
    let lines = |ls: &HighlightLines| -> Vec<PolylineLayer> {
        ls.lines
            .iter()
            .map(|l| PolylineLayer {
                points: l.points.clone(),
                closed: l.closed,
                color: FAIRING_LINE_COLOR,
                width_px: 1.6,
            })
            .collect()
    };
    let outline: Vec<PolylineLayer> = report
        .region
        .outline(before)
        .into_iter()
        .map(|(a, b)| PolylineLayer {
            points: vec![a, b],
            closed: false,
            color: FAIRING_OUTLINE_COLOR,
            width_px: 2.2,
        })
        .collect();
    let mut left = lines(&report.lines_before);
    left.extend(report.desired_before.lines.iter().map(|d| PolylineLayer {
        points: d.samples.clone(),
        closed: false,
        color: FAIRING_DESIRED_COLOR,
        width_px: 2.4,
    }));
    left.extend(outline.iter().cloned());
    let mut right = lines(&report.lines_after);
    right.extend(outline);
    let a = mesh_picture(
        before,
        &Picture {
            polylines: left,
            title: Some("before: highlight lines, region, desired lines".into()),
            zebra,
            ..Default::default()
        },
        opts,
    )?;
    let b = mesh_picture(
        after,
        &Picture {
            polylines: right,
            title: Some(
                match report.method {
                    FairMethod::Highlight => "after highlight-line fairing",
                    FairMethod::Paper => "after highlight-line fairing (Yong et al.)",
                    FairMethod::DiffusionFlow => "after surface diffusion flow (baseline)",
                    FairMethod::Membrane => "after membrane-energy fairing",
                    FairMethod::ThinPlate => "after thin-plate-energy fairing",
                    FairMethod::Mvs => "after minimum-variation fairing",
                }
                .into(),
            ),
            zebra,
            ..Default::default()
        },
        opts,
    )?;
    Ok(side_by_side(&[a, b], &["before", "after"]))
}
