"""fairline: highlight lines, fairing, smoothing and feature enhancement of
surfaces, with numpy arrays in and out.

Every function mirrors a command of the ``fairline`` command-line tool with
its option names in snake_case (``--pass-band`` → ``pass_band``;
``--lambda`` → ``lambda_``, since ``lambda`` is a Python keyword) and the
CLI's defaults. Meshes are ``V``, an (n, 3) float64 array of positions, and
``F``, an (m, 3) or (m, 4) integer array of faces or a list of faces for
meshes with mixed polygons; a ``trimesh.Trimesh`` may be passed as ``V``
(with ``F`` left out). Algorithms return their result and a report ``dict``
with the keys of the CLI's ``--report`` JSON (``"command"``, ``"time_s"``,
…); report warnings are also issued as :class:`FairlineWarning`.

:class:`Mesh` builds a mesh's connectivity once and keeps it for repeated
calls, with the operators of libigl and trimesh (vertex normals, principal
curvatures, the cotangent Laplacian and mass matrix as scipy.sparse
matrices, smoothing, highlight lines as flat arrays); every function takes
a :class:`Mesh` in place of ``(V, F)``.

Errors raise :class:`FairlineError` (a :class:`ValueError`) with the CLI's
message; see :mod:`fairline._errors`. Computations release the GIL.

Example::

    import fairline
    V, F = fairline.read_mesh("fairline-demo/wavy.obj")
    V2, report = fairline.smooth(V, F, method="taubin", iterations=10)
    values, _ = fairline.curvature(V2, F)
    print(report["max_displacement"], values["mean"].max())
"""

from __future__ import annotations

import functools as _functools
import json as _json
import os as _os
import warnings as _warnings
from typing import Any, Dict, List, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as _np

from . import _native
from ._errors import (
    FairlineComputationError,
    FairlineError,
    FairlineFileError,
    FairlineNotConvergedError,
    FairlineTypeError,
)
from ._inspect import inspect

__version__ = _native.__version__

__all__ = [
    "FairlineError",
    "FairlineFileError",
    "FairlineComputationError",
    "FairlineNotConvergedError",
    "FairlineTypeError",
    "FairlineWarning",
    "Mesh",
    "PrincipalCurvatures",
    "read_mesh",
    "write_mesh",
    "curvature",
    "deviation",
    "section",
    "draft",
    "highlight_lines",
    "highlight_curves",
    "detect",
    "fair",
    "smooth",
    "fair_quad",
    "enhance",
    "repair",
    "read_surfaces",
    "write_surfaces",
    "surface_highlight_lines",
    "surface_highlight_curves",
    "surface_iso_curves",
    "surface_deviation",
    "fair_surface",
    "inspect",
    "from_trimesh",
    "to_trimesh",
]

PathLike = Union[str, "_os.PathLike[str]"]
Faces = Union[_np.ndarray, Sequence[Sequence[int]]]
Vector = Sequence[float]


class FairlineWarning(UserWarning):
    """A warning of a fairline computation (the CLI's ``warning:`` lines):
    something did not converge or got worse. Also listed under
    ``"warnings"`` in the report."""


# ---- array conversions ---------------------------------------------------

_U32_MAX = 2**32 - 1


