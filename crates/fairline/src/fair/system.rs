//! The quadratic sub-problems of one fairing iteration (Yong et al.
//! §3.3–3.6): residual vectors r(x) ≈ r0 + J x, linear in the normal
//! displacements x of the movable vertices, whose squared norms are the
//! energies.
//!
//! - f_fair (Eq. (6)–(9)): Σ_{i∈I_R} A_i ‖K_i‖² with the mean-curvature
//!   normal K_i = (1 / 2A_i) Σ_j w_ij (V_i − V_j) = H_i N_i, w_ij = ½(cot α_ij +
//!   cot β_ij) from [`geom::halfedge_weights`] and A_i the barycentric area
//!   of Eq. (7) from [`geom::barycentric_vertex_areas`]. Yong et al. Eq. (8)
//!   omits the ½ of the mean-curvature normal (its K is 2H N); fairline uses
//!   H N so that f_fair is the Willmore energy ∫H² dA itself. With w and A
//!   frozen, K_i is linear in x: rows √A_i (K_i⁰ + Σ_k B_ik x_k).
//! - f_diff (Eq. (10)–(14)): Σ l_i ‖Q̄_i(x) − Q̃_i‖² with Q̄_i of Eq. (13),
//!   linearised at x = 0 (Gauss–Newton) with analytic, sparse derivatives
//!   ([`node_linear`]: each node depends on its support vertices only). The
//!   component across the line is linearised, not the full vector: see
//!   [`difference_residual`] for why (the Eq. (13) Jacobian is unbounded).
//!   Yong et al. do not state units (f_diff is a length³, f_fair is
//!   dimensionless, and their ω1 = ω2 = 1 fits their model's size only). To
//!   make the balance independent of the model's scale and resolution,
//!   fairline measures deviations in light spacings s and line length
//!   relative to the region's diameter D (bounding-box diagonal):
//!   f_diff = Σ (l_i/D) (ν_i·(Q̄_i − Q̃_i) / s)², the squared deviation in
//!   spacings integrated along the lines per region diameter.
//! - The diffusion-flow baseline (Xu et al., ∂V/∂t = N Δ_B H): rows
//!   √A_i (Δ_B H)_i for the movable vertices, H_j = N_j·K_j linear in x as
//!   above and (Δ_B H)_i = (1/A_i) Σ_j w_ij (H_j − H_i).

use crate::Vec3;
use crate::geom::{self, LaplaceWeights};
use crate::highlight::{HighlightModel, LightArray, NodeId};
use crate::mesh::{FaceId, SurfaceMesh, VertexId};
use rayon::prelude::*;

/// A sparse row: (column, value) pairs.
type Row = Vec<(u32, f64)>;
/// A sparse row of 3-vectors.
type Row3 = Vec<(u32, Vec3)>;

/// Marks a vertex that is not movable in a column map.
pub(crate) const NOT_MOVABLE: u32 = u32::MAX;

/// Cotangent weights and vertex areas frozen for one iteration (§3.6).
pub(crate) struct Frozen {
    /// ½(cot α + cot β) per halfedge.
    pub w: Vec<f64>,
    /// Barycentric vertex areas, Eq. (7).
    pub areas: Vec<f64>,
}

impl Frozen {
    pub(crate) fn new(mesh: &SurfaceMesh) -> Self {
        Frozen {
            w: geom::halfedge_weights(mesh, LaplaceWeights::Cotangent),
            areas: geom::barycentric_vertex_areas(mesh),
        }
    }

    /// K_i = (1 / 2A_i) Σ_j w_ij (V_i − V_j) and Σ_j w_ij; `None` for a
    /// vertex of zero area.
    fn curvature_normal(&self, mesh: &SurfaceMesh, v: VertexId) -> Option<(Vec3, f64)> {
        let a = self.areas[v.idx()];
        if !(a > 0.0) {
            return None;
        }
        let p = mesh.positions();
        let xi = p[v.idx()];
        let mut s = Vec3::ZERO;
        let mut sw = 0.0;
        for h in mesh.outgoing(v) {
            let w = self.w[h.idx()];
            s += w * (xi - p[mesh.to_vertex(h).idx()]);
            sw += w;
        }
        let k = s / (2.0 * a);
        k.is_finite().then_some((k, sw))
    }
}

