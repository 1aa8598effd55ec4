//! The bench converter's Mitsuba XML (bench/niebla2mitsuba.py and
//! bench/mitsuba_xml.py) read back by niebla's importer renders
//! bit-identically to the niebla scene it was made from.
//!
//! `SCENE_XML` is the converter's output for `SCENE_JSON` (only the path of
//! the grid file made relative): camera and spot as `<lookat>`, a rectangle
//! as `<scale>`, `<rotate>`, `<translate>`, boxes as cube matrices, and
//! media as sigma_t = sigma_a + sigma_s and albedo = sigma_s / sigma_t of
//! niebla's own f32 coefficients (a gray sigma_a/sigma_s medium, a chromatic
//! sigma_t/albedo one, and a gridvolume with its `.vol` file, written here).
//! Both are rendered with the same seed, sample count and sampler (each of
//! independent and Sobol); every pixel must be equal to the last bit, since
//! one flipped random decision would show. bench/roundtrip.py does the same
//! for every bench scene, with the converter run live.

use std::path::{Path, PathBuf};

use niebla::render::{render, RenderOptions};
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, read_scene_source, GeometryDesc, LightDesc, ShadingBacksideDesc};

const SCENE_JSON: &str = r#"{
 "version": 1,
 "camera": {
  "type": "perspective",
  "position": [
   0.3,
   1.3,
   4.6
  ],
  "target": [
   0.0,
   0.7,
   0.0
  ],
  "up": [
   0,
   1,
   0
  ],
  "fov_y": 38,
  "width": 16,
  "height": 12
 },
 "media": {
  "fog": {
   "type": "homogeneous",
   "sigma_a": 0.03,
   "sigma_s": 0.7,
   "phase": {
    "type": "hg",
    "g": 0.3
   }
  },
  "milk": {
   "type": "homogeneous",
   "sigma_t": [
    2.1,
    3.7,
    5.7
   ],
   "albedo": [
    0.99,
    0.97,
    0.93
   ],
   "phase": {
    "type": "isotropic"
   }
  },
  "smoke": {
   "type": "grid",
   "density": {
    "type": "vol",
    "file": "g.vol"
   },
   "sigma_t": 12,
   "albedo": 0.9,
   "phase": {
    "type": "hg",
    "g": 0.35
   }
  }
 },
 "shapes": [
  {
   "type": "box",
   "min": [
    -1.6,
    0.0,
    -1.1
   ],
   "max": [
    -0.1,
    1.3,
    0.9
   ],
   "interior": "fog",
   "bsdf": {
    "type": "null"
   }
  },
  {
   "type": "box",
   "min": [
    0.2,
    0.0,
    -0.5
   ],
   "max": [
    1.1,
    1.0,
    0.4
   ],
   "interior": "smoke",
   "bsdf": {
    "type": "null"
   }
  },
  {
   "type": "rectangle",
   "to_world": {
    "scale": 3,
    "rotate_x": -90,
    "rotate_y": 15,
    "translate": [
     0,
     -0.01,
     0
    ]
   },
   "bsdf": {
    "type": "diffuse",
    "reflectance": [
     0.5,
     0.45,
     0.4
    ]
   }
  },
  {
   "type": "sphere",
   "center": [
    -0.7,
    0.35,
    0.1
   ],
   "radius": 0.35,
   "bsdf": {
    "type": "diffuse",
    "reflectance": 0.7
   }
  },
  {
   "type": "sphere",
   "center": [
    0.35,
    0.3,
    1.3
   ],
   "radius": 0.3,
   "interior": "milk",
   "bsdf": {
    "type": "null"
   }
  }
 ],
 "lights": [
  {
   "type": "spot",
   "position": [
    0.4,
    3.3,
    0.8
   ],
   "target": [
    0.1,
    0.0,
    -0.1
   ],
   "intensity": [
    40,
    36,
    30
   ],
   "cutoff_angle": 30,
   "beam_width": 22
  },
  {
   "type": "point",
   "position": [
    -1.0,
    1.1,
    1.3
   ],
   "intensity": [
    2.0,
    2.2,
    2.6
   ]
  },
  {
   "type": "directional",
   "direction": [
    -0.3,
    -0.9,
    -0.2
   ],
   "irradiance": 0.6
  },
  {
   "type": "constant",
   "radiance": [
    0.05,
    0.06,
    0.08
   ]
  }
 ],
 "render": {
  "spp": 4,
  "integrator": {
   "type": "volpath",
   "max_depth": 16
  }
 }
}"#;

