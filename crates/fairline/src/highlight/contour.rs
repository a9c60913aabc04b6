//! Level-set contouring of a per-vertex scalar field on a triangle mesh:
//! nodes on edges by linear interpolation (Yong et al. Eq. (4), with the
//! spacing of Eq. (13)), segments per triangle by the connection rules of
//! §2.4, and chaining into polylines.
//!
//! The field is a value per vertex plus a *branch* per vertex (0 = undefined,
//! ±1 = the side of a discontinuity, e.g. the sign of Z·N for linear lights).
//! An edge is valid when both ends carry the same non-zero branch; a triangle
//! contributes segments only when its three edges are valid, so nothing is
//! drawn across a jump of the field through infinity.

use crate::mesh::{EdgeId, FaceId, HalfedgeId, SurfaceMesh, VertexId};
use crate::{Vec3, geom};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

/// A highlight node (Yong et al. §2.3): the point of level m on a mesh edge,
/// or a vertex lying exactly on level m. Identifies the node across mesh
/// updates as long as it stays on the same element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NodeId {
    /// The node of index m on edge e.
    Edge(EdgeId, i64),
    /// Vertex v whose value equals level m exactly.
    Vertex(VertexId, i64),
}

impl NodeId {
    /// The level (light) index m of the node.
    pub fn index(self) -> i64 {
        match self {
            NodeId::Edge(_, m) | NodeId::Vertex(_, m) => m,
        }
    }
}

/// One highlight line: a polyline through highlight nodes of one index m
/// (Yong et al. §2.4). A closed line does not repeat its first point.
#[derive(Clone, Debug, PartialEq)]
pub struct HighlightLine {
    /// Light index m (for circular lights: the index of the radius).
    pub index: i64,
    /// True when the polyline is a loop.
    pub closed: bool,
    /// Node positions in order (mesh units).
    pub points: Vec<Vec3>,
    /// The node behind each point.
    pub nodes: Vec<NodeId>,
}

/// A highlight line model: all lines, sorted by index and then by their
/// first node (deterministic).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HighlightLines {
    /// The polylines.
    pub lines: Vec<HighlightLine>,
}

impl HighlightLines {
    /// Total number of nodes over all lines.
    pub fn node_count(&self) -> usize {
        self.lines.iter().map(|l| l.nodes.len()).sum()
    }
}

/// Which levels of the field are contoured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Levels {
    /// Levels offset + m·spacing for every integer m (index m).
    Periodic { spacing: f64, offset: f64 },
    /// The single level `value`, reported with index `index`.
    Single { value: f64, index: i64 },
}

impl Levels {
    #[inline]
    pub(crate) fn value(&self, m: i64) -> f64 {
        match *self {
            Levels::Periodic { spacing, offset } => offset + m as f64 * spacing,
            Levels::Single { value, .. } => value,
        }
    }
}

/// Compact node key ordered by (m, kind, element).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct Key {
    m: i64,
    /// bit 32: 1 = edge, 0 = vertex; low 32 bits: element id.
    elem: u64,
}

impl Key {
    #[inline]
    fn vertex(v: u32, m: i64) -> Key {
        Key { m, elem: v as u64 }
    }
    #[inline]
    fn edge(e: u32, m: i64) -> Key {
        Key {
            m,
            elem: (1u64 << 32) | e as u64,
        }
    }
    /// True for a node at a vertex.
    #[inline]
    fn is_vertex(self) -> bool {
        self.elem >> 32 == 0
    }
    #[inline]
    pub(crate) fn node(self) -> NodeId {
        let id = self.elem as u32;
        if self.elem >> 32 == 1 {
            NodeId::Edge(EdgeId(id), self.m)
        } else {
            NodeId::Vertex(VertexId(id), self.m)
        }
    }
}

/// One segment inside a triangle, between two nodes of the same index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    pub(crate) face: u32,
    pub(crate) a: Key,
    pub(crate) b: Key,
}

