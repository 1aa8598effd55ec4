"""Write a Mitsuba 3 scene dict (as `niebla2mitsuba.convert` makes) as Mitsuba
3 XML text, which both Mitsuba (`mi.load_file`) and niebla read.

Mitsuba 3.9 has no dict-to-XML writer of its own. This one covers the dicts
the converter writes: plugin dicts (tag chosen from the plugin type), refs,
`rgb` values, numbers, booleans, strings, 3-vectors (`<point>` or
`<vector>`) and `ScalarTransform4f`s: written as the operations they were
made from when they remember them (`niebla2mitsuba.placement`: `<lookat>`,
`<scale>`, `<rotate>`, `<translate>`, `<matrix>`), else as one `<matrix>`.
Floats are written with Python's `repr` (the shortest text that reads back as
the same double), so no digits are lost on the way.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

TAGS = {
    "bsdf": {"diffuse", "dielectric", "conductor", "null", "roughconductor", "roughdielectric", "thindielectric",
             "plastic", "roughplastic", "twosided"},
    "shape": {"sphere", "cube", "rectangle", "disk", "obj", "ply"},
    "emitter": {"point", "spot", "directional", "constant", "envmap", "area"},
    "medium": {"homogeneous", "heterogeneous"},
    "phase": {"isotropic", "hg", "rayleigh", "blendphase", "tabphase"},
    "volume": {"gridvolume", "constvolume"},
    "sensor": {"perspective"},
    "film": {"hdrfilm"},
    "rfilter": {"box", "gaussian", "tent"},
    "sampler": {"independent", "stratified", "multijitter"},
    "integrator": {"volpath", "volpathmis", "path", "moment"},
    "texture": {"bitmap", "checkerboard"},
}
VECTORS = {"direction"}


def _tag(plugin_type: str) -> str:
    for tag, types in TAGS.items():
        if plugin_type in types:
            return tag
    raise ValueError(f"unknown plugin type {plugin_type!r}")


def _num(x) -> str:
    return repr(float(x))


def _matrix(t) -> str:
    import numpy as np

    m = np.array(t.matrix, dtype=float).reshape(4, 4)
    return " ".join(_num(v) for v in m.flatten())


def _ops(ops, indent: str) -> str:
    import numpy as np

    xyz = lambda v: ", ".join(_num(x) for x in v)
    out = []
    for op in ops:
        kind = op[0]
        if kind == "lookat":
            out.append(f'<lookat origin="{xyz(op[1])}" target="{xyz(op[2])}" up="{xyz(op[3])}"/>')
        elif kind in ("scale", "translate"):
            out.append(f'<{kind} value="{xyz(op[1])}"/>')
        elif kind == "rotate":
            a = op[1]
            out.append(f'<rotate x="{_num(a[0])}" y="{_num(a[1])}" z="{_num(a[2])}" angle="{_num(op[2])}"/>')
        elif kind == "matrix":
            out.append(f'<matrix value="{" ".join(_num(x) for x in np.asarray(op[1], dtype=float).flatten())}"/>')
        else:
            raise ValueError(f"unknown transform operation {kind!r}")
    return "".join(f"{indent}  {o}\n" for o in out)


def _value(name: str, v, indent: str) -> str:
    n = quoteattr(name)
    if isinstance(v, bool):
        return f'{indent}<boolean name={n} value="{str(v).lower()}"/>\n'
    if isinstance(v, int):
        return f'{indent}<integer name={n} value="{v}"/>\n'
    if isinstance(v, float):
        return f'{indent}<float name={n} value="{_num(v)}"/>\n'
    if isinstance(v, str):
        return f"{indent}<string name={n} value={quoteattr(v)}/>\n"
    if isinstance(v, (list, tuple)) and len(v) == 3:
        tag = "vector" if name in VECTORS else "point"
        return f'{indent}<{tag} name={n} value="{", ".join(_num(x) for x in v)}"/>\n'
    if isinstance(v, dict):
        if v.get("type") == "ref":
            return f"{indent}<ref name={n} id={quoteattr(v['id'])}/>\n"
        if v.get("type") == "rgb":
            return f'{indent}<rgb name={n} value="{", ".join(_num(x) for x in v["value"])}"/>\n'
        return _plugin(v, indent, name)
    if getattr(v, "ops", None) is not None:
        return f"{indent}<transform name={n}>\n{_ops(v.ops, indent)}{indent}</transform>\n"
    if hasattr(v, "matrix"):
        return f'{indent}<transform name={n}>\n{indent}  <matrix value="{_matrix(v)}"/>\n{indent}</transform>\n'
    raise ValueError(f"{name}: cannot write {type(v).__name__} {v!r}")


def _plugin(d: dict, indent: str, name: str | None = None) -> str:
    tag = _tag(d["type"])
    attrs = f'type="{d["type"]}"'
    if "id" in d:
        attrs += f" id={quoteattr(d['id'])}"
    if name is not None and not name.startswith(("shape_", "light_", "medium_", "bsdf_")) and name not in TAGS:
        attrs += f" name={quoteattr(name)}"
    body = "".join(_value(k, v, indent + "  ") for k, v in d.items() if k not in ("type", "id"))
    return f"{indent}<{tag} {attrs}>\n{body}{indent}</{tag}>\n"


def dict_to_xml(scene: dict) -> str:
    """The XML text of a scene dict (`{"type": "scene", ...}`)."""
    assert scene["type"] == "scene"
    body = "".join(_value(k, v, "  ") for k, v in scene.items() if k != "type")
    return f'<?xml version="1.0" encoding="utf-8"?>\n<scene version="3.0.0">\n{body}</scene>\n'
