//! The highlight line model of a triangle mesh under an array of linear
//! lights: Yong et al. §2, Algorithm 1, with the corrections of DESIGN.md §3.

use super::HighlightError;
use super::contour::{self, Levels, NodeId, Segment};
use super::light::{LightArray, vertex_distance};
use super::readable::Readability;
use super::{HighlightBands, HighlightLines};
use crate::geom;
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use crate::{Control, Vec3};
use rayon::prelude::*;

/// Options of the highlight line model and of the highlight-line entry
/// points ([`highlight_lines`], [`super::circular_highlight_lines`],
/// [`super::circular_highlight_bands`]).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct HighlightOptions {
    /// Smallest |Z·N| for which a vertex gets a highlight distance (default
    /// 0.1, normals within about 84° of the light plane). Below it the
    /// normal line meets the light plane too far away and d_P runs off to
    /// infinity; edges at such vertices, and edges where Z·N changes sign,
    /// carry no nodes (DESIGN.md §3). Linear lights only.
    pub min_normal_cos: f64,
    /// Most levels (lights) one triangle may be crossed by (default 4);
    /// a triangle crossed by more is skipped: those lines are below the
    /// mesh resolution (this happens only near silhouettes). Linear lights
    /// only (a circular light has one level).
    pub max_lines_per_face: u32,
    /// Progress callback and cancel flag: circular lights take one step per
    /// light (stage `"lights"`); a linear array, whose lights are all
    /// contoured in one pass over the faces, one step per phase (stage
    /// `"highlight model"`: vertex distances, segments, chaining).
    pub control: Control,
}

impl Default for HighlightOptions {
    fn default() -> Self {
        HighlightOptions {
            min_normal_cos: 0.1,
            max_lines_per_face: 4,
            control: Control::default(),
        }
    }
}

impl HighlightOptions {
    /// Sets [`HighlightOptions::min_normal_cos`].
    pub fn min_normal_cos(mut self, c: f64) -> Self {
        self.min_normal_cos = c;
        self
    }
    /// Sets [`HighlightOptions::max_lines_per_face`].
    pub fn max_lines_per_face(mut self, n: u32) -> Self {
        self.max_lines_per_face = n;
        self
    }
    /// Sets [`HighlightOptions::control`].
    pub fn control(mut self, control: Control) -> Self {
        self.control = control;
        self
    }
    fn check(&self) -> Result<(), HighlightError> {
        if !(self.min_normal_cos >= 0.0 && self.min_normal_cos < 1.0) {
            return Err(HighlightError::InvalidOption(format!(
                "min_normal_cos must lie in [0, 1), got {}",
                self.min_normal_cos
            )));
        }
        Ok(())
    }
}

/// The highlight line model of a triangle mesh (Yong et al. Algorithm 1):
/// per-vertex normals (Eq. (3)) and highlight distances (Eq. (1), corrected),
/// the segments of every triangle (§2.4), and the polylines built from them.
///
/// Keeps its per-vertex and per-face state so that
/// [`HighlightModel::update`] can re-derive only what a moved vertex set
/// touches (the fairing loop of Yong et al. Algorithm 2, step 9).
#[derive(Clone, Debug)]
pub struct HighlightModel {
    light: LightArray,
    options: HighlightOptions,
    normals: Vec<Vec3>,
    distances: Vec<f64>,
    /// sign of Z·N, 0 where the distance is undefined
    branch: Vec<i8>,
    /// segments sorted by face
    segments: Vec<Segment>,
}

/// The progress stage of a linear light array and its phases: vertex
/// distances, segments, chaining ([`highlight_lines`]).
const MODEL_STAGE: &str = "highlight model";
const MODEL_PHASES: u64 = 3;

