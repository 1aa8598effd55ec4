"""Builds a Blender Cycles scene (through `bpy`, Blender as a Python module)
from a niebla scene description, with conventions matched so that both
renderers compute the same image (only what the bench scenes use; anything
else raises `Unsupported`). Runs inside bench/.venv-cycles (bpy 5.0.1).

Matched conventions (checked in the Cycles 5.0 sources and by comparing image
means with niebla; see bench/README.md):

- camera: a perspective camera at niebla's position, looking at its target,
  `sensor_fit` VERTICAL with `angle_y` = niebla's `fov_y`; Blender cameras look
  down their local -Z with +Y up, so the camera matrix has columns right, up,
  -forward. Box pixel filter of one pixel.
- unbiased and comparable: no denoising, no adaptive sampling, no clamping,
  no path guiding, `blur_glossy` 0, unbiased (null-scattering) volumes,
  every caustic path allowed. Cycles' sampler (Owen-scrambled Sobol) is kept.
- depth: niebla's `max_depth` N counts scattering vertices, each with
  next-event estimation. Cycles' bounce count starts at 0 for the first
  vertex (0 bounces = direct light only), so Cycles gets N - 1 in every
  bounce class.
- media: Cycles' Volume Coefficients node takes sigma_a and sigma_s per unit
  length (and the HG anisotropy), exactly niebla's coefficients. A medium
  inside a box is a mesh whose material links only a Volume (an index-matched
  boundary, niebla's `null` BSDF). A grid medium is a Volume object reading a
  VDB written from the same voxels (cell-centred, voxel size = the cell size
  of niebla's bounds, float precision, no clipping), its `density` attribute
  multiplying the coefficients. A grid medium whose density is itself a VDB
  grid (`{"type": "vdb"}`, grid `density`) reads that file directly, placed
  by the medium's `to_world`; its active voxels must lie in the container box
  (niebla clips to the box, Cycles does not).
- lights: a directional light of irradiance E is a Sun of strength E and
  angle 0; a point light of intensity I (W/sr) a Point of radius 0, soft
  falloff off, power 4 pi I; a constant environment of radiance L the World
  background color L at strength 1; a spot light only with a hard edge
  (`beam_width` = `cutoff_angle`): a Spot of `spot_size` 2 cutoff, blend 0,
  power 4 pi I (Cycles' blend is a smoothstep in the cosine, which cannot
  express Mitsuba's linear-in-angle falloff that niebla follows).
- pyro media (`"type": "pyro"`, whose model follows Principled Volume): a
  Volume object reading the same VDB file (placed by `to_world`), shaded by a
  Principled Volume with the same Density, Density Attribute, Color,
  Absorption Color, Anisotropy, Emission Strength, Blackbody Intensity and
  Tint, Temperature and Temperature Attribute (grid names resolved as niebla
  does: the name given, else the first of the exporters' names in the file);
  Emission Color is `emission_color` times the flame attribute through a
  Color Ramp (linear) of `flame_ramp` (the attribute itself without a ramp);
  `temperature_offset` feeds Temperature through a Multiply Add node of the
  temperature attribute. niebla emits only where the density is positive,
  Cycles wherever the volume's active voxels are: the same light when flame
  and temperature vanish outside the density, as scenes/make_fireball.py
  writes them. The container box must hold every grid's active voxels
  (niebla clips to it, Cycles does not). Cycles' blackbody color is a
  fitted curve over 800-12000 K (a constant color below 800 K), niebla's a
  table of Planck's law integrated against the CIE matching functions: the
  colors differ slightly (see bench/README.md for the measured agreement).
- surfaces: `diffuse` is a Diffuse BSDF (roughness 0: Lambertian); spheres
  are smooth-shaded UV spheres of 512 x 256 segments (the polyhedron's
  volume is within 1e-4 of the sphere's).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from niebla2mitsuba import niebla_transform  # noqa: E402


class Unsupported(Exception):
    """A feature of the niebla scene with no matched Cycles counterpart here."""


def _rgb(v):
    if isinstance(v, (int, float)):
        return [float(v)] * 3
    if len(v) != 3:
        raise Unsupported(f"color {v!r}")
    return [float(x) for x in v]


def _normalize(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _look_at_matrix(position, target, up):
    """Blender object matrix of a camera (or light pointing down -Z) at
    `position` looking at `target`."""
    f = _normalize(np.asarray(target, float) - np.asarray(position, float))
    r = _normalize(np.cross(f, up))
    u = np.cross(r, f)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = r, u, -f, position
    return m


def _aim_matrix(position, direction):
    """A light at `position` whose local -Z points along `direction`."""
    d = _normalize(direction)
    up = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    return _look_at_matrix(np.asarray(position, float), np.asarray(position, float) + d, up)


def _coefficients(m):
    """(sigma_a, sigma_s) per channel, with `scale` applied."""
    scale = float(m.get("scale", 1.0))
    if "sigma_t" in m:
        st, al = _rgb(m["sigma_t"]), _rgb(m.get("albedo", 1.0))
        ss = [t * a for t, a in zip(st, al)]
        sa = [t - s for t, s in zip(st, ss)]
    else:
        sa, ss = _rgb(m["sigma_a"]), _rgb(m["sigma_s"])
    return [x * scale for x in sa], [x * scale for x in ss]


def _anisotropy(m):
    p = m.get("phase") or {"type": "isotropic"}
    if p["type"] == "isotropic":
        return 0.0
    if p["type"] == "hg":
        return float(p["g"])
    raise Unsupported(f"phase function {p['type']!r}")


def write_vdb(npy_path: str, bounds: dict, vdb_path: str) -> None:
    """Writes the `.npy` density ([z][y][x], cell-centred over `bounds`) as a
    float VDB grid named `density` whose voxel (i, j, k) sits at the cell
    centre niebla uses; done by Debian's python3-openvdb (the system python)."""
    if os.path.exists(vdb_path) and os.path.getmtime(vdb_path) >= os.path.getmtime(npy_path):
        return
    script = r"""
import sys, numpy as np
try:
    import openvdb as vdb
except ImportError:
    import pyopenvdb as vdb
npy, out, bmin, bmax = sys.argv[1], sys.argv[2], [float(x) for x in sys.argv[3:6]], [float(x) for x in sys.argv[6:9]]
a = np.load(npy).astype(np.float32)          # [z][y][x]
nz, ny, nx = a.shape
cell = [(bmax[0]-bmin[0])/nx, (bmax[1]-bmin[1])/ny, (bmax[2]-bmin[2])/nz]
assert max(cell) - min(cell) < 1e-6 * max(cell), ("non-cubic cells", cell)
g = vdb.FloatGrid()
g.name = "density"
g.copyFromArray(np.ascontiguousarray(a.transpose(2, 1, 0)))   # [x][y][z]: index (i, j, k)
m = [[cell[0], 0, 0, 0], [0, cell[1], 0, 0], [0, 0, cell[2], 0],
     [bmin[0] + 0.5*cell[0], bmin[1] + 0.5*cell[1], bmin[2] + 0.5*cell[2], 1]]
g.transform = vdb.createLinearTransform(m)
g.gridClass = vdb.GridClass.FOG_VOLUME
vdb.write(out + ".tmp", grids=[g])
"""
    args = ["/usr/bin/python3", "-c", script, npy_path, vdb_path]
    args += [str(x) for x in bounds["min"]] + [str(x) for x in bounds["max"]]
    subprocess.run(args, check=True)
    os.replace(vdb_path + ".tmp", vdb_path)


