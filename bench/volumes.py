"""Seeded density grids for the benchmark scenes, written as Mitsuba 3 `.vol`
files (read by both renderers, so both see the same voxels) and as `.npy`.

Run directly to (re)generate them: `python bench/volumes.py`; `compare.py`
calls `ensure_volumes()` itself. Only NumPy is needed.

Layout (both formats): array shape (nz, ny, nx), indexed [z][y][x], x
fastest; values at cell centers of the bounding box, which is stored in the
`.vol` header (niebla reads it from there; Mitsuba ignores it unless
`use_grid_bbox` is set, so the converter gives Mitsuba an explicit `to_world`).
"""

from __future__ import annotations

import os
import struct
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "scenes", "data")

# name -> (resolution (nx, ny, nz), bounds min, bounds max, generator seed).
# The bounds must match the boxes in scenes/*.json.
VOLUMES = {
    "plume": ((48, 96, 48), (-0.75, 0.0, -0.75), (0.75, 3.0, 0.75), 7),
    "cloud": ((128, 80, 128), (-1.2, -0.75, -1.2), (1.2, 0.75, 1.2), 11),
}


def write_vol(path: str, density: np.ndarray, bmin, bmax) -> None:
    """Mitsuba 3 gridvolume file: 'VOL', version 3, encoding 1 (float32),
    xres, yres, zres, channels (int32), bbox (6 float32), then the data with x
    fastest (C order of a (nz, ny, nx) array)."""
    nz, ny, nx = density.shape
    with open(path + ".tmp", "wb") as f:
        f.write(b"VOL")
        f.write(struct.pack("<B", 3))
        f.write(struct.pack("<iiiii", 1, nx, ny, nz, 1))
        f.write(struct.pack("<6f", *bmin, *bmax))
        f.write(np.ascontiguousarray(density, dtype="<f4").tobytes())
    os.replace(path + ".tmp", path)


def read_vol(path: str):
    with open(path, "rb") as f:
        head = f.read(48)
        assert head[:3] == b"VOL" and head[3] == 3, path
        enc, nx, ny, nz, ch = struct.unpack("<iiiii", head[4:24])
        bbox = struct.unpack("<6f", head[24:48])
        data = np.frombuffer(f.read(), dtype="<f4").reshape(nz, ny, nx, ch)
    return data[..., 0], bbox[:3], bbox[3:]


def vdb_to_vol(vdb_path: str, vol_path: str, grid: str = "density") -> dict:
    """Writes the float grid `grid` of a VDB file as a dense Mitsuba `.vol`:
    the voxels of its active bounding box plus one voxel of zeros on each
    side (so that Mitsuba's clamped lookups beyond the box give 0, and its
    trilinear ramp from the last active voxel to 0 is OpenVDB's), cell
    centred: voxel index (i, j, k) sits at the VDB's own voxel centre. Needs
    an axis-aligned, uniform, unrotated index-to-world map. Done by Debian's
    python3-openvdb (the system python); skipped when `vol_path` is newer.
    Returns {"shape": (nz, ny, nx), "min": [...], "max": [...]} read back from
    the header."""
    import subprocess

    if not (os.path.exists(vol_path) and os.path.getmtime(vol_path) >= os.path.getmtime(vdb_path)):
        script = r"""
import struct, sys
import numpy as np
try:
    import pyopenvdb as vdb
except ImportError:
    import openvdb as vdb
src, out, name = sys.argv[1:4]
g = vdb.read(src, name)
lo, hi = g.evalActiveVoxelBoundingBox()
lo = [c - 1 for c in lo]
hi = [c + 1 for c in hi]
o = g.transform.indexToWorld((0, 0, 0))
vs = [g.transform.indexToWorld(tuple(1 if a == b else 0 for b in range(3)))[a] - o[a] for a in range(3)]
assert max(vs) - min(vs) <= 1e-6 * max(vs), ("non-uniform voxels", vs)
for a in range(3):
    e = [0, 0, 0]; e[(a + 1) % 3] = 1
    p = g.transform.indexToWorld(tuple(e))
    assert abs(p[a] - o[a]) <= 1e-9 + 1e-6 * max(vs), "a rotated index-to-world map"
shape = [hi[a] - lo[a] + 1 for a in range(3)]
arr = np.zeros(shape, dtype=np.float32)          # [x][y][z]
g.copyToArray(arr, ijk=tuple(lo))
dens = np.ascontiguousarray(arr.transpose(2, 1, 0))   # [z][y][x], x fastest
bmin = [o[a] + (lo[a] - 0.5) * vs[a] for a in range(3)]
bmax = [o[a] + (hi[a] + 0.5) * vs[a] for a in range(3)]
with open(out + ".tmp", "wb") as f:
    f.write(b"VOL" + struct.pack("<B", 3) + struct.pack("<iiiii", 1, shape[0], shape[1], shape[2], 1))
    f.write(struct.pack("<6f", *bmin, *bmax))
    dens.tofile(f)
"""
        subprocess.run(["/usr/bin/python3", "-c", script, vdb_path, vol_path, grid], check=True)
        os.replace(vol_path + ".tmp", vol_path)
    with open(vol_path, "rb") as f:
        head = f.read(48)
    _, nx, ny, nz, _ = struct.unpack("<iiiii", head[4:24])
    bbox = struct.unpack("<6f", head[24:48])
    return {"shape": (nz, ny, nx), "min": list(bbox[:3]), "max": list(bbox[3:])}


def _smooth(t):
    return t * t * (3.0 - 2.0 * t)


