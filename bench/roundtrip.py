"""Round trip: niebla JSON -> Mitsuba XML (bench/niebla2mitsuba.py and
bench/mitsuba_xml.py) -> niebla's XML importer, rendered against the
original.

    /work/main/bench/.venv/bin/python bench/roundtrip.py [--niebla PATH] [--spp 2] [--size 64]

For every scene in bench/scenes/ and scenes/ the converter accepts, writes
the XML to bench/out/roundtrip/, renders the JSON and the XML with the same
niebla binary, seed and sample count (the camera resized to --size pixels
wide in both), and prints how many pixels are bit-identical, the largest
per-pixel difference and the difference of the image means. Scenes the
converter refuses are listed with its reason. Exit status 1 when a
converted scene fails to load or the image means differ by more than
--mean-tolerance (relative).
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)


def read_exr(path):
    import mitsuba as mi

    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--niebla", default=os.path.join(ROOT, "target", "debug", "niebla"))
    ap.add_argument("--spp", type=int, default=2)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--mean-tolerance", type=float, default=0.02)
    a = ap.parse_args()
    import llvm

    llvm.use_newest_llvm()
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    import mitsuba_xml
    import niebla2mitsuba as n2m
    import volumes

    volumes.ensure_volumes(log=lambda *_: None)
    out = os.path.join(HERE, "out", "roundtrip")
    os.makedirs(out, exist_ok=True)
    failed = False
    for path in sorted(glob.glob(os.path.join(HERE, "scenes", "*.json")) + glob.glob(os.path.join(ROOT, "scenes", "*.json"))):
        name = os.path.splitext(os.path.basename(path))[0]
        try:
            d = n2m.load(path, spp=a.spp)
        except n2m.Unsupported as e:
            print(f"{name}: not converted ({e})")
            continue
        with open(path) as f:
            desc = json.load(f)
        cam = desc["camera"]
        h = max(1, round(a.size * cam["height"] / cam["width"]))
        # Same resolution on both sides: the JSON is edited, the XML gets the same numbers.
        cam["width"], cam["height"] = a.size, h
        d["sensor"]["film"]["width"], d["sensor"]["film"]["height"] = a.size, h
        js = os.path.join(os.path.dirname(path), f".roundtrip_{name}.json")
        xml = os.path.join(out, name + ".xml")
        with open(js, "w") as f:
            json.dump(desc, f)
        with open(xml, "w") as f:
            f.write(mitsuba_xml.dict_to_xml(d))
        imgs = []
        try:
            for src, tag in ((js, "json"), (xml, "xml")):
                exr = os.path.join(out, f"{name}_{tag}.exr")
                r = subprocess.run([a.niebla, "render", src, "--spp", str(a.spp), "--seed", "0", "--quiet", "-o", exr],
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    print(f"{name}: {tag}: niebla failed: {r.stderr.strip()}")
                    failed = True
                    break
                imgs.append(read_exr(exr))
        finally:
            os.remove(js)
        if len(imgs) != 2:
            continue
        x, y = imgs
        same = np.all(x == y, axis=2).mean()
        rel = np.abs(x - y) / np.maximum(np.abs(y), 1e-6)
        mean_rel = abs(x.mean() - y.mean()) / y.mean()
        print(f"{name}: {100 * same:.1f}% of pixels bit-identical, median per-pixel relative difference "
              f"{np.median(rel):.2e}, largest {rel.max():.2e}; image means differ by {100 * mean_rel:.4f}%")
        if mean_rel > a.mean_tolerance:
            failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
