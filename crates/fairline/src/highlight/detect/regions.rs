//! Regions: the faces around flagged sites, their connected components
//! with holes filled, their scores and the highlight lines crossing them.

use super::grid::Grid;
use super::report::{IrregularRegion, LineFairness, Site};
use crate::Vec3;
use crate::highlight::{HighlightLines, NodeId};
use crate::mesh::{FaceId, SurfaceMesh};
use rayon::prelude::*;

/// Area of `faces` over `total` (0 when the total is not positive).
pub(super) fn area_share(faces: &[FaceId], areas: &[f64], total: f64) -> f64 {
    if !(total > 0.0) {
        return 0.0;
    }
    let a: f64 = faces.iter().map(|f| areas[f.idx()]).fold(0.0, |a, b| a + b);
    (a / total).clamp(0.0, 1.0)
}

/// Whether the normal measure flags a site (its score above its threshold).
pub(super) fn normal_flagged(site: &Site) -> bool {
    site.score.is_some_and(|sc| sc > site.threshold)
}

/// Faces whose centroid lies within `margin` of a flagged site, and the
/// faces around the flagged sites' vertices.
pub(super) fn faces_near_sites(
    mesh: &SurfaceMesh,
    sites: &[Site],
    flagged: &[usize],
    margin: f64,
) -> Vec<bool> {
    let p = mesh.positions();
    let nf = mesh.face_count();
    let fgrid = Grid::new(
        margin,
        flagged.iter().map(|&i| (i as u32, sites[i].position)),
    );
    let centroid = |f: FaceId| {
        let [a, b, c] = mesh.triangle(f);
        (p[a.idx()] + p[b.idx()] + p[c.idx()]) / 3.0
    };
    let mut in_region: Vec<bool> = if flagged.is_empty() {
        vec![false; nf]
    } else {
        (0..nf)
            .into_par_iter()
            .map(|f| {
                let c = centroid(FaceId(f as u32));
                let mut hit = false;
                fgrid.around(c, |i| {
                    hit |= (sites[i as usize].position - c).length_squared() <= margin * margin;
                });
                hit
            })
            .collect()
    };
    for &i in flagged {
        for f in mesh.vertex_faces(sites[i].vertex) {
            in_region[f.idx()] = true;
        }
    }
    in_region
}

/// The connected components of the region faces (as unscored regions) and
/// each face's component (`u32::MAX` outside).
pub(super) fn connected_regions(
    mesh: &SurfaceMesh,
    in_region: &[bool],
    areas: &[f64],
) -> (Vec<IrregularRegion>, Vec<u32>) {
    let nf = mesh.face_count();
    let mut comp = vec![u32::MAX; nf];
    let mut regions: Vec<IrregularRegion> = Vec::new();
    for f0 in 0..nf {
        if !in_region[f0] || comp[f0] != u32::MAX {
            continue;
        }
        let id = regions.len() as u32;
        let mut faces = Vec::new();
        let mut stack = vec![FaceId(f0 as u32)];
        comp[f0] = id;
        while let Some(f) = stack.pop() {
            faces.push(f);
            for hh in mesh.face_halfedges(f) {
                if let Some(g) = mesh.face(mesh.opposite(hh))
                    && in_region[g.idx()]
                    && comp[g.idx()] == u32::MAX
                {
                    comp[g.idx()] = id;
                    stack.push(g);
                }
            }
        }
        faces.sort_unstable();
        let area = faces.iter().map(|f| areas[f.idx()]).sum();
        regions.push(IrregularRegion {
            faces,
            score: 0.0,
            threshold: 0.0,
            flat_spot: 0.0,
            severity: 0.0,
            center: Vec3::ZERO,
            area,
            flagged_sites: 0,
            lines: Vec::new(),
            spacing: 0.0,
        });
    }
    (regions, comp)
}

