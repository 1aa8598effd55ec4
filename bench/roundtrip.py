"""Round trip: niebla JSON -> Mitsuba XML (bench/niebla2mitsuba.py and
bench/mitsuba_xml.py) -> niebla's XML importer, rendered against the
original.

    /work/main/bench/.venv/bin/python bench/roundtrip.py [--niebla PATH] [--spp 64] [--size 48]

For every scene in bench/scenes/ and scenes/ the converter accepts, writes
the XML to bench/out/roundtrip/, renders the JSON and the XML with the same
niebla binary, seed and sample count (the camera resized to --size pixels
wide in both), and prints how many pixels are bit-identical, the largest
per-pixel difference and the difference of the image means; it also
converts the XML back to niebla JSON (`niebla convert`) and checks camera,
depth, media coefficients, phase functions, shapes and lights against the
original within f32 rounding (relative 1e-6, 1e-5 for coefficients). Scenes
the converter refuses are listed with its reason. Exit status 1 when a
converted scene fails to load, differs structurally, or the image means
differ by more than --mean-tolerance (relative, default 1%).

Bit-identical images are not possible: the converter writes transforms as
float32 matrices computed in float64 (niebla composes `rotate_x: -90` in
float32, where cos 90 deg is -4.4e-8, not 6e-17), the camera's look-at
matrix holds the normalized view direction in float32, and media are
rewritten from sigma_a/sigma_s to sigma_t/albedo/scale. Each changes some
values in their last bit, and one flipped random decision (a null collision,
Russian roulette) decorrelates the rest of that path.
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


def _coeffs(m):
    """(sigma_a, sigma_s) per unit length (per unit density for grids), scale applied."""
    scale = float(m.get("scale", 1.0))
    c = lambda v: np.array([v] * 3 if isinstance(v, (int, float)) else v, dtype=float)
    if "sigma_t" in m:
        st, al = c(m["sigma_t"]), c(m.get("albedo", 1.0))
        return st * (1 - al) * scale, st * al * scale
    return c(m["sigma_a"]) * scale, c(m["sigma_s"]) * scale


def structural_differences(orig: dict, conv: dict) -> list:
    """What differs between the original niebla scene and the one read back
    from XML by more than f32 rounding (relative 1e-6)."""
    out = []

    def close(a, b, what, tol=1e-6):
        a, b = np.array(a, dtype=float), np.array(b, dtype=float)
        if a.shape != b.shape or not np.allclose(a, b, rtol=tol, atol=tol):
            out.append(f"{what}: {a.tolist()} vs {b.tolist()}")

    oc, cc = orig["camera"], conv["camera"]
    close(oc["position"], cc["position"], "camera.position")
    d = lambda c: (np.array(c["target"], float) - c["position"]) / np.linalg.norm(np.array(c["target"], float) - c["position"])
    close(d(oc), d(cc), "camera direction")
    close(oc.get("fov_y", 40), cc["fov_y"], "camera.fov_y")
    oi, ci = orig["render"]["integrator"], conv["render"]["integrator"]
    if oi.get("max_depth", 1024) != ci.get("max_depth", 1024):
        out.append(f"max_depth {oi.get('max_depth')} vs {ci.get('max_depth')}")
    if len(orig.get("media", {})) != len(conv["media"]):
        out.append("number of media")
    for name, m in orig.get("media", {}).items():
        cm = conv["media"]["medium_" + name]
        for a, b, what in zip(_coeffs(m), _coeffs(cm), ("sigma_a", "sigma_s")):
            close(a, b, f"media.{name}.{what}", tol=1e-5)
        if m.get("phase", {"type": "isotropic"}) != cm["phase"]:
            out.append(f"media.{name}.phase: {m.get('phase')} vs {cm['phase']}")
    os_, cs = orig.get("shapes", []), conv["shapes"]
    if [s["type"] for s in os_] != [s["type"] for s in cs]:
        out.append(f"shape types {[s['type'] for s in os_]} vs {[s['type'] for s in cs]}")
    else:
        import niebla2mitsuba as n2m

        for i, (a, b) in enumerate(zip(os_, cs)):
            for k in ("min", "max", "center", "radius"):
                if k in a:
                    close(a[k], b[k], f"shapes[{i}].{k}")
            if a["type"] == "rectangle":
                close(n2m.niebla_transform(a.get("to_world")), b["to_world"]["matrix"], f"shapes[{i}].to_world")
    ol, cl = orig.get("lights", []), conv["lights"]
    if [l["type"] for l in ol] != [l["type"] for l in cl]:
        out.append("light types")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--niebla", default=os.path.join(ROOT, "target", "debug", "niebla"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--size", type=int, default=48)
    ap.add_argument("--mean-tolerance", type=float, default=0.01)
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
        conv = os.path.join(out, name + "_converted.json")
        r = subprocess.run([a.niebla, "convert", xml, "-o", conv], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{name}: convert failed: {r.stderr.strip()}")
            failed = True
            os.remove(js)
            continue
        with open(conv) as f:
            diffs = structural_differences(desc, json.load(f))
        print(f"{name}: read back: " + ("the same scene within f32 rounding" if not diffs else "; ".join(diffs)))
        failed |= bool(diffs)
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