/// Segments of one triangle for all levels crossing it (Yong et al. §2.4).
/// `max_levels` caps how many levels a single triangle may carry; a triangle
/// crossed by more is skipped (the lines there are below mesh resolution).
// one kernel over the field's parallel arrays; bundling them buys nothing
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn face_segments(
    mesh: &SurfaceMesh,
    f: FaceId,
    values: &[f64],
    branch: &[i8],
    levels: Levels,
    max_levels: i64,
    edge_ok: &impl Fn(usize, usize) -> bool,
    out: &mut Vec<Segment>,
) {
    let h0 = mesh.face_halfedge(f);
    let h1 = mesh.next(h0);
    let h2 = mesh.next(h1);
    let corners = Corners {
        halfedges: [h0.0, h1.0, h2.0],
        vertices: [
            mesh.from_vertex(h0).0,
            mesh.to_vertex(h0).0,
            mesh.to_vertex(h1).0,
        ],
    };
    let field = corners.field(values, branch);
    triangle_segments(f, &corners, field, levels, max_levels, edge_ok, out);
}

/// The halfedges of a triangle (the stored one first, then in order) and
/// its vertices a → b → c (the source of the first halfedge, then the
/// targets): edge k joins vertex k and vertex k + 1.
#[derive(Clone, Copy, Default)]
struct Corners {
    halfedges: [u32; 3],
    vertices: [u32; 3],
}

impl Corners {
    /// The field values and branches at the three vertices.
    #[inline]
    fn field(&self, values: &[f64], branch: &[i8]) -> ([f64; 3], [i8; 3]) {
        let v = self.vertices.map(|v| v as usize);
        (v.map(|v| values[v]), v.map(|v| branch[v]))
    }
}

/// [`face_segments`] of triangle `f` with its corners and their field
/// values and branches already loaded.
#[inline]
fn triangle_segments(
    f: FaceId,
    corners: &Corners,
    (d, br): ([f64; 3], [i8; 3]),
    levels: Levels,
    max_levels: i64,
    edge_ok: &impl Fn(usize, usize) -> bool,
    out: &mut Vec<Segment>,
) {
    let vs = corners.vertices;
    if br[0] == 0 || br[1] != br[0] || br[2] != br[0] {
        return;
    }
    let (a, b, c) = (vs[0] as usize, vs[1] as usize, vs[2] as usize);
    if !(edge_ok(a, b) && edge_ok(b, c) && edge_ok(c, a)) {
        return;
    }
    let lo = d[0].min(d[1]).min(d[2]);
    let hi = d[0].max(d[1]).max(d[2]);
    let (m0, m1) = match levels {
        Levels::Single { value, index } => {
            if value < lo || value > hi {
                return;
            }
            (index, index)
        }
        Levels::Periodic { spacing, offset } => {
            if too_many_levels(lo, hi, spacing, offset, max_levels) {
                return;
            }
            (
                floor((lo - offset) / spacing) as i64,
                ceil((hi - offset) / spacing) as i64,
            )
        }
    };
    // the edge of halfedge h is h / 2 (SurfaceMesh::edge)
    let es = corners.halfedges.map(|h| h >> 1);
    for m in m0..=m1 {
        let l = levels.value(m);
        // Rounding is monotone, so all three differences share the sign of
        // these two: all above or all below the level, no segment (the
        // common case, decided without the edges).
        if lo - l > 0.0 || hi - l < 0.0 {
            continue;
        }
        let s = [sign(d[0] - l), sign(d[1] - l), sign(d[2] - l)];
        let zeros = s.iter().filter(|&&x| x == 0).count();
        match zeros {
            0 => {
                let mut nodes = [Key::vertex(0, 0); 2];
                let mut n = 0;
                for k in 0..3 {
                    if s[k] != s[(k + 1) % 3] {
                        nodes[n] = Key::edge(es[k], m);
                        n += 1;
                    }
                }
                if n == 2 {
                    out.push(seg(f, nodes[0], nodes[1]));
                }
            }
            1 => {
                let k = s.iter().position(|&x| x == 0).unwrap_or(0);
                let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                if s[k1] != s[k2] {
                    // the edge opposite vertex k joins k1 and k2: edge index k1
                    out.push(seg(f, Key::vertex(vs[k], m), Key::edge(es[k1], m)));
                }
            }
            2 => {
                // a highlight edge: both of its vertices lie on the level
                let k = s.iter().position(|&x| x != 0).unwrap_or(0);
                let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                out.push(seg(f, Key::vertex(vs[k1], m), Key::vertex(vs[k2], m)));
            }
            _ => {}
        }
    }
}

