"""Rendering across processes and machines with Dask (``pip install
niebla[distributed]``).

    from dask.distributed import Client
    import niebla.distributed

    client = Client("tcp://scheduler:8786")        # or None: a LocalCluster
    result = niebla.distributed.render("smoke.json", spp=4096, chunk_spp=64, client=client)
    niebla.write_exr(result.image(), "smoke.exr")

:func:`render` splits the sample indices ``0 .. spp`` into chunks of
``chunk_spp`` consecutive samples; each chunk is one Dask task that renders
that sample range on a worker (:meth:`niebla.Scene.render_sums`) and returns
the exact per-pixel sums (:class:`niebla.SampleSums`). Sample ``s`` of pixel
``(x, y)`` depends only on ``(seed, x, y, s)``, and the sums are integers
(fixed point), so adding the chunks gives exactly the sums of one render of
all the samples: the image is bit for bit the one-process render, whatever
the number of workers, the order in which chunks finish, or retries after a
worker died.

:func:`render_frames` renders one frame per task (each frame a scene of its
own) and writes each output file atomically.

Scenes travel as their description (JSON) plus the files they name (grids,
tables, environment maps: every ``"file"`` field). By default workers read
those files by their absolute path (a shared filesystem, the common case on
clusters); ``ship_files=True`` sends the files' bytes to every worker once
(Dask's scatter), and workers write them to a local temporary folder. A
worker that cannot read a file fails its task with an error naming the file,
and the render raises it.
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import SampleSums, Scene, SceneError, _join_ranges, _json_default, scene_hash, write_image

__all__ = ["ChunkError", "SceneSpec", "render", "render_frames", "split_samples"]

#: A scene given to this module: a scene file's path, a scene dict (relative
#: file names resolve against the current folder), or a :class:`niebla.Scene`.
SceneSpec = Union[str, "os.PathLike[str]", Mapping[str, Any], Scene]


class ChunkError(RuntimeError):
    """A task failed on a worker for a reason in the scene (for example a
    file it could not read); ``str(e)`` is the worker's message, which names
    the file."""


@dataclass(frozen=True)
class _Job:
    """What a worker needs to build the scene: its description as JSON text,
    the folder relative file names resolve against, and the files to write
    locally first (``ship_files``), by the path the description uses."""

    text: str
    base_dir: str
    name: str
    shipped: Tuple[str, ...] = ()


# ---------------------------------------------------------------- splitting


def split_samples(first: int, end: int, chunk_spp: int) -> List[Tuple[int, int]]:
    """The sample range ``first .. end`` cut into consecutive chunks of
    ``chunk_spp`` samples (the last one shorter when ``chunk_spp`` does not
    divide the count).

    >>> split_samples(0, 10, 4)
    [(0, 4), (4, 8), (8, 10)]
    """
    if chunk_spp < 1:
        raise ValueError(f"chunk_spp: must be at least 1, got {chunk_spp}")
    return [(s, min(s + chunk_spp, end)) for s in range(first, end, chunk_spp)]


def _missing(spp: int, done: Sequence[Tuple[int, int]]) -> List[Tuple[int, int]]:
    """The parts of ``0 .. spp`` that the sorted disjoint ranges ``done`` do not cover."""
    out, at = [], 0
    for start, end in done:
        if start > at:
            out.append((at, min(start, spp)))
        at = max(at, end)
    if at < spp:
        out.append((at, spp))
    return [r for r in out if r[0] < r[1]]


# ------------------------------------------------------------------- scenes


def _describe(scene: SceneSpec) -> Tuple[Dict[str, Any], str, str, str]:
    """(description dict, base folder, name for messages, scene hash) of a scene."""
    if isinstance(scene, Scene):
        desc = scene.to_dict()
        text = json.dumps(desc, sort_keys=True)
        return desc, str(scene.base_dir), scene.source, scene_hash(text)
    if isinstance(scene, Mapping):
        text = json.dumps(scene, default=_json_default, allow_nan=False, sort_keys=True)
        return json.loads(text), os.getcwd(), "<dict>", scene_hash(text)
    path = Path(scene).resolve()
    data = path.read_bytes()
    # The hash of the file's bytes is the one `niebla render` records, so
    # checkpoints of both can be merged.
    return json.loads(data), str(path.parent), str(path), scene_hash(data)


def _file_fields(value: Any, found: List[Tuple[Dict[str, Any], str]]) -> None:
    """Collect (object, key) of every string ``"file"`` field in a description."""
    if isinstance(value, dict):
        for key, item in value.items():
            if key == "file" and isinstance(item, str):
                found.append((value, key))
            else:
                _file_fields(item, found)
    elif isinstance(value, list):
        for item in value:
            _file_fields(item, found)


def _make_job(desc: Dict[str, Any], base_dir: str, name: str, ship_files: bool) -> Tuple[_Job, Dict[str, bytes]]:
    """The job of a scene, with its file names made absolute; with
    ``ship_files`` also the files' bytes by absolute path (a file missing
    here raises FileNotFoundError naming it)."""
    desc = copy.deepcopy(desc)
    fields: List[Tuple[Dict[str, Any], str]] = []
    _file_fields(desc, fields)
    files: Dict[str, bytes] = {}
    for obj, key in fields:
        path = os.path.normpath(os.path.join(base_dir, obj[key]))
        obj[key] = path
        if ship_files and path not in files:
            files[path] = Path(path).read_bytes()
    job = _Job(json.dumps(desc), base_dir, name, tuple(sorted(files)))
    return job, files


# Per worker process: built scenes by job (a worker renders many chunks of one
# scene; parsing and building it once saves that time per chunk), and the
# folders holding shipped files by content hash.
_SCENES: Dict[_Job, Scene] = {}
_SHIPPED: Dict[str, str] = {}


def _local_copies(files: Mapping[str, bytes]) -> Dict[str, str]:
    """Write shipped files to this worker's temporary folder (once per
    content) and return the local path of each original path."""
    local = {}
    for path, data in files.items():
        digest = hashlib.sha256(data).hexdigest()[:20]
        if digest not in _SHIPPED:
            folder = tempfile.mkdtemp(prefix="niebla-shipped-")
            target = os.path.join(folder, os.path.basename(path))
            with open(target + ".tmp", "wb") as f:
                f.write(data)
            os.replace(target + ".tmp", target)
            _SHIPPED[digest] = target
        local[path] = _SHIPPED[digest]
    return local


def _worker_scene(job: _Job, files: Optional[Mapping[str, bytes]]) -> Scene:
    """The scene of ``job`` on this worker (built once per process)."""
    if job in _SCENES:
        return _SCENES[job]
    desc = json.loads(job.text)
    if files:
        local = _local_copies(files)
        fields: List[Tuple[Dict[str, Any], str]] = []
        _file_fields(desc, fields)
        for obj, key in fields:
            obj[key] = local.get(obj[key], obj[key])
    try:
        scene = Scene.from_dict(desc, job.base_dir, job.name)
    except (SceneError, OSError) as e:
        # A plain exception with the renderer's message (which names the
        # file) travels back to the client whatever the worker's packages.
        raise ChunkError(f"on worker {_worker_name()}: {e}") from None
    if len(_SCENES) >= 4:
        _SCENES.clear()
    _SCENES[job] = scene
    return scene


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except Exception:
        return f"pid {os.getpid()}"


def _render_chunk(
    job: _Job,
    files: Optional[Mapping[str, bytes]],
    integrator: Optional[Any],
    first: int,
    end: int,
    seed: Optional[int],
    threads: Optional[int],
) -> SampleSums:
    """Task: the sums of samples ``first .. end`` of the job's scene, packed
    for the trip to the client (:func:`_pack`)."""
    scene = _worker_scene(job, files)
    sums = scene.render_sums(integrator, first_sample=first, spp=end - first, seed=seed, threads=threads, progress=False)
    return _pack(sums)


#: A chunk's sums as sent: words 0..2 (uint32), word 3 (int32), ranges, seed, integrator key.
_Packed = Tuple[np.ndarray, np.ndarray, List[Tuple[int, int]], int, str]


def _pack(sums: SampleSums) -> _Packed:
    """Sums as a chunk sends them: the words of a render's sums are
    normalized (words 0..2 in [0, 2**32), word 3 a signed 32-bit value), so
    uint32 and int32 arrays hold them losslessly in half the bytes (48 per
    pixel instead of 96)."""
    low = sums.words[..., :3].astype(np.uint32)
    high = sums.words[..., 3].astype(np.int32)
    assert np.array_equal(low, sums.words[..., :3]) and np.array_equal(high, sums.words[..., 3])
    return low, high, sums.ranges, sums.seed, sums.integrator


def _render_frame(
    job: _Job, files: Optional[Mapping[str, bytes]], integrator: Optional[Any], spp: Optional[int], seed, threads
) -> np.ndarray:
    """Task: one frame's image."""
    scene = _worker_scene(job, files)
    return scene.render(integrator, spp=spp, seed=seed, threads=threads, progress=False)


