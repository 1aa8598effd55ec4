"""Smoke from numpy: build a density volume with numpy, render it with two
integrators and look at the difference.

A notebook-style script: run it as a whole (``python
examples/smoke_from_numpy.py``) or cell by cell (``# %%`` cells, as in VS
Code or Jupytext). It needs the ``niebla`` package (``bash scripts/test.sh``
builds it into ``.venv-py``; or ``maturin develop --release -m
crates/niebla-py/Cargo.toml``) and numpy; with matplotlib it shows a figure,
without it writes PNG and EXR files.

What the difference shows: ``volpath`` follows light through any number of
scattering events, ``single`` only through one, so ``volpath - single`` is
the light that scattered more than once: bright inside the thick core of the
plume, where single scattering underestimates most.
"""

# %% Setup
import argparse
import time
from pathlib import Path

import numpy as np

import niebla

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--spp", type=int, default=32, help="samples per pixel of each render")
parser.add_argument("--size", type=int, default=256, help="image width and height in pixels")
parser.add_argument("--voxels", type=int, default=64, help="density voxels per axis")
parser.add_argument("--out", type=Path, default=Path("smoke_from_numpy"), help="folder for the images")
parser.add_argument("--no-show", action="store_true", help="do not open a matplotlib window")
args, _ = parser.parse_known_args()  # tolerate a notebook kernel's own arguments
args.out.mkdir(parents=True, exist_ok=True)

# %% A smoke density with numpy
# The array has shape (nz, ny, nx) and is indexed [z, y, x]: its values sit at
# the cell centers of the unit box [0, 1]^3 (given to set_density as
# `bounds`), y is up, so density[:, 0, :] is the bottom slice.
n = args.voxels
rng = np.random.default_rng(1)
z, y, x = np.meshgrid(*(np.linspace(0.5 / n, 1 - 0.5 / n, n),) * 3, indexing="ij")

# A plume: a column that rises from the floor, drifts sideways with height
# and widens as it goes.
center_x = 0.5 + 0.12 * np.sin(3.0 * y) * y
center_z = 0.5 + 0.08 * np.cos(4.0 * y) * y
radius = 0.06 + 0.22 * y
column = np.exp(-(((x - center_x) ** 2 + (z - center_z) ** 2) / radius**2))

# Turbulence: a few random Fourier octaves, larger features dominating.
noise = np.zeros_like(x)
for octave in range(4):
    frequency = 3.0 * 2**octave
    for _ in range(4):
        k = rng.normal(size=3) * frequency
        phase = rng.uniform(0, 2 * np.pi)
        noise += 0.5**octave * np.cos(2 * np.pi * (k[0] * x + k[1] * y + k[2] * z) / 4 + phase)
noise /= np.abs(noise).max()

density = column * np.clip(0.75 + 0.5 * noise, 0.0, None) * np.clip(1.0 - y, 0.0, 1.0) ** 0.5
density[density < 0.02] = 0.0
density = density.astype(np.float32)
print(f"density: shape {density.shape} (nz, ny, nx), max {density.max():.2f}, "
      f"{(density > 0).mean() * 100:.0f}% of the voxels non-zero")

# %% The scene, as a dict with the schema of a scene file
scene = niebla.Scene.from_dict({
    "version": 1,
    "camera": {"type": "perspective", "position": [0, 1.1, 4.0], "target": [0, 0.95, 0],
               "fov_y": 40, "width": args.size, "height": args.size},
    "render": {"integrator": {"type": "volpath", "max_depth": 256}, "spp": args.spp, "seed": 0},
    "media": {
        "smoke": {
            "type": "grid",
            # Replaced by the numpy array below; any density source will do here.
            "density": {"type": "constant", "value": 1},
            # Per unit density and per scene unit.
            "sigma_t": 18, "albedo": 0.92,
            "phase": {"type": "hg", "g": 0.4},
            # The unit box [0, 1]^3 becomes [-1, 1] x [0, 2] x [-1, 1].
            "to_world": {"scale": 2, "translate": [-1, 0, -1]},
        }
    },
    "ambient_medium": "smoke",
    "shapes": [{"type": "rectangle", "to_world": {"scale": 6, "rotate_x": -90},
                "bsdf": {"type": "diffuse", "reflectance": [0.45, 0.42, 0.38]}}],
    "lights": [
        {"type": "directional", "direction": [-0.6, -0.8, -0.35], "irradiance": [3.2, 2.9, 2.5]},
        {"type": "constant", "radiance": [0.16, 0.22, 0.34]},
    ],
})
scene.set_density("smoke", density, bounds=((0, 0, 0), (1, 1, 1)))
print(scene)

# %% Two integrators, the same samples per pixel
images = {}
for name, integrator in [("volpath", "volpath"), ("single", {"type": "single", "sampling": "mis"})]:
    start = time.perf_counter()
    images[name] = scene.render(integrator, spp=args.spp)
    print(f"{name}: {args.spp} spp in {time.perf_counter() - start:.1f} s, "
          f"mean radiance {images[name].mean():.4f} W/(sr m^2)")
difference = images["volpath"] - images["single"]
print(f"multiple scattering adds {difference.mean() / images['volpath'].mean() * 100:.0f}% "
      f"of the mean radiance; relative MSE of single against volpath: "
      f"{niebla.relative_mse(images['single'], images['volpath']):.3g}")

# %% Look at them
for name, image in images.items():
    niebla.write_exr(image, args.out / f"{name}.exr")
    niebla.write_png(image, args.out / f"{name}.png")
niebla.write_exr(difference, args.out / "difference.exr")
try:
    import matplotlib

    if args.no_show:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    # No matplotlib: the difference as a PNG, brightened two stops (negative
    # values, where single is brighter by noise, clip to black).
    niebla.write_png(np.abs(difference), args.out / "difference.png", exposure=2.0)
    print(f"matplotlib is not installed; wrote volpath, single and difference .png/.exr to {args.out}/")
else:
    def display(image):
        """Linear radiance to sRGB for imshow."""
        v = np.clip(image, 0.0, 1.0)
        return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)

    figure, axes = plt.subplots(1, 3, figsize=(13, 4.6), constrained_layout=True)
    for axis, name in zip(axes, images):
        axis.imshow(display(images[name]))
        axis.set_title(f"{name}, {args.spp} spp")
    luminance = difference @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)
    limit = np.percentile(np.abs(luminance), 99.5) or 1.0
    shown = axes[2].imshow(luminance, cmap="RdBu_r", vmin=-limit, vmax=limit)
    axes[2].set_title("volpath - single (luminance)")
    figure.colorbar(shown, ax=axes[2], shrink=0.8, label="W/(sr m²)")
    for axis in axes:
        axis.set_axis_off()
    figure.savefig(args.out / "comparison.png", dpi=100)
    print(f"wrote {args.out}/comparison.png and the images")
    if not args.no_show:
        plt.show()
