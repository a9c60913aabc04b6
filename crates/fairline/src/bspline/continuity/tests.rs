//! Patch pairs built exactly from their control nets with known seams.

use super::*;

/// A bicubic Bézier patch from a 4 × 4 net `p[i][j]`.
fn bezier(p: [[Vec3; 4]; 4]) -> BSplineSurface {
    BSplineSurface::bezier(p.iter().map(|r| r.to_vec()).collect(), None).unwrap()
}

/// A plane z = 0 patch over [x0, x0 + 1] × [y0, y0 + len] (control points at
/// thirds: linear parametrisation, |S_u| = 1, |S_v| = len).
fn flat(x0: f64, y0: f64, len: f64) -> [[Vec3; 4]; 4] {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| Vec3::new(x0 + i as f64 / 3.0, y0 + len * j as f64 / 3.0, 0.0))
    })
}

fn only(report: &ContinuityReport) -> &Seam {
    assert_eq!(
        report.seams.len(),
        1,
        "{:#?}",
        report
            .seams
            .iter()
            .map(|s| (s.surfaces, s.sides, s.range))
            .collect::<Vec<_>>()
    );
    &report.seams[0]
}

#[test]
fn continuity_classifies_constructed_seams() {
    let a = bezier(flat(0.0, 0.0, 1.0));
    let opts = ContinuityOptions::default();
    // G2: the two halves of one cubic patch split by de Casteljau at u = ½
    // (z = a polynomial of degree 3 in u and v) — C∞ across the seam.
    let curved: [[Vec3; 4]; 4] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let (x, y) = (2.0 * i as f64 / 3.0, j as f64 / 3.0);
            Vec3::new(
                x,
                y,
                0.3 * ((i * j) % 3) as f64 + 0.2 * (i == 2) as u8 as f64,
            )
        })
    });
    let (left, right) = split_u(curved);
    let r = continuity(&[bezier(left), bezier(right)], &opts).unwrap();
    let s = only(&r);
    assert_eq!(s.class, SeamClass::G2, "{s:?}");
    assert_eq!(s.surfaces, [0, 1]);
    assert_eq!(
        s.sides,
        [
            Boundary::Side(PatchSide::UMax),
            Boundary::Side(PatchSide::UMin)
        ]
    );
    assert!(
        s.g0_max < 1e-12 && s.g1_max_deg < 1e-6 && s.g2_max_relative < 1e-6,
        "{s:?}"
    );
    assert!((s.range[0] - 0.0).abs() < 1e-12 && (s.range[1] - 1.0).abs() < 1e-12);

    // G0: B's row next to the seam lifted by h: its cross tangent is
    // 3 (P1 − P0) = (1, 0, 3h) against A's (1, 0, 0): angle atan(3h).
    let h = 0.02;
    let mut b = flat(1.0, 0.0, 1.0);
    for j in 0..4 {
        b[1][j].z += h;
    }
    let r = continuity(&[a.clone(), bezier(b)], &opts).unwrap();
    let s = only(&r);
    assert_eq!(s.class, SeamClass::G0);
    let want = (3.0 * h).atan().to_degrees();
    assert!(
        (s.g1_max_deg - want).abs() < 1e-9,
        "{} vs {want}",
        s.g1_max_deg
    );
    assert!(s.g0_max < 1e-12);

    // G1: collinear rows across the seam, the third row lifted by h2: B's
    // second derivative across the seam is 6 (P2 − 2 P1 + P0) = (0, 0, 6 h2)
    // at unit speed, so κ_B = 6 h2 against A's 0.
    let h2 = 0.01;
    let mut b = flat(1.0, 0.0, 1.0);
    for j in 0..4 {
        b[2][j].z += h2;
    }
    let r = continuity(&[a.clone(), bezier(b)], &opts).unwrap();
    let s = only(&r);
    assert_eq!(s.class, SeamClass::G1, "{s:?}");
    assert!(s.g1_max_deg < 1e-9);
    assert!((s.g2_max - 6.0 * h2).abs() < 1e-9, "{}", s.g2_max);

    // gap: B shifted up by 3 tolerances.
    let tol = 1e-3;
    let b: [[Vec3; 4]; 4] =
        flat(1.0, 0.0, 1.0).map(|r| r.map(|p| p + Vec3::new(0.0, 0.0, 3.0 * tol)));
    let o = ContinuityOptions {
        tolerance: Some(tol),
        ..opts.clone()
    };
    let s = continuity(&[a.clone(), bezier(b)], &o).unwrap();
    let s = only(&s);
    assert_eq!(s.class, SeamClass::Gap);
    assert!((s.g0_max - 3.0 * tol).abs() < 1e-12);

    // A partial overlap (T-junction): B's side covers y ∈ [0.25, 0.75] of
    // A's, and B runs the other way (v reversed): still G2, over that range.
    let mut b = flat(1.0, 0.25, 0.5);
    for row in &mut b {
        row.reverse();
    }
    let r = continuity(&[a.clone(), bezier(b)], &opts).unwrap();
    let s = only(&r);
    assert_eq!(s.class, SeamClass::G2);
    // The ends are found to within the position tolerance (past B's end
    // the gap grows from 0: the stretch extends while it is below it).
    let tol = r.tolerance;
    assert!(
        (s.range[0] - 0.25).abs() <= tol && (s.range[1] - 0.75).abs() <= tol,
        "{:?} (tolerance {tol})",
        s.range
    );
    assert!((s.length - 0.5).abs() <= 2.0 * tol);

    // Far apart or touching at a corner only: no seam.
    assert!(
        continuity(&[a.clone(), bezier(flat(3.0, 0.0, 1.0))], &opts)
            .unwrap()
            .seams
            .is_empty()
    );
    assert!(
        continuity(&[a.clone(), bezier(flat(1.0, 1.0, 1.0))], &opts)
            .unwrap()
            .seams
            .is_empty()
    );
    // A kink of 0.3°: within the default 0.5° (and B's curvature across,
    // 12 hk = 0.021, is below 5 % of 1 / model size: G2), G0 at 0.1°.
    let mut b = flat(1.0, 0.0, 1.0);
    let hk = (0.3f64).to_radians().tan() / 3.0;
    for j in 0..4 {
        b[1][j].z += hk;
    }
    let pair = [a.clone(), bezier(b)];
    let s = continuity(&pair, &opts).unwrap();
    assert_eq!(only(&s).class, SeamClass::G2);
    assert!((only(&s).g1_max_deg - 0.3).abs() < 1e-9);
    let strict = ContinuityOptions {
        angle_tolerance_deg: 0.1,
        ..opts
    };
    assert_eq!(
        only(&continuity(&pair, &strict).unwrap()).class,
        SeamClass::G0
    );
}