/// Whether an element whose field values span `lo..=hi` is crossed by more
/// levels `offset + m·spacing` than `max_levels` allows, counted as
/// `ceil((hi − offset)/spacing) − floor((lo − offset)/spacing) >
/// max_levels + 2`: such an element (near a silhouette, where the lines are finer than
/// the elements) carries no segment. The one rule of mesh triangles
/// ([`face_segments`]) and B-spline grid cells
/// (`highlight::surface::contour_field`, `linear_lights`), so that both
/// draw the same lights.
#[inline]
pub(crate) fn too_many_levels(
    lo: f64,
    hi: f64,
    spacing: f64,
    offset: f64,
    max_levels: i64,
) -> bool {
    let a = floor((lo - offset) / spacing);
    let b = ceil((hi - offset) / spacing);
    !(b - a <= max_levels as f64 + 2.0)
}

/// `x.floor()` without a call into libm (the x86-64 baseline has no
/// rounding instruction and this runs for every triangle): equal to
/// `f64::floor` except that −0.0 may come out as 0.0.
#[inline]
pub(crate) fn floor(x: f64) -> f64 {
    // beyond 2^52 every f64 is an integer (and ±inf, NaN pass through)
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t }
    } else {
        x
    }
}

/// `x.ceil()` without libm, as [`floor`].
#[inline]
pub(crate) fn ceil(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64;
        if t < x { t + 1.0 } else { t }
    } else {
        x
    }
}

#[inline]
fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

#[inline]
fn seg(f: FaceId, a: Key, b: Key) -> Segment {
    let (a, b) = if a <= b { (a, b) } else { (b, a) };
    Segment { face: f.0, a, b }
}

/// Segments of all triangles, in face order (parallel, deterministic): the
/// segments of [`face_segments`] for every face.
///
/// Two things make this pass cheap on large meshes without changing a bit
/// of its result. Most triangles lie between two adjacent levels and carry
/// no segment: with periodic levels each vertex gets its level cell
/// ([`level_cell`]) first, and a triangle whose three vertices lie well
/// inside one cell is passed over without its field values (see
/// [`level_cell`] for why that is exact). And each batch of faces is
/// loaded stage by stage (halfedges, vertices, cells, field values:
/// [`geom::gather_triangles`]), so that the cache misses of different
/// faces overlap (a scan's faces and halfedges lie far apart in memory).
pub(crate) fn all_segments(
    mesh: &SurfaceMesh,
    values: &[f64],
    branch: &[i8],
    levels: Levels,
    max_levels: i64,
    edge_ok: &(impl Fn(usize, usize) -> bool + Sync),
) -> Vec<Segment> {
    const CHUNK: usize = 4096;
    const BATCH: usize = geom::BATCH;
    let cells: Vec<i32> = match levels {
        Levels::Periodic { spacing, offset }
            if spacing > 1e-200 && offset.abs() <= CELL_LIMIT * spacing =>
        {
            values
                .par_iter()
                .map(|&d| level_cell(d, spacing, offset))
                .collect()
        }
        // every vertex "near a level": every face takes the full test
        _ => Vec::new(),
    };
    let cell = |v: u32| cells.get(v as usize).copied().unwrap_or(NEAR_LEVEL);
    let nf = mesh.face_count();
    let chunks: Vec<Vec<Segment>> = (0..nf.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(nf));
            for f0 in (lo..hi).step_by(BATCH) {
                let n = BATCH.min(hi - f0);
                let mut halfedges = [[0u32; 3]; BATCH];
                let mut tri = [[0u32; 3]; BATCH];
                geom::gather_triangles(mesh, f0, &mut halfedges[..n], &mut tri[..n]);
                // the faces that may carry a segment, with their corners
                let mut open = [(0u32, Corners::default()); BATCH];
                let mut k = 0;
                for i in 0..n {
                    // a → b → c: from(h0), to(h0), to(h1)
                    let (h, t) = (halfedges[i], tri[i]);
                    let vertices = [mesh.from_vertex(HalfedgeId(h[0])).0, t[0], t[1]];
                    let c0 = cell(vertices[0]);
                    let may_cross =
                        (c0 == NEAR_LEVEL) | (cell(vertices[1]) != c0) | (cell(vertices[2]) != c0);
                    // kept without a branch (the cells may still be on
                    // their way from memory; a mispredicted branch waits)
                    let corners = Corners {
                        halfedges: h,
                        vertices,
                    };
                    open[k] = ((f0 + i) as u32, corners);
                    k += usize::from(may_cross);
                }
                let mut field = [([0.0; 3], [0i8; 3]); BATCH];
                for (fv, (_, corners)) in field.iter_mut().zip(&open[..k]) {
                    *fv = corners.field(values, branch);
                }
                for ((f, corners), &fv) in open[..k].iter().zip(&field) {
                    triangle_segments(
                        FaceId(*f),
                        corners,
                        fv,
                        levels,
                        max_levels,
                        edge_ok,
                        &mut out,
                    );
                }
            }
            out
        })
        .collect();
    chunks.concat()
}

