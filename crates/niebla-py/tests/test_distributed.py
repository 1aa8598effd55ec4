"""niebla.distributed on a real LocalCluster of worker processes: the
distributed image equals the one-process render bit for bit (1, 2 and 3
workers, chunk sizes that do not divide spp), survives a worker killed with
SIGKILL mid-render, names a file the workers cannot read, renders frames
equal to each frame alone, ships files, stops at a time budget and resumes
from a checkpoint."""

import os
import signal
import time

import numpy as np
import pytest

import niebla

distributed = pytest.importorskip("distributed")
import niebla.distributed as nd  # noqa: E402


def bits(image):
    """The float32 image as raw bits, so equality means bit for bit."""
    return np.ascontiguousarray(image, dtype=np.float32).view(np.uint32)


def grid_scene(tiny_scene, npy_path):
    """The tiny scene with its fog's density read from an .npy grid."""
    scene = dict(tiny_scene)
    scene["media"] = {
        "fog": {
            "type": "grid",
            "density": {"type": "npy", "file": str(npy_path)},
            "sigma_t": 2.0,
            "albedo": 0.9,
            "phase": {"type": "hg", "g": 0.3},
            "to_world": {"scale": [2, 2, 2], "translate": [-1, 0, -1]},
        }
    }
    scene["shapes"] = [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}]
    return scene


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None, silence_logs=40
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def scale(client, n):
    """Resize the cluster to exactly n workers and wait for it."""
    client.cluster.scale(n)
    deadline = time.monotonic() + 30
    while len(client.scheduler_info()["workers"]) != n:
        assert time.monotonic() < deadline, f"cluster did not reach {n} workers"
        time.sleep(0.05)


def test_distributed_image_equals_the_one_process_render_for_1_2_3_workers(client, tiny_scene):
    tiny_scene["camera"]["width"], tiny_scene["camera"]["height"] = 24, 18
    local = niebla.Scene.from_dict(tiny_scene).render(spp=10, progress=False)
    assert local.mean() > 0
    try:
        for workers, chunks in [(1, [3]), (2, [3, 4, 7, 10]), (3, [4])]:
            scale(client, workers)
            for chunk_spp in chunks:
                result = nd.render(tiny_scene, spp=10, chunk_spp=chunk_spp, client=client, progress=False)
                assert result.spp == 10 and result.ranges == [(0, 10)]
                assert np.array_equal(bits(result.image()), bits(local)), (workers, chunk_spp)
    finally:
        scale(client, 2)
    # A chunk alone is a different (noisier) image: the comparison has teeth.
    part = nd.render(tiny_scene, spp=3, client=client, progress=False)
    assert not np.array_equal(bits(part.image()), bits(local))


def test_a_worker_killed_mid_render_leaves_the_image_unchanged(client, tiny_scene):
    tiny_scene["render"]["integrator"] = {"type": "volpath"}
    tiny_scene["camera"]["width"], tiny_scene["camera"]["height"] = 32, 24
    spp = 48
    local = niebla.Scene.from_dict(tiny_scene).render(spp=spp, progress=False)
    pids = client.run(os.getpid)
    killed = []

    def kill_one_busy_worker(done, total):
        if killed:
            return
        # A worker that is rendering a chunk right now.
        for address, tasks in client.processing().items():
            if tasks and address in pids:
                os.kill(pids[address], signal.SIGKILL)
                killed.append(address)
                return

    result = nd.render(tiny_scene, spp=spp, chunk_spp=2, client=client, progress=kill_one_busy_worker)
    assert killed, "no worker was busy when the first chunk finished"
    assert np.array_equal(bits(result.image()), bits(local))
    assert result.spp == spp
    # The nanny restarted the worker: a new process replaced the killed one.
    client.wait_for_workers(2, timeout=30)
    assert pids[killed[0]] not in client.run(os.getpid).values()


def test_a_grid_file_missing_on_the_workers_is_named_in_the_error(client, tiny_scene, tmp_path):
    scene = grid_scene(tiny_scene, tmp_path / "no_such_density.npy")
    started = time.monotonic()
    with pytest.raises(nd.ChunkError, match="no_such_density.npy"):
        nd.render(scene, spp=4, chunk_spp=1, client=client, progress=False)
    assert time.monotonic() - started < 20