const SCENE_XML: &str = r#"<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
  <medium type="homogeneous" id="medium_fog">
    <phase type="hg">
      <float name="g" value="0.3"/>
    </phase>
    <float name="albedo" value="0.9589041097987591"/>
    <boolean name="has_spectral_extinction" value="false"/>
    <float name="sigma_t" value="0.7299999874085188"/>
  </medium>
  <medium type="homogeneous" id="medium_milk">
    <phase type="isotropic">
    </phase>
    <rgb name="albedo" value="0.9900000431424115, 0.9700000483280897, 0.9299999682108551"/>
    <boolean name="has_spectral_extinction" value="true"/>
    <rgb name="sigma_t" value="0.3684210482286503, 0.649122837104223, 1.0"/>
    <float name="scale" value="5.699999809265137"/>
  </medium>
  <medium type="heterogeneous" id="medium_smoke">
    <phase type="hg">
      <float name="g" value="0.35"/>
    </phase>
    <float name="albedo" value="0.8999999364217123"/>
    <boolean name="has_spectral_extinction" value="false"/>
    <volume type="gridvolume" name="sigma_t">
      <string name="filename" value="g.vol"/>
      <string name="filter_type" value="trilinear"/>
      <transform name="to_world">
        <matrix value="0.9000000208616257 0.0 0.0 0.20000000298023224 0.0 1.0 0.0 0.0 0.0 0.0 0.9000000059604645 -0.5 0.0 0.0 0.0 1.0"/>
      </transform>
    </volume>
    <float name="scale" value="12.0"/>
  </medium>
  <integrator type="volpathmis">
    <integer name="max_depth" value="17"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="38.0"/>
    <string name="fov_axis" value="y"/>
    <transform name="to_world">
      <lookat origin="0.3, 1.3, 4.6" target="0.0, 0.7, 0.0" up="0.0, 1.0, 0.0"/>
    </transform>
    <film type="hdrfilm">
      <integer name="width" value="16"/>
      <integer name="height" value="12"/>
      <rfilter type="box">
      </rfilter>
    </film>
    <sampler type="independent">
      <integer name="sample_count" value="4"/>
      <integer name="seed" value="0"/>
    </sampler>
  </sensor>
  <shape type="cube">
    <transform name="to_world">
      <matrix value="0.75 0.0 0.0 -0.8500000000000001 0.0 0.65 0.0 0.65 0.0 0.0 1.0 -0.10000000000000003 0.0 0.0 0.0 1.0"/>
    </transform>
    <bsdf type="null">
    </bsdf>
    <ref name="interior" id="medium_fog"/>
  </shape>
  <shape type="cube">
    <transform name="to_world">
      <matrix value="0.45000000000000007 0.0 0.0 0.65 0.0 0.5 0.0 0.5 0.0 0.0 0.45 -0.04999999999999999 0.0 0.0 0.0 1.0"/>
    </transform>
    <bsdf type="null">
    </bsdf>
    <ref name="interior" id="medium_smoke"/>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="3.0, 3.0, 3.0"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-90.0"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="15.0"/>
      <translate value="0.0, -0.01, 0.0"/>
    </transform>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.5, 0.45, 0.4"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" value="-0.7, 0.35, 0.1"/>
    <float name="radius" value="0.35"/>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.7, 0.7, 0.7"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" value="0.35, 0.3, 1.3"/>
    <float name="radius" value="0.3"/>
    <bsdf type="null">
    </bsdf>
    <ref name="interior" id="medium_milk"/>
  </shape>
  <emitter type="spot">
    <transform name="to_world">
      <lookat origin="0.4, 3.3, 0.8" target="0.1, 0.0, -0.1" up="1.0, 0.0, 0.0"/>
    </transform>
    <rgb name="intensity" value="40.0, 36.0, 30.0"/>
    <float name="cutoff_angle" value="30.0"/>
    <float name="beam_width" value="22.0"/>
  </emitter>
  <emitter type="point">
    <point name="position" value="-1.0, 1.1, 1.3"/>
    <rgb name="intensity" value="2.0, 2.2, 2.6"/>
  </emitter>
  <emitter type="directional">
    <vector name="direction" value="-0.3, -0.9, -0.2"/>
    <rgb name="irradiance" value="0.6, 0.6, 0.6"/>
  </emitter>
  <emitter type="constant">
    <rgb name="radiance" value="0.05, 0.06, 0.08"/>
  </emitter>
</scene>
"#;

/// A textured scene: `bitmap` textures (sRGB bilinear repeat with `scale`
/// and `to_uv`; raw nearest mirror; clamp) on rectangles and a disk, and
/// `checkerboard`s (with and without `scale`/`to_uv`) on spheres, in fog.
const TEXTURED_JSON: &str = r#"{
 "version": 1,
 "camera": {"type": "perspective", "position": [0.2, 1.4, 4.2], "target": [0.0, 0.5, 0.0], "up": [0, 1, 0],
            "fov_y": 40, "width": 16, "height": 12},
 "media": {
  "fog": {"type": "homogeneous", "sigma_a": 0.02, "sigma_s": 0.3, "phase": {"type": "hg", "g": 0.4}}
 },
 "shapes": [
  {"type": "box", "min": [-2.0, -0.1, -2.0], "max": [2.0, 2.0, 1.5], "interior": "fog", "bsdf": {"type": "null"}},
  {"type": "rectangle", "to_world": {"scale": 1.8, "rotate_x": -90, "translate": [0, 0, 0]},
   "bsdf": {"type": "diffuse", "reflectance": {"type": "bitmap", "file": "tex_srgb.png", "scale": [3, 2],
            "to_uv": [[0.8, 0.3, 0.1], [-0.2, 0.9, 0.35]]}}},
  {"type": "sphere", "center": [-0.6, 0.45, 0.2], "radius": 0.45,
   "bsdf": {"type": "diffuse", "reflectance": {"type": "checkerboard", "color0": [0.8, 0.2, 0.1], "color1": 0.6,
            "scale": [6, 3], "to_uv": [[1.0, 0.1, 0.05], [0.0, 1.0, 0.2]]}}},
  {"type": "sphere", "center": [0.7, 0.35, 0.4], "radius": 0.35,
   "bsdf": {"type": "diffuse", "reflectance": {"type": "checkerboard", "color0": 0.9, "color1": [0.1, 0.3, 0.7]}}},
  {"type": "disk", "to_world": {"scale": 0.6, "rotate_y": 20, "translate": [0.2, 0.9, -1.2]},
   "bsdf": {"type": "diffuse", "reflectance": {"type": "bitmap", "file": "tex_raw.png", "raw": true,
            "filter": "nearest", "wrap": "mirror", "scale": [2.5, 1.5]}}},
  {"type": "rectangle", "to_world": {"scale": 0.5, "translate": [-1.2, 1.2, -1.0]},
   "bsdf": {"type": "diffuse", "reflectance": {"type": "bitmap", "file": "tex_srgb.png", "wrap": "clamp"}}}
 ],
 "lights": [
  {"type": "spot", "position": [0.5, 3.0, 1.5], "target": [0.0, 0.0, 0.0], "intensity": [30, 28, 25],
   "cutoff_angle": 35, "beam_width": 25},
  {"type": "directional", "direction": [-0.3, -0.9, -0.2], "irradiance": 0.8},
  {"type": "constant", "radiance": [0.05, 0.06, 0.08]}
 ],
 "render": {"spp": 4, "integrator": {"type": "volpath", "max_depth": 8}}
}"#;