#[test]
fn continuity_finds_the_seam_of_a_closed_patch() {
    // A cylinder-like patch whose u = 0 and u = 1 sides coincide (a closed
    // ring of control points with a repeated first point is not needed:
    // the first and last rows are the same points) — a self seam, G0 here
    // (the ring of four rows has a corner at the seam).
    let ring = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let p: [[Vec3; 4]; 4] = std::array::from_fn(|i| {
        std::array::from_fn(|j| ring[i] + Vec3::new(0.0, 0.0, j as f64 / 3.0))
    });
    let r = continuity(&[bezier(p)], &ContinuityOptions::default()).unwrap();
    let s = only(&r);
    assert_eq!(s.surfaces, [0, 0]);
    assert_eq!(
        s.sides,
        [
            Boundary::Side(PatchSide::UMin),
            Boundary::Side(PatchSide::UMax)
        ]
    );
    assert_eq!(s.class, SeamClass::G0);
}

#[test]
fn continuity_rejects_bad_options_and_survives_degenerate_patches() {
    let a = bezier(flat(0.0, 0.0, 1.0));
    let bad = ContinuityOptions {
        tolerance: Some(-1.0),
        ..Default::default()
    };
    assert!(continuity(std::slice::from_ref(&a), &bad).is_err());
    let bad = ContinuityOptions {
        angle_tolerance_deg: f64::NAN,
        ..Default::default()
    };
    assert!(continuity(std::slice::from_ref(&a), &bad).is_err());
    // A patch collapsed to a point and an empty input.
    let point = bezier([[Vec3::ONE; 4]; 4]);
    let r = continuity(&[point, a], &ContinuityOptions::default()).unwrap();
    assert!(r.seams.is_empty());
    assert_eq!(r.degenerate_sides, 4);
    assert!(
        continuity(&[], &ContinuityOptions::default())
            .unwrap()
            .seams
            .is_empty()
    );
}

