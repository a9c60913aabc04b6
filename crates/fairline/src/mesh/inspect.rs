//! Inspection of a [`Soup`] that may be broken: counts and defects, without
//! refusing non-manifold or otherwise invalid input (`fairline info`).

use super::union_find::{find, union};
use super::{EdgeId, FaceId, HalfedgeId, MeshError, Soup, SurfaceMesh, VertexId, topology_summary};
use crate::Vec3;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// Minimum, mean and maximum of a set of values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    /// Smallest value.
    pub min: f64,
    /// Mean value.
    pub mean: f64,
    /// Largest value.
    pub max: f64,
}

impl Stats {
    /// Statistics of the finite values (all zero when there are none).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Stats {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
        for v in values.into_iter().filter(|v| v.is_finite()) {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        if n == 0 {
            Stats::default()
        } else {
            Stats {
                min,
                mean: sum / n as f64,
                max,
            }
        }
    }
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BoundingBox {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// What `fairline info` reports about a mesh file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshInfo {
    /// Number of vertices in the file.
    pub vertices: usize,
    /// Number of faces.
    pub faces: usize,
    /// Histogram of face sizes: number of vertices → number of faces.
    pub face_sizes: BTreeMap<usize, usize>,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges with exactly one face.
    pub boundary_edges: usize,
    /// Closed chains of boundary edges (connected components of the
    /// boundary-edge graph).
    pub boundary_loops: usize,
    /// Distinct edges shared by more than two faces.
    pub non_manifold_edges: usize,
    /// Face–edge incidences on those edges (what trimesh counts as
    /// non-manifold face edges).
    pub non_manifold_edge_incidences: usize,
    /// Faces with the same vertex set as an earlier face.
    pub duplicate_faces: usize,
    /// Vertices whose faces form more than one fan (counted on the manifold
    /// edges only).
    pub non_manifold_vertices: usize,
    /// Edges used twice in the same direction by two faces (orientation
    /// conflicts before any repair).
    pub inconsistently_oriented_edges: usize,
    /// Connected components of faces joined across shared edges (faces that
    /// touch only at a vertex are separate components).
    pub components: usize,
    /// Vertices used by no face.
    pub isolated_vertices: usize,
    /// Faces with an index out of range, fewer than 3 vertices or a repeated
    /// vertex.
    pub invalid_faces: usize,
    /// Faces of zero (relative) area.
    pub degenerate_faces: usize,
    /// Vertices with NaN or infinite coordinates.
    pub non_finite_vertices: usize,
    /// Euler characteristic V − E + F over the used vertices.
    pub euler_characteristic: i64,
    /// Genus when the mesh is a valid oriented manifold with at least one
    /// face, else `None`.
    pub genus: Option<i64>,
    /// True when `SurfaceMesh` accepts the file.
    pub manifold: bool,
    /// Why `SurfaceMesh` refuses the file, when it does.
    pub manifold_error: Option<String>,
    /// True when all faces are triangles.
    pub triangle_mesh: bool,
    /// Bounding box (finite coordinates only).
    pub bbox: BoundingBox,
    /// Edge-length statistics.
    pub edge_length: Stats,
    /// Total area of the valid faces.
    pub area: f64,
}

/// Area of a polygon (half the length of its Newell vector about the
/// centroid) and whether it is degenerate: twice its area at most
/// [`super::DEGENERATE_RELATIVE_AREA`] times the sum of its squared
/// edge lengths (the test of `geom`'s triangle areas, for any polygon).
pub(super) fn polygon_area(p: &[Vec3], face: &[u32]) -> (f64, bool) {
    let n = face.len();
    if n == 0 {
        return (0.0, true);
    }
    let c = face.iter().map(|&i| p[i as usize]).sum::<Vec3>() / n as f64;
    let mut s = Vec3::ZERO;
    let mut scale = 0.0;
    for k in 0..n {
        let a = p[face[k] as usize] - c;
        let b = p[face[if k + 1 == n { 0 } else { k + 1 }] as usize] - c;
        s += a.cross(b);
        scale += (b - a).length_squared();
    }
    let a2 = s.length();
    (0.5 * a2, !(a2 > super::DEGENERATE_RELATIVE_AREA * scale))
}

/// Counts and defects of a soup. Never fails; invalid faces are counted and
/// left out of the edge analysis.
///
/// When the soup makes a [`SurfaceMesh`] (the usual case, non-manifold
/// vertices included), the counts come from the halfedge structure in a few
/// linear, partly parallel passes; boundary loops are then the halfedge
/// boundary loops (two loops touching at a non-manifold vertex count twice).
/// Otherwise a slower analysis of the raw face list counts every defect.
pub fn inspect(soup: &Soup) -> MeshInfo {
    match super::build::build_with_flips(soup) {
        Ok((mesh, flip)) => inspect_mesh(soup, &mesh, &flip),
        Err(e) => inspect_broken(soup, e),
    }
}

/// Below this many faces the per-face passes run sequentially.
const PARALLEL_FACES: usize = 20_000;
/// Faces per chunk of the parallel sums (fixed, so sums are deterministic).
const CHUNK: usize = 8192;

/// [`inspect`] of a soup that built `mesh`, with the builder's face flips.
fn inspect_mesh(soup: &Soup, mesh: &SurfaceMesh, flip: &[u8]) -> MeshInfo {
    let nv = soup.vertex_count();
    let nf = soup.face_count();
    let p = &soup.positions;
    let face_sizes = face_size_histogram(soup);
    // degenerate faces and area, in fixed chunks
    let chunk_stats = |range: std::ops::Range<usize>| {
        let (mut degenerate, mut area) = (0usize, 0.0f64);
        for f in range {
            let (a, d) = polygon_area(p, soup.face(f));
            degenerate += usize::from(d);
            if a.is_finite() {
                area += a;
            }
        }
        (degenerate, area)
    };
    let chunks: Vec<(usize, f64)> = if nf >= PARALLEL_FACES {
        (0..nf.div_ceil(CHUNK))
            .into_par_iter()
            .map(|k| chunk_stats(k * CHUNK..((k + 1) * CHUNK).min(nf)))
            .collect()
    } else {
        vec![chunk_stats(0..nf)]
    };
    let degenerate_faces = chunks.iter().map(|c| c.0).sum();
    let area = chunks.iter().map(|c| c.1).sum();
    // per edge: boundary, orientation conflicts in the input, length (the
    // counts in parallel, the lengths into one array summed in order)
    let ne = mesh.edge_count();
    let edge_flags = |e: usize| {
        let (f, g) = (
            mesh.face(HalfedgeId(2 * e as u32)),
            mesh.face(HalfedgeId(2 * e as u32 + 1)),
        );
        match (f, g) {
            (Some(f), Some(g)) => (0, usize::from(flip[f.idx()] != flip[g.idx()])),
            _ => (1, 0),
        }
    };
    let edge_length = |e: usize| {
        let (a, b) = mesh.edge_vertices(EdgeId(e as u32));
        mesh.position(a).distance(mesh.position(b))
    };
    let add = |x: (usize, usize), y: (usize, usize)| (x.0 + y.0, x.1 + y.1);
    let ((boundary_edges, inconsistent), lengths): ((usize, usize), Vec<f64>) =
        if ne >= PARALLEL_FACES {
            (
                (0..ne)
                    .into_par_iter()
                    .map(edge_flags)
                    .reduce(|| (0, 0), add),
                (0..ne).into_par_iter().map(edge_length).collect(),
            )
        } else {
            (
                (0..ne).map(edge_flags).fold((0, 0), add),
                (0..ne).map(edge_length).collect(),
            )
        };
    let summary = topology_summary(mesh);
    let original = mesh.original_vertex_count();
    let isolated = (0..original as u32)
        .filter(|&v| mesh.is_isolated(VertexId(v)))
        .count();
    let euler = (nv - isolated) as i64 - ne as i64 + nf as i64;
    MeshInfo {
        vertices: nv,
        faces: nf,
        face_sizes,
        edges: ne,
        boundary_edges,
        boundary_loops: summary.boundary_loops,
        non_manifold_edges: 0,
        non_manifold_edge_incidences: 0,
        duplicate_faces: duplicate_faces_of_mesh(soup, mesh),
        non_manifold_vertices: mesh.split_vertex_count(),
        inconsistently_oriented_edges: inconsistent,
        components: summary.components,
        isolated_vertices: isolated,
        invalid_faces: 0,
        degenerate_faces,
        non_finite_vertices: 0,
        euler_characteristic: euler,
        // an empty surface has no genus
        genus: (nf > 0).then_some(summary.genus),
        manifold: true,
        manifold_error: None,
        triangle_mesh: mesh.is_triangle_mesh(),
        bbox: bbox_of(p),
        edge_length: Stats::of(lengths),
        area,
    }
}

/// Number of faces of each size: counted in an array for the usual small
/// sizes (a map lookup per face costs more than the rest of the pass).
fn face_size_histogram(soup: &Soup) -> BTreeMap<usize, usize> {
    const SMALL: usize = 64;
    let mut small = [0usize; SMALL];
    let mut sizes = BTreeMap::new();
    for w in soup.offsets.windows(2) {
        let n = (w[1] - w[0]) as usize;
        match small.get_mut(n) {
            Some(count) => *count += 1,
            None => *sizes.entry(n).or_insert(0) += 1,
        }
    }
    for (n, &count) in small.iter().enumerate() {
        if count > 0 {
            sizes.insert(n, count);
        }
    }
    sizes
}

/// Faces with the same vertex set as an earlier face, in a mesh that built.
/// Two triangles with one vertex set share all three edges, so they are
/// neighbours across their first halfedge (a closed two-face component);
/// larger polygons are compared by sorted vertex lists.
fn duplicate_faces_of_mesh(soup: &Soup, mesh: &SurfaceMesh) -> usize {
    let nf = soup.face_count();
    let same_set = |f: usize, g: usize| {
        let (a, b) = (soup.face(f), soup.face(g));
        a.len() == b.len() && a.iter().all(|v| b.contains(v))
    };
    let mut n = 0;
    let mut polygons: Vec<(Vec<u32>, usize)> = Vec::new();
    for f in 0..nf {
        if soup.face(f).len() == 3 {
            let h = mesh.face_halfedge(FaceId(f as u32));
            if let Some(g) = mesh.face(mesh.opposite(h))
                && g.idx() < f
                && same_set(f, g.idx())
            {
                n += 1;
            }
        } else {
            let mut key = soup.face(f).to_vec();
            key.sort_unstable();
            polygons.push((key, f));
        }
    }
    polygons.sort_unstable();
    n + polygons.windows(2).filter(|w| w[0].0 == w[1].0).count()
}

fn bbox_of(p: &[Vec3]) -> BoundingBox {
    super::bounding_box(p)
        .map(|(lo, hi)| BoundingBox {
            min: lo.to_array(),
            max: hi.to_array(),
        })
        .unwrap_or_default()
}

/// [`inspect`] of a soup the mesh builder refuses with `error`.
fn inspect_broken(soup: &Soup, error: MeshError) -> MeshInfo {
    let nv = soup.vertex_count();
    let p = &soup.positions;
    let mut face_sizes = BTreeMap::new();
    let mut invalid_faces = 0;
    let mut degenerate_faces = 0;
    let mut area = 0.0;
    let mut used = vec![false; nv];
    // directed edges (a, b, face)
    let mut directed: Vec<(u32, u32, u32)> = Vec::new();
    let mut duplicate_faces = 0;
    let mut seen_faces = std::collections::HashSet::new();
    for (fi, face) in soup.faces().enumerate() {
        *face_sizes.entry(face.len()).or_insert(0) += 1;
        let valid = face.len() >= 3
            && face.iter().all(|&i| (i as usize) < nv)
            && face.iter().enumerate().all(|(k, a)| !face[..k].contains(a));
        if !valid {
            invalid_faces += 1;
            continue;
        }
        for k in 0..face.len() {
            let (a, b) = (face[k], face[(k + 1) % face.len()]);
            used[a as usize] = true;
            directed.push((a, b, fi as u32));
        }
        let mut key = face.to_vec();
        key.sort_unstable();
        if !seen_faces.insert(key) {
            duplicate_faces += 1;
        }
        let (face_area, degenerate) = polygon_area(p, face);
        degenerate_faces += usize::from(degenerate);
        if face_area.is_finite() {
            area += face_area;
        }
    }
    // undirected edge analysis
    let mut undirected: Vec<(u32, u32, bool, u32)> = directed
        .iter()
        .map(|&(a, b, f)| (a.min(b), a.max(b), a < b, f))
        .collect();
    let mut face_parent: Vec<u32> = (0..soup.face_count() as u32).collect();
    let mut nm_incidences = 0;
    undirected.sort_unstable();
    let (mut edges, mut boundary_edges, mut non_manifold_edges, mut inconsistent) = (0, 0, 0, 0);
    let mut boundary_parent: Vec<u32> = (0..nv as u32).collect();
    let mut boundary_vertex = vec![false; nv];
    let mut lengths = Vec::new();
    let mut manifold_edge_faces: Vec<(u32, u32)> = Vec::new();
    let mut i = 0;
    while i < undirected.len() {
        let (a, b, _, _) = undirected[i];
        let mut j = i;
        while j < undirected.len() && undirected[j].0 == a && undirected[j].1 == b {
            j += 1;
        }
        edges += 1;
        for k in i + 1..j {
            union(&mut face_parent, undirected[i].3, undirected[k].3);
        }
        lengths.push(p[a as usize].distance(p[b as usize]));
        match j - i {
            1 => {
                boundary_edges += 1;
                union(&mut boundary_parent, a, b);
                boundary_vertex[a as usize] = true;
                boundary_vertex[b as usize] = true;
            }
            2 => {
                if undirected[i].2 == undirected[i + 1].2 {
                    inconsistent += 1;
                }
                manifold_edge_faces.push((a, b));
            }
            n => {
                non_manifold_edges += 1;
                nm_incidences += n;
            }
        }
        i = j;
    }
    let mut loop_roots = std::collections::BTreeSet::new();
    for v in 0..nv {
        if boundary_vertex[v] {
            loop_roots.insert(find(&mut boundary_parent, v as u32));
        }
    }
    let mut comp_roots = std::collections::BTreeSet::new();
    for &(_, _, f) in &directed {
        comp_roots.insert(find(&mut face_parent, f));
    }
    // non-manifold vertices: count fans through the faces around each vertex
    let non_manifold_vertices = count_non_manifold_vertices(soup, nv);
    let used_count = used.iter().filter(|&&u| u).count();
    let valid_faces = soup.face_count() - invalid_faces;
    let euler = used_count as i64 - edges as i64 + valid_faces as i64;
    let (manifold, manifold_error, genus) = (false, Some(error.to_string()), None);
    let bbox = bbox_of(p);
    MeshInfo {
        vertices: nv,
        faces: soup.face_count(),
        face_sizes,
        edges,
        boundary_edges,
        boundary_loops: loop_roots.len(),
        non_manifold_edges,
        non_manifold_edge_incidences: nm_incidences,
        duplicate_faces,
        non_manifold_vertices,
        inconsistently_oriented_edges: inconsistent,
        components: comp_roots.len(),
        isolated_vertices: nv - used_count,
        invalid_faces,
        degenerate_faces,
        non_finite_vertices: p.iter().filter(|v| !v.is_finite()).count(),
        euler_characteristic: euler,
        genus,
        manifold,
        manifold_error,
        triangle_mesh: soup.is_triangle_soup(),
        bbox,
        edge_length: Stats::of(lengths),
        area,
    }
}

/// Vertices whose incident valid faces do not form a single edge-connected
/// fan.
fn count_non_manifold_vertices(soup: &Soup, nv: usize) -> usize {
    // faces per vertex (CSR)
    let mut count = vec![0u32; nv + 1];
    let valid = |face: &[u32]| {
        face.len() >= 3
            && face.iter().all(|&i| (i as usize) < nv)
            && face.iter().enumerate().all(|(k, a)| !face[..k].contains(a))
    };
    for face in soup.faces().filter(|f| valid(f)) {
        for &v in face {
            count[v as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        count[i + 1] += count[i];
    }
    let mut fill = count.clone();
    let mut vf = vec![0u32; count[nv] as usize];
    for (f, face) in soup.faces().enumerate() {
        if !valid(face) {
            continue;
        }
        for &v in face {
            vf[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    // the faces around v joined where they share a second vertex: the
    // (neighbour, face) pairs sorted, equal neighbours joined (linear in the
    // faces around v up to the sort, however many repeat one vertex set)
    let mut bad = 0;
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut parent: Vec<u32> = Vec::new();
    for v in 0..nv {
        let faces = &vf[count[v] as usize..count[v + 1] as usize];
        if faces.len() <= 1 {
            continue;
        }
        pairs.clear();
        for (a, &f) in faces.iter().enumerate() {
            let face = soup.face(f as usize);
            let k = face.iter().position(|&x| x as usize == v).unwrap_or(0);
            pairs.push((face[(k + 1) % face.len()], a as u32));
            pairs.push((face[(k + face.len() - 1) % face.len()], a as u32));
        }
        pairs.sort_unstable();
        parent.clear();
        parent.extend(0..faces.len() as u32);
        for w in pairs.windows(2) {
            if w[0].0 == w[1].0 {
                union(&mut parent, w[0].1, w[1].1);
            }
        }
        let root = find(&mut parent, 0);
        if (1..faces.len() as u32).any(|k| find(&mut parent, k) != root) {
            bad += 1;
        }
    }
    bad
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn inspect_agrees_with_the_halfedge_mesh_on_valid_input() {
        let m = shapes::torus(2.0, 0.5, 10, 6);
        let info = inspect(&m.to_soup());
        assert_eq!(info.edges, m.edge_count());
        assert_eq!(info.genus, Some(1));
        assert!(info.manifold);
        assert_eq!(info.boundary_loops, 0);
        assert_eq!(info.face_sizes.get(&3), Some(&120));
        let g = shapes::quad_grid(4, 4, (0.0, 1.0), (0.0, 1.0), |_, _| 0.0);
        let info = inspect(&g.to_soup());
        assert_eq!((info.boundary_edges, info.boundary_loops), (12, 1));
        assert!((info.area - 1.0).abs() < 1e-12);
    }

    #[test]
    fn inspect_reports_defects_instead_of_refusing() {
        let p: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new(i as f64, (i % 3) as f64, 0.0))
            .collect();
        let mut soup = Soup::from_polygons(p, &[[0u32, 1, 2], [1, 0, 3], [0, 1, 4]]);
        soup.push_face(&[5, 6, 9]);
        soup.push_face(&[5, 5, 6]);
        soup.push_face(&[0, 6, 7]);
        let info = inspect(&soup);
        assert_eq!(info.non_manifold_edges, 1);
        assert_eq!(info.invalid_faces, 2);
        assert_eq!(info.non_manifold_vertices, 1); // vertex 0: fan {0,1,2 faces} + face 5
        assert!(!info.manifold);
        assert!(
            info.manifold_error
                .unwrap()
                .contains("face 3 refers to vertex 9")
        );
        assert_eq!(info.genus, None);
    }
}
