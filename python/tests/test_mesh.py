"""``fairline.Mesh``: connectivity built once, the same numbers as the module
functions bit for bit, the operators libigl and trimesh users know
(checked against ``igl`` and ``trimesh.smoothing``), and the same errors.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import fairline
from fairline import _native
from conftest import need


@pytest.fixture(scope="module")
def sphere(demo):
    return fairline.read_mesh(demo / "sphere.ply")


@pytest.fixture(scope="module")
def panel(demo):
    return fairline.read_mesh(demo / "dented-panel.obj")


def noisy(V, seed=5):
    return V + 0.01 * np.random.default_rng(seed).standard_normal(V.shape)


def bowtie():
    """Two triangle fans meeting at vertex 0 only (a non-manifold vertex,
    split when the mesh is built) plus an open quad strip elsewhere."""
    V = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [-1, 0, 0.1], [-1, -1, 0], [0, 1, 0.3], [-1, 1, 0.1]],
        dtype=float,
    )
    F = np.array([[0, 1, 2], [0, 2, 5], [0, 3, 4], [0, 6, 3]])
    return V, F


# ---- the same numbers as the module functions --------------------------------------


@pytest.mark.parametrize(
    "options",
    [
        {"method": "taubin", "iterations": 10},
        {"method": "laplace", "weights": "cotan", "iterations": 3},
        {"method": "taubin", "fixed": [0, 5, 9], "fix_boundary": True},
        {"method": "implicit"},
    ],
)
def test_smooth_equals_the_module_function(sphere, options):
    V, F = sphere
    V = noisy(V)
    mesh = fairline.Mesh(V, F)
    ours = mesh.smooth(**options)
    theirs, report = fairline.smooth(V, F, **options)
    assert np.array_equal(ours, theirs)
    assert not np.array_equal(ours, V), "the smoothing must move the noise"
    again, report2 = mesh.smooth(report=True, **options)
    assert np.array_equal(again, theirs) and report2["command"] == report["command"] == "smooth"
    # the module function given the Mesh takes the same path
    via, _ = fairline.smooth(mesh, **options)
    assert np.array_equal(via, theirs)


@pytest.mark.parametrize("method", ["rusinkiewicz", "meyer"])
def test_curvature_equals_the_module_function(sphere, method):
    V, F = sphere
    mesh = fairline.Mesh(V, F)
    theirs, _ = fairline.curvature(V, F, method=method)
    ours, _ = mesh.curvature(method=method)
    assert ours.keys() == theirs.keys()
    for k in theirs:
        assert np.array_equal(ours[k], theirs[k]), k
    pc = mesh.principal_curvatures(method=method)
    k1, k2, d1, d2 = pc
    assert np.array_equal(pc.k1, theirs["k1"]) and np.array_equal(k2, theirs["k2"])
    assert np.array_equal(d1, theirs["d1"]) and np.array_equal(d2, theirs["d2"])
    assert np.all(k1 >= k2)
    via, _ = fairline.curvature(mesh, method=method)
    assert np.array_equal(via["mean"], theirs["mean"])


HIGHLIGHT = [
    {},
    {"direction": [0, 1, 0], "plane_normal": [0, 0, 1], "plane_point": [0, 0, 5], "spacing": 0.1, "band": 0.02},
    {"circle_center": [0, 0, 5], "circle_axis": [0, 0, 1], "radii": [1, 2, 3], "band": 0.05},
]


def flat_lines(arrays):
    """The flat arrays split back into the lines file's dicts."""
    pts, off = arrays["points"], arrays["offsets"]
    out = []
    for k in range(len(arrays["index"])):
        line = {"index": int(arrays["index"][k]), "closed": bool(arrays["closed"][k]), "points": pts[off[k] : off[k + 1]]}
        if "radius" in arrays:
            line["radius"] = float(arrays["radius"][k])
        out.append(line)
    return out


def same_lines(ours, theirs):
    assert len(ours) == len(theirs)
    for a, b in zip(ours, theirs):
        assert {k: v for k, v in a.items() if k != "points"} == {k: v for k, v in b.items() if k != "points"}
        assert np.array_equal(a["points"], np.asarray(b["points"], dtype=float).reshape(-1, 3))