/// A sparse linearised residual r(x) = r0 + J x (rows of J as sorted
/// (column, value) lists).
#[derive(Default)]
pub(crate) struct Residual {
    pub r0: Vec<f64>,
    pub rows: Vec<Vec<(u32, f64)>>,
}

impl Residual {
    /// ‖r0‖².
    pub fn energy(&self) -> f64 {
        self.r0.iter().map(|r| r * r).sum()
    }
    fn push(&mut self, r0: f64, row: Vec<(u32, f64)>) {
        self.r0.push(r0);
        self.rows.push(row);
    }
    /// Appends the rows of `other` scaled by `s`.
    pub fn extend_scaled(&mut self, other: Residual, s: f64) {
        for (r, row) in other.r0.into_iter().zip(other.rows) {
            self.r0.push(s * r);
            self.rows
                .push(row.into_iter().map(|(c, v)| (c, s * v)).collect());
        }
    }
}

/// Merges duplicate columns of a (column, 3-vector) list.
fn merge3(mut v: Vec<(u32, Vec3)>) -> Vec<(u32, Vec3)> {
    v.sort_by_key(|e| e.0);
    let mut out: Vec<(u32, Vec3)> = Vec::with_capacity(v.len());
    for (c, x) in v {
        match out.last_mut() {
            Some(last) if last.0 == c => last.1 += x,
            _ => out.push((c, x)),
        }
    }
    out
}

fn merge1(mut v: Vec<(u32, f64)>) -> Vec<(u32, f64)> {
    v.sort_by_key(|e| e.0);
    let mut out: Vec<(u32, f64)> = Vec::with_capacity(v.len());
    for (c, x) in v {
        match out.last_mut() {
            Some(last) if last.0 == c => last.1 += x,
            _ => out.push((c, x)),
        }
    }
    out
}

/// Splits a 3-vector residual block into three scalar rows.
fn push3(res: &mut Residual, r0: Vec3, cols: &[(u32, Vec3)]) {
    for d in 0..3 {
        res.push(r0[d], cols.iter().map(|&(c, v)| (c, v[d])).collect());
    }
}

/// K_i(x) = K_i⁰ + Σ_k B_ik x_k for vertex `v` (frozen weights): the
/// constant part, Σ w, and the coefficient vectors B_ik of the movable k.
fn curvature_normal_linear(
    mesh: &SurfaceMesh,
    frozen: &Frozen,
    normals: &[Vec3],
    col: &[u32],
    v: VertexId,
) -> Option<(Vec3, Vec<(u32, Vec3)>)> {
    let (k0, sw) = frozen.curvature_normal(mesh, v)?;
    let c = 1.0 / (2.0 * frozen.areas[v.idx()]);
    let mut cols = Vec::new();
    if col[v.idx()] != NOT_MOVABLE {
        cols.push((col[v.idx()], c * sw * normals[v.idx()]));
    }
    for h in mesh.outgoing(v) {
        let j = mesh.to_vertex(h);
        if col[j.idx()] != NOT_MOVABLE {
            cols.push((col[j.idx()], -c * frozen.w[h.idx()] * normals[j.idx()]));
        }
    }
    Some((k0, merge3(cols)))
}

/// f_fair rows (Eq. (6)–(9), frozen areas and cotangents) for the inside
/// vertices `inside`; ‖r0‖² is the region's Willmore energy.
pub(crate) fn willmore_residual(
    mesh: &SurfaceMesh,
    frozen: &Frozen,
    normals: &[Vec3],
    col: &[u32],
    inside: &[VertexId],
) -> Residual {
    let blocks: Vec<Option<(Vec3, Row3)>> = inside
        .par_iter()
        .map(|&v| {
            let (k0, cols) = curvature_normal_linear(mesh, frozen, normals, col, v)?;
            let s = frozen.areas[v.idx()].sqrt();
            Some((s * k0, cols.into_iter().map(|(c, b)| (c, s * b)).collect()))
        })
        .collect();
    let mut res = Residual::default();
    for (r0, cols) in blocks.into_iter().flatten() {
        push3(&mut res, r0, &cols);
    }
    res
}

