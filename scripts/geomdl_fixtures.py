#!/usr/bin/env python3
"""Writes the geomdl JSON fixtures of crates/fairline/tests/data/geomdl/ and
prints the points geomdl evaluates on them, the reference values of
crates/fairline/tests/geomdl_json.rs.

Needs geomdl 5.3.1 (NURBS-Python, MIT):
    python3 -m venv venv && venv/bin/pip install geomdl==5.3.1
    venv/bin/python scripts/geomdl_fixtures.py

Files:
  cylinder_and_bicubic.json  exchange.export_json of a container of two
      surfaces: a rational quarter cylinder (radius 2, height 3; degrees
      2 x 1) and a non-rational bicubic (6 x 4 control points, an interior
      knot in u) whose sizes differ, so a transposed net cannot pass.
  bicubic.json               exchange.export_json of the bicubic alone.
  trimmed.json               exchange.export_json of three trimmed surfaces
      (see trimmed_plate, trimmed_band and two_islands below); the script
      prints the face areas (closed forms) and, for a grid of parameters,
      whether geomdl's trimmed tessellator keeps the point (its
      tessellate.TrimTessellate rule: default sense 0 trims the enclosed
      area away, sense 1 keeps it; winding numbers of trim.evalpts).
"""

import math
import os
import sys

from geomdl import BSpline, NURBS, exchange, freeform, linalg, multi, trimming

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "crates", "fairline", "tests", "data", "geomdl")

# parameters evaluated in both surfaces' domains ([0, 1]^2 after geomdl
# normalises the knot vectors)
PARAMS = [(0.0, 0.0), (0.3, 0.7), (0.5, 0.5), (0.9, 0.15), (1.0, 1.0), (0.123, 0.987)]


def cylinder():
    s = NURBS.Surface()
    s.degree_u = 2
    s.degree_v = 1
    w = math.sqrt(0.5)
    pts, wts = [], []
    for x, y, wt in [(2.0, 0.0, 1.0), (2.0, 2.0, w), (0.0, 2.0, 1.0)]:
        for z in (0.0, 3.0):
            pts.append([x, y, z])
            wts.append(wt)
    s.set_ctrlpts([p + [1.0] for p in pts], 3, 2)  # placeholder weights
    s.ctrlpts = pts
    s.weights = wts
    s.knotvector_u = [0, 0, 0, 1, 1, 1]
    s.knotvector_v = [0, 0, 1, 1]
    return s


def bicubic():
    s = BSpline.Surface()
    s.degree_u = 3
    s.degree_v = 3
    pts = []
    for i in range(6):
        for j in range(4):
            pts.append([i * 1.5, j * 1.0 + 0.1 * i, math.sin(0.7 * i) * math.cos(0.9 * j) + 0.05 * i * j])
    s.set_ctrlpts(pts, 6, 4)
    s.knotvector_u = [0, 0, 0, 0, 0.25, 0.6, 1, 1, 1, 1]
    s.knotvector_v = [0, 0, 0, 0, 1, 1, 1, 1]
    return s


def plate():
    """The plane z = 0 with S(u, v) = (2u, 3v, 0): areas are 6 x parameter areas."""
    s = BSpline.Surface()
    s.degree_u = 1
    s.degree_v = 1
    s.set_ctrlpts([[0, 0, 0], [0, 3, 0], [2, 0, 0], [2, 3, 0]], 2, 2)
    s.knotvector_u = [0, 0, 1, 1]
    s.knotvector_v = [0, 0, 1, 1]
    return s


def circle(cx, cy, r, sense=None):
    """A rational quadratic full circle in the parameter plane (9 points)."""
    c = NURBS.Curve()
    c.degree = 2
    w = math.sqrt(0.5)
    pts = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0)]
    c.ctrlpts = [[cx + r * x, cy + r * y] for x, y in pts]
    c.weights = [1, w, 1, w, 1, w, 1, w, 1]
    c.knotvector = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    if sense is not None:
        c.opt = ["reversed", sense]
    return c


def segment(a, b):
    c = BSpline.Curve()
    c.degree = 1
    c.ctrlpts = [list(a), list(b)]
    c.knotvector = [0, 0, 1, 1]
    return c


