"""The package gives the CLI's results bit for bit on the same input: the
same positions, curvature columns, lines, regions, surfaces and reports
(every key except the computation time)."""

from __future__ import annotations

import inspect
import json
import re

import numpy as np
import pytest

import fairline
from conftest import cli_report, read_ply, run, same_report


def exact(a, b):
    """Equal shapes and bit-identical float64 values."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape
    assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), f"largest difference {np.abs(a - b).max()}"


# ---- reading and writing -------------------------------------------------


def test_read_mesh_equals_an_independent_obj_parse(demo):
    path = demo / "wavy.obj"
    V, F = fairline.read_mesh(path)
    vs, fs = [], []
    for line in path.read_text().splitlines():
        w = line.split()
        if w[:1] == ["v"]:
            vs.append([float(x) for x in w[1:4]])
        elif w[:1] == ["f"]:
            fs.append([int(x.split("/")[0]) - 1 for x in w[1:]])
    exact(V, vs)
    assert V.dtype == np.float64 and F.dtype == np.int64
    assert np.array_equal(F, np.array(fs))


def test_read_mesh_equals_an_independent_ply_parse(demo):
    V, F = fairline.read_mesh(demo / "sphere.ply")
    names, values, faces = read_ply(demo / "sphere.ply")
    assert names[:3] == ["x", "y", "z"]
    exact(V, values[:, :3])
    assert np.array_equal(F, np.array(faces))


@pytest.mark.parametrize("ext", ["obj", "ply", "off", "stl"])
def test_write_mesh_writes_the_bytes_of_fairline_convert(cli, demo, tmp_path, ext):
    src = demo / "quad-saddle.obj" if ext != "stl" else demo / "wavy.obj"
    run(cli, "convert", src, tmp_path / f"cli.{ext}")
    V, F = fairline.read_mesh(src)
    fairline.write_mesh(tmp_path / f"py.{ext}", V, F)
    assert (tmp_path / f"py.{ext}").read_bytes() == (tmp_path / f"cli.{ext}").read_bytes()


# ---- algorithms ------------------------------------------------------------


@pytest.mark.parametrize("method", ["rusinkiewicz", "meyer"])
@pytest.mark.parametrize("name", ["sphere.ply", "quad-saddle.obj"])
def test_curvature_equals_cli(cli, demo, tmp_path, method, name):
    run(cli, "curvature", demo / name, "-o", tmp_path / "c.ply", "--method", method, "--report", tmp_path / "r.json")
    names, values, _ = read_ply(tmp_path / "c.ply")
    col = {n: values[:, k] for k, n in enumerate(names)}
    V, F = fairline.read_mesh(demo / name)
    c, report = fairline.curvature(V, F, method=method)
    for key in ["k1", "k2", "mean", "gauss"]:
        exact(c[key], col[key])
    exact(c["normals"], np.column_stack([col["nx"], col["ny"], col["nz"]]))
    exact(c["d1"], np.column_stack([col["d1x"], col["d1y"], col["d1z"]]))
    exact(c["d2"], np.column_stack([col["d2x"], col["d2y"], col["d2z"]]))
    same_report(report, cli_report(tmp_path / "r.json"))


SMOOTH_CASES = [
    ("wavy.obj", {}, []),
    ("wavy.obj", {"method": "taubin", "iterations": 7, "pass_band": 0.05}, ["--method", "taubin", "--iterations", "7", "--pass-band", "0.05"]),
    ("wavy.obj", {"method": "taubin", "lambda_": 0.6, "mu": -0.62}, ["--method", "taubin", "--lambda", "0.6", "--mu", "-0.62"]),
    ("quad-saddle.obj", {"method": "laplace", "weights": "edge", "fix_boundary": True}, ["--method", "laplace", "--weights", "edge", "--fix-boundary"]),
    ("sphere.ply", {"method": "implicit", "time_step": 2.0, "preserve_volume": True}, ["--method", "implicit", "--time-step", "2", "--preserve-volume"]),
    ("wavy.obj", {"method": "spring"}, ["--method", "spring"]),
    ("dented-roof.obj", {"method": "schneider-kobbelt", "iterations": 10}, ["--method", "schneider-kobbelt", "--iterations", "10"]),
    ("wavy.obj", {"method": "laplace", "weights": "cotan", "tangential": True, "fixed": [0, 5, 9]}, ["--method", "laplace", "--weights", "cotan", "--tangential", "--fixed", "FIXED"]),
    ("quad-saddle.obj", {"method": "laplace", "hierarchical_boundary": True}, ["--method", "laplace", "--hierarchical-boundary"]),
]


@pytest.mark.parametrize("name,kwargs,args", SMOOTH_CASES)
def test_smooth_equals_cli(cli, demo, tmp_path, name, kwargs, args):
    if "FIXED" in args:
        (tmp_path / "fixed.json").write_text(json.dumps({"vertices": kwargs["fixed"]}))
        args = [tmp_path / "fixed.json" if a == "FIXED" else a for a in args]
    run(cli, "smooth", demo / name, *args, "-o", tmp_path / "s.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "s.ply")
    V, F = fairline.read_mesh(demo / name)
    V2, report = fairline.smooth(V, F, **kwargs)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"))


def zigzag_quads(n=13):
    """A free-form quad grid whose structure lines zigzag (the CLI demo's
    `zigzag_freeform`)."""
    f = lambda x, y: 0.3 * np.sin(1.5 * x) * (1.0 + 0.5 * y * y) + 0.2 * x * y
    h = 2.0 / (n - 1)
    V, F = [], []
    for j in range(n):
        for i in range(n):
            x, y = -1 + i * h, -1 + j * h
            if 0 < i < n - 1 and 0 < j < n - 1:
                x += 0.2 * h if j % 2 == 0 else -0.2 * h
                y += 0.1 * h if i % 2 == 0 else -0.1 * h
            V.append([x, y, f(x, y)])
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            F.append([a, a + 1, a + n + 1, a + n])
    return np.array(V), np.array(F)


@pytest.mark.parametrize("kwargs,args", [({}, []), ({"weight": 0.005, "deviation": 0.05, "iterations": 4, "fix_boundary": True},
                                          ["--weight", "0.005", "--deviation", "0.05", "--iterations", "4", "--fix-boundary"]),
                                         ({"off_surface": True}, ["--off-surface"]),
                                         ({"deviation_weights": True}, ["--deviation-weights"])])
def test_fair_quad_equals_cli(cli, tmp_path, kwargs, args):
    V, F = zigzag_quads()
    fairline.write_mesh(tmp_path / "zigzag.obj", V, F)
    run(cli, "fair-quad", tmp_path / "zigzag.obj", *args, "-o", tmp_path / "q.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "q.ply")
    V2, report = fairline.fair_quad(V, F, **kwargs)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"))
    assert report["max_displacement"] > 0
    assert report["structure_energy_after"] < report["structure_energy_before"]


def test_fair_quad_network_equals_cli(cli, tmp_path):
    # the polyline network with tolerance cylinders (Grüner §3.1.1): only
    # the heights move, within tolerance × the mean edge length
    V, F = zigzag_quads()
    V[:, 2] += np.where(np.arange(len(V)) % 2 == 0, 0.01, -0.01)
    fairline.write_mesh(tmp_path / "zigzag.obj", V, F)
    args = ["--method", "network", "--tolerance", "0.05", "--fix-boundary"]
    run(cli, "fair-quad", tmp_path / "zigzag.obj", *args, "-o", tmp_path / "q.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "q.ply")
    V2, report = fairline.fair_quad(V, F, method="network", tolerance=0.05, fix_boundary=True)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"))
    assert report["method"] == "network"
    assert report["network_energy_after"] < report["network_energy_before"]
    assert np.array_equal(V2[:, :2], V[:, :2])
    with pytest.raises(fairline.FairlineError):
        fairline.fair_quad(V, F, method="fast")


@pytest.mark.parametrize("kwargs,args", [({}, []), ({"lambda_": 0.5, "solver": "cg"}, ["--lambda", "0.5", "--solver", "cg"]),
                                         ({"projection": "none"}, ["--projection", "none"])])
def test_enhance_equals_cli(cli, demo, tmp_path, kwargs, args):
    run(cli, "enhance", demo / "rounded-cube.obj", *args, "-o", tmp_path / "e.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "e.ply")
    V, F = fairline.read_mesh(demo / "rounded-cube.obj")
    V2, report = fairline.enhance(V, F, **kwargs)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"))


def test_repair_equals_cli(cli, tmp_path):
    # a dirty mesh: a duplicate face, a zero-area face, an unreferenced
    # vertex, one face against the orientation of its neighbours
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [5, 5, 5], [3, 0, 0]], dtype=float)
    F = [[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 1, 0], [4, 6, 1], [2, 4, 1]]
    fairline.write_mesh(tmp_path / "dirty.obj", V, [list(f) for f in F])
    run(cli, "repair", tmp_path / "dirty.obj", tmp_path / "clean.ply", "--report", tmp_path / "r.json")
    _, values, faces = read_ply(tmp_path / "clean.ply")
    V2, F2, report = fairline.repair(*fairline.read_mesh(tmp_path / "dirty.obj"))
    exact(V2, values)
    assert np.array_equal(np.asarray(F2), np.array(faces))
    same_report(report, cli_report(tmp_path / "r.json"))
    assert report["removed_faces"], "the dirty mesh must need repairs"


HIGHLIGHT_CASES = [
    ("sphere.ply", {}, []),
    ("dented-panel.obj", {"direction": [0, 1, 0], "plane_normal": [0, 0, 1], "plane_point": [0, 0, 5], "spacing": 0.1, "band": 0.02},
     ["--direction", "0,1,0", "--plane-normal", "0,0,1", "--plane-point", "0,0,5", "--spacing", "0.1", "--band", "0.02"]),
    ("dented-panel.obj", {"circle_center": [0, 0, 5], "circle_axis": [0, 0, 1], "radii": [1, 2, 3], "band": 0.05},
     ["--circle-center", "0,0,5", "--circle-axis", "0,0,1", "--radii", "1,2,3", "--band", "0.05"]),
    ("quad-saddle.obj", {"up": "y"}, ["--up", "y"]),
]


def same_lines(ours, theirs):
    assert len(ours) == len(theirs)
    for a, b in zip(ours, theirs):
        assert {k: v for k, v in a.items() if k not in ("points", "uv")} == {k: v for k, v in b.items() if k not in ("points", "uv")}
        exact(a["points"], np.asarray(b["points"]).reshape(-1, 3))
        if "uv" in b:
            exact(a["uv"], np.asarray(b["uv"]).reshape(-1, 2))


def same_document(ours, theirs):
    assert ours.keys() == theirs.keys()
    same_lines(ours["lines"], theirs["lines"])
    if "bands" in theirs:
        assert ours["bands"]["radius"] == theirs["bands"]["radius"]
        same_lines(ours["bands"]["lower"], theirs["bands"]["lower"])
        same_lines(ours["bands"]["upper"], theirs["bands"]["upper"])


@pytest.mark.parametrize("name,kwargs,args", HIGHLIGHT_CASES)
def test_highlight_lines_equal_cli(cli, demo, tmp_path, name, kwargs, args):
    run(cli, "highlight", demo / name, *args, "-o", tmp_path / "l.json", "--report", tmp_path / "r.json")
    lines, report = fairline.highlight_lines(*fairline.read_mesh(demo / name), **kwargs)
    same_document(lines, json.loads((tmp_path / "l.json").read_text()))
    same_report(report, cli_report(tmp_path / "r.json"))
    assert lines["lines"], "lights that cross the mesh must give lines"


def test_highlight_lines_from_a_lights_file_equal_cli(cli, demo, tmp_path):
    lights = {"plane_point": [0.1, 0, 4], "plane_normal": [0, 0.1, 1], "direction": [1, 0, 0], "spacing": 0.15}
    (tmp_path / "lights.json").write_text(json.dumps(lights))
    run(cli, "highlight", demo / "dented-panel.obj", "--lights", tmp_path / "lights.json", "-o", tmp_path / "l.json", "--report", tmp_path / "r.json")
    V, F = fairline.read_mesh(demo / "dented-panel.obj")
    for given in (lights, tmp_path / "lights.json"):
        doc, report = fairline.highlight_lines(V, F, lights=given)
        same_document(doc, json.loads((tmp_path / "l.json").read_text()))
        same_report(report, cli_report(tmp_path / "r.json"))


def test_detect_equals_cli(cli, demo, tmp_path):
    run(cli, "detect", demo / "dented-panel.obj", "-o", tmp_path / "region.json", "--report", tmp_path / "r.json")
    faces, report = fairline.detect(*fairline.read_mesh(demo / "dented-panel.obj"))
    assert faces.tolist() == json.loads((tmp_path / "region.json").read_text())["faces"]
    same_report(report, cli_report(tmp_path / "r.json"))
    assert report["regions"], "the dented panel's dent must be found"


@pytest.mark.parametrize("name,kwargs,args", [
    ("dented-panel.obj", {"threshold": 1.5, "region_margin": 0.5, "max_regions": 1},
     ["--threshold", "1.5", "--region-margin", "0.5", "--max-regions", "1"]),
    ("dented-panel.obj", {"lights": {"plane_point": [0, 0, 5], "plane_normal": [0, 0, 1], "direction": [1, 0.2, 0], "spacing": 0.12}},
     ["--plane-point", "0,0,5", "--plane-normal", "0,0,1", "--direction", "1,0.2,0", "--spacing", "0.12"]),
    ("rounded-cube.obj", {}, []),
])
def test_detect_options_equal_cli(cli, demo, tmp_path, name, kwargs, args):
    """The same detection policy in both: the measure at the lights asked
    for, the lines read at their readable lights, what one light array
    leaves unjudged judged again with finer arrays."""
    run(cli, "detect", demo / name, *args, "-o", tmp_path / "region.json", "--report", tmp_path / "r.json")
    faces, report = fairline.detect(*fairline.read_mesh(demo / name), **kwargs)
    assert faces.tolist() == json.loads((tmp_path / "region.json").read_text())["faces"]
    same_report(report, cli_report(tmp_path / "r.json"), input_path=demo / name)


def test_fair_equals_cli(cli, demo, tmp_path):
    region = demo / "dented-panel-region.json"
    run(cli, "fair", demo / "dented-panel.obj", "--region", region, "--max-iterations", "5", "-o", tmp_path / "f.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "f.ply")
    V, F = fairline.read_mesh(demo / "dented-panel.obj")
    faces = json.loads(region.read_text())["faces"]
    for given in (faces, {"faces": faces}, region):
        V2, report = fairline.fair(V, F, given, max_iterations=5)
        exact(V2, values)
        same_report(report, cli_report(tmp_path / "r.json"), input_path=demo / "dented-panel.obj")
    assert report["max_displacement"] > 0


@pytest.mark.parametrize("kwargs,args", [({"method": "paper"}, ["--method", "paper"]),
                                         ({"laplacian_weight": 0.1}, ["--laplacian-weight", "0.1"]),
                                         ({"least_change": False}, ["--no-least-change"])])
def test_fair_methods_equal_cli(cli, demo, tmp_path, kwargs, args):
    region = demo / "dented-panel-region.json"
    run(cli, "fair", demo / "dented-panel.obj", "--region", region, "--max-iterations", "5", *args, "-o", tmp_path / "f.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "f.ply")
    V2, report = fairline.fair(*fairline.read_mesh(demo / "dented-panel.obj"), region, max_iterations=5, **kwargs)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"), input_path=demo / "dented-panel.obj")


def test_fair_auto_equals_cli(cli, demo, tmp_path):
    run(cli, "fair", demo / "dented-panel.obj", "--auto", "--max-iterations", "3", "-o", tmp_path / "f.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "f.ply")
    V2, report = fairline.fair(*fairline.read_mesh(demo / "dented-panel.obj"), auto=True, max_iterations=3)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"), input_path=demo / "dented-panel.obj")


def test_fair_with_grow_and_lights_equals_cli(cli, demo, tmp_path):
    """Every fair option Python shares with the CLI: the region grown, the
    lights given whole, the method and the iterations."""
    lights = {"plane_point": [0, 0, 5], "plane_normal": [0, 0, 1], "direction": [1, 0.2, 0], "spacing": 0.12}
    (tmp_path / "lights.json").write_text(json.dumps(lights))
    region = demo / "dented-panel-region.json"
    run(cli, "fair", demo / "dented-panel.obj", "--region", region, "--grow", "1", "--lights", tmp_path / "lights.json",
        "--method", "diffusion-flow", "--max-iterations", "3", "-o", tmp_path / "f.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "f.ply")
    V2, report = fairline.fair(*fairline.read_mesh(demo / "dented-panel.obj"), region, grow=1, lights=lights,
                               method="diffusion-flow", max_iterations=3)
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"), input_path=demo / "dented-panel.obj")


def test_fair_quad_and_enhance_with_fixed_vertices_equal_cli(cli, demo, tmp_path):
    V, F = zigzag_quads()
    fairline.write_mesh(tmp_path / "zigzag.obj", V, F)
    (tmp_path / "fixed.json").write_text(json.dumps({"vertices": [14, 15, 27]}))
    run(cli, "fair-quad", tmp_path / "zigzag.obj", "--fixed", tmp_path / "fixed.json", "-o", tmp_path / "q.ply", "--report", tmp_path / "r.json")
    _, values, _ = read_ply(tmp_path / "q.ply")
    V2, report = fairline.fair_quad(V, F, fixed=[14, 15, 27])
    exact(V2, values)
    same_report(report, cli_report(tmp_path / "r.json"))
    run(cli, "enhance", demo / "rounded-cube.obj", "--fixed", tmp_path / "fixed.json", "--iterations", "2", "-o", tmp_path / "e.ply", "--report", tmp_path / "r2.json")
    _, values, _ = read_ply(tmp_path / "e.ply")
    V3, report = fairline.enhance(*fairline.read_mesh(demo / "rounded-cube.obj"), fixed=[14, 15, 27], iterations=2)
    exact(V3, values)
    same_report(report, cli_report(tmp_path / "r2.json"))


# ---- B-spline surfaces -----------------------------------------------------


def test_read_and_write_surfaces_keep_every_number(cli, demo, tmp_path):
    path = demo / "bspline-panel-dented.json"
    surfaces = fairline.read_surfaces(path)
    raw = json.loads(path.read_text())["surfaces"]
    assert len(surfaces) == len(raw)
    exact(surfaces[0]["control_points"], raw[0]["control_points"])
    fairline.write_surfaces(tmp_path / "copy.json", surfaces)
    run(cli, "convert", path, tmp_path / "cli.json")
    assert (tmp_path / "copy.json").read_bytes() == (tmp_path / "cli.json").read_bytes()


@pytest.mark.parametrize("ext", ["igs", "step"])
def test_write_surfaces_as_cad_files_round_trips_through_the_cli(cli, demo, tmp_path, ext):
    """IGES and STEP written from Python read back bit-identical, and the
    CLI converts them back to exactly the JSON it writes for the original
    (the files themselves carry a time stamp)."""
    path = demo / "bspline-panel-dented.json"
    surfaces = fairline.read_surfaces(path)
    out = tmp_path / f"py.{ext}"
    fairline.write_surfaces(out, surfaces)
    back = fairline.read_surfaces(out)
    assert len(back) == len(surfaces)
    for a, b in zip(surfaces, back):
        exact(a["control_points"], b["control_points"])
    run(cli, "convert", out, tmp_path / "via-cad.json")
    run(cli, "convert", path, tmp_path / "direct.json")
    assert (tmp_path / "via-cad.json").read_bytes() == (tmp_path / "direct.json").read_bytes()


def test_surface_highlight_lines_equal_cli(cli, demo, tmp_path):
    args = ["--circle-center", "2,1.5,2.5", "--circle-axis", "0,0,1", "--radii", "2.4,2.6,2.8", "--grid", "120"]
    run(cli, "highlight", demo / "bspline-panel-dented.json", *args, "-o", tmp_path / "l.json", "--report", tmp_path / "r.json")
    surfaces = fairline.read_surfaces(demo / "bspline-panel-dented.json")
    lines, report = fairline.surface_highlight_lines(surfaces, circle_center=[2, 1.5, 2.5], circle_axis=[0, 0, 1], radii=[2.4, 2.6, 2.8], grid=120)
    same_document(lines, json.loads((tmp_path / "l.json").read_text()))
    same_report(report, cli_report(tmp_path / "r.json"))
    assert lines["lines"]


def without_timestamps(text: str) -> str:
    """An IGES file's text with its generation time (YYYYMMDD.HHNNSS) blanked."""
    return re.sub(r"\d{8}\.\d{6}", "00000000.000000", text)


