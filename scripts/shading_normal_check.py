"""Measures how niebla and Mitsuba 3 differ on meshes with interpolated
(smooth) vertex normals, where a camera ray's `wo` can lie behind the
shading normal while in front of the geometric one.

    /work/main/bench/.venv/bin/python scripts/shading_normal_check.py [NIEBLA]

Writes a coarse UV sphere (5 rings x 8 segments, vertex normals on the
sphere) and a scene of two of them (white diffuse 0.8, rough aluminium
alpha 0.2) under a uniform white environment into a temporary folder, and
renders it 16 x 64 spp with Mitsuba (llvm_ad_rgb) and with niebla (NIEBLA,
default target/release/niebla), once with the smooth normals and once with
`face_normals` (the control: no shading normals). Prints the image means
with their standard errors and the largest relative difference of 8x8
block means.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SCENE = """<scene version="3.0.0">
  <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/><rfilter type="box"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
  <shape type="obj">
    <string name="filename" value="lowpoly.obj"/>{flat}
    <transform name="to_world"><rotate x="1" angle="-70"/><translate x="-0.75"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>
  </shape>
  <shape type="obj">
    <string name="filename" value="lowpoly.obj"/>{flat}
    <transform name="to_world"><rotate x="1" angle="-70"/><scale value="0.7"/><translate x="0.9"/></transform>
    <bsdf type="roughconductor"><string name="material" value="Al"/><float name="alpha" value="0.2"/></bsdf>
  </shape>
</scene>
"""


def write_sphere(path, rings=5, segs=8):
    v = [(0.0, 0.0, 1.0)]
    for i in range(1, rings):
        th = math.pi * i / rings
        v += [(math.sin(th) * math.cos(2 * math.pi * j / segs), math.sin(th) * math.sin(2 * math.pi * j / segs),
               math.cos(th)) for j in range(segs)]
    v.append((0.0, 0.0, -1.0))
    idx = lambda i, j: 1 + (i - 1) * segs + j % segs
    f = [(0, idx(1, j), idx(1, j + 1)) for j in range(segs)]
    for i in range(1, rings - 1):
        for j in range(segs):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            f += [(a, b, c), (a, c, d)]
    f += [(idx(rings - 1, j), len(v) - 1, idx(rings - 1, j + 1)) for j in range(segs)]
    with open(path, "w") as out:
        out.writelines("v %f %f %f\n" % p for p in v)
        out.writelines("vn %f %f %f\n" % p for p in v)
        out.writelines("f %d//%d %d//%d %d//%d\n" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1) for a, b, c in f)


def stats(images):
    means = np.array([im.mean(axis=(0, 1)) for im in images])
    return np.mean(images, 0), means.mean(0), means.std(0, ddof=1) / math.sqrt(len(images))


def main():
    niebla = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "release", "niebla")
    sys.path.insert(0, os.path.join(ROOT, "bench"))
    import llvm

    llvm.use_newest_llvm()
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    tmp = tempfile.mkdtemp()
    write_sphere(os.path.join(tmp, "lowpoly.obj"))
    for label, flat in [("smooth normals", ""), ("face_normals", '<boolean name="face_normals" value="true"/>')]:
        xml = os.path.join(tmp, "scene.xml")
        with open(xml, "w") as f:
            f.write(SCENE.format(flat=flat))
        scene = mi.load_file(xml)
        m_img, m_mean, m_se = stats([np.array(mi.render(scene, seed=k, spp=64), np.float64)[:, :, :3]
                                     for k in range(16)])
        n_imgs = []
        for k in range(16):
            out = os.path.join(tmp, "n.exr")
            subprocess.run([niebla, "render", "--quiet", "--spp", "64", "--seed", str(k), xml, "-o", out],
                           check=True, stdout=subprocess.DEVNULL)
            n_imgs.append(np.array(mi.Bitmap(out), np.float64)[:, :, :3])
        n_img, n_mean, n_se = stats(n_imgs)
        h, w, _ = n_img.shape
        blocks = lambda im: im.reshape(h // 8, 8, w // 8, 8, 3).mean(axis=(1, 3))
        rel = (blocks(n_img) - blocks(m_img)) / blocks(m_img)
        print(f"{label}: Mitsuba mean {np.round(m_mean, 5)} (se {np.round(m_se, 5)}), niebla {np.round(n_mean, 5)} "
              f"(se {np.round(n_se, 5)}): niebla/Mitsuba - 1 = {np.round(n_mean / m_mean - 1, 5)}; largest block "
              f"difference {rel.flat[np.argmax(np.abs(rel))]:+.4f}")


if __name__ == "__main__":
    main()