/// Willmore energy Σ_{i∈I_R} A_i ‖K_i‖² of the region at the current
/// positions (Yong et al. Eq. (6)).
pub(crate) fn region_willmore(mesh: &SurfaceMesh, frozen: &Frozen, inside: &[VertexId]) -> f64 {
    let parts: Vec<f64> = inside
        .par_iter()
        .map(|&v| {
            frozen
                .curvature_normal(mesh, v)
                .map_or(0.0, |(k, _)| frozen.areas[v.idx()] * k.length_squared())
        })
        .collect();
    parts.iter().sum()
}

/// Light quantities of one vertex for the node Jacobian.
struct VertexLight {
    /// Unnormalised Eq. (3) sum of face area vectors.
    n_raw_len: f64,
    /// Unit normal N.
    n: Vec3,
    /// Z·N.
    den: f64,
    /// H × (P − A0).
    u: Vec3,
    /// Highlight distance d.
    d: f64,
}

fn vertex_light(
    mesh: &SurfaceMesh,
    light: &LightArray,
    normals: &[Vec3],
    distances: &[f64],
    v: VertexId,
) -> VertexLight {
    let p = mesh.positions();
    let mut raw = Vec3::ZERO;
    for f in mesh.vertex_faces(v) {
        let [a, b, c] = mesh.triangle(f).map(|w| p[w.idx()]);
        raw += 0.5 * (b - a).cross(c - a);
    }
    let n = normals[v.idx()];
    VertexLight {
        n_raw_len: raw.length(),
        n,
        den: light.plane_normal().dot(n),
        u: light.direction().cross(p[v.idx()] - light.plane_point()),
        d: distances[v.idx()],
    }
}

/// ∂d_a/∂x_k for every movable k in the one-ring of `a` (and `a`), moving
/// V_k along N_k: d = N·u / (Z·N) (Eq. (1) corrected) depends on x_k only
/// through the Eq. (3) normal N_a (the position term N_a·(H × N_a) vanishes
/// for k = a). With n the sum of face area vectors, a triangle's area vector
/// changes by ½ N_k × (V_next − V_prev) when V_k moves by N_k, and
/// dN = (I − N Nᵀ) dn / ‖n‖, dd = dN·(u − d Z) / (Z·N).
fn distance_gradient(
    mesh: &SurfaceMesh,
    light: &LightArray,
    normals: &[Vec3],
    col: &[u32],
    vl: &VertexLight,
    a: VertexId,
) -> Vec<(u32, f64)> {
    if !(vl.n_raw_len > 0.0) || !(vl.den.abs() > 0.0) {
        return Vec::new();
    }
    let p = mesh.positions();
    let g = (vl.u - vl.d * light.plane_normal()) / vl.den;
    let mut out = Vec::new();
    for f in mesh.vertex_faces(a) {
        let tri = mesh.triangle(f);
        for i in 0..3 {
            let k = tri[i];
            let c = col[k.idx()];
            if c == NOT_MOVABLE {
                continue;
            }
            let next = p[tri[(i + 1) % 3].idx()];
            let prev = p[tri[(i + 2) % 3].idx()];
            let dn = 0.5 * normals[k.idx()].cross(next - prev);
            let dn_unit = (dn - vl.n * vl.n.dot(dn)) / vl.n_raw_len;
            out.push((c, dn_unit.dot(g)));
        }
    }
    merge1(out)
}

/// A highlight node linearised in the normal displacements x of the
/// movable vertices.
pub(crate) struct NodeLinear {
    /// Position by Eq. (13) (unclamped), or the vertex.
    pub q: Vec3,
    /// The edge (a, b) and parameter t with Q = (1 − t) V_a + t V_b (for a
    /// vertex node: a = b = the vertex, t = 0).
    pub a: VertexId,
    /// See `a`.
    pub b: VertexId,
    /// See `a`.
    pub t: f64,
    /// Coefficients of δd(Q) = (1 − t) δd_a + t δd_b, the change of the
    /// interpolated highlight distance at the node's point.
    pub dd: Vec<(u32, f64)>,
    /// Coefficients of (1 − t) δV_a + t δV_b.
    pub dv: Vec<(u32, Vec3)>,
}

