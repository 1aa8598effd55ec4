"""Round trip: niebla JSON -> Mitsuba XML (bench/niebla2mitsuba.py and
bench/mitsuba_xml.py) -> niebla's XML importer, rendered against the
original.

    /work/main/bench/.venv/bin/python bench/roundtrip.py [--niebla PATH] [--spp 16] [--size 32]
        [--only NAME ...] [--mitsuba N [--mitsuba-spp 256]]

For every scene in bench/scenes/ and scenes/ the converter accepts, writes
the XML to bench/out/roundtrip/, renders the JSON and the XML with the same
niebla binary, seed, sample count and sampler (the camera resized to --size
pixels wide in both; each sampler in --samplers, passed as `--sampler` to
both renders because the XML names Mitsuba's `independent` sampler), and
requires the two images to be bit-identical. It also converts the XML back
to niebla JSON (`niebla convert`) and requires the camera, depth, media
coefficients (niebla's float32 sigma_a and sigma_s), phase functions,
shapes and lights to be the same float32 values as the original's. Scenes
the converter refuses are listed with its reason. With `--mitsuba N` each
converted XML is also rendered N times by Mitsuba 3 (llvm_ad_rgb) and the
JSON N times by niebla, and the image means are printed with z-scores: the
converted scene means the same in Mitsuba. Exit status 1 when a
converted scene fails to load, differs structurally, or renders a different
image.

Why it is exact: the converter writes the numbers of the niebla scene as
written (camera and spot `<lookat>`, a rectangle's `<scale>`, `<rotate>`,
`<translate>`), and niebla's importer hands a lone `<lookat>` and a
transform in niebla's own order back to niebla unchanged; media go out as
sigma_t = sigma_a + sigma_s and albedo = sigma_s / sigma_t of niebla's own
float32 coefficients (in float64), which the importer turns back into
sigma_a and sigma_s in float64 and rounds to those float32 values.
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


def structural_differences(orig: dict, conv: dict) -> list:
    """What differs between the original niebla scene and the one read back
    from XML as the float32 values niebla keeps."""
    import niebla2mitsuba as n2m

    out = []
    f32 = lambda v: np.array(v, dtype=np.float32)

    def same(a, b, what):
        a, b = f32(a), f32(b)
        if a.shape != b.shape or not np.array_equal(a, b):
            out.append(f"{what}: {a.tolist()} vs {b.tolist()}")

    oc, cc = orig["camera"], conv["camera"]
    for k, default in (("position", None), ("target", None), ("up", [0, 1, 0]), ("fov_y", 40)):
        same(oc.get(k, default), cc.get(k, default), f"camera.{k}")
    oi, ci = orig["render"]["integrator"], conv["render"]["integrator"]
    if oi.get("max_depth", 1024) != ci.get("max_depth", 1024):
        out.append(f"max_depth {oi.get('max_depth')} vs {ci.get('max_depth')}")
    if len(orig.get("media", {})) != len(conv["media"]):
        out.append("number of media")
    for name, m in orig.get("media", {}).items():
        cm = conv["media"]["medium_" + name]
        for a, b, what in zip(n2m.niebla_coefficients(m), n2m.niebla_coefficients(cm), ("sigma_a", "sigma_s")):
            same(a, b, f"media.{name}.{what}")
        op, cp = m.get("phase", {"type": "isotropic"}), cm["phase"]
        if op["type"] != cp["type"] or any(not np.array_equal(f32(op[k]), f32(cp.get(k))) for k in op if k != "type"):
            out.append(f"media.{name}.phase: {op} vs {cp}")
    os_, cs = orig.get("shapes", []), conv["shapes"]
    if [s["type"] for s in os_] != [s["type"] for s in cs]:
        out.append(f"shape types {[s['type'] for s in os_]} vs {[s['type'] for s in cs]}")
    else:
        for i, (a, b) in enumerate(zip(os_, cs)):
            for k in ("min", "max", "center", "radius"):
                if k in a:
                    same(a[k], b[k], f"shapes[{i}].{k}")
            ra, rb = a.get("rotation") or {}, b.get("rotation") or {}
            if set(ra) != set(rb):
                out.append(f"shapes[{i}].rotation: {ra} vs {rb}")
            else:
                for k in ra:
                    same(ra[k], rb[k], f"shapes[{i}].rotation.{k}")
            if "to_world" in a:
                ta, tb = a["to_world"], b.get("to_world", {})
                for k in set(ta) | set(tb):
                    same(ta.get(k, 0.0), tb.get(k, 0.0), f"shapes[{i}].to_world.{k}")
    ol, cl = orig.get("lights", []), conv["lights"]
    if [l["type"] for l in ol] != [l["type"] for l in cl]:
        out.append("light types")
    else:
        for i, (a, b) in enumerate(zip(ol, cl)):
            for k in set(a) - {"type"}:
                va, vb = a[k], b.get(k)
                if k == "shape":
                    out += _light_shape_differences(va, vb, f"lights[{i}].shape")
                    continue
                if k == "two_sided":
                    if bool(va) != bool(vb):
                        out.append(f"lights[{i}].two_sided: {va} vs {vb}")
                    continue
                if isinstance(va, (int, float)) and isinstance(vb, list):
                    va = [va] * 3
                if isinstance(vb, (int, float)) and isinstance(va, list):
                    vb = [vb] * 3
                same(va, vb, f"lights[{i}].{k}")
    return out


def _light_shape_differences(a: dict, b: dict, where: str) -> list:
    """What differs between an area light's shape and the one read back
    (type, sphere center and radius, to_world, a mesh's file name and its
    flip_normals and face_normals; a sphere light's `rotation` has no effect
    and is not written)."""
    out = []
    f32 = lambda v: np.array(v, dtype=np.float32)
    if a["type"] != b["type"]:
        return [f"{where}.type: {a['type']} vs {b['type']}"]
    for k in ("center", "radius"):
        if k in a and not np.array_equal(f32(a[k]), f32(b.get(k))):
            out.append(f"{where}.{k}: {a[k]} vs {b.get(k)}")
    ta, tb = a.get("to_world") or {}, b.get("to_world") or {}
    for k in set(ta) | set(tb):
        default = 1.0 if k == "scale" else 0.0
        va, vb = f32(ta.get(k, default)), f32(tb.get(k, default))
        if k == "scale":
            va, vb = np.broadcast_to(va, 3), np.broadcast_to(vb, 3)
        if k == "translate":
            va, vb = np.broadcast_to(va, 3), np.broadcast_to(vb, 3)
        if not np.array_equal(va, vb):
            out.append(f"{where}.to_world.{k}: {ta.get(k)} vs {tb.get(k)}")
    if a["type"] == "mesh":
        if os.path.basename(a["file"]) != os.path.basename(b.get("file", "")):
            out.append(f"{where}.file: {a['file']} vs {b.get('file')}")
        for k in ("flip_normals", "face_normals"):
            if bool(a.get(k)) != bool(b.get(k)):
                out.append(f"{where}.{k}: {a.get(k)} vs {b.get(k)}")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--niebla", default=os.path.join(ROOT, "target", "debug", "niebla"))
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--size", type=int, default=32)
    ap.add_argument("--samplers", nargs="+", default=["independent", "sobol"], choices=["independent", "sobol"])
    ap.add_argument("--only", nargs="+", metavar="NAME", help="only these scenes (file names without .json)")
    ap.add_argument("--mitsuba", type=int, default=0, metavar="N",
                    help="also render each converted XML N times with Mitsuba 3 (llvm_ad_rgb) and the JSON N times "
                         "with niebla, at --mitsuba-spp each, and print the image means with their z-scores")
    ap.add_argument("--mitsuba-spp", type=int, default=256)
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
        if a.only and name not in a.only:
            continue
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
        # An XML mesh's vertex normals shade by Mitsuba's rule where wo lies
        # behind them (the importer's "shading_normal_backside": "mitsuba"):
        # the JSON side says so too.
        for shape in desc.get("shapes", []):
            if shape.get("type") == "mesh" and not shape.get("face_normals"):
                shape.setdefault("shading_normal_backside", "mitsuba")
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
        print(f"{name}: read back: " + ("the same float32 values" if not diffs else "; ".join(diffs)))
        failed |= bool(diffs)
        try:
            for sampler in a.samplers:
                imgs = []
                for src, tag in ((js, "json"), (xml, "xml")):
                    exr = os.path.join(out, f"{name}_{sampler}_{tag}.exr")
                    r = subprocess.run([a.niebla, "render", src, "--spp", str(a.spp), "--seed", "0", "--sampler", sampler,
                                        "--quiet", "-o", exr], capture_output=True, text=True)
                    if r.returncode != 0:
                        print(f"{name}: {tag}: niebla failed: {r.stderr.strip()}")
                        failed = True
                        break
                    imgs.append(read_exr(exr))
                if len(imgs) != 2:
                    continue
                x, y = imgs
                same = np.all(x == y, axis=2).mean()
                mean_rel = abs(x.mean() - y.mean()) / y.mean()
                if same == 1.0:
                    print(f"{name}: {sampler}: {x.shape[1]}x{x.shape[0]} at {a.spp} spp: bit-identical "
                          f"(image mean {y.mean():.6g})")
                else:
                    rel = np.abs(x - y) / np.maximum(np.abs(y), 1e-6)
                    print(f"{name}: {sampler}: NOT bit-identical: {100 * same:.1f}% of pixels equal, largest per-pixel "
                          f"relative difference {rel.max():.2e}; image means differ by {100 * mean_rel:.4f}%")
                    failed = True
            if a.mitsuba:
                mitsuba_means(a, name, js, xml, out)
        finally:
            os.remove(js)
    sys.exit(1 if failed else 0)


MITSUBA_RENDER = """
import json, sys
import numpy as np
sys.path.insert(0, {here!r})
import llvm
llvm.use_newest_llvm()
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
scene = mi.load_file({xml!r})
means = [np.array(mi.render(scene, spp={spp}, seed=1000 + i), dtype=np.float64)[:, :, :3].mean(axis=(0, 1)).tolist()
         for i in range({n})]
