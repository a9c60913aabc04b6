//! Fair surfaces with G¹ boundary conditions by Δ_B H = 0 (Schneider and
//! Kobbelt; Grüner thesis §3.4, Eq. (25)–(29)).

use super::{
    Constraints, Role, SmoothError, SmoothReport, StopReason, max_distance, roles, setters,
};
use crate::geom::{self, LaplaceWeights};
use crate::mesh::{SurfaceMesh, VertexId};
use crate::solve::{ConstrainedOptions, ConstrainedSolver, least_squares, sparse_from_triplets};
use crate::{Control, Output, Vec3};

/// Options of [`schneider_kobbelt`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SchneiderKobbeltOptions {
    /// Upper bound on the outer iterations M_k → M_{k+1}.
    pub max_iterations: usize,
    /// Stop when the largest normal move divided by the mean edge length is
    /// below ε.
    pub epsilon: f64,
    /// Further fixed vertices (bit-identical in the output). The boundary
    /// vertices and their normals are always fixed (the G¹ boundary
    /// condition).
    pub fixed: Vec<VertexId>,
    /// G¹ normals of constrained vertices (normalised). Constrained
    /// boundary vertices not listed get the normal of a quadric fit over
    /// their input `normal_fit_rings`-ring ([`geom::quadric_fit_rings`]),
    /// falling back to the vertex normal, made perpendicular to the
    /// boundary curve (its tangent, or both one-sided tangents at a
    /// corner): a surface through the fixed boundary cannot have a normal
    /// with a component along it. Given normals are taken as they are.
    pub normals: Vec<(VertexId, Vec3)>,
    /// Rings of the quadric fit ([`geom::quadric_fit_rings`]) that
    /// estimates the G¹ normals not given in `normals`; `None` chooses them
    /// from the mesh: a fit radius of 0.15 × the bounding-box diagonal,
    /// i.e. ⌈0.15 · diagonal / ē⌉ rings, within 2..=12. A boundary vertex
    /// sees half a disc, so a two-ring fit on a noisy mesh tilts the normal
    /// by about σ/h (0.2 rad for noise of 0.2 edge lengths) and Δ_B H = 0
    /// then bends the whole patch to honour it; wider rings average the
    /// noise out but add the bias of the unmodelled higher-order terms.
    /// Where the true normals are known, pass them in `normals`: with exact
    /// normals the method is exact on a sphere cap.
    pub normal_fit_rings: Option<usize>,
    /// Most work, in evaluations of Δ_B H at one vertex (a sweep costs
    /// about (probe groups of the Jacobian + line-search trials) ×
    /// vertices): a sweep that would take the total beyond it is not
    /// started ([`StopReason::WorkLimit`]).
    pub max_work: u64,
    /// Progress callback and cancel flag (one step per outer iteration).
    pub control: Control,
}

/// Sweeps over which the merit must fall by [`STAGNATION_DECREASE`].
pub const STAGNATION_WINDOW: usize = 5;
/// Least relative decrease of the merit over [`STAGNATION_WINDOW`] sweeps
/// before the iteration counts as stagnated: 10 % in five sweeps is a
/// linear rate of 2 % a sweep, which would need hundreds of sweeps to
/// converge. (A noisy 41² sphere cap crawls at 5 % a sweep for 17 sweeps
/// before the Newton steps take over; the cow "Spot" falls to 1 % a sweep
/// after 25 sweeps and stays there.)
pub const STAGNATION_DECREASE: f64 = 0.1;
/// A residual max |H − H̃|·ē this many times the smallest one so far
/// counts as diverged (the merit falls at every accepted step, the
/// largest residual may rise for a sweep: 1.4× on the 41² cap).
pub const DIVERGENCE_FACTOR: f64 = 4.0;
/// Default of [`SchneiderKobbeltOptions::max_work`]: 10⁷ evaluations of
/// Δ_B H at a vertex, about ten seconds (a sweep over 2,930 vertices costs
/// about 1.5·10⁵, one over 36,000 about 1.5·10⁶).
pub const DEFAULT_MAX_WORK: u64 = 10_000_000;

impl Default for SchneiderKobbeltOptions {
    fn default() -> Self {
        SchneiderKobbeltOptions {
            max_iterations: 50,
            epsilon: 1e-5,
            fixed: Vec::new(),
            normals: Vec::new(),
            normal_fit_rings: None,
            max_work: DEFAULT_MAX_WORK,
            control: Control::default(),
        }
    }
}

setters!(SchneiderKobbeltOptions {
    max_iterations: usize,
    epsilon: f64,
    fixed: Vec<VertexId>,
    normals: Vec<(VertexId, Vec3)>,
    normal_fit_rings: Option<usize>,
    max_work: u64,
    control: Control,
});

