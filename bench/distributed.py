"""Overhead and scaling of niebla.distributed on this machine (not a test).

    .venv-py/bin/python bench/distributed.py            # about 2-3 minutes
    .venv-py/bin/python bench/distributed.py --seconds 10   # shorter

Measures, on scenes/default.json at 240x180 with volpath:
1. a local render (Scene.render, 2 threads) of about --seconds seconds, and the
   same render through niebla.distributed on a LocalCluster of 2 worker
   processes with 1 thread each (equal total threads): the overhead in wall
   time, and in CPU time of every process (robust to other processes sharing
   the cores), and the CPU Dask spends idle (heartbeats, profiler);
2. the same fixed-spp render with 1 and with 2 single-threaded workers: wall
   time, and the largest CPU time of one worker (the wall time the render
   would take with a free core per worker);
3. the round trip of an empty Dask task (scheduler latency) and the bytes of
   one chunk's sums (48 per pixel: 12 32-bit words), the inputs of the
   16-machine estimate in README.md.
Every distributed image is checked bit for bit against the local render.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

# Run as a script, this file's folder comes first on sys.path, and its name
# would shadow the `distributed` package: take the folder out.
_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or ".") != _HERE]

import numpy as np  # noqa: E402

import niebla  # noqa: E402
import niebla.distributed as nd  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
# The default scene (a hazy room, spot and point lights) at 240x180 with volpath.
SCENE = json.loads((REPO / "scenes" / "default.json").read_text())
SCENE["camera"].update(width=240, height=180)
SCENE["render"]["integrator"] = {"type": "volpath"}


def timed(f):
    start = time.perf_counter()
    value = f()
    return value, time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=30.0, help="target length of the local render")
    args = parser.parse_args()

    print("load average at start: %.2f %.2f %.2f (other processes share the cores)" % os.getloadavg())
    scene = niebla.Scene.from_dict(SCENE)
    _, t4 = timed(lambda: scene.render(spp=4, threads=2, progress=False))
    spp = max(8, int(round(args.seconds / (t4 / 4) / 8)) * 8)
    print(f"scene {scene.width}x{scene.height} volpath; {t4 / 4 * 1000:.0f} ms per spp on 2 threads -> spp {spp}")

    cpu0 = time.process_time()
    local, t_local = timed(lambda: scene.render(spp=spp, threads=2, progress=False))
    cpu_local = time.process_time() - cpu0
    print(f"local render, 2 threads:                 {t_local:7.2f} s wall, {cpu_local:7.2f} s CPU")

    cluster, t_start = timed(lambda: LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None, silence_logs=40))
    client = Client(cluster)
    print(f"LocalCluster start (2 processes):        {t_start:7.2f} s (not counted below)")
    def cpu_everywhere():
        """CPU seconds so far of the workers, the scheduler and this process
        (contention from other processes inflates wall time, hardly CPU time)."""
        workers = sum(client.run(time.process_time).values())
        return workers + client.run_on_scheduler(time.process_time) + time.process_time()

    cpu0, wall0 = cpu_everywhere(), time.perf_counter()
    time.sleep(5)
    idle = (cpu_everywhere() - cpu0) / (time.perf_counter() - wall0)
    print(f"idle Dask (scheduler, 2 workers, client): {100 * idle:.1f}% of one core")

    for chunk_spp in (spp // 8, spp // 2):
        cpu0 = cpu_everywhere()
        result, t = timed(lambda: nd.render(SCENE, spp=spp, chunk_spp=chunk_spp, client=client, threads=1, progress=False))
        cpu = cpu_everywhere() - cpu0
        same = np.array_equal(result.image().view(np.uint32), local.view(np.uint32))
        print(
            f"distributed, 2 workers x 1 thread, {spp // chunk_spp:2d} chunks of {chunk_spp:3d} spp: {t:7.2f} s wall "
            f"(overhead {100 * (t / t_local - 1):+.1f}%), {cpu:7.2f} s CPU ({100 * (cpu / cpu_local - 1):+.1f}%), "
            f"bit-identical: {same}"
        )

    # Scaling at fixed spp: 1 worker, then 2.
    fixed = max(4, spp // 2)
    reference = scene.render(spp=fixed, threads=1, progress=False)
    times, busiest = {}, {}
    for workers in (1, 2):
        cluster.scale(workers)
        while len(client.scheduler_info()["workers"]) != workers:
            time.sleep(0.05)
        before = client.run(time.process_time)
        result, times[workers] = timed(
            lambda: nd.render(SCENE, spp=fixed, chunk_spp=max(1, fixed // 8), client=client, threads=1, progress=False)
        )
        after = client.run(time.process_time)
        busiest[workers] = max(after[w] - before.get(w, 0.0) for w in after)
        assert np.array_equal(result.image().view(np.uint32), reference.view(np.uint32))
        print(
            f"{fixed} spp on {workers} single-threaded worker(s): {times[workers]:7.2f} s wall, "
            f"busiest worker {busiest[workers]:7.2f} s CPU"
        )
    print(
        f"speed-up 1 -> 2 workers: {times[1] / times[2]:.2f}x in wall time, "
        f"{busiest[1] / busiest[2]:.2f}x in the busiest worker's CPU time"
    )

    # Scheduler round trip of an empty task, and bytes of a chunk's sums.
    client.submit(int, 0, pure=False).result()
    n = 200
    _, t_tasks = timed(lambda: client.gather([client.submit(int, i, pure=False) for i in range(n)]))
    _, t_one = timed(lambda: [client.submit(int, i, pure=False).result() for i in range(20)])
    print(f"empty tasks: {1000 * t_tasks / n:.2f} ms each when {n} are queued, {1000 * t_one / 20:.2f} ms round trip one at a time")
    print(f"sums per chunk: {48 * scene.width * scene.height / 1e6:.2f} MB ({scene.width}x{scene.height} x 48 bytes); 1920x1080: 99.5 MB")
    print("load average at end: %.2f %.2f %.2f" % os.getloadavg())
    client.close()
    cluster.close()


if __name__ == "__main__":
    main()