/// The converter's output for `TEXTURED_JSON` (image paths made relative):
/// each bitmap's `to_uv` is niebla's float32 uv map followed by `v -> 1 - v`,
/// each checkerboard's half niebla's map (Mitsuba's cells are half a unit).
const TEXTURED_XML: &str = r#"<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
  <medium type="homogeneous" id="medium_fog">
    <phase type="hg">
      <float name="g" value="0.4"/>
    </phase>
    <float name="albedo" value="0.9375000036379787"/>
    <boolean name="has_spectral_extinction" value="false"/>
    <float name="sigma_t" value="0.3200000114738941"/>
  </medium>
  <integrator type="volpath">
    <integer name="max_depth" value="9"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="40.0"/>
    <string name="fov_axis" value="y"/>
    <transform name="to_world">
      <lookat origin="0.2, 1.4, 4.2" target="0.0, 0.5, 0.0" up="0.0, 1.0, 0.0"/>
    </transform>
    <film type="hdrfilm">
      <integer name="width" value="16"/>
      <integer name="height" value="12"/>
      <rfilter type="box">
      </rfilter>
      <string name="pixel_format" value="rgb"/>
    </film>
    <sampler type="independent">
      <integer name="sample_count" value="4"/>
      <integer name="seed" value="0"/>
    </sampler>
  </sensor>
  <shape type="cube">
    <transform name="to_world">
      <matrix value="2.0 0.0 0.0 0.0 0.0 1.05 0.0 0.95 0.0 0.0 1.75 -0.25 0.0 0.0 0.0 1.0"/>
    </transform>
    <bsdf type="null">
    </bsdf>
    <ref name="interior" id="medium_fog"/>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="1.8, 1.8, 1.8"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-90.0"/>
      <translate value="0.0, 0.0, 0.0"/>
    </transform>
    <bsdf type="diffuse">
      <texture type="bitmap" name="reflectance">
        <string name="filename" value="tex_srgb.png"/>
        <string name="filter_type" value="bilinear"/>
        <string name="wrap_mode" value="repeat"/>
        <boolean name="raw" value="false"/>
        <transform name="to_uv">
          <matrix value="2.4000000953674316 0.9000000357627869 0.0 0.30000001192092896 0.4000000059604645 -1.7999999523162842 0.0 0.30000001192092896 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
    </bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" value="-0.6, 0.45, 0.2"/>
    <float name="radius" value="0.45"/>
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.8, 0.2, 0.1"/>
        <rgb name="color1" value="0.6, 0.6, 0.6"/>
        <transform name="to_uv">
          <matrix value="3.0 0.30000001192092896 0.0 0.15000000596046448 0.0 1.5 0.0 0.30000001192092896 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
    </bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" value="0.7, 0.35, 0.4"/>
    <float name="radius" value="0.35"/>
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.9, 0.9, 0.9"/>
        <rgb name="color1" value="0.1, 0.3, 0.7"/>
      </texture>
    </bsdf>
  </shape>
  <shape type="disk">
    <transform name="to_world">
      <scale value="0.6, 0.6, 0.6"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="20.0"/>
      <translate value="0.2, 0.9, -1.2"/>
    </transform>
    <bsdf type="diffuse">
      <texture type="bitmap" name="reflectance">
        <string name="filename" value="tex_raw.png"/>
        <string name="filter_type" value="nearest"/>
        <string name="wrap_mode" value="mirror"/>
        <boolean name="raw" value="true"/>
        <transform name="to_uv">
          <matrix value="2.5 0.0 0.0 0.0 -0.0 -1.5 0.0 1.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
    </bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="0.5, 0.5, 0.5"/>
      <translate value="-1.2, 1.2, -1.0"/>
    </transform>
    <bsdf type="diffuse">
      <texture type="bitmap" name="reflectance">
        <string name="filename" value="tex_srgb.png"/>
        <string name="filter_type" value="bilinear"/>
        <string name="wrap_mode" value="clamp"/>
        <boolean name="raw" value="false"/>
        <transform name="to_uv">
          <matrix value="1.0 0.0 0.0 0.0 -0.0 -1.0 0.0 1.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
    </bsdf>
  </shape>
  <emitter type="spot">
    <transform name="to_world">
      <lookat origin="0.5, 3.0, 1.5" target="0.0, 0.0, 0.0" up="0.0, 1.0, 0.0"/>
    </transform>
    <rgb name="intensity" value="30.0, 28.0, 25.0"/>
    <float name="cutoff_angle" value="35.0"/>
    <float name="beam_width" value="25.0"/>
  </emitter>
  <emitter type="directional">
    <vector name="direction" value="-0.3, -0.9, -0.2"/>
    <rgb name="irradiance" value="0.8, 0.8, 0.8"/>
  </emitter>
  <emitter type="constant">
    <rgb name="radiance" value="0.05, 0.06, 0.08"/>
  </emitter>