/// [`level_cell`] of a value within rounding distance of a level (or not
/// finite, or too far out): its triangles take the full test.
const NEAR_LEVEL: i32 = i32::MIN;

/// Largest |cell index| (and |offset| / spacing) for which [`level_cell`]
/// decides; beyond it every value counts as near a level.
const CELL_LIMIT: f64 = 1_048_576.0;

/// The level cell k of a field value d under the levels offset + m·spacing
/// (offset + k·spacing < d < offset + (k + 1)·spacing), when d lies well
/// inside it: q = (d − offset)/spacing is at least 10⁻⁶ from an integer and
/// |q| < 2²⁰; otherwise [`NEAR_LEVEL`].
///
/// A triangle whose three vertices have the same cell k carries no
/// segment in [`triangle_segments`]: its levels run from m0 = k to
/// m1 = k + 1 (the floor and ceiling of the same q, which rounding keeps
/// monotone), and level k lies below every value and level k + 1 above,
/// by a margin (10⁻⁶·spacing) that the rounding of q, of the level values
/// and of the comparisons (relative 10⁻¹⁶ of values below 2²⁰·spacing)
/// cannot close. So skipping it changes nothing.
#[inline]
fn level_cell(d: f64, spacing: f64, offset: f64) -> i32 {
    const MARGIN: f64 = 1e-6;
    let q = (d - offset) / spacing;
    let k = floor(q);
    let frac = q - k;
    if frac > MARGIN && frac < 1.0 - MARGIN && k.abs() < CELL_LIMIT {
        k as i32
    } else {
        NEAR_LEVEL
    }
}

/// Position of a node: the vertex, or the point of level m on the edge by
/// Yong et al. Eq. (4) as corrected in DESIGN.md §3:
/// Q = ((ℓ − d2)·V1 + (d1 − ℓ)·V2) / (d1 − d2) with ℓ the level value.
#[inline]
pub(crate) fn node_position(
    mesh: &SurfaceMesh,
    values: &[f64],
    levels: Levels,
    node: NodeId,
) -> Vec3 {
    let p = mesh.positions();
    match node {
        NodeId::Vertex(v, _) => p[v.idx()],
        NodeId::Edge(e, m) => {
            let (v1, v2) = mesh.edge_vertices(e);
            let (d1, d2) = (values[v1.idx()], values[v2.idx()]);
            let l = levels.value(m);
            let den = d1 - d2;
            if den == 0.0 || !den.is_finite() {
                return 0.5 * (p[v1.idx()] + p[v2.idx()]);
            }
            // convex weights, clamped against rounding
            let t = ((d1 - l) / den).clamp(0.0, 1.0);
            (1.0 - t) * p[v1.idx()] + t * p[v2.idx()]
        }
    }
}

/// No segment / no neighbour.
const NONE: u32 = u32::MAX;

/// Chains segments into polylines (Yong et al. §2.4), deterministically.
/// Segments must be sorted by face (as [`all_segments`] returns them).
/// Duplicate segments (a highlight edge seen from both triangles) count once.
///
/// The result is defined by the node order (m, vertex before edge, element
/// id) and, at each node, the order of its segments (by position in the
/// segment list, highlight edges after all others, by their node pair):
/// first, from every node whose degree is not 2, in that order, each of its
/// unused segments is followed through degree-2 nodes to the next node of
/// another degree (an open line, or a closed one if it returns); then each
/// remaining loop starts at its smallest node along that node's first
/// segment. Lines are sorted by index and first node.
///
/// No global numbering of nodes is needed: a node on edge e lies on at most
/// the two triangles of e, so its other segment is found in the segment run
/// of the face across e (one pass over the faces gives those runs); only
/// nodes at vertices, rare on real data, are grouped by a sort. The lines
/// of each index m share no node and are walked in parallel.
pub(crate) fn chain(
    mesh: &SurfaceMesh,
    segments: &[Segment],
    position: impl Fn(NodeId) -> Vec3 + Sync,
) -> HighlightLines {
    let ns = segments.len();
    if ns == 0 {
        return HighlightLines::default();
    }
    debug_assert!(segments.windows(2).all(|w| w[0].face <= w[1].face));
    let face_first = face_segment_runs(mesh.face_count(), segments);
    let used: Vec<AtomicBool> = (0..ns).map(|_| AtomicBool::new(false)).collect();
    let ranks = SegmentRanks::new(segments, &used);
    let mut links = edge_node_links(mesh, segments, &face_first);
    let vends = vertex_node_ends(segments, &used, &ranks);
    let mut starts = edge_start_ports(segments, &links);
    link_vertex_nodes(&vends, &mut links, &mut starts);
    starts.par_sort_unstable();
    // segments grouped by index m (stable: by position within a group)
    let order = group_by_index(segments);
    let walker = Walker {
        segments,
        links: &links,
        used: &used,
    };
    let walks = walk_all_lines(&walker, &ranks, &starts, &order);
    lines_of_walks(walks, |k| k.node(), position)
}

