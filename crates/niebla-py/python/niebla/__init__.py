"""niebla: physically based rendering of participating media (fog, smoke,
clouds, fire) from Python.

    import niebla
    scene = niebla.Scene.from_file("scenes/smoke.json")
    image = scene.render("volpath", spp=16)        # (H, W, 3) float32
    niebla.write_exr(image, "smoke.exr")

Units and conventions (the renderer's, see ARCHITECTURE.md):

- lengths are in scene units; optical coefficients (``sigma_a``,
  ``sigma_s``, ``sigma_t``) are per scene unit; angles in degrees;
- images are linear radiance, W/(sr m^2) of the scene's length unit, linear
  Rec.709 RGB, as numpy arrays of shape (H, W, 3) and dtype float32, row 0 at
  the top of the image and column 0 at its left;
- density arrays have shape (nz, ny, nx) and are indexed ``[z][y][x]`` (x
  fastest, as ``.npy`` and ``.vol`` files); their values sit at the cell
  centers of a box given in the medium's own space (the medium's
  ``to_world`` places that box in the world); y is up, so ``density[:, 0, :]``
  is the bottom slice, not the top row of an image;
- a scene, a seed and a sample count determine the image bit for bit: the
  same render from Python and from the ``niebla`` command gives the same
  float32 values, whatever the number of threads.

Errors in a scene (a dict or a file) raise :class:`SceneError`, a
``ValueError`` whose message names the file and the JSON path of the bad
value, exactly as the ``niebla`` command reports it.
"""

from __future__ import annotations

import json
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _niebla
from ._niebla import INTEGRATORS, RenderError, SceneError, __version__

__all__ = [
    "INTEGRATORS",
    "RenderError",
    "RenderStats",
    "SampleSums",
    "Scene",
    "SceneError",
    "load_scene",
    "read_exr",
    "read_exr_layers",
    "denoise",
    "oidn_library",
    "relative_mse",
    "scene_hash",
    "write_exr",
    "write_image",
    "write_png",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]
#: ``progress(done, total)``: pixel samples done and to do (a sample budget),
#: or milliseconds spent and allowed (a time budget).
ProgressCallback = Callable[[int, int], Any]
#: An integrator: a name from :data:`INTEGRATORS`, or a dict with the schema
#: of a scene file's ``render.integrator`` (``{"type": "single", "sampling": "mis"}``).
IntegratorSpec = Union[str, Mapping[str, Any]]
Vec3 = Sequence[float]


@dataclass(frozen=True)
class RenderStats:
    """What a finished render did."""

    #: Integrator name.
    integrator: str
    #: Samples per pixel rendered.
    spp: int
    #: Wall-clock time in seconds.
    seconds: float