</scene>
"#;

/// A scene with textured roughness: a GGX conductor floor with a bitmap
/// `alpha_u` and a checkerboard `alpha_v`, a `twosided` wall (front:
/// checkerboard `alpha`; back: `eta`/`k`, `alpha_u` 0.05 and a nearest bitmap
/// `alpha_v`), a one-child `twosided` panel seen from behind with a bitmap
/// `alpha`, and a rough glass pane with checkerboard `alpha_u` (scaled) and
/// `alpha_v` (one color not gray), and a sphere and a turned disk with
/// constant anisotropic roughness; every anisotropic shape says
/// `"tangent_frame": "dpdu"` (Mitsuba's frame, which the importer gives back),
/// so the converter writes them all. (A rectangle turned about x in the
/// default `"normal"` frame is converted too, the frames agreeing, but its
/// basis is computed otherwise and the images differ in rounding.)
const ROUGH_JSON: &str = r#"{
 "version": 1,
 "camera": {"type": "perspective", "position": [0.2, 1.4, 4.2], "target": [0.0, 0.5, 0.0], "up": [0, 1, 0],
            "fov_y": 40, "width": 16, "height": 12},
 "shapes": [
  {"type": "rectangle", "to_world": {"scale": 1.8, "rotate_x": -90}, "tangent_frame": "dpdu",
   "bsdf": {"type": "roughconductor", "distribution": "ggx", "material": "Al",
            "alpha_u": {"type": "bitmap", "file": "alpha_gray.png", "raw": true, "scale": [2, 1.5]},
            "alpha_v": {"type": "checkerboard", "color0": 0.03, "color1": 0.3, "scale": [6, 6]}}},
  {"type": "rectangle", "to_world": {"scale": 1.5, "translate": [0, 1, -1.2]}, "tangent_frame": "dpdu",
   "bsdf": {"type": "twosided", "bsdf": [
     {"type": "roughconductor", "material": "Au", "alpha": {"type": "checkerboard", "color0": 0.06, "color1": 0.35}},
     {"type": "roughconductor", "distribution": "ggx", "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.1],
      "alpha_u": 0.05, "alpha_v": {"type": "bitmap", "file": "alpha_gray.png", "raw": true, "filter": "nearest"}}]}},
  {"type": "rectangle", "to_world": {"scale": 0.5, "rotate_x": 150, "translate": [-0.9, 0.6, 0.6]},
   "bsdf": {"type": "twosided", "bsdf": {"type": "roughconductor", "material": "Cu",
            "alpha": {"type": "bitmap", "file": "alpha_gray.png", "raw": true}}}},
  {"type": "rectangle", "to_world": {"scale": 0.5, "rotate_x": -20, "translate": [0.7, 0.5, 0.4]},
   "tangent_frame": "dpdu",
   "bsdf": {"type": "roughdielectric", "distribution": "ggx", "int_ior": 1.5,
            "alpha_u": {"type": "checkerboard", "color0": 0.05, "color1": 0.5, "scale": [4, 2]},
            "alpha_v": {"type": "checkerboard", "color0": [0.3, 0.1, 0.2], "color1": 0.1}}},
  {"type": "sphere", "center": [-0.3, 0.35, 0.9], "radius": 0.3, "tangent_frame": "dpdu",
   "bsdf": {"type": "roughconductor", "distribution": "ggx", "material": "Au", "alpha_u": 0.04, "alpha_v": 0.4}},
  {"type": "disk", "to_world": {"scale": 0.4, "rotate_x": -60, "rotate_y": 25, "translate": [0.9, 0.9, -0.3]},
   "tangent_frame": "dpdu",
   "bsdf": {"type": "roughconductor", "distribution": "beckmann", "material": "Cu", "alpha_u": 0.3, "alpha_v": 0.05}}
 ],
 "lights": [
  {"type": "spot", "position": [0.5, 3.0, 1.5], "target": [0.0, 0.0, 0.0], "intensity": [30, 28, 25],
   "cutoff_angle": 35, "beam_width": 25},
  {"type": "constant", "radiance": [0.3, 0.35, 0.4]}
 ],
 "render": {"spp": 4, "integrator": {"type": "volpath", "max_depth": 8}}
}"#;