@pytest.mark.parametrize("options", HIGHLIGHT)
def test_highlight_lines_equal_the_lines_document(panel, options):
    V, F = panel
    mesh = fairline.Mesh(V, F)
    arrays, report = mesh.highlight_lines(report=True, **options)
    assert report["command"] == "highlight"
    # the JSON document of the CLI's lines file, from the native layer
    kw = fairline._highlight_kwargs(**options)
    v, i, o = fairline._mesh(V, F)
    text, _ = _native.highlight_lines(v, i, o, **kw)
    doc = json.loads(text)
    assert arrays["points"].dtype == np.float64 and arrays["points"].shape[1] == 3
    assert arrays["offsets"][0] == 0 and arrays["offsets"][-1] == len(arrays["points"])
    assert np.all(np.diff(arrays["offsets"]) > 0)
    same_lines(flat_lines(arrays), doc["lines"])
    assert doc["lines"], "lights that cross the mesh must give lines"
    if "bands" in doc:
        assert arrays["band_radius"] == doc["bands"]["radius"]
        same_lines(flat_lines(arrays["lower"]), doc["bands"]["lower"])
        same_lines(flat_lines(arrays["upper"]), doc["bands"]["upper"])
    # the module function (arrays or a Mesh) gives the document's dicts
    for source in ((V, F), (mesh,)):
        lines, _ = fairline.highlight_lines(*source, **options)
        same_lines(lines["lines"], doc["lines"])
        if "bands" in doc:
            same_lines(lines["bands"]["upper"], doc["bands"]["upper"])


def test_highlight_lines_of_a_quad_mesh_triangulate_once(demo):
    V, F = fairline.read_mesh(demo / "quad-saddle.obj")
    mesh = fairline.Mesh(V, F)
    assert not mesh.is_triangle_mesh
    a = mesh.highlight_lines(up="y")
    b = mesh.highlight_lines(up="y")  # from the kept triangulation
    lines, _ = fairline.highlight_lines(V, F, up="y")
    for arrays in (a, b):
        same_lines(flat_lines(arrays), lines["lines"])


# ---- the operators against libigl ------------------------------------------------


