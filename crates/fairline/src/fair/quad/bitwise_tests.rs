//! Bit-for-bit regression of [`fair_structure_lines`]: checksums of the
//! output positions and the report, recorded with an independent reference
//! implementation (its own banded Cholesky and line-block conjugate
//! gradients, commit 85564a7), which this one must reproduce.

use super::tests::{zigzag_grid, zigzag_staircase};
use super::*;
use crate::enhance::bitwise_checksum as checksum;

type Case = (&'static str, SurfaceMesh, QuadFairOptions, Method);

fn cases() -> Vec<Case> {
    let saddle = |x: f64, y: f64| 0.3 * (x * x - y * y);
    let roof = |x: f64, y: f64| 0.5 * (1.0 - 0.3 * x * x) * (0.8 * y).cos();
    let (_, small) = zigzag_grid(16, 16, 0.2, saddle);
    let (_, roof_grid) = zigzag_grid(22, 41, 0.2, roof);
    let (_, stair) = zigzag_staircase(21, 21, |j| 21 - 3 * (j / 4), 0.2, saddle);
    // above the direct limit: the line-block conjugate gradients
    let (_, large) = zigzag_grid(160, 160, 0.2, roof);
    let fixed: Vec<VertexId> = (0..small.vertex_count() as u32)
        .step_by(5)
        .map(VertexId)
        .collect();
    vec![
        (
            "saddle default",
            small.clone(),
            QuadFairOptions::default(),
            Method::Auto,
        ),
        (
            "saddle thesis",
            small.clone(),
            QuadFairOptions {
                on_surface: false,
                deviation_factor: 0.5,
                ..Default::default()
            },
            Method::Auto,
        ),
        (
            "saddle fixed, boundary",
            small.clone(),
            QuadFairOptions {
                fix_boundary: true,
                fixed,
                weight: 0.1,
                ..Default::default()
            },
            Method::Auto,
        ),
        (
            "saddle iterative",
            small,
            QuadFairOptions::default(),
            Method::Iterative,
        ),
        (
            "roof default",
            roof_grid.clone(),
            QuadFairOptions::default(),
            Method::Auto,
        ),
        (
            "roof iterative",
            roof_grid,
            QuadFairOptions::default(),
            Method::Iterative,
        ),
        (
            "staircase default",
            stair,
            QuadFairOptions::default(),
            Method::Auto,
        ),
        (
            "large default",
            large.clone(),
            QuadFairOptions::default(),
            Method::Auto,
        ),
        (
            "large direct",
            large,
            QuadFairOptions::default(),
            Method::Direct,
        ),
    ]
}

/// Recorded before the refactor (see the module documentation).
const RECORDED: &[(&str, u64)] = &[
    ("saddle default", 0x87b263e4de3b2666),
    ("saddle thesis", 0x0d8bf17d20030281),
    ("saddle fixed, boundary", 0x8c2e02dd0725f957),
    ("saddle iterative", 0x1d6967515b7cab71),
    ("roof default", 0xafbba906971e5070),
    ("roof iterative", 0xd9a46efb4ea9b2c6),
    ("staircase default", 0xe277aab7261c9723),
    ("large default", 0xc3200d528983fd2e),
    ("large direct", 0x31293cb0d5694519),
];

#[test]
fn results_are_bit_identical_to_the_recorded_ones() {
    let mut mismatches = Vec::new();
    for (name, mesh, options, method) in cases() {
        let out = fair_structure_lines_with(&mesh, &options, method).unwrap();
        let r = &out.report;
        let mut sum = checksum(
            &out.positions,
            &[r.structure_lines, r.free_vertices, r.iterations],
        );
        for x in [
            r.structure_energy_before,
            r.structure_energy_after,
            r.max_displacement,
        ] {
            sum = sum.rotate_left(7) ^ x.to_bits();
        }
        let recorded = RECORDED.iter().find(|(n, _)| *n == name).map(|c| c.1);
        if recorded != Some(sum) {
            mismatches.push(name);
        }
    }
    assert!(mismatches.is_empty(), "changed: {mismatches:?}");
}