/// The converter's output for `ROUGH_JSON` (image paths made relative): each
/// roughness checkerboard has its colors swapped (Mitsuba's `eval_1` gives
/// color1 where its `eval` gives color0; niebla's importer swaps them back).
const ROUGH_XML: &str = r#"<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
  <integrator type="volpath">
    <integer name="max_depth" value="9"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="40.0"/>
    <string name="fov_axis" value="y"/>
    <transform name="to_world">
      <lookat origin="0.2, 1.4, 4.2" target="0.0, 0.5, 0.0" up="0.0, 1.0, 0.0"/>
    </transform>
    <film type="hdrfilm">
      <integer name="width" value="16"/>
      <integer name="height" value="12"/>
      <rfilter type="box">
      </rfilter>
      <string name="pixel_format" value="rgb"/>
    </film>
    <sampler type="independent">
      <integer name="sample_count" value="4"/>
      <integer name="seed" value="0"/>
    </sampler>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="1.8, 1.8, 1.8"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-90.0"/>
    </transform>
    <bsdf type="roughconductor">
      <string name="distribution" value="ggx"/>
      <texture type="bitmap" name="alpha_u">
        <string name="filename" value="alpha_gray.png"/>
        <string name="filter_type" value="bilinear"/>
        <string name="wrap_mode" value="repeat"/>
        <boolean name="raw" value="true"/>
        <transform name="to_uv">
          <matrix value="2.0 0.0 0.0 0.0 -0.0 -1.5 0.0 1.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
      <texture type="checkerboard" name="alpha_v">
        <rgb name="color0" value="0.3, 0.3, 0.3"/>
        <rgb name="color1" value="0.03, 0.03, 0.03"/>
        <transform name="to_uv">
          <matrix value="3.0 0.0 0.0 0.0 0.0 3.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
      <string name="material" value="Al"/>
    </bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="1.5, 1.5, 1.5"/>
      <translate value="0.0, 1.0, -1.2"/>
    </transform>
    <bsdf type="twosided">
      <bsdf type="roughconductor">
        <string name="distribution" value="beckmann"/>
        <texture type="checkerboard" name="alpha">
          <rgb name="color0" value="0.35, 0.35, 0.35"/>
          <rgb name="color1" value="0.06, 0.06, 0.06"/>
        </texture>
        <string name="material" value="Au"/>
      </bsdf>
      <bsdf type="roughconductor">
        <string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.05"/>
        <texture type="bitmap" name="alpha_v">
          <string name="filename" value="alpha_gray.png"/>
          <string name="filter_type" value="nearest"/>
          <string name="wrap_mode" value="repeat"/>
          <boolean name="raw" value="true"/>
          <transform name="to_uv">
            <matrix value="1.0 0.0 0.0 0.0 -0.0 -1.0 0.0 1.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
          </transform>
        </texture>
        <rgb name="eta" value="0.2, 0.9, 1.1"/>
        <rgb name="k" value="3.9, 2.4, 2.1"/>
      </bsdf>
    </bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="0.5, 0.5, 0.5"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="150.0"/>
      <translate value="-0.9, 0.6, 0.6"/>
    </transform>
    <bsdf type="twosided">
      <bsdf type="roughconductor">
        <string name="distribution" value="beckmann"/>
        <texture type="bitmap" name="alpha">
          <string name="filename" value="alpha_gray.png"/>
          <string name="filter_type" value="bilinear"/>
          <string name="wrap_mode" value="repeat"/>
          <boolean name="raw" value="true"/>
          <transform name="to_uv">
            <matrix value="1.0 0.0 0.0 0.0 -0.0 -1.0 0.0 1.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
          </transform>
        </texture>
        <string name="material" value="Cu"/>
      </bsdf>
    </bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="0.5, 0.5, 0.5"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-20.0"/>
      <translate value="0.7, 0.5, 0.4"/>
    </transform>
    <bsdf type="roughdielectric">
      <string name="distribution" value="ggx"/>
      <texture type="checkerboard" name="alpha_u">
        <rgb name="color0" value="0.5, 0.5, 0.5"/>
        <rgb name="color1" value="0.05, 0.05, 0.05"/>
        <transform name="to_uv">
          <matrix value="2.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
      <texture type="checkerboard" name="alpha_v">
        <rgb name="color0" value="0.1, 0.1, 0.1"/>
        <rgb name="color1" value="0.3, 0.1, 0.2"/>
      </texture>
      <float name="int_ior" value="1.5"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <point name="center" value="-0.3, 0.35, 0.9"/>
    <float name="radius" value="0.3"/>
    <bsdf type="roughconductor">
      <string name="distribution" value="ggx"/>
      <float name="alpha_u" value="0.04"/>
      <float name="alpha_v" value="0.4"/>
      <string name="material" value="Au"/>
    </bsdf>
  </shape>
  <shape type="disk">
    <transform name="to_world">
      <scale value="0.4, 0.4, 0.4"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-60.0"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="25.0"/>
      <translate value="0.9, 0.9, -0.3"/>
    </transform>
    <bsdf type="roughconductor">
      <string name="distribution" value="beckmann"/>
      <float name="alpha_u" value="0.3"/>
      <float name="alpha_v" value="0.05"/>
      <string name="material" value="Cu"/>
    </bsdf>
  </shape>
  <emitter type="spot">
    <transform name="to_world">
      <lookat origin="0.5, 3.0, 1.5" target="0.0, 0.0, 0.0" up="0.0, 1.0, 0.0"/>
    </transform>
    <rgb name="intensity" value="30.0, 28.0, 25.0"/>
    <float name="cutoff_angle" value="35.0"/>
    <float name="beam_width" value="25.0"/>
  </emitter>
  <emitter type="constant">
    <rgb name="radiance" value="0.3, 0.35, 0.4"/>
  </emitter>
</scene>
"#;

