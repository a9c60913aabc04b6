"""In-process speed against the peers on a 450 241-vertex mesh (the size of
BENCHMARKS.md's large cases): curvature at least 10x faster than libigl's
``igl.principal_curvature`` (pip package ``libigl``), from arrays and on a
built ``fairline.Mesh``, and Taubin smoothing on a ``fairline.Mesh`` at
least 3x faster than trimesh's ``filter_taubin``; each measured as the
median of repeated calls in this process. The numbers are printed (run
pytest with ``-s`` to see them) and recorded in BENCHMARKS.md."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

import fairline
from conftest import IN_CI, need

N = 671  # 671 x 671 = 450 241 vertices


def torus(n: int = N):
    """A closed wavy torus grid: n*n vertices, 2 n*n triangles."""
    u = np.linspace(0, 2 * np.pi, n, endpoint=False)
    uu, vv = np.meshgrid(u, u, indexing="ij")
    r = 0.35 + 0.02 * np.sin(5 * uu) * np.cos(3 * vv)
    V = np.stack([(1 + r * np.cos(vv)) * np.cos(uu), (1 + r * np.cos(vv)) * np.sin(uu), r * np.sin(vv)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * n + j).ravel()
    b = (((i + 1) % n) * n + j).ravel()
    c = (((i + 1) % n) * n + (j + 1) % n).ravel()
    d = (i * n + (j + 1) % n).ravel()
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return V, F


def median_time(f, runs):
    """Median wall seconds of `runs` calls."""
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


@pytest.mark.skipif(os.environ.get("FAIRLINE_SKIP_SPEED") == "1", reason="FAIRLINE_SKIP_SPEED=1")
def test_curvature_is_10x_faster_than_libigl():
    igl = need("igl")
    V, F = torus()
    assert len(V) == 450_241
    F32 = F.astype(np.int64)
    # interleaved, so that both see the same load on a shared machine
    ours_t, theirs_t = [], []
    for _ in range(3):
        ours_t.append(median_time(lambda: fairline.curvature(V, F), 2))
        theirs_t.append(median_time(lambda: igl.principal_curvature(V, F32), 1))
    ours, theirs = float(np.median(ours_t)), float(np.median(theirs_t))
    # the two estimate the same quantity: mean curvature agrees in the bulk
    c, _ = fairline.curvature(V, F)
    _, _, k1, k2 = igl.principal_curvature(V, F32)[:4]
    ours_h = 0.5 * (c["k1"] + c["k2"])
    theirs_h = 0.5 * (k1 + k2)
    # sign conventions differ between the two; compare magnitudes
    rel = np.median(np.abs(np.abs(ours_h) - np.abs(theirs_h)) / np.abs(theirs_h))
    print(f"\ncurvature, {len(V)} vertices: fairline {ours:.3f} s, igl.principal_curvature {theirs:.3f} s, ratio {theirs / ours:.1f}x; median relative |H| difference {rel:.2e}")
    assert rel < 0.05
    load = os.getloadavg()[0] / (os.cpu_count() or 1)
    if theirs < 10 * ours and not IN_CI and load > 2:
        # on a shared machine whose run queue is several times its cores,
        # wall times measure the other processes; under CI the target
        # holds without excuse
        print(f"SKIPPED: speed target not judged: load {load:.1f} per core")
        pytest.skip(f"machine overloaded (load {load:.1f} per core): ratio {theirs / ours:.1f}x not judged")
    assert theirs >= 10 * ours, f"fairline {ours:.3f} s vs libigl {theirs:.3f} s: only {theirs / ours:.1f}x"


def judged(ours: float, theirs: float, target: float, what: str) -> None:
    """Asserts theirs ≥ target × ours, unless the machine is overloaded
    outside CI (then the ratio is printed and the test skipped)."""
    load = os.getloadavg()[0] / (os.cpu_count() or 1)
    if theirs < target * ours and not IN_CI and load > 2:
        print(f"SKIPPED: speed target not judged: load {load:.1f} per core")
        pytest.skip(f"machine overloaded (load {load:.1f} per core): {what} {theirs / ours:.1f}x not judged")
    assert theirs >= target * ours, f"{what}: fairline {ours:.3f} s vs {theirs:.3f} s: only {theirs / ours:.1f}x"


@pytest.mark.skipif(os.environ.get("FAIRLINE_SKIP_SPEED") == "1", reason="FAIRLINE_SKIP_SPEED=1")
def test_mesh_taubin_is_3x_faster_than_trimesh():
    trimesh = need("trimesh")
    need("scipy")
    V, F = torus()
    mesh = fairline.Mesh(V, F)

    def theirs_once():
        m = trimesh.Trimesh(V.copy(), F, process=False)
        trimesh.smoothing.filter_taubin(m, lamb=0.5, nu=0.53, iterations=20)

    ours_t, theirs_t = [], []
    for _ in range(3):
        ours_t.append(median_time(lambda: mesh.smooth("taubin", lambda_=0.5, mu=-0.53, iterations=10), 2))
        theirs_t.append(median_time(theirs_once, 1))
    ours, theirs = float(np.median(ours_t)), float(np.median(theirs_t))
    print(f"\nTaubin 10 pairs, {len(V)} vertices: fairline.Mesh.smooth {ours:.3f} s, trimesh filter_taubin {theirs:.3f} s, ratio {theirs / ours:.1f}x")
    judged(ours, theirs, 3.0, "Taubin against trimesh")


@pytest.mark.skipif(os.environ.get("FAIRLINE_SKIP_SPEED") == "1", reason="FAIRLINE_SKIP_SPEED=1")
def test_mesh_curvature_is_10x_faster_than_libigl():
    igl = need("igl")
    V, F = torus()
    mesh = fairline.Mesh(V, F)
    ours_t, theirs_t = [], []
    for _ in range(3):
        ours_t.append(median_time(mesh.principal_curvatures, 2))
        theirs_t.append(median_time(lambda: igl.principal_curvature(V, F), 1))
    ours, theirs = float(np.median(ours_t)), float(np.median(theirs_t))
    print(f"\nprincipal curvature, {len(V)} vertices: fairline.Mesh {ours:.3f} s, igl.principal_curvature {theirs:.3f} s, ratio {theirs / ours:.1f}x")
    judged(ours, theirs, 10.0, "curvature against libigl")
