"""Mitsuba 3 references for the XML test scenes in scenes/mitsuba/.

    /work/main/bench/.venv/bin/python scripts/mitsuba_refs.py [--data] [--textures] [--cube] [--sphere] [--renders 16] [--spp 64] [NAME ...]

(disk_roughplastic was made with `--renders 64 disk_roughplastic`, and
aniso_dpdu with `--renders 64 aniso_dpdu`, cube_uv with `--renders 64 cube_uv`, smooth_normals with `--renders 64 smooth_normals`,
smooth_normals_inward with `--renders 64 smooth_normals_inward`, sphere_turned with
`--renders 64 sphere_turned`, mesh_emitters with `--renders 64 mesh_emitters`: their image means need the
smaller standard error to be checked against 0.5%.)

`--data` (re)writes the scenes' input files (scenes/mitsuba/data/sky.exr, a
uniform 16x8 sky, smoke.vol, a 16^3 smooth blob, and albedo_rgb.vol, a 3-channel
10 x 8 x 6 albedo ramp for grid_albedo), all from fixed formulas; `--data` or
`--textures` (re)writes the images of the `textured` scene (tex_srgb.png, a
16 x 8 8-bit sRGB image, and tex_raw.png, a 4 x 4 8-bit image read raw) and
of the `rough_textured` scene (alpha_gray.png, an 8 x 8 8-bit gray roughness map read raw),
also from fixed formulas.
`--cube` writes crates/niebla/tests/data/mitsuba_cube.json: Mitsuba's own
`cube` mesh as `mi.traverse` gives it (vertex_positions, vertex_normals,
vertex_texcoords, faces), and the surface interactions (p, n, uv, dp_du,
dp_dv) of rays aimed at two points of each face of a cube placed by a fixed
`to_world` matrix (turned, unevenly scaled, moved), and those of a triangle
without uvs with and without `flip_normals`, and the vertices of a cube
turned by `<rotate>` about a non-unit axis, for the importer's tests.
`--sphere` writes crates/niebla/tests/data/mitsuba_sphere.json: for spheres
turned by their `to_world` (written in the XML as stored in the table), the
surface interactions (p, n, uv, dp_du) of rays aimed along the normal at
points spread over each sphere.
For each scene, Mitsuba renders `--renders` independent images (seeds 0, 1,
...) of `--spp` samples per pixel, and the script stores only small
statistics in crates/niebla/tests/data/mitsuba_refs/NAME.json: per 8x8-pixel
block and channel the mean over the renders and its standard error (the
spread of the per-render block means over sqrt(renders)), the image mean per
channel with its standard error, and the Mitsuba version and variant. The
Rust test tests/mitsuba_scenes.rs renders the same XML with niebla and
compares.
"""

from __future__ import annotations

import argparse
import json
import os
import struct
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "scenes", "mitsuba")
OUT = os.path.join(ROOT, "crates", "niebla", "tests", "data", "mitsuba_refs")
BLOCK = 8
NAMES = ["mesh_in_fog", "area_fog", "envmap_glass_medium", "grid_smoke", "chromatic_mis", "emitter_in_medium",
         "spot_rough_glass", "thin_boundaries", "tabphase_fog", "disk_roughplastic", "grid_albedo", "textured",
         "rough_textured", "rough_aniso_twosided", "aniso_dpdu", "cube_uv", "smooth_normals",
         "smooth_normals_inward", "sphere_turned", "mesh_emitters"]