def scipy_curve_distance(curve, points) -> float:
    """Largest distance from `points` to `curve`, evaluated by scipy's
    B-spline (an independent evaluator) on a fine parameter grid."""
    from scipy.interpolate import BSpline

    k, t, c = curve["degree"], np.asarray(curve["knots"]), np.asarray(curve["points"])
    spline = BSpline(t, c, k)
    p = np.asarray(points)
    u = np.linspace(t[k], t[-k - 1], 40 * len(c) + 200)
    nearest = np.linalg.norm(p[:, None, :] - spline(u)[None, :, :], axis=2).argmin(axis=1)
    # golden-section search for the closest parameter between the
    # neighbours of the nearest sample
    lo = u[np.maximum(nearest - 1, 0)]
    hi = u[np.minimum(nearest + 1, len(u) - 1)]
    g = (np.sqrt(5.0) - 1.0) / 2.0
    for _ in range(60):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        da = np.linalg.norm(spline(a) - p, axis=1)
        db = np.linalg.norm(spline(b) - p, axis=1)
        hi = np.where(da < db, b, hi)
        lo = np.where(da < db, lo, a)
    return float(np.linalg.norm(spline(0.5 * (lo + hi)) - p, axis=1).max())


@pytest.mark.parametrize(
    "name,kwargs,args",
    [
        ("dented-panel.obj", {}, []),
        ("dented-panel.obj", {"tolerance": 0.002}, ["--curve-tolerance", "0.002"]),
        ("bspline-panel-dented.json", {}, []),
    ],
)
def test_highlight_curves_write_the_clis_file(cli, demo, tmp_path, name, kwargs, args):
    src = demo / name
    run(cli, "highlight", src, *args, "-o", tmp_path / "cli.igs", "--report", tmp_path / "r.json")
    ours = tmp_path / "py.igs"
    if name.endswith(".json"):
        curves, report = fairline.surface_highlight_curves(fairline.read_surfaces(src), path=ours, **kwargs)
        lines = [l for l in fairline.surface_highlight_lines(fairline.read_surfaces(src))[0]["lines"] if l["level"] == 0]
    else:
        V, F = fairline.read_mesh(src)
        curves, report = fairline.highlight_curves(V, F, path=ours, **kwargs)
        again, _ = fairline.Mesh(V, F).highlight_curves(**kwargs)
        assert [c["label"] for c in again] == [c["label"] for c in curves]
        lines = fairline.highlight_lines(V, F)[0]["lines"]
    assert without_timestamps(ours.read_text()) == without_timestamps((tmp_path / "cli.igs").read_text())
    same_report(report, cli_report(tmp_path / "r.json"))
    summary = report["curves"]
    assert summary["curves"] == len(curves) == len(lines) > 0
    assert sum(len(c["points"]) for c in curves) == summary["control_points"]
    # every line point lies within the tolerance of its curve, by scipy
    tol = summary["tolerance"]
    worst = max(scipy_curve_distance(c, l["points"]) for c, l in zip(curves, lines))
    assert worst <= tol * 1.001, f"{worst} > {tol}"


