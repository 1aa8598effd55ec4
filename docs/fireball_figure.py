"""Equal-time picture of the fire showcase (docs/fireball-equal-time.png).

Generates the fireball VDB (scenes/make_fireball.py, Debian's python3 with
python3-openvdb), renders scenes/fireball.json at 240x240 with `volpath` with
and without volume light sampling for the same number of seconds each, and
puts them side by side with their labels. Needs a release build of niebla
and Pillow:

    cargo build --release -p niebla-cli
    python3 docs/fireball_figure.py [SECONDS]   # e.g. bench/.venv/bin/python after bench/.venv/bin/pip install pillow
"""

import json
import os
import subprocess
import sys
import tempfile

from PIL import Image, ImageDraw

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NIEBLA = os.path.join(ROOT, "target", "release", "niebla")


def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 20.0
    with open(os.path.join(ROOT, "scenes", "fireball.json")) as f:
        scene = json.load(f)
    scene["camera"]["width"], scene["camera"]["height"] = 240, 240
    panels = []
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scenes", "make_fireball.py"),
                        os.path.join(tmp, "fireball.vdb")], check=True, capture_output=True)
        for on in [False, True]:
            scene["render"]["integrator"]["volume_light_sampling"] = on
            path = os.path.join(tmp, "fireball.json")
            with open(path, "w") as f:
                json.dump(scene, f)
            out = os.path.join(tmp, f"vls_{on}.png")
            run = subprocess.run(
                [NIEBLA, "render", path, "--time", str(seconds), "-o", out, "--exposure", "0.5", "--quiet"],
                check=True, capture_output=True, text=True)
            summary = run.stdout.strip().splitlines()[-1]
            spp = summary.split(" at ")[1].split(" spp")[0]
            what = "volume light sampling" if on else "free flight only"
            panels.append((Image.open(out).convert("RGB"), f"{what}: {spp} spp in {seconds:g} s"))
    w, h = panels[0][0].size
    figure = Image.new("RGB", (2 * w + 4, h + 18), "white")
    draw = ImageDraw.Draw(figure)
    for i, (image, label) in enumerate(panels):
        figure.paste(image, (i * (w + 4), 18))
        draw.text((i * (w + 4) + 4, 3), label, fill="black")
    target = os.path.join(ROOT, "docs", "fireball-equal-time.png")
    figure.save(target, optimize=True)
    print(target, os.path.getsize(target), "bytes")


if __name__ == "__main__":
    main()