def _vertices(V: Any) -> _np.ndarray:
    """``V`` as a C-contiguous (n, 3) float64 array (integer and smaller
    float types are converted exactly); anything else raises."""
    try:
        a = _np.asarray(V)
    except (TypeError, ValueError) as e:
        raise FairlineError(f"V must be an (n, 3) array of numbers: {e}") from None
    if a.dtype.kind not in "fiu":
        raise FairlineError(f"V must hold real numbers, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise FairlineError(f"V must have shape (n, 3), got {a.shape}")
    return _np.ascontiguousarray(a, dtype=_np.float64)


def _index_array(a: _np.ndarray, what: str) -> _np.ndarray:
    if a.dtype.kind not in "iu":
        raise FairlineError(f"{what} must hold integers, got dtype {a.dtype}")
    return a


def _faces(F: Any, n_vertices: int) -> Tuple[_np.ndarray, _np.ndarray]:
    """Faces as flat uint32 indices plus offsets (face f is
    ``indices[offsets[f]:offsets[f+1]]``)."""
    rows: Optional[List[_np.ndarray]] = None
    if isinstance(F, _np.ndarray):
        a: Optional[_np.ndarray] = F
    else:
        try:
            rows = [_np.asarray(f) for f in F]
        except TypeError:
            raise FairlineError("F must be an integer array or a list of faces") from None
        if not rows:
            a = _np.zeros((0, 3), dtype=_np.int64)
        elif all(r.ndim == 1 for r in rows) and len({r.shape[0] for r in rows}) == 1:
            a = _np.stack(rows)
        else:
            a = None
    if a is not None:
        if a.size:
            _index_array(a, "F")
        if a.ndim != 2:
            raise FairlineError(
                f"F must have shape (m, 3) or (m, 4), or be a list of faces; got shape {a.shape}"
            )
    if a is not None:
        m, k = a.shape
        flat = a.reshape(-1)
        offsets = _np.arange(0, m * k + 1, k, dtype=_np.int64) if k > 0 else _np.zeros(m + 1, dtype=_np.int64)
    else:
        assert rows is not None
        for f, r in enumerate(rows):
            if r.ndim != 1:
                raise FairlineError(f"F: face {f} must be a list of vertex indices, got shape {r.shape}")
            _index_array(r, f"F: face {f}")
        flat = _np.concatenate(rows) if rows else _np.zeros(0, dtype=_np.int64)
        offsets = _np.concatenate([[0], _np.cumsum([len(r) for r in rows])])
    if flat.size:
        if flat.min() < 0:
            pos = int(_np.argmax(flat < 0))
            face = int(_np.searchsorted(offsets, pos, side="right") - 1)
            raise FairlineError(
                f"face {face} refers to vertex {int(flat[pos])}, but vertex indices start at 0"
            )
        if flat.max() > _U32_MAX:
            pos = int(_np.argmax(flat > _U32_MAX))
            face = int(_np.searchsorted(offsets, pos, side="right") - 1)
            raise FairlineError(
                f"face {face} refers to vertex {int(flat[pos])}, but the mesh has {n_vertices} vertices"
            )
    if offsets[-1] > _U32_MAX:
        raise FairlineError("mesh too large for 32-bit indices")
    return (
        _np.ascontiguousarray(flat, dtype=_np.uint32),
        _np.ascontiguousarray(offsets, dtype=_np.uint32),
    )


def _mesh(V: Any, F: Any) -> Tuple[_np.ndarray, _np.ndarray, _np.ndarray]:
    """(V, indices, offsets) for the native layer; a :class:`Mesh` or a
    ``trimesh.Trimesh`` (or anything with ``vertices`` and ``faces``) may
    stand in for ``V``."""
    if isinstance(V, Mesh):
        if F is not None:
            raise FairlineError("F must be left out when V is a fairline.Mesh")
        return V._V, V._indices, V._offsets
    if F is None:
        if hasattr(V, "vertices") and hasattr(V, "faces"):
            V, F = V.vertices, V.faces
        else:
            raise FairlineError("F is missing: give V and F, or a trimesh.Trimesh as V")
    v = _vertices(V)
    indices, offsets = _faces(F, len(v))
    return v, indices, offsets


def _faces_out(indices: _np.ndarray, offsets: _np.ndarray) -> Faces:
    """(m, k) int64 when every face has k vertices, else a list of arrays."""
    sizes = _np.diff(offsets.astype(_np.int64))
    idx = indices.astype(_np.int64)
    if len(sizes) == 0:
        return _np.zeros((0, 3), dtype=_np.int64)
    if _np.all(sizes == sizes[0]):
        return idx.reshape(-1, int(sizes[0]))
    return [idx[a:b] for a, b in zip(offsets[:-1].astype(_np.int64), offsets[1:].astype(_np.int64))]


def _report(text: str) -> Dict[str, Any]:
    """The report dict; its warnings are issued as FairlineWarning."""
    report = _json.loads(text)
    for w in report.get("warnings", []):
        _warnings.warn(f"fairline {report.get('command', '')}: {w}", FairlineWarning, stacklevel=4)
    return report


def _vec(name: str, v: Optional[Vector]) -> Optional[List[float]]:
    if v is None:
        return None
    try:
        a = _np.asarray(v, dtype=_np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise FairlineError(f"{name} must be three numbers, got {v!r}") from None
    if a.shape != (3,):
        raise FairlineError(f"{name} must be three numbers, got {v!r}")
    return [float(x) for x in a]


def _number(name: str, x: Any) -> Optional[float]:
    """An optional real number."""
    if x is None:
        return None
    try:
        return float(x)
    except (TypeError, ValueError):
        raise FairlineTypeError(f"{name} must be a number, got {x!r}") from None


def _count(name: str, n: Any) -> Optional[int]:
    """An optional non-negative whole number."""
    if n is None:
        return None
    if isinstance(n, bool) or not isinstance(n, (int, _np.integer)):
        raise FairlineTypeError(f"{name} must be a whole number, got {n!r}")
    if n < 0:
        raise FairlineError(f"{name} must be at least 0, got {n}")
    return int(n)


def _fixed(fixed: Optional[Sequence[int]]) -> Optional[List[int]]:
    if fixed is None:
        return None
    a = _np.asarray(fixed)
    if a.size == 0:
        return []
    if a.ndim != 1 or a.dtype.kind not in "iu":
        raise FairlineError(f"fixed must be a list of vertex indices, got {a.dtype} with shape {a.shape}")
    if a.dtype.kind == "u" and a.size and int(a.max()) > 2**63 - 1:
        raise FairlineError("fixed: vertex index too large")
    return [int(x) for x in a]


def _json_text(name: str, value: Any) -> Optional[str]:
    """A dictionary (or a JSON file's path) as JSON text for the native layer."""
    if value is None:
        return None
    if isinstance(value, (str, _os.PathLike)):
        path = _os.fspath(value)
        try:
            with open(path, encoding="utf-8") as f:
                return f.read()
        except OSError as e:
            raise FairlineFileError(f"{path}: {e.strerror or e}") from None
    try:
        return _json.dumps(value, default=_jsonable, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise FairlineError(f"{name}: {e}") from None


def _jsonable(o: Any) -> Any:
    if isinstance(o, _np.ndarray):
        return o.tolist()
    if isinstance(o, _np.generic):
        return o.item()
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


def _light_kwargs(direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos) -> Dict[str, Any]:
    return dict(
        direction=_vec("direction", direction),
        plane_normal=_vec("plane_normal", plane_normal),
        up=up,
        plane_point=_vec("plane_point", plane_point),
        spacing=None if spacing is None else float(spacing),
        lights=_json_text("lights", lights),
        min_normal_cos=float(min_normal_cos),
    )


# ---- files ------------------------------------------------------------------


def read_mesh(path: PathLike) -> Tuple[_np.ndarray, Faces]:
    """Reads a mesh file (``.obj .ply .off .stl``, chosen by extension).

    Returns ``(V, F)``: positions (n, 3) float64 and faces, (m, k) int64 when
    every face has k vertices, else a list of int64 arrays. Nothing is
    checked beyond what the file format demands (index range, face size,
    finite coordinates), so dirty meshes can be read and :func:`repair`-ed.
    Coordinates are exact (f64 text round trip, binary doubles).

    Raises :class:`FairlineError` naming the file, line and element
    (``bunny.ply:12: vertex 3: expected 3 coordinates, found 2``), or
    :class:`FairlineFileError` when the file cannot be opened.
    """
    v, indices, offsets = _native.read_mesh(_os.fspath(path))
    return v, _faces_out(indices, offsets)


def write_mesh(path: PathLike, V: Any, F: Faces = None) -> None:
    """Writes a mesh file atomically, format by extension (``.obj .ply .off
    .stl``); OBJ/OFF print exact shortest round-trip numbers, PLY is binary
    doubles, STL is f32 by definition. Refuses non-finite coordinates and
    out-of-range indices (nothing is written then)."""
    v, indices, offsets = _mesh(V, F)
    _native.write_mesh(_os.fspath(path), v, indices, offsets)


# ---- mesh algorithms ----------------------------------------------------------


def curvature(V: Any, F: Faces = None, method: str = "rusinkiewicz") -> Tuple[Dict[str, _np.ndarray], Dict[str, Any]]:
    """Per-vertex principal curvatures (``fairline curvature``).

    ``method``: ``"rusinkiewicz"`` (per-face shape-operator fit,
    Rusinkiewicz 2004) or ``"meyer"`` (mean-curvature normal and angle
    defect, Meyer et al. 2003). Polygon meshes are triangulated first.

    Returns ``(values, report)``; ``values`` has ``normals`` (n, 3), ``k1``,
    ``k2`` (k1 ≥ k2; a sphere of radius r with outward normals gives +1/r),
    ``mean``, ``gauss`` (n,), and the principal directions ``d1``, ``d2``
    (n, 3) — the columns the CLI writes to its PLY, bit for bit.
    """
    if isinstance(V, Mesh) and F is None:
        cols, report = V._curvature(method=method)
    else:
        v, indices, offsets = _mesh(V, F)
        cols, report = _native.curvature(v, indices, offsets, method=method)
    values = dict(cols)
    return values, _report(report)


def deviation(
    V_before: Any,
    F_before: Faces,
    V_after: Any,
    F_after: Faces = None,
    *,
    region: Optional[Sequence[int]] = None,
    bins: int = 41,
    broad_wavelength: Optional[float] = None,
) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """Signed deviation of a mesh from a reference (``fairline deviation``).

    One value per vertex of the *after* mesh: for meshes of the same
    connectivity the vertex motion along the reference's normal, otherwise
    the distance to the closest point of the reference, positive on the side
    its normals point to (model units). ``F_after`` defaults to
    ``F_before``. ``region``: faces of the after mesh; the report then
    splits the statistics into ``inside_region`` (the intended motion) and
    ``outside_region`` (side effects, 0 for highlight-line fairing).
    The deviation is also split by wavelength (``broad_wavelength``, model
    units; default ten mean edge lengths of the after mesh) into its
    ``broad`` part (whole neighbourhoods moved: offset, drift, the
    shrinkage of a smoothing) and its ``local`` part (the noise or defect
    a repair removes); ``broad + local == signed``.

    Returns ``(values, report)``; ``values`` has ``signed``, ``distance``,
    ``broad``, ``local`` (n,) float64 and ``in_region`` (n,) bool; the
    report has ``method``, ``all`` (``min``, ``max``, ``max_abs``,
    ``mean``, ``mean_abs``, ``rms``, ``p50_abs`` … ``p99_abs``,
    ``histogram``), ``broad``, ``local``, ``broad_wavelength`` and the
    region's parts.
    """
    v0, i0, o0 = _mesh(V_before, F_before)
    if F_after is None and not (hasattr(V_after, "vertices") and hasattr(V_after, "faces")):
        F_after = F_before
    v1, i1, o1 = _mesh(V_after, F_after)
    reg = None if region is None else [int(f) for f in region]
    wavelength = None if broad_wavelength is None else float(broad_wavelength)
    signed, distance, inside, broad, local, report = _native.deviation(
        v0, i0, o0, v1, i1, o1, region=reg, bins=int(bins), broad_wavelength=wavelength
    )
    values = {"signed": signed, "distance": distance, "in_region": inside, "broad": broad, "local": local}
    return values, _report(report)


def surface_deviation(
    surfaces: Union["Surface", Sequence["Surface"]],
    V: Any,
    F: Faces = None,
    *,
    grid: int = 64,
    region: Optional[Sequence[int]] = None,
    bins: int = 41,
    broad_wavelength: Optional[float] = None,
) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """Signed distance of every vertex of a mesh from B-spline surfaces
    (``fairline deviation PART.igs MESH``): the exact distance to the
    surfaces themselves, by point inversion started at the closest point of
    their tessellation (``grid`` per patch and direction), positive on the
    side ``S_u x S_v`` points to. Returns ``(values, report)`` as
    :func:`deviation`; the report's ``method`` is ``"surface-point"`` and
    ``unrefined`` counts the vertices left at the tessellation's value.
    """
    v1, i1, o1 = _mesh(V, F)
    reg = None if region is None else [int(f) for f in region]
    wavelength = None if broad_wavelength is None else float(broad_wavelength)
    signed, distance, inside, broad, local, report = _native.surface_deviation(
        _surfaces_text(surfaces), v1, i1, o1, grid=int(grid), region=reg, bins=int(bins),
        broad_wavelength=wavelength,
    )
    values = {"signed": signed, "distance": distance, "in_region": inside, "broad": broad, "local": local}
    return values, _report(report)


def section(
    V: Any,
    F: Faces = None,
    *,
    point: Vector,
    normal: Vector,
    count: int = 1,
    spacing: float = 0.0,
    comb_scale: float = 1.0,
) -> Tuple[Dict[str, _np.ndarray], Dict[str, Any]]:
    """Plane sections with their curvature combs (``fairline section``).

    ``count`` parallel planes ``spacing`` apart along ``normal``, the first
    through ``point``; polygon meshes are triangulated first. The curvature
    of a section point comes from the surface (Meusnier's theorem); the comb
    vector is ``-comb_scale * curvature * m`` with ``m`` towards the centre
    of curvature (the comb stands on the convex side).

    Returns ``(curves, report)``; ``curves`` has the flat arrays ``points``
    (n, 3), ``curvature`` (n,), ``comb`` (n, 3), and per curve ``offsets``
    (curves + 1,: curve ``i`` is ``points[offsets[i]:offsets[i + 1]]``),
    ``closed`` (bool) and ``plane`` (the index of its plane). The report
    lists per plane its ``offset`` and curves (``points``, ``closed``,
    ``length``, ``max_curvature``).
    """
    v, indices, offsets = _mesh(V, F)
    pts, kappa, comb, starts, closed, plane, report = _native.section(
        v, indices, offsets, _vec("point", point), _vec("normal", normal),
        count=int(count), spacing=float(spacing), comb_scale=float(comb_scale),
    )
    curves = {
        "points": pts,
        "curvature": kappa,
        "comb": comb,
        "offsets": starts,
        "closed": closed,
        "plane": plane,
    }
    return curves, _report(report)


def draft(
    V: Any,
    F: Faces = None,
    *,
    pull: Vector = (0.0, 0.0, 1.0),
    min_angle: float = 3.0,
) -> Tuple[Dict[str, _np.ndarray], Dict[str, Any]]:
    """Draft angles against a pull direction (``fairline draft``).

    The draft angle is ``asin(n . pull)`` in degrees (90° minus the angle
    between the normal and the pull): positive where the surface looks
    along the pull, negative where it looks away, 0 on walls parallel to it.
    Faces with ``|angle| < min_angle`` have insufficient draft.

    Returns ``(values, report)``; ``values`` has ``vertex`` (n,) (from the
    area-weighted vertex normals), ``face`` (m,) and ``below`` (m,) bool;
    the report has ``below_share`` (the share of the area below the
    minimum), ``positive_share``, ``negative_share``, ``min_deg``,
    ``max_deg``.
    """
    v, indices, offsets = _mesh(V, F)
    vertex, face, below, report = _native.draft(
        v, indices, offsets, _vec("pull", pull), min_angle=float(min_angle)
    )
    return {"vertex": vertex, "face": face, "below": below}, _report(report)


def smooth(
    V: Any,
    F: Faces = None,
    method: str = "taubin",
    *,
    weights: str = "uniform",
    exponent: float = -1.0,
    iterations: Optional[int] = None,
    lambda_: Optional[float] = None,
    mu: Optional[float] = None,
    pass_band: float = 0.1,
    time_step: float = 1.0,
    epsilon: Optional[float] = None,
    max_work: Optional[int] = None,
    fix_boundary: bool = False,
    hierarchical_boundary: bool = False,
    fixed: Optional[Sequence[int]] = None,
    preserve_volume: bool = False,
    tangential: bool = False,
) -> Tuple[_np.ndarray, Dict[str, Any]]:
    """The classic smoothing family (``fairline smooth``, Grüner thesis ch. 3).

    ``method``: ``"laplace"`` (x' = x + λΔx), ``"taubin"`` (λ|μ pairs),
    ``"implicit"`` (backward Euler, cotangent Laplacian; triangles),
    ``"spring"`` (Yamada et al.; boundary fixed) or ``"schneider-kobbelt"``
    (Δ_B H = 0 with G¹ boundary; triangles).

    ``weights`` (laplace, taubin): ``"uniform"``, ``"edge"`` (|e|^exponent)
    or ``"cotan"``. ``iterations``: default 10, 1 for implicit, 200 for
    spring, 50 for schneider-kobbelt. ``lambda_``: laplace 0.5; taubin from
    ``pass_band`` (1/λ + 1/μ = k_PB) unless given with ``mu``.
    ``time_step``: implicit, in units of the squared mean edge length.
    ``epsilon``: convergence threshold (spring, schneider-kobbelt).
    Constraints: ``fix_boundary``, ``hierarchical_boundary``, ``fixed``
    (vertex indices that never move), ``preserve_volume`` (closed meshes),
    ``tangential`` (tangent-plane motion only).

    Returns ``(V_new, report)``; report keys ``iterations converged
    volume_before volume_after max_displacement`` (+ ``lambda mu pass_band
    transfer`` for Taubin, ``residual`` and ``stop_reason`` for
    Schneider–Kobbelt).

    ``max_work`` (schneider-kobbelt): the most work one run may do (the
    CLI's ``--max-work``; default: the CLI's bound). Schneider–Kobbelt
    stops early when its residual stagnates or diverges, or when the next
    iteration would pass ``max_work``; a run that stops without converging
    raises :class:`FairlineNotConvergedError` (``stop_reason``, ``report``
    and the positions reached as ``V``), as the CLI exits 1. A result that
    is not finite raises :class:`FairlineComputationError`.
    """
    options = dict(
        method=method, weights=weights, exponent=float(exponent),
        iterations=_count("iterations", iterations), lambda_=_number("lambda_", lambda_),
        mu=_number("mu", mu), pass_band=float(pass_band), time_step=float(time_step),
        epsilon=_number("epsilon", epsilon), max_work=_count("max_work", max_work),
        fix_boundary=bool(fix_boundary), hierarchical_boundary=bool(hierarchical_boundary),
        fixed=_fixed(fixed), preserve_volume=bool(preserve_volume),
        tangential=bool(tangential),
    )
    if isinstance(V, Mesh) and F is None:
        out, report, stopped = V._smooth(**options)
    else:
        v, indices, offsets = _mesh(V, F)
        out, report, stopped = _native.smooth(v, indices, offsets, **options)
    doc = _report(report)
    if stopped is not None:
        raise FairlineNotConvergedError(
            stopped, stop_reason=doc.get("stop_reason", ""), report=doc, V=out
        )
    return out, doc


def fair_quad(
    V: Any,
    F: Faces = None,
    *,
    weight: float = 0.01,
    deviation: float = 0.1,
    deviation_factor: float = 0.1,
    iterations: int = 3,
    fix_boundary: bool = False,
    fixed: Optional[Sequence[int]] = None,
    off_surface: bool = False,
    method: str = "structure-lines",
    tolerance: float = 0.1,
    deviation_weights: bool = False,
) -> Tuple[_np.ndarray, Dict[str, Any]]:
    """Structure-line fairing of a quad mesh (``fairline fair-quad``,
    Grüner thesis ch. 4, Eq. (30)–(34)): zigzagging structure lines are
    straightened by a sparse least-squares fit with a penalty ω‖p − p⁰‖²
    (``weight``, scale-invariant) that keeps the shape; runs whose deviation
    exceeds ``deviation`` free their middle points, the deviation shrinks by
    ``deviation_factor`` per iteration. Corners never move. By default the
    moved points are put back onto a smooth fit of the input surface after
    every solve (they slide along it while the lines straighten);
    ``off_surface=True`` gives the thesis' method as printed;
    ``deviation_weights=True`` gives every freed point its own weight
    ω·δ/d by its deviation d (the thesis' suggested extension).

    ``method="network"`` fairs the polyline network with tolerance
    cylinders instead (Grüner §3.1.1, after Hofer et al.): only the heights
    z move, minimising the bending energy of every structure line with each
    vertex within ``tolerance`` mean edge lengths of its input height
    (``fixed`` vertices and, with ``fix_boundary``, the boundary do not
    move); the report adds ``network_energy_before network_energy_after
    at_bound tolerance``.

    Returns ``(V_new, report)``; report keys ``structure_lines
    free_vertices structure_energy_before structure_energy_after
    max_displacement iterations``.
    """
    v, indices, offsets = _mesh(V, F)
    out, report = _native.fair_quad(
        v, indices, offsets, weight=float(weight), deviation=float(deviation),
        deviation_factor=float(deviation_factor), iterations=int(iterations),
        fix_boundary=bool(fix_boundary), fixed=_fixed(fixed), off_surface=bool(off_surface),
        method=str(method), tolerance=float(tolerance),
        deviation_weights=bool(deviation_weights),
    )
    return out, _report(report)


def enhance(
    V: Any,
    F: Faces = None,
    *,
    lambda_: float = 1.0,
    mu: float = 0.5,
    iterations: int = 1,
    solver: str = "auto",
    fixed: Optional[Sequence[int]] = None,
    projection: str = "smooth",
) -> Tuple[_np.ndarray, Dict[str, Any]]:
    """Feature enhancement by vertex flow (``fairline enhance``, Ji et al.
    2011): vertices slide from flat regions toward ridges and valleys,
    minimising F_em + λ F_sd + μ F_smo; connectivity unchanged, ``fixed``
    vertices and the corners of the boundary bit-identical, the other
    boundary vertices slide along the boundary curve (with ``projection="none"``
    the whole boundary stays). ``solver``: ``"auto"``, ``"cg"``,
    ``"amg"`` or ``"direct"``. ``projection``: ``"smooth"`` (moved vertices
    are put back onto a smooth fit of the input surface), ``"mesh"`` (onto
    the input triangles) or ``"none"`` (the paper's method as published).
    Triangle meshes only.

    Returns ``(V_new, report)``; report keys include ``flipped_triangles
    quality_before quality_after histogram_before histogram_after
    max_displacement solver cg_iterations timings``.
    """
    v, indices, offsets = _mesh(V, F)
    out, report = _native.enhance(
        v, indices, offsets, lambda_=float(lambda_), mu=float(mu), iterations=int(iterations),
        solver=solver, fixed=_fixed(fixed), projection=projection,
    )
    return out, _report(report)


def repair(V: Any, F: Faces = None) -> Tuple[_np.ndarray, Faces, Dict[str, Any]]:
    """Repairs a dirty mesh (``fairline repair``): splits non-manifold edges
    and vertices, removes duplicate and zero-area faces and unreferenced
    vertices, makes the orientation consistent. Every kept vertex keeps its
    coordinates bit-identical and its order; split copies are appended.

    Returns ``(V_new, F_new, report)``; the report lists every change
    (``removed_faces``, ``split_edges``, ``flipped_faces``,
    ``vertex_source`` when the vertex list changed, …).
    """
    v, indices, offsets = _mesh(V, F)
    (v2, i2, o2), report = _native.repair(v, indices, offsets)
    return v2, _faces_out(i2, o2), _report(report)


def _lines(doc: Dict[str, Any]) -> Dict[str, Any]:
    """Lines document with ``points`` (and ``uv``) as float64 arrays."""

    def conv(lines: List[Dict[str, Any]]) -> List[Dict[str, Any]]:
        for line in lines:
            line["points"] = _np.asarray(line["points"], dtype=_np.float64).reshape(-1, 3)
            if "uv" in line:
                line["uv"] = _np.asarray(line["uv"], dtype=_np.float64).reshape(-1, 2)
        return lines

    conv(doc["lines"])
    if "bands" in doc:
        conv(doc["bands"]["lower"])
        conv(doc["bands"]["upper"])
    return doc


def highlight_lines(
    V: Any,
    F: Faces = None,
    *,
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    circle_center: Optional[Vector] = None,
    circle_axis: Optional[Vector] = None,
    radii: Optional[Sequence[float]] = None,
    band: Optional[float] = None,
) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """Highlight lines of a triangle (or polygon) mesh (``fairline
    highlight``): under a linear light array (Yong et al. Algorithm 1) or,
    with ``circle_center``/``circle_axis``/``radii``, under concentric
    circular lights (Nishiyama et al. Eq. (2.18)).

    Linear lights default from the mesh (``up``: ``"auto"``, ``"x"``,
    ``"y"``, ``"z"``; about 20 lights across); ``direction``,
    ``plane_normal``, ``plane_point``, ``spacing`` override, or ``lights``
    gives the whole array as the CLI's lights JSON (a dict, or a path):
    ``{"plane_point","plane_normal","direction","spacing"}`` or the circular
    ``{"center","axis","radii"}``. ``band`` adds the ±ρ band boundaries.

    Returns ``(lines, report)``: ``lines`` is the CLI's output JSON,
    ``{"lines": [{"index", "closed", "points": (k, 3) array, "radius"?}],
    "bands"?: {...}}``, each line's ``points`` a view of one array.
    :meth:`Mesh.highlight_lines` gives the same lines as flat arrays with
    offsets, without a dict per line.
    """
    mesh = V if isinstance(V, Mesh) and F is None else _native.Mesh(*_mesh(V, F))
    arrays, report = mesh._highlight_lines(
        **_highlight_kwargs(
            direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos,
            circle_center, circle_axis, radii, band,
        )
    )
    doc: Dict[str, Any] = {"lines": _line_dicts(arrays)}
    if "lower" in arrays:
        doc["bands"] = {
            "radius": arrays["band_radius"],
            "lower": _line_dicts(arrays["lower"]),
            "upper": _line_dicts(arrays["upper"]),
        }
    return doc, _report(report)


def highlight_curves(
    V: Any,
    F: Faces = None,
    *,
    tolerance: Optional[float] = None,
    path: Optional[PathLike] = None,
    unit: Optional[str] = None,
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    circle_center: Optional[Vector] = None,
    circle_axis: Optional[Vector] = None,
    radii: Optional[Sequence[float]] = None,
) -> Tuple[List[Dict[str, Any]], Dict[str, Any]]:
    """Highlight lines of a mesh as cubic B-spline curves for a CAD system
    (``fairline highlight MESH -o LINES.igs``): the lines of
    :func:`highlight_lines` (same light options) each fitted within
    ``tolerance`` (default: 1e-4 of the bounding-box diagonal, at least a
    tenth of the mean edge length), kept as a polyline where no shorter
    cubic fits. With ``path`` (``.igs``/``.iges``) the curves are written
    atomically as IGES entities 126 labelled ``HLm`` (light m), in ``unit``
    (an IGES unit name; millimetres by default) — the file the CLI writes.

    Returns ``(curves, report)``: each curve a dict with ``label``,
    ``number``, ``degree``, ``knots`` (float64) and ``points`` ((k, 3)
    control points); the report as :func:`highlight_lines`' with
    ``"curves"``: counts, ``tolerance`` and ``max_deviation`` (the largest
    distance from a line point to its curve).
    """
    mesh = V if isinstance(V, Mesh) and F is None else _native.Mesh(*_mesh(V, F))
    options = _highlight_kwargs(
        direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos,
        circle_center, circle_axis, radii,
    )
    del options["band"]
    curves, report = mesh._highlight_curves(**_curves_kwargs(tolerance, path, unit), **options)
    return curves, _report(report)


def _curves_kwargs(tolerance: Optional[float], path: Optional[PathLike], unit: Optional[str]) -> Dict[str, Any]:
    return dict(
        tolerance=None if tolerance is None else float(tolerance),
        path=None if path is None else _os.fspath(path),
        unit=None if unit is None else str(unit),
    )


def _highlight_kwargs(
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    circle_center: Optional[Vector] = None,
    circle_axis: Optional[Vector] = None,
    radii: Optional[Sequence[float]] = None,
    band: Optional[float] = None,
) -> Dict[str, Any]:
    """The options of :func:`highlight_lines` for the native layer."""
    return dict(
        **_light_kwargs(direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos),
        circle_center=_vec("circle_center", circle_center),
        circle_axis=_vec("circle_axis", circle_axis),
        radii=None if radii is None else [float(r) for r in radii],
        band=None if band is None else float(band),
    )


def _line_dicts(arrays: Dict[str, Any]) -> List[Dict[str, Any]]:
    """The lines of :meth:`Mesh.highlight_lines`'s flat arrays as the
    dicts of the CLI's lines file (``points`` are views of one array)."""
    points = arrays["points"]
    offsets = arrays["offsets"].tolist()
    radius = arrays["radius"].tolist() if "radius" in arrays else None
    out = []
    for k, (index, closed) in enumerate(zip(arrays["index"].tolist(), arrays["closed"].tolist())):
        line: Dict[str, Any] = {"index": index, "closed": closed, "points": points[offsets[k] : offsets[k + 1]]}
        if radius is not None:
            line["radius"] = radius[k]
        out.append(line)
    return out


def detect(
    V: Any,
    F: Faces = None,
    *,
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    threshold: float = 1.0,
    smooth_radius: float = 1.5,
    region_margin: float = 1.0,
    max_regions: Optional[int] = None,
) -> Tuple[_np.ndarray, Dict[str, Any]]:
    """Finds defects that disturb the highlight lines (``fairline detect``)
    and turns them into a fairing region: the surface's normals are
    compared with a smooth cubic fit over ``smooth_radius`` light spacings;
    the score is the highlight-line displacement that causes, in tenths of a
    spacing, flagged above ``threshold`` (raised above the noise of scans).
    A second measure flags flat spots wider than the fit (the curvature's
    drop against the surface smoothed at four smooth radii; report keys
    ``flat_spot_floor``, ``flat_spot_sites``, ``curvature_noise``, each
    region's ``flat_spot``); regions are ranked by ``severity``.
    Light options as for :func:`highlight_lines` (linear lights only).

    Returns ``(region_faces, report)``: the face indices the CLI writes as
    region JSON (regions plus two rings of support faces, ready for
    :func:`fair`), and the report ranking the regions.
    """
    v, indices, offsets = _mesh(V, F)
    faces, report = _native.detect(
        v, indices, offsets,
        **_light_kwargs(direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos),
        threshold=float(threshold), smooth_radius=float(smooth_radius),
        region_margin=float(region_margin), max_regions=max_regions,
    )
    return faces.astype(_np.int64), _report(report)


def fair(
    V: Any,
    F: Faces = None,
    region: Any = None,
    *,
    auto: bool = False,
    grow: int = 0,
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    max_iterations: int = 50,
    epsilon: float = 0.001,
    method: str = "highlight",
    fair_weight: float = 1.0,
    diff_weight: float = 1.0,
    laplacian_weight: float = 0.0,
    least_change: bool = True,
) -> Tuple[_np.ndarray, Dict[str, Any]]:
    """Highlight-line fairing inside a region (``fairline fair``, Yong et
    al. §3, Algorithm 2): moves only vertices whose motion changes nothing
    outside the region until the highlight lines inside follow smooth
    desired curves. ``method``: ``"highlight"`` (default: the paper's
    energy with the desired curves' end tangents taken from a smooth fit
    beyond the defect's footprint, then ¾ of that result + ¼ of the
    diffusion-flow result on the same region, kept only where it dominates
    the diffusion-flow result — nearer the desired curves and a smaller
    change of the part — else the diffusion-flow result; the report's
    ``kept_flow`` and ``least_change`` say which and why;
    ``least_change=False`` keeps the highlight result always),
    ``"paper"`` (Yong et al.'s Algorithm 2 exactly) or
    ``"diffusion-flow"`` (baseline); ``laplacian_weight`` adds a
    surface-diffusion term to ``"highlight"``.

    ``region``: face indices (e.g. :func:`detect`'s result), or the CLI's
    region JSON as a dict (``{"faces"}``, ``{"vertices"}``,
    ``{"sphere": {"center", "radius"}}``) or a path to it; or
    ``auto=True`` to detect the regions and fair each in turn. ``grow``
    adds rings of faces. Light options as for :func:`detect`: detection
    scores are measured with those lights (report key ``light``), the
    fairing works on the readable lights (``fairing_light``: every k-th
    line on round parts, the same lights on panels or with ``spacing``).

    Returns ``(V_new, report)`` with the CLI's report keys
    (``iterations converged movable_vertices willmore_before
    willmore_after highlight_deviation_before highlight_deviation_after
    max_displacement history detect_score_before detect_score_after
    detect_regions_after`` …); its ``warnings`` say when detection on the
    result still flags a region (``a defect remains: …``).
    """
    v, indices, offsets = _mesh(V, F)
    if region is None:
        region_text = None
    elif isinstance(region, (dict, str, _os.PathLike)):
        region_text = _json_text("region", region)
    else:
        faces = _np.asarray(region)
        if faces.ndim != 1 or (faces.size and faces.dtype.kind not in "iu"):
            raise FairlineError("region must be a list of face indices, a region dict or a path")
        region_text = _json.dumps({"faces": [int(f) for f in faces]})
    out, report = _native.fair(
        v, indices, offsets, region=region_text, auto=bool(auto), grow=int(grow),
        **_light_kwargs(direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos),
        max_iterations=int(max_iterations), epsilon=float(epsilon), method=method,
        fair_weight=float(fair_weight), diff_weight=float(diff_weight),
        laplacian_weight=float(laplacian_weight),
        least_change=bool(least_change),
    )
    return out, _report(report)


# ---- B-spline surfaces --------------------------------------------------------

Surface = Dict[str, Any]


def _surfaces_from(text: str) -> List[Surface]:
    doc = _json.loads(text)
    out = doc["surfaces"]
    for s in out:
        if "control_points" in s:
            try:
                s["control_points"] = _np.asarray(s["control_points"], dtype=_np.float64)
            except ValueError:
                pass  # ragged rows stay lists; the library refuses them
        if "weights" in s:
            try:
                s["weights"] = _np.asarray(s["weights"], dtype=_np.float64)
            except ValueError:
                pass
    return out


def _surfaces_text(surfaces: Union[Surface, Sequence[Surface]]) -> str:
    if isinstance(surfaces, dict):
        doc = surfaces if "surfaces" in surfaces else {"surfaces": [surfaces]}
    else:
        doc = {"surfaces": list(surfaces)}
    text = _json_text("surfaces", doc)
    assert text is not None
    return text


def read_surfaces(path: PathLike, *, skip_unreadable: bool = False) -> List[Surface]:
    """Reads B-spline surfaces from fairline JSON, IGES, STEP, GoTools
    ``.g2`` or geomdl (NURBS-Python) JSON, by extension and content.

    Returns a list of dicts in the JSON format of DESIGN.md §5
    (``degree_u``, ``degree_v``, ``knots_u``, ``knots_v``,
    ``control_points`` as an (nu, nv, 3) float64 array, ``weights`` when
    rational, ``trim`` when trimmed). Numbers are exact.

    A face the file holds but fairline cannot read (an unsupported surface
    or curve type) raises :class:`FairlineError` naming it, as the CLI
    fails; with ``skip_unreadable=True`` the other faces are returned and a
    :class:`FairlineWarning` names what was left out. A file none of whose
    faces can be read always raises.
    """
    text, said = _native.read_surfaces(_os.fspath(path), skip_unreadable)
    for w in said:
        _warnings.warn(f"fairline read_surfaces: {w}", FairlineWarning, stacklevel=3)
    return _surfaces_from(text)


def write_surfaces(path: PathLike, surfaces: Union[Surface, Sequence[Surface]]) -> None:
    """Writes surfaces (a dict or a list of dicts as :func:`read_surfaces`
    returns) to a ``.json`` file atomically; the library checks them first."""
    _native.write_surfaces(_os.fspath(path), _surfaces_text(surfaces))


def surface_highlight_lines(
    surfaces: Union[Surface, Sequence[Surface]],
    *,
    circle_center: Optional[Vector] = None,
    circle_axis: Optional[Vector] = None,
    radii: Optional[Sequence[float]] = None,
    band: Optional[float] = None,
    grid: int = 200,
    surface: Optional[int] = None,
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    circular: bool = False,
) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """Highlight lines of B-spline surfaces (``fairline highlight
    SURFACE.json``, Nishiyama et al. §2): d_s sampled on a ``grid`` ×
    ``grid`` (u, v) grid, contoured, refined onto the true zero. Circular
    lights with ``circle_center``/``circle_axis``/``radii`` or a circular
    ``lights`` dictionary ``{"center","axis","radii"}``, or derived from the
    whole part with ``circular=True`` (the report's ``light`` says which);
    else linear lights (options as :func:`highlight_lines`). ``surface``:
    only this one.

    Returns ``(lines, report)``: lines carry ``id`` (their position),
    ``uv`` (k, 2) and ``points`` (k, 3) arrays, ``light``, ``level``,
    ``closed`` and ``radius`` or ``index``.
    """
    doc, report = _native.surface_highlight_lines(
        _surfaces_text(surfaces),
        circle_center=_vec("circle_center", circle_center),
        circle_axis=_vec("circle_axis", circle_axis),
        radii=None if radii is None else [float(r) for r in radii],
        band=None if band is None else float(band),
        grid=int(grid),
        surface=surface,
        circular=bool(circular),
        **_light_kwargs(direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos),
    )
    return _lines(_json.loads(doc)), _report(report)


def surface_iso_curves(
    surfaces: Union[Surface, Sequence[Surface]],
    *,
    count: int = 5,
    samples: int = 200,
    surface: Optional[int] = None,
    comb_scale: float = 1.0,
) -> Tuple[Dict[str, _np.ndarray], Dict[str, Any]]:
    """Isoparametric curves of B-spline surfaces with their exact curvature
    combs (``fairline section SURFACES --iso N``): ``count`` curves per
    direction and surface, the domain's ends (the patch edges) included,
    each sampled at ``samples`` even parameters plus its interior knots; on
    trimmed faces only the pieces inside the face. The curvature is the
    curve's own, ``|C' x C''| / |C'|^3`` from the surface derivatives; the
    comb vector ``-comb_scale * curvature * m`` stands on the convex side.

    Returns ``(curves, report)``; ``curves`` has the flat arrays ``points``
    (n, 3), ``params`` (n,: the running parameter), ``curvature`` (n,),
    ``comb`` (n, 3), and per curve ``offsets`` (curves + 1,), ``surface``,
    ``kind`` (0: u held, the curve runs along v; 1: v held; 2: an edge of a
    trimmed face, its trimming curve on the surface) and ``value`` (the held
    parameter, or the edge's trimming loop).
    """
    curves, report = _native.surface_iso_curves(
        _surfaces_text(surfaces), count=int(count), samples=int(samples), surface=surface,
        comb_scale=float(comb_scale),
    )
    return curves, _report(report)


def surface_highlight_curves(
    surfaces: Union[Surface, Sequence[Surface]],
    *,
    tolerance: Optional[float] = None,
    path: Optional[PathLike] = None,
    unit: Optional[str] = None,
    circle_center: Optional[Vector] = None,
    circle_axis: Optional[Vector] = None,
    radii: Optional[Sequence[float]] = None,
    grid: int = 200,
    surface: Optional[int] = None,
    direction: Optional[Vector] = None,
    plane_normal: Optional[Vector] = None,
    up: str = "auto",
    plane_point: Optional[Vector] = None,
    spacing: Optional[float] = None,
    lights: Any = None,
    min_normal_cos: float = 0.1,
    circular: bool = False,
) -> Tuple[List[Dict[str, Any]], Dict[str, Any]]:
    """The exact highlight lines of B-spline surfaces as cubic B-spline
    curves for a CAD system (``fairline highlight PART.igs -o
    LINES.igs``): the lines of :func:`surface_highlight_lines` (same light
    options) fitted within ``tolerance`` (default: 1e-4 of the part's
    diagonal). With ``path`` (``.igs``/``.iges``) they are written
    atomically as IGES entities 126 labelled ``PkLj`` (patch k, light j) in
    ``unit`` — give the unit of the file the surfaces came from (an IGES
    unit name such as ``"MM"`` or ``"IN"``; millimetres by default), since
    the surfaces' dicts do not carry it.

    Returns ``(curves, report)`` as :func:`highlight_curves`.
    """
    curves, report = _native.surface_highlight_curves(
        _surfaces_text(surfaces),
        **_curves_kwargs(tolerance, path, unit),
        circle_center=_vec("circle_center", circle_center),
        circle_axis=_vec("circle_axis", circle_axis),
        radii=None if radii is None else [float(r) for r in radii],
        grid=int(grid),
        surface=surface,
        circular=bool(circular),
        **_light_kwargs(direction, plane_normal, up, plane_point, spacing, lights, min_normal_cos),
    )
    return curves, _report(report)


def fair_surface(
    surfaces: Union[Surface, Sequence[Surface]],
    lights: Any,
    endpoints: Any,
    *,
    surface: int = 0,
    max_iterations: int = 20,
    epsilon: float = 0.0001,
    truncation: float = 0.05,
    min_truncation: float = 0.001,
    sample_spacing: float = 0.005,
    grid: int = 200,
    method: str = "regularised",
    boundary: str = "fixed",
    keep_weight: float = 0.01,
    fairness_weight: float = 0.003,
    damped_step: float = 0.1,
    damping: str = "residual",
) -> Tuple[List[Surface], Dict[str, Any]]:
    """Circular-highlight fairing of a B-spline surface (``fairline
    fair-surface``, Nishiyama et al. §3): each endpoint pair is snapped onto
    the pre-image of its light, joined by a cubic Hermite target, and the
    control points over the endpoints' knot box move. ``method``:
    ``"regularised"`` (Levenberg–Marquardt, keeps every other line fair) or
    ``"paper"`` (Gauss–Newton, truncated SVD); ``boundary``: ``"fixed"``,
    ``"tangent"`` or ``"free"``; ``damped_step``: μ of the damped step
    (Eq. 3.13; 1 turns the damping off); ``damping``: when the paper's
    solver damps a step, ``"residual"`` (when Σ d_s² grows), ``"max-mean"``
    (Eq. 3.12 as printed) or ``"off"``.

    ``lights``: ``{"center","axis","radii"}``; ``endpoints``:
    ``{"endpoints": [{"radius", "start": [u, v], "end": [u, v]}]}`` (dicts
    or paths to the CLI's JSON files).

    Returns ``(surfaces, report)``: all surfaces with surface ``surface``
    faired (every other control point bit-identical), and the report.
    """
    out, report = _native.fair_surface(
        _surfaces_text(surfaces), _json_text("lights", lights), _json_text("endpoints", endpoints),
        surface=int(surface), max_iterations=int(max_iterations), epsilon=float(epsilon),
        truncation=float(truncation), min_truncation=float(min_truncation),
        sample_spacing=float(sample_spacing), grid=int(grid), method=method, boundary=boundary,
        keep_weight=float(keep_weight), fairness_weight=float(fairness_weight),
        damped_step=float(damped_step), damping=damping,
    )
    return _surfaces_from(out), _report(report)


# ---- a mesh built once ------------------------------------------------------------


class PrincipalCurvatures(NamedTuple):
    """Principal curvatures per vertex (:meth:`Mesh.principal_curvatures`):
    ``k1 ≥ k2`` (n,) signed, a sphere of radius r with outward normals
    giving +1/r, and the unit principal directions ``d1``, ``d2`` (n, 3)."""

    k1: _np.ndarray
    k2: _np.ndarray
    d1: _np.ndarray
    d2: _np.ndarray


def _scipy_sparse(what: str) -> Any:
    try:
        import scipy.sparse
    except ImportError:
        raise FairlineError(f"Mesh.{what} returns a scipy.sparse matrix and needs scipy: pip install scipy") from None
    return scipy.sparse


class Mesh(_native.Mesh):
    """A mesh whose connectivity (halfedges, split non-manifold vertices,
    the triangles of a polygon mesh) is built once, when it is made, and
    kept: every method and every module function given a ``Mesh`` skips
    that work, which on large meshes is a good part of a call.

    ``Mesh(V, F)`` takes what the module functions take (``V`` (n, 3)
    positions, ``F`` faces; or a ``trimesh.Trimesh`` as ``V``) and raises
    :class:`FairlineError` for what they refuse (an index out of range, a
    non-manifold edge …). ``Mesh.read(path)`` reads a mesh file. A ``Mesh``
    may be passed as ``V`` (with ``F`` left out) to every function of the
    package; :func:`curvature`, :func:`smooth` and :func:`highlight_lines`
    then reuse its connectivity. Results equal those of the module
    functions on ``(V, F)`` bit for bit.

    The mesh is immutable: ``V`` and ``F`` are read-only copies, and
    :meth:`smooth` returns new positions (make a new ``Mesh`` of them to go
    on). Methods release the GIL; Ctrl-C stops them.
    """

    def __new__(cls, V: Any, F: Faces = None) -> "Mesh":
        v, indices, offsets = _mesh(V, F)
        # copies: the connectivity is built from these and must not change
        return cls._of_arrays(_np.array(v, dtype=_np.float64, copy=True), _np.array(indices, copy=True), offsets)

    @classmethod
    def _of_arrays(cls, v: _np.ndarray, indices: _np.ndarray, offsets: _np.ndarray) -> "Mesh":
        self = super().__new__(cls, v, indices, offsets)
        for a in (v, indices, offsets):
            a.setflags(write=False)
        self._V, self._indices, self._offsets = v, indices, offsets
        self._F: Optional[Faces] = None
        return self

    def __init__(self, V: Any = None, F: Faces = None) -> None:
        pass  # built by __new__

    @classmethod
    def read(cls, path: PathLike) -> "Mesh":
        """A mesh file (``.obj .ply .off .stl``) as a :class:`Mesh` (as
        :func:`read_mesh`, then ``Mesh(V, F)``)."""
        try:
            v, indices, offsets = _native.read_mesh(_os.fspath(path))
        except TypeError as e:
            raise FairlineTypeError(f"Mesh.read: {e}") from e
        return cls._of_arrays(v, indices, offsets)

    def __repr__(self) -> str:
        return f"fairline.Mesh({self.vertex_count} vertices, {self.face_count} faces)"

    @property
    def V(self) -> _np.ndarray:
        """Positions (n, 3) float64, read-only."""
        return self._V

    @property
    def F(self) -> Faces:
        """Faces: (m, k) int64 when every face has k vertices, else a list
        of int64 arrays (as :func:`read_mesh` returns them)."""
        if self._F is None:
            self._F = _faces_out(self._indices, self._offsets)
        return self._F

    # the names trimesh gives them, so that a Mesh goes where a trimesh goes
    vertices = V
    faces = F

    def vertex_normals(self) -> _np.ndarray:
        """Unit vertex normals (n, 3): the area-weighted sum of the face
        normals around each vertex (Yong et al. Eq. (3); the
        ``igl.per_vertex_normals`` area weighting); zero where none is
        defined (an isolated vertex)."""
        return self._vertex_normals()

    def curvature(self, method: str = "rusinkiewicz") -> Tuple[Dict[str, _np.ndarray], Dict[str, Any]]:
        """:func:`curvature` of this mesh: ``(values, report)``."""
        return curvature(self, method=method)

    def principal_curvatures(self, method: str = "rusinkiewicz") -> PrincipalCurvatures:
        """Principal curvatures and directions per vertex, ``(k1, k2, d1,
        d2)`` as a named tuple: k1 ≥ k2 signed (a sphere of radius r with
        outward normals has +1/r; libigl's ``principal_curvature`` returns
        (PD1, PD2, PV1, PV2) with its own sign). ``method`` as for
        :func:`curvature` (Rusinkiewicz 2004 by default)."""
        values, _ = curvature(self, method=method)
        return PrincipalCurvatures(values["k1"], values["k2"], values["d1"], values["d2"])

    def cotangent_laplacian(self) -> Any:
        """The cotangent Laplacian as an (n, n) ``scipy.sparse.csr_matrix``:
        L_ij = ½ (cot α_ij + cot β_ij) for each edge, L_ii = −Σ_j L_ij
        (Meyer et al. 2003 Eq. (8); libigl's ``cotmatrix`` convention:
        symmetric, negative semi-definite, constants in its null space; not
        divided by areas). Cotangents of degenerate triangles are 0 and
        their magnitudes are clamped to 1e6. Triangle meshes only; needs
        scipy (:class:`FairlineError` otherwise)."""
        sparse = _scipy_sparse("cotangent_laplacian")
        kind, data, a, b, n = self._cotangent_laplacian()
        if kind == "csr":
            return sparse.csr_matrix((data, a, b), shape=(n, n))
        return sparse.coo_matrix((data, (a, b)), shape=(n, n)).tocsr()

    def mass_matrix(self) -> Any:
        """The lumped mass matrix as an (n, n) diagonal
        ``scipy.sparse.csr_matrix``: the mixed Voronoi area of each vertex
        (Meyer et al. 2003 §3.3; libigl's ``massmatrix`` with
        ``MASSMATRIX_TYPE_VORONOI``); the diagonal sums to the surface area.
        Needs scipy (:class:`FairlineError` otherwise)."""
        sparse = _scipy_sparse("mass_matrix")
        return sparse.diags(self._vertex_areas(), format="csr")

    def smooth(self, method: str = "taubin", *, report: bool = False, **options: Any) -> Any:
        """:func:`smooth` of this mesh; returns the new positions (n, 3), or
        ``(V_new, report)`` with ``report=True``. Options as for
        :func:`smooth` (``iterations``, ``lambda_``, ``mu``, ``weights``,
        ``fixed`` …); a run that stops unconverged raises
        :class:`FairlineNotConvergedError`."""
        V_new, doc = smooth(self, None, method, **options)
        return (V_new, doc) if report else V_new

    def highlight_lines(self, *, report: bool = False, **options: Any) -> Any:
        """Highlight lines of this mesh as flat arrays (options as for
        :func:`highlight_lines`): a dict with ``points`` (N, 3) float64,
        the nodes of every line in turn; ``offsets`` (L + 1,) int64, line k
        being ``points[offsets[k]:offsets[k + 1]]``; ``index`` (L,) int64,
        the light of each line; ``closed`` (L,) bool; for circular lights
        ``radius`` (L,); with ``band``, ``band_radius`` and the band
        boundaries ``lower`` and ``upper`` as dicts of the same arrays.
        With ``report=True`` returns ``(arrays, report)``."""
        arrays, text = self._highlight_lines(**_highlight_kwargs(**options))
        doc = _report(text)
        return (arrays, doc) if report else arrays

    def highlight_curves(
        self,
        *,
        tolerance: Optional[float] = None,
        path: Optional[PathLike] = None,
        unit: Optional[str] = None,
        **options: Any,
    ) -> Tuple[List[Dict[str, Any]], Dict[str, Any]]:
        """Highlight lines of this mesh as B-spline curves, as
        :func:`highlight_curves` (light options as :func:`highlight_lines`,
        no ``band``). Returns ``(curves, report)``."""
        if "band" in options:
            raise FairlineError("band: band boundaries are not written as curves")
        light = _highlight_kwargs(**options)
        del light["band"]
        curves, text = self._highlight_curves(**_curves_kwargs(tolerance, path, unit), **light)
        return curves, _report(text)


# ---- trimesh adapters -----------------------------------------------------------


def from_trimesh(mesh: Any) -> Tuple[_np.ndarray, _np.ndarray]:
    """``(V, F)`` of a ``trimesh.Trimesh`` as float64 / int64 copies."""
    return (
        _np.array(mesh.vertices, dtype=_np.float64, copy=True),
        _np.array(mesh.faces, dtype=_np.int64, copy=True),
    )


def to_trimesh(V: Any, F: Faces, **kwargs: Any) -> Any:
    """A ``trimesh.Trimesh`` of ``V`` and triangle faces ``F`` with
    ``process=False`` (vertices kept as they are, in their order). Needs
    the optional ``trimesh`` package."""
    try:
        import trimesh
    except ImportError:
        raise ImportError("fairline.to_trimesh needs the trimesh package: pip install trimesh") from None
    kwargs.setdefault("process", False)
    return trimesh.Trimesh(vertices=_vertices(V), faces=_np.asarray(F, dtype=_np.int64), **kwargs)


# ---- every error a FairlineError ------------------------------------------


def _checked(f: Any) -> Any:
    """``f`` raising only :class:`FairlineError`: an error of a conversion
    it did not foresee (numpy's ``ValueError`` for a bad array, Python's
    ``TypeError`` for an argument of the wrong type) is raised as a
    :class:`FairlineError` (:class:`FairlineTypeError` for a ``TypeError``
    or an ``AttributeError``: an object of the wrong type)
    naming the function, the original as its cause. Warnings turned into
    errors and :class:`KeyboardInterrupt` pass unchanged."""

    @_functools.wraps(f)
    def checked(*args: Any, **kwargs: Any) -> Any:
        try:
            return f(*args, **kwargs)
        except (FairlineError, Warning):
            raise
        except (TypeError, AttributeError) as e:
            raise FairlineTypeError(f"{f.__name__}: {e}") from e
        except (ValueError, IndexError, KeyError, ArithmeticError) as e:
            raise FairlineError(f"{f.__name__}: {e}") from e
        except OSError as e:
            raise FairlineFileError(f"{f.__name__}: {e}") from e

    return checked


for _name in __all__:
    _f = globals()[_name]
    if callable(_f) and not isinstance(_f, type):
        globals()[_name] = _checked(_f)
del _name, _f


for _name in ("read", "vertex_normals", "curvature", "principal_curvatures", "cotangent_laplacian",
              "mass_matrix", "smooth", "highlight_lines", "highlight_curves"):
    _m = Mesh.__dict__[_name]
    if isinstance(_m, classmethod):
        setattr(Mesh, _name, classmethod(_checked(_m.__func__)))
    else:
        setattr(Mesh, _name, _checked(_m))
del _name, _m


def __dir__() -> List[str]:
    """The public names only (no imported modules or typing names)."""
    return sorted(__all__ + ["__version__"])