/// Each region's score (largest flagged score inside), flat spot,
/// severity, centre (score-weighted; flat-spot-weighted where only the
/// flat-spot measure flagged) and number of flagged sites. `flat_floor` is
/// the flat-spot floor.
pub(super) fn score_regions(
    mesh: &SurfaceMesh,
    sites: &[Site],
    flagged: &[usize],
    flat_floor: f64,
    component: &[u32],
    regions: &mut [IrregularRegion],
) {
    // per region and measure (normal, flat spot): the weighted sum of
    // positions, the weight, and the best score with its threshold
    #[derive(Clone, Copy, Default)]
    struct Tally {
        sum: Vec3,
        weight: f64,
        best: Option<(f64, f64)>,
    }
    let mut tallies = vec![[Tally::default(); 2]; regions.len()];
    for &i in flagged {
        let Some(f) = mesh.vertex_faces(sites[i].vertex).next() else {
            continue;
        };
        let r = component[f.idx()];
        if r == u32::MAX {
            continue;
        }
        let (site, r) = (&sites[i], r as usize);
        let sc = site.score.unwrap_or(0.0);
        let flat = site.flat_spot.unwrap_or(0.0);
        let by_flat = flat_floor > 0.0 && flat > flat_floor;
        let region = &mut regions[r];
        for (k, flagged_by, weight, severity) in [
            (0, normal_flagged(site), sc, sc / site.threshold),
            (
                1,
                by_flat,
                flat,
                if by_flat { flat / flat_floor } else { 0.0 },
            ),
        ] {
            if !flagged_by || !severity.is_finite() {
                continue;
            }
            let t = &mut tallies[r][k];
            t.sum += weight * site.position;
            t.weight += weight;
            if t.best.is_none_or(|(b, _)| sc > b) {
                t.best = Some((sc, site.threshold));
            }
            region.severity = region.severity.max(severity);
            if k == 1 {
                region.flat_spot = region.flat_spot.max(flat);
            }
        }
        region.flagged_sites += 1;
    }
    for (region, t) in regions.iter_mut().zip(&tallies) {
        // the normal measure's numbers where it flagged, else the flat spot's
        if let Some(t) = t.iter().find(|t| t.weight > 0.0) {
            region.center = t.sum / t.weight;
            (region.score, region.threshold) = t.best.unwrap_or((0.0, 0.0));
        }
    }
}

/// The stretches of the highlight lines inside the regions; records in
/// each region the lines crossing it.
pub(super) fn lines_crossing_regions(
    mesh: &SurfaceMesh,
    lines: &HighlightLines,
    in_region: &[bool],
    component: &[u32],
    regions: &mut [IrregularRegion],
) -> Vec<LineFairness> {
    let node_region = |nd: NodeId| -> Option<u32> {
        let f = match nd {
            NodeId::Edge(e, _) => [0, 1].iter().find_map(|&k| {
                mesh.face(mesh.edge_halfedge(e, k))
                    .filter(|f| in_region[f.idx()])
            }),
            NodeId::Vertex(v, _) => mesh.vertex_faces(v).find(|f| in_region[f.idx()]),
        }?;
        Some(component[f.idx()])
    };
    let mut line_out: Vec<LineFairness> = Vec::new();
    for (li, line) in lines.lines.iter().enumerate() {
        let mut stretches: Vec<Vec<Vec3>> = Vec::new();
        let mut current: Vec<Vec3> = Vec::new();
        let mut score: f64 = 0.0;
        for (&nd, &q) in line.nodes.iter().zip(&line.points) {
            match node_region(nd) {
                Some(r) if (r as usize) < regions.len() => {
                    current.push(q);
                    score = score.max(regions[r as usize].score);
                    if !regions[r as usize].lines.contains(&li) {
                        regions[r as usize].lines.push(li);
                    }
                }
                _ => {
                    if current.len() > 1 {
                        stretches.push(std::mem::take(&mut current));
                    }
                    current.clear();
                }
            }
        }
        if current.len() > 1 {
            stretches.push(current);
        }
        if !stretches.is_empty() {
            let length = line.points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
            line_out.push(LineFairness {
                line: li,
                index: line.index,
                length,
                score,
                stretches,
            });
        }
    }
    line_out
}

/// Fills the holes of a face set: complement components that touch no mesh
/// boundary, are not the largest complement component and are smaller than
/// the set itself are added to it.
pub(super) fn fill_holes(mesh: &SurfaceMesh, in_region: &mut [bool]) {
    let nf = mesh.face_count();
    let region_faces = in_region.iter().filter(|&&b| b).count();
    if region_faces == 0 {
        return;
    }
    let mut comp = vec![u32::MAX; nf];
    let mut parts: Vec<(Vec<FaceId>, bool)> = Vec::new();
    for f0 in 0..nf {
        if in_region[f0] || comp[f0] != u32::MAX {
            continue;
        }
        let id = parts.len() as u32;
        let mut faces = Vec::new();
        let mut boundary = false;
        let mut stack = vec![FaceId(f0 as u32)];
        comp[f0] = id;
        while let Some(f) = stack.pop() {
            faces.push(f);
            for hh in mesh.face_halfedges(f) {
                match mesh.face(mesh.opposite(hh)) {
                    Some(g) => {
                        if !in_region[g.idx()] && comp[g.idx()] == u32::MAX {
                            comp[g.idx()] = id;
                            stack.push(g);
                        }
                    }
                    None => boundary = true,
                }
            }
        }
        parts.push((faces, boundary));
    }
    let largest = parts
        .iter()
        .enumerate()
        .max_by_key(|(i, (f, _))| (f.len(), std::cmp::Reverse(*i)))
        .map(|(i, _)| i);
    for (i, (faces, boundary)) in parts.iter().enumerate() {
        if Some(i) == largest || *boundary || faces.len() >= region_faces {
            continue;
        }
        for f in faces {
            in_region[f.idx()] = true;
        }
    }
}
