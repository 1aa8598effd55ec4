#!/usr/bin/python3
"""Writes the procedural fireball of scenes/fireball.json as a multi-grid
OpenVDB file, the way a pyro simulation exports it from Houdini or Blender:
float grids `density`, `temperature` (normalized, 0..1, remapped to Kelvin by
the scene) and `flame` (0..1), and a Vec3 grid `vel` (world units per second),
all on one transform (voxel 0.025 over x, z in [-0.8, 0.8], y in [0, 2.4]).

    /usr/bin/python3 scenes/make_fireball.py [OUT.vdb]   # default scenes/fireball.vdb

Run with Debian's python (python3-openvdb and numpy). Reproducible: the noise
comes from a fixed seed of numpy's PCG64 generator, so the same file (same
voxel values) is written every time. Flame and temperature are zero wherever
the density is, so every renderer agrees on where the fire emits.
"""

import os
import sys

import numpy as np

os.environ.setdefault("OPENVDB_DISABLE_DELAYED_LOAD", "1")
try:
    import pyopenvdb as vdb
except ImportError:  # newer OpenVDB releases name the module openvdb
    import openvdb as vdb

VOXEL = 0.025
LO = np.array([-0.8, 0.0, -0.8])
SHAPE = (64, 96, 64)  # voxels along x, y, z
SEED = 17
CENTER = np.array([0.0, 0.42, 0.0])  # fireball centre (world units)
RADIUS = 0.36


def smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


class ValueNoise:
    """Trilinearly interpolated value noise (smoothstep-weighted) on a random
    periodic lattice of 32^3 values in [0, 1]."""

    def __init__(self, rng, n=32):
        self.n = n
        self.lattice = rng.random((n, n, n))

    def __call__(self, p):
        n = self.n
        f = np.floor(p)
        t = p - f
        t = t * t * (3.0 - 2.0 * t)
        i = f.astype(np.int64)
        out = np.zeros(p.shape[:-1])
        for dx in (0, 1):
            wx = t[..., 0] if dx else 1.0 - t[..., 0]
            for dy in (0, 1):
                wy = t[..., 1] if dy else 1.0 - t[..., 1]
                for dz in (0, 1):
                    wz = t[..., 2] if dz else 1.0 - t[..., 2]
                    v = self.lattice[(i[..., 0] + dx) % n, (i[..., 1] + dy) % n, (i[..., 2] + dz) % n]
                    out += wx * wy * wz * v
        return out


def fbm(noise, p, octaves=4):
    """Fractal sum of `octaves` octaves of `noise`, normalized to about [0, 1]."""
    total, amp, norm = np.zeros(p.shape[:-1]), 1.0, 0.0
    for o in range(octaves):
        total += amp * noise(p * (2.0**o) + 7.31 * o)
        norm += amp
        amp *= 0.5
    return total / norm


def fields():
    """(density, temperature, flame, vel) as arrays indexed [x][y][z] (vel
    with a trailing axis of 3), sampled at the voxel centres."""
    rng = np.random.default_rng(SEED)
    n1, n2, n3 = ValueNoise(rng), ValueNoise(rng), ValueNoise(rng)
    idx = np.stack(np.meshgrid(*[np.arange(s) for s in SHAPE], indexing="ij"), axis=-1)
    p = LO + (idx + 0.5) * VOXEL  # world position of each voxel centre

    # Fireball: a noisy ball, hottest in its core.
    d = p - CENTER
    r = np.linalg.norm(d, axis=-1) / RADIUS
    rn = r + 0.45 * (fbm(n1, p * 5.0) - 0.5)
    core = smoothstep(1.0, 0.6, rn)
    flame = np.clip(1.5 * (1.0 - rn), 0.0, 1.0) * (0.55 + 0.45 * fbm(n2, p * 7.0))
    flame *= core

    # Smoke: a column rising from the fireball and widening with height.
    y = p[..., 1]
    rho = 0.2 + 0.22 * np.clip(y - 0.55, 0.0, None)
    q = np.hypot(p[..., 0], p[..., 2]) / rho + 0.7 * (fbm(n3, p * 4.0) - 0.5)
    column = smoothstep(1.0, 0.35, q) * smoothstep(0.5, 0.85, y) * smoothstep(2.35, 1.85, y)
    smoke = column * (0.25 + 0.75 * fbm(n2, p * 3.0 + 11.0))

    # The burning gas is thin (density 0.08-0.2), the smoke above it thicker.
    density = np.maximum(core * (0.08 + 0.12 * fbm(n3, p * 6.0)), 0.6 * smoke)
    density = np.where(density > 1e-3, density, 0.0)
    live = density > 0.0
    flame = np.where(live & (flame > 1e-3), flame, 0.0)
    temperature = np.where(live, core * (0.35 + 0.65 * flame), 0.0)
    temperature = np.where(temperature > 1e-3, temperature, 0.0)

    # Velocity: outward from the fireball, upward in the column.
    r_world = np.linalg.norm(d, axis=-1, keepdims=True) + 1e-6
    vel = 1.5 * core[..., None] * d / r_world + 2.0 * column[..., None] * np.array([0.0, 1.0, 0.0])
    vel = np.where(live[..., None], vel, 0.0)
    return (density.astype(np.float32), temperature.astype(np.float32), flame.astype(np.float32),
            vel.astype(np.float32))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "fireball.vdb")
    density, temperature, flame, vel = fields()
    # Index (i, j, k) is the voxel centre LO + (i + 1/2, j + 1/2, k + 1/2) VOXEL.
    origin = LO + 0.5 * VOXEL
    matrix = [[VOXEL, 0, 0, 0], [0, VOXEL, 0, 0], [0, 0, VOXEL, 0], [origin[0], origin[1], origin[2], 1]]
    grids = []
    for name, values in (("density", density), ("temperature", temperature), ("flame", flame)):
        g = vdb.FloatGrid()
        g.name = name
        g.copyFromArray(np.ascontiguousarray(values), tolerance=0.0)
        g.transform = vdb.createLinearTransform(matrix)
        g.gridClass = vdb.GridClass.FOG_VOLUME
        grids.append(g)
    v = vdb.Vec3SGrid()
    v.name = "vel"
    v.copyFromArray(np.ascontiguousarray(vel), tolerance=(0.0, 0.0, 0.0))
    v.transform = vdb.createLinearTransform(matrix)
    grids.append(v)
    tmp = out + ".tmp"
    vdb.write(tmp, grids=grids)
    os.replace(tmp, out)
    print(f"{out}: {int((density > 0).sum())} active density voxels of {density.size}, "
          f"max density {density.max():.3f}, max flame {flame.max():.3f}, max temperature {temperature.max():.3f}")


if __name__ == "__main__":
    main()