/// Moreton–Séquin mean curvature at `x` with normal `n` and neighbours `q`
/// (Eq. (28) and the least-squares fit of Euler's formula): H = Σ g_j κ̃_j,
/// linear in the normal curvatures κ̃_j = 2⟨q_j − x, n⟩ / |q_j − x|². Falls
/// back to the mean of κ̃ (g_j = 1/m) when the 3×3 normal matrix is singular.
fn moreton_sequin(x: Vec3, n: Vec3, q: &[Vec3]) -> f64 {
    let m = q.len();
    let bx = n.any_orthonormal_vector();
    let by = n.cross(bx);
    let mut rows = Vec::with_capacity(m);
    let mut kappa = Vec::with_capacity(m);
    for &qj in q {
        let d = qj - x;
        let l2 = d.length_squared();
        let t = d - d.dot(n) * n;
        let (tx, ty) = (t.dot(bx), t.dot(by));
        let tl = (tx * tx + ty * ty).sqrt();
        let (tx, ty) = if tl > 0.0 {
            (tx / tl, ty / tl)
        } else {
            (0.0, 0.0)
        };
        rows.push([tx * tx, tx * ty, ty * ty]);
        kappa.push(if l2 > 0.0 { 2.0 * d.dot(n) / l2 } else { 0.0 });
    }
    let mut ata = glam::DMat3::ZERO;
    for r in &rows {
        let v = glam::DVec3::from_array(*r);
        ata += glam::DMat3::from_cols(v * r[0], v * r[1], v * r[2]);
    }
    let det = ata.determinant();
    let g: Vec<f64> = if det.abs() > 1e-10 && m >= 3 {
        let inv = ata.inverse();
        // H = ½ (x0 + x2), x = (AᵀA)⁻¹ Aᵀ κ̃  ⇒  g_j = ½ (e0 + e2)ᵀ (AᵀA)⁻¹ a_j
        let sel = inv.transpose() * glam::DVec3::new(0.5, 0.0, 0.5);
        rows.iter()
            .map(|r| sel.dot(glam::DVec3::from_array(*r)))
            .collect()
    } else if m > 0 {
        vec![1.0 / m as f64; m]
    } else {
        Vec::new()
    };
    g.iter().zip(&kappa).map(|(a, b)| a * b).sum()
}

/// State of one outer iteration: normals (fixed G¹ normals at constrained
/// vertices), Moreton–Séquin fits, cotangent half-edge weights and the merit
/// Σ_i (Σ_j w_ij (H_i − H_j))² over the free vertices.
struct Eval {
    normals: Vec<Vec3>,
    fits: Vec<Option<f64>>,
    hw: Vec<f64>,
    /// Σ_j w_ij (H_i − H_j) per free vertex (the residual of Δ_B H = 0).
    f: Vec<f64>,
    merit: f64,
}

/// The free vertices (the unknowns of both second-order problems) and their
/// components, joined by free–free edges.
struct Unknowns {
    /// Row of each vertex among the unknowns (`usize::MAX`: constrained).
    index: Vec<usize>,
    /// Vertex of each unknown.
    vertices: Vec<usize>,
    /// Component of each unknown.
    component: Vec<usize>,
    /// Per component: it touches no constrained vertex (no Dirichlet data).
    floating: Vec<bool>,
}

impl Unknowns {
    /// Numbers the free vertices and finds their components. A component
    /// that touches no constrained vertex — a closed mesh without fixed
    /// vertices — has no Dirichlet data: its harmonic functions are the
    /// constants, the Laplacian block is singular, and H̃ is the
    /// area-weighted mean of H over the component (the harmonic function
    /// nearest to H).
    fn new(roles: &[Role], nbrs: &[Vec<usize>]) -> Unknowns {
        let n = roles.len();
        let mut index = vec![usize::MAX; n];
        let mut vertices = Vec::new();
        for i in 0..n {
            if roles[i] == Role::Free {
                index[i] = vertices.len();
                vertices.push(i);
            }
        }
        let m = vertices.len();
        let mut component = vec![usize::MAX; m];
        let mut floating: Vec<bool> = Vec::new();
        for start in 0..m {
            if component[start] != usize::MAX {
                continue;
            }
            let id = floating.len();
            let mut touches = false;
            component[start] = id;
            let mut stack = vec![vertices[start]];
            while let Some(i) = stack.pop() {
                for &j in &nbrs[i] {
                    let r = index[j];
                    if r == usize::MAX {
                        touches = true;
                    } else if component[r] == usize::MAX {
                        component[r] = id;
                        stack.push(j);
                    }
                }
            }
            floating.push(!touches);
        }
        Unknowns {
            index,
            vertices,
            component,
            floating,
        }
    }

    fn any_floating(&self) -> bool {
        self.floating.iter().any(|f| *f)
    }

    /// The harmonic field's fixed values: constrained vertices and the free
    /// vertices of floating components.
    fn field_fixed(&self) -> Vec<bool> {
        (0..self.index.len())
            .map(|i| self.index[i] == usize::MAX || self.floating[self.component[self.index[i]]])
            .collect()
    }
}

/// Evaluates the discrete Δ_B H of a position vector on the input's
/// connectivity (every geometry quantity through geom's `*_at(positions)`
/// views).
struct Evaluator<'a> {
    mesh: &'a SurfaceMesh,
    roles: &'a [Role],
    /// G¹ normals of the constrained vertices.
    normals0: &'a [Vec3],
    nbrs: &'a [Vec<usize>],
    unknown: &'a [usize],
    /// Evaluations so far (each one costs O(vertices)).
    evaluations: std::cell::Cell<u64>,
}

