"""Latency and frame rate of `niebla view` in headless Chromium (Playwright
driving /usr/bin/chromium): for each scene, integrator and resolution,
 - latency: from sending a density-scale change (the slider's path) to the
   first frame of the edited scene arriving in the page (its first pass,
   precomputation included), median of 3;
 - drag fps: interactive frames per second shown while the mouse orbits the
   camera for 3 s (frames at 1/2 of the resolution, 1 spp, the default).
Figures depend on the machine's load; run back to back in one go.

  .venv-py/bin/python bench/view_latency.py [NIEBLA_BIN]
"""

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
NIEBLA = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target/release/niebla")
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
    latencies = []
    for scale in [1.5, 0.75, 1.0]:
        n = view("window.nieblaView.latencies.length")
        view(f"(window.nieblaView.scene.media['{medium}'].scale = {scale}, window.nieblaView.edit(false))")
        if not wait(f"window.nieblaView.latencies.length > {n}", 300):
            return None, None
        latencies.append(view("window.nieblaView.latencies.at(-1).ms"))
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
    return statistics.median(latencies), shown / elapsed


def main():
    rows = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True,
                                    args=["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
        for scene_name, medium in SCENES.items():
            for integrator in INTEGRATORS:
                for size in SIZES:
                    scene = json.loads((ROOT / "scenes" / f"{scene_name}.json").read_text())
                    scene["camera"]["width"] = scene["camera"]["height"] = size
                    scene["render"]["integrator"] = {"type": integrator}
                    work = Path(tempfile.mkdtemp(prefix="niebla-view-bench-"))
                    path = work / f"{scene_name}.json"
                    path.write_text(json.dumps(scene))
                    server = subprocess.Popen([NIEBLA, "view", str(path)], stdout=subprocess.PIPE, text=True)
                    try:
                        url = re.search(r"http://\S+", server.stdout.readline()).group(0)
                        page = browser.new_page(viewport={"width": 1300, "height": 900})
                        page.goto(url)
                        latency, fps = measure(page, medium)
                        page.close()
                    finally:
                        server.terminate()
                        server.wait(10)
                    rows.append((scene_name, integrator, size, latency, fps))
                    lat = "n/a" if latency is None else f"{latency:.0f} ms"
                    fps_text = "n/a" if fps is None else f"{fps:.1f}"
                    print(f"{scene_name:6} {integrator:8} {size}x{size}: edit-to-frame {lat:>9}, drag {fps_text:>5} frames/s", flush=True)
        browser.close()


if __name__ == "__main__":
    main()