def value_noise(shape, freq, rng) -> np.ndarray:
    """Smooth value noise in [-1, 1] sampled at the cell centers of a grid of
    `shape` (nz, ny, nx) spanning the unit cube, `freq` lattice cells per axis."""
    lat = rng.uniform(-1.0, 1.0, size=(freq + 2,) * 3)
    axes = []
    for n in shape:
        x = (np.arange(n) + 0.5) / n * freq
        i = np.floor(x).astype(int)
        axes.append((i, _smooth(x - i)))
    (iz, fz), (iy, fy), (ix, fx) = axes
    fz = fz[:, None, None]
    fy = fy[None, :, None]
    fx = fx[None, None, :]
    out = np.zeros(shape)
    for dz in (0, 1):
        wz = fz if dz else 1 - fz
        for dy in (0, 1):
            wy = fy if dy else 1 - fy
            for dx in (0, 1):
                wx = fx if dx else 1 - fx
                out += wz * wy * wx * lat[np.ix_(iz + dz, iy + dy, ix + dx)]
    return out


def fbm(shape, base_freq, octaves, rng, gain=0.5) -> np.ndarray:
    total = np.zeros(shape)
    amp, norm = 1.0, 0.0
    for o in range(octaves):
        total += amp * value_noise(shape, base_freq * 2**o, rng)
        norm += amp
        amp *= gain
    return total / norm


def _centers(res, bmin, bmax):
    nx, ny, nz = res
    xs = bmin[0] + (np.arange(nx) + 0.5) / nx * (bmax[0] - bmin[0])
    ys = bmin[1] + (np.arange(ny) + 0.5) / ny * (bmax[1] - bmin[1])
    zs = bmin[2] + (np.arange(nz) + 0.5) / nz * (bmax[2] - bmin[2])
    return np.meshgrid(zs, ys, xs, indexing="ij")  # z, y, x arrays of shape (nz, ny, nx)


def plume(res, bmin, bmax, seed) -> np.ndarray:
    """A rising smoke plume: a column widening and drifting with height,
    broken up by fractal noise, thinning out toward the top."""
    rng = np.random.default_rng(seed)
    z, y, x = _centers(res, bmin, bmax)
    shape = z.shape
    h = (y - bmin[1]) / (bmax[1] - bmin[1])  # 0 at the bottom, 1 at the top
    n1 = fbm(shape, 3, 4, rng)
    n2 = fbm(shape, 4, 4, rng)
    cx = 0.18 * np.sin(2.4 * h + 0.5) + 0.12 * n2
    cz = 0.12 * np.cos(3.1 * h) + 0.12 * n1
    radius = 0.10 + 0.45 * h**0.8
    r = np.sqrt((x - cx) ** 2 + (z - cz) ** 2) / radius
    core = np.clip(1.0 - r, 0.0, 1.0) ** 0.7
    detail = np.clip(0.55 + 0.9 * fbm(shape, 6, 4, rng), 0.0, 1.2)
    fade = np.clip(1.0 - h, 0.0, 1.0) ** 0.6 * np.clip(h / 0.04, 0.0, 1.0)
    d = np.clip(1.6 * core * detail * fade, 0.0, 1.0)
    return _zero_faces(d).astype(np.float32)


def cloud(res, bmin, bmax, seed) -> np.ndarray:
    """A dense cumulus-like cloud: a union of seeded ellipsoidal blobs with a
    flattened base, eroded by fractal noise; density ~1 inside, soft edges."""
    rng = np.random.default_rng(seed)
    z, y, x = _centers(res, bmin, bmax)
    shape = z.shape
    field = np.full(shape, -1e9)
    blobs = [(0.0, -0.05, 0.0, 0.75)]
    for _ in range(9):
        a = rng.uniform(0, 2 * np.pi)
        rr = rng.uniform(0.25, 0.6)
        blobs.append((rr * np.cos(a), rng.uniform(-0.25, 0.2), rr * np.sin(a), rng.uniform(0.3, 0.5)))
    for bx, by, bz, br in blobs:
        d = 1.0 - np.sqrt((x - bx) ** 2 + ((y - by) * 1.25) ** 2 + (z - bz) ** 2) / br
        field = np.maximum(field, d)
    field = field + 0.35 * fbm(shape, 4, 5, rng)
    field = np.where(y < -0.45, field - (-0.45 - y) * 6.0, field)  # flat base
    d = np.clip(field * 5.0, 0.0, 1.0)
    return _zero_faces(d).astype(np.float32)


def _zero_faces(d):
    d = d.copy()
    d[0, :, :] = d[-1, :, :] = 0.0
    d[:, 0, :] = d[:, -1, :] = 0.0
    d[:, :, 0] = d[:, :, -1] = 0.0
    return d


def ensure_volumes(force: bool = False, log=print) -> dict:
    """Writes scenes/data/<name>.vol and .npy unless present; returns paths."""
    os.makedirs(DATA, exist_ok=True)
    out = {}
    for name, (res, bmin, bmax, seed) in VOLUMES.items():
        vol = os.path.join(DATA, name + ".vol")
        npy = os.path.join(DATA, name + ".npy")
        out[name] = vol
        if os.path.exists(vol) and os.path.exists(npy) and not force:
            continue
        d = {"plume": plume, "cloud": cloud}[name](res, bmin, bmax, seed)
        write_vol(vol, d, bmin, bmax)
        np.save(npy, d)
        log(f"wrote {vol} ({res[0]}x{res[1]}x{res[2]}, mean density {d.mean():.3f}, max {d.max():.3f})")
    return out


if __name__ == "__main__":
    ensure_volumes(force="--force" in sys.argv)
