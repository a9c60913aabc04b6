"""Shared fixtures: the CLI binary built from this checkout, the files
`fairline demo` writes, an independent reader of binary PLY, and report
comparison.

Under CI (CI=true) a missing CLI binary or optional package fails the
tests; elsewhere they are skipped with a loud notice.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def missing(what: str) -> None:
    """Fails under CI, else skips loudly."""
    msg = f"{what} is missing"
    if IN_CI:
        pytest.fail(f"{msg} (CI is set: missing prerequisites fail)")
    print(f"\nSKIPPED: {msg}", file=sys.stderr)
    pytest.skip(msg)


def need(module: str):
    """Imports an optional test dependency (trimesh, igl, scipy)."""
    try:
        return __import__(module)
    except ImportError:
        missing(f"python package {module!r}")


@pytest.fixture(scope="session")
def cli() -> Path:
    exe = Path(os.environ.get("FAIRLINE_BIN", REPO / "target" / "release" / "fairline"))
    if not exe.is_file():
        missing(f"the fairline binary ({exe}; build it with `cargo build --release`)")
    return exe


def run(cli: Path, *args, cwd=None) -> subprocess.CompletedProcess:
    """Runs the CLI; fails the test with its stderr unless it exits 0."""
    p = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=600)
    if p.returncode != 0:
        pytest.fail(f"fairline {' '.join(map(str, args))} exited {p.returncode}:\n{p.stderr}")
    return p


@pytest.fixture(scope="session")
def demo(cli, tmp_path_factory) -> Path:
    """The files `fairline demo` writes."""
    d = tmp_path_factory.mktemp("demo") / "fairline-demo"
    run(cli, "demo", "--out", d)
    return d


def read_ply(path: Path):
    """Binary little-endian PLY with double vertex properties and
    uchar/uint-count int faces, parsed with numpy alone (independent of
    fairline's reader): (property names, (n, k) array, faces list)."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert "format binary_little_endian 1.0" in header
    names, n_vertices, n_faces, element = [], 0, 0, None
    count_type = "uchar"
    for line in header:
        w = line.split()
        if w[:1] == ["element"]:
            element = w[1]
            if element == "vertex":
                n_vertices = int(w[2])
            elif element == "face":
                n_faces = int(w[2])
        elif w[:1] == ["property"] and element == "vertex":
            assert w[1] == "double", line
            names.append(w[2])
        elif w[:2] == ["property", "list"]:
            count_type = w[2]
    k = len(names)
    values = np.frombuffer(data, dtype="<f8", count=n_vertices * k, offset=end).reshape(n_vertices, k)
    pos = end + 8 * n_vertices * k
    faces = []
    for _ in range(n_faces):
        if count_type == "uchar":
            c = data[pos]
            pos += 1
        else:
            c = int.from_bytes(data[pos : pos + 4], "little")
            pos += 4
        faces.append(np.frombuffer(data, dtype="<i4", count=c, offset=pos).astype(np.int64))
        pos += 4 * c
    return names, values, faces


def cli_report(path: Path) -> dict:
    return json.loads(Path(path).read_text())


def same_report(ours: dict, theirs: dict, ignore=("time_s", "timings"), input_path=None) -> None:
    """Every key equal (numbers bit for bit) except computation times (at
    any depth: fair-surface's history has one per iteration).
    Warnings the CLI starts with `INPUT: ` (naming its input file) are
    compared without that prefix: arrays have no file name."""
    def strip(v):
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if k not in ignore}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v

    a, b = strip(ours), strip(theirs)
    if input_path is not None and "warnings" in b:
        prefix = f"{input_path}: "
        b["warnings"] = [w[len(prefix):] if w.startswith(prefix) else w for w in b["warnings"]]
    assert a.keys() == b.keys(), (sorted(a.keys() ^ b.keys()))
    for k in a:
        assert a[k] == b[k], f"report key {k!r}: {a[k]!r} != {b[k]!r}"
