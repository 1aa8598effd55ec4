#!/usr/bin/env python3
"""Fills fuzz/corpus/<target>/ with seed inputs from the project:

- scene and render: scenes/*.json and every JSON scene written as a raw string literal
  (r#"{ ... }"#) in crates/niebla/tests/*.rs;
- vdb: the OpenVDB test files (target/tmp/niebla_test_vdbs, written by
  /work/shared/vdb/make_test_vdbs.py; generated here with --no-big if missing),
  up to 256 KiB each;
- vol, npy: the files the niebla-volume tests write under target/tmp
  (run `cargo test -p niebla-volume` once first), plus two made here.

Usage: python3 fuzz/seed_corpus.py   (from anywhere)
"""
import glob
import hashlib
import os
import re
import struct
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")
MAX_SEED = 256 * 1024


def put(target, data):
    if target == "scene":
        put("render", data)  # the render target reads scenes too
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    name = hashlib.sha1(data).hexdigest()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def seed_scenes():
    n = 0
    for p in glob.glob(os.path.join(ROOT, "scenes", "*.json")):
        put("scene", open(p, "rb").read())
        n += 1
    raw = re.compile(r'r(#+)"(\s*\{.*?)"\1', re.S)
    for p in glob.glob(os.path.join(ROOT, "crates", "niebla", "tests", "*.rs")):
        for m in raw.finditer(open(p, encoding="utf-8").read()):
            text = m.group(2)
            if '"version"' in text or '"camera"' in text or '"media"' in text:
                put("scene", text.encode())
                n += 1
    return n


def seed_files(target, pattern):
    n = 0
    for p in glob.glob(pattern):
        if os.path.getsize(p) <= MAX_SEED:
            put(target, open(p, "rb").read())
            n += 1
    return n


FILES = {
    # name the test scenes use: where a small valid file of that kind is
    "density.npy": "target/tmp/bright.npy",
    "glow.npy": "target/tmp/bright.npy",
    "rgb.npy": "target/tmp/bright_rgb.npy",
    "bunny.vol": "target/tmp/bright.vol",
    "plume.vdb": "target/tmp/niebla_test_vdbs/density_blosc.vdb",
    "multi_density_temperature.vdb": "target/tmp/niebla_test_vdbs/multi_density_temperature.vdb",
    "levelset_sphere.vdb": "target/tmp/niebla_test_vdbs/levelset_sphere.vdb",
    "xform_affine_rotated.vdb": "target/tmp/niebla_test_vdbs/xform_affine_rotated.vdb",
    "mie.csv": "crates/niebla/data/mie_fog_phase.csv",
    "sky.exr": "target/tmp/envmap_scene/sky.exr",
}


def copy_files():
    """Files the scene target's scenes may name (fuzz/files/)."""
    d = os.path.join(ROOT, "fuzz", "files")
    os.makedirs(d, exist_ok=True)
    n = 0
    for name, src in FILES.items():
        src = os.path.join(ROOT, src)
        if os.path.exists(src):
            with open(src, "rb") as f, open(os.path.join(d, name), "wb") as g:
                g.write(f.read())
            n += 1
    return n


def main():
    print("scene seeds:", seed_scenes())
    vdb_dir = os.path.join(ROOT, "target", "tmp", "niebla_test_vdbs")
    if not glob.glob(os.path.join(vdb_dir, "*.vdb")):
        script = os.environ.get("NIEBLA_VDB_SCRIPT", "/work/shared/vdb/make_test_vdbs.py")
        subprocess.run(["/usr/bin/python3", script, vdb_dir, "--no-big"], check=True)
    print("vdb seeds:", seed_files("vdb", os.path.join(vdb_dir, "*.vdb")))
    print("files for scenes:", copy_files())
    tmp = os.path.join(ROOT, "target", "tmp")
    # A small valid file of each kind, whatever the tests left behind.
    vol = b"VOL\x03" + struct.pack("<5i", 1, 2, 2, 2, 1) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    put("vol", vol + struct.pack("<8f", *range(8)))
    header = b"{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2, 2), }"
    header += b" " * (63 - len(header)) + b"\n"
    put("npy", b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + struct.pack("<8f", *range(8)))
    print("vol seeds:", seed_files("vol", os.path.join(tmp, "*.vol")) + 1)
    print("npy seeds:", seed_files("npy", os.path.join(tmp, "*.npy")) + 1)


if __name__ == "__main__":
    sys.exit(main())
