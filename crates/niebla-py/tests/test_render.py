"""Rendering: identical to the command line, progress, the GIL, Ctrl-C."""

import _thread
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import niebla


def test_python_and_command_line_renders_are_bit_identical(repo, tmp_path, niebla_bin):
    scene_file = repo / "scenes" / "smoke.json"
    cli_exr = tmp_path / "cli.exr"
    cmd = [niebla_bin, "render", str(scene_file), "--spp", "3", "--seed", "5", "--integrator", "volpath"]
    subprocess.run(cmd + ["--quiet", "-o", str(cli_exr)], check=True, capture_output=True)
    image = niebla.Scene.from_file(scene_file).render("volpath", spp=3, seed=5, progress=False)
    cli_image = niebla.read_exr(cli_exr)
    assert cli_image.dtype == image.dtype == np.float32
    # Bit for bit, compared as integers so that even NaN payloads would count.
    assert np.array_equal(cli_image.view(np.uint32), image.view(np.uint32))


@pytest.mark.parametrize("sampling", ["march", "mis"])
def test_single_scattering_matches_the_command_line(tiny_scene, tmp_path, niebla_bin, sampling):
    import json

    file = tmp_path / "tiny.json"
    file.write_text(json.dumps(tiny_scene))
    out = tmp_path / "cli.exr"
    subprocess.run(
        [niebla_bin, "render", str(file), "--integrator", "single", "--sampling", sampling, "--spp", "5"]
        + ["--threads", "2", "--quiet", "-o", str(out)],
        check=True,
        capture_output=True,
    )
    image = niebla.Scene.from_dict(tiny_scene).render(
        {"type": "single", "sampling": sampling}, spp=5, threads=1, progress=False
    )
    assert np.array_equal(niebla.read_exr(out), image)


def test_integrator_names_follow_the_command_line(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    # The scene's own integrator keeps its parameters (sampling "mis").
    assert np.array_equal(
        scene.render("single", spp=2, progress=False),
        scene.render({"type": "single", "sampling": "mis"}, spp=2, progress=False),
    )
    assert scene.last_render.integrator == "single" and scene.last_render.spp == 2
    for name in niebla.INTEGRATORS:
        try:
            image = scene.render(name, spp=1, progress=False)
        except (niebla.SceneError, niebla.RenderError):
            # A specialized method may not apply to this scene; the general ones must.
            assert name not in ("emission", "single", "volpath")
            continue
        assert image.shape == (30, 40, 3) and np.isfinite(image).all()


def test_progress_reports_every_sample(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    calls = []
    scene.render(spp=64, progress=lambda done, total: calls.append((done, total)))
    total = 40 * 30 * 64
    assert calls and calls[-1] == (total, total)
    assert all(t == total for _, t in calls)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))


def test_a_tqdm_bar_can_be_asked_for(tiny_scene, capsys):
    pytest.importorskip("tqdm")
    image = niebla.Scene.from_dict(tiny_scene).render(spp=8, progress=True)
    assert image.shape == (30, 40, 3)
    assert "niebla" in capsys.readouterr().err


def test_time_budget_stops_in_time(repo):
    scene = niebla.Scene.from_file(repo / "scenes" / "smoke.json")
    start = time.perf_counter()
    image = scene.render("volpath", time=1.0, progress=False)
    elapsed = time.perf_counter() - start
    assert image.shape == (400, 360, 3)
    assert scene.last_render.spp >= 1
    assert elapsed < 3.0


def test_the_gil_is_released_while_rendering(repo):
    scene = niebla.Scene.from_file(repo / "scenes" / "smoke.json")
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    thread = threading.Thread(target=count)
    start = time.perf_counter()
    thread.start()
    try:
        scene.render("volpath", spp=4, threads=1, progress=False)
    finally:
        stop.set()
        thread.join()
    seconds = time.perf_counter() - start
    # The counter ran all along (it would stall if the render held the GIL).
    assert seconds > 0.2
    assert len(ticks) > 0.3 * seconds / 0.005


def test_keyboard_interrupt_stops_a_render_and_the_scene_stays_usable(repo):
    scene = niebla.Scene.from_file(repo / "scenes" / "smoke.json")
    # What Ctrl-C does: Python's SIGINT flag is raised on the main thread.
    timer = threading.Timer(0.5, _thread.interrupt_main)
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        scene.render("volpath", spp=100_000, progress=False)
    assert time.perf_counter() - start < 5.0
    timer.join()
    assert scene.render("volpath", spp=1, progress=False).mean() > 0


def test_an_exception_in_the_progress_callback_stops_the_render(repo):
    scene = niebla.Scene.from_file(repo / "scenes" / "smoke.json")

    def explode(done, total):
        if done > 0:
            raise RuntimeError("enough")

    start = time.perf_counter()
    with pytest.raises(RuntimeError, match="enough"):
        scene.render("volpath", spp=100_000, progress=explode)
    assert time.perf_counter() - start < 5.0


def test_ctrl_c_interrupts_a_render_in_a_python_process(repo):
    script = (
        "import niebla, sys\n"
        f"scene = niebla.Scene.from_file({str(repo / 'scenes' / 'smoke.json')!r})\n"
        "print('rendering', flush=True)\n"
        "scene.render('volpath', spp=100000, progress=False)\n"
        "print('finished', flush=True)\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert process.stdout.readline().strip() == "rendering"
        time.sleep(0.5)
        start = time.perf_counter()
        process.send_signal(2)  # SIGINT, as Ctrl-C in a terminal
        _, stderr = process.communicate(timeout=20)
        stopped_in = time.perf_counter() - start
    finally:
        if process.poll() is None:
            process.kill()
    assert "KeyboardInterrupt" in stderr
    assert process.returncode != 0
    assert stopped_in < 5.0