def test_surface_iso_curves_equal_cli(cli, demo, tmp_path):
    src = demo / "bspline-panel-dented.json"
    run(cli, "section", src, "--iso", "4", "--samples", "30", "--comb-scale", "0.2",
        "--csv", tmp_path / "c.csv", "--report", tmp_path / "r.json")
    curves, report = fairline.surface_iso_curves(fairline.read_surfaces(src), count=4, samples=30, comb_scale=0.2)
    same_report(report, cli_report(tmp_path / "r.json"))
    rows = np.loadtxt(tmp_path / "c.csv", delimiter=",", skiprows=1, usecols=(0, 2, 3, 5, 6, 7, 8, 9, 10, 11, 12))
    kind = [line.split(",")[1] for line in (tmp_path / "c.csv").read_text().splitlines()[1:]]
    exact(curves["points"], rows[:, 4:7])
    exact(curves["params"], rows[:, 3])
    exact(curves["curvature"], rows[:, 7])
    exact(curves["comb"], rows[:, 8:11])
    per_point = np.repeat(np.arange(len(curves["surface"])), np.diff(curves["offsets"]))
    assert np.array_equal(per_point, rows[:, 2].astype(int))
    exact(curves["value"][per_point], rows[:, 1])
    assert [("u", "v", "trim")[f] for f in curves["kind"][per_point]] == kind
    assert len(curves["surface"]) == report["iso"]["curves"] == 8