class Scene:
    """A scene ready to render: the JSON description of a scene file, parsed,
    checked and built by the renderer.

    Make one with :meth:`from_file`, :meth:`from_dict` or :meth:`from_json`.
    """

    def __init__(self, native: "_niebla.Scene") -> None:
        self._native = native
        #: Statistics of the last :meth:`render`, or None.
        self.last_render: Optional[RenderStats] = None

    # ----------------------------------------------------------------- making

    @classmethod
    def from_file(
        cls, path: PathLike, defines: Optional[Mapping[str, Any]] = None, frame: Optional[int] = None
    ) -> "Scene":
        """Load a scene file: niebla JSON (version 1), or a Mitsuba 3 XML
        scene (``.xml``, converted as ``niebla convert`` does; ``defines``
        sets its ``<default>`` parameters like ``-D name=value``, and what it
        accepts without effect is raised as ``UserWarning``). Relative paths
        inside it resolve against the file's folder. Raises
        :class:`SceneError` (with the file, the JSON path or XML line, and
        the message of the ``niebla`` command). With ``frame``, the scene of
        that frame of a sequence as ``niebla render --frames`` renders it:
        keyframed camera and lights at that frame, and frame patterns in file
        names (``smoke.####.vdb``, ``{frame:04}``) replaced."""
        d = {str(k): str(v) for k, v in (defines or {}).items()}
        return cls(_niebla.Scene.from_file(os.fspath(path), d, frame))

    @classmethod
    def from_dict(cls, desc: Mapping[str, Any], base_dir: PathLike = ".", name: str = "<dict>") -> "Scene":
        """Build a scene from a dict with the schema of a scene file.

        The dict is written as JSON text and read by the same parser as a
        file, so mistakes raise :class:`SceneError` with the same messages
        and JSON paths (``"<dict>: media.fog.sigma_s[2]: ..."``). numpy
        arrays and numbers inside it are accepted. Relative file names
        resolve against ``base_dir``; ``name`` stands for the file name in
        messages.
        """
        _check_finite(desc, "", name)
        text = json.dumps(desc, default=_json_default, allow_nan=False)
        return cls(_niebla.Scene.from_json(text, name, os.path.abspath(os.fspath(base_dir))))

    @classmethod
    def from_json(cls, text: str, base_dir: PathLike = ".", name: str = "<json>") -> "Scene":
        """Build a scene from JSON text with the schema of a scene file."""
        return cls(_niebla.Scene.from_json(text, name, os.path.abspath(os.fspath(base_dir))))

    def to_dict(self) -> Dict[str, Any]:
        """The scene description as a dict (densities set from arrays appear
        as inline ``grid`` sources), so ``Scene.from_dict(s.to_dict(),
        s.base_dir)`` rebuilds the same scene."""
        return json.loads(self._native.to_json())

    def to_json(self) -> str:
        """The scene description as JSON text (see :meth:`to_dict`)."""
        return self._native.to_json()

    def view(self, port: int = 0, host: str = "127.0.0.1", open: bool = False, threads: Optional[int] = None) -> "_niebla.Viewer":
        """Serve a live, editable, progressive view of this scene to the
        browser, as ``niebla view`` does, and return the running viewer:
        ``viewer.url`` (with its access token) is the page's address,
        ``viewer.stop()`` ends it (so does leaving a ``with`` block or
        dropping the object). Saved images and scenes go to the scene's
        folder (``base_dir``). In a notebook the viewer shows as a link.
        """
        viewer = self._native.view(port, host, open, threads)
        print(f"niebla view: {viewer.url}")
        return viewer

    # ------------------------------------------------------------- properties

    @property
    def width(self) -> int:
        """Image width in pixels."""
        return self._native.width

    @property
    def height(self) -> int:
        """Image height in pixels."""
        return self._native.height

    @property
    def spp(self) -> int:
        """Samples per pixel the scene asks for (``render.spp``)."""
        return self._native.spp

    @property
    def seed(self) -> int:
        """Sampler seed the scene asks for (``render.seed``)."""
        return self._native.seed

    @property
    def exposure(self) -> float:
        """PNG exposure in stops the scene asks for (``render.exposure``)."""
        return self._native.exposure

    @property
    def integrator(self) -> str:
        """Name of the scene's integrator (``render.integrator.type``)."""
        return self._native.integrator

    @property
    def media(self) -> List[str]:
        """Names of the scene's media, sorted."""
        return self._native.media

    @property
    def source(self) -> str:
        """Name of the description in messages: the file, or ``<dict>``."""
        return self._native.source

    @property
    def base_dir(self) -> Path:
        """Folder that relative file names in the description resolve against."""
        return Path(self._native.base_dir)

    def __repr__(self) -> str:
        return repr(self._native)

    # ------------------------------------------------------------------ edits

    def set_density(
        self,
        medium: str,
        density: np.ndarray,
        bounds: Tuple[Vec3, Vec3] = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
    ) -> None:
        """Replace the density of ``medium`` by a voxel array.

        ``density`` has shape (nz, ny, nx) and is indexed ``density[z, y, x]``
        (x fastest; float32 or float64, finite, >= 0; a dimensionless factor
        of the medium's coefficients). Value ``density[k, j, i]`` sits at the
        center of cell (i, j, k) of the box ``bounds = (min, max)``, given in
        scene units in the medium's own space (the medium's ``to_world``
        places the box in the world): at ``x = min.x + (i + 0.5) * (max.x -
        min.x) / nx``, and likewise for y with ``j, ny`` and z with ``k,
        nz``. Between centers the density is trilinear, within half a cell
        of a face it is the nearest cell's value, and outside the box it is
        zero. y is up: ``density[:, 0, :]`` is the bottom slice.

        A homogeneous medium becomes a grid medium with the same coefficients
        per unit density (and, if it emits, ``L_ve`` times the density).
        The scene is rebuilt at once; on an error it is left unchanged.
        """
        if not isinstance(density, np.ndarray):
            density = np.asarray(density)
        if density.dtype not in (np.float32, np.float64):
            density = density.astype(np.float64)
        if density.ndim != 3:
            raise ValueError(f"density: expected an array of shape (nz, ny, nx), got shape {density.shape}")
        lo, hi = (tuple(float(v) for v in corner) for corner in bounds)
        if len(lo) != 3 or len(hi) != 3:
            raise ValueError(f"bounds: expected ((x, y, z), (x, y, z)), got {bounds!r}")
        self._native.set_density(medium, density, (lo, hi))

    def set_density_vdb(self, medium: str, file: PathLike, grid: str = "density") -> None:
        """Replace the density of ``medium`` by the float grid ``grid`` of an
        OpenVDB file. A relative ``file`` is taken relative to the current
        folder. The grid keeps its own index-to-world transform (values at
        integer index points); the medium's ``to_world`` applies after it."""
        self._native.set_density_vdb(medium, os.path.abspath(os.fspath(file)), grid)

    # ----------------------------------------------------------------- render

    def render(
        self,
        integrator: Optional[IntegratorSpec] = None,
        *,
        spp: Optional[int] = None,
        time: Optional[float] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: Union[None, bool, ProgressCallback] = None,
    ) -> np.ndarray:
        """Render the scene; returns linear radiance as an (H, W, 3) float32
        array (row 0 at the top).

        ``integrator``: None for the scene's own; a name (``"volpath"``,
        ``"single"``, ``"emission"``, see :data:`INTEGRATORS`) keeps the
        scene's parameters when the scene uses that integrator and takes
        defaults otherwise (as ``niebla render --integrator``); a dict is a
        full ``render.integrator`` object, e.g. ``{"type": "single",
        "sampling": "mis"}``.

        ``spp`` (samples per pixel; default the scene's) or ``time`` (seconds
        of wall-clock time: passes that double the sample count run while the
        next one fits). ``seed`` defaults to the scene's; ``threads`` to all
        cores (the image does not depend on it).

        ``progress``: None shows a tqdm bar when tqdm is installed and the
        output is a terminal or a notebook; False shows nothing; True always
        uses tqdm; a callable is called as ``progress(done, total)`` (pixel
        samples for a sample budget, milliseconds for a time budget) on this
        thread about every 50 ms.

        The GIL is released while rendering. Ctrl-C stops the render within
        a tile and raises KeyboardInterrupt; an exception raised by the
        progress callback stops it too and propagates.
        """
        if isinstance(integrator, str):
            name = integrator
            integrator_json = None if name == self.integrator else json.dumps({"type": name})
        elif integrator is None:
            name, integrator_json = self.integrator, None
        else:
            name = str(integrator.get("type", "single"))
            integrator_json = json.dumps(integrator, default=_json_default, allow_nan=False)
        callback, close = _progress_callback(progress, time)
        try:
            image, spp_done, seconds = self._native.render(integrator_json, spp, seed, time, threads, callback)
        finally:
            close()
        self.last_render = RenderStats(name, spp_done, seconds)
        return image

    def render_layers(
        self,
        aovs: Union[str, Sequence[str]],
        integrator: Optional[IntegratorSpec] = None,
        *,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: Union[None, bool, ProgressCallback] = None,
    ) -> Dict[str, np.ndarray]:
        """Render the scene with layers beside the beauty; returns a dict of
        float32 arrays: ``beauty`` (H, W, 3) and each layer asked for
        (``aovs``: names or ``"all"``): ``alpha`` and ``depth`` (H, W),
        ``direct``, ``indirect``, ``emission``, ``surface``, ``albedo``,
        ``normal``, ``variance`` (H, W, 3); alpha is added when the scene's
        film is transparent. The values are those ``niebla render --aovs``
        writes for the same scene, seed and spp. The split layers
        (direct, indirect, emission, surface) need ``volpath``. The other
        arguments are those of :meth:`render`.
        """
        names = aovs if isinstance(aovs, str) else ",".join(aovs)
        integrator_json = self._integrator_json(integrator)
        callback, close = _progress_callback(progress, None)
        try:
            layers, spp_done, seconds = self._native.render_layers(names, integrator_json, spp, seed, threads, callback)
        finally:
            close()
        name = integrator if isinstance(integrator, str) else self.integrator
        self.last_render = RenderStats(str(name), spp_done, seconds)
        return layers

    def render_sums(
        self,
        integrator: Optional[IntegratorSpec] = None,
        *,
        first_sample: int = 0,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: Union[None, bool, ProgressCallback] = None,
    ) -> "SampleSums":
        """Render samples ``first_sample .. first_sample + spp`` of every
        pixel and return their exact per-pixel sums (:class:`SampleSums`).

        Sums of disjoint sample ranges add up (``a + b``) to the sums of
        their union, exactly, and ``sums.image()`` is bit for bit the image
        :meth:`render` gives for the same samples: a render can be split into
        sample ranges over processes or machines (``niebla.distributed``).
        The other arguments are those of :meth:`render`.
        """
        integrator_json = self._integrator_json(integrator)
        callback, close = _progress_callback(progress, None)
        try:
            words, spp_done, seconds, key = self._native.render_sums(
                integrator_json, int(first_sample), spp, seed, threads, callback
            )
        finally:
            close()
        used_seed = self.seed if seed is None else int(seed)
        return SampleSums(words, [(int(first_sample), int(first_sample) + spp_done)], used_seed, key)

    def integrator_key(self, integrator: Optional[IntegratorSpec] = None) -> str:
        """The stable key of an integrator's settings (None: the scene's) with
        the scene's sampler (``; sampler=sobol`` appended for Sobol), as
        checkpoints record it."""
        return self._native.integrator_key(self._integrator_json(integrator))

    def _integrator_json(self, integrator: Optional[IntegratorSpec]) -> Optional[str]:
        """JSON text of an integrator argument for the native calls (None: the scene's)."""
        if integrator is None or integrator == self.integrator:
            return None
        if isinstance(integrator, str):
            return json.dumps({"type": integrator})
        return json.dumps(integrator, default=_json_default, allow_nan=False)