impl Evaluator<'_> {
    fn evaluate(&self, p: &[Vec3]) -> Eval {
        let (mesh, n) = (self.mesh, self.roles.len());
        self.evaluations.set(self.evaluations.get() + 1);
        let mut normals = geom::vertex_normals_max_at(mesh, p);
        for i in 0..n {
            if self.roles[i] != Role::Free {
                normals[i] = self.normals0[i];
            }
        }
        let fits: Vec<Option<f64>> = (0..n)
            .map(|i| {
                if self.nbrs[i].is_empty() || normals[i] == Vec3::ZERO {
                    return None;
                }
                let q: Vec<Vec3> = self.nbrs[i].iter().map(|&j| p[j]).collect();
                Some(moreton_sequin(p[i], normals[i], &q))
            })
            .collect();
        let hw = geom::halfedge_weights_at(mesh, p, LaplaceWeights::Cotangent);
        // merit: Σ_i (Σ_j w_ij (H_i − H_j))² over the free vertices
        let h_of = |i: usize| fits[i].unwrap_or(0.0);
        let f: Vec<f64> = self
            .unknown
            .iter()
            .map(|&i| {
                mesh.outgoing(VertexId(i as u32))
                    .map(|h| 2.0 * hw[h.idx()] * (h_of(i) - h_of(mesh.to_vertex(h).idx())))
                    .sum()
            })
            .collect();
        let merit = f.iter().map(|x| x * x).sum();
        Eval {
            normals,
            fits,
            hw,
            f,
            merit,
        }
    }
}

/// G¹ normals of the constrained vertices: given in `opts.normals`, else a
/// quadric fit over the input's `normal_fit_rings` rings (a boundary vertex
/// sees only half a fan, which tilts fan normals by O(h)), else the vertex
/// normal; an estimated normal of a boundary vertex is then made
/// perpendicular to the boundary curve ([`perpendicular_to_boundary`]).
/// The fit's error along the curve is not noise the fairing can average
/// out: with the boundary positions fixed it contradicts them, and the
/// Moreton–Séquin estimate of H at the boundary (Eq. (28)), the Dirichlet
/// data of H̃, then bends the first rings to honour it — on noisy sphere
/// caps the largest error sat there, most at the patch corners
/// (BENCHMARKS.md). Free vertices get their vertex normal
/// (replaced every iteration).
fn g1_normals(
    mesh: &SurfaceMesh,
    roles: &[Role],
    opts: &SchneiderKobbeltOptions,
    ebar: f64,
) -> Result<Vec<Vec3>, SmoothError> {
    let n = mesh.vertex_count();
    let fit_rings = opts.normal_fit_rings.unwrap_or_else(|| {
        let (lo, hi) = mesh.positions().iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let rings = 0.15 * (hi - lo).length() / ebar;
        if rings.is_finite() {
            (rings.ceil() as usize).clamp(2, 12)
        } else {
            2
        }
    });
    let mut normals0 = geom::vertex_normals_max(mesh);
    for i in 0..n {
        let v = VertexId(i as u32);
        if roles[i] != Role::Free
            && mesh.is_boundary_vertex(v)
            && let Some(f) = geom::quadric_fit_rings(mesh, v, fit_rings)
        {
            normals0[i] = f.normal;
        }
    }
    for (i, tangents) in boundary_tangents(mesh) {
        if roles[i] != Role::Free {
            normals0[i] = perpendicular_to_boundary(normals0[i], tangents);
        }
    }
    for &(v, nv) in &opts.normals {
        let i = v.idx();
        if i >= n {
            return Err(SmoothError::InvalidOption(format!(
                "normal given for vertex {i}, the mesh has {n}"
            )));
        }
        let l = nv.length();
        if !(l > 0.0) || !l.is_finite() {
            return Err(SmoothError::InvalidOption(format!(
                "normal of vertex {i} is zero or not finite"
            )));
        }
        normals0[i] = nv / l;
    }
    Ok(normals0)
}

/// Tangents of the boundary curve at a boundary vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
enum BoundaryTangents {
    /// A smooth point: the tangent of the parabola through the vertex and
    /// its two neighbours along the boundary.
    Smooth(Vec3),
    /// A kink (the one-sided tangents differ by more than
    /// [`KINK_ANGLE_DEG`]): the incoming and the outgoing one-sided tangents.
    Kink(Vec3, Vec3),
}

/// Angle between the one-sided tangents of the boundary curve above which a
/// boundary vertex is a kink (a corner of the patch) rather than a smooth
/// point of the curve.
const KINK_ANGLE_DEG: f64 = 30.0;

/// Derivative at `x` (chord parameter 0) of the parabola through `x`, `a`
/// (at distance h1 along the curve) and `b` (h2 beyond `a`); second order
/// for any spacing. `None` when two points coincide.
fn one_sided_tangent(x: Vec3, a: Vec3, b: Vec3) -> Option<Vec3> {
    let (h1, h2) = (x.distance(a), a.distance(b));
    if !(h1 > 0.0 && h2 > 0.0) {
        return None;
    }
    let t = -(2.0 * h1 + h2) / (h1 * (h1 + h2)) * x + (h1 + h2) / (h1 * h2) * a
        - h1 / (h2 * (h1 + h2)) * b;
    let t = t.normalize_or_zero();
    (t != Vec3::ZERO && t.is_finite()).then_some(t)
}

