//! Unit tests of the Mitsuba importer: conversions checked against the
//! values Mitsuba's own definitions give, and errors with file:line.

use std::path::Path;

use serde_json::json;

use super::*;

const SENSOR: &str = r#"<sensor type="perspective">
    <float name="fov" value="40"/><string name="fov_axis" value="y"/>
    <transform name="to_world"><lookat origin="0, 1, 5" target="0, 1, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
    <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="20"/>
      <rfilter type="box"/></film></sensor>"#;

fn import(body: &str) -> Result<MitsubaImport, crate::scene::SceneError> {
    let text = format!("<scene version=\"3.0.0\">\n{SENSOR}\n{body}\n</scene>");
    import_mitsuba_str(&text, "t.xml", Path::new("/nonexistent"), &[])
}

fn err(body: &str) -> String {
    import(body).unwrap_err().to_string()
}

#[test]
fn camera_from_look_at() {
    let s = import("").unwrap().scene;
    assert_eq!(s["camera"]["position"], json!([0.0, 1.0, 5.0]));
    // A lone <lookat> keeps its numbers as written.
    assert_eq!(s["camera"]["target"], json!([0.0, 1.0, 0.0]));
    assert_eq!(s["camera"]["up"], json!([0.0, 1.0, 0.0]));
    assert_eq!(s["camera"]["fov_y"], json!(40.0));
    assert_eq!(s["render"], json!({"spp": 8, "seed": 0, "sampler": "independent", "integrator": {"type": "volpath"}}));
    crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
}

/// fov_axis x (Mitsuba's default) on a 2:1 image: tan(fov_y / 2) = tan(fov_x / 2) / 2.
#[test]
fn horizontal_fov_becomes_vertical() {
    let text = SENSOR.replace("<string name=\"fov_axis\" value=\"y\"/>", "");
    let text = format!("<scene version=\"3.0.0\">{text}</scene>");
    let s = import_mitsuba_str(&text, "t.xml", Path::new("."), &[]).unwrap().scene;
    let fov_y = s["camera"]["fov_y"].as_f64().unwrap();
    let expected = 2.0 * ((20f64.to_radians()).tan() / 2.0).atan().to_degrees();
    assert!((fov_y - expected).abs() < 1e-12, "{fov_y} vs {expected}");
}