@dataclass
class SampleSums:
    """Exact per-pixel sums of the samples of some sample ranges of a render.

    ``words`` is an (H, W, 3, 4) int64 array: per pixel and RGB channel the
    fixed-point sum ``round(sample * 2**60)`` over the samples, written as
    32-bit words ``w0 + w1 * 2**32 + w2 * 2**64 + w3 * 2**96``. Adding two
    such arrays with numpy's ``+`` adds the sums exactly, in any order, so
    renders of disjoint sample ranges merge to the render of their union bit
    for bit. ``ranges`` are the half-open sample index ranges held, sorted;
    ``seed`` the sampler seed; ``integrator`` the integrator's settings key.
    """

    words: np.ndarray
    ranges: List[Tuple[int, int]]
    seed: int
    integrator: str

    @property
    def spp(self) -> int:
        """Samples per pixel held."""
        return sum(end - start for start, end in self.ranges)

    def image(self) -> np.ndarray:
        """The mean of the samples: an (H, W, 3) float32 array, bit for bit
        the image of one render of these samples."""
        return _niebla.sums_to_image(self.words, self.spp)

    def __add__(self, other: "SampleSums") -> "SampleSums":
        """The sums of both (same seed, integrator and size; disjoint ranges)."""
        if (self.seed, self.integrator) != (other.seed, other.integrator):
            raise ValueError(
                f"cannot add sums of seed {other.seed} / {other.integrator} to seed {self.seed} / {self.integrator}"
            )
        if self.words.shape != other.words.shape:
            raise ValueError(f"cannot add sums of shape {other.words.shape} to {self.words.shape}")
        ranges = _join_ranges(self.ranges + other.ranges)
        return SampleSums(self.words + other.words, ranges, self.seed, self.integrator)

    def write_exr(self, path: PathLike, scene_hash: str) -> None:
        """Write as a niebla checkpoint EXR (the mean image, the sums, the
        sample ranges, seed, ``scene_hash`` and integrator in the header),
        atomically; ``niebla merge`` and :meth:`read_exr` read it."""
        _niebla.write_sums_exr(self.words, os.fspath(path), self.ranges, self.seed, scene_hash, self.integrator)

    @staticmethod
    def read_exr(path: PathLike) -> Tuple["SampleSums", str]:
        """Read a checkpoint EXR (of :meth:`write_exr` or ``niebla render``):
        the sums and the scene hash it records."""
        words, ranges, seed, scene_hash, integrator = _niebla.read_sums_exr(os.fspath(path))
        return SampleSums(words, [tuple(r) for r in ranges], seed, integrator), scene_hash


