"""Type stubs of the native layer (python/src/*.rs). Use the documented
functions of the ``fairline`` package instead: they check shapes and types
and convert the JSON texts returned here into dicts and arrays."""

from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

_F64_2 = npt.NDArray[np.float64]
_U32 = npt.NDArray[np.uint32]
_Soup = Tuple[_F64_2, _U32, _U32]

def read_mesh(path: str) -> _Soup: ...
def write_mesh(path: str, v: _F64_2, indices: _U32, offsets: _U32) -> None: ...
def curvature(
    v: _F64_2, indices: _U32, offsets: _U32, method: str = "rusinkiewicz"
) -> Tuple[List[Tuple[str, npt.NDArray[np.float64]]], str]: ...  # normals d1 d2 (n, 3); k1 k2 mean gauss (n,)
def deviation(
    v0: _F64_2,
    indices0: _U32,
    offsets0: _U32,
    v1: _F64_2,
    indices1: _U32,
    offsets1: _U32,
    region: Optional[Sequence[int]] = None,
    bins: int = 41,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_], str]: ...
def section(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    point: Sequence[float],
    normal: Sequence[float],
    count: int = 1,
    spacing: float = 0.0,
    comb_scale: float = 1.0,
) -> Tuple[_F64_2, npt.NDArray[np.float64], _F64_2, _U32, npt.NDArray[np.bool_], _U32, str]: ...
def draft(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    pull: Sequence[float],
    min_angle: float = 3.0,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_], str]: ...
def smooth(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    method: str = "taubin",
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
) -> Tuple[_F64_2, str, Optional[str]]: ...
def fair_quad(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    weight: float = 0.01,
    deviation: float = 0.1,
    deviation_factor: float = 0.1,
    iterations: int = 3,
    fix_boundary: bool = False,
    fixed: Optional[Sequence[int]] = None,
    off_surface: bool = False,
    method: str = "structure-lines",
    tolerance: float = 0.1,
) -> Tuple[_F64_2, str]: ...
def enhance(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    lambda_: float = 1.0,
    mu: float = 0.5,
    iterations: int = 1,
    solver: str = "auto",
    fixed: Optional[Sequence[int]] = None,
    projection: str = "smooth",
) -> Tuple[_F64_2, str]: ...
def repair(v: _F64_2, indices: _U32, offsets: _U32) -> Tuple[_Soup, str]: ...
def highlight_lines(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    direction: Optional[Sequence[float]] = None,
    plane_normal: Optional[Sequence[float]] = None,
    up: str = "auto",
    plane_point: Optional[Sequence[float]] = None,
    spacing: Optional[float] = None,
    lights: Optional[str] = None,
    min_normal_cos: Optional[float] = None,
    circle_center: Optional[Sequence[float]] = None,
    circle_axis: Optional[Sequence[float]] = None,
    radii: Optional[Sequence[float]] = None,
    band: Optional[float] = None,
) -> Tuple[str, str]: ...
def detect(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    direction: Optional[Sequence[float]] = None,
    plane_normal: Optional[Sequence[float]] = None,
    up: str = "auto",
    plane_point: Optional[Sequence[float]] = None,
    spacing: Optional[float] = None,
    lights: Optional[str] = None,
    min_normal_cos: Optional[float] = None,
    threshold: Optional[float] = None,
    smooth_radius: Optional[float] = None,
    region_margin: Optional[float] = None,
    max_regions: Optional[int] = None,
) -> Tuple[_U32, str]: ...
def fair(
    v: _F64_2,
    indices: _U32,
    offsets: _U32,
    region: Optional[str] = None,
    auto: bool = False,
    grow: int = 0,
    direction: Optional[Sequence[float]] = None,
    plane_normal: Optional[Sequence[float]] = None,
    up: str = "auto",
    plane_point: Optional[Sequence[float]] = None,
    spacing: Optional[float] = None,
    lights: Optional[str] = None,
    min_normal_cos: Optional[float] = None,
    max_iterations: Optional[int] = None,
    epsilon: Optional[float] = None,
    method: str = "highlight",
    fair_weight: Optional[float] = None,
    diff_weight: Optional[float] = None,
    laplacian_weight: Optional[float] = None,
) -> Tuple[_F64_2, str]: ...
def read_surfaces(path: str, skip_unreadable: bool) -> Tuple[str, List[str]]: ...
def write_surfaces(path: str, surfaces: str) -> None: ...
def surface_highlight_lines(
    surfaces: str,
    circle_center: Optional[Sequence[float]] = None,
    circle_axis: Optional[Sequence[float]] = None,
    radii: Optional[Sequence[float]] = None,
    band: Optional[float] = None,
    grid: int = 200,
    surface: Optional[int] = None,
    direction: Optional[Sequence[float]] = None,
    plane_normal: Optional[Sequence[float]] = None,
    up: str = "auto",
    plane_point: Optional[Sequence[float]] = None,
    spacing: Optional[float] = None,
    lights: Optional[str] = None,
    min_normal_cos: Optional[float] = None,
    circular: bool = False,
) -> Tuple[str, str]: ...
def surface_deviation(
    surfaces: str,
    v1: _F64_2,
    indices1: _U32,
    offsets1: _U32,
    grid: int = 64,
    region: Optional[Sequence[int]] = None,
    bins: int = 41,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_], str]: ...
