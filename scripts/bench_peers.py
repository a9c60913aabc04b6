"""fairline against its peers, as users run them: whole processes (the
`fairline` command against a Python script of trimesh, pymeshlab or
libigl doing the same job: read the file, compute, write the result) and
calls in one Python process (``fairline.Mesh`` against ``trimesh`` and
``igl``). Run by scripts/bench-peers, which builds fairline and installs
the peers; prints a Markdown table with the machine, its load and the
date.

    python scripts/bench_peers.py --bin target/release/fairline [--runs 5] [--work DIR]
    python scripts/bench_peers.py peer NAME ARGS...   (one peer script; internal)

Each row alternates the runs of the two sides (ours, theirs, ours, …), so
both see the same load, and reports the median wall seconds of each and
the ratio theirs / ours, and the median CPU seconds of each (user + system
of the child process for whole processes; of this process, all threads, for
calls in process): on a loaded machine wall times measure the other
processes too, CPU seconds much less so.

The mesh is the raw Stanford bunny scan (bunny_zipper.ply) split 4 × 4
(every triangle into four at its edge midpoints, twice) and cut to
449,088 vertices, as the highlight benchmarks make it
(crates/fairline/benches/highlight.rs), written as binary PLY.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TAUBIN_LAMBDA, TAUBIN_NU, TAUBIN_PAIRS = 0.5, 0.53, 10


# ---- the peers' scripts (each run as its own process) --------------------------------


def peer(name: str, args: list) -> None:
    """One peer doing one job on the file ``args[0]``, writing ``args[1]``."""
    src, out = args[0], args[1] if len(args) > 1 else None
    if name == "trimesh-taubin":
        import trimesh

        m = trimesh.load(src, process=False)
        trimesh.smoothing.filter_taubin(m, lamb=TAUBIN_LAMBDA, nu=TAUBIN_NU, iterations=2 * TAUBIN_PAIRS)
        m.export(out)
    elif name == "trimesh-load":
        import trimesh

        m = trimesh.load(src)
        print(len(m.vertices), len(m.faces), m.is_watertight, m.euler_number)
    elif name == "pymeshlab-curvature":
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(src)
        ms.compute_curvature_principal_directions_per_vertex()
        ms.save_current_mesh(out, save_vertex_quality=True)
    elif name == "igl-curvature":
        import igl
        import numpy as np

        V, F = igl.read_triangle_mesh(src)
        d1, d2, k1, k2 = igl.principal_curvature(V, F)[:4]
        np.savez(out, d1=d1, d2=d2, k1=k1, k2=k2)
    else:
        raise SystemExit(f"unknown peer {name}")


# ---- the mesh ----------------------------------------------------------------------------


def split4(V, F, times):
    """Every triangle into four at its edge midpoints, one shared midpoint
    per edge numbered in order of first use (face by face, edges 01 12 20)."""
    import numpy as np

    for _ in range(times):
        n = len(V)
        corners = np.stack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1).reshape(-1, 2)
        key = np.sort(corners, axis=1)
        code = key[:, 0].astype(np.int64) * (n + 1) + key[:, 1]
        uniq, first, inv = np.unique(code, return_index=True, return_inverse=True)
        order = np.argsort(first, kind="stable")
        rank = np.empty(len(uniq), dtype=np.int64)
        rank[order] = np.arange(len(uniq))
        ends = key[first[order]]
        V = np.concatenate([V, 0.5 * (V[ends[:, 0]] + V[ends[:, 1]])])
        e = (n + rank[inv]).reshape(-1, 3)
        t = F
        F = np.stack(
            [
                np.stack([t[:, 0], e[:, 0], e[:, 2]], 1),
                np.stack([t[:, 1], e[:, 1], e[:, 0]], 1),
                np.stack([t[:, 2], e[:, 2], e[:, 1]], 1),
                e,
            ],
            1,
        ).reshape(-1, 3)
    return V, F


def cut_to(V, F, target):
    """The part below a plane across the longest bounding-box axis with
    about ``target`` vertices, vertex and face order kept."""
    import numpy as np

    axis = int(np.argmax(V.max(0) - V.min(0)))
    k = min(target, len(V) - 1)
    cut = np.partition(V[:, axis], k)[k]
    keep = V[:, axis] < cut
    F = F[keep[F].all(1)]
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    idx = np.full(len(V), -1, np.int64)
    idx[used] = np.arange(used.sum())
    return V[used], idx[F]


def bunny(work: Path) -> Path:
    import fairline
    import numpy as np

    path = work / "bunny-split-450k.ply"
    if not path.exists():
        src = REPO.parent / "shared" / "data" / "meshes" / "bunny_zipper.ply"
        if not src.exists():
            raise SystemExit(f"bench-peers: {src} is missing (the raw bunny scan)")
        V, F = fairline.read_mesh(src)
        V, F = cut_to(*split4(V, np.asarray(F, dtype=np.int64), 2), 450_000)
        fairline.write_mesh(path, V, F)
    return path


# ---- measuring ---------------------------------------------------------------------------


def process(cmd: list) -> tuple:
    """Wall and CPU seconds (user + system) of one process; it must succeed."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f"bench-peers: {' '.join(map(str, cmd))} exited {p.returncode}:\n{p.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def alternate(ours, theirs, runs: int) -> tuple:
    """Median results of ``runs`` alternating calls of the two sides."""
    a, b = [], []
    ours()  # one warm-up each (page cache, imports on disk)
    theirs()
    for _ in range(runs):
        a.append(ours())
        b.append(theirs())
    return a, b


def med(values, k=0):
    return statistics.median(v[k] if isinstance(v, tuple) else v for v in values)


def timed(f):
    """``f`` as a measurement: wall and CPU seconds (this process, all threads)."""

    def run():
        c = time.process_time()
        t = time.perf_counter()
        f()
        return time.perf_counter() - t, time.process_time() - c

    return run


def load() -> str:
    return " ".join(f"{x:.1f}" for x in os.getloadavg())


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True, help="the fairline binary")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--work", default=str(REPO / "target" / "bench-peers"))
    ap.add_argument("--only", default="", help="comma-separated row groups: process,python")
    a = ap.parse_args()
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    mesh = bunny(work)
    fl = str(Path(a.bin).resolve())
    py = sys.executable
    me = str(Path(__file__).resolve())
    groups = set(a.only.split(",")) if a.only else {"process", "python"}
    import fairline

    counts = fairline.Mesh.read(mesh)
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    load_before = load()
    rows = []

    def row(what, ours_name, theirs_name, ours, theirs):
        ra, rb = alternate(ours, theirs, a.runs)
        wa, wb = med(ra), med(rb)
        cells = [what, ours_name, f"{wa:.3f}", theirs_name, f"{wb:.3f}", f"{wb / wa:.1f}×" if wa > 0 else "–"]
        cells.append(f"{med(ra, 1):.2f} / {med(rb, 1):.2f}")
        rows.append(cells)
        print("  " + " | ".join(cells), file=sys.stderr, flush=True)

    if "process" in groups:
        out = work / "out"
        out.mkdir(exist_ok=True)
        row(
            f"Taubin {TAUBIN_PAIRS} pairs, read + write PLY",
            "`fairline smooth`",
            "trimesh script",
            lambda: process([fl, "smooth", mesh, "--method", "taubin", "--lambda", str(TAUBIN_LAMBDA),
                             "--mu", str(-TAUBIN_NU), "--iterations", str(TAUBIN_PAIRS), "-o", out / "s.ply"]),
            lambda: process([py, me, "peer", "trimesh-taubin", mesh, out / "t.ply"]),
        )
        row(
            "principal curvature, read + write",
            "`fairline curvature`",
            "pymeshlab script",
            lambda: process([fl, "curvature", mesh, "-o", out / "c.ply"]),
            lambda: process([py, me, "peer", "pymeshlab-curvature", mesh, out / "m.ply"]),
        )
        row(
            "principal curvature, read + write",
            "`fairline curvature`",
            "libigl script",
            lambda: process([fl, "curvature", mesh, "-o", out / "c.ply"]),
            lambda: process([py, me, "peer", "igl-curvature", mesh, out / "i.npz"]),
        )
        row(
            "read and describe the mesh",
            "`fairline info`",
            "trimesh load",
            lambda: process([fl, "info", mesh]),
            lambda: process([py, me, "peer", "trimesh-load", mesh]),
        )

    if "python" in groups:
        import igl
        import numpy as np
        import trimesh

        V, F = fairline.read_mesh(mesh)
        F = np.asarray(F, dtype=np.int64)
        m = fairline.Mesh(V, F)
        tm = trimesh.Trimesh(V.copy(), F, process=False)

        def trimesh_taubin():
            t = trimesh.Trimesh(V.copy(), F, process=False)
            trimesh.smoothing.filter_taubin(t, lamb=TAUBIN_LAMBDA, nu=TAUBIN_NU, iterations=2 * TAUBIN_PAIRS)

        taubin = dict(method="taubin", lambda_=TAUBIN_LAMBDA, mu=-TAUBIN_NU, iterations=TAUBIN_PAIRS)
        row("Taubin 10 pairs from (V, F)", "`Mesh(V, F).smooth()`", "trimesh filter_taubin",
            timed(lambda: fairline.Mesh(V, F).smooth(**taubin)), timed(trimesh_taubin))
        row("Taubin 10 pairs on a built mesh", "`mesh.smooth()`", "trimesh filter_taubin",
            timed(lambda: m.smooth(**taubin)), timed(trimesh_taubin))
        row("principal curvature from (V, F)", "`Mesh(V, F).principal_curvatures()`", "igl.principal_curvature",
            timed(lambda: fairline.Mesh(V, F).principal_curvatures()), timed(lambda: igl.principal_curvature(V, F)),
            )
        row("principal curvature on a built mesh", "`mesh.principal_curvatures()`", "igl.principal_curvature",
            timed(m.principal_curvatures), timed(lambda: igl.principal_curvature(V, F)))
        row("cotangent Laplacian", "`mesh.cotangent_laplacian()`", "igl.cotmatrix",
            timed(m.cotangent_laplacian), timed(lambda: igl.cotmatrix(V, F)))
        row("mass matrix (Voronoi)", "`mesh.mass_matrix()`", "igl.massmatrix",
            timed(m.mass_matrix), timed(lambda: igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)))
        row("vertex normals (area-weighted)", "`mesh.vertex_normals()`", "igl.per_vertex_normals",
            timed(m.vertex_normals),
            timed(lambda: igl.per_vertex_normals(V, F, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)))
        row("vertex normals (area-weighted)", "`mesh.vertex_normals()`", "trimesh vertex_normals",
            timed(m.vertex_normals),
            timed(lambda: trimesh.Trimesh(V, F, process=False).vertex_normals))
        row("highlight lines, default lights", "`mesh.highlight_lines()` (arrays)",
            "`fairline.highlight_lines(V, F)` (dicts)",
            timed(m.highlight_lines), timed(lambda: fairline.highlight_lines(V, F)))
        del tm

    print(f"\nMachine: {os.cpu_count()} cores ({cpu_model()}), {platform.system()} {platform.release()}; "
          f"measured {started}; load average (1, 5, 15 min) {load_before} before, {load()} after; "
          f"{a.runs} alternating runs per row after one warm-up each, medians. Mesh: {mesh.name}, "
          f"{counts.vertex_count:,} vertices, {counts.face_count:,} triangles (binary PLY, "
          f"{mesh.stat().st_size / 2**20:.1f} MiB).\n")
    print("| task | fairline | wall s | peer | wall s | peer / fairline | CPU s (fairline / peer) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "peer":
        peer(sys.argv[2], sys.argv[3:])
    else:
        main()