def scene_hash(text: Union[str, bytes]) -> str:
    """The 64-bit FNV-1a hash of a scene's text as 16 hex digits, as the
    ``niebla`` command records it in checkpoints (of the scene file's bytes)."""
    data = text.encode() if isinstance(text, str) else text
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def _join_ranges(ranges: Sequence[Tuple[int, int]]) -> List[Tuple[int, int]]:
    """Sorted half-open ranges with touching ones joined; ValueError if two overlap."""
    out: List[Tuple[int, int]] = []
    for start, end in sorted(ranges):
        if out and start < out[-1][1]:
            raise ValueError(f"sample ranges {out[-1][0]}..{out[-1][1]} and {start}..{end} overlap")
        if out and start == out[-1][1]:
            out[-1] = (out[-1][0], end)
        else:
            out.append((start, end))
    return out


def load_scene(path: PathLike) -> Scene:
    """Load a scene file; the same as :meth:`Scene.from_file`."""
    return Scene.from_file(path)


def write_exr(image: np.ndarray, path: PathLike) -> None:
    """Write an (H, W, 3) image of linear radiance to an OpenEXR file (float32,
    unclamped, lossless), through a temporary file renamed into place. The
    bytes are those the ``niebla`` command writes for the same image."""
    _niebla.write_exr(image, os.fspath(path))