def write_data(mi):
    os.makedirs(os.path.join(SCENES, "data"), exist_ok=True)
    # Sky: one color. niebla looks environment maps up per pixel (nearest),
    # Mitsuba interpolates bilinearly with rows centered on the poles, so only a
    # map without gradients is the same light in both (see the envmap docs).
    sky = np.empty((8, 16, 3), np.float32)
    sky[:] = [0.9, 1.0, 1.3]
    mi.Bitmap(sky).write(os.path.join(SCENES, "data", "sky.exr"))
    # Smoke: a smooth blob with a lobe, zero on the faces, 16^3, box [0,1]^3 in the file.
    n = 16
    c = (np.arange(n) + 0.5) / n
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    d = np.exp(-(((x - 0.5) / 0.25) ** 2 + ((y - 0.4) / 0.3) ** 2 + ((z - 0.5) / 0.25) ** 2))
    d += 0.6 * np.exp(-(((x - 0.7) / 0.12) ** 2 + ((y - 0.7) / 0.12) ** 2 + ((z - 0.4) / 0.15) ** 2))
    d[0, :, :] = d[-1, :, :] = d[:, 0, :] = d[:, -1, :] = d[:, :, 0] = d[:, :, -1] = 0
    with open(os.path.join(SCENES, "data", "smoke.vol"), "wb") as f:
        f.write(b"VOL" + struct.pack("<B", 3) + struct.pack("<iiiii", 1, n, n, n, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(d.astype("<f4").tobytes())
    # Albedo: 3 channels, 10 x 8 x 6 cells (x, y, z), box [0,1]^3 in the file;
    # values in [0.2, 0.98], varying along every axis and per channel.
    nx, ny, nz = 10, 8, 6
    z, y, x = np.meshgrid((np.arange(nz) + 0.5) / nz, (np.arange(ny) + 0.5) / ny, (np.arange(nx) + 0.5) / nx,
                          indexing="ij")
    a = np.stack([0.2 + 0.78 * x, 0.98 - 0.7 * y, 0.5 + 0.45 * np.cos(2 * np.pi * (x + z))], axis=-1)
    with open(os.path.join(SCENES, "data", "albedo_rgb.vol"), "wb") as f:
        f.write(b"VOL" + struct.pack("<B", 3) + struct.pack("<iiiii", 1, nx, ny, nz, 3))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(a.astype("<f4").tobytes())


def write_textures(mi):
    """Images of the `textured` scene. Row 0 is the image's top."""
    os.makedirs(os.path.join(SCENES, "data"), exist_ok=True)
    # 16 x 8 sRGB: red ramps left to right, green is bright at the top and dark
    # at the bottom (a v flip changes the picture), blue has a bar in row 1.
    h, w = 8, 16
    y, x = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    img = np.stack([20 + 14 * x, 235 - 30 * y, np.where(y == 1, 230, 40 + 5 * x)], axis=-1).astype(np.uint8)
    mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB).write(os.path.join(SCENES, "data", "tex_srgb.png"))
    # 4 x 4 raw values: distinct levels per texel, darker toward the bottom right.
    y, x = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
    raw = np.stack([230 - 40 * x - 10 * y, 60 + 50 * y, 200 - 45 * y + 5 * x], axis=-1).astype(np.uint8)
    mi.Bitmap(raw, pixel_format=mi.Bitmap.PixelFormat.RGB).write(os.path.join(SCENES, "data", "tex_raw.png"))
    # 8 x 8 gray roughness (read raw, for `rough_textured`): alpha from 0.04 to about 0.6, rising left to
    # right and bottom to top with a smooth bump, so that both uv axes matter.
    y, x = np.meshgrid(np.arange(8), np.arange(8), indexing="ij")
    alpha = 0.04 + 0.05 * x + 0.02 * (7 - y) + 0.12 * np.exp(-((x - 2) ** 2 + (y - 5) ** 2) / 3.0)
    gray = np.round(255 * alpha).astype(np.uint8)[:, :, None]
    mi.Bitmap(gray, pixel_format=mi.Bitmap.PixelFormat.Y).write(os.path.join(SCENES, "data", "alpha_gray.png"))


def write_cube(mi):
    """Mitsuba's cube mesh and its surface interactions under a fixed to_world."""
    cube = mi.load_dict({"type": "cube"})
    params = mi.traverse(cube)
    table = {
        "mitsuba": mi.__version__,
        "variant": mi.variant(),
        "vertex_positions": np.array(params["vertex_positions"]).reshape(-1, 3).tolist(),
        "vertex_normals": np.array(params["vertex_normals"]).reshape(-1, 3).tolist(),
        "vertex_texcoords": np.array(params["vertex_texcoords"]).reshape(-1, 2).tolist(),
        "faces": np.array(params["faces"]).reshape(-1, 3).tolist(),
    }
    to_world = mi.ScalarTransform4f().translate([0.4, -0.3, 0.7]).rotate([1, 2, 0.5], 37).scale([0.6, 1.3, 0.9])
    m = np.array(to_world.matrix, dtype=np.float64)
    scene = mi.load_dict({"type": "scene", "cube": {"type": "cube", "to_world": to_world}})
    hits = []
    for n in np.vstack([np.eye(3), -np.eye(3)]):
        k = int(np.argmax(np.abs(n)))
        a, b = [i for i in range(3) if i != k]
        for s, t in [(0.5, 0.3), (-0.6, -0.4)]:
            q = n.copy()
            q[a], q[b] = s, t
            p = (m @ np.append(q, 1.0))[:3]
            nw = np.linalg.inv(m[:3, :3]).T @ n
            nw /= np.linalg.norm(nw)
            o = p + 0.5 * nw
            si = scene.ray_intersect(mi.Ray3f(o.tolist(), (-nw).tolist()))
            hits.append({"origin": o.tolist(), "direction": (-nw).tolist(), "p": list(si.p), "n": list(si.n),
                         "uv": list(si.uv), "dp_du": list(si.dp_du), "dp_dv": list(si.dp_dv)})
    table["to_world"] = m.tolist()
    table["hits"] = hits
    # A triangle without uvs, as is and with flip_normals: Mitsuba's uv is the
    # barycentric (b1, b2) and dp_du = p1 - p0 in the file's order either way.
    tri = [[0.3, -1.0, 0.2], [-0.4, 1.2, -0.1], [1.1, 0.5, 0.3]]
    bare = []
    for flip in (False, True):
        props = mi.Properties()
        props["flip_normals"] = flip
        mesh = mi.Mesh("tri", 3, 1, has_vertex_normals=False, has_vertex_texcoords=False, props=props)
        mp = mi.traverse(mesh)
        mp["vertex_positions"] = np.array(tri).ravel().tolist()
        mp["faces"] = [0, 1, 2]
        mp.update()
        si = mi.load_dict({"type": "scene", "m": mesh}).ray_intersect(mi.Ray3f([0.3, 0.2, 5.0], [0.0, 0.0, -1.0]))
        bare.append({"flip_normals": flip, "origin": [0.3, 0.2, 5.0], "direction": [0.0, 0.0, -1.0], "p": list(si.p),
                     "n": list(si.n), "uv": list(si.uv), "dp_du": list(si.dp_du)})
    table["bare_triangle"] = tri
    table["bare_hits"] = bare
    # <rotate x="1" y="1" z="0.3" angle="40"/>: Mitsuba uses the axis as written (not normalized).
    rotated = mi.load_string('<scene version="3.0.0"><shape type="cube"><transform name="to_world">'
                             '<rotate x="1" y="1" z="0.3" angle="40"/></transform></shape></scene>').shapes()[0]
    table["rotated_cube_positions"] = np.array(mi.traverse(rotated)["vertex_positions"]).reshape(-1, 3).tolist()
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(os.path.dirname(OUT), "mitsuba_cube.json"), "w") as f:
        json.dump(table, f)


