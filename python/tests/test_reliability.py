"""Every error the package raises is a FairlineError; Ctrl-C stops a long
call within a second; a Schneider–Kobbelt run that does not converge and a
result that is not finite raise, as the CLI exits 1."""

from __future__ import annotations

import signal
import threading
import time

import numpy as np
import pytest

import fairline
from fairline import (
    FairlineComputationError,
    FairlineError,
    FairlineNotConvergedError,
    FairlineTypeError,
)


def grid(n: int, bump: float = 0.0):
    """An n×n vertex grid on [0, 1]², triangulated, with a bump of height
    `bump` in the middle and a little deterministic noise."""
    xs, ys = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    z = bump * np.exp(-((xs - 0.5) ** 2 + (ys - 0.5) ** 2) / 0.02)
    z += 0.002 * np.sin(37.0 * xs * n) * np.cos(23.0 * ys * n)
    V = np.c_[xs.ravel(), ys.ravel(), z.ravel()].astype(np.float64)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    F = np.concatenate([np.c_[a, a + 1, a + n + 1], np.c_[a, a + n + 1, a + n]])
    return V, F


V, F = grid(6)

# A bad argument of every kind, through the functions that take it.
BAD_CALLS = {
    "V of strings": lambda: fairline.smooth(np.array([["a", "b", "c"]] * 36), F),
    "V of objects": lambda: fairline.smooth(np.array([[object()] * 3] * 36), F),
    "V ragged list": lambda: fairline.smooth([[0, 1], [2]], F),
    "V wrong shape": lambda: fairline.enhance(V[:, :2], F),
    "V NaN": lambda: fairline.detect(np.where(V == 1, np.nan, V), F),
    "V inf": lambda: fairline.highlight_lines(V + np.inf, F),
    "V empty": lambda: fairline.smooth(np.zeros((0, 3)), np.zeros((0, 3), int)),
    "F float": lambda: fairline.curvature(V, F.astype(float)),
    "F out of range": lambda: fairline.repair(V, F + 1000),
    "F negative": lambda: fairline.fair_quad(V, F - 100),
    "F empty array": lambda: fairline.highlight_lines(V, np.zeros((0, 3), int)),
    "F empty list": lambda: fairline.detect(V, []),
    "F three-dimensional": lambda: fairline.smooth(V, F[None]),
    "fixed of strings": lambda: fairline.smooth(V, F, fixed=["a"]),
    "fixed out of range": lambda: fairline.smooth(V, F, fixed=[10**6]),
    "region of floats": lambda: fairline.fair(V, F, region=np.array([0.5, 1.5])),
    "region out of range": lambda: fairline.fair(V, F, region=[10**6]),
    "direction NaN": lambda: fairline.highlight_lines(V, F, direction=[np.nan, 0, 1]),
    "spacing not a number": lambda: fairline.highlight_lines(V, F, spacing="x"),
    "radii not numbers": lambda: fairline.highlight_lines(
        V, F, radii=["x"], circle_center=[0, 0, 1], circle_axis=[0, 0, 1]
    ),
    "iterations a float": lambda: fairline.smooth(V, F, iterations=2.5),
    "iterations negative": lambda: fairline.smooth(V, F, iterations=-1),
    "max_work zero": lambda: fairline.smooth(V, F, method="schneider-kobbelt", max_work=0),
    "lambda_ a string": lambda: fairline.smooth(V, F, lambda_="x"),
    "exponent a string": lambda: fairline.smooth(V, F, exponent="x"),
    "enhance iterations a string": lambda: fairline.enhance(V, F, iterations="x"),
    "fair_quad weight a string": lambda: fairline.fair_quad(V, F, weight="x"),
    "detect threshold a string": lambda: fairline.detect(V, F, threshold="x"),
    "detect max_regions negative": lambda: fairline.detect(V, F, max_regions=-1),
    "curvature method a number": lambda: fairline.curvature(V, F, method=3),
    "surfaces not a surface": lambda: fairline.surface_highlight_lines(5),
    "read_mesh of a number": lambda: fairline.read_mesh(5),
    "to_trimesh faces a string": lambda: fairline.to_trimesh(V, "abc"),
    "from_trimesh of a number": lambda: fairline.from_trimesh(5),
    "a keyword that does not exist": lambda: fairline.smooth(V, F, iteration=3),
}


@pytest.mark.parametrize("name", sorted(BAD_CALLS))
def test_every_error_is_a_fairline_error(name):
    with pytest.raises(FairlineError) as info:
        BAD_CALLS[name]()
    assert str(info.value), name


