"""What the scripts that time niebla against its peers share
(bench/compare.py, bench/fire_cycles.py, bench/production_frame.py):

- `ensure_venv(script)`: re-runs the calling script with bench/.venv's Python
  (mitsuba and numpy; created by bench/setup.sh when missing);
- `ensure_cycles()` and `cycles_version()`: bench/.venv-cycles (PyPI bpy);
- `read_exr(path)`: the R, G, B channels of an EXR as float32 (H, W, 3);
- `Niebla`: `niebla render` in a child process, with the render time niebla
  reports and the child's CPU seconds and peak resident set;
- `Cycles`: a Blender Cycles worker process (bench/cycles_worker.py) that
  builds the scene once and renders on request, with wall and CPU seconds of
  each render call and their fixed per-call parts.

Imports only the standard library at the top, so that a script can import it
before `ensure_venv` has put numpy within reach.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
VENV_PY = os.path.join(HERE, ".venv", "bin", "python")
CYCLES_PY = os.path.join(HERE, ".venv-cycles", "bin", "python")


def ensure_venv(script: str) -> None:
    """Returns when mitsuba and numpy import here; otherwise re-executes
    `script` (with this process's arguments) under bench/.venv's Python,
    running bench/setup.sh first when that venv lacks them."""
    try:
        import mitsuba  # noqa: F401
        import numpy  # noqa: F401
        return
    except ImportError:
        pass
    # (The venv's python is a symlink to the system one: compare prefixes, not executables.)
    if os.path.realpath(sys.prefix) != os.path.realpath(os.path.join(HERE, ".venv")):
        if not os.path.exists(VENV_PY) or subprocess.run([VENV_PY, "-c", "import mitsuba, numpy"]).returncode:
            subprocess.run(["bash", os.path.join(HERE, "setup.sh")], check=True)
        os.execv(VENV_PY, [VENV_PY, os.path.abspath(script)] + sys.argv[1:])
    sys.exit("mitsuba or numpy missing from bench/.venv: run bench/setup.sh")


def ensure_cycles() -> None:
    """Creates bench/.venv-cycles (bench/setup.sh --cycles) unless bpy imports there."""
    if not os.path.exists(CYCLES_PY) or subprocess.run([CYCLES_PY, "-c", "import bpy"],
                                                       capture_output=True).returncode:
        subprocess.run(["bash", os.path.join(HERE, "setup.sh"), "--cycles"], check=True)


def cycles_version() -> str:
    """Blender's version string, as bpy in bench/.venv-cycles reports it."""
    out = subprocess.run([CYCLES_PY, "-c", "import bpy; print(bpy.app.version_string)"],
                         capture_output=True, text=True).stdout.strip().splitlines()
    return out[-1] if out else "?"


@contextlib.contextmanager
def bitmap_io():
    """Around Mitsuba's image reading and writing (mi.Bitmap): gives Dr.Jit's
    thread pool at least two threads meanwhile, then restores its size. With
    one thread (`--threads 1`), reading an EXR through mi.Bitmap waits
    forever (Mitsuba 3.9.1, Dr.Jit 1.5.0)."""
    import drjit as dr

    n = dr.thread_count()
    if n < 2:
        dr.set_thread_count(2)
    try:
        yield
    finally:
        if n < 2:
            dr.set_thread_count(n)


def read_exr(path: str):
    """The R, G, B channels of an EXR file, float32 (height, width, 3)."""
    import mitsuba as mi
    import numpy as np

    # niebla's EXR also holds the exact per-pixel sums (channels
    # niebla.sum.*, read by `niebla merge`): take R, G, B by name.
    with bitmap_io():
        bmp = mi.Bitmap(path)
        names = [f.name for f in bmp.struct_()]
        arr = np.array(bmp, dtype=np.float32).reshape(bmp.height(), bmp.width(), len(names))
    return arr[..., [names.index(c) for c in ("R", "G", "B")]]


class Niebla:
    """`niebla render SCENE` in a child process, `threads` threads.

    `render` returns (image, seconds, wall seconds). `seconds` is, with
    clock "wall", the render time niebla reports ("rendered ... in X s": the
    render passes and their EXR checkpoints, not start-up or scene
    loading/baking); with clock "cpu", the child's user + system CPU seconds
    (wait4) net of `fixed_cpu`, the CPU seconds of an 8-pixel-wide 1-spp
    render of the same scene (start-up, loading, baking), measured by
    `measure_fixed_cpu()`. After each call `last_cpu` holds the child's gross
    CPU seconds, `last_output` its printed output, and `peak_mib` the
    largest peak resident set so far (MiB).

    With `no_writes`, renders run with --no-checkpoints (no EXR
    checkpoints between passes; the reported render time then excludes all
    writes) and the CPU seconds are those niebla reports before writing its
    final EXR (loading included), as a peer's render call does not save its
    image either."""

    name = "niebla"

    def __init__(self, binary: str, scene_path: str, workdir: str, threads: int = 2, clock: str = "wall",
                 no_writes: bool = False):
        self.binary, self.scene_path, self.workdir = binary, scene_path, workdir
        self.threads, self.clock, self.no_writes = threads, clock, no_writes
        self.fixed_cpu, self.last_cpu, self.peak_mib = 0.0, 0.0, 0.0

    def run(self, scene_path: str, spp: int, seed: int, tag: str, extra=()):
        """One `niebla render`: (EXR path, reported render seconds, CPU
        seconds, peak RSS MiB, wall seconds of the process)."""
        import time

        out = os.path.join(self.workdir, f"niebla_{tag}.exr")
        if self.no_writes:
            extra = (*extra, "--no-checkpoints")
        cmd = [self.binary, "render", scene_path, "--spp", str(spp), "--seed", str(seed),
               "--threads", str(self.threads), "--quiet", "-o", out, *extra]
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        with p.stdout:
            text = p.stdout.read()
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        if p.returncode:
            raise RuntimeError(f"{' '.join(cmd)} failed:\n{text}")
        m = re.search(r"rendered \S+ at (\d+) spp with \S+ in ([0-9.]+) s", text)
        if not m or int(m.group(1)) != spp:
            raise RuntimeError(f"unexpected niebla output: {text!r}")
        self.last_output = text
        cpu = ru.ru_utime + ru.ru_stime
        if self.no_writes:
            c = re.search(r"process CPU ([0-9.]+) s before the final write", text)
            if not c:
                raise RuntimeError(f"no CPU time in niebla's output {text!r} (a binary without --no-checkpoints?)")
            cpu = float(c.group(1))
        return out, float(m.group(2)), cpu, ru.ru_maxrss / 1024.0, wall

    def measure_fixed_cpu(self, repeats: int = 2) -> float:
        """The smaller CPU seconds of `repeats` 8-pixel-wide, 1-spp renders
        of the scene: the per-call cost that does not grow with pixels or
        samples. Stored in `fixed_cpu`."""
        self.fixed_cpu = min(self.run(self.scene_path, 1, 90000 + k, f"fixed_{k}", ("--width", "8"))[2]
                             for k in range(repeats))
        return self.fixed_cpu

    def render(self, spp: int, seed: int, tag: str):
        """(image, seconds on the chosen clock, wall seconds of the process)."""
        out, t, cpu, peak, wall = self.run(self.scene_path, spp, seed, tag)
        self.last_cpu = cpu
        self.peak_mib = max(self.peak_mib, peak)
        sec = max(cpu - self.fixed_cpu, 1e-3) if self.clock == "cpu" else t
        return read_exr(out), sec, wall


class Cycles:
    """Blender Cycles 5.0 (PyPI `bpy`, CPU) in a worker process of its own
    (bench/cycles_worker.py in bench/.venv-cycles), the scene built once by
    bench/niebla2cycles.py. Times are those of the render call after a
    warm-up render; `fixed_s` / `fixed_cpu` are the wall / CPU seconds of a
    1x1-pixel, 1-spp render (the per-call scene synchronisation, mostly the
    volume octree of grid media; the smaller of two), which `net` times
    subtract. CPU seconds: the worker's user + system time during the render
    call (all its threads). With clock "cpu", `render` gives CPU seconds;
    `cpu_log` keeps every call's gross CPU seconds."""

    name = "cycles"
    third = "net_seconds"  # what the third value of render() is, in sweep rows

    def __init__(self, scene_path: str, scene_dir: str, workdir: str, threads: int = 2, clock: str = "wall"):
        self.workdir, self.clock, self.cpu_log = workdir, clock, []
        self.proc = subprocess.Popen([CYCLES_PY, os.path.join(HERE, "cycles_worker.py"), scene_path, scene_dir,
                                      str(threads)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True)
        first = json.loads(self.proc.stdout.readline() or '{"unsupported": "the worker died"}')
        self.unsupported = first.get("unsupported")
        if self.unsupported:
            self.close()
            return
        self._call(1, 999999, "warmup")
        fixed = [self._call(1, 999998, "fixed", 1, 1) for _ in range(2)]
        self.fixed_s = min(r["seconds"] for r in fixed)
        self.fixed_cpu = min(r["cpu_seconds"] for r in fixed)

    def _call(self, spp, seed, tag, width=None, height=None) -> dict:
        """One render request; the worker's answer {"seconds", "cpu_seconds"}."""
        req = {"spp": spp, "seed": seed, "out": os.path.join(self.workdir, f"cycles_{tag}.exr")}
        if width:
            req.update(width=width, height=height)
        self.proc.stdin.write(json.dumps(req) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("the Cycles worker died")
        r = json.loads(line)
        self.cpu_log.append(r["cpu_seconds"])
        return r

    def render(self, spp: int, seed: int, tag: str):
        """(image, seconds, seconds net of the fixed per-call cost), wall or
        CPU seconds by the clock."""
        r = self._call(spp, seed, tag)
        t, fixed = (r["cpu_seconds"], self.fixed_cpu) if self.clock == "cpu" else (r["seconds"], self.fixed_s)
        return read_exr(os.path.join(self.workdir, f"cycles_{tag}.exr")), t, max(t - fixed, 1e-6)

    def peak_mib(self) -> float:
        """The worker's peak resident set (VmHWM), MiB; Blender itself included."""
        with open(f"/proc/{self.proc.pid}/status") as f:
            return next(int(l.split()[1]) for l in f if l.startswith("VmHWM")) / 1024.0

    def close(self):
        if self.proc.poll() is None:
            self.proc.stdin.close()
            self.proc.wait()
