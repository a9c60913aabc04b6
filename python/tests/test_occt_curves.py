"""Highlight lines as curves, read by an independent kernel: `fairline
highlight -o LINES.igs` writes each line as a B-spline curve (IGES entity
126) within --curve-tolerance; OpenCASCADE must read every curve, and every
point of every line must lie within the tolerance of its curve (OCCT's own
point-to-curve projection).
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from conftest import missing

try:
    from OCP.BRep import BRep_Tool
    from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
    from OCP.gp import gp_Pnt
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Reader
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS
except ImportError:  # pragma: no cover - reported per test
    IGESControl_Reader = None


def occt_curves(path: Path) -> list:
    """The 3-D curves of the edges OCCT builds from an IGES file, in order."""
    if IGESControl_Reader is None:
        missing("python package 'OCP' (cadquery-ocp-novtk, OpenCASCADE)")
    r = IGESControl_Reader()
    assert r.ReadFile(str(path)) == IFSelect_RetDone, f"OCCT cannot read {path}"
    r.TransferRoots()
    ex = TopExp_Explorer(r.OneShape(), TopAbs_EDGE)
    out = []
    while ex.More():
        out.append(BRep_Tool.Curve_s(TopoDS.Edge_s(ex.Current()), 0.0, 1.0))
        ex.Next()
    return out


def distance(curve, p) -> float:
    q = gp_Pnt(*p)
    proj = GeomAPI_ProjectPointOnCurve(q, curve)
    ends = min(curve.Value(curve.FirstParameter()).Distance(q), curve.Value(curve.LastParameter()).Distance(q))
    return min(proj.LowerDistance(), ends) if proj.NbPoints() > 0 else ends


def highlight(cli: Path, src: Path, out: Path, *extra) -> dict:
    report = out.with_suffix(".report.json")
    p = subprocess.run(
        [str(cli), "highlight", str(src), "-o", str(out), "--report", str(report), *extra],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    return json.loads(report.read_text())


@pytest.mark.parametrize(
    "name,extra",
    [("bspline-panel-dented.json", []), ("dented-panel.obj", ["--curve-tolerance", "0.002"])],
)
def test_occt_reads_highlight_lines_as_curves_within_the_tolerance(cli, demo, tmp_path, name, extra):
    src = demo / name
    curves_report = highlight(cli, src, tmp_path / "lines.igs", *extra)["curves"]
    highlight(cli, src, tmp_path / "lines.json")
    doc = json.loads((tmp_path / "lines.json").read_text())
    lines = [l for l in doc["lines"] if l.get("level", 0) == 0]
    tol = curves_report["tolerance"]
    assert curves_report["curves"] == len(lines)
    assert curves_report["polylines"] == 0, "every line of these parts is a cubic"
    # far fewer control points than line points: curves, not copies
    assert curves_report["control_points"] < 0.2 * curves_report["points"]
    assert curves_report["max_deviation"] <= tol
    curves = occt_curves(tmp_path / "lines.igs")
    assert len(curves) == len(lines), f"OCCT built {len(curves)} edges of {len(lines)} curves"
    worst = 0.0
    for line, curve in zip(lines, curves):
        assert curve.Degree() == 3
        for p in line["points"]:
            worst = max(worst, distance(curve, p))
    # OCCT's projection measures the distance to the curve, the fit the
    # distance at the point's own parameter: the first is never larger
    assert worst <= tol, f"a line point is {worst} from its curve (tolerance {tol})"


def occt_face_surfaces(path: Path) -> list:
    """The surfaces of the faces OCCT builds from an IGES file, in order."""
    if IGESControl_Reader is None:
        missing("python package 'OCP' (cadquery-ocp-novtk, OpenCASCADE)")
    from OCP.TopAbs import TopAbs_FACE

    r = IGESControl_Reader()
    assert r.ReadFile(str(path)) == IFSelect_RetDone, f"OCCT cannot read {path}"
    r.TransferRoots()
    ex = TopExp_Explorer(r.OneShape(), TopAbs_FACE)
    out = []
    while ex.More():
        out.append(BRep_Tool.Surface_s(TopoDS.Face_s(ex.Current())))
        ex.Next()
    return out


def test_exact_surface_deviation_agrees_with_occt_projection(cli, demo, tmp_path):
    """`fairline deviation BEFORE.json AFTER.json` measures against the
    B-spline surfaces themselves: every distance equals OCCT's own point
    projection onto the same surface (read back from fairline's IGES) to
    1e-9 of the part's size."""
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf

    before, after = demo / "bspline-panel-dented.json", demo / "bspline-panel-faired.json"
    subprocess.run([str(cli), "convert", str(before), str(tmp_path / "before.igs")], check=True, capture_output=True)
    p = subprocess.run(
        [str(cli), "deviation", str(before), str(after),
         "--csv", str(tmp_path / "exact.csv"), "--report", str(tmp_path / "exact.json")],
        capture_output=True, text=True, timeout=300,
    )
    assert p.returncode == 0, p.stderr
    report = json.loads((tmp_path / "exact.json").read_text())
    assert report["method"] == "surface-point"
    assert report["unrefined"] == 0 and report["unmatched"] == 0
    (surface,) = occt_face_surfaces(tmp_path / "before.igs")
    rows = [line.split(",") for line in (tmp_path / "exact.csv").read_text().splitlines()[1:]]
    size = 4.0
    worst = 0.0
    moved = 0
    for row in rows[:: max(1, len(rows) // 400)]:
        x, y, z, distance = (float(v) for v in row[1:4] + row[5:6])
        proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(x, y, z), surface)
        assert proj.NbPoints() > 0
        worst = max(worst, abs(proj.LowerDistance() - distance))
        moved += distance > 1e-6
    assert moved > 10, "the faired panel moved somewhere"
    assert worst <= 1e-9 * size, f"fairline vs OCCT projection: {worst}"