# ------------------------------------------------------------------ clients


def _client(client: Any) -> Tuple[Any, Callable[[], None]]:
    """The client to use and a function that closes what was started here:
    ``client``, else the current Dask client, else a new LocalCluster."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as e:  # pragma: no cover - depends on the installation
        raise ImportError("niebla.distributed needs Dask: pip install 'niebla[distributed]'") from e
    if client is not None:
        return client, lambda: None
    try:
        from distributed import default_client

        return default_client(), lambda: None
    except ValueError:
        pass
    cluster = LocalCluster(threads_per_worker=1)
    made = Client(cluster)

    def close() -> None:
        made.close()
        cluster.close()

    return made, close


def _ship(client: Any, files: Dict[str, bytes]) -> Any:
    """The files' bytes scattered once to every worker (a future), or None."""
    if not files:
        return None
    return client.scatter([files], broadcast=True, hash=False)[0]


def _bar(progress: Union[bool, Callable[[int, int], Any]], total: int, unit: str) -> Tuple[Callable[[int], None], Callable[[], None]]:
    """(advance(n), close()) of a tqdm bar, a callable ``progress(done, total)``, or nothing."""
    if callable(progress):
        done = [0]

        def advance(n: int) -> None:
            done[0] += n
            progress(done[0], total)

        return advance, lambda: None
    if not progress:
        return lambda n: None, lambda: None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return lambda n: None, lambda: None
    bar = tqdm(total=total, unit=unit, desc="niebla", leave=False)
    return bar.update, bar.close