/// de Casteljau split of a Bézier net at u = ½ (rows i).
fn split_u(p: [[Vec3; 4]; 4]) -> ([[Vec3; 4]; 4], [[Vec3; 4]; 4]) {
    let mut l = p;
    let mut r = p;
    for j in 0..4 {
        let mut col: Vec<Vec3> = (0..4).map(|i| p[i][j]).collect();
        let mut left = vec![col[0]];
        let mut right = vec![col[3]];
        for _ in 1..4 {
            col = col.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
            left.push(col[0]);
            right.push(col[col.len() - 1]);
        }
        right.reverse();
        for i in 0..4 {
            l[i][j] = left[i];
            r[i][j] = right[i];
        }
    }
    (l, r)
}

/// The one shape: progress per phase, cancellation at the next
/// phase, the same result with a control that never stops, and the report
/// serialises to the CLI's keys with the class counts of its seams.
#[test]
fn continuity_reports_progress_can_be_cancelled_and_serialises_the_cli_keys() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let a = bezier(flat(0.0, 0.0, 1.0));
    let b = bezier(flat(1.0, 0.0, 1.0));
    let plain = continuity(&[a.clone(), b.clone()], &ContinuityOptions::default()).unwrap();
    let steps = Arc::new(AtomicUsize::new(0));
    let seen = Arc::clone(&steps);
    let watched = continuity(
        &[a.clone(), b.clone()],
        &ContinuityOptions::default().control(Control::new().on_progress(move |_| {
            seen.fetch_add(1, Ordering::Relaxed);
        })),
    )
    .unwrap();
    assert_eq!(watched, plain);
    assert_eq!(steps.load(Ordering::Relaxed), 4, "3 phases + done");
    let flag = Arc::new(AtomicBool::new(false));
    let raise = Arc::clone(&flag);
    let stopping = Control::new()
        .cancel_flag(flag)
        .on_progress(move |_| raise.store(true, Ordering::Relaxed));
    assert!(matches!(
        continuity(&[a, b], &ContinuityOptions::default().control(stopping)),
        Err(ContinuityError::Cancelled(_))
    ));
    // one G2 seam between two halves of a plane
    assert_eq!(
        plain.classes,
        ClassCounts {
            g2: 1,
            ..Default::default()
        }
    );
    let json = serde_json::to_value(&plain).unwrap();
    assert_eq!(json["classes"]["G2"], 1);
    assert_eq!(json["classes"]["gap"], 0);
    let edge = &json["edges"][0];
    assert_eq!(edge["class"], "G2");
    assert_eq!(edge["surfaces"], serde_json::json!([0, 1]));
    assert_eq!(edge["worst"].as_array().map(Vec::len), Some(3));
    for key in [
        "sides",
        "range",
        "length",
        "g0_max",
        "g1_max_deg",
        "g2_max",
        "g2_max_relative",
        "degenerate_samples",
    ] {
        assert!(edge.get(key).is_some(), "{key}");
    }
    assert!(edge.get("points").is_none());
    assert!(json["tolerance"].as_f64().unwrap() > 0.0);
}