/// The tangents of the boundary curves at their vertices (vertex index,
/// tangents), from the boundary polylines: at a smooth point the tangent of
/// the parabola through the previous, the vertex and the next point
/// (chord-length parameter; second order for any spacing), at a kink both
/// one-sided parabola tangents. Loops of fewer than five vertices and
/// coincident points give nothing.
fn boundary_tangents(mesh: &SurfaceMesh) -> Vec<(usize, BoundaryTangents)> {
    let mut out = Vec::new();
    for lp in crate::mesh::boundary_loops(mesh) {
        let k = lp.len();
        if k < 5 {
            continue;
        }
        // the loop's vertices in order: vertex j is where half-edge j starts
        let p: Vec<Vec3> = lp
            .iter()
            .map(|h| mesh.position(mesh.from_vertex(*h)))
            .collect();
        for j in 0..k {
            let at = |d: isize| p[(j as isize + d).rem_euclid(k as isize) as usize];
            let (x, prev, next) = (at(0), at(-1), at(1));
            let (Some(back), Some(ahead)) = (
                one_sided_tangent(x, prev, at(-2)),
                one_sided_tangent(x, next, at(2)),
            ) else {
                continue;
            };
            // back points backwards along the curve, ahead forwards
            let turn = (-back).angle_between(ahead);
            let tangents = if turn.to_degrees() > KINK_ANGLE_DEG {
                BoundaryTangents::Kink(-back, ahead)
            } else {
                let (h1, h2) = (x.distance(prev), x.distance(next));
                // derivative at x of the parabola through prev, x, next
                let t = (h2 * h2 * (x - prev) + h1 * h1 * (next - x)) / (h1 * h2 * (h1 + h2));
                let t = t.normalize_or_zero();
                if t == Vec3::ZERO || !t.is_finite() {
                    continue;
                }
                BoundaryTangents::Smooth(t)
            };
            out.push((mesh.from_vertex(lp[j]).idx(), tangents));
        }
    }
    out
}

/// The unit vector nearest to the estimated normal `n` that is
/// perpendicular to the boundary curve: a surface through the boundary
/// curve has its normal perpendicular to the curve's tangent (at a kink, to
/// both one-sided tangents), so G¹ data with a component along the curve
/// contradict the fixed boundary positions. `n` where the projection
/// vanishes.
fn perpendicular_to_boundary(n: Vec3, tangents: BoundaryTangents) -> Vec3 {
    let m = match tangents {
        BoundaryTangents::Smooth(t) => n - n.dot(t) * t,
        BoundaryTangents::Kink(a, b) => {
            let c = a.cross(b).normalize_or_zero();
            c * c.dot(n).signum()
        }
    };
    let m = m.normalize_or_zero();
    if m == Vec3::ZERO || !m.is_finite() {
        n
    } else {
        m
    }
}

/// The vertices within `depth` rings of `start` (itself first).
fn rings(nbrs: &[Vec<usize>], start: usize, depth: usize) -> Vec<usize> {
    let mut seen = vec![start];
    let mut frontier = vec![start];
    for _ in 0..depth {
        let mut next = Vec::new();
        for &a in &frontier {
            for &b in &nbrs[a] {
                if !seen.contains(&b) {
                    seen.push(b);
                    next.push(b);
                }
            }
        }
        frontier = next;
    }
    seen
}

