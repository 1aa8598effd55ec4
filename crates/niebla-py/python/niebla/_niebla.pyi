"""Type stubs of the native module ``niebla._niebla`` (PyO3). The public API
is the ``niebla`` package, which wraps it; units are documented there."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
#: Names of the integrators this build can run.
INTEGRATORS: List[str]

class SceneError(ValueError):
    """A mistake in a scene description; ``str(e)`` is ``"{file}: {path}: {message}"``."""

    #: The scene file, or ``<dict>`` / ``<json>``.
    file: str
    #: JSON path of the bad value, e.g. ``media.fog.sigma_s[2]``; empty for whole-file errors.
    path: str
    #: What is wrong and what was expected.
    message: str

class RenderError(RuntimeError):
    """A render that could not run."""

_Path = Union[str, PathLike[str]]
_Vec3 = Sequence[float]

class Viewer:
    @property
    def url(self) -> str: ...
    @property
    def running(self) -> bool: ...
    def stop(self) -> None: ...
    def __enter__(self) -> Viewer: ...
    def __exit__(self, *args: object) -> None: ...

class Scene:
    def view(self, port: int = 0, host: str = "127.0.0.1", open: bool = False, threads: Optional[int] = None) -> Viewer: ...
    @staticmethod
    def from_file(path: _Path, defines: dict[str, str] = ..., frame: Optional[int] = ...) -> Scene: ...
    @staticmethod
    def from_json(text: str, source: str = "<json>", base_dir: _Path = ".") -> Scene: ...
    def to_json(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def base_dir(self) -> str: ...
    @property
    def width(self) -> int:
        """Image width in pixels."""
    @property
    def height(self) -> int:
        """Image height in pixels."""
    @property
    def spp(self) -> int:
        """Samples per pixel (``render.spp``)."""
    @property
    def seed(self) -> int: ...
    @property
    def exposure(self) -> float:
        """PNG exposure in stops."""
    @property
    def integrator(self) -> str: ...
    @property
    def media(self) -> List[str]: ...
    def set_density(
        self,
        medium: str,
        density: Union[npt.NDArray[np.float32], npt.NDArray[np.float64]],
        bounds: Tuple[_Vec3, _Vec3],
    ) -> None:
        """Density from a (nz, ny, nx) array indexed [z][y][x], values at the cell
        centers of ``bounds`` (scene units, the medium's own space)."""
    def set_density_vdb(self, medium: str, file: _Path, grid: str = "density") -> None: ...
    def render(
        self,
        integrator: Optional[str] = None,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        time: Optional[float] = None,
        threads: Optional[int] = None,
        progress: Optional[Callable[[int, int], Any]] = None,
    ) -> Tuple[npt.NDArray[np.float32], int, float]:
        """Returns (image (H, W, 3) float32 linear radiance, spp rendered, seconds)."""
    def render_sums(
        self,
        integrator: Optional[str] = None,
        first_sample: int = 0,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: Optional[Callable[[int, int], Any]] = None,
    ) -> Tuple[npt.NDArray[np.int64], int, float, str]:
        """Returns (exact sums as (H, W, 3, 4) int64 32-bit words, spp rendered, seconds, integrator key)."""
    def integrator_key(self, integrator: Optional[str] = None) -> str: ...
    def render_layers(
        self,
        aovs: str,
        integrator: Optional[str] = None,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: Optional[Callable[[int, int], Any]] = None,
    ) -> Tuple[Dict[str, npt.NDArray[np.float32]], int, float]:
        """Returns (layers by name, beauty included, spp rendered, seconds)."""

def write_exr(image: npt.NDArray[np.floating[Any]], path: _Path) -> None: ...
def read_exr_layers(path: _Path) -> Dict[str, npt.NDArray[np.float32]]: ...
def denoise(
    image: npt.NDArray[np.floating[Any]],
    albedo: Optional[npt.NDArray[np.floating[Any]]] = None,
    normal: Optional[npt.NDArray[np.floating[Any]]] = None,
    library: Optional[_Path] = None,
) -> npt.NDArray[np.float32]: ...
def write_png(image: npt.NDArray[np.floating[Any]], path: _Path, exposure: float = 0.0) -> None: ...
def read_exr(path: _Path) -> npt.NDArray[np.float32]: ...
def relative_mse(image: npt.NDArray[np.floating[Any]], reference: npt.NDArray[np.floating[Any]]) -> float: ...
def sums_to_image(words: npt.NDArray[np.int64], spp: int) -> npt.NDArray[np.float32]: ...
def write_sums_exr(
    words: npt.NDArray[np.int64],
    path: _Path,
    ranges: Sequence[Tuple[int, int]],
    seed: int,
    scene_hash: str,
    integrator: str,
) -> None: ...
def read_sums_exr(path: _Path) -> Tuple[npt.NDArray[np.int64], List[Tuple[int, int]], int, str, str]: ...