/// The highlight lines of `walks` (closed flag, path of keys whose node is
/// `node(key)`), positioned by `position`, sorted by (light index, first
/// node): the last step of [`chain`] and of the per-vertex-field
/// contouring.
fn lines_of_walks<K: Copy + Send>(
    walks: Vec<(bool, Vec<K>)>,
    node: impl Fn(K) -> NodeId + Sync,
    position: impl Fn(NodeId) -> Vec3 + Sync,
) -> HighlightLines {
    let mut lines: Vec<HighlightLine> = walks
        .into_par_iter()
        .map(|(closed, path)| {
            let nodes: Vec<NodeId> = path.iter().map(|&k| node(k)).collect();
            HighlightLine {
                index: nodes.first().map_or(0, |n| n.index()),
                closed,
                points: nodes.iter().map(|&nd| position(nd)).collect(),
                nodes,
            }
        })
        .collect();
    lines.sort_by(|a, b| {
        (a.index, a.nodes.first().copied()).cmp(&(b.index, b.nodes.first().copied()))
    });
    HighlightLines { lines }
}

/// `face_first[f]..face_first[f + 1]`: the positions of face f's segments
/// in `segments` (sorted by face).
fn face_segment_runs(nf: usize, segments: &[Segment]) -> Vec<u32> {
    let ns = segments.len();
    let mut face_first = vec![0u32; nf + 1];
    const FCHUNK: usize = 1 << 14;
    face_first
        .par_chunks_mut(FCHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            let f0 = (c * FCHUNK) as u32;
            let mut i = segments.partition_point(|s| s.face < f0);
            for (k, slot) in out.iter_mut().enumerate() {
                let f = f0 + k as u32;
                while i < ns && segments[i].face < f {
                    i += 1;
                }
                *slot = i as u32;
            }
        });
    face_first
}

/// The order of the segments at a node (see [`chain`]).
struct SegmentRanks {
    /// (segment, rank) of the highlight edges kept, by segment.
    highlight_edges: Vec<(u32, u64)>,
}

impl SegmentRanks {
    /// Highlight edges (segments joining two vertex nodes) come once from
    /// each of their triangles: the first of equal ones is kept, the
    /// repeats are marked `used` (never walked). Their rank (order among a
    /// node's segments) is after all other segments, by node pair; the
    /// rank of any other segment is its position.
    fn new(segments: &[Segment], used: &[AtomicBool]) -> Self {
        let mut vv: Vec<(Key, Key, u32)> = segments
            .par_iter()
            .enumerate()
            .filter(|(_, s)| s.a.is_vertex() && s.b.is_vertex())
            .map(|(i, s)| (s.a, s.b, i as u32))
            .collect();
        vv.sort_unstable();
        let mut highlight_edges: Vec<(u32, u64)> = Vec::with_capacity(vv.len());
        let mut pairs = 0u64;
        for (k, &(a, b, i)) in vv.iter().enumerate() {
            if k > 0 && vv[k - 1].0 == a && vv[k - 1].1 == b {
                used[i as usize].store(true, Relaxed); // a repeat: never walked
            } else {
                highlight_edges.push((i, (1u64 << 32) | pairs));
                pairs += 1;
            }
        }
        highlight_edges.sort_unstable();
        SegmentRanks { highlight_edges }
    }

    fn rank(&self, s: u32) -> u64 {
        match self.highlight_edges.binary_search_by_key(&s, |&(i, _)| i) {
            Ok(k) => self.highlight_edges[k].1,
            Err(_) => s as u64,
        }
    }
}

