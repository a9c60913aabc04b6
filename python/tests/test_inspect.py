"""fairline.inspect: the same report, byte for byte, on the local cores and
on a real two-worker Dask LocalCluster; parts stream back as they complete.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import fairline
from conftest import REPO, missing, need

DATA = REPO.parent / "shared" / "data"


def _files(folder: Path) -> dict:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and not any(part.startswith(".") for part in p.relative_to(folder).parts)
    }


@pytest.fixture
def parts(tmp_path, cli, monkeypatch) -> Path:
    monkeypatch.setenv("FAIRLINE_BIN", str(cli))
    monkeypatch.chdir(tmp_path)
    folder = tmp_path / "parts"
    folder.mkdir()
    for name in ("bob_small.ply", "bunny_res4.ply", "bunny_npm.obj"):
        src = DATA / "meshes" / name
        if not src.is_file():
            missing(f"shared data {src}")
        shutil.copy(src, folder / name)
    (folder / "broken.off").write_text("OFF\n3 1 0\n0 0 0\n")
    return folder


def test_dask_local_cluster_gives_the_local_report_byte_for_byte(parts):
    need("dask")
    distributed = need("distributed")
    local = fairline.inspect(["parts"], "local", jobs=2)
    assert local["totals"]["parts"] == 4
    assert local["totals"]["failed"] == 1
    assert local["parts"][0]["status"] == "error"
    assert "broken.off" in local["parts"][0]["path"]
    seen = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        remote = fairline.inspect(["parts"], "cluster", client=client,
                                  progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (4, 4)
    assert remote == local
    a, b = _files(Path("local")), _files(Path("cluster"))
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name] == b[name], f"{name} differs between the local run and the cluster"


def test_inspect_errors_and_rerun(parts):
    with pytest.raises(fairline.FairlineError):
        fairline.inspect(["parts/nothing.xyz"], "r")
    first = fairline.inspect(["parts/bob_small.ply"], "r")
    assert first["totals"] == {"parts": 1, "with_regions": first["totals"]["with_regions"],
                               "mostly_not_judged": first["totals"]["mostly_not_judged"],
                               "failed": 0, "warnings": first["totals"]["warnings"]}
    stamp = next(Path("r/parts").glob("*/part.json")).stat().st_mtime_ns
    again = fairline.inspect(["parts/bob_small.ply"], "r")
    assert again == first
    assert next(Path("r/parts").glob("*/part.json")).stat().st_mtime_ns == stamp
