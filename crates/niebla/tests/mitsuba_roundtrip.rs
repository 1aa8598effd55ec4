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
use niebla::scene::{build_scene, read_scene_source};

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

fn render_file(path: &Path, sampler: SamplerKind) -> Vec<[f32; 3]> {
    let source = read_scene_source(path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let built = build_scene(&source.desc, &path.display().to_string(), path.parent().unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let options = RenderOptions { spp: 4, seed: 7, first_sample: 0, threads: None, sampler };
    let image = render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
    let (w, h) = (built.scene.camera.width, built.scene.camera.height);
    assert_eq!((w, h), (16, 12));
    (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| image.get(x, y).0).collect()
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("niebla_mitsuba_roundtrip_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn converted_xml_renders_bit_identically() {
    let dir = temp_dir();
    write_vol(&dir.join("g.vol"));
    std::fs::write(dir.join("scene.json"), SCENE_JSON).unwrap();
    std::fs::write(dir.join("scene.xml"), SCENE_XML).unwrap();
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        let a = render_file(&dir.join("scene.json"), sampler);
        let b = render_file(&dir.join("scene.xml"), sampler);
        let mean = a.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.len()) as f64;
        assert!(mean > 0.01, "{sampler:?}: the image is (nearly) black: mean {mean}");
        let differ = a.iter().zip(&b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
        println!("{sampler:?}: image mean {mean:.6}, {differ} of {} pixels differ", a.len());
        assert_eq!(differ, 0, "{sampler:?}: {differ} pixels differ between the JSON and its XML");
    }
    std::fs::remove_dir_all(&dir).ok();
}
