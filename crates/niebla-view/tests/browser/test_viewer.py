"""The viewer in a real browser: Debian's chromium driven headless by
Playwright opens `niebla view` on a small fog scene and checks, from pixel
statistics of screenshots of the canvas, that the image changes from pass to
pass, that a camera drag changes it, that a denser medium darkens the
background seen through it, that the integrator switch and the split view
work (with a relative MSE shown), that an invalid value shows the command
line's message, and that a saved EXR carries the edited scene, which niebla
reads back.

Run: NIEBLA_BIN=target/release/niebla .venv-py/bin/python crates/niebla-view/tests/browser/test_viewer.py [--screenshot docs/viewer.png]
Exits 0 when every check passes, 77 (skip) without /usr/bin/chromium.
"""

import io
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"

# A box of absorbing, weakly scattering fog in front of a bright sky: a denser
# fog darkens the sky seen through it (transmittance exp(-sigma_t d)).
SCENE = {
    "version": 1,
    "camera": {"type": "perspective", "position": [0, 1, 5], "target": [0, 1, 0], "fov_y": 40, "width": 160, "height": 120},
    "render": {"integrator": {"type": "single", "sampling": "mis"}, "spp": 16, "seed": 1},
    "media": {"fog": {"sigma_a": 0.25, "sigma_s": 0.15, "phase": {"type": "hg", "g": 0.3}}},
    "shapes": [
        {"type": "box", "min": [-1.2, -0.2, -1.2], "max": [1.2, 2.2, 1.2], "interior": "fog"},
        {"type": "sphere", "center": [0.6, 0.6, -3], "radius": 0.6, "bsdf": {"type": "diffuse", "reflectance": [0.8, 0.3, 0.2]}},
    ],
    "lights": [
        {"type": "point", "position": [1.5, 3, 1.5], "intensity": [30, 28, 25]},
        {"type": "constant", "radiance": [0.6, 0.7, 0.9]},
    ],
}


def exr_text_attributes(path):
    """The text (`string`) attributes of an OpenEXR file's header."""
    data = Path(path).read_bytes()
    assert data[:4] == b"\x76\x2f\x31\x01", "not an EXR file"
    pos, out = 8, {}
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        name, kind = data[pos:name_end].decode(), data[name_end + 1:type_end].decode()
        (size,) = struct.unpack("<i", data[type_end + 1:type_end + 5])
        value = data[type_end + 5:type_end + 5 + size]
        if kind == "string":
            out[name] = value.decode()
        pos = type_end + 5 + size
    return out