print(json.dumps(means))
"""


def mitsuba_means(a, name, js, xml, out):
    """Image means of `a.mitsuba` Mitsuba renders of the converted XML
    (another process: llvm_ad_rgb) and as many niebla renders of the JSON,
    each at `a.mitsuba_spp`, with the z-score of their difference per
    channel (both sides' standard errors from the spread of the renders)."""
    code = MITSUBA_RENDER.format(here=HERE, xml=xml, spp=a.mitsuba_spp, n=a.mitsuba)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"{name}: Mitsuba failed: {r.stderr.strip()[-2000:]}")
        return
    mit = np.array(json.loads(r.stdout.strip().splitlines()[-1]))
    nie = []
    for i in range(a.mitsuba):
        exr = os.path.join(out, f"{name}_mean_{i}.exr")
        subprocess.run([a.niebla, "render", js, "--spp", str(a.mitsuba_spp), "--seed", str(i), "--quiet", "-o", exr],
                       check=True, capture_output=True)
        nie.append(read_exr(exr).mean(axis=(0, 1)))
    nie = np.array(nie)
    n = a.mitsuba
    se = np.sqrt(mit.var(axis=0, ddof=1) / n + nie.var(axis=0, ddof=1) / n)
    rel = nie.mean(axis=0) / mit.mean(axis=0) - 1
    z = (nie.mean(axis=0) - mit.mean(axis=0)) / se
    print(f"{name}: image means over {n} x {a.mitsuba_spp} spp: niebla (JSON) {np.round(nie.mean(axis=0), 5).tolist()}, "
          f"Mitsuba (XML) {np.round(mit.mean(axis=0), 5).tolist()}: niebla/Mitsuba - 1 = "
          f"{' '.join(f'{100 * x:+.2f}%' for x in rel)} (z {' '.join(f'{x:+.2f}' for x in z)})")


if __name__ == "__main__":
    main()