/// Linearises a highlight node: Eq. (13) position and the sensitivities of
/// the interpolated highlight distance and of the edge point.
pub(crate) fn node_linear(
    mesh: &SurfaceMesh,
    light: &LightArray,
    normals: &[Vec3],
    distances: &[f64],
    col: &[u32],
    node: NodeId,
) -> NodeLinear {
    let p = mesh.positions();
    let (a, b, t, q) = match node {
        NodeId::Vertex(v, _) => (v, v, 0.0, p[v.idx()]),
        NodeId::Edge(e, m) => {
            let (a, b) = mesh.edge_vertices(e);
            let (pa, pb) = (p[a.idx()], p[b.idx()]);
            let den = distances[a.idx()] - distances[b.idx()];
            if den == 0.0 || !den.is_finite() {
                (a, b, 0.5, 0.5 * (pa + pb))
            } else {
                let t = (distances[a.idx()] - m as f64 * light.spacing()) / den;
                (a, b, t, (1.0 - t) * pa + t * pb)
            }
        }
    };
    let mut dd = Vec::new();
    let mut dv = Vec::new();
    for (v, w) in [(a, 1.0 - t), (b, t)] {
        if w == 0.0 || (v == b && a == b) {
            continue;
        }
        let vl = vertex_light(mesh, light, normals, distances, v);
        dd.extend(
            distance_gradient(mesh, light, normals, col, &vl, v)
                .into_iter()
                .map(|(c, g)| (c, w * g)),
        );
        if col[v.idx()] != NOT_MOVABLE {
            dv.push((col[v.idx()], w * normals[v.idx()]));
        }
    }
    if a == b {
        let vl = vertex_light(mesh, light, normals, distances, a);
        dd = distance_gradient(mesh, light, normals, col, &vl, a);
        if col[a.idx()] != NOT_MOVABLE {
            dv = vec![(col[a.idx()], normals[a.idx()])];
        }
    }
    NodeLinear {
        q,
        a,
        b,
        t,
        dd: merge1(dd),
        dv: merge3(dv),
    }
}

/// The Jacobian of Eq. (13) itself: dQ = (1 − t) dV_a + t dV_b +
/// (V_b − V_a) δd(Q) / (d_a − d_b). Its factor 1/(d_a − d_b) is unbounded
/// on edges nearly parallel to the line (see [`difference_residual`]).
#[cfg(test)]
pub(crate) fn node_jacobian(
    mesh: &SurfaceMesh,
    light: &LightArray,
    normals: &[Vec3],
    distances: &[f64],
    col: &[u32],
    node: NodeId,
) -> (Vec3, Vec<(u32, Vec3)>) {
    let nl = node_linear(mesh, light, normals, distances, col, node);
    let p = mesh.positions();
    let mut cols = nl.dv.clone();
    let den = distances[nl.a.idx()] - distances[nl.b.idx()];
    if nl.a != nl.b && den != 0.0 {
        let dir = p[nl.b.idx()] - p[nl.a.idx()];
        cols.extend(nl.dd.iter().map(|&(c, g)| (c, dir * (g / den))));
    }
    (nl.q, merge3(cols))
}