def trimmed_plate():
    """Three holes: a NURBS circle (radius 0.2 about (0.3, 0.5)), a
    container triangle whose middle side runs backwards, and a freeform
    square polyline. Face area 6 (1 - 0.04 pi - 0.03 - 0.01)."""
    s = plate()
    tri = multi.CurveContainer()
    tri.add(segment((0.65, 0.2), (0.85, 0.2)))
    tri.add(segment((0.75, 0.5), (0.85, 0.2)))  # reversed: geomdl's fix would flip it
    tri.add(segment((0.75, 0.5), (0.65, 0.2)))
    square = freeform.Freeform()
    square.evaluate(points=[[0.6, 0.7], [0.7, 0.7], [0.7, 0.8], [0.6, 0.8], [0.6, 0.7]])
    s.trims = [circle(0.3, 0.5, 0.2), tri, square]
    return s, 6.0 * (1.0 - 0.04 * math.pi - 0.03 - 0.01)


def trimmed_band():
    """The rational quarter cylinder kept between v = 0.2 and 0.7 (a kept
    rectangle, sense 1): area (pi/2 x 2) x (3 x 0.5) = 1.5 pi."""
    s = cylinder()
    band = freeform.Freeform()
    band.evaluate(points=[[0, 0.2], [1, 0.2], [1, 0.7], [0, 0.7], [0, 0.2]])
    band.opt = ["reversed", 1]
    s.trims = [band]
    return s, 1.5 * math.pi


def two_islands():
    """The plate kept inside two circles (sense 1; radii 0.2 and 0.15), the
    second with a hole of radius 0.05: two faces, 6 x 0.04 pi and
    6 x (0.0225 - 0.0025) pi."""
    s = plate()
    s.trims = [circle(0.3, 0.3, 0.2, 1), circle(0.7, 0.7, 0.15, 1), circle(0.7, 0.7, 0.05)]
    return s, [6.0 * 0.04 * math.pi, 6.0 * 0.02 * math.pi]


def kept_by_geomdl(s, u, v):
    """Whether geomdl's TrimTessellate keeps the parameter point (u, v):
    its vertex rule in _tessellate.surface_trim_tessellate, unset sense 0."""
    inside = False
    no_trim = trim = False
    for t in s.trims:
        sense = t.opt_get("reversed") or 0
        pts = t.evalpts
        if linalg.wn_poly([u, v], pts):
            if sense:
                if not trim:
                    inside = False
                    no_trim = True
            else:
                inside = True
                trim = True
        elif sense and not no_trim:
            inside = True
    return not inside


def main():
    os.makedirs(OUT, exist_ok=True)
    cyl, bic = cylinder(), bicubic()
    both = multi.SurfaceContainer(cyl, bic)
    exchange.export_json(both, os.path.join(OUT, "cylinder_and_bicubic.json"))
    exchange.export_json(bic, os.path.join(OUT, "bicubic.json"))
    trimmed = [trimmed_plate(), trimmed_band(), two_islands()]
    exchange.export_json(multi.SurfaceContainer(*[t for t, _ in trimmed]), os.path.join(OUT, "trimmed.json"))
    # the classification below: on new copies whose containers geomdl's own
    # fix_multi_trim_curves has joined end to start (its tessellator reads
    # a container's points in the order given), curves evaluated finely
    trimmed = [trimmed_plate(), trimmed_band(), two_islands()]
    for t, _ in trimmed:
        trimming.fix_multi_trim_curves(multi.SurfaceContainer(t), delta=0.0005)
        for c in t.trims:
            if not isinstance(c, (freeform.Freeform, multi.CurveContainer)):
                c.delta = 0.0005
    grid = [(i / 16 + 0.01, j / 16 + 0.013) for i in range(16) for j in range(16)]
    for (t, area), name in zip(trimmed, ("plate", "band", "islands")):
        print(f"// {name}: area {area!r}")
        print("".join("1" if kept_by_geomdl(t, u, v) else "0" for u, v in grid))
    for name, s in (("cylinder", cyl), ("bicubic", bic)):
        print(f"// {name}")
        for u, v in PARAMS:
            p = s.evaluate_single((u, v))
            print(f"(({u!r}, {v!r}), [{p[0]!r}, {p[1]!r}, {p[2]!r}]),")
    return 0


if __name__ == "__main__":
    sys.exit(main())
