"""Bad input raises FairlineError (a ValueError) with a message naming the
problem — the CLI's message where the CLI has one — and never crashes."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import fairline
from fairline import FairlineComputationError, FairlineError, FairlineFileError

TRI_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.2]], dtype=np.float64)
TRI_F = np.array([[0, 1, 2], [1, 3, 2]])


def test_error_classes():
    assert issubclass(FairlineError, ValueError)
    assert issubclass(FairlineFileError, FairlineError) and issubclass(FairlineFileError, OSError)
    assert issubclass(FairlineComputationError, FairlineError) and issubclass(FairlineComputationError, RuntimeError)


@pytest.mark.parametrize(
    "V,match",
    [
        (np.zeros((4, 2)), r"V must have shape \(n, 3\), got \(4, 2\)"),
        (np.zeros(12), r"V must have shape \(n, 3\)"),
        (np.zeros((4, 3), dtype=complex), "V must hold real numbers, got dtype complex128"),
        (np.array([["a", "b", "c"]] * 4), "V must hold real numbers"),
        (np.zeros((4, 3), dtype=bool), "V must hold real numbers, got dtype bool"),
    ],
)
def test_bad_vertex_arrays(V, match):
    with pytest.raises(FairlineError, match=match):
        fairline.smooth(V, TRI_F)


@pytest.mark.parametrize(
    "F,match",
    [
        (np.array([[0, 1, 2], [1, 3, 9]]), "face 1 refers to vertex 9, but the mesh has 4 vertices"),
        (np.array([[0, 1, 2], [1, -3, 2]]), "face 1 refers to vertex -3, but vertex indices start at 0"),
        (np.array([[0, 1, 2], [1, 2**40, 2]]), f"face 1 refers to vertex {2**40}, but the mesh has 4 vertices"),
        (np.array([[0.0, 1, 2], [1, 3, 2]]), "F must hold integers, got dtype float64"),
        (np.array([0, 1, 2]), r"F must have shape \(m, 3\) or \(m, 4\)"),
        (np.array([[0, 1], [1, 3]]), "face 0 has 2 vertices; a face needs at least 3"),
        (np.array([[0, 1, 1], [1, 3, 2]]), "face 0 uses vertex 1 more than once"),
        ([[0, 1, 2], [1, 3]], "face 1 has 2 vertices; a face needs at least 3"),
        (5, "F must be an integer array or a list of faces"),
    ],
)
def test_bad_face_arrays(F, match):
    with pytest.raises(FairlineError, match=match):
        fairline.curvature(TRI_V, F)


def test_nan_and_inf_coordinates_name_the_vertex():
    for bad in (np.nan, np.inf):
        V = TRI_V.copy()
        V[2, 1] = bad
        with pytest.raises(FairlineError, match="vertex 2 has a coordinate that is NaN or infinite"):
            fairline.smooth(V, TRI_F)
        with pytest.raises(FairlineError, match="vertex 2"):
            fairline.write_mesh("never-written.obj", V, TRI_F)


def test_non_manifold_edge_is_named():
    V = np.vstack([TRI_V, [[0.5, 0.5, 1.0]]])
    F = np.array([[0, 1, 2], [1, 3, 2], [2, 1, 4]])
    with pytest.raises(FairlineError, match=r"edge \(1, 2\) is non-manifold"):
        fairline.curvature(V, F)
    # repair accepts what the algorithms refuse
    V2, F2, report = fairline.repair(V, F)
    assert report["split_edges"]


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: fairline.smooth(TRI_V, TRI_F, method="gauss"), r'method must be one of laplace, taubin, implicit, spring, schneider-kobbelt; got "gauss"'),
        (lambda: fairline.smooth(TRI_V, TRI_F, weights="heavy"), "weights must be one of uniform, edge, cotan"),
        (lambda: fairline.smooth(TRI_V, TRI_F, lambda_=float("nan")), "lambda_ must be finite"),
        (lambda: fairline.smooth(TRI_V, TRI_F, iterations=0), "iterations must be at least 1"),
        (lambda: fairline.smooth(TRI_V, TRI_F, fixed=[0, 4]), r"fixed\[1\] = 4 is not a vertex \(the mesh has 4\)"),
        (lambda: fairline.smooth(TRI_V, TRI_F, fixed=[-1]), r"fixed\[0\] = -1 is not a vertex"),
        (lambda: fairline.enhance(TRI_V, TRI_F, fixed=[7]), "fixed vertex 7 does not exist; the mesh has 4 vertices"),
        (lambda: fairline.enhance(TRI_V, TRI_F, solver="magic"), "solver must be one of auto, direct, cg, amg"),
        (lambda: fairline.enhance(TRI_V, [[0, 1, 3, 2]]), "enhance needs a triangle mesh"),
        (lambda: fairline.fair_quad(TRI_V, TRI_F), "fair-quad needs a quad mesh"),
        (lambda: fairline.fair_quad(TRI_V, [[0, 1, 3, 2]], weight=0), "weight must be a positive number"),
        (lambda: fairline.curvature(TRI_V, TRI_F, method="gauss"), "method must be one of rusinkiewicz, meyer"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, up="w"), "up must be one of auto, x, y, z"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, direction=[0, 0]), "direction must be three numbers"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, direction=[0, 0, float("nan")]), "direction must be three finite numbers"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, direction=[0, 0, 1], plane_normal=[0, 0, 1]), "light direction is parallel to the plane normal"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, spacing=-1.0), "spacing must be a positive finite number"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, band=0), "band must be a positive number"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, radii=[1.0]), "circular lights need circle_center, circle_axis and radii together"),
        (lambda: fairline.highlight_lines(TRI_V, TRI_F, lights={"plane_point": [0, 0, 1]}), "lights: missing field"),
        (lambda: fairline.detect(TRI_V, TRI_F, lights={"center": [0, 0, 1], "axis": [0, 0, 1], "radii": [1]}), "circular lights are drawn by `highlight_lines` only"),
        (lambda: fairline.fair(TRI_V, TRI_F), "give a region, or auto=True"),
        (lambda: fairline.fair(TRI_V, TRI_F, [0], auto=True), "region and auto=True cannot be given together"),
        (lambda: fairline.fair(TRI_V, TRI_F, {"faces": [5]}), "region: "),
        (lambda: fairline.fair(TRI_V, TRI_F, [0], method="newton"), "method must be one of highlight, paper, diffusion-flow"),
        (lambda: fairline.surface_highlight_lines({"degree_u": 3}), "surfaces: "),
        (lambda: fairline.fair_surface([], {"center": [0, 0, 0], "axis": [0, 0, 1], "radii": [1]}, {"endpoints": []}), "surface 0 is out of range"),
    ],
)
def test_bad_options_are_named(call, match):
    with pytest.raises(FairlineError, match=match):
        call()


def test_bad_files_name_file_and_line(tmp_path):
    p = tmp_path / "bad.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1\nf 1 2 3\n")
    with pytest.raises(FairlineError, match=r"bad\.obj:3: vertex 2"):
        fairline.read_mesh(p)
    with pytest.raises(FairlineError, match=r"unknown mesh format \(expected extension \.obj, \.ply, \.off or \.stl\)"):
        fairline.read_mesh(tmp_path / "mesh.xyz")
    with pytest.raises(FairlineFileError, match="missing.ply") as e:
        fairline.read_mesh(tmp_path / "missing.ply")
    assert isinstance(e.value, OSError)
    with pytest.raises(FairlineFileError):
        fairline.read_surfaces(tmp_path / "missing.json")
    (tmp_path / "s.json").write_text('{"surfaces": [{"degree_u": 3}]}')
    with pytest.raises(FairlineError, match=r"s\.json"):
        fairline.read_surfaces(tmp_path / "s.json")
    with pytest.raises(FairlineError, match=r"surfaces are written as \.json, \.igs/\.iges or \.step/\.stp"):
        fairline.write_surfaces(tmp_path / "s.obj", [])
    with pytest.raises(FairlineFileError):
        fairline.write_mesh(tmp_path / "no-such-dir" / "m.obj", TRI_V, TRI_F)


def test_same_messages_as_the_cli(cli, tmp_path):
    """The message after the CLI's `error: ` is the exception's text."""
    p = tmp_path / "bad.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    c = subprocess.run([str(cli), "convert", str(p), str(tmp_path / "o.ply")], capture_output=True, text=True)
    assert c.returncode == 2
    cli_message = [l for l in c.stderr.splitlines() if l.startswith("error: ")][0][len("error: "):]
    with pytest.raises(FairlineError) as e:
        fairline.read_mesh(p)
    assert str(e.value) == cli_message


def test_no_array_input_crashes():
    """Odd but legal inputs give results or FairlineError, never a crash."""
    empty_v = np.zeros((0, 3))
    empty_f = np.zeros((0, 3), dtype=np.int64)
    for call in (
        lambda: fairline.smooth(empty_v, empty_f),
        lambda: fairline.curvature(empty_v, empty_f),
        lambda: fairline.highlight_lines(empty_v, empty_f),
        lambda: fairline.detect(empty_v, empty_f),
        lambda: fairline.enhance(empty_v, empty_f),
        lambda: fairline.repair(empty_v, empty_f),
        lambda: fairline.smooth(TRI_V[:, :], [[0, 1, 2]] * 3),
        lambda: fairline.smooth(np.asfortranarray(TRI_V), TRI_F),
        lambda: fairline.smooth(TRI_V[::1].astype(np.float32), TRI_F.astype(np.uint8)),
    ):
        try:
            call()
        except FairlineError:
            pass


def test_a_cad_file_with_no_readable_face_is_refused_naming_it(tmp_path):
    f = tmp_path / "offset.stp"
    f.write_text(
        "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT('',(0.,0.,0.));\n"
        "#2=DIRECTION('',(0.,0.,1.));\n#3=AXIS2_PLACEMENT_3D('',#1,#2,$);\n"
        "#4=DEGENERATE_TOROIDAL_SURFACE('',#3,1.,2.,.T.);\n#5=OFFSET_SURFACE('',#4,1.,.F.);\n#6=ADVANCED_FACE('',(),#5,.T.);\n"
        "ENDSEC;\nEND-ISO-10303-21;\n"
    )
    for skip in (False, True):
        with pytest.raises(fairline.FairlineError, match="no face could be read.*OFFSET_SURFACE"):
            fairline.read_surfaces(f, skip_unreadable=skip)
