#!/usr/bin/python3
"""Write a large sparse density VDB for the memory benchmarks (not committed).

Usage:  /usr/bin/python3 bench/make_big_vdb.py OUT.vdb [--size N] [--balls K] [--seed S] [--none]

A "cloud" of K seeded noisy balls (radii N/8 to N/4) in the index box [0, N)^3:
density 2.5 (1 - d/r) times a ripple, clamped to 1, zero outside the balls.
The defaults (N = 1024, K = 8) give about 1 GB of float leaves in memory.
Written by Debian's reference bindings (apt-get install python3-openvdb; they
load only in /usr/bin/python3) with the library's default compression (blosc
on Debian's build), or with none when --none is given (the 10.x bindings
cannot choose, so --none re-encodes with vdb_tool from libopenvdb-tools).
"""
import argparse
import os
import subprocess
import sys

os.environ.setdefault("OPENVDB_DISABLE_DELAYED_LOAD", "1")
import numpy as np  # noqa: E402

try:
    import pyopenvdb as vdb  # noqa: E402
except ImportError:
    import openvdb as vdb  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--balls", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--none", action="store_true", help="uncompressed (needs vdb_tool)")
    a = ap.parse_args()
    n = a.size
    rng = np.random.default_rng(a.seed)
    balls = []
    for _ in range(a.balls):
        r = rng.uniform(n / 8, n / 4)
        c = rng.uniform(r, n - r, size=3)
        balls.append((c, r))
    grid = vdb.FloatGrid(0.0)
    grid.name = "density"
    grid.transform = vdb.createLinearTransform(voxelSize=1.0 / n)
    chunk = 128
    ax = np.arange(chunk, dtype=np.float32)
    for x0 in range(0, n, chunk):
        for y0 in range(0, n, chunk):
            for z0 in range(0, n, chunk):
                lo = np.array([x0, y0, z0], dtype=np.float64)
                hi = lo + chunk - 1
                near = [(c, r) for c, r in balls if np.linalg.norm(c - np.clip(c, lo, hi)) < r]
                if not near:
                    continue
                x = (x0 + ax)[:, None, None]
                y = (y0 + ax)[None, :, None]
                z = (z0 + ax)[None, None, :]
                ripple = 0.8 + 0.2 * np.sin(x * 0.21 + y * 0.13) * np.cos(z * 0.17)
                v = np.zeros((chunk, chunk, chunk), dtype=np.float32)
                for c, r in near:
                    d = np.sqrt((x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2)
                    v = np.maximum(v, 2.5 * (1.0 - d / r) * ripple)
                v = np.clip(v, 0.0, 1.0).astype(np.float32)
                # Array axes are (x, y, z), as copyFromArray expects.
                grid.copyFromArray(v, ijk=(x0, y0, z0), tolerance=0.0)
    grid.prune()
    out = a.out
    tmp = out + ".blosc.vdb" if a.none else out
    vdb.write(tmp, grids=[grid])
    if a.none:
        subprocess.run(["vdb_tool", "-read", tmp, "-write", "codec=none", out], check=True)
        os.remove(tmp)
    print(f"{out}: {grid.activeVoxelCount()} active voxels, {grid.leafCount()} leaves, "
          f"{os.path.getsize(out) / 2**20:.1f} MiB on disk", file=sys.stderr)


if __name__ == "__main__":
    main()