def surface_iso_curves(
    surfaces: str,
    count: int = 5,
    samples: int = 200,
    surface: Optional[int] = None,
    comb_scale: float = 1.0,
) -> Tuple[Dict[str, Any], str]: ...
def surface_highlight_curves(
    surfaces: str,
    tolerance: Optional[float] = None,
    path: Optional[str] = None,
    unit: Optional[str] = None,
    circle_center: Optional[Sequence[float]] = None,
    circle_axis: Optional[Sequence[float]] = None,
    radii: Optional[Sequence[float]] = None,
    grid: int = 200,
    surface: Optional[int] = None,
    direction: Optional[Sequence[float]] = None,
    plane_normal: Optional[Sequence[float]] = None,
    up: str = "auto",
    plane_point: Optional[Sequence[float]] = None,
    spacing: Optional[float] = None,
    lights: Optional[str] = None,
    min_normal_cos: Optional[float] = None,
    circular: bool = False,
) -> Tuple[List[Dict[str, Any]], str]: ...
def fair_surface(
    surfaces: str,
    lights: str,
    endpoints: str,
    surface: int = 0,
    max_iterations: Optional[int] = None,
    epsilon: Optional[float] = None,
    truncation: Optional[float] = None,
    min_truncation: Optional[float] = None,
    sample_spacing: Optional[float] = None,
    grid: Optional[int] = None,
    method: str = "regularised",
    boundary: str = "fixed",
    keep_weight: Optional[float] = None,
    fairness_weight: Optional[float] = None,
    damped_step: Optional[float] = None,
    damping: str = "residual",
) -> Tuple[str, str]: ...

class Mesh:
    """A mesh with its connectivity built once (python/src/mesh.rs); the
    package's ``fairline.Mesh`` subclasses it."""

    def __new__(cls, v: _F64_2, indices: _U32, offsets: _U32) -> "Mesh": ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def face_count(self) -> int: ...
    @property
    def is_triangle_mesh(self) -> bool: ...
    def _vertex_normals(self) -> _F64_2: ...
    def _curvature(
        self, method: str = "rusinkiewicz"
    ) -> Tuple[List[Tuple[str, npt.NDArray[np.float64]]], str]: ...
    # ("csr", data, indices, indptr, n) or ("coo", data, rows, cols, n)
    def _cotangent_laplacian(
        self,
    ) -> Tuple[str, npt.NDArray[np.float64], npt.NDArray[np.int64], npt.NDArray[np.int64], int]: ...
    def _vertex_areas(self) -> npt.NDArray[np.float64]: ...
    def _smooth(
        self,
        method: str = "taubin",
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
    ) -> Tuple[_F64_2, str, Optional[str]]: ...
    # points (N, 3), offsets (L + 1,), index (L,), closed (L,), radius (L,)?;
    # with a band also band_radius, lower, upper
    def _highlight_lines(
        self,
        direction: Optional[Sequence[float]] = None,
        plane_normal: Optional[Sequence[float]] = None,
        up: str = "auto",
        plane_point: Optional[Sequence[float]] = None,
        spacing: Optional[float] = None,
        lights: Optional[str] = None,
        min_normal_cos: Optional[float] = None,
        circle_center: Optional[Sequence[float]] = None,
        circle_axis: Optional[Sequence[float]] = None,
        radii: Optional[Sequence[float]] = None,
        band: Optional[float] = None,
    ) -> Tuple[Dict[str, Any], str]: ...
    def _highlight_curves(
        self,
        tolerance: Optional[float] = None,
        path: Optional[str] = None,
        unit: Optional[str] = None,
        direction: Optional[Sequence[float]] = None,
        plane_normal: Optional[Sequence[float]] = None,
        up: str = "auto",
        plane_point: Optional[Sequence[float]] = None,
        spacing: Optional[float] = None,
        lights: Optional[str] = None,
        min_normal_cos: Optional[float] = None,
        circle_center: Optional[Sequence[float]] = None,
        circle_axis: Optional[Sequence[float]] = None,
        radii: Optional[Sequence[float]] = None,
    ) -> Tuple[List[Dict[str, Any]], str]: ...
