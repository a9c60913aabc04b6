"""``fairline.inspect``: the command ``fairline inspect`` over many parts,
on the local cores or on a Dask cluster.

The work of each part is done by the ``fairline`` command-line binary (the
same program the CLI runs, so a part gives the same bytes wherever it
runs); this module plans the parts with it, hands each part to a Dask
worker when a ``dask.distributed.Client`` is given, collects each part's
folder as it completes and has the binary write the report from them.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

from ._errors import FairlineComputationError, FairlineError, FairlineFileError

PathLike = Union[str, "os.PathLike[str]"]


def _binary(fairline_bin: Optional[PathLike]) -> str:
    """The ``fairline`` binary: the argument, ``$FAIRLINE_BIN`` or the one
    on ``PATH``."""
    exe = fairline_bin or os.environ.get("FAIRLINE_BIN") or shutil.which("fairline")
    if not exe or not Path(exe).is_file():
        raise FairlineError(
            "fairline.inspect needs the fairline command-line binary: install it with "
            "`cargo install --path crates/fairline-cli` (or pass fairline_bin=..., or set FAIRLINE_BIN)"
        )
    return str(exe)


def _raise_for(p: subprocess.CompletedProcess, what: str) -> None:
    """Raises the error class of the binary's exit status (2: bad input)."""
    if p.returncode == 0:
        return
    lines = [l for l in p.stderr.splitlines() if l.startswith(("error:", "hint:"))]
    msg = "; ".join(l.split(":", 1)[1].strip() for l in lines) or p.stderr.strip() or what
    if p.returncode == 2:
        raise FairlineFileError(msg) if "No such file" in msg else FairlineError(msg)
    raise FairlineComputationError(msg)


def _run_part(exe: str, planned: str, cwd: str, timeout: float, memory: int) -> Dict[str, bytes]:
    """One part's job in a fresh temporary folder (on whichever machine
    runs it); returns its files by name."""
    with tempfile.TemporaryDirectory(prefix="fairline-part-") as tmp:
        folder = os.path.join(tmp, "part")
        args = [exe, "inspect", "--run-part", planned, "--part-dir", folder,
                "--part-timeout", repr(float(timeout)), "--part-memory", str(int(memory))]
        p = subprocess.run(args, capture_output=True, text=True, cwd=cwd)
        if p.returncode != 0:
            raise FairlineComputationError(
                f"fairline inspect --run-part exited {p.returncode}: {p.stderr.strip()}"
            )
        files = {}
        for name in sorted(os.listdir(folder)):
            with open(os.path.join(folder, name), "rb") as f:
                files[name] = f.read()
        return files


def _put_in_place(parts_dir: Path, part_id: str, files: Dict[str, bytes]) -> None:
    """Writes a part's files into a hidden folder, then renames it into
    place (an old result is replaced whole)."""
    tmp = parts_dir / f".{part_id}.{os.getpid()}.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    for name, data in files.items():
        if "/" in name or name.startswith("."):
            raise FairlineComputationError(f"unexpected file name {name!r} from a worker")
        (tmp / name).write_bytes(data)
    dest = parts_dir / part_id
    shutil.rmtree(dest, ignore_errors=True)
    tmp.rename(dest)


def inspect(
    paths: Sequence[PathLike],
    out: PathLike,
    *,
    manifest: Sequence[PathLike] = (),
    client: Any = None,
    jobs: Optional[int] = None,
    part_timeout: float = 600.0,
    part_memory: int = 8192,
    force: bool = False,
    fairline_bin: Optional[PathLike] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Dict[str, Any]:
    """Judges many parts and writes the report folder ``out`` — the
    command ``fairline inspect PATHS -o OUT`` (see its ``--help``):
    ``index.html``, ``summary.json``, ``summary.csv`` and ``parts/ID/``.

    ``paths`` are part files and folders (searched recursively); a
    ``manifest`` (CSV or JSON) lists parts with their own settings. Without
    ``client`` the parts run on the local cores (``jobs`` at a time); with a
    ``dask.distributed.Client`` each part is a task on the cluster (the
    workers need the ``fairline`` binary at the same path or on ``PATH``, and
    the part files at the same paths), and its files stream back into
    ``out`` as it completes. Either way the report is the same bytes.
    Parts unchanged since an earlier run into ``out`` are not redone
    (``force=True`` redoes them). ``progress(done, total)`` is called as
    parts complete on the cluster.

    Returns the summary (``summary.json`` as a dict). Parts that could not
    be judged do not raise: their rows say why (``summary["totals"]
    ["failed"]``); bad arguments raise :class:`FairlineError`.

    Example::

        from dask.distributed import Client
        summary = fairline.inspect(["parts/"], "report", client=Client("tcp://scheduler:8786"))
        print(summary["totals"])
    """
    exe = _binary(fairline_bin)
    out = Path(out)
    args: List[str] = [exe, "inspect", *map(str, paths)]
    for m in manifest:
        args += ["--manifest", str(m)]
    args += ["-o", str(out), "--part-timeout", repr(float(part_timeout)),
             "--part-memory", str(int(part_memory))]
    if force:
        args.append("--force")
    if client is None:
        if jobs is not None:
            args += ["--jobs", str(int(jobs))]
        p = subprocess.run(args, capture_output=True, text=True)
        if p.returncode not in (0, 1) or not (out / "summary.json").is_file():
            _raise_for(p, "fairline inspect failed")
        return json.loads((out / "summary.json").read_text())
    p = subprocess.run(args + ["--plan"], capture_output=True, text=True)
    _raise_for(p, "fairline inspect --plan failed")
    planned = json.loads(p.stdout)
    todo = [entry for entry in planned if not entry["up_to_date"]]
    parts_dir = out / "parts"
    parts_dir.mkdir(parents=True, exist_ok=True)
    cwd = os.getcwd()
    from dask.distributed import as_completed

    futures = {
        client.submit(_run_part, exe, json.dumps(entry), cwd, part_timeout, part_memory,
                      key=f"fairline-part-{entry['id']}-{entry['key'][:16]}", pure=False): entry
        for entry in todo
    }
    done = 0
    for future in as_completed(list(futures)):
        entry = futures[future]
        _put_in_place(parts_dir, entry["id"], future.result())
        done += 1
        if progress is not None:
            progress(done, len(todo))
    p = subprocess.run(args + ["--assemble"], capture_output=True, text=True)
    if p.returncode not in (0, 1) or not (out / "summary.json").is_file():
        _raise_for(p, "fairline inspect --assemble failed")
    return json.loads((out / "summary.json").read_text())