# Spheres turned by their to_world: Mitsuba keeps the rotation, which turns
# the uv parameterization and dp/du. Rotation axes are unit (Mitsuba uses a
# <rotate> axis as written, so a non-unit one would also scale).
SPHERE_XML = [
    '<shape type="sphere"><point name="center" x="0.1" y="0.2" z="-0.3"/><float name="radius" value="0.5"/>'
    '<transform name="to_world"><scale value="0.7"/>'
    '<rotate x="0.4364357805" y="0.8728715609" z="0.2182178902" angle="37"/>'
    '<translate x="0.2" y="-0.1" z="0.3"/></transform></shape>',
    '<shape type="sphere"><float name="radius" value="1.3"/>'
    '<transform name="to_world"><rotate x="1" angle="-70"/><rotate z="1" angle="120"/>'
    '<translate x="-0.5" y="0.4" z="0.1"/></transform></shape>',
]


def write_sphere(mi):
    """Surface interactions on spheres turned by their to_world."""
    table = {"mitsuba": mi.__version__, "variant": mi.variant(), "spheres": []}
    for xml in SPHERE_XML:
        scene = mi.load_string(f'<scene version="3.0.0">{xml}</scene>')
        shape = scene.shapes()[0]
        m = np.array(mi.traverse(shape)["to_world"].matrix, dtype=np.float64)
        center, radius = m[:3, 3], float(np.linalg.norm(m[:3, 0]))
        rot = m[:3, :3] / radius
        hits = []
        # Local polar angle and azimuth, away from the poles and the seam.
        for theta, phi in [(0.35, 0.6), (0.9, 1.7), (1.2, 2.9), (1.6, 3.6), (2.0, 4.4), (2.5, 5.3), (2.85, 6.0),
                           (1.4, 0.2)]:
            local = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
            n = rot @ local
            p = center + radius * n
            o = p + 0.5 * n
            si = scene.ray_intersect(mi.Ray3f(o.tolist(), (-n).tolist()))
            hits.append({"origin": o.tolist(), "direction": (-n).tolist(), "p": list(si.p), "n": list(si.n),
                         "uv": list(si.uv), "dp_du": list(si.dp_du)})
        table["spheres"].append({"xml": xml, "to_world": m.tolist(), "hits": hits})
    with open(os.path.join(os.path.dirname(OUT), "mitsuba_sphere.json"), "w") as f:
        json.dump(table, f)


