#!/usr/bin/python3
"""Write OpenVDB files with Vec3 grids (and a Mantaflow-style multi-grid file)
with the reference library, plus OUTDIR/expected.json of what the library reads
back from each written file.

Usage:  /usr/bin/python3 make_vec3_vdbs.py OUTDIR

Needs Debian's python3-openvdb (importable from /usr/bin/python3) and numpy,
and vdb_tool (libopenvdb-tools) for the zip and uncompressed variants (the
10.x Python bindings always write blosc + active mask).  The 10.x bindings
have no Vec3DGrid, so double-precision vector grids are not written here.

Files:
  vec3_blosc.vdb, vec3_half_blosc.vdb, vec3_zip.vdb, vec3_half_zip.vdb,
  vec3_none.vdb: one Vec3SGrid "vel" with a swirl of vectors, single voxels
    on both sides of root-node borders, an active 8^3 tile, an active 128^3
    tile, an inactive tile holding a value other than the background, and a
    non-zero background;
  mantaflow_fire.vdb: the grids Blender's Mantaflow writes for fire
    (density, flame, temperature, heat, fuel, react as floats; vel and color
    as Vec3), on one voxel transform, with heat, fuel, react and an extra
    vector grid "velocity_guide" empty.
"""
import json
import os
import shutil
import subprocess
import sys

os.environ.setdefault("OPENVDB_DISABLE_DELAYED_LOAD", "1")

import numpy as np  # noqa: E402
import pyopenvdb as vdb  # noqa: E402

BACKGROUND = (0.5, -0.25, 0.0)
VOXELS = {
    (0, 0, 0): (1.0, 0.0, 0.0),
    (1, 2, 3): (0.0, -2.0, 0.5),
    (-1, -1, -1): (0.25, 0.5, 0.75),
    (-300, 200, -4100): (0.1, 0.2, 0.3),       # 0.1 etc. are not halves
    (4095, 4096, -4097): (-3.0, 4.0, 12.0),    # root-node borders
}
TILE8 = ((64, 0, 0), (71, 7, 7), (1.0, 2.0, 3.0), True)
TILE128 = ((128, 128, 128), (255, 255, 255), (-0.5, 0.25, 2.0), True)
INACTIVE_TILE = ((-64, 0, 0), (-57, 7, 7), (7.0, 7.0, 7.0), False)
UNSET = [(2, 2, 2), (-2, 5, 9), (5000, 5000, 5000)]