def write_png(image: np.ndarray, path: PathLike, exposure: float = 0.0) -> None:
    """Write an (H, W, 3) image to an 8-bit sRGB PNG: radiance times
    ``2**exposure`` (exposure in stops), the sRGB curve, clamped."""
    _niebla.write_png(image, os.fspath(path), float(exposure))


def write_image(image: np.ndarray, path: PathLike, exposure: float = 0.0) -> None:
    """Write ``.exr`` or ``.png`` by the file's extension (exposure applies to PNG only)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".exr":
        write_exr(image, path)
    elif suffix == ".png":
        write_png(image, path, exposure)
    else:
        raise ValueError(f"{os.fspath(path)}: unsupported image extension (expected .exr or .png)")


def read_exr(path: PathLike) -> np.ndarray:
    """Read an OpenEXR file's RGB channels into an (H, W, 3) float32 array."""
    return _niebla.read_exr(os.fspath(path))


def oidn_library() -> Optional[str]:
    """The Intel Open Image Denoise library :func:`denoise` loads: the file
    named by ``NIEBLA_OIDN_LIBRARY``, else the one shipped in the ``pyoidn``
    wheel when that package is installed (``pip install pyoidn``), else None
    (the dynamic loader's search path)."""
    given = os.environ.get("NIEBLA_OIDN_LIBRARY")
    if given:
        return given
    import importlib.util

    spec = importlib.util.find_spec("pyoidn")
    if spec is not None and spec.submodule_search_locations:
        for folder in spec.submodule_search_locations:
            candidate = Path(folder) / "oidn" / "lib" / "libOpenImageDenoise.so.2"
            if candidate.exists():
                return str(candidate)
    return None