/// Area lights of every shape and turned spheres: a rectangle, a disk, a
/// sphere and three meshes from OBJ files (an open roof without normals,
/// turned to emit downward by `flip_normals`, with `compute_normals`; a
/// sphere mesh with `face_normals`; the same mesh with its file's vertex
/// normals), a point light between them (the lights keep their order), in
/// fog; two checkerboarded spheres turned by their `rotation`, one by angles
/// and one by a matrix (the rotation turns their uvs, so a rotation read
/// back in other bits would show).
const AREA_JSON: &str = r#"{
 "version": 1,
 "camera": {"type": "perspective", "position": [0.2, 1.5, 4.4], "target": [0.0, 0.9, 0.0], "up": [0, 1, 0],
            "fov_y": 45, "width": 16, "height": 12},
 "media": {
  "fog": {"type": "homogeneous", "sigma_a": 0.03, "sigma_s": 0.25, "phase": {"type": "hg", "g": 0.3}}
 },
 "shapes": [
  {"type": "box", "min": [-2.5, -0.1, -2.0], "max": [2.5, 2.6, 2.0], "interior": "fog", "bsdf": {"type": "null"}},
  {"type": "rectangle", "to_world": {"scale": 2.4, "rotate_x": -90, "rotate_y": 10, "translate": [0, 0, 0]},
   "bsdf": {"type": "diffuse", "reflectance": [0.6, 0.55, 0.5]}},
  {"type": "sphere", "center": [-0.7, 0.4, 0.3], "radius": 0.4,
   "rotation": {"rotate_x": -63.7, "rotate_y": 21.3, "rotate_z": 117.9},
   "bsdf": {"type": "diffuse", "reflectance": {"type": "checkerboard", "color0": [0.8, 0.2, 0.1], "color1": 0.6,
            "scale": [6, 3]}}},
  {"type": "sphere", "center": [0.7, 0.35, 0.5], "radius": 0.35,
   "rotation": {"matrix": [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]]},
   "bsdf": {"type": "diffuse", "reflectance": {"type": "checkerboard", "color0": 0.9, "color1": [0.1, 0.3, 0.7],
            "scale": [8, 4]}}}
 ],
 "lights": [
  {"type": "area", "shape": {"type": "rectangle", "to_world": {"scale": [0.5, 0.3, 1], "rotate_x": 100,
   "rotate_y": -20, "translate": [-0.9, 2.2, -0.6]}}, "radiance": [6, 5, 4]},
  {"type": "point", "position": [1.2, 1.8, 1.0], "intensity": [0.6, 0.7, 0.9]},
  {"type": "area", "shape": {"type": "disk", "to_world": {"scale": 0.3, "rotate_y": -35, "translate": [1.3, 1.2, -1.5]}},
   "radiance": [2, 4, 6]},
  {"type": "area", "shape": {"type": "sphere", "center": [0.1, 1.6, -0.3], "radius": 0.12}, "radiance": 20},
  {"type": "area", "shape": {"type": "mesh", "file": "tent.obj", "flip_normals": true, "compute_normals": true,
   "to_world": {"scale": 0.6, "rotate_y": 20, "translate": [0.2, 2.1, 0.4]}}, "radiance": [5, 5, 4]},
  {"type": "area", "shape": {"type": "mesh", "file": "lowpoly_sphere.obj", "face_normals": true,
   "to_world": {"scale": 0.2, "rotate_x": -70, "translate": [-1.6, 1.3, 0.6]}}, "radiance": [3, 2, 1]},
  {"type": "area", "shape": {"type": "mesh", "file": "lowpoly_sphere.obj",
   "to_world": {"scale": 0.15, "rotate_y": 30, "translate": [1.6, 0.6, 0.9]}}, "radiance": [1, 3, 2]}
 ],
 "render": {"spp": 4, "integrator": {"type": "volpath", "max_depth": 8}}
}"#;