/// `links[s][side]`: the other segment at end `side` (0 = a, 1 = b) of s
/// when that node lies on an edge and has degree 2, else NONE: a node on
/// edge e lies on at most the two triangles of e, so its other segment is
/// in the segment run of the face across e.
fn edge_node_links(mesh: &SurfaceMesh, segments: &[Segment], face_first: &[u32]) -> Vec<[u32; 2]> {
    segments
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            let mut l = [NONE; 2];
            for (side, key) in [s.a, s.b].into_iter().enumerate() {
                if key.is_vertex() {
                    continue;
                }
                let e = key.elem as u32;
                let f0 = mesh.face(mesh.edge_halfedge(EdgeId(e), 0));
                let f1 = mesh.face(mesh.edge_halfedge(EdgeId(e), 1));
                let g = if f0 == Some(FaceId(s.face)) { f1 } else { f0 };
                if let Some(g) = g {
                    let (lo, hi) = (face_first[g.idx()], face_first[g.idx() + 1]);
                    l[side] = (lo..hi)
                        .find(|&t| {
                            t as usize != i
                                && (segments[t as usize].a == key || segments[t as usize].b == key)
                        })
                        .unwrap_or(NONE);
                }
            }
            l
        })
        .collect()
}

/// The segment ends at vertex nodes (node, rank, segment, side), repeats
/// left out, sorted: grouped by node, in rank order.
fn vertex_node_ends(
    segments: &[Segment],
    used: &[AtomicBool],
    ranks: &SegmentRanks,
) -> Vec<(Key, u64, u32, u8)> {
    let mut vends: Vec<(Key, u64, u32, u8)> = segments
        .par_iter()
        .enumerate()
        .filter(|(_, s)| s.a.is_vertex() || s.b.is_vertex())
        .flat_map_iter(|(i, s)| {
            let i = i as u32;
            [(s.a, 0u8), (s.b, 1u8)]
                .into_iter()
                .filter(move |&(k, _)| k.is_vertex())
                .map(move |(k, side)| (k, i, side))
        })
        .filter(|&(_, i, _)| !used[i as usize].load(Relaxed)) // repeats
        .map(|(k, i, side)| (k, ranks.rank(i), i, side))
        .collect();
    vends.sort_unstable();
    vends
}

/// Start ports (node, rank, segment) at the edge nodes whose degree is
/// not 2.
fn edge_start_ports(segments: &[Segment], links: &[[u32; 2]]) -> Vec<(Key, u64, u32)> {
    links
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, l)| {
            let s = &segments[i];
            [(s.a, l[0]), (s.b, l[1])]
                .into_iter()
                .filter(|&(k, t)| !k.is_vertex() && t == NONE)
                .map(move |(k, _)| (k, i as u64, i as u32))
        })
        .collect()
}

/// Links the two segments at each vertex node of degree 2; the ends at
/// vertex nodes of any other degree become start ports.
fn link_vertex_nodes(
    vends: &[(Key, u64, u32, u8)],
    links: &mut [[u32; 2]],
    starts: &mut Vec<(Key, u64, u32)>,
) {
    let mut r0 = 0;
    while r0 < vends.len() {
        let mut r1 = r0 + 1;
        while r1 < vends.len() && vends[r1].0 == vends[r0].0 {
            r1 += 1;
        }
        if r1 - r0 == 2 {
            let (x, y) = (vends[r0], vends[r0 + 1]);
            links[x.2 as usize][x.3 as usize] = y.2;
            links[y.2 as usize][y.3 as usize] = x.2;
        } else {
            starts.extend(vends[r0..r1].iter().map(|&(k, r, i, _)| (k, r, i)));
        }
        r0 = r1;
    }
}

/// Follows segments through degree-2 nodes, marking them used.
struct Walker<'a> {
    segments: &'a [Segment],
    links: &'a [[u32; 2]],
    used: &'a [AtomicBool],
}