def test_type_errors_stay_type_errors():
    with pytest.raises(FairlineTypeError) as info:
        fairline.smooth(V, F, iterations=2.5)
    assert isinstance(info.value, TypeError)
    assert "iterations must be a whole number" in str(info.value)


def test_a_mesh_without_faces_is_refused_naming_the_count():
    with pytest.raises(FairlineError, match="has no faces, only 36 vertices"):
        fairline.detect(V, np.zeros((0, 3), int))


def test_the_non_manifold_error_says_how_to_repair():
    # three triangles on one edge
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    f = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    with pytest.raises(FairlineError) as info:
        fairline.smooth(v, f)
    text = str(info.value)
    assert "non-manifold" in text, text
    assert "hint: run `V, F, report = fairline.repair(V, F)`" in text, text
    # and the hint is right: the repaired mesh smooths
    v2, f2, _ = fairline.repair(v, f)
    fairline.smooth(v2, f2)


def test_dir_shows_the_public_names_only():
    names = dir(fairline)
    for private in ("np", "json", "os", "warnings", "Any", "Dict", "List", "Optional",
                    "Sequence", "Tuple", "Union", "annotations", "functools"):
        assert private not in names, private
    assert set(fairline.__all__) <= set(names)
    for name in fairline.__all__:
        assert getattr(fairline, name) is not None, name
    assert "smooth" in names and "FairlineError" in names


def test_schneider_kobbelt_not_converging_raises_with_the_reason_and_report():
    v, f = grid(12, bump=0.2)
    with pytest.raises(FairlineNotConvergedError) as info:
        fairline.smooth(v, f, method="schneider-kobbelt", iterations=1, fix_boundary=True)
    e = info.value
    assert isinstance(e, FairlineComputationError)
    assert e.stop_reason == "max_iterations"
    assert e.report["stop_reason"] == "max_iterations"
    assert e.report["converged"] is False
    assert e.V.shape == v.shape and np.isfinite(e.V).all()
    assert str(e).startswith("schneider-kobbelt stopped unconverged (max_iterations) after 1 iteration(s)"), str(e)
    assert "more iterations" in str(e), str(e)
    with pytest.raises(FairlineNotConvergedError) as info:
        fairline.smooth(v, f, method="schneider-kobbelt", max_work=1, fix_boundary=True)
    assert info.value.stop_reason == "work_limit"
    assert "raise max_work" in str(info.value), str(info.value)
    # a run that converges returns as before
    out, report = fairline.smooth(v, f, method="schneider-kobbelt", fix_boundary=True,
                                  iterations=200, epsilon=1e-2)
    assert report["stop_reason"] == "converged", report


def test_an_exploding_result_raises():
    v, f = grid(8, bump=0.2)
    for lam in (1e308, 1e6):
        with pytest.raises(FairlineComputationError, match="diverged"):
            fairline.smooth(v, f, method="laplace", weights="cotan", lambda_=lam)


# ---- Ctrl-C ------------------------------------------------------------------

BIG_V, BIG_F = grid(160, bump=0.2)
_CENTRES = BIG_V[BIG_F].mean(axis=1)
MIDDLE = np.nonzero(np.hypot(_CENTRES[:, 0] - 0.5, _CENTRES[:, 1] - 0.5) < 0.25)[0]

LONG_CALLS = {
    "smooth": lambda: fairline.smooth(BIG_V, BIG_F, method="laplace", iterations=10**8),
    "enhance": lambda: fairline.enhance(BIG_V, BIG_F, iterations=10**6),
    "fair": lambda: [fairline.fair(BIG_V, BIG_F, MIDDLE, max_iterations=10**6, epsilon=1e-300)
                     for _ in range(1000)],
    "detect": lambda: [fairline.detect(BIG_V, BIG_F, spacing=0.001) for _ in range(1000)],
    "highlight_lines": lambda: [fairline.highlight_lines(BIG_V, BIG_F, spacing=0.0005) for _ in range(1000)],
}


@pytest.mark.parametrize("name", sorted(LONG_CALLS))
def test_ctrl_c_stops_a_long_call_within_a_second(name):
    main = threading.main_thread().ident
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        signal.pthread_kill(main, signal.SIGINT)

    timer = threading.Timer(0.5, interrupt)
    started = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            LONG_CALLS[name]()
        caught = time.monotonic()
    finally:
        timer.cancel()
    assert sent, f"{name} finished in {time.monotonic() - started:.2f} s, before the signal"
    assert caught - sent[0] < 1.5, f"{name}: KeyboardInterrupt {caught - sent[0]:.2f} s after SIGINT"