/// Sparsity and probe colouring of the Newton Jacobian. The residual f_i of
/// a free vertex depends on the positions within two rings of it (H_i and
/// its normal on the one-ring, H_j of the neighbours on theirs, the
/// cotangent weights on the one-ring), so moving vertex k changes only the
/// rows of its two-ring: columns whose two-rings are disjoint (distance
/// above 4) are probed by one finite difference together. Returns the rows of
/// each column and the groups of columns probed together.
fn jacobian_pattern(nbrs: &[Vec<usize>], u: &Unknowns) -> (Vec<Vec<usize>>, Vec<Vec<usize>>) {
    let index = &u.index;
    let support: Vec<Vec<usize>> = u
        .vertices
        .iter()
        .map(|&k| {
            let mut rows: Vec<usize> = rings(nbrs, k, 2)
                .into_iter()
                .filter_map(|i| (index[i] != usize::MAX).then_some(index[i]))
                .collect();
            rows.sort_unstable();
            rows
        })
        .collect();
    let mut colour = vec![usize::MAX; u.vertices.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (c, &k) in u.vertices.iter().enumerate() {
        let taken: Vec<usize> = rings(nbrs, k, 4)
            .into_iter()
            .filter(|&i| index[i] != usize::MAX)
            .map(|i| colour[index[i]])
            .filter(|&g| g != usize::MAX)
            .collect();
        let g = (0..).find(|g| !taken.contains(g)).unwrap_or(0);
        colour[c] = g;
        if g == groups.len() {
            groups.push(Vec::new());
        }
        groups[g].push(c);
    }
    (support, groups)
}

/// Step (1): the harmonic H̃, Σ_j w_ij (H̃_i − H̃_j) = 0 at the free
/// vertices (−L of geom's cotangent Laplacian, by the one constrained
/// solve, its symbolic factorisation kept in `solver`), Dirichlet values H
/// at the constrained vertices; a floating component takes the
/// area-weighted mean of its H as given value.
fn harmonic_mean_curvature(
    mesh: &SurfaceMesh,
    work: &[Vec3],
    ev: &Eval,
    u: &Unknowns,
    field_fixed: &[bool],
    solver: &mut Option<ConstrainedSolver>,
) -> Result<Vec<f64>, SmoothError> {
    let n = mesh.vertex_count();
    let h_of = |i: usize| ev.fits[i].unwrap_or(0.0);
    let (index, component, floating) = (&u.index, &u.component, &u.floating);
    let mut float_mean = vec![(0.0, 0.0); floating.len()];
    if u.any_floating() {
        let area = geom::barycentric_vertex_areas_at(mesh, work);
        for (r, &i) in u.vertices.iter().enumerate() {
            if floating[component[r]] {
                let e = &mut float_mean[component[r]];
                e.0 += area[i] * h_of(i);
                e.1 += area[i];
            }
        }
    }
    let mut htilde: Vec<f64> = (0..n)
        .map(|i| match index[i] {
            usize::MAX => h_of(i),
            r if floating[component[r]] => {
                let (sum, total) = float_mean[component[r]];
                if total > 0.0 { sum / total } else { 0.0 }
            }
            _ => 0.0,
        })
        .collect();
    let mut a = geom::laplacian_from_weights(mesh, &ev.hw);
    let diagonal: Vec<Option<usize>> = {
        let (col_ptr, row_idx) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
        (0..n)
            .map(|j| (col_ptr[j]..col_ptr[j + 1]).find(|&k| row_idx[k] == j))
            .collect()
    };
    let values = a.val_mut();
    for v in values.iter_mut() {
        *v *= -2.0;
    }
    // an isolated free vertex (all weights 0) keeps a solvable row
    for k in diagonal.into_iter().flatten() {
        values[k] = values[k].max(1e-300);
    }
    let harmonic = match solver.as_mut() {
        Some(s) => s,
        None => solver.insert(ConstrainedSolver::analyse(
            a.symbolic(),
            field_fixed,
            &ConstrainedOptions::default(),
        )?),
    };
    harmonic.factor(a.as_ref())?;
    harmonic.solve(&vec![0.0; n], &mut htilde)?;
    Ok(htilde)
}

/// Step (2)'s Jacobian of the residuals Σ_j w_ij (H_i − H_j) in the offsets
/// t along the current normals, by coloured finite differences of the
/// whole evaluation (so it includes what a hand linearisation of Eq. (29)
/// freezes: the normals, the Moreton–Séquin fit weights, the cotangent
/// weights; with frozen terms the step was no descent direction on larger
/// patches). Triplets (row, column, value).
fn finite_difference_jacobian(
    evaluator: &Evaluator,
    ev: &Eval,
    work: &[Vec3],
    support: &[Vec<usize>],
    groups: &[Vec<usize>],
    ebar: f64,
) -> Vec<(usize, usize, f64)> {
    let unknown = evaluator.unknown;
    let step = 1e-6 * ebar;
    let mut jac = Vec::new();
    let mut probe = work.to_vec();
    for group in groups {
        for &c in group {
            let i = unknown[c];
            probe[i] = work[i] + step * ev.normals[i];
        }
        let e = evaluator.evaluate(&probe);
        for &c in group {
            for &r in &support[c] {
                let v = (e.f[r] - ev.f[r]) / step;
                if v != 0.0 && v.is_finite() {
                    jac.push((r, c, v));
                }
            }
            let i = unknown[c];
            probe[i] = work[i];
        }
    }
    jac
}

/// Levenberg–Marquardt step min ‖J t + f‖² + δ‖t‖² with δ = `relative` ·
/// max_c ‖J e_c‖² (m unknowns). On a closed mesh without fixed vertices the
/// residuals sum to zero and moving along the normals of a rigid
/// translation or a scaling leaves Δ_B H unchanged, so J is rank deficient
/// and its normal equations singular; the damping picks the least-norm
/// step. On open patches the damped step also kept a 41×41 noisy cap from
/// stalling where the undamped Gauss–Newton steps ran into a region without
/// descent.
fn damped_step(
    jac: &[(usize, usize, f64)],
    f: &[f64],
    m: usize,
    relative: f64,
) -> Result<Vec<f64>, SmoothError> {
    let mut colsq = vec![0.0f64; m];
    for &(_, c, v) in jac {
        colsq[c] += v * v;
    }
    let delta = relative * colsq.iter().fold(0.0f64, |a, b| a.max(*b));
    let d = if delta > 0.0 { delta.sqrt() } else { 1e-300 };
    let mut trip = jac.to_vec();
    trip.extend((0..m).map(|c| (m + c, c, d)));
    let mut rhs: Vec<f64> = f.iter().map(|x| -x).collect();
    rhs.resize(2 * m, 0.0);
    let jm = sparse_from_triplets(2 * m, m, &trip)?;
    Ok(least_squares(jm.as_ref(), std::slice::from_ref(&rhs))?
        .pop()
        .unwrap_or_default())
}

/// What one Newton iteration of step (2) found.
enum NewtonOutcome {
    /// A step that lowers the merit: new positions, their evaluation and
    /// the size of the Newton step (max |t| / ē).
    Accepted(Vec<Vec3>, Eval, f64),
    /// The Newton step is below ε and lowers nothing: converged in place.
    BelowEpsilon,
    /// No attempt lowered the merit.
    NoDescent,
}

/// Step (2): every free vertex moves along its normal, all offsets at once,
/// by a Newton step on Σ_j w_ij (H_i − H_j) = 0 (Eq. (29)), |t_i| clamped to
/// half the mean length of its edges, kept only when it lowers the merit
/// (backtracking down to 1/64).
fn newton_step(
    evaluator: &Evaluator,
    ev: &Eval,
    work: &[Vec3],
    jac: &[(usize, usize, f64)],
    any_floating: bool,
    ebar: f64,
    epsilon: f64,
) -> Result<NewtonOutcome, SmoothError> {
    let (unknown, nbrs) = (evaluator.unknown, evaluator.nbrs);
    let m = unknown.len();
    let p = work;
    let normals = &ev.normals;
    // the damped step first, the undamped one (unless the system is
    // known to be singular) when it finds no descent
    let undamped = if any_floating {
        None
    } else {
        let rhs: Vec<f64> = ev.f.iter().map(|x| -x).collect();
        let jm = sparse_from_triplets(m, m, jac)?;
        least_squares(jm.as_ref(), std::slice::from_ref(&rhs))
            .ok()
            .and_then(|mut t| t.pop())
    };
    // Attempts, in order: the lightly damped step (1e-12 relative, 1e-10
    // where a component floats), the undamped one, then
    // Levenberg–Marquardt steps with ever stronger damping. Far from
    // Δ_B H = 0 (the cow "Spot": ears, horns and legs) the Gauss–Newton
    // step, clamped to half an edge, often lowers the merit for no step
    // length down to 1/64, so the iteration would stop after one step;
    // a strongly damped step turns toward −Jᵀf, which lowers the merit
    // for a small enough length whenever f is not stationary.
    let light = if any_floating { 1e-10 } else { 1e-12 };
    let attempts: [Option<f64>; 6] = [
        Some(light),
        None,
        Some(1e-6),
        Some(1e-3),
        Some(1e-1),
        Some(10.0),
    ];
    // size of the lightly damped (Newton) step: the convergence measure,
    // whichever attempt is taken (a strongly damped step is short by
    // construction and says nothing about convergence)
    let mut newton_step = f64::INFINITY;
    for attempt in attempts {
        let newton = attempt.is_none_or(|relative| relative <= light);
        let t = match (attempt, &undamped) {
            (Some(relative), _) => damped_step(jac, &ev.f, m, relative)?,
            (None, Some(t)) => t.clone(),
            (None, None) => continue,
        };
        // clamp |t_i| to half the mean length of its edges
        let t: Vec<f64> = unknown
            .iter()
            .enumerate()
            .map(|(r, &i)| {
                let lmean = nbrs[i].iter().map(|&j| p[j].distance(p[i])).sum::<f64>()
                    / nbrs[i].len().max(1) as f64;
                let ti = t.get(r).copied().unwrap_or(0.0);
                if ti.is_finite() && normals[i] != Vec3::ZERO {
                    ti.clamp(-0.5 * lmean, 0.5 * lmean)
                } else {
                    0.0
                }
            })
            .collect();
        let tmax = t.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // backtracking on the merit ‖Σ_j w_ij (H_i − H_j)‖²: far from
        // the solution the linearisation can overshoot; halve the step
        // until the merit drops (a step that lowers it for no α ≥ 1/64
        // is not taken). A Newton step below ε means convergence: it is
        // taken when it lowers the merit (a merit at round-off level
        // cannot be lowered, and the mesh then stays where it is).
        if attempt == Some(light) {
            newton_step = tmax / ebar;
        }
        let small = newton && tmax / ebar < epsilon;
        let mut alpha = 1.0;
        let mut trial = work.to_vec();
        let found = loop {
            for (r, &i) in unknown.iter().enumerate() {
                trial[i] = p[i] + alpha * t[r] * normals[i];
            }
            let e = evaluator.evaluate(&trial);
            if e.merit < ev.merit {
                break Some(e);
            }
            if small || alpha < 1.0 / 64.0 {
                break None;
            }
            alpha *= 0.5;
        };
        if let Some(e) = found {
            let size = if newton {
                alpha * tmax / ebar
            } else {
                newton_step
            };
            return Ok(NewtonOutcome::Accepted(trial, e, size));
        }
        if small {
            return Ok(NewtonOutcome::BelowEpsilon);
        }
    }
    Ok(NewtonOutcome::NoDescent)
}

/// Why [`schneider_kobbelt`] stopped watching its sweeps: the merit
/// history over the last [`STAGNATION_WINDOW`] sweeps, the smallest
/// residual so far and the work done.
struct Progress {
    vertices: u64,
    /// Probe groups of the Jacobian: the evaluations of a sweep at least.
    groups: u64,
    max_work: u64,
    merits: Vec<f64>,
    best_residual: f64,
    /// Evaluations at the start of the last sweep and how many it took.
    last_start: u64,
    last_cost: u64,
    /// Vertex evaluations so far (evaluations × vertices).
    work: u64,
}

impl Progress {
    fn new(vertices: usize, groups: usize, max_work: u64) -> Progress {
        Progress {
            vertices: vertices as u64,
            groups: groups as u64,
            max_work,
            merits: Vec::new(),
            best_residual: f64::INFINITY,
            last_start: 0,
            last_cost: 0,
            work: 0,
        }
    }

    /// Called at the head of every sweep with the current merit, residual
    /// and evaluation count: why to stop, if the sweeps stagnated, diverged
    /// or the next sweep would exceed the work bound.
    fn stop(&mut self, merit: f64, residual: f64, evaluations: u64) -> Option<StopReason> {
        self.last_cost = evaluations - self.last_start;
        self.last_start = evaluations;
        self.work = evaluations.saturating_mul(self.vertices);
        self.merits.push(merit);
        if !residual.is_finite() || residual > DIVERGENCE_FACTOR * self.best_residual {
            return Some(StopReason::Diverged);
        }
        self.best_residual = self.best_residual.min(residual);
        let k = self.merits.len();
        if k > STAGNATION_WINDOW {
            let before = self.merits[k - 1 - STAGNATION_WINDOW];
            if merit > (1.0 - STAGNATION_DECREASE) * before {
                return Some(StopReason::Stagnated);
            }
        }
        let sweep = self.last_cost.max(self.groups + 1);
        let next = self
            .work
            .saturating_add(sweep.saturating_mul(self.vertices));
        (next > self.max_work).then_some(StopReason::WorkLimit)
    }
}

/// Schneider–Kobbelt fairing of a triangle mesh with G¹ boundary (fixed
/// boundary vertices and normals; Grüner §3.4). The fourth-order Δ_B H = 0
/// is factorised into two nested second-order problems per outer iteration
/// M_k → M_{k+1}:
///
/// 1. H̃ solves the discrete Dirichlet problem Σ_j (cot α_j + cot β_j)
///    (H̃_i − H̃_j) = 0 at the free vertices (Eq. (26)–(27), sparse Cholesky,
///    symbolic factorisation reused), with boundary values H_b given by the
///    Moreton–Séquin estimate (Eq. (28) and the Euler-formula fit) at each
///    constrained vertex with its *fixed* G¹ normal and its current
///    neighbours — this is where the normal condition enters;
/// 2. every free vertex moves along its normal, q_i + t_i n_i, so that its
///    Moreton–Séquin mean curvature equals H̃_i (Eq. (29)). Moving q_j
///    changes κ̃_j at q_i by the same order as moving q_i, and the normals,
///    fit weights and cotangent weights move too, so the t_i are solved
///    together: one Newton step on the residuals Σ_j w_ij (H_i − H_j) of the
///    free vertices, with the Jacobian by finite differences of the whole
///    evaluation, coloured so that vertices more than four rings apart are
///    probed together (a residual depends on its two-ring only), and solved
///    by sparse least squares (`solve::least_squares`). |t_i| is limited to
///    half the mean length of its edges. (A vertex-by-vertex update converges
///    like Jacobi on a Laplacian; a hand linearisation that freezes normals
///    and weights gave no descent direction on a 61×61 dented roof.)
///
/// Closed meshes and meshes constrained only by fixed vertices: a free
/// component that touches no constrained vertex has no Dirichlet data for
/// H̃; its harmonic functions are the constants and H̃ is the area-weighted
/// mean of H there. The Newton system is then rank deficient (a rigid
/// motion or a scaling along the normals keeps Δ_B H = 0) and is solved with
/// a Levenberg–Marquardt damping of 1e-10 relative (the least-norm step); a
/// noisy closed sphere converges back onto a sphere.
///
/// Iterates until max |t| / ē < ε (ē the input mean edge length), or until
/// the Newton step itself is below ε (the mesh already satisfies
/// Δ_B H = 0 to round-off, e.g. a perfect sphere: converged, 0 iterations); the report
/// gives the accepted iterations and the final residual max |H − H̃| · ē.
/// A step is accepted only if it lowers the merit Σ_i (Σ_j w_ij (H_i − H_j))²;
/// when no step length down to 1/64 does, the iteration stops unconverged
/// instead of drifting ([`StopReason::NoDescent`]). It also stops
/// unconverged, with the reason in the report's `stop_reason`, when the
/// merit fell by less than [`STAGNATION_DECREASE`] over the last
/// [`STAGNATION_WINDOW`] sweeps ([`StopReason::Stagnated`]), when the
/// residual grew beyond [`DIVERGENCE_FACTOR`] times its smallest value
/// ([`StopReason::Diverged`]), when the next sweep would take the work
/// beyond `opts.max_work` ([`StopReason::WorkLimit`]) or after
/// `opts.max_iterations` sweeps ([`StopReason::MaxIterations`]).
pub fn schneider_kobbelt(
    mesh: &SurfaceMesh,
    opts: &SchneiderKobbeltOptions,
) -> Result<Output<SmoothReport>, SmoothError> {
    mesh.require_triangles()?;
    let c = Constraints {
        fixed: opts.fixed.clone(),
        fix_boundary: true,
        ..Constraints::default()
    };
    let roles = roles(mesh, &c)?;
    let input = mesh.positions().to_vec();
    let v0 = geom::volume(mesh);
    let ebar = geom::mean_edge_length(mesh);
    let nbrs: Vec<Vec<usize>> = mesh
        .vertices()
        .map(|v| mesh.one_ring(v).map(|u| u.idx()).collect())
        .collect();
    let normals0 = g1_normals(mesh, &roles, opts, ebar)?;
    let unknowns = Unknowns::new(&roles, &nbrs);
    let m = unknowns.vertices.len();
    let any_floating = unknowns.any_floating();
    let field_fixed = unknowns.field_fixed();
    let evaluator = Evaluator {
        mesh,
        roles: &roles,
        normals0: &normals0,
        nbrs: &nbrs,
        unknown: &unknowns.vertices,
        evaluations: std::cell::Cell::new(0),
    };
    let (support, groups) = jacobian_pattern(&nbrs, &unknowns);
    // current positions (the connectivity is the input's)
    let mut work: Vec<Vec3> = input.clone();
    let mut solver: Option<ConstrainedSolver> = None;
    let mut iterations = 0;
    let mut converged = m == 0 || !(ebar > 0.0);
    let mut stop = if converged {
        StopReason::Converged
    } else {
        StopReason::MaxIterations
    };
    let mut residual = 0.0;
    let mut last_step = f64::INFINITY;
    let mut ev = evaluator.evaluate(&work);
    let mut progress = Progress::new(mesh.vertex_count(), groups.len(), opts.max_work);
    while !converged {
        opts.control
            .step("iterations", iterations as u64, opts.max_iterations as u64)?;
        let htilde =
            harmonic_mean_curvature(mesh, &work, &ev, &unknowns, &field_fixed, &mut solver)?;
        let h_of = |i: usize| ev.fits[i].unwrap_or(0.0);
        residual = unknowns
            .vertices
            .iter()
            .map(|&i| htilde[i] - h_of(i))
            .fold(0.0f64, |a, r| a.max(r.abs()))
            * ebar;
        if last_step < opts.epsilon {
            converged = true;
            stop = StopReason::Converged;
            break;
        }
        if iterations >= opts.max_iterations {
            break;
        }
        if let Some(reason) = progress.stop(ev.merit, residual, evaluator.evaluations.get()) {
            stop = reason;
            break;
        }
        let jac = finite_difference_jacobian(&evaluator, &ev, &work, &support, &groups, ebar);
        match newton_step(
            &evaluator,
            &ev,
            &work,
            &jac,
            any_floating,
            ebar,
            opts.epsilon,
        )? {
            NewtonOutcome::Accepted(trial, e, worst) => {
                iterations += 1;
                work = trial;
                ev = e;
                last_step = worst;
            }
            // the loop head computes the final residual and stops
            NewtonOutcome::BelowEpsilon => last_step = 0.0,
            NewtonOutcome::NoDescent => {
                stop = StopReason::NoDescent;
                break;
            }
        }
    }
    let report = SmoothReport {
        iterations,
        volume_before: v0,
        volume_after: geom::volume_at(mesh, &work),
        max_displacement: max_distance(&work, &input),
        converged,
        residual: Some(residual),
        stop_reason: Some(stop),
        taubin: None,
    };
    Ok(Output {
        positions: work,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stopping rules on given merit and residual sequences: a merit
    /// that falls by less than [`STAGNATION_DECREASE`] over
    /// [`STAGNATION_WINDOW`] sweeps stagnates (by more it goes on), a
    /// residual beyond [`DIVERGENCE_FACTOR`] times its smallest value
    /// diverges, a non-finite one too, and a sweep that would pass the work
    /// bound is not started.
    #[test]
    fn sweeps_stop_when_they_stagnate_diverge_or_would_exceed_the_work() {
        let unbounded = || Progress::new(10, 3, u64::MAX);
        // 3 % a sweep: 14 % over five sweeps, goes on
        let mut p = unbounded();
        for k in 0..40 {
            assert_eq!(p.stop(0.97f64.powi(k), 1.0, 5 * k as u64 + 1), None, "{k}");
        }
        // 1 % a sweep: stagnated once five sweeps are seen
        let mut p = unbounded();
        let stops: Vec<Option<StopReason>> = (0..7)
            .map(|k| p.stop(0.99f64.powi(k), 1.0, 5 * k as u64 + 1))
            .collect();
        assert_eq!(stops[..5], [None; 5]);
        assert_eq!(stops[5], Some(StopReason::Stagnated));
        // the residual: up to the factor goes on, beyond it diverges
        let mut p = unbounded();
        assert_eq!(p.stop(1.0, 1.0, 1), None);
        assert_eq!(p.stop(0.5, DIVERGENCE_FACTOR, 6), None);
        assert_eq!(
            p.stop(0.25, 1.01 * DIVERGENCE_FACTOR, 11),
            Some(StopReason::Diverged)
        );
        let mut p = unbounded();
        assert_eq!(p.stop(1.0, f64::NAN, 1), Some(StopReason::Diverged));
        // work: 10 vertices, sweeps of 5 evaluations; a bound of 200 allows
        // the sweeps to 150 evaluations × vertices, not the next
        let mut p = Progress::new(10, 3, 200);
        assert_eq!(p.stop(1.0, 1.0, 1), None); // next: (3 + 1) × 10 = 40
        assert_eq!(p.stop(0.5, 1.0, 6), None); // 60 + 50
        assert_eq!(p.stop(0.25, 1.0, 11), None); // 110 + 50
        assert_eq!(p.stop(0.125, 1.0, 16), Some(StopReason::WorkLimit)); // 160 + 50
    }
}