impl Walker<'_> {
    /// Follows segment s0 from node `start`. Returns whether the line
    /// closed, its nodes, and the segment after each node.
    fn walk(&self, start: Key, s0: u32) -> (bool, Vec<Key>, Vec<u32>) {
        let mut path = vec![start];
        let mut via = Vec::new();
        let (mut from, mut s) = (start, s0);
        loop {
            self.used[s as usize].store(true, Relaxed);
            via.push(s);
            let seg = &self.segments[s as usize];
            let (to, side) = if seg.a == from {
                (seg.b, 1)
            } else {
                (seg.a, 0)
            };
            if to == start {
                return (true, path, via);
            }
            path.push(to);
            let t = self.links[s as usize][side];
            if t == NONE || self.used[t as usize].load(Relaxed) {
                return (false, path, via);
            }
            from = to;
            s = t;
        }
    }
}

/// Every line, index by index in parallel (the lines of one index share
/// no node): first the open ones from the start ports in order, then each
/// remaining loop from its smallest node along that node's first segment.
/// `order` holds the segments grouped by index.
fn walk_all_lines(
    walker: &Walker,
    ranks: &SegmentRanks,
    starts: &[(Key, u64, u32)],
    order: &[u32],
) -> Vec<(bool, Vec<Key>)> {
    let segments = walker.segments;
    let used = walker.used;
    let mut groups: Vec<(usize, usize)> = Vec::new();
    let mut g0 = 0;
    for k in 1..=order.len() {
        if k == order.len() || segments[order[k] as usize].a.m != segments[order[g0] as usize].a.m {
            groups.push((g0, k));
            g0 = k;
        }
    }
    groups
        .par_iter()
        .flat_map_iter(|&(lo, hi)| {
            let m = segments[order[lo] as usize].a.m;
            let mut out = Vec::new();
            let p0 = starts.partition_point(|p| p.0.m < m);
            for &(k, _, s) in starts[p0..].iter().take_while(|p| p.0.m == m) {
                if !used[s as usize].load(Relaxed) {
                    let (closed, path, _) = walker.walk(k, s);
                    out.push((closed, path));
                }
            }
            // loops: start at the smallest node, along its first segment
            for &s in &order[lo..hi] {
                if used[s as usize].load(Relaxed) {
                    continue;
                }
                let (closed, mut path, via) = walker.walk(segments[s as usize].a, s);
                if closed {
                    let n = path.len();
                    let j = (0..n).min_by_key(|&j| path[j]).unwrap_or(0);
                    // via[j] leaves node j forwards, via[j - 1] backwards
                    if ranks.rank(via[j]) <= ranks.rank(via[(j + n - 1) % n]) {
                        path.rotate_left(j);
                    } else {
                        path.reverse();
                        path.rotate_left(n - 1 - j);
                    }
                }
                out.push((closed, path));
            }
            out
        })
        .collect()
}

/// Positions of the segments sorted by (index m, position): a counting sort
/// when the indices span a range comparable to the number of segments, a
/// comparison sort otherwise (same order).
fn group_by_index(segments: &[Segment]) -> Vec<u32> {
    let (lo, hi) = segments
        .par_iter()
        .map(|s| (s.a.m, s.a.m))
        .reduce(|| (i64::MAX, i64::MIN), |x, y| (x.0.min(y.0), x.1.max(y.1)));
    let span = (hi as i128 - lo as i128 + 1).max(0) as u128;
    if span <= 2 * segments.len() as u128 + 1024 {
        let mut count = vec![0u32; span as usize + 1];
        for s in segments {
            count[(s.a.m - lo) as usize + 1] += 1;
        }
        for k in 1..count.len() {
            count[k] += count[k - 1];
        }
        let mut order = vec![0u32; segments.len()];
        for (i, s) in segments.iter().enumerate() {
            let c = &mut count[(s.a.m - lo) as usize];
            order[*c as usize] = i as u32;
            *c += 1;
        }
        order
    } else {
        let mut order: Vec<u32> = (0..segments.len() as u32).collect();
        order.par_sort_unstable_by_key(|&i| (segments[i as usize].a.m, i));
        order
    }
}