def test_highlight_curves_refuse_bad_options(demo, tmp_path):
    V, F = fairline.read_mesh(demo / "dented-panel.obj")
    with pytest.raises(fairline.FairlineError, match="tolerance must be a positive number"):
        fairline.highlight_curves(V, F, tolerance=-1)
    with pytest.raises(fairline.FairlineError, match=r"curves are written as \.igs or \.iges"):
        fairline.highlight_curves(V, F, path=tmp_path / "lines.json")
    with pytest.raises(fairline.FairlineError, match="unit must be an IGES unit name"):
        fairline.highlight_curves(V, F, path=tmp_path / "lines.igs", unit="furlong")
    assert not list(tmp_path.iterdir()), "nothing is written on bad options"
    curves, _ = fairline.highlight_curves(V, F, path=tmp_path / "lines.igs", unit="in")
    assert "2HIN" in (tmp_path / "lines.igs").read_text()


def test_fair_surface_equals_cli(cli, demo, tmp_path):
    lights, ends = demo / "bspline-panel-lights.json", demo / "bspline-panel-endpoints.json"
    run(cli, "fair-surface", demo / "bspline-panel-dented.json", "--lights", lights, "--endpoints", ends, "--max-iterations", "3",
        "-o", tmp_path / "out.json", "--report", tmp_path / "r.json")
    surfaces = fairline.read_surfaces(demo / "bspline-panel-dented.json")
    faired, report = fairline.fair_surface(surfaces, json.loads(lights.read_text()), ends, max_iterations=3)
    theirs = json.loads((tmp_path / "out.json").read_text())["surfaces"]
    exact(faired[0]["control_points"], theirs[0]["control_points"])
    same_report(report, cli_report(tmp_path / "r.json"))
    assert report["modified_control_points"] > 0
    fairline.write_surfaces(tmp_path / "py.json", faired)
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "out.json").read_bytes()