def denoise(
    image: np.ndarray, albedo: Optional[np.ndarray] = None, normal: Optional[np.ndarray] = None
) -> np.ndarray:
    """Denoise a render ((H, W, 3) linear radiance) with Intel Open Image
    Denoise on the CPU, guided by the ``albedo`` and ``normal`` layers of
    :meth:`Scene.render_layers` (a normal needs the albedo too); returns a
    new (H, W, 3) float32 array. Raises RuntimeError with install advice
    when the library is missing (:func:`oidn_library`)."""
    return _niebla.denoise(image, albedo, normal, oidn_library())


def read_exr_layers(path: PathLike) -> Dict[str, np.ndarray]:
    """Read an OpenEXR file written by ``niebla render --aovs`` into the dict
    :meth:`Scene.render_layers` returns (``beauty`` and each layer)."""
    return _niebla.read_exr_layers(os.fspath(path))


def relative_mse(image: np.ndarray, reference: np.ndarray) -> float:
    """niebla's relative mean squared error (dimensionless): the mean over
    pixels and channels of ``(x - r)**2 / (r**2 + eps)``, with ``eps = (0.01 *
    mean(reference))**2`` so black reference pixels do not dominate."""
    return _niebla.relative_mse(image, reference)


# --------------------------------------------------------------------- helpers


def _json_default(value: Any) -> Any:
    """JSON for numpy values and paths inside scene dicts."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{type(value).__name__} is not allowed in a scene description")


def _check_finite(value: Any, path: str, name: str) -> None:
    """Raise SceneError at the JSON path of the first NaN or infinity (JSON
    has no way to write them, so the parser would only see a syntax error)."""
    if isinstance(value, (float, np.floating)) and not math.isfinite(value):
        error = SceneError(f"{name}: {path}: must be a finite number, got {value}")
        error.file, error.path, error.message = name, path, f"must be a finite number, got {value}"
        raise error
    if isinstance(value, Mapping):
        for key, item in value.items():
            _check_finite(item, f"{path}.{key}" if path else str(key), name)
    elif isinstance(value, (list, tuple)):
        for i, item in enumerate(value):
            _check_finite(item, f"{path}[{i}]", name)
    elif isinstance(value, np.ndarray) and value.dtype.kind == "f" and not np.isfinite(value).all():
        index = np.argwhere(~np.isfinite(value))[0]
        _check_finite(float(value[tuple(index)]), path + "".join(f"[{i}]" for i in index), name)


def _in_notebook() -> bool:
    shell = sys.modules.get("IPython")
    try:
        return shell is not None and type(shell.get_ipython()).__name__ == "ZMQInteractiveShell"
    except Exception:
        return False


def _progress_callback(
    progress: Union[None, bool, ProgressCallback], time: Optional[float]
) -> Tuple[Optional[ProgressCallback], Callable[[], None]]:
    """The callback to hand to the renderer and a function that closes any bar."""
    if callable(progress):
        return progress, lambda: None
    if progress is False:
        return None, lambda: None
    try:
        if _in_notebook():
            from tqdm.auto import tqdm
        else:
            from tqdm import tqdm
    except ImportError:
        if progress is True:
            raise
        return None, lambda: None
    if progress is None and not (_in_notebook() or sys.stderr.isatty()):
        return None, lambda: None
    if time is not None:
        bar = tqdm(total=round(float(time), 1), unit="s", desc="niebla", leave=False)
        scale = 0.001
    else:
        bar = tqdm(total=None, unit="samples", unit_scale=True, desc="niebla", leave=False)
        scale = 1.0

    def update(done: int, total: int) -> None:
        if bar.total is None:
            bar.total = total
        bar.n = round(done * scale, 1) if scale != 1.0 else done
        bar.refresh()

    return update, bar.close
