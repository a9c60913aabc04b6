"""trimesh's uniform Laplace and Taubin filters (trimesh.smoothing) give
our numbers where the semantics agree, and the trimesh adapters.

Parameter mapping (closed meshes: trimesh's equal-weight operator takes a
vertex's neighbours from the directed face edges, so on a boundary it
misses one neighbour and the two differ there by design):

* ``filter_laplacian(m, lamb=l, iterations=k, volume_constraint=False)``
  == ``smooth(V, F, method="laplace", weights="uniform", lambda_=l,
  iterations=k)`` (trimesh's default ``volume_constraint=True`` rescales
  about the centre of mass after every step; ours preserves volume
  differently, so it is switched off);
* ``filter_taubin(m, lamb=l, nu=n, iterations=2k)`` == ``smooth(V, F,
  method="taubin", lambda_=l, mu=-n, iterations=k)``: trimesh counts single
  steps (λ, then μ, alternating), ours counts λ|μ pairs, and trimesh's ν is
  −μ;
* ``laplacian_calculation(m, pinned_vertices=P)`` == ``fixed=P``.

The two sum the umbrella in different orders, so they agree to rounding
(1e-12 of the size of the mesh), not bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

import fairline
from conftest import need


@pytest.fixture(scope="module")
def sphere(demo):
    trimesh = need("trimesh")
    need("scipy")
    V, F = fairline.read_mesh(demo / "sphere.ply")
    m = trimesh.Trimesh(V, F, process=False)
    assert m.is_watertight, "the comparison needs a closed mesh"
    return V, F


def close(a, b, V):
    size = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    d = np.abs(a - b).max()
    assert d <= 1e-12 * size, f"largest difference {d:.3e} (size {size:.3e})"


def noisy(V, seed=3):
    rng = np.random.default_rng(seed)
    return V + 0.01 * rng.standard_normal(V.shape)


@pytest.mark.parametrize("lamb,iterations", [(0.5, 10), (0.33, 3)])
def test_uniform_laplace_equals_trimesh(sphere, lamb, iterations):
    trimesh = need("trimesh")
    V, F = sphere
    V = noisy(V)
    m = trimesh.Trimesh(V.copy(), F, process=False)
    trimesh.smoothing.filter_laplacian(m, lamb=lamb, iterations=iterations, volume_constraint=False)
    ours, report = fairline.smooth(V, F, method="laplace", weights="uniform", lambda_=lamb, iterations=iterations)
    close(ours, np.asarray(m.vertices), V)
    assert report["max_displacement"] > 1e-3  # the filter did move the noise


@pytest.mark.parametrize("lamb,nu,pairs", [(0.5, 0.53, 10), (0.6307, 0.6732, 4)])
def test_taubin_equals_trimesh(sphere, lamb, nu, pairs):
    trimesh = need("trimesh")
    V, F = sphere
    V = noisy(V)
    m = trimesh.Trimesh(V.copy(), F, process=False)
    trimesh.smoothing.filter_taubin(m, lamb=lamb, nu=nu, iterations=2 * pairs)
    ours, report = fairline.smooth(V, F, method="taubin", lambda_=lamb, mu=-nu, iterations=pairs)
    close(ours, np.asarray(m.vertices), V)
    assert report["lambda"] == lamb and report["mu"] == -nu


def test_pinned_vertices_equal_fixed(sphere):
    trimesh = need("trimesh")
    V, F = sphere
    V = noisy(V)
    pinned = [0, 7, 42]
    m = trimesh.Trimesh(V.copy(), F, process=False)
    op = trimesh.smoothing.laplacian_calculation(m, equal_weight=True, pinned_vertices=pinned)
    trimesh.smoothing.filter_laplacian(m, lamb=0.5, iterations=5, volume_constraint=False, laplacian_operator=op)
    ours, _ = fairline.smooth(V, F, method="laplace", lambda_=0.5, iterations=5, fixed=pinned)
    close(ours, np.asarray(m.vertices), V)
    assert np.array_equal(ours[pinned], V[pinned])


def test_a_trimesh_can_stand_in_for_v_and_f(sphere):
    trimesh = need("trimesh")
    V, F = sphere
    m = fairline.to_trimesh(V, F)
    assert isinstance(m, trimesh.Trimesh)
    assert np.array_equal(m.vertices, V) and np.array_equal(m.faces, F)
    a, _ = fairline.smooth(m, method="taubin")
    b, _ = fairline.smooth(V, F, method="taubin")
    assert np.array_equal(a, b)
    V2, F2 = fairline.from_trimesh(m)
    assert V2.dtype == np.float64 and F2.dtype == np.int64
    assert np.array_equal(V2, V) and np.array_equal(F2, F)
    c, _ = fairline.curvature(m)
    assert c["k1"].shape == (len(V),)
