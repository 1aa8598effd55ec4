"""Convert a niebla scene file (JSON, version 1) into a Mitsuba 3 scene dict.

Only the subset the benchmark scenes use is supported, and anything else is
an error rather than a silent approximation:

- camera: `perspective` (position, target, up, fov_y, width, height) ->
  `perspective` with `fov_axis: 'y'`, `look_at`, an `hdrfilm` with a box
  reconstruction filter (niebla's pixel filter) and an `independent` sampler;
- integrator: niebla `volpath` with `max_depth` N (N scattering events, surface
  or medium) -> Mitsuba `volpath` or `volpathmis` with `max_depth` N + 1
  (Mitsuba counts path segments: 1 = directly visible emitters only);
- media: `homogeneous` -> `homogeneous`; `grid` with an `npy`/`vol`/`vdb`
  density -> `heterogeneous` whose `sigma_t` is a `gridvolume` read from the
  `.vol` file with the same voxels (the `.npy` or `.vdb` next to it, same
  stem, is what niebla reads; a VDB's `.vol` is written by
  `volumes.vdb_to_vol`, dense, with a border of zero voxels),
  trilinear, placed by an explicit `to_world` (Mitsuba ignores the bbox stored
  in a `.vol` unless `use_grid_bbox` is set). Coefficients are passed as
  `sigma_t` and `albedo` (Mitsuba's form). `has_spectral_extinction` is set
  from the data (false for gray media, as a Mitsuba user would);
- phase: `isotropic`, `hg` (same sign convention: g > 0 forward), an inline
  `tabulated` table at regularly spaced cosines -> `tabphase`;
- shapes: `box` -> `cube` (scaled [-1,1]^3), `sphere` (with a `rotation`:
  the unit sphere placed by scale, the rotation and translate), `rectangle` and
  `disk` (both renderers use [-1,1]^2, or the unit disk, in local xy with
  normal +z) with niebla's
  `to_world` (scale, rotate x, y, z, translate, or a matrix); bsdf `null` ->
  `null`, `diffuse` -> `diffuse`, its reflectance a color or a `bitmap` or
  `checkerboard` texture (see `texture`; not on a box, whose uvs differ from
  Mitsuba's cube); `roughconductor` (a Mitsuba `material` name or `eta`/`k`),
  `roughdielectric` and `twosided` (of `diffuse` and `roughconductor`) with
  the same names, their `alpha` or `alpha_u`/`alpha_v` numbers or textures
  (see `alpha_texture`; anisotropic only where the tangent frames agree:
  with `"tangent_frame": "dpdu"` on a sphere, rectangle or disk, else on a
  rectangle turned about x, see `_frames_agree`); `interior`/`exterior`
  media by reference;
- lights: `point`, `spot` (look_at from position to target), `directional`,
  `constant`: the same parameters, since niebla follows Mitsuba's radiometry;
  `area` lights (`rectangle`, `disk`, `sphere`, or a `mesh` from an OBJ or
  PLY file) as the shape with a black `diffuse` bsdf and an `area` emitter
  (see `area_light`; not `two_sided`, which Mitsuba's emitter lacks);
- the camera's medium: niebla finds it (innermost closed shape with an
  interior containing the camera, else `ambient_medium`); Mitsuba needs it on
  the sensor, so it is computed the same way here.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np


class Unsupported(ValueError):
    pass


def _color(v):
    if isinstance(v, (int, float)):
        return [float(v)] * 3
    if isinstance(v, list) and len(v) == 3:
        return [float(x) for x in v]
    raise Unsupported(f"not a color: {v!r}")


def _is_gray(c):
    return c[0] == c[1] == c[2]


def _spectrum(c):
    c = _color(c)
    if _is_gray(c):
        return c[0]
    return {"type": "rgb", "value": c}


def niebla_transform(t) -> np.ndarray:
    """niebla's `to_world`: scale, then rotate about x, y, z (degrees, world
    axes), then translate; or a row-major 4x4 `matrix`."""
    if t is None:
        return np.eye(4)
    if "matrix" in t:
        return np.array(t["matrix"], dtype=float)
    s = t.get("scale", 1.0)
    s = [s] * 3 if isinstance(s, (int, float)) else s
    m = np.diag([s[0], s[1], s[2], 1.0])

    def rot(axis, deg):
        a = math.radians(deg)
        c, sn = math.cos(a), math.sin(a)
        r = np.eye(4)
        i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -sn, sn, c
        return r

    for axis in ("x", "y", "z"):
        deg = t.get("rotate_" + axis, 0.0)
        if deg:
            m = rot(axis, deg) @ m
    tr = np.eye(4)
    tr[:3, 3] = t.get("translate", [0.0, 0.0, 0.0])
    return tr @ m


def placement(mi, ops):
    """A `mi.ScalarTransform4f` (a subclass of it) that also remembers the
    operations it was made from, so that bench/mitsuba_xml.py writes them as
    `<lookat>`, `<scale>`, `<rotate>`, `<translate>` and `<matrix>` elements
    with the numbers of the niebla scene as written: niebla's importer hands
    those numbers to niebla unchanged, which composes them in float32 exactly
    as from the JSON file. `ops`: ("lookat", origin, target, up), ("scale",
    [x, y, z]), ("rotate", axis, degrees), ("translate", [x, y, z]) or
    ("matrix", 4x4), applied first to last."""
    t = mi.ScalarTransform4f()
    for op in ops:
        kind, args = op[0], op[1:]
        if kind == "lookat":
            step = mi.ScalarTransform4f().look_at(origin=args[0], target=args[1], up=args[2])
        elif kind == "scale":
            step = mi.ScalarTransform4f().scale(args[0])
        elif kind == "rotate":
            step = mi.ScalarTransform4f().rotate(args[0], args[1])
        elif kind == "translate":
            step = mi.ScalarTransform4f().translate(args[0])
        elif kind == "matrix":
            step = mi.ScalarTransform4f(np.asarray(args[0], dtype=float).tolist())
        else:
            raise ValueError(kind)
        t = step @ t
    cls = _placement_class(mi)
    out = cls(t)
    out.ops = [tuple(op) for op in ops]
    return out


_PLACEMENT = {}


def _placement_class(mi):
    if "cls" not in _PLACEMENT:

        class Placement(mi.ScalarTransform4f):
            ops = None

        _PLACEMENT["cls"] = Placement
    return _PLACEMENT["cls"]


def niebla_transform_ops(t):
    """niebla's `to_world` object as placement operations (see `placement`)."""
    if t is None:
        return []
    if "matrix" in t:
        return [("matrix", np.array(t["matrix"], dtype=float))]
    ops = []
    if "scale" in t:
        s = t["scale"]
        ops.append(("scale", [float(s)] * 3 if isinstance(s, (int, float)) else [float(x) for x in s]))
    for axis, v in (("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0]), ("z", [0.0, 0.0, 1.0])):
        deg = t.get("rotate_" + axis, 0.0)
        if deg:
            ops.append(("rotate", v, float(deg)))
    if "translate" in t:
        ops.append(("translate", [float(x) for x in t["translate"]]))
    return ops


def _sphere_ops(s):
    """A sphere with a `rotation` (which turns its uvs and dp/du) as Mitsuba's
    unit sphere placed by scale (its radius), the rotation (about x, then y,
    then z, or its 3x3 matrix) and translate (its center). niebla's importer
    reads the angles back as written (niebla composes them in float32 as
    from the JSON file) and a matrix as the same float32 rows."""
    r, ops = float(s["radius"]), []
    rot = s["rotation"]
    if "matrix" in rot:
        # niebla's float32 radius and rows: the importer divides the f64
        # matrix by its scale (a few f64 rounding steps), which rounds back
        # to exactly these float32 values.
        r = float(np.float32(r))
        ops.append(("scale", [r, r, r]))
        m = np.eye(4)
        m[:3, :3] = np.array(rot["matrix"], dtype=np.float32).astype(float)
        ops.append(("matrix", m))
    else:
        ops.append(("scale", [r, r, r]))
        for axis, v in (("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0]), ("z", [0.0, 0.0, 1.0])):
            deg = rot.get("rotate_" + axis, 0.0)
            if deg:
                ops.append(("rotate", v, float(deg)))
    ops.append(("translate", [float(x) for x in s["center"]]))
    return ops


def _box_matrix(bmin, bmax):
    bmin, bmax = np.array(bmin, float), np.array(bmax, float)
    m = np.diag([*((bmax - bmin) / 2), 1.0])
    m[:3, 3] = (bmax + bmin) / 2
    return m


def _unit_box_matrix(bmin, bmax):
    """Maps [0,1]^3 onto the box (a gridvolume's local space)."""
    bmin, bmax = np.array(bmin, float), np.array(bmax, float)
    m = np.diag([*(bmax - bmin), 1.0])
    m[:3, 3] = bmin
    return m


def _phase(p):
    p = p or {"type": "isotropic"}
    if p["type"] == "isotropic":
        return {"type": "isotropic"}
    if p["type"] == "hg":
        return {"type": "hg", "g": float(p["g"])}
    if p["type"] == "tabulated" and "mu" in p:
        # Mitsuba's tabphase takes values at cosines regularly spaced from -1 to 1.
        mu, values = np.asarray(p["mu"], float), p["p"]
        if np.allclose(mu, np.linspace(-1.0, 1.0, len(mu)), rtol=0.0, atol=1e-12):
            return {"type": "tabphase", "values": ", ".join(repr(float(v)) for v in values)}
        raise Unsupported("tabulated phase function with irregular cosines (Mitsuba's tabphase is regular)")
    raise Unsupported(f"phase function {p['type']!r}")


def niebla_coefficients(m):
    """(sigma_a, sigma_s) as niebla computes them from the medium's JSON, in
    float32 and in its order of operations (sigma_s = sigma_t * albedo,
    sigma_a = sigma_t - sigma_s, then each times `scale`), as float32 arrays."""
    f = lambda v: np.array(_color(v), dtype=np.float32)
    scale = np.float32(m.get("scale", 1.0))
    if "sigma_t" in m:
        st, al = f(m["sigma_t"]), f(m.get("albedo", 1.0))
        ss = st * al
        sa = st - ss
    else:
        sa, ss = f(m["sigma_a"]), f(m["sigma_s"])
    return sa * scale, ss * scale


def _coefficients(m):
    """(sigma_t, albedo) as RGB lists of floats, `scale` applied: sigma_t =
    sigma_a + sigma_s and albedo = sigma_s / sigma_t of niebla's own float32
    coefficients, in float64. niebla's importer computes sigma_s = sigma_t *
    albedo and sigma_a = sigma_t - sigma_s in float64 and rounds them to
    float32, which gives back exactly these float32 values (the float64
    errors are ~1e-16 relative, far below a float32 step)."""
    sa, ss = niebla_coefficients(m)
    st = [float(a) + float(s) for a, s in zip(sa, ss)]
    al = [float(s) / t if t > 0 else 0.0 for s, t in zip(ss, st)]
    return st, al


def _medium(mi, name, m, scene_dir):
    kind = m.get("type", "grid" if "density" in m else "homogeneous")
    if kind not in ("homogeneous", "grid"):
        raise Unsupported(f"media.{name}: type {kind!r}")
    if m.get("emission"):
        raise Unsupported(f"media.{name}: emission")
    st, al = _coefficients(m)
    out = {
        "phase": _phase(m.get("phase")),
        "albedo": _spectrum(al),
        "has_spectral_extinction": not _is_gray(st),
    }
    if kind == "homogeneous":
        # Mitsuba reads an `rgb` value as a reflectance in [0, 1]: pass the
        # extinction's color normalized to a maximum of 1 and its maximum as
        # `scale` (which multiplies sigma_t only).
        # A gray extinction is a plain float (no normalization, no scale).
        if _is_gray(st):
            out.update(type="homogeneous", sigma_t=st[0])
            return out
        top = max(st)
        out.update(type="homogeneous", sigma_t=_spectrum([x / top for x in st]), scale=top)
        return out
    if kind != "grid":
        raise Unsupported(f"media.{name}: type {kind!r}")
    if m.get("to_world"):
        raise Unsupported(f"media.{name}: to_world on a grid medium")
    if m.get("albedo_grid"):
        raise Unsupported(f"media.{name}: albedo_grid (not converted yet)")
    d = m["density"]
    if d["type"] == "npy":
        # The .vol with the same stem holds the same voxels (volumes.py writes both).
        vol = os.path.splitext(os.path.join(scene_dir, d["file"]))[0] + ".vol"
        bounds = d["bounds"]
    elif d["type"] == "vol":
        vol = os.path.join(scene_dir, d["file"])
        bounds = None
    elif d["type"] == "vdb":
        # Mitsuba reads no VDB: the .vol with the same stem holds the same
        # voxels, densely, with a border of zero voxels (volumes.vdb_to_vol).
        if d.get("grid", "density") != "density":
            raise Unsupported(f"media.{name}: VDB grid {d.get('grid')!r} (vdb_to_vol converts 'density')")
        src = os.path.join(scene_dir, d["file"])
        vol = os.path.splitext(src)[0] + ".vol"
        if os.path.exists(vol) and os.path.exists(src) and os.path.getmtime(vol) < os.path.getmtime(src):
            raise Unsupported(f"media.{name}: {vol} is older than {src} (rerun volumes.vdb_to_vol)")
        bounds = None
    else:
        raise Unsupported(f"media.{name}: density type {d['type']!r}")
    if not os.path.exists(vol):
        raise Unsupported(f"media.{name}: {vol} missing (run bench/volumes.py, or volumes.vdb_to_vol for a VDB)")
    from volumes import read_vol

    grid, bmin, bmax = read_vol(vol)
    if bounds is not None:
        assert np.allclose(bmin, bounds["min"]) and np.allclose(bmax, bounds["max"]), (vol, bounds)
        npy = os.path.join(scene_dir, d["file"])
        if os.path.exists(npy):
            assert np.array_equal(np.load(npy), grid), f"{npy} and {vol} differ"
    # sigma_t(p) = sigma_t * density(p): the density grid times a constant
    # (scale) when gray; Mitsuba's `scale` multiplies sigma_t.
    if _is_gray(st):
        sigma_t = {
            "type": "gridvolume",
            "filename": vol,
            "filter_type": "trilinear",
            "to_world": placement(mi, [("matrix", _unit_box_matrix(bmin, bmax))]),
        }
        out.update(type="heterogeneous", sigma_t=sigma_t, scale=st[0])
        return out
    raise Unsupported(f"media.{name}: chromatic sigma_t with a grid density")


def niebla_uv_map(t) -> np.ndarray:
    """The 2x3 float32 uv map niebla builds from a texture's JSON: `scale`
    after `to_uv` (rows `[[a, b, c], [d, e, f]]`), in niebla's float32 order
    of operations (`UvMap::after`)."""
    f32 = np.float32
    su, sv = (f32(x) for x in t.get("scale", [1.0, 1.0] if t["type"] == "bitmap" else [2.0, 2.0]))
    if t.get("to_uv") is None:
        return np.array([[su, 0, 0], [0, sv, 0]], dtype=np.float32)
    b = np.array(t["to_uv"], dtype=np.float32)
    a = np.array([[su, 0, 0], [0, sv, 0]], dtype=np.float32)
    out = np.zeros((2, 3), dtype=np.float32)
    for r in range(2):
        out[r, 0] = a[r, 0] * b[0, 0] + a[r, 1] * b[1, 0]
        out[r, 1] = a[r, 0] * b[0, 1] + a[r, 1] * b[1, 1]
        out[r, 2] = a[r, 0] * b[0, 2] + a[r, 1] * b[1, 2] + a[r, 2]
    return out


def _to_uv(mi, rows):
    """A Mitsuba `to_uv` (4x4; the bitmap and checkerboard use rows and
    columns 0, 1 and 3) from 2x3 float64 rows."""
    m = np.eye(4)
    m[0, [0, 1, 3]] = rows[0]
    m[1, [0, 1, 3]] = rows[1]
    return placement(mi, [("matrix", m)])


def texture(mi, t, scene_dir, field):
    """A niebla texture object (`bitmap` or `checkerboard`) as a Mitsuba
    `<texture>` that niebla's importer reads back as the same float32 uv map.

    niebla's uv map N is `scale` after `to_uv` (float32). The importer gives
    a bitmap the map `v -> 1 - v` after Mitsuba's `to_uv` (Mitsuba's `v = 0`
    is the image's top row, niebla's the bottom) and scale 1, so the bitmap's
    Mitsuba `to_uv` is N followed by `v -> 1 - v`: rows `N0` and `-N1` with
    `1 - N1[2]` (float64, from which the importer's `1 - (1 - c)` gives back
    the float32 `c`). The importer gives a checkerboard scale 2 after
    Mitsuba's `to_uv` (Mitsuba's cells are half a unit), so its `to_uv` is
    N / 2 (exact in float32)."""
    kind = t.get("type")
    n = niebla_uv_map(t)
    if kind == "bitmap":
        path = os.path.join(scene_dir, t["file"])
        c = float(n[1, 2])
        flipped = 1.0 - c
        if 1.0 - flipped != c:
            raise Unsupported(f"{field}.to_uv: v offset {c!r} does not survive the v flip exactly")
        rows = [[float(n[0, 0]), float(n[0, 1]), float(n[0, 2])], [-float(n[1, 0]), -float(n[1, 1]), flipped]]
        out = {"type": "bitmap", "filename": path, "filter_type": t.get("filter", "bilinear"),
               "wrap_mode": t.get("wrap", "repeat"), "raw": bool(t.get("raw", False))}
        if rows != [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]:
            # (Mitsuba's default, the identity, is left out: N is then the flip.)
            out["to_uv"] = _to_uv(mi, rows)
        return out
    if kind == "checkerboard":
        out = {"type": "checkerboard", "color0": {"type": "rgb", "value": _color(t.get("color0", 0.4))},
               "color1": {"type": "rgb", "value": _color(t.get("color1", 0.2))}}
        half = n / np.float32(2.0)
        if not np.array_equal(half * np.float32(2.0), n):
            raise Unsupported(f"{field}: uv map {n.tolist()} is not exactly twice a float32 map")
        if not np.array_equal(n, np.array([[2, 0, 0], [0, 2, 0]], dtype=np.float32)):
            out["to_uv"] = _to_uv(mi, [[float(x) for x in half[0]], [float(x) for x in half[1]]])
        return out
    raise Unsupported(f"{field}: texture type {kind!r}")


def alpha_texture(mi, t, scene_dir, field):
    """A niebla roughness texture as a Mitsuba `<texture>` whose `eval_1`
    (what Mitsuba's microfacet models read) is niebla's scalar at every uv.
    Mitsuba's checkerboard `eval_1` gives color1 where its `eval` gives
    color0 (Mitsuba 3.9.1; niebla's importer swaps them on the way in), so a
    checkerboard's colors are swapped here."""
    out = texture(mi, t, scene_dir, field)
    if out["type"] == "checkerboard":
        out["color0"], out["color1"] = out["color1"], out["color0"]
    return out


def _mitsuba_conductors():
    """Mitsuba 3's conductor names, as niebla lists them
    (crates/niebla/src/bsdf/mitsuba_conductors.rs)."""
    import re

    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                        "crates", "niebla", "src", "bsdf", "mitsuba_conductors.rs")
    with open(path) as f:
        return set(re.findall(r'preset\("([^"]+)"', f.read()))


def _frames_agree(shape):
    """Whether niebla's tangent frame of anisotropic roughness is Mitsuba's
    (`dp/du` made orthogonal to the normal) on `shape`. With
    `"tangent_frame": "dpdu"` niebla uses its shapes' `dp/du`, which is
    Mitsuba's on a sphere, rectangle and disk (the same uv
    parameterizations), not on a box (written as a `cube`, whose uv layout
    differs). With the default `"normal"` frame (built from the normal alone)
    the two agree only on a rectangle placed by `scale`, `rotate_x` and
    `translate` (its `dp/du` stays along +x, and niebla's frame of a normal
    in the y-z plane has x = +x too)."""
    if shape.get("tangent_frame", "normal") == "dpdu":
        return shape["type"] in ("sphere", "rectangle", "disk")
    t = shape.get("to_world") or {}
    return shape["type"] == "rectangle" and set(t) <= {"scale", "rotate_x", "translate"}


def _microfacet(mi, b, scene_dir, field, out, shape):
    """`distribution` and `alpha` or `alpha_u`/`alpha_v` (numbers or textures).
    Anisotropic roughness only where the two renderers' tangent frames agree."""
    out["distribution"] = b.get("distribution", "beckmann").lower()
    keys = ["alpha_u", "alpha_v"] if "alpha_u" in b or "alpha_v" in b else ["alpha"]
    if keys != ["alpha"] and b.get("alpha_u") != b.get("alpha_v") and not _frames_agree(shape):
        raise Unsupported(f"{field}: anisotropic roughness on a {shape['type']} with tangent_frame "
                          f"\"{shape.get('tangent_frame', 'normal')}\" (niebla's tangent frame is Mitsuba's with "
                          "\"dpdu\" on a sphere, rectangle or disk, and with \"normal\" only on a rectangle turned "
                          "about x)")
    for k in keys:
        v = b.get(k, 0.1)
        out[k] = alpha_texture(mi, v, scene_dir, f"{field}.{k}") if isinstance(v, dict) else float(v)


def _has_texture(v):
    """True when a bsdf object (or anything in it) is or holds a texture."""
    if isinstance(v, dict):
        return v.get("type") in ("bitmap", "checkerboard") or any(_has_texture(x) for x in v.values())
    if isinstance(v, list):
        return any(_has_texture(x) for x in v)
    return False


def bsdf(mi, b, scene_dir, field, shape, nested=False):
    """A niebla bsdf object as a Mitsuba bsdf dict (see the module doc)."""
    kind = b["type"]
    if _has_texture(b) and shape["type"] == "box":
        # niebla's box uv (per face) is not Mitsuba's cube mesh's.
        raise Unsupported(f"{field}: a textured box (Mitsuba's cube has other uvs)")
    if kind == "null" and not nested:
        return {"type": "null"}
    if kind == "diffuse":
        r = b.get("reflectance", 0.5)
        if isinstance(r, dict):
            return {"type": "diffuse", "reflectance": texture(mi, r, scene_dir, f"{field}.reflectance")}
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": _color(r)}}
    if kind == "roughconductor":
        out = {"type": "roughconductor"}
        _microfacet(mi, b, scene_dir, field, out, shape)
        if "material" in b:
            if b["material"] not in _mitsuba_conductors():
                raise Unsupported(f"{field}.material: {b['material']!r} is not one of Mitsuba's names")
            out["material"] = b["material"]
        elif "eta" in b or "k" in b:
            out["eta"] = {"type": "rgb", "value": _color(b["eta"])}
            out["k"] = {"type": "rgb", "value": _color(b["k"])}
        elif "reflectance" in b:
            raise Unsupported(f"{field}.reflectance (niebla's conductor from a reflectance)")
        r = b.get("specular_reflectance", 1.0)
        if isinstance(r, dict):
            out["specular_reflectance"] = texture(mi, r, scene_dir, f"{field}.specular_reflectance")
        elif _color(r) != [1.0] * 3:
            out["specular_reflectance"] = {"type": "rgb", "value": _color(r)}
        return out
    if kind == "roughdielectric" and not nested:
        out = {"type": "roughdielectric"}
        _microfacet(mi, b, scene_dir, field, out, shape)
        for k in ("int_ior", "ext_ior"):
            if k in b:
                out[k] = float(b[k])
        for k in ("specular_reflectance", "specular_transmittance"):
            if k in b and _color(b[k]) != [1.0] * 3:
                out[k] = {"type": "rgb", "value": _color(b[k])}
        return out
    if kind == "twosided" and not nested:
        sides = b["bsdf"] if isinstance(b["bsdf"], list) else [b["bsdf"]]
        out = {"type": "twosided"}
        for j, side in enumerate(sides):
            where = f"{field}.bsdf[{j}]" if len(sides) == 2 else f"{field}.bsdf"
            out[f"bsdf_{j}"] = bsdf(mi, side, scene_dir, where, shape, nested=True)
        return out
    raise Unsupported(f"{field}: bsdf {kind!r}")


def _mesh_has_normals(path):
    """Whether an OBJ (`vn` lines) or PLY (an `nx` vertex property) file
    holds vertex normals."""
    with open(path, "rb") as f:
        if path.lower().endswith(".ply"):
            header = b""
            for line in f:
                header += line
                if line.strip() == b"end_header":
                    break
            return b" nx" in header
        return any(line.startswith(b"vn ") for line in f)


def _mesh_light_shape(mi, s, scene_dir, field):
    """A niebla mesh (from an `.obj` or `.ply` file) as Mitsuba's `obj` or
    `ply` shape that niebla's importer reads back as the same mesh: the file,
    `to_world`, `flip_normals` and `face_normals`. The importer gives a mesh
    without `face_normals` Mitsuba's computed vertex normals
    (`compute_normals`), so a niebla mesh without them is converted only when
    its file has vertex normals of its own (where the key changes nothing)."""
    if s.get("file") is None:
        raise Unsupported(f"{field}: an inline mesh (Mitsuba's XML reads meshes from files)")
    for k in ("object", "uvs", "allow_open", "motion"):
        if s.get(k):
            raise Unsupported(f"{field}.{k} on an emitting mesh")
    path = os.path.join(scene_dir, s["file"])
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".obj", ".ply"):
        raise Unsupported(f"{field}.file: {s['file']!r} is neither .obj nor .ply")
    face_normals = bool(s.get("face_normals", False))
    if not face_normals and not s.get("compute_normals", False) and not _mesh_has_normals(path):
        raise Unsupported(f"{field}: a mesh without vertex normals and without \"compute_normals\": true "
                          "(Mitsuba computes vertex normals for it)")
    d = {"type": ext[1:], "filename": path}
    if s.get("to_world"):
        d["to_world"] = placement(mi, niebla_transform_ops(s["to_world"]))
    if s.get("flip_normals"):
        d["flip_normals"] = True
    if face_normals:
        d["face_normals"] = True
    return d


def area_light(mi, l, scene_dir, field):
    """A niebla `area` light as a Mitsuba shape holding an `area` emitter
    with the same `radiance` (both renderers emit from the shape's front:
    a rectangle's or disk's local +z side, a sphere's outside, a mesh's
    shading-normal side). The shape's bsdf is black `diffuse`, the surface
    of niebla's lights (which absorb what reaches them). A sphere's
    `rotation` is left out (it has no effect on a light). `two_sided` has
    no Mitsuba counterpart (its area emitter emits from the front only)."""
    if l.get("two_sided"):
        raise Unsupported(f"{field}.two_sided (Mitsuba's area emitter emits from the front only)")
    s = l["shape"]
    t = s["type"]
    if s.get("motion"):
        raise Unsupported(f"{field}.shape.motion")
    if t == "sphere":
        d = {"type": "sphere", "center": [float(x) for x in s["center"]], "radius": float(s["radius"])}
    elif t in ("rectangle", "disk"):
        d = {"type": t}
        if s.get("to_world"):
            d["to_world"] = placement(mi, niebla_transform_ops(s["to_world"]))
    elif t == "mesh":
        d = _mesh_light_shape(mi, s, scene_dir, f"{field}.shape")
    else:
        raise Unsupported(f"{field}.shape: type {t!r}")
    d["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    d["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": _color(l["radiance"])}}
    return d


def _inside(shape, p):
    t = shape["type"]
    if t == "box":
        return all(lo < x < hi for lo, x, hi in zip(shape["min"], p, shape["max"]))
    if t == "sphere":
        return float(np.linalg.norm(np.subtract(p, shape["center"]))) < shape["radius"]
    return False


def _volume_of(shape):
    if shape["type"] == "box":
        return float(np.prod(np.subtract(shape["max"], shape["min"])))
    return 4 / 3 * math.pi * shape["radius"] ** 3


def camera_medium(desc):
    """niebla's rule: innermost closed shape with an interior containing the
    camera, else the ambient medium, else vacuum."""
    pos = desc["camera"]["position"]
    best = None
    for s in desc.get("shapes", []):
        if s.get("interior") and _inside(s, pos):
            if best is None or _volume_of(s) < _volume_of(best):
                best = s
    if best is not None:
        return best["interior"]
    return desc.get("ambient_medium")


def convert(desc: dict, scene_dir: str, spp: int = 16, integrator: str = "auto", seed: int = 0) -> dict:
    """The Mitsuba 3 scene dict of niebla scene `desc` (already parsed JSON).
    `integrator`: 'volpath', 'volpathmis' or 'auto' (volpathmis when a medium
    has a chromatic extinction, where Mitsuba's docs recommend it)."""
    import mitsuba as mi

    if desc.get("version") != 1:
        raise Unsupported("scene version must be 1")
    if desc.get("ambient_medium"):
        # Mitsuba has no medium filling the world; a camera medium alone
        # would not fill rays that leave and re-enter.
        raise Unsupported("ambient_medium (put the medium in a box instead)")
    out = {"type": "scene"}

    media = {}
    for name, m in desc.get("media", {}).items():
        media[name] = _medium(mi, name, m, scene_dir)
        out["medium_" + name] = dict(media[name], id="medium_" + name)

    def ref(name):
        return {"type": "ref", "id": "medium_" + name}

    r = desc.get("render", {})
    integ = r.get("integrator", {"type": "single"})
    if integ.get("type") != "volpath":
        raise Unsupported(f"integrator {integ.get('type')!r}: only volpath has a Mitsuba counterpart")
    max_depth = int(integ.get("max_depth", 1024))
    if integrator == "auto":
        chromatic = any(m["has_spectral_extinction"] for m in media.values())
        integrator = "volpathmis" if chromatic else "volpath"
    out["integrator"] = {"type": integrator, "max_depth": max_depth + 1}

    cam = desc["camera"]
    if cam.get("type", "perspective") != "perspective":
        raise Unsupported("camera type")
    sensor = {
        "type": "perspective",
        "fov": float(cam.get("fov_y", 40.0)),
        "fov_axis": "y",
        "to_world": placement(mi, [("lookat", cam["position"], cam["target"], cam.get("up", [0, 1, 0]))]),
        "film": {
            "type": "hdrfilm",
            "width": int(cam["width"]),
            "height": int(cam["height"]),
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
        "sampler": {"type": "independent", "sample_count": int(spp), "seed": int(seed)},
    }
    cm = camera_medium(desc)
    if cm:
        sensor["medium"] = ref(cm)
    out["sensor"] = sensor

    for i, s in enumerate(desc.get("shapes", [])):
        t = s["type"]
        if t == "box":
            d = {"type": "cube", "to_world": placement(mi, [("matrix", _box_matrix(s["min"], s["max"]))])}
        elif t == "sphere":
            d = {"type": "sphere", "center": s["center"], "radius": float(s["radius"])}
            if s.get("rotation"):
                d = {"type": "sphere", "to_world": placement(mi, _sphere_ops(s))}
        elif t in ("rectangle", "disk"):
            d = {"type": t, "to_world": placement(mi, niebla_transform_ops(s.get("to_world")))}
        else:
            raise Unsupported(f"shapes[{i}]: type {t!r}")
        d["bsdf"] = bsdf(mi, s.get("bsdf", {"type": "null"}), scene_dir, f"shapes[{i}].bsdf", s)
        if s.get("interior"):
            d["interior"] = ref(s["interior"])
        if s.get("exterior"):
            d["exterior"] = ref(s["exterior"])
        out[f"shape_{i}"] = d

    for i, l in enumerate(desc.get("lights", [])):
        t = l["type"]
        if t == "point":
            d = {"type": "point", "position": l["position"], "intensity": {"type": "rgb", "value": _color(l["intensity"])}}
        elif t == "spot":
            pos = np.array(l["position"], float)
            target = np.array(l["target"], float) if "target" in l else pos + np.array(l["direction"], float)
            # niebla's numbers as written when it names a target.
            lookat_target = l["target"] if "target" in l else target.tolist()
            axis = target - pos
            up = np.array([0.0, 1.0, 0.0]) if abs(axis[1]) < 0.9 * np.linalg.norm(axis) else np.array([1.0, 0.0, 0.0])
            cutoff = float(l.get("cutoff_angle", 20.0))
            d = {
                "type": "spot",
                "to_world": placement(mi, [("lookat", l["position"], lookat_target, up.tolist())]),
                "intensity": {"type": "rgb", "value": _color(l["intensity"])},
                "cutoff_angle": cutoff,
                "beam_width": float(l.get("beam_width", 0.75 * cutoff)),
            }
        elif t == "directional":
            d = {"type": "directional", "direction": l["direction"], "irradiance": {"type": "rgb", "value": _color(l["irradiance"])}}
        elif t == "constant":
            d = {"type": "constant", "radiance": {"type": "rgb", "value": _color(l["radiance"])}}
        elif t == "area":
            d = area_light(mi, l, scene_dir, f"lights[{i}]")
        else:
            raise Unsupported(f"lights[{i}]: type {t!r}")
        out[f"light_{i}"] = d
    return out


def load(path: str, **kw) -> dict:
    with open(path) as f:
        desc = json.load(f)
    return convert(desc, os.path.dirname(os.path.abspath(path)), **kw)