impl HighlightModel {
    /// Builds the model (Yong et al. Algorithm 1). Errors when the mesh has
    /// a face that is not a triangle or an option is out of range.
    /// Degenerate triangles are harmless: they contribute no normal weight
    /// and their segments have zero length.
    pub fn new(
        mesh: &SurfaceMesh,
        light: LightArray,
        options: HighlightOptions,
    ) -> Result<Self, HighlightError> {
        options.check()?;
        mesh.require_triangles()?;
        options.control.step(MODEL_STAGE, 0, MODEL_PHASES)?;
        // one pass per vertex: the Eq. (3) normal (bit-identical to
        // geom::vertex_normals) and the Eq. (1) distance
        let area_vectors = geom::face_area_vectors(mesh);
        let p = mesh.positions();
        let nv = mesh.vertex_count();
        let mut normals = vec![Vec3::ZERO; nv];
        let mut distances = vec![0.0; nv];
        let mut branch = vec![0i8; nv];
        const CHUNK: usize = 4096;
        normals
            .par_chunks_mut(CHUNK)
            .zip(distances.par_chunks_mut(CHUNK))
            .zip(branch.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, ((ns, ds), bs))| {
                geom::vertex_normals_into(mesh, &area_vectors, c * CHUNK, ns);
                let cells = ns.iter().zip(ds.iter_mut()).zip(bs.iter_mut());
                for (k, ((&n, d), b)) in cells.enumerate() {
                    let v = c * CHUNK + k;
                    (*d, *b) = vertex_distance(&light, p[v], n, options.min_normal_cos);
                }
            });
        drop(area_vectors);
        options.control.step(MODEL_STAGE, 1, MODEL_PHASES)?;
        let segments = contour::all_segments(
            mesh,
            &distances,
            &branch,
            Self::levels_of(&light),
            options.max_lines_per_face as i64,
            &|_, _| true,
        );
        Ok(HighlightModel {
            light,
            options,
            normals,
            distances,
            branch,
            segments,
        })
    }

    fn levels_of(light: &LightArray) -> Levels {
        Levels::Periodic {
            spacing: light.spacing(),
            offset: 0.0,
        }
    }

    /// The light array.
    pub fn light(&self) -> &LightArray {
        &self.light
    }
    /// The options.
    pub fn options(&self) -> &HighlightOptions {
        &self.options
    }
    /// Unit vertex normals, Yong et al. Eq. (3).
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }
    /// Highlight distance d_P per vertex, Eq. (1) corrected (mesh units);
    /// `None` where |Z·N| is below `min_normal_cos`.
    pub fn distance(&self, v: VertexId) -> Option<f64> {
        (self.branch[v.idx()] != 0).then(|| self.distances[v.idx()])
    }
    /// All highlight distances (0 where undefined; see [`Self::distance`]).
    pub fn distances(&self) -> &[f64] {
        &self.distances
    }
    /// Number of segments (highlight edges seen from both sides count twice).
    pub fn segment_count(&self) -> usize {
        self.segments.len()
    }

    /// Position of a node on the current mesh: the vertex, or the point of
    /// Yong et al. Eq. (4) as corrected in DESIGN.md §3,
    /// ((m·s − d2)·V1 + (d1 − m·s)·V2) / (d1 − d2).
    pub fn node_position(&self, mesh: &SurfaceMesh, node: NodeId) -> Vec3 {
        contour::node_position(mesh, &self.distances, Self::levels_of(&self.light), node)
    }

    /// The highlight lines: segments chained into open or closed polylines,
    /// each with its light index m (Yong et al. §2.4). `mesh` must be the
    /// mesh the model was built or last updated with.
    /// Chaining is one pass over all segments (a sort of their ends); after
    /// an [`Self::update`], positions of known nodes are cheaper to follow
    /// with [`Self::node_position`].
    pub fn lines(&self, mesh: &SurfaceMesh) -> HighlightLines {
        let levels = Self::levels_of(&self.light);
        contour::chain(mesh, &self.segments, |n| {
            contour::node_position(mesh, &self.distances, levels, n)
        })
    }

    /// The readable drawing of `lines` (this model's lines): cut where
    /// neighbouring lines lie closer than `r.min_separation` on the surface
    /// (spacing/|∇d|, see [`super::readable`]) and without pieces shorter
    /// than `r.min_length`. For pictures only; the lines are the data.
    pub fn readable_lines(
        &self,
        mesh: &SurfaceMesh,
        lines: &HighlightLines,
        r: &Readability,
    ) -> HighlightLines {
        super::readable::readable_lines(
            mesh,
            &self.distances,
            &self.branch,
            self.light.spacing(),
            lines,
            r,
        )
    }

    /// [`Self::lines`] by the previous sort-based chaining, for tests.
    #[cfg(test)]
    pub(crate) fn lines_reference(&self, mesh: &SurfaceMesh) -> HighlightLines {
        let levels = Self::levels_of(&self.light);
        contour::chain_reference(&self.segments, |n| {
            contour::node_position(mesh, &self.distances, levels, n)
        })
    }

    /// Incremental update after the vertices in `moved` changed position
    /// (connectivity unchanged). Recomputes normals and distances of the
    /// moved vertices and their one-ring neighbours (whose Eq. (3) normals
    /// depend on the moved positions) and the segments of every triangle
    /// touching those vertices. The result equals a full rebuild exactly.
    /// Cost: the local work plus one copy of the segment list (no search
    /// over the whole mesh). Returns the number of vertices recomputed.
    pub fn update(
        &mut self,
        mesh: &SurfaceMesh,
        moved: &[VertexId],
    ) -> Result<usize, HighlightError> {
        if mesh.vertex_count() != self.distances.len() {
            return Err(HighlightError::InvalidOption(format!(
                "the mesh has {} vertices, the model {}",
                mesh.vertex_count(),
                self.distances.len()
            )));
        }
        let nv = mesh.vertex_count() as u32;
        let mut affected: Vec<u32> = Vec::new();
        for &v in moved {
            if v.0 >= nv {
                return Err(HighlightError::InvalidOption(format!(
                    "moved vertex {} out of range ({} vertices)",
                    v.0, nv
                )));
            }
            affected.push(v.0);
            affected.extend(mesh.one_ring(v).map(|w| w.0));
        }
        affected.sort_unstable();
        affected.dedup();
        let p = mesh.positions();
        let min_cos = self.options.min_normal_cos;
        let fresh: Vec<(Vec3, f64, i8)> = affected
            .par_iter()
            .map(|&v| {
                let n = geom::vertex_normal(mesh, VertexId(v));
                let (d, b) = vertex_distance(&self.light, p[v as usize], n, min_cos);
                (n, d, b)
            })
            .collect();
        for (&v, &(n, d, b)) in affected.iter().zip(&fresh) {
            self.normals[v as usize] = n;
            self.distances[v as usize] = d;
            self.branch[v as usize] = b;
        }
        let mut faces: Vec<u32> = affected
            .iter()
            .flat_map(|&v| mesh.vertex_faces(VertexId(v)).map(|f| f.0))
            .collect();
        faces.sort_unstable();
        faces.dedup();
        let levels = Self::levels_of(&self.light);
        let mut new_segments = Vec::new();
        for &f in &faces {
            contour::face_segments(
                mesh,
                FaceId(f),
                &self.distances,
                &self.branch,
                levels,
                self.options.max_lines_per_face as i64,
                &|_, _| true,
                &mut new_segments,
            );
        }
        // Segments are sorted by face: copy the untouched runs between the
        // affected faces wholesale and put the fresh segments in their place.
        let old = std::mem::take(&mut self.segments);
        let mut merged = Vec::with_capacity(old.len() + new_segments.len());
        let mut fresh = new_segments.as_slice();
        let mut at = 0usize;
        for &f in &faces {
            let start = at + old[at..].partition_point(|s| s.face < f);
            let end = start + old[start..].partition_point(|s| s.face == f);
            merged.extend_from_slice(&old[at..start]);
            let k = fresh.partition_point(|s| s.face == f);
            merged.extend_from_slice(&fresh[..k]);
            fresh = &fresh[k..];
            at = end;
        }
        merged.extend_from_slice(&old[at..]);
        self.segments = merged;
        Ok(affected.len())
    }

    /// Band boundaries of lights of radius `rho` (> 0): the level sets
    /// d_P = m·s − ρ (`lower`) and d_P = m·s + ρ (`upper`), each reported
    /// with the index m of its light; a band is the strip between them.
    pub fn bands(&self, mesh: &SurfaceMesh, rho: f64) -> Result<HighlightBands, HighlightError> {
        if !(rho > 0.0) || !rho.is_finite() {
            return Err(HighlightError::InvalidOption(format!(
                "band radius must be a positive finite number, got {rho}"
            )));
        }
        let s = self.light.spacing();
        let max = self.options.max_lines_per_face as i64;
        let band = |offset: f64| {
            contour::contour(
                mesh,
                &self.distances,
                &self.branch,
                Levels::Periodic { spacing: s, offset },
                max,
                &|_, _| true,
            )
        };
        Ok(HighlightBands {
            radius: rho,
            lower: band(-rho),
            upper: band(rho),
        })
    }
}

/// The highlight lines of a triangle mesh under a linear light array
/// (Yong et al. Algorithm 1 with Eq. (1), (3), (4) as corrected in
/// DESIGN.md §3). Errors on non-triangle meshes, and with
/// [`HighlightError::Cancelled`] when `options.control` asks to stop.
pub fn highlight_lines(
    mesh: &SurfaceMesh,
    light: &LightArray,
    options: &HighlightOptions,
) -> Result<HighlightLines, HighlightError> {
    let model = HighlightModel::new(mesh, *light, options.clone())?;
    options.control.step(MODEL_STAGE, 2, MODEL_PHASES)?;
    let lines = model.lines(mesh);
    options
        .control
        .progress(MODEL_STAGE, MODEL_PHASES, MODEL_PHASES);
    Ok(lines)
}
