"""Equal-time picture of the volumetric caustic (docs/caustic-equal-time.png).

Renders scenes/caustic_fog_area.json at 200x150 with `volpath` and with `ppm`
(the scene's own settings: beam queries, initial radius 0.1) for the same
number of seconds each, and puts them side by side with their labels.
Needs a release build of niebla and Pillow:

    cargo build --release -p niebla-cli
    python3 docs/caustic_figure.py [SECONDS]
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
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    with open(os.path.join(ROOT, "scenes", "caustic_fog_area.json")) as f:
        scene = json.load(f)
    scene["camera"]["width"], scene["camera"]["height"] = 200, 150
    panels = []
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "caustic.json")
        with open(path, "w") as f:
            json.dump(scene, f)
        for integrator in ["volpath", "ppm"]:
            out = os.path.join(tmp, f"{integrator}.png")
            run = subprocess.run(
                [NIEBLA, "render", path, "--integrator", integrator, "--time", str(seconds), "-o", out,
                 "--exposure", "1", "--quiet"],
                check=True, capture_output=True, text=True)
            summary = run.stdout.strip().splitlines()[-1]
            spp = summary.split(" at ")[1].split(" spp")[0]
            panels.append((Image.open(out).convert("RGB"), f"{integrator}: {spp} spp in {seconds:g} s"))
    w, h = panels[0][0].size
    figure = Image.new("RGB", (2 * w + 4, h + 18), "white")
    draw = ImageDraw.Draw(figure)
    for i, (image, label) in enumerate(panels):
        figure.paste(image, (i * (w + 4), 18))
        draw.text((i * (w + 4) + 4, 3), label, fill="black")
    target = os.path.join(ROOT, "docs", "caustic-equal-time.png")
    figure.save(target, optimize=True)
    print(target)


if __name__ == "__main__":
    main()