def main():
    if not os.path.exists(CHROMIUM):
        print(f"skipped: {CHROMIUM} is missing (apt-get install chromium)")
        return 77
    from PIL import Image
    import numpy as np
    from playwright.sync_api import sync_playwright

    root = Path(__file__).resolve().parents[4]
    niebla = os.environ.get("NIEBLA_BIN", str(root / "target/release/niebla"))
    screenshot_out = sys.argv[sys.argv.index("--screenshot") + 1] if "--screenshot" in sys.argv else None
    work = Path(tempfile.mkdtemp(prefix="niebla-view-browser-"))
    scene_path = work / "fog.json"
    scene_path.write_text(json.dumps(SCENE, indent=1))
    server = subprocess.Popen([niebla, "view", str(scene_path), "--threads", "2"], stdout=subprocess.PIPE, text=True)
    checks = []

    def check(name, ok, detail=""):
        checks.append((name, ok))
        print(f"{'ok  ' if ok else 'FAIL'} {name} {detail}")

    try:
        url = re.search(r"http://\S+", server.stdout.readline()).group(0)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True,
                                        args=["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
            page = browser.new_page(viewport={"width": 1100, "height": 800})
            page.goto(url)
            view = lambda expr: page.evaluate(f"() => {expr}")

            def wait(expr, timeout=60):
                start = time.time()
                while time.time() - start < timeout:
                    if view(expr):
                        return True
                    time.sleep(0.05)
                return False

            def shot():
                png = page.locator("#canvas").screenshot()
                return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64)

            def settled():
                """Wait until the latest edit's full-resolution frame is shown (2+ spp), then screenshot."""
                time.sleep(0.3)
                assert wait("!window.nieblaView.busy && window.nieblaView.frames[0] && !window.nieblaView.frames[0].interactive && "
                            "window.nieblaView.frames[0].version === window.nieblaView.lastVersion && "
                            "window.nieblaView.frames[0].spp >= 4"), "no settled frame"
                return shot()

            # Passes: the first frames differ pixel by pixel as samples accumulate.
            # An early pass (whichever the page catches: on a fast machine the
            # first passes land between two polls), then one with 4x its samples.
            page.fill("#max-spp", "256")
            page.dispatch_event("#max-spp", "change")
            assert wait("window.nieblaView.frames[0]?.version === window.nieblaView.lastVersion && "
                        "window.nieblaView.frames[0]?.spp <= 32"), "no early pass"
            first_spp = view("window.nieblaView.frames[0].spp")
            first = shot()
            assert wait(f"window.nieblaView.frames[0]?.spp >= {4 * first_spp}"), "no later pass"
            later = shot()
            diff = np.abs(first - later).mean()
            check("image changes from pass to pass", diff > 0.05, f"(mean |difference| {diff:.3f} levels)")
            status = page.inner_text("#status")
            check("status shows spp, time, samples/s and error", all(s in status for s in ["spp", " s ", "Msamples/s", "est. rel. error"]), repr(status))

            # Camera drag: orbit by 80 pixels.
            before = settled()
            box = page.locator("#canvas").bounding_box()
            cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(cx, cy)
            page.mouse.down()
            for i in range(1, 9):
                page.mouse.move(cx + 10 * i, cy, steps=1)
                time.sleep(0.05)
            page.mouse.up()
            after = settled()
            drag_frames = [l for l in view("window.nieblaView.latencies") if l["interactive"]]
            check("camera drag changes the image", np.abs(after - before).mean() > 1.0, f"(mean |difference| {np.abs(after - before).mean():.2f} levels, {len(drag_frames)} drag frames)")

            # Density: the sky seen through the fog (top rows of the box region) darkens.
            before = settled()
            page.fill('input[data-path="media.fog.scale#number"]', "4")
            page.dispatch_event('input[data-path="media.fog.scale#number"]', "change")
            after = settled()
            h, w = before.shape[:2]
            window = (slice(int(0.2 * h), int(0.45 * h)), slice(int(0.4 * w), int(0.6 * w)))
            b, a = before[window].mean(), after[window].mean()
            check("denser medium darkens the background", a < b - 10, f"(mean level {b:.1f} -> {a:.1f})")

            # An invalid value: the command line's message, shown in the page; the render goes on.
            page.fill('input[data-path="media.fog.sigma_a#number"]', "-1")
            page.dispatch_event('input[data-path="media.fog.sigma_a#number"]', "change")
            wait("!document.getElementById('error').hidden", 10)
            shown = page.inner_text("#error")
            bad = json.loads(scene_path.read_text())
            bad["media"]["fog"]["sigma_a"] = -1.0
            bad["media"]["fog"]["scale"] = 4.0
            bad_path = work / "bad" / "fog.json"
            bad_path.parent.mkdir()
            bad_path.write_text(json.dumps(bad))
            cli = subprocess.run([niebla, "info", str(bad_path)], capture_output=True, text=True)
            cli_message = cli.stderr.strip().removeprefix("error: ").replace(str(bad_path), str(scene_path))
            check("invalid value shows the command line's message", shown == cli_message, f"({shown!r})")
            page.fill('input[data-path="media.fog.sigma_a#number"]', "0.25")
            page.dispatch_event('input[data-path="media.fog.sigma_a#number"]', "change")
            wait("document.getElementById('error').hidden", 10)

            # Integrator switch.
            page.select_option("#integrator", "hegeman")
            ok = wait("window.nieblaView.frames[0]?.integrator === 'hegeman'", 60)
            check("integrator switch", ok, f"({view('window.nieblaView.frames[0].integrator')})")
            page.select_option("#integrator", "single")
            wait("window.nieblaView.frames[0]?.integrator === 'single'", 60)

            # Split view: single against volpath, the wipe and the error map.
            page.select_option("#compare-integrator", "volpath")
            page.select_option("#split-mode", "1")
            ok = wait("window.nieblaView.frames[1]?.integrator === 'volpath' && window.nieblaView.frames[1].spp >= 4 && window.nieblaView.relativeMse > 0", 90)
            wipe = shot()
            page.select_option("#split-mode", "2")
            time.sleep(0.3)
            error_map = shot()
            mse = view("window.nieblaView.relativeMse")
            check("split view renders volpath beside single with a relative MSE", ok and np.abs(wipe - error_map).mean() > 5, f"(relative MSE {mse})")
            check("bias is named", "biased" in page.inner_text("#bias-note"), repr(page.inner_text("#bias-note")))
            page.select_option("#split-mode", "1")
            time.sleep(0.5)
            if screenshot_out:
                page.screenshot(path=screenshot_out)

            # Save: the EXR carries the edited scene, which niebla reads back.
            page.click("#save-exr")
            wait("window.nieblaView.saved?.endsWith('.exr')", 10)
            saved = view("window.nieblaView.saved")
            attributes = exr_text_attributes(saved)
            embedded = json.loads(attributes["niebla:scene"])
            (work / "from-exr.json").write_text(json.dumps(embedded))
            info = subprocess.run([niebla, "info", str(work / "from-exr.json")], capture_output=True, text=True)
            check("saved EXR holds the edited scene, read back by niebla",
                  embedded["media"]["fog"]["scale"] == 4 and info.returncode == 0 and "sigma_a [1.0, 1.0, 1.0]" in info.stdout,
                  f"({saved}; {info.stdout.splitlines()[4].strip() if info.returncode == 0 else info.stderr})")
            page.click("#save-scene")
            wait("window.nieblaView.saved?.endsWith('.json')", 10)
            check("edited scene saved beside the original", Path(view("window.nieblaView.saved")).parent == work and json.loads(scene_path.read_text()) == SCENE)
            browser.close()
    finally:
        server.terminate()
        server.wait(10)
        shutil.rmtree(work, ignore_errors=True)
    failed = [name for name, ok in checks if not ok]
    print(f"{len(checks) - len(failed)} of {len(checks)} browser checks passed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
