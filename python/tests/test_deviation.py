"""fairline.deviation: closed forms on planes (the displacement of a lifted
grid, the closest-point distance to a differently triangulated one), the
split at a region, and refusals."""

import numpy as np
import pytest

import fairline


def grid(n, z=0.0, flip=False):
    xs = np.linspace(-1.0, 1.0, n)
    X, Y = np.meshgrid(xs, xs)
    V = np.column_stack([X.ravel(), Y.ravel(), np.full(n * n, z)])
    F = []
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            b, c, d = a + 1, a + n + 1, a + n
            F += [[a, b, d], [b, c, d]] if flip else [[a, b, c], [a, c, d]]
    return V, np.array(F)


def test_lifted_grid_moves_by_the_lift():
    V, F = grid(11)
    W = V.copy()
    W[:, 2] += 0.01
    values, report = fairline.deviation(V, F, W)
    assert report["method"] == "displacement"
    assert np.allclose(values["signed"], 0.01)
    assert np.allclose(values["distance"], 0.01)
    assert report["all"]["count"] == len(V)
    assert sum(report["all"]["histogram"]["counts"]) == len(V)


def test_other_triangulation_is_measured_by_closest_points():
    V, F = grid(11)
    W, G = grid(17, z=-0.02, flip=True)
    values, report = fairline.deviation(V, F, W, G)
    assert report["method"] == "closest-point"
    assert values["signed"].shape == (len(W),)
    assert np.allclose(values["signed"], -0.02)


def test_region_splits_the_statistics():
    V, F = grid(11)
    W = V.copy()
    region = [0, 1, 2, 3]
    inside = np.unique(F[region].ravel())
    W[inside, 2] += 0.05
    values, report = fairline.deviation(V, F, W, region=region)
    assert values["in_region"].sum() == len(inside)
    assert report["inside_region"]["max_abs"] == pytest.approx(0.05)
    assert report["outside_region"]["max_abs"] == 0.0


def test_bad_region_is_refused():
    V, F = grid(5)
    with pytest.raises(fairline.FairlineError, match="out of range"):
        fairline.deviation(V, F, V, region=[10_000])


def test_broad_and_local_parts_split_an_offset_from_a_spike():
    V, F = grid(41)
    W = V.copy()
    W[:, 2] += 0.01
    spike = 20 * 41 + 20
    W[spike, 2] += 0.02
    values, report = fairline.deviation(V, F, W, broad_wavelength=0.5)
    assert report["broad_wavelength"] == 0.5
    assert np.allclose(values["broad"] + values["local"], values["signed"], atol=1e-12)
    assert report["broad"]["mean"] == pytest.approx(0.01, abs=1e-4)
    assert values["local"][spike] > 0.015
    assert np.abs(np.delete(values["local"], spike)).max() < 0.005
    # the default: ten mean edge lengths (edges 0.05 and 0.05·√2)
    _, default = fairline.deviation(V, F, W)
    assert 0.5 < default["broad_wavelength"] < 0.6
    with pytest.raises(fairline.FairlineError, match="broad"):
        fairline.deviation(V, F, W, broad_wavelength=-1.0)