# ------------------------------------------------------------------- render


def render(
    scene: SceneSpec,
    spp: Optional[int] = None,
    *,
    client: Any = None,
    chunk_spp: Optional[int] = None,
    integrator: Optional[Any] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = 1,
    time_budget: Optional[float] = None,
    progress: Union[bool, Callable[[int, int], Any]] = True,
    ship_files: bool = False,
    checkpoint: Optional[Union[str, "os.PathLike[str]"]] = None,
    resume: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> SampleSums:
    """Render ``spp`` samples per pixel of ``scene`` on a Dask cluster.

    Returns the exact sums of the samples rendered (:class:`niebla.SampleSums`):
    ``result.image()`` is the (H, W, 3) float32 image, bit for bit the one
    ``niebla.Scene.render`` gives for the same scene, integrator, seed and
    ``result.spp``; ``result.ranges`` are the sample ranges it holds.

    - ``spp``: samples per pixel (default: the scene's); ``chunk_spp``:
      samples per task (default: ``spp`` split into about 4 tasks per
      worker thread). Smaller chunks balance load better and lose less
      work when a worker dies; each costs one task's overhead (scheduling
      and the transfer of its sums, 48 bytes per pixel).
    - ``integrator``, ``seed``: as in :meth:`niebla.Scene.render`;
      ``threads``: render threads per task (1: one per Dask worker thread).
    - ``client``: a ``dask.distributed.Client`` (None: the current one, or a
      new ``LocalCluster`` closed afterwards).
    - ``time_budget`` (seconds): chunks are dispatched a few at a time (two
      per worker thread) and none after the budget runs out; those already
      dispatched finish, and the result holds the samples done
      (``result.spp``, less than ``spp``, from sample 0 on).
    - ``progress``: a tqdm bar over samples (True), nothing (False), or a
      callable ``progress(samples_done, samples_total)``.
    - ``ship_files``: send the files the scene names to the workers (no
      shared filesystem) instead of letting them read the same paths.
    - ``checkpoint``: an EXR rewritten (atomically) after finished chunks,
      at most once a second and at the end, with the sums so far and their
      sample ranges in its header (``niebla merge`` reads it too);
      ``resume``: such a file (of the same scene, seed and integrator), whose
      samples are not rendered again.

    Ctrl-C (KeyboardInterrupt) cancels the tasks and is raised. A task that
    fails (a file a worker cannot read) cancels the others and raises
    :class:`ChunkError` with the worker's message.
    """
    desc, base_dir, name, hash_ = _describe(scene)
    job, files = _make_job(desc, base_dir, name, ship_files)
    client, close = _client(client)
    try:
        shipped = _ship(client, files)
        # The description travels to each worker once, not with every chunk
        # (a scene with numpy densities carries them inline); a copy on every
        # worker survives the death of any one of them.
        job = client.scatter([job], broadcast=True, hash=False)[0]
        # The scene is built on a worker first: its size, defaults and
        # integrator key, and any file a worker cannot read, are known before
        # the chunks are sent (the client need not read the files at all).
        probe = client.submit(_scene_info, job, shipped, integrator, pure=False)
        width, height, scene_spp, scene_seed, key = _result(client, [probe])[0]
        spp = int(scene_spp if spp is None else spp)
        if spp < 1:
            raise ValueError(f"spp: must be at least 1, got {spp}")
        seed = int(scene_seed if seed is None else seed)
        done: Optional[SampleSums] = None
        if resume is not None:
            done = _read_resume(resume, hash_, seed, key, width, height)
        todo = _missing(spp, done.ranges if done is not None else [])
        if chunk_spp is None:
            slots = max(1, sum(client.nthreads().values()))
            chunk_spp = max(1, -(-spp // (4 * slots)))
        chunks = [c for part in todo for c in split_samples(part[0], part[1], int(chunk_spp))]
        empty = SampleSums(np.zeros((height, width, 3, 4), np.int64), [], seed, key)
        total = _Running(done if done is not None else empty)
        last_write = [time.monotonic()]

        def on_chunk(packed: _Packed) -> None:
            total.add(packed)
            if checkpoint is not None and time.monotonic() - last_write[0] >= 1.0:
                total.sums().write_exr(checkpoint, hash_)
                last_write[0] = time.monotonic()

        pixels = width * height
        _run_chunks(client, chunks, job, shipped, integrator, seed, threads, time_budget, progress, pixels, on_chunk)
        if checkpoint is not None:
            total.sums().write_exr(checkpoint, hash_)
        return total.sums()
    finally:
        close()


def _scene_info(job: _Job, files: Optional[Mapping[str, bytes]], integrator: Optional[Any]) -> Tuple[int, int, int, int, str]:
    """Task: (width, height, spp, seed, integrator key) of the job's scene."""
    scene = _worker_scene(job, files)
    return scene.width, scene.height, scene.spp, scene.seed, scene.integrator_key(integrator)


def _read_resume(path, hash_: str, seed: int, key: str, width: int, height: int) -> SampleSums:
    """The sums of a checkpoint to resume, checked against this render."""
    done, resume_hash = SampleSums.read_exr(path)
    problem = None
    if resume_hash != hash_:
        problem = f"was rendered from another scene (scene hash {resume_hash}, this one {hash_})"
    elif done.seed != seed:
        problem = f"was rendered with seed {done.seed}, not {seed}"
    elif done.integrator != key:
        problem = f"was rendered with {done.integrator}, not {key}"
    elif done.words.shape[:2] != (height, width):
        problem = f"is {done.words.shape[1]} x {done.words.shape[0]} pixels, the scene {width} x {height}"
    if problem:
        raise ValueError(f"resume: {os.fspath(path)}: {problem}")
    return done


def _result(client: Any, futures: List[Any]) -> List[Any]:
    """The results of ``futures``; on an error or Ctrl-C cancels them all and raises."""
    try:
        return client.gather(futures)
    except BaseException:
        client.cancel(futures)
        raise


class _Running:
    """The running total of a render's chunks, added in place as they arrive.
    Integer sums are exact, so the total does not depend on the order in
    which chunks arrive (nor on retries: a chunk's sums depend only on its
    samples); only the list of ranges is kept sorted."""

    def __init__(self, start: SampleSums) -> None:
        self.words = start.words.astype(np.int64, copy=True)
        self.ranges = list(start.ranges)
        self.seed, self.integrator = start.seed, start.integrator

    def add(self, packed: "_Packed") -> None:
        """Add a chunk's packed sums (:func:`_pack`)."""
        low, high, ranges, seed, integrator = packed
        assert (seed, integrator) == (self.seed, self.integrator), "a chunk of another render"
        self.ranges = _join_ranges(self.ranges + [tuple(r) for r in ranges])
        # Each word gains less than 2**32 per chunk: int64 holds 2**31 chunks.
        self.words[..., :3] += low
        self.words[..., 3] += high

    def sums(self) -> SampleSums:
        """The total so far (a view of the running words)."""
        return SampleSums(self.words, list(self.ranges), self.seed, self.integrator)


def _run_chunks(
    client, chunks, job, shipped, integrator, seed, threads, time_budget, progress, pixels, on_chunk
) -> None:
    """Submit the chunks (all at once, or a few at a time under a time
    budget) and hand each result to ``on_chunk(packed sums)`` as it arrives.
    An error of a task or Ctrl-C cancels every task and is raised."""
    from distributed import as_completed

    start = time.monotonic()
    advance, close_bar = _bar(progress, sum(e - s for s, e in chunks) * pixels, "samples")
    # Under a time budget only a few chunks are queued at once, so that few
    # start after the budget; otherwise all are queued and Dask balances them.
    window = len(chunks) if time_budget is None else max(1, 2 * sum(client.nthreads().values()))
    index_of: Dict[str, int] = {}
    futures: List[Any] = []

    def submit(index: int) -> Any:
        first, end = chunks[index]
        future = client.submit(_render_chunk, job, shipped, integrator, first, end, seed, threads, pure=False)
        index_of[future.key] = index
        futures.append(future)
        return future

    for i in range(min(window, len(chunks))):
        submit(i)
    next_index = len(futures)
    try:
        pending = as_completed(list(futures))
        for future in pending:
            if future.status == "error":
                raise future.exception()
            index = index_of[future.key]
            on_chunk(future.result())
            future.release()
            first, end = chunks[index]
            advance((end - first) * pixels)
            out_of_time = time_budget is not None and time.monotonic() - start > time_budget
            if next_index < len(chunks) and not out_of_time:
                pending.add(submit(next_index))
                next_index += 1
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        close_bar()


# ------------------------------------------------------------------- frames


def render_frames(
    scenes: Union[Sequence[SceneSpec], Callable[[int], SceneSpec]],
    output: str,
    frames: Optional[Iterable[int]] = None,
    *,
    client: Any = None,
    spp: Optional[int] = None,
    integrator: Optional[Any] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = 1,
    exposure: float = 0.0,
    progress: Union[bool, Callable[[int, int], Any]] = True,
    ship_files: bool = False,
) -> List[str]:
    """Render an animation, one Dask task per frame, and write each frame.

    ``scenes`` is a sequence of scenes (paths, dicts or :class:`niebla.Scene`,
    frame ``i`` is ``scenes[i]``) or a callable ``scenes(frame)`` returning
    the scene of a frame number (called here, on the client). ``frames``:
    the frame numbers (default: every index of the sequence). ``output`` is a
    file name pattern with ``{frame}`` (e.g. ``"out/smoke_{frame:04d}.exr"``;
    ``.exr`` or ``.png`` with ``exposure``). Each frame is rendered whole on
    one worker (the image equals ``niebla.Scene.render`` of that scene) and
    written here, through a temporary file renamed into place, as soon as it
    arrives. Returns the files written, in frame order. Errors, Ctrl-C and
    ``ship_files`` behave as in :func:`render`.
    """
    if frames is None:
        if callable(scenes):
            raise ValueError("frames: give the frame numbers when scenes is a callable")
        frames = range(len(scenes))
    frames = list(frames)
    if "{frame" not in output:
        raise ValueError(f"output: {output!r} has no {{frame}} field")
    jobs, all_files = [], {}
    for frame in frames:
        spec = scenes(frame) if callable(scenes) else scenes[frame]
        desc, base_dir, name, _ = _describe(spec)
        job, files = _make_job(desc, base_dir, name, ship_files)
        jobs.append(job)
        all_files.update(files)
    paths = [output.format(frame=frame) for frame in frames]
    for path in paths:
        folder = os.path.dirname(path)
        if folder and not os.path.isdir(folder):
            raise FileNotFoundError(f"{path}: output folder {folder} does not exist")

    from distributed import as_completed

    client, close = _client(client)
    advance, close_bar = _bar(progress, len(frames), "frames")
    futures: List[Any] = []
    index_of: Dict[str, int] = {}
    try:
        shipped = _ship(client, all_files)
        for i, job in enumerate(jobs):
            future = client.submit(_render_frame, job, shipped, integrator, spp, seed, threads, pure=False)
            index_of[future.key] = i
            futures.append(future)
        for future in as_completed(list(futures)):
            if future.status == "error":
                raise future.exception()
            write_image(future.result(), paths[index_of[future.key]], exposure)
            future.release()
            advance(1)
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        close_bar()
        close()
    return paths