def block_means(img: np.ndarray) -> np.ndarray:
    h, w, _ = img.shape
    return img.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, 3).mean(axis=(1, 3))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", action="store_true")
    ap.add_argument("--textures", action="store_true")
    ap.add_argument("--cube", action="store_true")
    ap.add_argument("--sphere", action="store_true")
    ap.add_argument("--renders", type=int, default=16)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("names", nargs="*")
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(ROOT, "bench"))
    import llvm

    llvm.use_newest_llvm()
    import mitsuba as mi

    mi.set_variant(a.variant)
    if a.data:
        write_data(mi)
    if a.data or a.textures:
        write_textures(mi)
    if a.cube or a.sphere:
        mi.set_variant("scalar_rgb")
        if a.cube:
            write_cube(mi)
        if a.sphere:
            write_sphere(mi)
        mi.set_variant(a.variant)
        if not a.names:
            return
    os.makedirs(OUT, exist_ok=True)
    for name in a.names or NAMES:
        scene = mi.load_file(os.path.join(SCENES, name + ".xml"), spp=str(a.spp))
        blocks, means = [], []
        for seed in range(a.renders):
            img = np.array(mi.render(scene, seed=seed, spp=a.spp), dtype=np.float64)[:, :, :3]
            blocks.append(block_means(img))
            means.append(img.mean(axis=(0, 1)))
        blocks, means = np.array(blocks), np.array(means)
        k = a.renders
        out = {
            "scene": f"scenes/mitsuba/{name}.xml",
            "mitsuba": mi.__version__,
            "variant": a.variant,
            "renders": k,
            "spp_per_render": a.spp,
            "block": BLOCK,
            "block_mean": np.round(blocks.mean(0), 7).tolist(),
            "block_stderr": np.round(blocks.std(0, ddof=1) / np.sqrt(k), 7).tolist(),
            "image_mean": means.mean(0).tolist(),
            "image_stderr": (means.std(0, ddof=1) / np.sqrt(k)).tolist(),
        }
        with open(os.path.join(OUT, name + ".json"), "w") as f:
            json.dump(out, f)
        print(name, "mean", np.round(out["image_mean"], 5), "rel stderr", np.round(np.array(out["image_stderr"]) / out["image_mean"], 5))


if __name__ == "__main__":
    main()