/// In-surface gradient of the linearly interpolated highlight distance at
/// a node: the mean of the gradients over the node's faces (an edge's two
/// faces, a vertex's fan) whose three vertices have a defined distance.
fn distance_field_gradient(
    mesh: &SurfaceMesh,
    model: &HighlightModel,
    node: NodeId,
) -> Option<Vec3> {
    let faces: Vec<FaceId> = match node {
        NodeId::Edge(e, _) => (0..2)
            .filter_map(|i| mesh.face(mesh.edge_halfedge(e, i)))
            .collect(),
        NodeId::Vertex(v, _) => mesh.vertex_faces(v).collect(),
    };
    let p = mesh.positions();
    let mut sum = Vec3::ZERO;
    let mut count = 0.0;
    for f in faces {
        let tri = mesh.triangle(f);
        let Some(d) = tri
            .iter()
            .map(|&v| model.distance(v))
            .collect::<Option<Vec<f64>>>()
        else {
            continue;
        };
        let x = tri.map(|v| p[v.idx()]);
        let area2 = (x[1] - x[0]).cross(x[2] - x[0]);
        let l2 = area2.length_squared();
        if !(l2 > 0.0) {
            continue;
        }
        // ∇φ_i = n × (x_{i+2} − x_{i+1}) / 2A with n the unit normal
        let mut g = Vec3::ZERO;
        for i in 0..3 {
            g += d[i] * area2.cross(x[(i + 2) % 3] - x[(i + 1) % 3]) / l2;
        }
        if g.is_finite() {
            sum += g;
            count += 1.0;
        }
    }
    (count > 0.0).then(|| sum / count)
}

/// Smallest in-surface gradient |∇d| (dimensionless: highlight distance per
/// surface length) at which a node's across-line position is linearised;
/// below it the line's position is undefined to first order and the node
/// gets no row.
const MIN_DISTANCE_GRADIENT: f64 = 1e-3;

/// f_diff rows (Eq. (10)–(14), Gauss–Newton at x = 0) for the desired
/// lines: √(l_i/unit) ν_i·(Q̄_i(x) − Q̃_i) per inside node (unit = D s², see
/// the module documentation), with ν_i the unit
/// in-surface gradient direction of the highlight distance at Q_i (across
/// the line).
///
/// Correction to the paper: Eq. (13) moves a node along its mesh edge at the
/// speed (V_b − V_a)/(d_a − d_b), which is unbounded on edges nearly
/// parallel to the highlight line (on a finely meshed plane it reaches
/// 1e17). That motion along the line is an artefact of where the line
/// crosses the edges, not a change of the line's shape. Its component
/// across the line is bounded: ν·dQ = ν·((1 − t) dV_a + t dV_b) − δd(Q)/|∇d|
/// (the level-set motion of d = m·s), which is the first-order change of the
/// line's shape. fairline therefore linearises the across-line component of
/// Q̄_i − Q̃_i; its along-line component does not change to first order.
pub(crate) fn difference_residual(
    mesh: &SurfaceMesh,
    model: &HighlightModel,
    normals: &[Vec3],
    col: &[u32],
    desired: &super::DesiredLines,
    unit: f64,
) -> (Residual, Vec<DiffNode>) {
    let light = model.light();
    let distances = model.distances();
    let items: Vec<(NodeId, Vec3, f64)> = desired
        .lines
        .iter()
        .flat_map(|l| {
            l.nodes
                .iter()
                .zip(&l.targets)
                .zip(&l.lengths)
                .map(|((&n, &t), &w)| (n, t, w))
        })
        .collect();
    let inv = 1.0 / unit;
    let p = mesh.positions();
    let rows: Vec<Option<(f64, Row, DiffNode)>> = items
        .par_iter()
        .map(|&(node, target, l)| {
            let grad = distance_field_gradient(mesh, model, node)?;
            let g = grad.length();
            if !(g > MIN_DISTANCE_GRADIENT) {
                return None;
            }
            let nu = grad / g;
            let nl = node_linear(mesh, light, normals, distances, col, node);
            let s = (l * inv).sqrt();
            let mut cols: Vec<(u32, f64)> =
                nl.dv.iter().map(|&(c, v)| (c, s * nu.dot(v))).collect();
            cols.extend(nl.dd.iter().map(|&(c, v)| (c, -s * v / g)));
            let base = nu.dot(nl.q - target);
            let info = DiffNode {
                a: nl.a,
                b: nl.b,
                t: nl.t,
                pa: p[nl.a.idx()],
                pb: p[nl.b.idx()],
                level: node.index() as f64 * light.spacing(),
                nu,
                g,
                scale: s,
                base,
            };
            Some((s * base, merge1(cols), info))
        })
        .collect();
    let mut res = Residual::default();
    let mut nodes = Vec::new();
    for (r0, row, info) in rows.into_iter().flatten() {
        if r0.is_finite() && row.iter().all(|c| c.1.is_finite()) {
            res.push(r0, row);
            nodes.push(info);
        }
    }
    (res, nodes)
}