#[cfg(test)]
/// The previous chaining by one sort of all segment ends, kept as the
/// reference [`chain`] must reproduce exactly: open lines first from their
/// end nodes, then loops, visiting nodes in key order.
/// Duplicate segments (a highlight edge seen from both triangles) count once.
///
/// One sort of the 2·#segments segment ends by node key gives both the node
/// numbering and each node's incident segments (the run of equal keys), so
/// no search structure is built.
pub(crate) fn chain_reference(
    segments: &[Segment],
    position: impl Fn(NodeId) -> Vec3 + Sync,
) -> HighlightLines {
    // Only a segment between two vertex nodes (a highlight edge) can occur
    // twice, once from each of its triangles; drop the repeats.
    let mut pairs: Vec<(Key, Key)> = Vec::with_capacity(segments.len());
    let mut vertex_pairs: Vec<(Key, Key)> = Vec::new();
    for s in segments {
        if s.a.elem >> 32 == 0 && s.b.elem >> 32 == 0 {
            vertex_pairs.push((s.a, s.b));
        } else {
            pairs.push((s.a, s.b));
        }
    }
    vertex_pairs.sort_unstable();
    vertex_pairs.dedup();
    pairs.extend(vertex_pairs);
    // segment ends (key, 2·segment + side), sorted by key
    let mut ends: Vec<(Key, u32)> = Vec::with_capacity(2 * pairs.len());
    for (i, &(a, b)) in pairs.iter().enumerate() {
        ends.push((a, 2 * i as u32));
        ends.push((b, 2 * i as u32 + 1));
    }
    ends.par_sort_unstable();
    // node numbering: runs of equal keys; offs[v]..offs[v+1] are its ends
    let mut keys: Vec<Key> = Vec::new();
    let mut offs: Vec<usize> = Vec::new();
    let mut node_of_end = vec![0u32; ends.len()];
    for (k, &(key, e)) in ends.iter().enumerate() {
        if keys.last() != Some(&key) {
            keys.push(key);
            offs.push(k);
        }
        node_of_end[e as usize] = (keys.len() - 1) as u32;
    }
    offs.push(ends.len());
    let n = keys.len();
    // the neighbour across the segment of end k, and that segment
    let adj = |k: usize| -> (usize, usize) {
        let e = ends[k].1 as usize;
        (node_of_end[e ^ 1] as usize, e >> 1)
    };
    let deg = |v: usize| offs[v + 1] - offs[v];
    // Lines of different light indices m never share a node, and nodes are
    // ordered by m first: each run of nodes with one m is walked on its
    // own, in parallel. Within a run the order of visits is the global one
    // restricted to it, so the lines are the same as a serial walk's. Each
    // segment belongs to exactly one run, so the flags are never contended.
    let used: Vec<AtomicBool> = (0..pairs.len()).map(|_| AtomicBool::new(false)).collect();
    let mut groups: Vec<(usize, usize)> = Vec::new();
    let mut g0 = 0;
    for v in 1..=n {
        if v == n || keys[v].m != keys[g0].m {
            groups.push((g0, v));
            g0 = v;
        }
    }
    let walk = |start: usize, first: (usize, usize)| -> (bool, Vec<usize>) {
        let mut path = vec![start];
        let (mut cur, mut s) = first;
        loop {
            used[s].store(true, Relaxed);
            if cur == start {
                return (true, path);
            }
            path.push(cur);
            if deg(cur) != 2 {
                return (false, path);
            }
            match (offs[cur]..offs[cur + 1])
                .map(adj)
                .find(|(_, t)| !used[*t].load(Relaxed))
            {
                Some((nxt, t)) => {
                    cur = nxt;
                    s = t;
                }
                None => return (false, path),
            }
        }
    };
    let walks: Vec<(bool, Vec<usize>)> = groups
        .par_iter()
        .flat_map_iter(|&(lo, hi)| {
            let mut walks = Vec::new();
            for v in lo..hi {
                if deg(v) == 2 {
                    continue;
                }
                for k in offs[v]..offs[v + 1] {
                    let (w, s) = adj(k);
                    if !used[s].load(Relaxed) {
                        walks.push(walk(v, (w, s)));
                    }
                }
            }
            for v in lo..hi {
                for k in offs[v]..offs[v + 1] {
                    let (w, s) = adj(k);
                    if !used[s].load(Relaxed) {
                        walks.push(walk(v, (w, s)));
                    }
                }
            }
            walks
        })
        .collect();
    lines_of_walks(walks, |i| keys[i].node(), position)
}

/// Contours `levels` of the per-vertex field (`values`, `branch`) into
/// polylines; see the module documentation.
pub(crate) fn contour(
    mesh: &SurfaceMesh,
    values: &[f64],
    branch: &[i8],
    levels: Levels,
    max_levels: i64,
    edge_ok: &(impl Fn(usize, usize) -> bool + Sync),
) -> HighlightLines {
    let segs = all_segments(mesh, values, branch, levels, max_levels, edge_ok);
    chain(mesh, &segs, |n| node_position(mesh, values, levels, n))
}