def test_shipped_files_render_the_same_image(client, tiny_scene, tmp_path):
    z, y, x = np.mgrid[0:6, 0:5, 0:4]
    np.save(tmp_path / "density.npy", ((x + y + z) / 12.0).astype(np.float32))
    scene = grid_scene(tiny_scene, "density.npy")
    local = niebla.Scene.from_dict(scene, base_dir=tmp_path).render(spp=6, progress=False)
    shipped = nd.render(
        niebla.Scene.from_dict(scene, base_dir=tmp_path), spp=6, chunk_spp=4, client=client, ship_files=True,
        progress=False,
    )
    assert np.array_equal(bits(shipped.image()), bits(local))
    copies = [p for paths in client.run(lambda: list(nd._SHIPPED.values())).values() for p in paths]
    assert copies and all(os.path.basename(p) == "density.npy" for p in copies)


def test_render_frames_equal_each_frame_alone(client, tiny_scene, tmp_path):
    def frame(i):
        scene = dict(tiny_scene)
        scene["camera"] = dict(tiny_scene["camera"], width=16, height=12)
        scene["lights"] = [{"type": "point", "position": [1 - 0.4 * i, 3, 1], "intensity": 10}]
        return scene

    written = nd.render_frames(frame, str(tmp_path / "frame_{frame:02d}.exr"), frames=range(6), client=client, spp=3, progress=False)
    assert written == [str(tmp_path / f"frame_{i:02d}.exr") for i in range(6)]
    images = [niebla.read_exr(p) for p in written]
    for i, image in enumerate(images):
        alone = niebla.Scene.from_dict(frame(i)).render(spp=3, progress=False)
        assert np.array_equal(bits(image), bits(alone)), i
    assert not np.array_equal(bits(images[0]), bits(images[5]))
    assert not [p for p in os.listdir(tmp_path) if p.endswith(".tmp")]


def test_time_budget_and_checkpoint_resume(client, tiny_scene, tmp_path):
    local = niebla.Scene.from_dict(tiny_scene)
    # A budget already spent: only the first window of chunks (2 workers x 2)
    # runs, and the result is the render of the samples done.
    partial = nd.render(
        tiny_scene, spp=40, chunk_spp=2, client=client, time_budget=0.0, progress=False,
        checkpoint=tmp_path / "partial.exr",
    )
    assert partial.ranges == [(0, 8)] and partial.spp == 8
    assert np.array_equal(bits(partial.image()), bits(local.render(spp=8, progress=False)))
    # Resumed from the checkpoint: the missing samples only, to the full image.
    resumed = nd.render(tiny_scene, spp=12, chunk_spp=3, client=client, resume=tmp_path / "partial.exr", progress=False)
    assert resumed.ranges == [(0, 12)]
    assert np.array_equal(bits(resumed.image()), bits(local.render(spp=12, progress=False)))
    with pytest.raises(ValueError, match="seed 1, not 2"):
        nd.render(tiny_scene, spp=12, seed=2, client=client, resume=tmp_path / "partial.exr", progress=False)


def test_a_distributed_checkpoint_merges_with_a_command_line_render(client, tiny_scene, tmp_path, niebla_bin):
    import json
    import subprocess

    scene = tmp_path / "fog.json"
    scene.write_text(json.dumps(tiny_scene))
    nd.render(scene, spp=5, chunk_spp=2, client=client, checkpoint=tmp_path / "py.exr", progress=False)
    run = lambda *args: subprocess.run([niebla_bin, *args], cwd=tmp_path, check=True, capture_output=True)  # noqa: E731
    run("render", "fog.json", "--first-sample", "5", "--spp", "4", "-o", "cli.exr", "--quiet")
    run("merge", "py.exr", "cli.exr", "-o", "merged.exr")
    run("render", "fog.json", "--spp", "9", "-o", "whole.exr", "--quiet")
    assert np.array_equal(bits(niebla.read_exr(tmp_path / "merged.exr")), bits(niebla.read_exr(tmp_path / "whole.exr")))


def test_keyboard_interrupt_cancels_the_tasks(client, tiny_scene):
    tiny_scene["render"]["integrator"] = {"type": "volpath"}

    def interrupt(done, total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as interrupted:
        nd.render(tiny_scene, spp=64, chunk_spp=1, client=client, progress=interrupt)
    # The 63 chunks left were cancelled, so the scheduler forgets them even
    # though the traceback (kept alive here) still holds their futures.
    deadline = time.monotonic() + 10
    def chunks_on_scheduler(dask_scheduler):
        return sum(str(key).startswith("_render_chunk") for key in dask_scheduler.tasks)

    while client.run_on_scheduler(chunks_on_scheduler):
        assert time.monotonic() < deadline, "tasks still on the scheduler after KeyboardInterrupt"
        time.sleep(0.05)
    assert interrupted.traceback
