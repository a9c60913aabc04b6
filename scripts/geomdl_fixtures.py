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
"""

import math
import os
import sys

from geomdl import BSpline, NURBS, exchange, multi

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


def main():
    os.makedirs(OUT, exist_ok=True)
    cyl, bic = cylinder(), bicubic()
    both = multi.SurfaceContainer(cyl, bic)
    exchange.export_json(both, os.path.join(OUT, "cylinder_and_bicubic.json"))
    exchange.export_json(bic, os.path.join(OUT, "bicubic.json"))
    for name, s in (("cylinder", cyl), ("bicubic", bic)):
        print(f"// {name}")
        for u, v in PARAMS:
            p = s.evaluate_single((u, v))
            print(f"(({u!r}, {v!r}), [{p[0]!r}, {p[1]!r}, {p[2]!r}]),")
    return 0


if __name__ == "__main__":
    sys.exit(main())
