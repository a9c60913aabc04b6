"""fairline.section and fairline.draft: closed forms on a sphere (a
section's curvature is 1/√(r² − d²); the area with |draft| < α is the band
of height 2 r sin α, sin α of the sphere's area), the flat-array layout of
the curves, and refusals."""

import math

import numpy as np
import pytest

import fairline


def icosphere(radius=2.0, subdivisions=4):
    t = (1.0 + 5.0**0.5) / 2.0
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(subdivisions):
        mid = {}
        G = []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = V[a] + V[b]
                V.append(p / np.linalg.norm(p))
                mid[key] = len(V) - 1
            return mid[key]

        for a, b, c in F:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            G += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        F = G
    return radius * np.array(V), np.array(F)


def test_sphere_sections_are_circles_of_the_closed_form_curvature():
    V, F = icosphere(2.0, 4)
    # off the equator, where the icosphere has vertices on the plane
    curves, report = fairline.section(V, F, point=(0, 0, 0.1), normal=(0, 0, 1), count=3, spacing=0.5, comb_scale=0.2)
    offsets = curves["offsets"]
    assert len(offsets) == len(curves["closed"]) + 1 == len(curves["plane"]) + 1
    assert offsets[0] == 0 and offsets[-1] == len(curves["points"]) == len(curves["curvature"])
    assert list(curves["plane"]) == [0, 1, 2]
    assert curves["closed"].all()
    for i, d in enumerate([0.1, 0.6, 1.1]):
        pts = curves["points"][offsets[i]:offsets[i + 1]]
        assert np.allclose(pts[:, 2], d)
        kappa = curves["curvature"][offsets[i]:offsets[i + 1]].mean()
        want = 1.0 / math.sqrt(4.0 - d * d)
        assert kappa == pytest.approx(want, rel=0.03)
    # the comb stands outside (the convex side), |comb| = scale · κ
    comb = curves["comb"]
    assert np.allclose(np.linalg.norm(comb, axis=1), 0.2 * curves["curvature"])
    radial = curves["points"].copy()
    radial[:, 2] = 0
    assert (np.einsum("ij,ij->i", comb, radial) > 0).all()
    assert [s["offset"] for s in report["sections"]] == [0.0, 0.5, 1.0]


def test_section_missing_the_part_warns_and_bad_normal_is_refused():
    V, F = icosphere(1.0, 2)
    with pytest.warns(fairline.FairlineWarning, match="no plane crosses"):
        curves, _ = fairline.section(V, F, point=(0, 0, 5), normal=(0, 0, 1))
    assert len(curves["points"]) == 0 and list(curves["offsets"]) == [0]
    with pytest.raises(fairline.FairlineError, match="plane_normal"):
        fairline.section(V, F, point=(0, 0, 0), normal=(0, 0, 0))


def test_draft_band_share_on_a_sphere_is_sin_alpha():
    V, F = icosphere(1.0, 5)
    values, report = fairline.draft(V, F, pull=(0, 0, 3), min_angle=20)
    assert report["below_share"] == pytest.approx(math.sin(math.radians(20)), abs=0.01)
    assert values["vertex"].shape == (len(V),)
    assert values["face"].shape == values["below"].shape == (len(F),)
    # a vertex's draft is asin(z / r) on the unit sphere
    assert np.allclose(values["vertex"], np.degrees(np.arcsin(V[:, 2])), atol=0.5)
    assert (np.abs(values["face"][values["below"]]) < 20).all()
    assert report["min_deg"] >= -90 and report["max_deg"] <= 90


def test_draft_refuses_a_zero_pull_and_a_bad_angle():
    V, F = icosphere(1.0, 1)
    with pytest.raises(fairline.FairlineError, match="pull"):
        fairline.draft(V, F, pull=(0, 0, 0))
    with pytest.raises(fairline.FairlineError, match="min_angle"):
        fairline.draft(V, F, pull=(0, 0, 1), min_angle=120)
