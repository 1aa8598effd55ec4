"""Latency and frame rate of `niebla view` in headless Chromium (Playwright
driving /usr/bin/chromium): for each scene, integrator and resolution,
 - density latency: from sending a density-scale change (the slider's
   path) to the first frame of the edited scene arriving in the page (its
   first pass at full resolution, precomputation included), median of 3;
 - density drag latency: the same for a density change sent as a slider
   drag sends it (interactive: 1/2 resolution, 1 spp; zhou lights its
   coarser preview lattice), median of 3;
 - camera latency: the same for a camera move sent as a finished edit
   (full resolution), median of 3;
 - drag fps: interactive frames per second shown while the mouse orbits the
   camera for 3 s (frames at 1/2 of the resolution, 1 spp, the default).
Under each row, where the time went (medians, ms): the page's records
(edit sent to frame drawn) with the server's stages from the frame's
X-Niebla-Timing header: post (the edit's POST round trip), up+down (the
edit-to-headers time not spent in the server), validate, queue (job made
to render slot start), parse, prepare (scene rebuild + integrator update),
pass, image, wait (frame published to taken by the page's request), encode
(half floats), body, upload (texture), draw; and the CPU milliseconds per
shown drag frame used by the viewer, by Chromium and by the Playwright
driver (with psutil), which depend less on the machine's load than times.
Figures depend on the machine's load; run back to back in one go.

  .venv-py/bin/python bench/view_latency.py [NIEBLA_BIN] [--sizes 256 512]
      [--integrators zhou hegeman single volpath] [--scenes smoke cloud]
"""

import argparse
import os
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

try:
    import psutil
except ImportError:  # the CPU split is then left out
    psutil = None

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"smoke": "plume", "cloud": "cloud"}
INTEGRATORS = ["zhou", "hegeman", "single", "volpath"]
SIZES = [256, 512]


def cpu_seconds(server_pid):
    """CPU seconds (user + system) used so far by the viewer (`server_pid`),
    by Chromium (this script's descendants named chromium) and by the
    Playwright driver (the other descendants)."""
    if psutil is None:
        return None
    out = {"server": 0.0, "browser": 0.0, "driver": 0.0}
    for proc in psutil.Process(os.getpid()).children(recursive=True) + [psutil.Process(server_pid)]:
        try:
            times = proc.cpu_times()
            name = proc.name()
        except psutil.Error:
            continue
        kind = "server" if proc.pid == server_pid else "browser" if "chrom" in name else "driver"
        out[kind] += times.user + times.system
    return out


def measure(page, medium, server_pid):
    view = lambda expr: page.evaluate(f"() => {expr}")

    def wait(expr, timeout=120):
        start = time.time()
        while time.time() - start < timeout:
            if view(expr):
                return True
            time.sleep(0.01)
        return False

    assert wait("window.nieblaView.frames[0] !== null", 300), "no first frame"
    def latency(change, interactive=False):
        n = view("window.nieblaView.latencies.length")
        view(f"({change}, window.nieblaView.edit({'true' if interactive else 'false'}))")
        if not wait(f"window.nieblaView.latencies.length > {n}", 300):
            return None
        return view("window.nieblaView.latencies.at(-1).ms")

    latencies, camera = [], []
    for scale in [1.5, 0.75, 1.0]:
        latencies.append(latency(f"window.nieblaView.scene.media['{medium}'].scale = {scale}"))
    drag_density = []
    for scale in [1.3, 1.1, 1.0]:
        drag_density.append(latency(f"window.nieblaView.scene.media['{medium}'].scale = {scale}", True))
    latency("0")  # the drag's end: the full frame of the same scene
    for dx in [0.05, -0.1, 0.05]:
        camera.append(latency(f"window.nieblaView.scene.camera.position[0] += {dx}"))
    if None in latencies or None in camera or None in drag_density:
        return None, None, None, None
    box = page.locator("#canvas").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    before = view("window.nieblaView.latencies.filter(l => l.interactive).length")
    frames_before = view("window.nieblaView.frameCount[0]")
    page.mouse.move(cx, cy)
    page.mouse.down()
    cpu_before = cpu_seconds(server_pid)
    start = time.time()
    i = 0
    while time.time() - start < 3.0:
        i += 1
        page.mouse.move(cx + 40 * ((i % 20) / 20 - 0.5), cy, steps=1)
        time.sleep(0.016)
    elapsed = time.time() - start
    cpu_after = cpu_seconds(server_pid)
    shown = view("window.nieblaView.frameCount[0]") - frames_before
    page.mouse.up()
    drags = view(f"window.nieblaView.latencies.filter(l => l.interactive).slice({before})")
    edits = view("window.nieblaView.latencies.filter(l => !l.interactive)")
    density_drags = view("window.nieblaView.latencies.filter(l => l.interactive)")[:3]
    breakdown = {"camera": breakdown_of(edits[-3:]), "density drag": breakdown_of(density_drags),
                 "drag": breakdown_of(drags)}
    if cpu_before is not None and shown > 0:
        breakdown["drag CPU"] = {k: 1e3 * (cpu_after[k] - cpu_before[k]) / shown for k in cpu_before}
    breakdown["density drag edit-to-frame (ms)"] = statistics.median(drag_density)
    return statistics.median(latencies), statistics.median(camera), shown / elapsed, breakdown


