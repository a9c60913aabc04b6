"""The computation runs with the GIL released: another Python thread keeps
running while fairline computes (it could not execute a single bytecode
while a native call held the GIL)."""

from __future__ import annotations

import threading
import time

import numpy as np

import fairline
from test_speed import torus


def test_other_threads_run_during_a_computation():
    V, F = torus(300)  # 90 000 vertices
    done = threading.Event()
    result = {}

    def work():
        t = time.perf_counter()
        result["out"] = fairline.smooth(V, F, method="laplace", iterations=300)
        result["seconds"] = time.perf_counter() - t
        done.set()

    ticks = 0
    worker = threading.Thread(target=work)
    worker.start()
    # spin until the worker is inside the native call, then count how often
    # this thread runs Python code while the computation is under way
    time.sleep(0.01)
    while not done.is_set():
        ticks += 1
        time.sleep(0.0005)
    worker.join()
    V2, report = result["out"]
    assert report["iterations"] == 300 and np.isfinite(V2).all()
    # at least one tick per 20 ms of computation (about one per 0.5 ms when
    # the GIL is free, on a loaded machine fewer; none at all while a
    # native call holds it), and the computation must last long enough to
    # tell the two apart
    assert result["seconds"] > 0.1, f"too short to judge: {result['seconds']:.3f} s"
    assert ticks >= max(5, result["seconds"] / 0.02), f"{ticks} ticks in {result['seconds']:.3f} s"