def build(desc: dict, scene_dir: str, threads: int = 2):
    """Replaces Blender's current scene by the niebla scene `desc` (data paths
    relative to `scene_dir`). Returns the bpy scene."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_preview_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.use_guiding = False
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.volume_biased = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.use_animated_seed = False
    integ = desc["render"]["integrator"]
    if integ.get("type") != "volpath":
        raise Unsupported(f"integrator {integ.get('type')!r}")
    bounces = int(integ.get("max_depth", 64)) - 1
    if not 0 <= bounces <= 1024:
        raise Unsupported(f"max_depth {bounces + 1}")
    for attr in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces"):
        setattr(c, attr, bounces)
    c.transparent_max_bounces = 1024
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    scene.render.use_persistent_data = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "NONE"
    scene.render.image_settings.color_mode = "RGB"

    cam_d = desc["camera"]
    if cam_d.get("type", "perspective") != "perspective":
        raise Unsupported(f"camera {cam_d.get('type')!r}")
    scene.render.resolution_x = int(cam_d["width"])
    scene.render.resolution_y = int(cam_d["height"])
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(float(cam_d["fov_y"]))
    cam.clip_start = 1e-4
    cam.clip_end = 1e6
    cam_obj = bpy.data.objects.new("camera", cam)
    cam_obj.matrix_world = _look_at_matrix(cam_d["position"], cam_d["target"], cam_d.get("up", [0, 1, 0])).T.tolist()
    scene.collection.objects.link(cam_obj)
    scene.camera = cam_obj

    media = desc.get("media", {})
    grid_objects = {}
    for shape in desc.get("shapes", []):
        _shape(bpy, scene, shape, media, scene_dir, grid_objects)

    world = bpy.data.worlds.new("world")
    scene.world = world
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    for light in desc.get("lights", []):
        _light(bpy, scene, light, bg)
    return scene


def _material_volume(bpy, name, m, density_from_grid: bool):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    vc = nt.nodes.new("ShaderNodeVolumeCoefficients")
    vc.phase = "HENYEY_GREENSTEIN"
    inputs = {i.name: i for i in vc.inputs}
    inputs["Weight"].default_value = 1.0
    inputs["Anisotropy"].default_value = _anisotropy(m)
    sa, ss = _coefficients(m)
    if m.get("emission"):
        raise Unsupported("emissive media")
    if density_from_grid:
        info = nt.nodes.new("ShaderNodeVolumeInfo")
        for socket, coeff in (("Absorption Coefficients", sa), ("Scatter Coefficients", ss)):
            sc = nt.nodes.new("ShaderNodeVectorMath")
            sc.operation = "SCALE"
            sc.inputs[0].default_value = coeff
            nt.links.new(info.outputs["Density"], sc.inputs["Scale"])
            nt.links.new(sc.outputs["Vector"], inputs[socket])
    else:
        inputs["Absorption Coefficients"].default_value = sa
        inputs["Scatter Coefficients"].default_value = ss
    inputs["Emission Coefficients"].default_value = (0.0, 0.0, 0.0)
    nt.links.new(vc.outputs["Volume"], out.inputs["Volume"])
    return mat


def _material_surface(bpy, name, bsdf):
    kind = (bsdf or {"type": "null"}).get("type", "null")
    if kind == "null":
        return None
    if kind != "diffuse":
        raise Unsupported(f"bsdf {kind!r}")
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    refl = bsdf.get("reflectance", 0.5)
    if isinstance(refl, dict):
        raise Unsupported("textured reflectance")
    d.inputs["Color"].default_value = (*_rgb(refl), 1.0)
    d.inputs["Roughness"].default_value = 0.0
    nt.links.new(d.outputs["BSDF"], out.inputs["Surface"])
    return mat


def _mesh_object(bpy, scene, name, verts, faces, smooth=False):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(map(float, v)) for v in verts], [], [tuple(f) for f in faces])
    mesh.update()
    if smooth:
        mesh.shade_smooth()
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def _box_mesh(bmin, bmax):
    x0, y0, z0 = bmin
    x1, y1, z1 = bmax
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    f = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (0, 4, 7, 3)]
    return v, f


def _sphere_mesh(center, radius, seg=512, rings=256):
    v = [(center[0], center[1] + radius, center[2])]
    for i in range(1, rings):
        th = math.pi * i / rings
        for j in range(seg):
            ph = 2 * math.pi * j / seg
            v.append((center[0] + radius * math.sin(th) * math.cos(ph), center[1] + radius * math.cos(th),
                      center[2] + radius * math.sin(th) * math.sin(ph)))
    v.append((center[0], center[1] - radius, center[2]))
    f = []
    for j in range(seg):
        f.append((0, 1 + (j + 1) % seg, 1 + j))
    for i in range(rings - 2):
        a, b = 1 + i * seg, 1 + (i + 1) * seg
        for j in range(seg):
            j2 = (j + 1) % seg
            f.append((a + j, a + j2, b + j2, b + j))
    last = len(v) - 1
    base = 1 + (rings - 2) * seg
    for j in range(seg):
        f.append((last, base + j, base + (j + 1) % seg))
    return v, f


PYRO_DENSITY_NAMES = ["density", "smoke"]
PYRO_TEMPERATURE_NAMES = ["temperature", "heat"]
PYRO_FLAME_NAMES = ["flame", "flames", "fire"]


def vdb_grids(vdb_path: str) -> dict:
    """{grid name: (value type, world min, world max)} of a VDB file, the
    bounds those of its active voxels (voxel centres +- half a voxel, through
    the grid's index-to-world map; None for an empty grid); read by Debian's
    python3-openvdb."""
    script = r"""
import itertools, json, sys
try:
    import pyopenvdb as vdb
except ImportError:
    import openvdb as vdb
out = {}
for g in vdb.readAll(sys.argv[1])[0]:
    if g.activeVoxelCount() == 0:
        out[g.name] = [g.valueTypeName, None, None]
        continue
    lo, hi = g.evalActiveVoxelBoundingBox()
    pts = [g.transform.indexToWorld(tuple((hi if bit else lo)[a] + (0.5 if bit else -0.5) for a, bit in enumerate(bits)))
           for bits in itertools.product((0, 1), repeat=3)]
    out[g.name] = [g.valueTypeName, [min(p[a] for p in pts) for a in range(3)], [max(p[a] for p in pts) for a in range(3)]]
print(json.dumps(out))
"""
    import json

    res = subprocess.run(["/usr/bin/python3", "-c", script, vdb_path], check=True, capture_output=True, text=True)
    return json.loads(res.stdout)


def _grid_name(given, defaults, grids, what):
    """The grid niebla's pyro medium reads for `what`: the name given (`""`
    for none), else the first default name present in the file."""
    if given is not None:
        if given == "":
            return None
        if given not in grids:
            raise Unsupported(f"pyro {what} grid {given!r} absent from the file")
        return given
    return next((n for n in defaults if n in grids), None)


def _grid_volume_object(bpy, scene, name, path, grids, names, xf, shape, what):
    """A Volume object reading the VDB file `path` (full precision, no
    clipping, object space), placed by the 4x4 matrix `xf` (niebla's
    `to_world`; None for the identity), linked into `scene`. niebla clips the
    grids to the container box `shape`; Cycles renders every active voxel:
    so first checks that the box holds the active voxels of each grid in
    `names` (their bounds from `grids`, as `vdb_grids` gives them), else
    raises Unsupported naming `what` (e.g. "pyro grid")."""
    if shape is not None:
        bmin, bmax = np.asarray(shape["min"], float), np.asarray(shape["max"], float)
        m = np.eye(4) if xf is None else xf
        for g in names:
            lo, hi = grids[g][1], grids[g][2]
            if lo is None:
                continue
            for c in np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T:
                w = (m @ np.array([*c, 1.0]))[:3]
                if np.any(w < bmin - 1e-4) or np.any(w > bmax + 1e-4):
                    raise Unsupported(f"{what} {g!r} reaches beyond its container box ({w} outside {bmin}..{bmax})")
    vol = bpy.data.volumes.new(name)
    vol.filepath = path
    vol.render.precision = "FULL"
    vol.render.clipping = 0.0
    vol.render.space = "OBJECT"
    obj = bpy.data.objects.new(name, vol)
    if xf is not None:
        obj.matrix_world = xf.T.tolist()
    scene.collection.objects.link(obj)
    return obj


def _pyro_object(bpy, scene, name, m, shape, scene_dir):
    """A pyro medium as a Volume object reading the same VDB file, shaded by a
    Principled Volume with niebla's parameters (the pyro model follows that
    node): Density, Color, Absorption Color, Anisotropy, Emission Strength,
    Emission Color (times the flame attribute through a Color Ramp, linear),
    Blackbody Intensity and Tint, Temperature (times the temperature
    attribute, plus `temperature_offset` through a Multiply Add node)."""
    path = m["file"] if os.path.isabs(m["file"]) else os.path.join(scene_dir, m["file"])
    grids = vdb_grids(path)
    density = _grid_name(m.get("density_attribute"), PYRO_DENSITY_NAMES, grids, "density")
    if density is None:
        raise Unsupported("a pyro medium without a density grid")
    strength = float(m.get("emission_strength", 0.0))
    bb_intensity = float(m.get("blackbody_intensity", 0.0))
    flame = _grid_name(m.get("flame_attribute"), PYRO_FLAME_NAMES, grids, "flame") if strength > 0 else None
    temp = _grid_name(m.get("temperature_attribute"), PYRO_TEMPERATURE_NAMES, grids, "temperature") \
        if bb_intensity > 0 else None
    obj = _grid_volume_object(bpy, scene, name, path, grids, list(filter(None, (density, flame, temp))),
                              niebla_transform(m.get("to_world")), shape, "pyro grid")

    mat = bpy.data.materials.new(name + "_pyro")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    pv = nt.nodes.new("ShaderNodeVolumePrincipled")
    inp = {i.name: i for i in pv.inputs}
    inp["Density"].default_value = float(m.get("density", 1.0))
    inp["Density Attribute"].default_value = density
    inp["Color"].default_value = (*_rgb(m.get("color", 0.5)), 1.0)
    inp["Color Attribute"].default_value = ""
    inp["Absorption Color"].default_value = (*_rgb(m.get("absorption_color", 0.0)), 1.0)
    inp["Anisotropy"].default_value = float(m.get("anisotropy", 0.0))
    inp["Emission Strength"].default_value = strength
    ecolor = _rgb(m.get("emission_color", 1.0))
    inp["Emission Color"].default_value = (*ecolor, 1.0)
    if flame is not None:
        attr = nt.nodes.new("ShaderNodeAttribute")
        attr.attribute_name = flame
        src = attr.outputs["Fac"]
        stops = m.get("flame_ramp")
        if stops:
            ramp = nt.nodes.new("ShaderNodeValToRGB")
            ramp.color_ramp.interpolation = "LINEAR"
            els = ramp.color_ramp.elements
            while len(els) < len(stops):
                els.new(1.0)
            if len(stops) == 1:
                els.remove(els[1])
            for e, (pos, col) in zip(els, stops):
                e.position = float(pos)
                e.color = (*_rgb(col), 1.0)
            nt.links.new(attr.outputs["Fac"], ramp.inputs["Fac"])
            src = ramp.outputs["Color"]
        if ecolor != [1.0, 1.0, 1.0]:
            mix = nt.nodes.new("ShaderNodeMix")
            mix.data_type = "RGBA"
            mix.blend_type = "MULTIPLY"
            mix.inputs["Factor"].default_value = 1.0
            nt.links.new(src, mix.inputs[6])
            mix.inputs[7].default_value = (*ecolor, 1.0)
            src = mix.outputs[2]
        nt.links.new(src, inp["Emission Color"])
    inp["Blackbody Intensity"].default_value = bb_intensity
    inp["Blackbody Tint"].default_value = (*_rgb(m.get("blackbody_tint", 1.0)), 1.0)
    scale, offset = float(m.get("temperature", 1000.0)), float(m.get("temperature_offset", 0.0))
    if temp is not None and offset != 0.0:
        attr = nt.nodes.new("ShaderNodeAttribute")
        attr.attribute_name = temp
        mad = nt.nodes.new("ShaderNodeMath")
        mad.operation = "MULTIPLY_ADD"
        nt.links.new(attr.outputs["Fac"], mad.inputs[0])
        mad.inputs[1].default_value = scale
        mad.inputs[2].default_value = offset
        nt.links.new(mad.outputs["Value"], inp["Temperature"])
        inp["Temperature Attribute"].default_value = ""
    else:
        inp["Temperature"].default_value = scale + (offset if temp is None else 0.0)
        inp["Temperature Attribute"].default_value = temp or ""
    nt.links.new(pv.outputs["Volume"], out.inputs["Volume"])
    obj.data.materials.append(mat)


def _vdb_grid_object(bpy, scene, name, m, d, shape, scene_dir):
    """A `grid` medium whose density is a VDB grid (`{"type": "vdb"}`): a
    Volume object reading the same file (placed by the medium's `to_world`),
    its `density` grid multiplying the coefficients (Volume Info's Density
    reads the grid named `density`). niebla clips the grid to the container
    box, Cycles renders every active voxel: the box must hold them all."""
    grid = d.get("grid", "density")
    if grid != "density":
        raise Unsupported(f"a VDB density grid named {grid!r} (Volume Info reads 'density')")
    for key in ("velocity", "albedo_grid", "emission"):
        if m.get(key):
            raise Unsupported(f"a VDB grid medium with {key}")
    path = d["file"] if os.path.isabs(d["file"]) else os.path.join(scene_dir, d["file"])
    grids = vdb_grids(path)
    if grid not in grids:
        raise Unsupported(f"grid {grid!r} absent from {path}")
    obj = _grid_volume_object(bpy, scene, name, path, grids, [grid], niebla_transform(m.get("to_world")), shape,
                              "VDB grid")
    obj.data.materials.append(_material_volume(bpy, name + "_volume", m, True))


def _shape(bpy, scene, shape, media, scene_dir, grid_objects):
    kind = shape["type"]
    name = f"shape{len(scene.collection.objects)}"
    if shape.get("exterior"):
        raise Unsupported("exterior media on shapes (the bench scenes give interiors only)")
    interior = shape.get("interior")
    surf = _material_surface(bpy, name + "_surface", shape.get("bsdf"))
    if kind == "box":
        verts, faces = _box_mesh(shape["min"], shape["max"])
        smooth = False
    elif kind == "sphere":
        verts, faces = _sphere_mesh(shape["center"], float(shape["radius"]))
        smooth = True
    elif kind == "rectangle":
        m = niebla_transform(shape.get("to_world"))
        corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
        verts = [tuple((m @ np.array([x, y, 0.0, 1.0]))[:3]) for x, y in corners]
        faces = [(0, 1, 2, 3)]
        smooth = False
    else:
        raise Unsupported(f"shape {kind!r}")
    if kind in ("box", "sphere") and shape.get("to_world"):
        raise Unsupported(f"a transformed {kind}")

    if interior is not None:
        m = media[interior]
        mkind = m.get("type", "grid" if "density" in m else "homogeneous")
        if mkind == "homogeneous":
            if surf is not None:
                raise Unsupported("a medium inside a non-null surface")
            obj = _mesh_object(bpy, scene, name, verts, faces, smooth)
            obj.data.materials.append(_material_volume(bpy, name + "_volume", m, False))
            return
        if mkind == "pyro":
            if kind != "box" or surf is not None:
                raise Unsupported("a pyro medium outside a null box")
            _pyro_object(bpy, scene, name, m, shape, scene_dir)
            return
        d = m["density"]
        if d.get("type") == "vdb":
            if kind != "box" or surf is not None:
                raise Unsupported("a VDB grid medium outside a null box")
            _vdb_grid_object(bpy, scene, name, m, d, shape, scene_dir)
            return
        if d.get("type") != "npy":
            raise Unsupported(f"density {d.get('type')!r}")
        if kind != "box" or [list(map(float, shape["min"])), list(map(float, shape["max"]))] != [
                list(map(float, d["bounds"]["min"])), list(map(float, d["bounds"]["max"]))]:
            raise Unsupported("a grid medium whose container is not its bounding box")
        npy = d["file"] if os.path.isabs(d["file"]) else os.path.join(scene_dir, d["file"])
        vdb_path = os.path.splitext(npy)[0] + ".vdb"
        write_vdb(npy, d["bounds"], vdb_path)
        obj = _grid_volume_object(bpy, scene, name, vdb_path, {}, [], None, None, "grid")
        obj.data.materials.append(_material_volume(bpy, name + "_volume", m, True))
        return
    if surf is None:
        return  # a null surface without media changes nothing
    obj = _mesh_object(bpy, scene, name, verts, faces, smooth)
    obj.data.materials.append(surf)


def _light(bpy, scene, light, bg):
    kind = light["type"]
    name = f"light{len(scene.collection.objects)}"
    if kind == "constant":
        bg.inputs["Color"].default_value = (*_rgb(light["radiance"]), 1.0)
        return
    if kind == "directional":
        e = _rgb(light["irradiance"])
        lt = bpy.data.lights.new(name, type="SUN")
        lt.angle = 0.0
        mx = max(e)
        lt.energy = mx
        lt.color = [x / mx for x in e]
        obj = bpy.data.objects.new(name, lt)
        obj.matrix_world = _aim_matrix([0.0, 0.0, 0.0], light["direction"]).T.tolist()
    elif kind in ("point", "spot"):
        i = _rgb(light["intensity"])
        mx = max(i)
        lt = bpy.data.lights.new(name, type="POINT" if kind == "point" else "SPOT")
        lt.shadow_soft_size = 0.0
        lt.use_soft_falloff = False
        lt.energy = 4.0 * math.pi * mx
        lt.color = [x / mx for x in i]
        pos = np.asarray(light["position"], float)
        if kind == "spot":
            cutoff = float(light.get("cutoff_angle", 20.0))
            beam = float(light.get("beam_width", cutoff * 0.75))
            if abs(beam - cutoff) > 1e-6:
                raise Unsupported("a spot light with a soft edge (Cycles' blend is a smoothstep in the cosine, "
                                  "niebla's and Mitsuba's falloff is linear in the angle)")
            lt.spot_size = math.radians(2.0 * cutoff)
            lt.spot_blend = 0.0
            direction = (np.asarray(light["target"], float) - pos) if "target" in light else light["direction"]
        else:
            direction = [0.0, -1.0, 0.0]
        obj = bpy.data.objects.new(name, lt)
        obj.matrix_world = _aim_matrix(pos, direction).T.tolist()
    else:
        raise Unsupported(f"light {kind!r}")
    scene.collection.objects.link(obj)