STAGES = ["validate", "queue", "parse", "prepare", "pass", "image", "wait", "encode"]


def breakdown_of(latencies):
    """Median milliseconds per stage of `latencies` (the page's records):
    the whole edit-to-drawn-frame time, the POST round trip, the network up
    (edit sent to the server's reply, minus the server's time), the server's
    stages, then the body, the texture upload and the draw in the page."""
    if not latencies:
        return None
    med = lambda values: statistics.median(values) if values else float("nan")
    out = {"total": med([l["ms"] for l in latencies]), "post": med([l["timing"]["post"] for l in latencies])}
    out["up+down"] = med([l["timing"]["up"] for l in latencies if l["timing"]["up"] is not None])
    for stage in STAGES + ["server"]:
        out[stage] = med([l["timing"]["server"].get(stage, float("nan")) for l in latencies])
    for stage in ["body", "upload", "draw"]:
        out[stage] = med([l["timing"][stage] for l in latencies])
    out["n"] = len(latencies)
    return out


def format_breakdown(name, b):
    if b is None:
        return f"    {name}: no frames"
    if isinstance(b, (int, float)):
        return f"    {name}: {b:.0f}"
    if name == "drag CPU":
        return "    drag CPU per shown frame (ms): " + ", ".join(f"{k} {v:.1f}" for k, v in b.items())
    parts = " ".join(f"{k} {b[k]:.1f}" for k in ["post", "up+down"] + STAGES + ["body", "upload", "draw"])
    return f"    {name} (median of {b['n']}, ms): total {b['total']:.1f}, server {b['server']:.1f}; {parts}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("niebla", nargs="?", default=str(ROOT / "target/release/niebla"))
    parser.add_argument("--sizes", nargs="+", type=int, default=SIZES)
    parser.add_argument("--integrators", nargs="+", default=INTEGRATORS)
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    args = parser.parse_args()
    rows = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True,
                                    args=["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
        for scene_name in args.scenes:
            medium = SCENES[scene_name]
            for integrator in args.integrators:
                for size in args.sizes:
                    scene = json.loads((ROOT / "scenes" / f"{scene_name}.json").read_text())
                    scene["camera"]["width"] = scene["camera"]["height"] = size
                    scene["render"]["integrator"] = {"type": integrator}
                    work = Path(tempfile.mkdtemp(prefix="niebla-view-bench-"))
                    path = work / f"{scene_name}.json"
                    path.write_text(json.dumps(scene))
                    server = subprocess.Popen([args.niebla, "view", str(path)], stdout=subprocess.PIPE, text=True)
                    try:
                        url = re.search(r"http://\S+", server.stdout.readline()).group(0)
                        page = browser.new_page(viewport={"width": 1300, "height": 900})
                        page.goto(url)
                        latency, camera, fps, breakdown = measure(page, medium, server.pid)
                        page.close()
                    finally:
                        server.terminate()
                        server.wait(10)
                    rows.append((scene_name, integrator, size, latency, camera, fps))
                    if breakdown is None:
                        breakdown = {}
                    ms = lambda v: "n/a" if v is None else f"{v:.0f} ms"
                    fps_text = "n/a" if fps is None else f"{fps:.1f}"
                    print(f"{scene_name:6} {integrator:8} {size}x{size}: density edit-to-frame {ms(latency):>9}, "
                          f"camera edit-to-frame {ms(camera):>9}, drag {fps_text:>5} frames/s", flush=True)
                    for name, b in breakdown.items():
                        print(format_breakdown(name, b), flush=True)
        browser.close()


if __name__ == "__main__":
    main()
