#!/usr/bin/env python3
"""Measures fairline's CAD exchange against OpenCASCADE and prints the
markdown tables of docs/bench/cad.md.

    FAIRLINE_BIN=target/release/fairline \
      target/occt-venv/bin/python scripts/occt-exchange-table.py [OUTDIR]

Needs the `OCP` module (pip install cadquery-ocp-novtk, pinned in
python/requirements-test.txt). Reading: OCCT writes every part of
python/tests/occt_parts.py to STEP AP214 and IGES 5.3 (faces and B-rep
mode); `fairline info --json --area` reads each. Writing: `fairline
convert` writes STEP and IGES of what it read and of ../shared/data's
surface files; OCCT imports each (in a child process, stopped after
OCCT_TIMEOUT seconds, default 120).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python" / "tests"))
import occt_parts as occt  # noqa: E402

CLI = os.environ.get("FAIRLINE_BIN", str(ROOT / "target" / "release" / "fairline"))
TIMEOUT = float(os.environ.get("OCCT_TIMEOUT", "120"))


def fairline_info(path: Path):
    t0 = time.perf_counter()
    p = subprocess.run([CLI, "info", "--json", "--area", str(path)], capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if p.returncode != 0:
        last = (p.stderr.strip().splitlines() or ["?"])[-1]
        return None, None, dt, f"exit {p.returncode}: {last[:90]}"
    info = json.loads(p.stdout)
    warn = "; ".join(info.get("warnings", []))[:90]
    return info["surfaces"], info["area"], dt, warn


def occt_import(path: Path):
    code = (
        "import sys, json; sys.path.insert(0, %r); import occt_parts as o;"
        "s, t = o.read(%r); print(json.dumps([o.faces(s), o.area(s), t]))"
    ) % (str(ROOT / "python" / "tests"), str(path))
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return None, None, time.perf_counter() - t0, f"no result in {TIMEOUT:.0f} s"
    if p.returncode != 0:
        return None, None, time.perf_counter() - t0, "OCCT failed"
    n, a, t = json.loads(p.stdout.strip().splitlines()[-1])
    return n, a, t, ""


def rel(a, b):
    if a is None or b is None or b == 0:
        return "—"
    return f"{(a - b) / b:+.1e}"


def fmt(x):
    return "—" if x is None else f"{x:.6f}"



def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="occt-table-"))
    out.mkdir(parents=True, exist_ok=True)
    print("## fairline reads what OCCT writes\n")
    print("| file | faces OCCT | faces fairline | area OCCT | closed form | area fairline | rel. error | fairline read s | note |")
    print("|---|---|---|---|---|---|---|---|---|")
    parts = {}
    for name, (_, exact) in occt.PARTS.items():
        shape = occt.build(name)
        n, a_occt = occt.faces(shape), occt.area(shape)
        # the reference: the closed form where there is one, else OCCT's
        a = exact if exact is not None else a_occt
        parts[name] = (n, a)
        occt.write_step(shape, out / f"{name}.step")
        occt.write_iges(shape, out / f"{name}.igs")
        occt.write_iges(shape, out / f"{name}.brep.igs", brep=True)
        for ext in ("step", "igs", "brep.igs"):
            f = out / f"{name}.{ext}"
            fn, fa, dt, note = fairline_info(f)
            print(
                f"| {f.name} | {n} | {fn if fn is not None else '—'} | {a_occt:.6f} | {fmt(exact)} | {fmt(fa)} | {rel(fa, a)} | {dt:.2f} | {note} |"
            )
    print("\n## OCCT reads what fairline writes\n")
    print("| source | written | faces fairline | faces OCCT | reference area | area OCCT | rel. error | OCCT import s | note |")
    print("|---|---|---|---|---|---|---|---|---|")
    sources = [ROOT.parent / "shared" / "data" / "surfaces" / s for s in ("teapot.json", "impeller.igs")]
    sources += [out / f"{n}.step" for n in occt.PARTS]
    for src in sources:
        fn, fa, _, note = fairline_info(src)
        # a generated part: its reference area (closed form or OCCT's of the
        # part it built); a real file: fairline's area of what it read
        ref = parts.get(src.stem, (None, fa))[1]
        if fn is None:
            print(f"| {src.name} | — | — | — | — | — | — | — | fairline cannot read it |")
            continue
        for ext in ("step", "igs"):
            w = out / f"fairline-{src.stem}.{ext}"
            p = subprocess.run([CLI, "convert", str(src), str(w)], capture_output=True, text=True)
            if p.returncode != 0:
                print(f"| {src.name} | {w.name} | {fn} | — | {fa:.6f} | — | — | — | convert exit {p.returncode} |")
                continue
            on, oa, t, note = occt_import(w)
            print(
                f"| {src.name} | .{ext} | {fn} | {on if on is not None else '—'} | {ref:.6f} | {fmt(oa)} | {rel(oa, ref)} | {t:.1f} | {note} |"
            )


if __name__ == "__main__":
    main()