@pytest.mark.parametrize("kwargs,args", [({"boundary": "tangent", "keep_weight": 0.5}, ["--boundary", "tangent", "--keep-weight", "0.5"]),
                                         ({"grid": 80, "sample_spacing": 0.05}, ["--grid", "80", "--sample-spacing", "0.05"])])
def test_fair_surface_options_equal_cli(cli, demo, tmp_path, kwargs, args):
    lights, ends = demo / "bspline-panel-lights.json", demo / "bspline-panel-endpoints.json"
    run(cli, "fair-surface", demo / "bspline-panel-dented.json", "--lights", lights, "--endpoints", ends, "--max-iterations", "2", *args,
        "-o", tmp_path / "out.json", "--report", tmp_path / "r.json")
    surfaces = fairline.read_surfaces(demo / "bspline-panel-dented.json")
    faired, report = fairline.fair_surface(surfaces, json.loads(lights.read_text()), ends, max_iterations=2, **kwargs)
    fairline.write_surfaces(tmp_path / "py.json", faired)
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "out.json").read_bytes()
    same_report(report, cli_report(tmp_path / "r.json"))


# ---- defaults ------------------------------------------------------------------


FUNCTIONS = {
    "curvature": fairline.curvature,
    "smooth": fairline.smooth,
    "fair-quad": fairline.fair_quad,
    "enhance": fairline.enhance,
    "highlight": fairline.highlight_lines,
    "detect": fairline.detect,
    "fair": fairline.fair,
    "fair-surface": fairline.fair_surface,
}


