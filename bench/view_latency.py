"""Latency and frame rate of `niebla view` in headless Chromium (Playwright
driving /usr/bin/chromium): for each scene, integrator and resolution,
 - density latency: from sending a density-scale change (the slider's
   path) to the first frame of the edited scene arriving in the page (its
   first pass at full resolution, precomputation included), median of 3;
 - camera latency: the same for a camera move sent as a finished edit
   (full resolution), median of 3;
 - drag fps: interactive frames per second shown while the mouse orbits the
   camera for 3 s (frames at 1/2 of the resolution, 1 spp, the default).
Figures depend on the machine's load; run back to back in one go.

  .venv-py/bin/python bench/view_latency.py [NIEBLA_BIN] [--sizes 256 512]
      [--integrators zhou hegeman single volpath] [--scenes smoke cloud]
"""

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"smoke": "plume", "cloud": "cloud"}
INTEGRATORS = ["zhou", "hegeman", "single", "volpath"]
SIZES = [256, 512]


def measure(page, medium):
    view = lambda expr: page.evaluate(f"() => {expr}")

    def wait(expr, timeout=120):
        start = time.time()
        while time.time() - start < timeout:
            if view(expr):
                return True
            time.sleep(0.01)
        return False

    assert wait("window.nieblaView.frames[0] !== null", 300), "no first frame"
    def latency(change):
        n = view("window.nieblaView.latencies.length")
        view(f"({change}, window.nieblaView.edit(false))")
        if not wait(f"window.nieblaView.latencies.length > {n}", 300):
            return None
        return view("window.nieblaView.latencies.at(-1).ms")

    latencies, camera = [], []
    for scale in [1.5, 0.75, 1.0]:
        latencies.append(latency(f"window.nieblaView.scene.media['{medium}'].scale = {scale}"))
    for dx in [0.05, -0.1, 0.05]:
        camera.append(latency(f"window.nieblaView.scene.camera.position[0] += {dx}"))
    if None in latencies or None in camera:
        return None, None, None
    box = page.locator("#canvas").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    before = view("window.nieblaView.latencies.filter(l => l.interactive).length")
    frames_before = view("window.nieblaView.frameCount[0]")
    page.mouse.move(cx, cy)
    page.mouse.down()
    start = time.time()
    i = 0
    while time.time() - start < 3.0:
        i += 1
        page.mouse.move(cx + 40 * ((i % 20) / 20 - 0.5), cy, steps=1)
        time.sleep(0.016)
    elapsed = time.time() - start
    shown = view("window.nieblaView.frameCount[0]") - frames_before
    page.mouse.up()
    return statistics.median(latencies), statistics.median(camera), shown / elapsed


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
                        latency, camera, fps = measure(page, medium)
                        page.close()
                    finally:
                        server.terminate()
                        server.wait(10)
                    rows.append((scene_name, integrator, size, latency, camera, fps))
                    ms = lambda v: "n/a" if v is None else f"{v:.0f} ms"
                    fps_text = "n/a" if fps is None else f"{fps:.1f}"
                    print(f"{scene_name:6} {integrator:8} {size}x{size}: density edit-to-frame {ms(latency):>9}, "
                          f"camera edit-to-frame {ms(camera):>9}, drag {fps_text:>5} frames/s", flush=True)
        browser.close()


if __name__ == "__main__":
    main()