#[test]
fn max_depth_counts_segments() {
    let s = import(r#"<integrator type="volpathmis"><integer name="max_depth" value="65"/></integrator>"#).unwrap();
    assert_eq!(s.scene["render"]["integrator"], json!({"type": "volpath", "max_depth": 64}));
    let s = import(r#"<integrator type="moment"><integrator type="path"/></integrator>"#).unwrap();
    assert_eq!(s.scene["render"]["integrator"], json!({"type": "volpath"}));
    assert!(err(r#"<integrator type="volpath"><integer name="max_depth" value="1"/></integrator>"#)
        .contains("max_depth` 1"));
}

#[test]
fn media_shapes_and_refs() {
    let s = import(
        r#"<medium type="homogeneous" id="fog">
             <rgb name="sigma_t" value="1, 2, 3"/><float name="albedo" value="0.5"/><float name="scale" value="2"/>
             <phase type="blendphase"><float name="weight" value="0.25"/>
               <phase type="hg"><float name="g" value="0.7"/></phase><phase type="isotropic"/></phase>
           </medium>
           <shape type="cube"><transform name="to_world"><scale value="2"/><translate x="1"/></transform>
             <bsdf type="null"/><ref name="interior" id="fog"/></shape>
           <shape type="cube"><transform name="to_world"><rotate y="1" angle="30"/></transform></shape>
           <shape type="sphere"><float name="radius" value="0.5"/>
             <transform name="to_world"><scale value="2"/><translate y="3"/></transform>
             <emitter type="area"><rgb name="radiance" value="4"/></emitter>
             <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></shape>"#,
    )
    .unwrap();
    let sc = &s.scene;
    assert_eq!(
        sc["media"]["fog"],
        // sigma_s = sigma_t scale albedo, sigma_a = sigma_t scale - sigma_s.
        json!({"type": "homogeneous", "sigma_a": [1.0, 2.0, 3.0], "sigma_s": [1.0, 2.0, 3.0],
               "phase": {"type": "double_hg", "w": 0.75, "g1": 0.7, "g2": 0.0}})
    );
    assert_eq!(
        sc["shapes"][0],
        json!({"type": "box", "min": [-1.0, -2.0, -2.0], "max": [3.0, 2.0, 2.0], "interior": "fog",
               "bsdf": {"type": "null"}})
    );
    assert_eq!(sc["shapes"][1]["type"], json!("mesh"));
    assert_eq!(sc["shapes"][1]["bsdf"], json!({"type": "diffuse", "reflectance": 0.5}));
    assert_eq!(
        sc["lights"][0],
        json!({"type": "area", "shape": {"type": "sphere", "center": [0.0, 3.0, 0.0], "radius": 1.0}, "radiance": 4.0})
    );
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    crate::scene::parse_scene_str(&sc.to_string(), "t").unwrap();
}

#[test]
fn disks_keep_their_placement_and_emit() {
    let s = import(
        r#"<shape type="disk"><transform name="to_world"><scale value="2"/><translate z="1"/></transform></shape>
           <shape type="disk"><boolean name="flip_normals" value="true"/>
             <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#,
    )
    .unwrap();
    let sc = &s.scene;
    assert_eq!(
        sc["shapes"][0],
        // Scale then translate is niebla's own transform object.
        json!({"type": "disk", "to_world": {"scale": 2.0, "translate": [0.0, 0.0, 1.0]},
               "bsdf": {"type": "diffuse", "reflectance": 0.5}})
    );
    // flip_normals: a half turn about x (y and z negated).
    assert_eq!(sc["lights"][0]["shape"]["type"], json!("disk"));
    assert_eq!(sc["lights"][0]["shape"]["to_world"]["matrix"][2][2], json!(-1.0));
    let desc = crate::scene::parse_scene_str(&sc.to_string(), "t").unwrap();
    assert!(matches!(desc.shapes[0].geometry, crate::scene::desc::GeometryDesc::Disk(_)));
}

#[test]
fn rough_bsdfs_keep_mitsuba_names() {
    let s = import(
        r#"<shape type="sphere"><bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
             <float name="alpha" value="0.2"/><string name="int_ior" value="water"/></bsdf></shape>
           <shape type="sphere"><bsdf type="twosided"><bsdf type="roughplastic"/></bsdf></shape>
           <shape type="sphere"><bsdf type="roughconductor"><string name="material" value="Au"/>
             <float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf></shape>"#,
    )
    .unwrap();
    let sh = &s.scene["shapes"];
    assert_eq!(
        sh[0]["bsdf"],
        json!({"type": "roughdielectric", "distribution": "ggx", "alpha": 0.2, "int_ior": 1.333, "ext_ior": 1.000277})
    );
    assert_eq!(
        sh[1]["bsdf"],
        json!({"type": "twosided", "bsdf": {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.1,
               "diffuse_reflectance": 0.5, "specular_reflectance": 1.0, "int_ior": 1.49, "ext_ior": 1.000277,
               "nonlinear": false}})
    );
    assert_eq!(
        sh[2]["bsdf"],
        json!({"type": "roughconductor", "distribution": "beckmann", "alpha_u": 0.1, "alpha_v": 0.3, "material": "Au"})
    );
    // niebla reads every one of them.
    crate::scene::parse_scene_str(&s.scene.to_string(), "t").unwrap();
}

#[test]
fn lights_keep_their_numbers() {
    let s = import(
        r#"<emitter type="spot"><transform name="to_world"><lookat origin="0, 4, 0" target="0, 0, 0" up="1, 0, 0"/></transform>
             <rgb name="intensity" value="10, 20, 30"/><float name="cutoff_angle" value="30"/></emitter>
           <emitter type="directional"><vector name="direction" x="0" y="-1" z="0"/><float name="irradiance" value="3"/></emitter>
           <emitter type="point"><point name="position" value="1, 2, 3"/></emitter>"#,
    )
    .unwrap();
    let l = &s.scene["lights"];
    assert_eq!(
        l[0],
        json!({"type": "spot", "position": [0.0, 4.0, 0.0], "target": [0.0, 0.0, 0.0],
               "intensity": [10.0, 20.0, 30.0], "cutoff_angle": 30.0, "beam_width": 22.5})
    );
    assert_eq!(l[1], json!({"type": "directional", "direction": [0.0, -1.0, 0.0], "irradiance": 3.0}));
    assert_eq!(l[2], json!({"type": "point", "position": [1.0, 2.0, 3.0], "intensity": 1.0}));
}

/// Transforms in niebla's order (scale, rotate about +x, +y, +z, translate)
/// become niebla's transform object; anything else stays a matrix.
#[test]
fn transforms_in_niebla_order_keep_their_numbers() {
    let placed = |ops: &str| {
        let s = import(&format!(r#"<shape type="rectangle"><transform name="to_world">{ops}</transform></shape>"#))
            .unwrap()
            .scene;
        s["shapes"][0]["to_world"].clone()
    };
    assert_eq!(
        placed(r#"<scale value="3"/><rotate x="1" angle="-90"/><rotate z="1" angle="10"/><translate y="0.5"/>"#),
        json!({"scale": 3.0, "rotate_x": -90.0, "rotate_z": 10.0, "translate": [0.0, 0.5, 0.0]})
    );
    assert_eq!(placed(r#"<scale x="2" y="1" z="4"/>"#), json!({"scale": [2.0, 1.0, 4.0]}));
    // Out of niebla's order, a tilted or negative axis, a repeated step: the matrix.
    for ops in [
        r#"<rotate x="1" angle="-90"/><scale value="3"/>"#,
        r#"<rotate x="1" y="1" angle="30"/>"#,
        r#"<rotate x="-1" angle="30"/>"#,
        r#"<translate x="1"/><translate x="1"/>"#,
    ] {
        assert!(placed(ops).get("matrix").is_some(), "{ops}: {}", placed(ops));
    }
}

/// The bench converter writes a medium as sigma_t = sigma_a + sigma_s and
/// albedo = sigma_s / sigma_t (in f64, as shortest decimal text) of niebla's
/// f32 coefficients; the importer gives back exactly those f32 values, over
/// coefficients from 1e-4 to 1e3 and ratios sigma_a / sigma_s up to 1e7.
#[test]
fn media_coefficients_read_back_to_the_same_f32() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..2000 {
        let draw = |u: f64| 10f64.powf(-4.0 + 7.0 * u) as f32;
        let (sa, ss) = (draw(uniform()), draw(uniform()));
        let (sa, ss) = if i % 7 == 0 {
            (0.0, ss)
        } else if i % 11 == 0 {
            (sa, 0.0)
        } else {
            (sa, ss)
        };
        let st = sa as f64 + ss as f64;
        let albedo = ss as f64 / st;
        let text = format!(
            r#"<medium type="homogeneous" id="m"><float name="sigma_t" value="{st:?}"/><float name="albedo" value="{albedo:?}"/></medium>
               <shape type="sphere"><ref name="interior" id="m"/></shape>"#
        );
        let s = import(&text).unwrap().scene;
        let m = &s["media"]["m"];
        let read = |k: &str| m[k].as_f64().unwrap() as f32;
        assert_eq!((read("sigma_a"), read("sigma_s")), (sa, ss), "{m}");
    }
}

#[test]
fn errors_name_file_line_and_element() {
    assert!(
        err("<shape type=\"sphere\">\n<bsdf type=\"hair\"/></shape>")
            .starts_with("t.xml:9: <bsdf type=\"hair\">: not supported"),
        "{}",
        err("<shape type=\"sphere\">\n<bsdf type=\"hair\"/></shape>")
    );
    let e = err("<shape type=\"sphere\"><ref name=\"interior\" id=\"nope\"/></shape>");
    assert!(e.starts_with("t.xml:8: <ref id=\"nope\">: no element has id \"nope\""), "{e}");
    let e = err("<shape type=\"cube\"><transform name=\"to_world\">\n<skew value=\"1\"/></transform></shape>");
    assert!(e.starts_with("t.xml:9: <transform>: unknown operation <skew>"), "{e}");
    let e = err("<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"0\"/></transform></shape>");
    assert!(e.starts_with("t.xml:8: <scale>: a scale factor is zero"), "{e}");
    let e = err("<shape type=\"ply\"><string name=\"filename\" value=\"missing.ply\"/></shape>");
    assert!(e.starts_with("t.xml:8: <shape type=\"ply\">: file \"missing.ply\" not found"), "{e}");
    let e =
        err("<shape type=\"sphere\"><float name=\"radius\" value=\"1\"/><float name=\"radiuss\" value=\"1\"/></shape>");
    assert!(
        e.starts_with("t.xml:8: <shape type=\"sphere\">: property `radiuss` (<float name=\"radiuss\">): not supported"),
        "{e}"
    );
    let e = err("<shape type=\"sphere\"><bsdf type=\"dielectric\"><texture type=\"checkerboard\" \
                 name=\"specular_reflectance\"/></bsdf></shape>");
    assert!(e.starts_with("t.xml:8: ") && e.contains("textures and volumes are not supported here"), "{e}");
    let e = err("<shape type=\"cylinder\"/>");
    assert!(e.starts_with("t.xml:8: <shape type=\"cylinder\">: not supported"), "{e}");
    let e = err("<shape type=\"sphere\"><float name=\"radius\" value=\"abc\"/></shape>");
    assert!(e.contains("expected one number"), "{e}");
    let e = err("<shape type=\"sphere\"><bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"400:0.1, 700:0.5\"/></bsdf></shape>");
    assert!(e.contains("spectra sampled at wavelengths"), "{e}");
}

#[test]
fn harmless_elements_become_notes() {
    let text = SENSOR.replace("<rfilter type=\"box\"/>", "<string name=\"pixel_format\" value=\"rgba\"/>");
    let text = format!("<scene version=\"3.0.0\">{text}</scene>");
    let s = import_mitsuba_str(&text, "t.xml", Path::new("."), &[]).unwrap();
    assert_eq!(s.notes.len(), 2, "{:?}", s.notes);
    assert!(s.notes.iter().any(|n| n.contains("pixel_format")), "{:?}", s.notes);
    assert!(s.notes.iter().any(|n| n.contains("Gaussian")), "{:?}", s.notes);
}

/// Every prefix of a real scene (every 5th byte) and every number in it
/// replaced by awkward values: errors, never panics.
#[test]
fn truncated_and_mangled_scenes_are_errors_not_panics() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mitsuba");
    let text = std::fs::read_to_string(dir.join("chromatic_mis.xml")).unwrap();
    for cut in (0..text.len()).step_by(5).filter(|&c| text.is_char_boundary(c)) {
        let _ = import_mitsuba_str(&text[..cut], "t.xml", &dir, &[]);
    }
    for bad in ["nan", "-1", "0", "1e40", "-0", "inf", "", "1 2", "$spp"] {
        let mut start = 0;
        while let Some(i) = text[start..].find("value=\"") {
            let a = start + i + 7;
            let b = a + text[a..].find('"').unwrap();
            let mangled = format!("{}{bad}{}", &text[..a], &text[b..]);
            if let Ok(s) = import_mitsuba_str(&mangled, "t.xml", &dir, &[]) {
                let _ = crate::scene::parse_scene_str(&s.scene.to_string(), "t");
            }
            start = b;
        }
    }
}

/// `tabphase`: values at cosines regularly spaced from -1 to 1, cos = 1
/// forward. p = 1 + mu (values 0, 1, 2) has mean cosine 1/3 exactly.
#[test]
fn tabphase_becomes_an_inline_table_in_mu() {
    let s = import(
        r#"<medium type="homogeneous" id="fog"><float name="sigma_t" value="1"/>
             <phase type="tabphase"><string name="values" value="0, 1,2"/></phase></medium>
           <shape type="cube"><bsdf type="null"/><ref name="interior" id="fog"/></shape>"#,
    )
    .unwrap();
    let phase = &s.scene["media"]["fog"]["phase"];
    assert_eq!(phase, &json!({"type": "tabulated", "mu": [-1.0, 0.0, 1.0], "p": [0.0, 1.0, 2.0]}));
    let desc = crate::scene::parse_scene_str(&s.scene.to_string(), "t").unwrap();
    let built = crate::scene::build_scene(&desc, "t", Path::new(".")).unwrap();
    let g = built.scene.media[0].phase().mean_cosine();
    assert!((g - 1.0 / 3.0).abs() < 1e-6, "mean cosine {g}");

    let e = err(
        r#"<medium type="homogeneous" id="a"><phase type="tabphase"><string name="values" value="1, x"/></phase></medium>"#,
    );
    assert!(e.contains("<phase type=\"tabphase\">: `values`: \"x\" is not a number"), "{e}");
    let e = err(
        r#"<medium type="homogeneous" id="b"><phase type="tabphase"><string name="values" value="1, -2"/></phase></medium>"#,
    );
    assert!(e.contains("p = -2: expected a finite value >= 0"), "{e}");
}

/// Writes a `.vol` header and zero voxels: `dims`, `channels`, box [0, 1]^3.
fn write_vol(path: &Path, dims: [i32; 3], channels: i32) {
    let mut bytes = b"VOL\x03".to_vec();
    for v in [1, dims[0], dims[1], dims[2], channels] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes.resize(bytes.len() + 4 * (dims.iter().product::<i32>() * channels) as usize, 0);
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn albedo_gridvolumes_become_albedo_grids() {
    let dir = std::env::temp_dir().join(format!("niebla_mitsuba_albedo_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_vol(&dir.join("d.vol"), [4, 4, 4], 1);
    write_vol(&dir.join("a1.vol"), [2, 3, 4], 1);
    write_vol(&dir.join("a3.vol"), [2, 2, 2], 3);
    write_vol(&dir.join("a2.vol"), [2, 2, 2], 2);
    let medium = |sigma_t: &str, albedo_file: &str, albedo_to_world: &str| {
        format!(
            "<medium type=\"heterogeneous\" id=\"m\">\n{sigma_t}\n\
             <volume type=\"gridvolume\" name=\"albedo\"><string name=\"filename\" value=\"{albedo_file}\"/>\
             {albedo_to_world}</volume>\n<float name=\"scale\" value=\"3\"/></medium>"
        )
    };
    let grid_sigma_t = "<volume type=\"gridvolume\" name=\"sigma_t\"><string name=\"filename\" value=\"d.vol\"/>\
                        <transform name=\"to_world\"><scale value=\"2\"/></transform></volume>";
    let run = |body: &str| {
        let text = format!("<scene version=\"3.0.0\">\n{SENSOR}\n{body}\n</scene>");
        import_mitsuba_str(&text, "t.xml", &dir, &[])
    };
    // Same placement as sigma_t: no albedo_to_world.
    let same = "<transform name=\"to_world\"><scale value=\"2\"/></transform>";
    let s = run(&medium(grid_sigma_t, "a1.vol", same)).unwrap_or_else(|e| panic!("{e}")).scene;
    let m = &s["media"]["m"];
    assert_eq!(m["type"], json!("grid"));
    assert_eq!(m["albedo_grid"]["type"], json!("vol"));
    assert!(m["albedo_grid"]["file"].as_str().unwrap().ends_with("a1.vol"));
    assert!(m.get("albedo").is_none() && m.get("albedo_to_world").is_none(), "{m}");
    assert_eq!(m["scale"], json!(3.0));
    // Its own placement (3 channels): kept, as the matrix mapping the file's box.
    let own = "<transform name=\"to_world\"><translate x=\"1\"/></transform>";
    let s = run(&medium(grid_sigma_t, "a3.vol", own)).unwrap_or_else(|e| panic!("{e}")).scene;
    assert_eq!(
        s["media"]["m"]["albedo_to_world"],
        json!({"matrix": [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]})
    );
    // Errors: file:line and what is expected.
    let e = run(&medium(grid_sigma_t, "a2.vol", "")).unwrap_err().to_string();
    assert!(e.starts_with("t.xml:10: ") && e.contains("has 2 channels: an albedo grid has 1 or 3"), "{e}");
    let e = run(&medium("<rgb name=\"sigma_t\" value=\"1\"/>", "a1.vol", "")).unwrap_err().to_string();
    assert!(e.starts_with("t.xml:10: ") && e.contains("needs `sigma_t` as a gridvolume"), "{e}");
    let rgb_sigma_t =
        "<volume type=\"gridvolume\" name=\"sigma_t\"><string name=\"filename\" value=\"a3.vol\"/></volume>";
    let e = run(&medium(rgb_sigma_t, "a1.vol", "")).unwrap_err().to_string();
    assert!(e.starts_with("t.xml:9: ") && e.contains("has 3 channels") && e.contains("one channel"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Imports `body` with a folder holding `a.png` (the importer only checks
/// that the file exists).
fn import_with_png(body: &str) -> Result<MitsubaImport, crate::scene::SceneError> {
    let dir = std::env::temp_dir().join(format!("niebla_mitsuba_tex_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a.png"), b"not decoded here").unwrap();
    let text = format!("<scene version=\"3.0.0\">\n{SENSOR}\n{body}\n</scene>");
    import_mitsuba_str(&text, "t.xml", &dir, &[])
}

/// A texture in `alpha` of roughconductor/roughdielectric becomes the
/// JSON `alpha` texture object (nested or by `<ref>`), with the
/// distribution kept; niebla's parser reads it back.
#[test]
fn textured_alpha_converts_for_rough_conductor_and_dielectric() {
    let s = import_with_png(
        r#"<texture type="bitmap" id="r"><string name="filename" value="a.png"/><boolean name="raw" value="true"/></texture>
           <shape type="rectangle"><bsdf type="roughconductor"><string name="distribution" value="ggx"/><string name="material" value="Al"/>
           <ref name="alpha" id="r"/></bsdf></shape>
           <shape type="sphere"><bsdf type="roughdielectric"><float name="int_ior" value="1.5"/>
           <texture type="checkerboard" name="alpha"><float name="color0" value="0.05"/>
           <float name="color1" value="0.45"/></texture></bsdf></shape>"#,
    )
    .unwrap()
    .scene;
    let a = &s["shapes"][0]["bsdf"];
    assert_eq!((&a["type"], &a["distribution"]), (&json!("roughconductor"), &json!("ggx")));
    assert_eq!((&a["alpha"]["type"], &a["alpha"]["raw"]), (&json!("bitmap"), &json!(true)));
    assert_eq!(a["alpha"]["to_uv"], json!([[1.0, 0.0, 0.0], [0.0, -1.0, 1.0]]));
    let b = &s["shapes"][1]["bsdf"];
    assert_eq!((&b["type"], &b["distribution"]), (&json!("roughdielectric"), &json!("beckmann")));
    assert_eq!(b["alpha"]["type"], json!("checkerboard"));
    // Swapped: Mitsuba's checkerboard `eval_1` gives color1 where `eval` gives color0.
    assert_eq!((&b["alpha"]["color0"], &b["alpha"]["color1"]), (&json!(0.45), &json!(0.05)));
    let desc = crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
    match &desc.shapes[1].bsdf {
        crate::scene::desc::BsdfDesc::RoughDielectric(d) => {
            assert!(matches!(d.microfacet.alpha, crate::scene::desc::AlphaDesc::Textured(_)))
        }
        other => panic!("{other:?}"),
    }
}

/// Textured `alpha_u`/`alpha_v` (one may be a number) and textured
/// roughness inside `twosided` (each side its own) convert to JSON texture
/// objects, checkerboards swapped; niebla's parser reads them back.
#[test]
fn textured_anisotropic_and_twosided_alpha_convert() {
    let import = import_with_png(
        r#"<texture type="bitmap" id="r"><string name="filename" value="a.png"/><boolean name="raw" value="true"/></texture>
           <shape type="rectangle"><bsdf type="roughconductor"><string name="material" value="Au"/><ref name="alpha_u" id="r"/>
           <float name="alpha_v" value="0.3"/></bsdf></shape>
           <shape type="rectangle"><bsdf type="twosided">
             <bsdf type="roughconductor"><string name="material" value="Au"/><texture type="checkerboard" name="alpha"><float name="color0" value="0.05"/>
               <float name="color1" value="0.45"/></texture></bsdf>
             <bsdf type="roughconductor"><string name="material" value="Au"/><string name="distribution" value="ggx"/><float name="alpha_u" value="0.2"/>
               <ref name="alpha_v" id="r"/></bsdf></bsdf></shape>"#,
    )
    .unwrap();
    let s = &import.scene;
    let a = &s["shapes"][0]["bsdf"];
    assert_eq!((&a["alpha_u"]["type"], &a["alpha_v"]), (&json!("bitmap"), &json!(0.3)));
    let sides = &s["shapes"][1]["bsdf"]["bsdf"];
    assert_eq!((&sides[0]["alpha"]["color0"], &sides[0]["alpha"]["color1"]), (&json!(0.45), &json!(0.05)));
    assert_eq!((&sides[1]["alpha_u"], &sides[1]["alpha_v"]["type"]), (&json!(0.2), &json!("bitmap")));
    // Anisotropic roughness takes Mitsuba's frame, without a note.
    assert!(!import.notes.iter().any(|n| n.contains("anisotropic")), "{:?}", import.notes);
    assert_eq!((&s["shapes"][0]["tangent_frame"], &s["shapes"][1]["tangent_frame"]), (&json!("dpdu"), &json!("dpdu")));
    let desc = crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
    match &desc.shapes[0].bsdf {
        crate::scene::desc::BsdfDesc::RoughConductor(d) => {
            assert!(matches!(d.microfacet.alpha, crate::scene::desc::AlphaDesc::TexturedAnisotropic(_)))
        }
        other => panic!("{other:?}"),
    }
}

/// Anisotropic roughness takes Mitsuba's frame (`"tangent_frame": "dpdu"`)
/// on every shape (a cube as Mitsuba's own mesh with uvs, a sphere turned by
/// its to_world with its `rotation`), without a note; isotropic roughness
/// sets no key.
#[test]
fn anisotropic_roughness_takes_mitsubas_frame() {
    let import = |shape: &str, to_world: &str, alpha_v: &str| {
        let body = format!(
            "<shape type=\"{shape}\">{to_world}\n<bsdf type=\"roughconductor\"><string name=\"material\" value=\"Au\"/><float name=\"alpha_u\" \
             value=\"0.1\"/><float name=\"alpha_v\" value=\"{alpha_v}\"/></bsdf></shape>"
        );
        let i = import_with_png(&body).unwrap();
        let notes = i.notes.into_iter().filter(|n| n.contains("anisotropic")).collect::<Vec<_>>();
        (i.scene["shapes"][0]["tangent_frame"].clone(), notes)
    };
    let turned = |axis: &str| format!("<transform name=\"to_world\"><rotate {axis}=\"1\" angle=\"40\"/></transform>");
    for (shape, to_world) in
        [("sphere", String::new()), ("rectangle", turned("y")), ("disk", turned("z")), ("rectangle", turned("x"))]
    {
        assert_eq!(import(shape, &to_world, "0.4"), (json!("dpdu"), vec![]), "{shape} {to_world}");
    }
    assert_eq!(import("sphere", "", "0.1").0, serde_json::Value::Null);
    assert_eq!(import("cube", "", "0.4"), (json!("dpdu"), vec![]));
    assert_eq!(import("cube", &turned("x"), "0.4"), (json!("dpdu"), vec![]));
    assert_eq!(import("sphere", &turned("y"), "0.4"), (json!("dpdu"), vec![]));
}

/// A sphere's to_world (uniform scale, rotation, translation) becomes its
/// center, radius and `rotation`: niebla's angles as written when the XML
/// spells the to_world in niebla's order (scale, rotate about x, y, z,
/// translate; here a quarter turn about z), else the to_world's linear part
/// over its scale, row-major (here 2 x an eighth turn about z); both moved
/// by (1, 2, 3) and textured. An unturned sphere has no `rotation`.
#[test]
fn turned_sphere_keeps_its_rotation() {
    let sphere = |rotate: &str| {
        import_with_png(&format!(
            "<shape type=\"sphere\"><point name=\"center\" x=\"1\" y=\"0\" z=\"0\"/><float name=\"radius\" \
             value=\"0.5\"/><transform name=\"to_world\"><scale value=\"2\"/>{rotate}<translate x=\"1\" y=\"2\" \
             z=\"3\"/></transform><bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\"/></bsdf>\
             </shape>"
        ))
        .unwrap()
        .scene
    };
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    let eighth = "<rotate z=\"1\" angle=\"45\"/>";
    let (scene_angles, scene_matrix) = (sphere("<rotate z=\"1\" angle=\"90\"/>"), sphere(&format!("{eighth}{eighth}")));
    let (by_angles, by_matrix) = (&scene_angles["shapes"][0], &scene_matrix["shapes"][0]);
    for s in [by_angles, by_matrix] {
        let center: Vec<f64> = s["center"].as_array().unwrap().iter().map(num).collect();
        for (a, b) in center.iter().zip([1.0, 4.0, 3.0]) {
            assert!((a - b).abs() < 1e-12, "{center:?}");
        }
        assert!((num(&s["radius"]) - 1.0).abs() < 1e-15, "{s}");
    }
    assert_eq!(by_angles["rotation"], json!({"rotate_z": 90.0}));
    let expected = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    for (i, row) in expected.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            assert!((num(&by_matrix["rotation"]["matrix"][i][j]) - x).abs() < 1e-12, "{by_matrix}");
        }
    }
    for (scene, angles) in [(&scene_angles, true), (&scene_matrix, false)] {
        let desc = crate::scene::parse_scene_str(&scene.to_string(), "t").unwrap();
        match &desc.shapes[0].geometry {
            crate::scene::desc::GeometryDesc::Sphere(d) => match d.rotation {
                Some(crate::scene::desc::RotationDesc::Angles(a)) => assert!(angles && a == [0.0, 0.0, 90.0], "{a:?}"),
                Some(crate::scene::desc::RotationDesc::Matrix(_)) => assert!(!angles),
                None => panic!("no rotation"),
            },
            other => panic!("{other:?}"),
        }
    }
    let plain = import(
        "<shape type=\"sphere\"><transform name=\"to_world\"><scale value=\"2\"/><translate x=\"1\"/>\
                        </transform></shape>",
    )
    .unwrap()
    .scene;
    assert!(plain["shapes"][0].get("rotation").is_none(), "{plain}");
}

/// Mitsuba's bitmap reads row `v * height` from the image's top, niebla's
/// `(1 - v) * height`: the imported `to_uv` is Mitsuba's followed by
/// `v -> 1 - v`; Mitsuba's 4x4 `to_uv` contributes rows/columns 0, 1, 3.
#[test]
fn bitmap_textures_convert_with_mitsubas_uv_origin() {
    let s = import_with_png(
        r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
           <string name="filename" value="a.png"/><string name="filter_type" value="nearest"/>
           <string name="wrap_mode" value="mirror"/><boolean name="raw" value="true"/>
           <transform name="to_uv"><scale x="2" y="4"/><translate x="0.5" y="0.25"/></transform>
           </texture></bsdf></shape>"#,
    )
    .unwrap()
    .scene;
    let r = &s["shapes"][0]["bsdf"]["reflectance"];
    assert_eq!(r["type"], json!("bitmap"));
    assert_eq!(r["file"], json!("a.png"));
    assert_eq!((&r["filter"], &r["wrap"], &r["raw"]), (&json!("nearest"), &json!("mirror"), &json!(true)));
    // u' = 2u + 0.5; Mitsuba's v' = 4v + 0.25 becomes niebla's 1 - v' = -4v + 0.75.
    assert_eq!(r["to_uv"], json!([[2.0, 0.0, 0.5], [0.0, -4.0, 0.75]]));
    crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
    // Defaults: bilinear, repeat, sRGB, and the flip alone.
    let s = import_with_png(
        r#"<texture type="bitmap" id="t"><string name="filename" value="a.png"/></texture>
           <shape type="obj"><string name="filename" value="a.png"/>
           <bsdf type="roughconductor"><string name="material" value="Au"/><ref name="specular_reflectance" id="t"/></bsdf>
           </shape>"#,
    )
    .unwrap()
    .scene;
    let shape = &s["shapes"][0];
    // OBJ uvs are flipped on load, as Mitsuba's flip_tex_coords (default true for OBJ).
    assert_eq!(shape["flip_tex_coords"], json!(true));
    let r = &shape["bsdf"]["specular_reflectance"];
    assert_eq!((&r["filter"], &r["wrap"], &r["raw"]), (&json!("bilinear"), &json!("repeat"), &json!(false)));
    assert_eq!(r["to_uv"], json!([[1.0, 0.0, 0.0], [0.0, -1.0, 1.0]]));
    // PLY: Mitsuba's default is no flip.
    let s = import_with_png(
        r#"<shape type="ply"><string name="filename" value="a.png"/>
           <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="a.png"/></texture>
           </bsdf></shape>"#,
    )
    .unwrap()
    .scene;
    assert!(s["shapes"][0].get("flip_tex_coords").is_none());
}

/// Mitsuba's checkerboard: color0 where frac(u) and frac(v) are both below
/// 1/2 or both above (niebla's cells of half a unit: scale 2), defaults 0.4 and 0.2.
#[test]
fn checkerboard_converts_with_its_defaults() {
    let s = import(
        r#"<shape type="sphere"><bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance">
           <transform name="to_uv"><scale x="3" y="5"/></transform></texture></bsdf></shape>"#,
    )
    .unwrap()
    .scene;
    let r = &s["shapes"][0]["bsdf"]["diffuse_reflectance"];
    assert_eq!(
        *r,
        json!({"type": "checkerboard", "color0": 0.4, "color1": 0.2, "scale": [2.0, 2.0],
               "to_uv": [[3.0, 0.0, 0.0], [0.0, 5.0, 0.0]]})
    );
    crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
}

#[test]
fn texture_errors_name_file_line_and_attribute() {
    let tex = |props: &str| {
        format!(
            "<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n<texture type=\"bitmap\" name=\"reflectance\">\n\
             <string name=\"filename\" value=\"a.png\"/>\n{props}</texture></bsdf></shape>"
        )
    };
    let e = import_with_png(&tex("<string name=\"filter_type\" value=\"cubic\"/>")).unwrap_err().to_string();
    assert!(
        e.starts_with("t.xml:11: <texture type=\"bitmap\">: `filter_type` \"cubic\": expected bilinear, nearest"),
        "{e}"
    );
    let e = import_with_png(&tex("<string name=\"wrap_mode\" value=\"tile\"/>")).unwrap_err().to_string();
    assert!(
        e.starts_with("t.xml:11: <texture type=\"bitmap\">: `wrap_mode` \"tile\": expected repeat, mirror, clamp"),
        "{e}"
    );
    let e = import_with_png(&tex("<float name=\"gamma\" value=\"2\"/>")).unwrap_err().to_string();
    assert!(e.starts_with("t.xml:11: <texture type=\"bitmap\">: property `gamma`"), "{e}");
    // A missing image: the texture's line and the file named.
    let e = err("<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n<texture type=\"bitmap\" name=\"reflectance\">\
                 <string name=\"filename\" value=\"missing.png\"/></texture></bsdf></shape>");
    assert!(e.starts_with("t.xml:9: <texture type=\"bitmap\">: file \"missing.png\" not found"), "{e}");
    let e = import_with_png(
        "<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n<texture type=\"mesh_attribute\" \
                             name=\"reflectance\"/></bsdf></shape>",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("t.xml:9: <texture type=\"mesh_attribute\">: not supported"), "{e}");
    // Textured roughness: not on roughplastic (as in Mitsuba 3), whether
    // `alpha` or a texture given with an anisotropic pair; shapes whose uvs
    // are not converted.
    let e = import_with_png(
        "<shape type=\"sphere\"><bsdf type=\"roughplastic\">\n\
                             <texture type=\"checkerboard\" name=\"alpha\"/></bsdf></shape>",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with(
            "t.xml:9: <bsdf type=\"roughplastic\">: `alpha` as <texture type=\"checkerboard\">: a textured \
                       roughness is not supported for roughplastic (its coating tables"
        ),
        "{e}"
    );
    assert!(e.contains("Mitsuba 3 refuses"), "{e}");
    let e = import_with_png(
        "<shape type=\"sphere\"><bsdf type=\"twosided\"><bsdf type=\"roughplastic\">\
                             <float name=\"alpha_u\" value=\"0.1\"/>\n\
                             <texture type=\"checkerboard\" name=\"alpha_v\"/></bsdf></bsdf></shape>",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("t.xml:9: <bsdf type=\"roughplastic\">: `alpha_v` as <texture"), "{e}");
    // A texture and a number for the same roughness.
    let e = import_with_png(
        "<shape type=\"sphere\"><bsdf type=\"roughconductor\">\n<float name=\"alpha_u\" value=\"0.1\"/>\
                             <texture type=\"checkerboard\" name=\"alpha\"/></bsdf></shape>",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("<bsdf type=\"roughconductor\">: give `alpha`, or both `alpha_u` and `alpha_v`"), "{e}");
}

/// A `roughconductor` without `material`, `eta` and `k` (or with material
/// "none", or `eta` or `k` alone) is Mitsuba's default, `eta` 0 and `k` 1
/// (Fresnel 1): it converts to a JSON rough conductor with those keys left
/// out, which niebla's parser reads with the same defaults; `material` with
/// `eta` is refused (as Mitsuba does). The smooth `conductor` without an
/// index is the same mirror, written with both keys (its JSON needs both).
#[test]
fn roughconductor_without_an_index_is_mitsubas_perfect_mirror() {
    use crate::scene::desc::{BsdfDesc, ColorDesc, ConductorDesc};
    let index = |inner: &str| {
        let s = import(&format!("<shape type=\"sphere\"><bsdf type=\"roughconductor\">{inner}</bsdf></shape>"))
            .unwrap()
            .scene;
        let desc = crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
        match &desc.shapes[0].bsdf {
            BsdfDesc::RoughConductor(d) => d.conductor,
            other => panic!("{other:?}"),
        }
    };
    let mirror = ConductorDesc::Index { eta: ColorDesc::Gray(0.0), k: ColorDesc::Gray(1.0) };
    assert_eq!(index(""), mirror);
    assert_eq!(index(r#"<string name="material" value="none"/>"#), mirror);
    assert_eq!(
        index(r#"<float name="eta" value="0.5"/>"#),
        ConductorDesc::Index { eta: ColorDesc::Gray(0.5), k: ColorDesc::Gray(1.0) }
    );
    let both = err(r#"<shape type="sphere"><bsdf type="roughconductor"><string name="material" value="Au"/>
        <float name="eta" value="0.5"/></bsdf></shape>"#);
    assert!(both.contains("not both"), "{both}");
    let smooth = |inner: &str| {
        let s =
            import(&format!("<shape type=\"sphere\"><bsdf type=\"conductor\">{inner}</bsdf></shape>")).unwrap().scene;
        let desc = crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
        match &desc.shapes[0].bsdf {
            BsdfDesc::Conductor(d) => *d,
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(smooth(""), mirror);
    assert_eq!(smooth(r#"<string name="material" value="none"/>"#), mirror);
    assert_eq!(
        smooth(r#"<float name="k" value="2"/>"#),
        ConductorDesc::Index { eta: ColorDesc::Gray(0.0), k: ColorDesc::Gray(2.0) }
    );
    let both = err(r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Au"/>
        <float name="k" value="2"/></bsdf></shape>"#);
    assert!(both.contains("not both"), "{both}");
    // A zero index (eta and k both 0) would divide by zero in the Fresnel
    // term: the JSON check refuses it for both conductors, naming the field.
    for t in ["conductor", "roughconductor"] {
        let s = import(&format!(
            "<shape type=\"sphere\"><bsdf type=\"{t}\"><float name=\"eta\" value=\"0\"/>\
             <float name=\"k\" value=\"0\"/></bsdf></shape>"
        ))
        .unwrap()
        .scene;
        let e = crate::scene::parse_scene_str(&s.to_string(), "t").unwrap_err();
        assert_eq!(e.path, "shapes[0].bsdf.k", "{e:?}");
        assert!(e.message.contains("both 0"), "{e:?}");
    }
}

/// Mitsuba's cube as `mi.traverse` gives it (the table written by
/// `scripts/mitsuba_refs.py --cube` with Mitsuba 3.9.1): a cube whose
/// surface reads uvs (a texture, or anisotropic roughness, also inside
/// `twosided`) imports as that mesh, vertex for vertex (exact: all entries
/// are 0 or +-1), placed by its to_world and flipped by `flip_normals`; a
/// cube with a plain surface stays a box (axis-aligned) or 12 triangles.
#[test]
fn cube_with_uvs_is_mitsubas_mesh() {
    let table: serde_json::Value =
        serde_json::from_str(include_str!("../../../tests/data/mitsuba_cube.json")).expect("the cube table");
    let bsdfs = [
        r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf>"#,
        r#"<bsdf type="twosided"><bsdf type="roughconductor"><float name="alpha_u" value="0.1"/>
           <float name="alpha_v" value="0.3"/></bsdf></bsdf>"#,
    ];
    for bsdf in bsdfs {
        for (to_world, flip) in [
            ("", ""),
            (
                "<transform name=\"to_world\"><rotate x=\"1\" angle=\"30\"/></transform>",
                "<boolean name=\"flip_normals\" value=\"true\"/>",
            ),
        ] {
            let s = import(&format!("<shape type=\"cube\">{to_world}{flip}{bsdf}</shape>")).unwrap().scene;
            let shape = &s["shapes"][0];
            assert_eq!(shape["type"], json!("mesh"), "{bsdf}");
            for (ours, theirs) in [
                ("positions", "vertex_positions"),
                ("normals", "vertex_normals"),
                ("uvs", "vertex_texcoords"),
                ("indices", "faces"),
            ] {
                let a: Vec<f64> = shape[ours]
                    .as_array()
                    .unwrap()
                    .iter()
                    .flat_map(|v| v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
                    .collect();
                let b: Vec<f64> = table[theirs]
                    .as_array()
                    .unwrap()
                    .iter()
                    .flat_map(|v| v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
                    .collect();
                assert_eq!(a, b, "{ours} vs Mitsuba's {theirs}");
            }
            assert_eq!(shape["flip_normals"].as_bool().unwrap_or(false), !flip.is_empty());
            crate::scene::parse_scene_str(&s.to_string(), "t").unwrap();
        }
    }
    // A plain surface: a box, or 12 triangles without uvs.
    let plain =
        import(r#"<shape type="cube"><bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></shape>"#)
            .unwrap()
            .scene;
    assert_eq!(plain["shapes"][0]["type"], json!("box"));
    let turned =
        import(r#"<shape type="cube"><transform name="to_world"><rotate x="1" angle="30"/></transform></shape>"#)
            .unwrap()
            .scene;
    assert_eq!(turned["shapes"][0]["indices"].as_array().unwrap().len(), 12);
    assert!(turned["shapes"][0].get("uvs").is_none());
}

/// `<rotate>` uses its axis as written, as Mitsuba 3.9.1 does (no
/// normalization): a cube turned about `(1, 1, 0.3)` by 40 degrees has
/// Mitsuba's vertices (`rotated_cube_positions` of the cube table, f32)
/// within 1e-6; only exact unit axes become niebla's `rotate_x/y/z`.
#[test]
fn rotate_keeps_a_non_unit_axis_as_mitsuba() {
    let table: serde_json::Value =
        serde_json::from_str(include_str!("../../../tests/data/mitsuba_cube.json")).expect("the cube table");
    let s = import(
        r#"<shape type="cube"><transform name="to_world"><rotate x="1" y="1" z="0.3" angle="40"/></transform>
           <bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></shape>"#,
    )
    .unwrap()
    .scene;
    let shape = &s["shapes"][0];
    let m: Vec<Vec<f64>> = serde_json::from_value(shape["to_world"]["matrix"].clone()).unwrap();
    let positions: Vec<[f64; 3]> = serde_json::from_value(shape["positions"].clone()).unwrap();
    let expected: Vec<[f64; 3]> = serde_json::from_value(table["rotated_cube_positions"].clone()).unwrap();
    for (p, e) in positions.iter().zip(&expected) {
        let q: Vec<f64> = (0..3).map(|i| (0..3).map(|j| m[i][j] * p[j]).sum::<f64>() + m[i][3]).collect();
        for i in 0..3 {
            assert!((q[i] - e[i]).abs() < 1e-6, "{q:?} vs Mitsuba's {e:?}");
        }
    }
    let placed = |axis: &str| {
        import(&format!(
            r#"<shape type="rectangle"><transform name="to_world"><rotate {axis} angle="30"/></transform></shape>"#
        ))
        .unwrap()
        .scene["shapes"][0]["to_world"]
            .clone()
    };
    assert_eq!(placed(r#"y="1""#), json!({"rotate_y": 30.0}));
    assert!(placed(r#"y="2""#).get("matrix").is_some());
}

/// An `area` emitter on an `obj` becomes a mesh light (Mitsuba's normals
/// computed where the file has none); on one whose triangles have no area
/// it is an error at the shape's line; a `cube` emitter is a 12-triangle
/// mesh light (not a box).
#[test]
fn emitting_meshes_become_mesh_lights() {
    let dir = std::env::temp_dir().join(format!("niebla_mitsuba_meshemit_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let run = |shape: &str| {
        let text = format!("<scene version=\"3.0.0\">\n{SENSOR}\n{shape}\n</scene>");
        import_mitsuba_str(&text, "t.xml", &dir, &[])
    };
    let s =
        run(r#"<shape type="obj"><string name="filename" value="tri.obj"/><boolean name="flip_normals" value="true"/>
        <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>"#)
        .unwrap()
        .scene;
    let light = &s["lights"][0];
    assert_eq!(light["type"], json!("area"));
    assert_eq!(light["radiance"], json!([1.0, 2.0, 3.0]));
    assert_eq!(light["shape"]["type"], json!("mesh"));
    assert_eq!(light["shape"]["flip_normals"], json!(true));
    assert_eq!(light["shape"]["compute_normals"], json!(true));
    assert!(s["shapes"].as_array().is_none_or(|a| a.is_empty()));
    crate::scene::build_scene(&crate::scene::parse_scene_str(&s.to_string(), "t").unwrap(), "t", &dir).unwrap();
    let e = run(r#"<shape type="obj"><string name="filename" value="flat.obj"/>
        <emitter type="area"/></shape>"#)
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("t.xml:8: <shape type=\"obj\">") && e.contains("positive area") && e.contains("flat.obj"),
        "{e}"
    );
    let s = run(r#"<shape type="cube"><emitter type="area"/></shape>"#).unwrap().scene;
    assert_eq!(s["lights"][0]["shape"]["type"], json!("mesh"));
    assert_eq!(s["lights"][0]["shape"]["indices"].as_array().unwrap().len(), 12);
    let _ = std::fs::remove_dir_all(&dir);
}