@pytest.mark.parametrize("command", sorted(FUNCTIONS))
def test_every_default_is_the_clis(cli, command):
    """Each option with a default in `fairline COMMAND --help` has a
    parameter of the same name (snake_case) with the same default."""
    text = run(cli, command, "--help").stdout
    params = inspect.signature(FUNCTIONS[command]).parameters
    found = 0
    # clap prints `--name <V>` then the help text, ending in [default: x]
    for m in re.finditer(r"--([a-z0-9-]+)(?: <[^>]+>)?\n((?:.(?!\n\s+-))*?)\[default: ([^\]]+)\]", text, re.S):
        name, value = m.group(1).replace("-", "_"), m.group(3)
        if name == "lambda":
            name = "lambda_"
        if name in ("grid",) and command == "highlight":
            continue  # B-spline option: surface_highlight_lines has it
        if name == "size":
            continue  # size of the --png picture: the Python functions draw none
        assert name in params, f"{command}: --{m.group(1)} has no parameter"
        default = params[name].default
        if isinstance(default, str):
            assert default == value, f"{command} {name}: {default!r} != {value!r}"
        else:
            assert float(default) == float(value), f"{command} {name}: {default!r} != {value!r}"
        found += 1
    assert found > 0 or command == "curvature" and params["method"].default == "rusinkiewicz"


def test_surface_deviation_equals_cli(cli, demo, tmp_path):
    before, after = demo / "bspline-panel-dented.json", demo / "bspline-panel-faired.json"
    run(cli, "convert", after, tmp_path / "after.obj")
    run(cli, "deviation", before, tmp_path / "after.obj", "--csv", tmp_path / "d.csv", "--report", tmp_path / "r.json")
    V, F = fairline.read_mesh(tmp_path / "after.obj")
    values, report = fairline.surface_deviation(fairline.read_surfaces(before), V, F)
    same_report(report, cli_report(tmp_path / "r.json"))
    assert report["method"] == "surface-point"
    rows = np.loadtxt(tmp_path / "d.csv", delimiter=",", skiprows=1, usecols=(4, 5))
    exact(values["signed"], rows[:, 0])
    exact(values["distance"], rows[:, 1])
