//! Pictures of meshes: the glue between [`crate::mesh`], [`crate::geom`] and
//! the software renderer of [`crate::render`]. Polygon meshes are
//! triangulated for drawing; vertices are smooth-shaded with area-weighted
//! normals; scalar fields are colour-mapped with a legend.

use crate::Vec3;
use crate::geom::vertex_normals;
use crate::mesh::{SurfaceMesh, triangle_list};
use crate::render::{
    Colormap, Image, Legend, MeshLayer, PlacedLabel, PolylineLayer, RegionLabels, RenderError,
    RenderOptions, Scene, render, render_labelled, scalar_colors,
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
    /// A reflection zebra over the shading.
    pub zebra: Option<crate::render::ReflectionZebra>,
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
    polylines.extend(picture.polylines.iter().cloned());
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
/// lines and the outline.
pub fn fairing_picture(
    before: &SurfaceMesh,
    after: &SurfaceMesh,
    report: &crate::fair::FairReport,
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
            ..Default::default()
        },
        opts,
    )?;
    Ok(side_by_side(&[a, b], &["before", "after"]))
}