/// The converter's output for `AREA_JSON` (mesh paths made relative): each
/// light a shape with a black `diffuse` bsdf and an `area` emitter; the
/// turned spheres as unit spheres placed by scale, the rotation (`<rotate>`
/// steps, or a `<matrix>` of niebla's float32 rows) and translate.
const AREA_XML: &str = r#"<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
  <medium type="homogeneous" id="medium_fog">
    <phase type="hg">
      <float name="g" value="0.3"/>
    </phase>
    <float name="albedo" value="0.8928571449953835"/>
    <boolean name="has_spectral_extinction" value="false"/>
    <float name="sigma_t" value="0.27999999932944775"/>
  </medium>
  <integrator type="volpath">
    <integer name="max_depth" value="9"/>
  </integrator>
  <sensor type="perspective">
    <float name="fov" value="45.0"/>
    <string name="fov_axis" value="y"/>
    <transform name="to_world">
      <lookat origin="0.2, 1.5, 4.4" target="0.0, 0.9, 0.0" up="0.0, 1.0, 0.0"/>
    </transform>
    <film type="hdrfilm">
      <integer name="width" value="16"/>
      <integer name="height" value="12"/>
      <rfilter type="box">
      </rfilter>
      <string name="pixel_format" value="rgb"/>
    </film>
    <sampler type="independent">
      <integer name="sample_count" value="4"/>
      <integer name="seed" value="0"/>
    </sampler>
  </sensor>
  <shape type="cube">
    <transform name="to_world">
      <matrix value="2.5 0.0 0.0 0.0 0.0 1.35 0.0 1.25 0.0 0.0 2.0 0.0 0.0 0.0 0.0 1.0"/>
    </transform>
    <bsdf type="null">
    </bsdf>
    <ref name="interior" id="medium_fog"/>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="2.4, 2.4, 2.4"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-90.0"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="10.0"/>
      <translate value="0.0, 0.0, 0.0"/>
    </transform>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.6, 0.55, 0.5"/>
    </bsdf>
  </shape>
  <shape type="sphere">
    <transform name="to_world">
      <scale value="0.4, 0.4, 0.4"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-63.7"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="21.3"/>
      <rotate x="0.0" y="0.0" z="1.0" angle="117.9"/>
      <translate value="-0.7, 0.4, 0.3"/>
    </transform>
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.8, 0.2, 0.1"/>
        <rgb name="color1" value="0.6, 0.6, 0.6"/>
        <transform name="to_uv">
          <matrix value="3.0 0.0 0.0 0.0 0.0 1.5 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
    </bsdf>
  </shape>
  <shape type="sphere">
    <transform name="to_world">
      <scale value="0.3499999940395355, 0.3499999940395355, 0.3499999940395355"/>
      <matrix value="0.36000001430511475 0.47999998927116394 -0.800000011920929 0.0 -0.800000011920929 0.6000000238418579 0.0 0.0 0.47999998927116394 0.6399999856948853 0.6000000238418579 0.0 0.0 0.0 0.0 1.0"/>
      <translate value="0.7, 0.35, 0.5"/>
    </transform>
    <bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.9, 0.9, 0.9"/>
        <rgb name="color1" value="0.1, 0.3, 0.7"/>
        <transform name="to_uv">
          <matrix value="4.0 0.0 0.0 0.0 0.0 2.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0"/>
        </transform>
      </texture>
    </bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="0.5, 0.3, 1.0"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="100.0"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="-20.0"/>
      <translate value="-0.9, 2.2, -0.6"/>
    </transform>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.0, 0.0, 0.0"/>
    </bsdf>
    <emitter type="area">
      <rgb name="radiance" value="6.0, 5.0, 4.0"/>
    </emitter>
  </shape>
  <emitter type="point">
    <point name="position" value="1.2, 1.8, 1.0"/>
    <rgb name="intensity" value="0.6, 0.7, 0.9"/>
  </emitter>
  <shape type="disk">
    <transform name="to_world">
      <scale value="0.3, 0.3, 0.3"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="-35.0"/>
      <translate value="1.3, 1.2, -1.5"/>
    </transform>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.0, 0.0, 0.0"/>
    </bsdf>
    <emitter type="area">
      <rgb name="radiance" value="2.0, 4.0, 6.0"/>
    </emitter>
  </shape>
  <shape type="sphere">
    <point name="center" value="0.1, 1.6, -0.3"/>
    <float name="radius" value="0.12"/>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.0, 0.0, 0.0"/>
    </bsdf>
    <emitter type="area">
      <rgb name="radiance" value="20.0, 20.0, 20.0"/>
    </emitter>
  </shape>
  <shape type="obj">
    <string name="filename" value="tent.obj"/>
    <transform name="to_world">
      <scale value="0.6, 0.6, 0.6"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="20.0"/>
      <translate value="0.2, 2.1, 0.4"/>
    </transform>
    <boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.0, 0.0, 0.0"/>
    </bsdf>
    <emitter type="area">
      <rgb name="radiance" value="5.0, 5.0, 4.0"/>
    </emitter>
  </shape>
  <shape type="obj">
    <string name="filename" value="lowpoly_sphere.obj"/>
    <transform name="to_world">
      <scale value="0.2, 0.2, 0.2"/>
      <rotate x="1.0" y="0.0" z="0.0" angle="-70.0"/>
      <translate value="-1.6, 1.3, 0.6"/>
    </transform>
    <boolean name="face_normals" value="true"/>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.0, 0.0, 0.0"/>
    </bsdf>
    <emitter type="area">
      <rgb name="radiance" value="3.0, 2.0, 1.0"/>
    </emitter>
  </shape>
  <shape type="obj">
    <string name="filename" value="lowpoly_sphere.obj"/>
    <transform name="to_world">
      <scale value="0.15, 0.15, 0.15"/>
      <rotate x="0.0" y="1.0" z="0.0" angle="30.0"/>
      <translate value="1.6, 0.6, 0.9"/>
    </transform>
    <bsdf type="diffuse">
      <rgb name="reflectance" value="0.0, 0.0, 0.0"/>
    </bsdf>
    <emitter type="area">
      <rgb name="radiance" value="1.0, 3.0, 2.0"/>
    </emitter>
  </shape>
</scene>
"#;

/// A 6^3 density grid over the smoke box, Mitsuba's `.vol` layout (x fastest).
fn write_vol(path: &Path) {
    let n = 6u32;
    let mut bytes = b"VOL\x03".to_vec();
    for v in [1, n, n, n, 1] {
        bytes.extend_from_slice(&(v as i32).to_le_bytes());
    }
    for v in [0.2f32, 0.0, -0.5, 1.1, 1.0, 0.4] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = ((x * 7 + y * 5 + z * 3) % 11) as f32 / 10.0;
                bytes.extend_from_slice(&d.to_le_bytes());
            }
        }
    }
    std::fs::write(path, bytes).unwrap();
}