/// What [`difference_energy_after`] needs of one f_diff row.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DiffNode {
    a: VertexId,
    b: VertexId,
    t: f64,
    pa: Vec3,
    pb: Vec3,
    level: f64,
    nu: Vec3,
    g: f64,
    scale: f64,
    base: f64,
}

/// f_diff of the same nodes and targets after the vertices moved,
/// evaluated without linearising the highlight distances: the level line
/// d = m·s near Q_i has moved across the line by
/// ν·((1 − t) δV_a + t δV_b) − (d̄ − m·s)/|∇d|, with d̄ = (1 − t) d_a + t d_b
/// from the updated model. Continuous in the displacements (unlike
/// re-extracting the lines, whose node sets change), so it can judge a
/// Gauss–Newton step; its linearisation is the f_diff rows above.
pub(crate) fn difference_energy_after(
    mesh: &SurfaceMesh,
    model: &HighlightModel,
    nodes: &[DiffNode],
) -> f64 {
    let p = mesh.positions();
    let d = model.distances();
    let parts: Vec<f64> = nodes
        .par_iter()
        .map(|n| {
            let dv = (1.0 - n.t) * (p[n.a.idx()] - n.pa) + n.t * (p[n.b.idx()] - n.pb);
            let dbar = (1.0 - n.t) * d[n.a.idx()] + n.t * d[n.b.idx()];
            let r = n.scale * (n.base + n.nu.dot(dv) - (dbar - n.level) / n.g);
            if r.is_finite() { r * r } else { f64::INFINITY }
        })
        .collect();
    parts.iter().sum()
}

/// Rows √A_i (Δ_B H)_i, i movable, of the diffusion-flow baseline, linear
/// in x with frozen weights and areas (see the module documentation).
pub(crate) fn diffusion_residual(
    mesh: &SurfaceMesh,
    frozen: &Frozen,
    normals: &[Vec3],
    col: &[u32],
    movable: &[VertexId],
) -> Residual {
    // H_j(x) = N_j·K_j(x) for the movable vertices and their one-rings
    let mut need: Vec<u32> = movable
        .iter()
        .flat_map(|&v| std::iter::once(v.0).chain(mesh.one_ring(v).map(|w| w.0)))
        .collect();
    need.sort_unstable();
    need.dedup();
    let lin: Vec<Option<(f64, Row)>> = need
        .par_iter()
        .map(|&j| {
            let v = VertexId(j);
            let (k0, cols) = curvature_normal_linear(mesh, frozen, normals, col, v)?;
            let n = normals[v.idx()];
            Some((
                n.dot(k0),
                cols.into_iter().map(|(c, b)| (c, n.dot(b))).collect(),
            ))
        })
        .collect();
    let lookup = |v: VertexId| -> Option<&(f64, Vec<(u32, f64)>)> {
        need.binary_search(&v.0).ok().and_then(|i| lin[i].as_ref())
    };
    let rows: Vec<Option<(f64, Row)>> = movable
        .par_iter()
        .map(|&i| {
            let a = frozen.areas[i.idx()];
            if !(a > 0.0) {
                return None;
            }
            let hi = lookup(i)?;
            let s = 1.0 / a.sqrt();
            let mut r0 = 0.0;
            let mut cols: Vec<(u32, f64)> = Vec::new();
            for h in mesh.outgoing(i) {
                let w = frozen.w[h.idx()];
                let Some(hj) = lookup(mesh.to_vertex(h)) else {
                    continue;
                };
                r0 += w * (hj.0 - hi.0);
                cols.extend(hj.1.iter().map(|&(c, v)| (c, s * w * v)));
                cols.extend(hi.1.iter().map(|&(c, v)| (c, -s * w * v)));
            }
            Some((s * r0, merge1(cols)))
        })
        .collect();
    let mut res = Residual::default();
    for (r0, row) in rows.into_iter().flatten() {
        if r0.is_finite() && row.iter().all(|c| c.1.is_finite()) {
            res.push(r0, row);
        }
    }
    res
}