def swirl(shape, centre):
    """A vortex field (-y, x, 0.3) * falloff around `centre`, zero far out."""
    n = shape
    ax = np.arange(n, dtype=np.float64) - n // 2
    x, y, z = np.meshgrid(ax, ax, ax, indexing="ij")
    fall = np.exp(-(x * x + y * y + z * z) / (2.0 * 4.0 ** 2))
    v = np.stack([-y * fall, x * fall, 0.3 * fall], axis=-1).astype(np.float32)
    v[fall < 0.02] = 0.0
    return v, tuple(c - n // 2 for c in centre)


def vec3_grid(half=False):
    g = vdb.Vec3SGrid(BACKGROUND)
    g.name = "vel"
    # Leave the class "unknown": OpenVDB never zip-compresses fog volumes.
    arr, origin = swirl(21, (20, 20, 20))
    # copyFromArray marks voxels equal to the background inactive; the swirl
    # is zero there, so first fill with zeros made active below.
    g.copyFromArray(arr, origin, (0.0, 0.0, 0.0))
    acc = g.getAccessor()
    for ijk, v in VOXELS.items():
        acc.setValueOn(ijk, v)
    for lo, hi, v, active in (TILE8, TILE128, INACTIVE_TILE):
        g.fill(lo, hi, v, active)
    g.transform = vdb.createLinearTransform(voxelSize=0.25)
    g.transform.translate((1.0, -2.0, 0.5))
    g.saveFloatAsHalf = half
    return g


def fire_grids():
    """A Mantaflow-style fire: a ball of smoke with a hot core."""
    n = 24
    ax = (np.arange(n, dtype=np.float64) - n / 2 + 0.5) / (n / 2)
    x, y, z = np.meshgrid(ax, ax, ax, indexing="ij")
    r = np.sqrt(x * x + y * y + z * z)
    density = np.clip(1.0 - r, 0.0, None).astype(np.float32)
    flame = np.clip(1.0 - 2.0 * r, 0.0, None).astype(np.float32)
    temperature = (flame * 3.0).astype(np.float32)  # Mantaflow: 0..~3
    vel = np.stack([0.0 * x, np.where(r < 1, 1.0 - r, 0.0), 0.0 * z], axis=-1).astype(np.float32)
    color = np.stack([density, 0.5 * density, 0.25 * density], axis=-1).astype(np.float32)
    xform = vdb.createLinearTransform(voxelSize=0.1)
    xform.translate((-1.2, 0.0, -1.2))
    grids = []

    def add(g, name, arr=None, tol=0.0):
        g.name = name
        if arr is not None:
            g.copyFromArray(arr, (0, 0, 0), tol)
        g.transform = xform
        grids.append(g)

    add(vdb.FloatGrid(0.0), "density", density)
    grids[-1].gridClass = vdb.GridClass.FOG_VOLUME
    add(vdb.FloatGrid(0.0), "flame", flame)
    add(vdb.FloatGrid(0.0), "temperature", temperature)
    add(vdb.FloatGrid(0.0), "heat")
    add(vdb.FloatGrid(0.0), "fuel")
    add(vdb.FloatGrid(0.0), "react")
    add(vdb.Vec3SGrid((0.0, 0.0, 0.0)), "vel", vel, (0.0, 0.0, 0.0))
    add(vdb.Vec3SGrid((0.0, 0.0, 0.0)), "color", color, (0.0, 0.0, 0.0))
    add(vdb.Vec3SGrid((0.0, 0.0, 0.0)), "velocity_guide")
    return grids


def recompress(outdir, src, dst, codec):
    tool = shutil.which("vdb_tool")
    if tool is None:
        print("warning: vdb_tool not found, skipping", dst, file=sys.stderr)
        return False
    subprocess.run([tool, "-read", os.path.join(outdir, src), "-write", "codec=" + codec,
                    os.path.join(outdir, dst)], check=True, stdout=subprocess.DEVNULL)
    return True


def as_list(v):
    return [float(c) for c in v] if isinstance(v, tuple) else [float(v)]


def reference(path):
    """What the library reads back: per grid, statistics and probes."""
    out = []
    for g in vdb.readAll(path)[0]:
        vector = isinstance(g, vdb.Vec3SGrid)
        count, sums = 0, np.zeros(3 if vector else 1)
        lo, hi = [2 ** 31] * 3, [-2 ** 31] * 3
        tiles = {}
        vmin, vmax = None, None
        probes = set(VOXELS) | set(UNSET) | {(20, 20, 20), (24, 17, 21), (12, 12, 12), (5, 9, 13)}
        for it in g.citerOnValues():
            v = np.array(as_list(it.value))
            count += it.count
            sums += v * it.count
            lo = [min(a, b) for a, b in zip(lo, it.min)]
            hi = [max(a, b) for a, b in zip(hi, it.max)]
            if it.count > 1:
                tiles[str(it.depth)] = tiles.get(str(it.depth), 0) + 1
                probes.add(tuple(it.min))
                probes.add(tuple(it.max))
            m = float(np.linalg.norm(v)) if vector else float(v[0])
            vmin = m if vmin is None else min(vmin, m)
            vmax = m if vmax is None else max(vmax, m)
        for it in g.citerOffValues():
            if it.count > 1 and as_list(it.value) != as_list(g.background):
                probes.add(tuple(it.min))
        acc = g.getAccessor()
        plist = []
        for ijk in sorted(probes):
            value, active = acc.probeValue(ijk)
            plist.append({"ijk": list(ijk), "value": as_list(value), "active": bool(active),
                          "world": list(g.transform.indexToWorld(ijk))})
        out.append({
            "name": g.name,
            "vector": vector,
            "half": bool(g.saveFloatAsHalf),
            "class": str(g.gridClass),
            "background": as_list(g.background),
            "active_voxel_count": int(count),
            "active_value_sums": [float(s) for s in sums],
            "active_bbox": [lo, hi] if count else None,
            "active_tiles": tiles,
            "value_range": [vmin, vmax] if count else None,
            "leaf_count": int(g.leafCount()),
            "probes": plist,
        })
    return out


def main():
    outdir = sys.argv[1]
    os.makedirs(outdir, exist_ok=True)
    files = []
    vdb.write(os.path.join(outdir, "vec3_blosc.vdb"), grids=[vec3_grid()])
    vdb.write(os.path.join(outdir, "vec3_half_blosc.vdb"), grids=[vec3_grid(half=True)])
    files += ["vec3_blosc.vdb", "vec3_half_blosc.vdb"]
    for src, dst, codec in (("vec3_blosc.vdb", "vec3_zip.vdb", "zip"),
                            ("vec3_blosc.vdb", "vec3_none.vdb", "none"),
                            ("vec3_half_blosc.vdb", "vec3_half_zip.vdb", "zip")):
        if recompress(outdir, src, dst, codec):
            files.append(dst)
    vdb.write(os.path.join(outdir, "mantaflow_fire.vdb"), grids=fire_grids())
    files.append("mantaflow_fire.vdb")
    expected = {f: reference(os.path.join(outdir, f)) for f in files}
    with open(os.path.join(outdir, "expected.json"), "w") as f:
        json.dump({"files": expected}, f, indent=1)


if __name__ == "__main__":
    main()