fn render_file(path: &Path, sampler: SamplerKind, size: (u32, u32)) -> Vec<[f32; 3]> {
    let source = read_scene_source(path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let built = build_scene(&source.desc, &path.display().to_string(), path.parent().unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let options = RenderOptions { spp: 4, seed: 7, first_sample: 0, threads: None, sampler };
    let image = render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
    let (w, h) = (built.scene.camera.width, built.scene.camera.height);
    assert_eq!((w, h), size);
    (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| image.get(x, y).0).collect()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("niebla_mitsuba_roundtrip_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn converted_xml_renders_bit_identically() {
    let dir = temp_dir("media");
    write_vol(&dir.join("g.vol"));
    std::fs::write(dir.join("scene.json"), SCENE_JSON).unwrap();
    std::fs::write(dir.join("scene.xml"), SCENE_XML).unwrap();
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        let a = render_file(&dir.join("scene.json"), sampler, (16, 12));
        let b = render_file(&dir.join("scene.xml"), sampler, (16, 12));
        let mean = a.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.len()) as f64;
        assert!(mean > 0.01, "{sampler:?}: the image is (nearly) black: mean {mean}");
        let differ = a.iter().zip(&b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
        println!("{sampler:?}: image mean {mean:.6}, {differ} of {} pixels differ", a.len());
        assert_eq!(differ, 0, "{sampler:?}: {differ} pixels differ between the JSON and its XML");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn converted_textured_xml_renders_bit_identically() {
    let dir = temp_dir("textured");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mitsuba/data");
    for f in ["tex_srgb.png", "tex_raw.png"] {
        std::fs::copy(data.join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("scene.json"), TEXTURED_JSON).unwrap();
    std::fs::write(dir.join("scene.xml"), TEXTURED_XML).unwrap();
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        let a = render_file(&dir.join("scene.json"), sampler, (16, 12));
        let b = render_file(&dir.join("scene.xml"), sampler, (16, 12));
        let mean = a.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.len()) as f64;
        assert!(mean > 0.01, "{sampler:?}: the image is (nearly) black: mean {mean}");
        let differ = a.iter().zip(&b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
        println!("textured {sampler:?}: image mean {mean:.6}, {differ} of {} pixels differ", a.len());
        assert_eq!(differ, 0, "{sampler:?}: {differ} pixels differ between the textured JSON and its XML");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn converted_rough_textured_xml_renders_bit_identically() {
    let dir = temp_dir("rough");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mitsuba/data");
    std::fs::copy(data.join("alpha_gray.png"), dir.join("alpha_gray.png")).unwrap();
    std::fs::write(dir.join("scene.json"), ROUGH_JSON).unwrap();
    std::fs::write(dir.join("scene.xml"), ROUGH_XML).unwrap();
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        let a = render_file(&dir.join("scene.json"), sampler, (16, 12));
        let b = render_file(&dir.join("scene.xml"), sampler, (16, 12));
        let mean = a.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.len()) as f64;
        assert!(mean > 0.01, "{sampler:?}: the image is (nearly) black: mean {mean}");
        let differ = a.iter().zip(&b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
        println!("rough {sampler:?}: image mean {mean:.6}, {differ} of {} pixels differ", a.len());
        assert_eq!(differ, 0, "{sampler:?}: {differ} pixels differ between the rough JSON and its XML");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn converted_area_lights_and_turned_spheres_render_bit_identically() {
    let dir = temp_dir("area");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mitsuba/data");
    for f in ["tent.obj", "lowpoly_sphere.obj"] {
        std::fs::copy(data.join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("scene.json"), AREA_JSON).unwrap();
    std::fs::write(dir.join("scene.xml"), AREA_XML).unwrap();
    // The importer reads back seven lights in the JSON's order, and the
    // spheres' rotations as angles and as a matrix.
    let source = read_scene_source(&dir.join("scene.xml"), &[]).unwrap_or_else(|e| panic!("{e}"));
    let json = read_scene_source(&dir.join("scene.json"), &[]).unwrap_or_else(|e| panic!("{e}"));
    // (The importer gives every mesh without `face_normals` Mitsuba's
    // normal options; on these lights, whose file has vertex normals or
    // whose JSON asks for computed ones, they change nothing.)
    let mitsuba_mesh_options = |mut lights: Vec<LightDesc>| {
        for light in &mut lights {
            if let LightDesc::Area(a) = light {
                if let GeometryDesc::Mesh(m) = &mut a.shape.geometry {
                    if !m.face_normals {
                        m.compute_normals = true;
                        m.shading_normal_backside = ShadingBacksideDesc::Mitsuba;
                    }
                }
            }
        }
        lights
    };
    assert_eq!(source.desc.lights, mitsuba_mesh_options(json.desc.lights.clone()), "lights read back from the XML");
    for i in [2, 3] {
        let (a, b) = (&source.desc.shapes[i].geometry, &json.desc.shapes[i].geometry);
        assert_eq!(a, b, "shapes[{i}] (a turned sphere) read back from the XML");
    }
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        let a = render_file(&dir.join("scene.json"), sampler, (16, 12));
        let b = render_file(&dir.join("scene.xml"), sampler, (16, 12));
        let mean = a.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.len()) as f64;
        assert!(mean > 0.01, "{sampler:?}: the image is (nearly) black: mean {mean}");
        let differ = a.iter().zip(&b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
        println!("area {sampler:?}: image mean {mean:.6}, {differ} of {} pixels differ", a.len());
        assert_eq!(differ, 0, "{sampler:?}: {differ} pixels differ between the area-light JSON and its XML");
    }
    // The turned spheres' rotations show in the image: without them it differs.
    let unturned = AREA_JSON
        .replace(r#""rotation": {"rotate_x": -63.7, "rotate_y": 21.3, "rotate_z": 117.9},"#, "")
        .replace(r#""rotation": {"matrix": [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]]},"#, "");
    assert_eq!(unturned.matches("rotation").count(), 0);
    std::fs::write(dir.join("unturned.json"), unturned).unwrap();
    let a = render_file(&dir.join("scene.json"), SamplerKind::Independent, (16, 12));
    let c = render_file(&dir.join("unturned.json"), SamplerKind::Independent, (16, 12));
    let differ = a.iter().zip(&c).filter(|(p, q)| p != q).count();
    println!("area: {differ} of {} pixels differ without the spheres' rotations", a.len());
    assert!(differ > 0, "the spheres' rotations do not show in the image");
    std::fs::remove_dir_all(&dir).ok();
}
