#!/usr/bin/env python3
"""Fills fuzz/corpus/<target>/ with seed inputs from the project:

- scene and render: scenes/*.json and every JSON scene written as a raw string literal
  (r#"{ ... }"#) in crates/niebla/tests/*.rs;
- vdb: the OpenVDB test files (target/tmp/niebla_test_vdbs, written by
  /work/shared/vdb/make_test_vdbs.py; generated here with --no-big if missing),
  up to 256 KiB each;
- vol, npy: the files the niebla-volume tests write under target/tmp
  (run `cargo test -p niebla-volume` once first), plus two made here;
- ply, obj: an octahedron in every PLY encoding and as OBJ, polygons, skipped
  elements and lists, several objects, and the real meshes in
  crates/niebla-mesh/tests/data (obj inputs start with the target's
  object-selector byte).

Usage: python3 fuzz/seed_corpus.py          (from anywhere; every target)
       python3 fuzz/seed_corpus.py ply obj  (only the mesh targets)
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
    # the Mitsuba XML seeds (scenes/mitsuba/*.xml) name their grids under data/
    "data/smoke.vol": "scenes/mitsuba/data/smoke.vol",
    "data/albedo_rgb.vol": "scenes/mitsuba/data/albedo_rgb.vol",
}


def copy_files():
    """Files the scene target's scenes may name (fuzz/files/)."""
    d = os.path.join(ROOT, "fuzz", "files")
    os.makedirs(d, exist_ok=True)
    n = 0
    for name, src in FILES.items():
        src = os.path.join(ROOT, src)
        if os.path.exists(src):
            os.makedirs(os.path.dirname(os.path.join(d, name)), exist_ok=True)
            with open(src, "rb") as f, open(os.path.join(d, name), "wb") as g:
                g.write(f.read())
            n += 1
    return n


OCTA_V = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCTA_F = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def ply_header(fmt, n_v, n_f, extra=""):
    return (
        f"ply\nformat {fmt} 1.0\ncomment seed\nelement vertex {n_v}\nproperty float x\nproperty float y\n"
        f"property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\n"
        f"property float v\nelement face {n_f}\nproperty list uchar int vertex_indices\n{extra}end_header\n"
    ).encode()


def seed_meshes():
    n = 0
    rows = [(*p, *p, (p[0] + 1) / 2, (p[1] + 1) / 2) for p in OCTA_V]
    text = "".join(" ".join(f"{x:g}" for x in r) + "\n" for r in rows)
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in OCTA_F)
    put("ply", ply_header("ascii", 6, 8) + text.encode())
    for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        body = b"".join(struct.pack(e + "8f", *r) for r in rows)
        body += b"".join(struct.pack(e + "B3i", 3, *f) for f in OCTA_F)
        put("ply", ply_header(fmt, 6, 8) + body)
        extra = "element note 2\nproperty list ushort char text\nproperty double w\n"
        notes = struct.pack(e + "H3bd", 3, 1, 2, 3, 0.5) + struct.pack(e + "Hd", 0, 1.5)
        put("ply", ply_header(fmt, 6, 8, extra) + body + notes)
    put("ply", b"ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\n"
        b"property double z\nproperty list uchar int links\nelement face 2\nproperty uchar flags\n"
        b"property list uchar uint vertex_index\nend_header\n0 0 0 0\n1 0 0 2 7 8\n1 1 0 0\n0 1 0 1 3\n"
        b"0.5 2 0 0\n1 4 0 1 2 3\n0 5 0 1 2 4 3\n")
    n += 6
    obj = "".join(f"v {x} {y} {z}\nvn {x} {y} {z}\nvt {(x + 1) / 2} {(y + 1) / 2}\n" for x, y, z in OCTA_V)
    obj += "".join(f"f {a + 1}/{a + 1}/{a + 1} {b + 1}/{b + 1}/{b + 1} {c + 1}/{c + 1}/{c + 1}\n" for a, b, c in OCTA_F)
    two = ("o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0 2\nf 1 2 3 4\n"
           "g b\nv 0 0 1\nvt 0 0\nvt 1 1\nf -1/1 1/2 2/1\nusemtl x\nf 5 3 4 1 2\nl 1 2 3\n")
    for text in (obj.encode(), two.encode()):
        for select in (b"\x00", b"\x01"):
            put("obj", select + text)
            n += 1
    n += seed_files_prefixed("obj", os.path.join(ROOT, "crates", "niebla-mesh", "tests", "data", "*.obj"), b"\x00")
    return n


def seed_files_prefixed(target, pattern, prefix):
    n = 0
    for p in glob.glob(pattern):
        if os.path.getsize(p) < MAX_SEED:
            put(target, prefix + open(p, "rb").read())
            n += 1
    return n


def main():
    only = set(sys.argv[1:])
    if only and only <= {"ply", "obj"}:
        print("ply/obj seeds:", seed_meshes())
        return 0
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
    print("ply/obj seeds:", seed_meshes())


if __name__ == "__main__":
    sys.exit(main())