def test_vertex_normals_equal_igl_area_weighted(sphere):
    igl = need("igl")
    V, F = sphere
    V = noisy(V)
    N = fairline.Mesh(V, F).vertex_normals()
    assert N.shape == V.shape
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-12)
    theirs = igl.per_vertex_normals(V, F.astype(np.int64), igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    assert np.abs(N - theirs).max() < 1e-12


def test_cotangent_laplacian_and_mass_matrix_equal_igl(sphere):
    igl = need("igl")
    need("scipy")
    import scipy.sparse as sparse
    V, F = sphere
    V = noisy(V)
    mesh = fairline.Mesh(V, F)
    L = mesh.cotangent_laplacian()
    M = mesh.mass_matrix()
    assert isinstance(L, sparse.csr_matrix) and isinstance(M, sparse.csr_matrix)
    n = len(V)
    assert L.shape == (n, n) and M.shape == (n, n)
    Li = igl.cotmatrix(V, F.astype(np.int64))
    Mi = igl.massmatrix(V, F.astype(np.int64), igl.MASSMATRIX_TYPE_VORONOI)
    scale = abs(Li).max()
    assert abs(L - Li).max() <= 1e-12 * scale
    assert abs(M - Mi).max() <= 1e-12 * abs(Mi).max()
    # invariants a wrong assembly breaks: symmetry, constants in the null
    # space, the diagonal of M sums to the area
    assert abs(L - L.T).max() == 0
    assert np.abs(L @ np.ones(n)).max() <= 1e-12 * scale
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()
    assert abs(M.diagonal().sum() - area) <= 1e-12 * area


def test_operators_of_a_non_manifold_mesh_are_over_its_input_vertices():
    need("scipy")
    V, F = bowtie()
    mesh = fairline.Mesh(V, F)
    assert mesh.vertex_count == len(V)
    L = mesh.cotangent_laplacian()
    M = mesh.mass_matrix()
    assert L.shape == (len(V), len(V)) and M.shape == (len(V), len(V))
    assert np.abs(L @ np.ones(len(V))).max() < 1e-12
    assert abs(L - L.T).max() < 1e-15
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()
    assert abs(M.diagonal().sum() - area) < 1e-12
    assert np.all(np.isfinite(mesh.vertex_normals()))
    assert np.array_equal(mesh.smooth(), fairline.smooth(V, F)[0])


def test_principal_curvatures_agree_with_igl(sphere):
    igl = need("igl")
    V, F = sphere
    k1, k2, _, _ = fairline.Mesh(V, F).principal_curvatures()
    _, _, pv1, pv2 = igl.principal_curvature(V, F.astype(np.int64))[:4]
    ours = 0.5 * np.abs(k1 + k2)
    theirs = 0.5 * np.abs(pv1 + pv2)
    assert np.median(np.abs(ours - theirs) / theirs) < 0.05


# ---- Taubin against trimesh --------------------------------------------------------


@pytest.mark.parametrize("lamb,nu,pairs", [(0.5, 0.53, 10), (0.6307, 0.6732, 4)])
def test_taubin_equals_trimesh(sphere, lamb, nu, pairs):
    trimesh = need("trimesh")
    need("scipy")
    V, F = sphere
    V = noisy(V)
    m = trimesh.Trimesh(V.copy(), F, process=False)
    mesh = fairline.Mesh(m)  # a Trimesh stands in for (V, F); copied before trimesh moves it
    trimesh.smoothing.filter_taubin(m, lamb=lamb, nu=nu, iterations=2 * pairs)
    ours = mesh.smooth("taubin", lambda_=lamb, mu=-nu, iterations=pairs)
    size = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    assert np.abs(ours - np.asarray(m.vertices)).max() <= 1e-12 * size


# ---- construction, files, errors ----------------------------------------------------


def test_read_and_arrays(demo, sphere):
    V, F = sphere
    mesh = fairline.Mesh.read(demo / "sphere.ply")
    assert isinstance(mesh, fairline.Mesh)
    assert np.array_equal(mesh.V, V) and np.array_equal(mesh.F, F)
    assert mesh.vertices is mesh.V and mesh.faces is mesh.F
    assert (mesh.vertex_count, mesh.face_count) == (len(V), len(F))
    assert "fairline.Mesh(" in repr(mesh)
    with pytest.raises(ValueError):
        mesh.V[0, 0] = 1.0  # read-only
    # the mesh keeps its own copy of the caller's arrays
    V2 = V.copy()
    m2 = fairline.Mesh(V2, F)
    V2[:] = 0
    assert np.array_equal(m2.V, V)
    # every module function takes a Mesh for (V, F)
    faces, _ = fairline.detect(mesh)
    faces2, _ = fairline.detect(V, F)
    assert np.array_equal(faces, faces2)
    d, _ = fairline.deviation(mesh, None, mesh)
    assert np.all(d["distance"] == 0)


def test_errors_are_fairline_errors(demo):
    V, F = bowtie()
    with pytest.raises(fairline.FairlineError, match="refers to vertex 9"):
        fairline.Mesh(V, np.array([[0, 1, 9]]))
    with pytest.raises(fairline.FairlineError, match="non-manifold|edge"):
        fairline.Mesh(V, np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4]]))
    with pytest.raises(fairline.FairlineFileError):
        fairline.Mesh.read(demo / "no-such-file.ply")
    mesh = fairline.Mesh(V, F)
    with pytest.raises(fairline.FairlineTypeError):
        mesh.smooth(no_such_option=1)
    with pytest.raises(fairline.FairlineError, match="method"):
        mesh.smooth("no-such-method")
    with pytest.raises(fairline.FairlineError, match="left out"):
        fairline.smooth(mesh, F)
    Vq, Fq = fairline.read_mesh(demo / "quad-saddle.obj")
    with pytest.raises(fairline.FairlineError, match="triangle mesh"):
        fairline.Mesh(Vq, Fq).cotangent_laplacian()
    with pytest.raises(fairline.FairlineError, match="no faces"):
        fairline.Mesh(V, np.zeros((0, 3), dtype=int)).highlight_lines()


def test_without_scipy_the_matrices_say_so(monkeypatch):
    V, F = bowtie()
    mesh = fairline.Mesh(V, F)
    monkeypatch.setitem(sys.modules, "scipy", None)
    monkeypatch.setitem(sys.modules, "scipy.sparse", None)
    with pytest.raises(fairline.FairlineError, match="needs scipy"):
        mesh.cotangent_laplacian()
    with pytest.raises(fairline.FairlineError, match="needs scipy"):
        mesh.mass_matrix()
