//! Scene files: a valid scene parses, and every bad input is an error that
//! names the file, the exact JSON path and what was expected, never a panic.
//!
//! Each error test takes the valid scene [`FULL`], changes one thing in its
//! text and checks the error's `file`, `path` and message.

use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::scene::{
    load_scene_file, parse_scene_str, BoundsDesc, BsdfDesc, CameraDesc, CoefficientsDesc, ColorDesc, DensitySourceDesc,
    GeometryDesc, GridEmissionDesc, GridMediumDesc, IntegratorSpec, LightDesc, MediumDesc, PhaseDesc, ProceduralDesc,
    ProceduralShapeDesc, ResolutionDesc, SceneDesc, SceneError, SchlickDesc, SpotAimDesc, TransformDesc,
};
use niebla::tracking::{MarchStep, TransmittanceMethod};

const FILE: &str = "test.json";

/// A valid scene using most of the schema.
const FULL: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0],
             "up": [0, 1, 0], "fov_y": 35, "width": 64, "height": 48},
  "render": {"integrator": {"type": "single", "step": 0.05, "sampling": "mis",
                            "transmittance": "analytic"},
             "spp": 4, "seed": 7, "exposure": 0.5},
  "media": {
    "fog": {"sigma_a": 0.01, "sigma_s": [0.08, 0.09, 0.1], "phase": {"type": "isotropic"}},
    "smoke": {"type": "homogeneous", "sigma_t": 3, "albedo": 0.8, "scale": 2,
              "phase": {"type": "hg", "g": 0.3}, "emission": {"L_ve": [0.1, 0.05, 0.01]}},
    "haze": {"sigma_a": 0, "sigma_s": 0.2,
             "phase": {"type": "double_hg", "w": 0.7, "g1": 0.8, "g2": -0.3}},
    "mist": {"sigma_a": 0, "sigma_s": 0.2, "phase": {"type": "schlick", "k": 0.5}},
    "cloud": {"sigma_t": [1, 2, 3], "albedo": [0.9, 0.95, 1],
              "phase": {"type": "tabulated", "file": "mie.csv"}}
  },
  "shapes": [
    {"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "interior": "smoke"},
    {"type": "sphere", "center": [0, 1, 0], "radius": 0.5, "interior": "haze", "exterior": "smoke"},
    {"type": "rectangle", "to_world": {"translate": [0, 0, 0], "scale": 10, "rotate_x": -90},
     "bsdf": {"type": "diffuse", "reflectance": 0.5}},
    {"type": "rectangle", "interior": "mist",
     "to_world": {"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]]}}
  ],
  "lights": [
    {"type": "directional", "direction": [-0.3, -1, -0.2], "irradiance": 3.0},
    {"type": "point", "position": [2, 3, 1], "intensity": [50, 45, 40]},
    {"type": "spot", "position": [0, 3, 0], "target": [0, 0, 0], "intensity": 100,
     "cutoff_angle": 30},
    {"type": "constant", "radiance": [0.05, 0.07, 0.1]}
  ],
  "ambient_medium": "fog"
}"#;

/// `FULL` with the one occurrence of `from` replaced by `to`.
fn edit(from: &str, to: &str) -> String {
    assert_eq!(FULL.matches(from).count(), 1, "`{from}` must occur once in FULL");
    FULL.replacen(from, to, 1)
}

/// Parses `text`, expects an error at `path` whose message contains
/// `expected`, and checks the file name and the Display form.
#[track_caller]
fn assert_error(text: &str, path: &str, expected: &str) -> SceneError {
    let err = match parse_scene_str(text, FILE) {
        Ok(_) => panic!("expected an error at `{path}`, but the scene parsed"),
        Err(e) => e,
    };
    assert_eq!(err.file, FILE, "{err}");
    assert_eq!(err.path, path, "{err}");
    assert!(err.message.contains(expected), "message of `{err}` lacks `{expected}`");
    let shown = err.to_string();
    if path.is_empty() {
        assert_eq!(shown, format!("{FILE}: {}", err.message));
    } else {
        assert_eq!(shown, format!("{FILE}: {path}: {}", err.message));
    }
    err
}

// ---------------------------------------------------------------------------
// The valid scene
// ---------------------------------------------------------------------------

#[test]
fn full_scene_parses_with_defaults_filled_in() {
    let desc = parse_scene_str(FULL, FILE).unwrap();
    let CameraDesc::Perspective(camera) = &desc.camera;
    assert_eq!((camera.width, camera.height, camera.fov_y), (64, 48, 35.0));
    assert_eq!(desc.render.spp, 4);
    assert_eq!(desc.render.seed, 7);
    match desc.render.integrator.settings {
        IntegratorSettings::Single { step, sampling, .. } => {
            assert_eq!(step, Some(MarchStep::Length(0.05)));
            assert_eq!(sampling, SingleSampling::Mis);
        }
        other => panic!("wrong integrator {other:?}"),
    }
    assert_eq!(desc.media.len(), 5);
    let MediumDesc::Homogeneous(smoke) = &desc.media["smoke"] else { panic!("smoke is homogeneous") };
    assert_eq!(
        smoke.coefficients,
        CoefficientsDesc::ExtinctionAlbedo { sigma_t: ColorDesc::Gray(3.0), albedo: ColorDesc::Gray(0.8) }
    );
    let (sigma_a, sigma_s) = smoke.sigma_a_sigma_s();
    assert!((sigma_s.r() - 4.8).abs() < 1e-5 && (sigma_a.g() - 1.2).abs() < 1e-5);
    assert_eq!(smoke.phase, PhaseDesc::HenyeyGreenstein { g: 0.3 });
    let MediumDesc::Homogeneous(fog) = &desc.media["fog"] else { panic!("fog is homogeneous") };
    assert_eq!(fog.scale, 1.0);
    assert_eq!(fog.emission, None);
    let MediumDesc::Homogeneous(mist) = &desc.media["mist"] else { panic!("mist is homogeneous") };
    assert_eq!(mist.phase, PhaseDesc::Schlick(SchlickDesc::K(0.5)));
    let MediumDesc::Homogeneous(cloud) = &desc.media["cloud"] else { panic!("cloud is homogeneous") };
    assert_eq!(cloud.phase, PhaseDesc::Tabulated { file: "mie.csv".into(), column: "p_mie_poly".into() });

    assert_eq!(desc.shapes.len(), 4);
    assert_eq!(desc.shapes[0].bsdf, BsdfDesc::Null);
    assert_eq!(desc.shapes[1].exterior.as_deref(), Some("smoke"));
    match &desc.shapes[2].geometry {
        GeometryDesc::Rectangle(r) => assert_eq!(
            r.to_world,
            TransformDesc::Components {
                scale: [10.0; 3],
                rotate_x: -90.0,
                rotate_y: 0.0,
                rotate_z: 0.0,
                translate: [0.0; 3]
            }
        ),
        other => panic!("wrong shape {other:?}"),
    }
    assert!(matches!(
        &desc.shapes[3].geometry,
        GeometryDesc::Rectangle(r) if matches!(r.to_world, TransformDesc::Matrix(_))
    ));
    match &desc.lights[2] {
        LightDesc::Spot(s) => {
            assert_eq!(s.aim, SpotAimDesc::Target([0.0; 3]));
            assert_eq!((s.cutoff_angle, s.beam_width), (30.0, 22.5));
        }
        other => panic!("wrong light {other:?}"),
    }
    assert_eq!(desc.ambient_medium.as_deref(), Some("fog"));
}

#[test]
fn minimal_scene_gets_documented_defaults() {
    let text = r#"{"version": 1, "camera": {"type": "perspective", "position": [0, 0, 5],
                   "target": [0, 0, 0], "width": 8, "height": 8}}"#;
    let desc = parse_scene_str(text, FILE).unwrap();
    let CameraDesc::Perspective(camera) = &desc.camera;
    assert_eq!((camera.up, camera.fov_y), ([0.0, 1.0, 0.0], 40.0));
    assert_eq!((desc.render.spp, desc.render.seed, desc.render.exposure), (16, 0, 0.0));
    assert_eq!(desc.render.integrator, IntegratorSpec::default());
    assert!(desc.media.is_empty() && desc.shapes.is_empty() && desc.lights.is_empty());
    assert_eq!(desc.ambient_medium, None);
}

#[test]
fn scene_file_loads_from_disk() {
    let path = std::env::temp_dir().join(format!("niebla_scene_{}.json", std::process::id()));
    std::fs::write(&path, FULL).unwrap();
    let loaded = load_scene_file(&path);
    std::fs::remove_file(&path).ok();
    assert_eq!(loaded.unwrap(), parse_scene_str(FULL, FILE).unwrap());
}

// ---------------------------------------------------------------------------
// Unknown keys
// ---------------------------------------------------------------------------

#[test]
fn unknown_top_level_key_names_the_key() {
    let text = edit(r#""ambient_medium": "fog""#, r#""ambient_medium": "fog", "ambient_mediun": 1"#);
    assert_error(&text, "ambient_mediun", "unknown field `ambient_mediun`, expected one of");
}

#[test]
fn unknown_medium_key_names_the_key() {
    let text = edit(r#""sigma_s": [0.08"#, r#""sigam_s": [0.08"#);
    let err = assert_error(&text, "media.fog.sigam_s", "unknown field `sigam_s`");
    assert!(err.message.contains("`sigma_s`"), "{err}");
}

#[test]
fn unknown_light_key_names_the_key() {
    let text = edit(r#""intensity": [50"#, r#""intensty": [50"#);
    assert_error(&text, "lights[1].intensty", "unknown field `intensty`");
}

#[test]
fn unknown_phase_key_names_the_key() {
    let text = edit(r#""g": 0.3"#, r#""g": 0.3, "gg": 1"#);
    assert_error(&text, "media.smoke.phase.gg", "unknown field `gg`, expected `g`");
    let text = edit(r#"{"type": "isotropic"}"#, r#"{"type": "isotropic", "g": 0}"#);
    assert_error(&text, "media.fog.phase.g", "unknown field `g`; this type has no fields besides `type`");
}

#[test]
fn unknown_keys_in_camera_render_integrator_and_emission_name_the_key() {
    let text = edit(r#""fov_y": 35"#, r#""fovy": 35"#);
    assert_error(&text, "camera.fovy", "unknown field `fovy`");
    let text = edit(r#""spp": 4"#, r#""spp": 4, "max_depth": 3"#);
    assert_error(&text, "render.max_depth", "unknown field `max_depth`");
    let text = edit(r#""sampling": "mis""#, r#""sampling": "mis", "sampels": 1"#);
    assert_error(&text, "render.integrator.sampels", "unknown field `sampels`");
    let text = edit(r#""L_ve""#, r#""L_e""#);
    assert_error(&text, "media.smoke.emission.L_e", "unknown field `L_e`, expected `L_ve`");
}

#[test]
fn unknown_keys_in_shapes_list_the_common_fields_too() {
    let text = edit(r#""interior": "smoke"}"#, r#""interor": "smoke"}"#);
    let err = assert_error(&text, "shapes[0].interor", "unknown field `interor`");
    assert!(err.message.contains("`interior`"), "{err}");
}

#[test]
fn unknown_keys_two_tagged_levels_deep_keep_the_full_path() {
    let text = edit(r#""reflectance": 0.5"#, r#""reflectanse": 0.5"#);
    assert_error(&text, "shapes[2].bsdf.reflectanse", "unknown field `reflectanse`");
    let text = edit(r#""rotate_x": -90"#, r#""rotate": -90"#);
    assert_error(&text, "shapes[2].to_world.rotate", "unknown field `rotate`");
}

#[test]
fn duplicate_key_is_an_error_at_its_path() {
    let text = edit(r#""radius": 0.5"#, r#""radius": 0.5, "radius": 2"#);
    assert_error(&text, "shapes[1].radius", "duplicate key `radius`");
}

// ---------------------------------------------------------------------------
// Wrong types and shapes of values
// ---------------------------------------------------------------------------

#[test]
fn string_where_number_expected_names_the_element() {
    let text = edit("[50, 45, 40]", r#"[50, 45, "40"]"#);
    assert_error(&text, "lights[1].intensity[2]", "expected a number");
    let text = edit(r#""fov_y": 35"#, r#""fov_y": "wide""#);
    assert_error(&text, "camera.fov_y", "invalid type: string \"wide\", expected a number");
    let text = edit(r#""radius": 0.5"#, r#""radius": "0.5""#);
    assert_error(&text, "shapes[1].radius", "expected a number");
}

#[test]
fn two_element_vector_is_rejected() {
    let text = edit(r#""position": [0, 1, 4]"#, r#""position": [0, 1]"#);
    assert_error(&text, "camera.position", "invalid length 2, expected an array of 3 numbers");
    let text = edit(r#""translate": [0, 0, 0]"#, r#""translate": [0, 0, 0, 0]"#);
    assert_error(&text, "shapes[2].to_world.translate", "invalid length 4");
}

#[test]
fn two_element_color_is_rejected() {
    let text = edit("[0.08, 0.09, 0.1]", "[0.08, 0.09]");
    assert_error(&text, "media.fog.sigma_s", "invalid length 2, expected a number or an array of 3 numbers");
}

#[test]
fn object_where_array_expected_is_rejected() {
    let text = edit(r#""intensity": 100"#, r#""intensity": {"r": 100}"#);
    assert_error(&text, "lights[2].intensity", "invalid type: map, expected a number or an array of 3 numbers");
    let text = edit(r#""center": [0, 1, 0]"#, r#""center": {"x": 0}"#);
    assert_error(&text, "shapes[1].center", "expected an array of 3 numbers");
    let text = r#"{"version": 1, "camera": {"type": "perspective", "position": [0, 0, 5],
                  "target": [0, 0, 0], "width": 8, "height": 8}, "lights": {"type": "point"}}"#;
    assert_error(text, "lights", "invalid type: map, expected a sequence");
}

#[test]
fn scalar_where_object_expected_is_rejected() {
    let text = edit(r#""phase": {"type": "hg", "g": 0.3}"#, r#""phase": 0.3"#);
    assert_error(&text, "media.smoke.phase", "expected a phase function object");
}

#[test]
fn fractional_or_negative_pixel_counts_are_rejected() {
    let text = edit(r#""width": 64"#, r#""width": 64.5"#);
    assert_error(&text, "camera.width", "expected a whole number");
    let text = edit(r#""width": 64"#, r#""width": -64"#);
    assert_error(&text, "camera.width", "expected a whole number");
}

// ---------------------------------------------------------------------------
// Medium names
// ---------------------------------------------------------------------------

#[test]
fn unknown_interior_medium_lists_known_media() {
    let text = edit(r#""interior": "mist""#, r#""interior": "fgo""#);
    assert_error(&text, "shapes[3].interior", r#"unknown medium "fgo"; known media: cloud, fog, haze, mist, smoke"#);
}

#[test]
fn unknown_exterior_medium_lists_known_media() {
    let text = edit(r#""exterior": "smoke""#, r#""exterior": "smok""#);
    assert_error(&text, "shapes[1].exterior", r#"unknown medium "smok"; known media:"#);
}

#[test]
fn unknown_ambient_medium_lists_known_media() {
    let text = edit(r#""ambient_medium": "fog""#, r#""ambient_medium": "vapor""#);
    assert_error(&text, "ambient_medium", r#"unknown medium "vapor"; known media: cloud"#);
}

// ---------------------------------------------------------------------------
// Value ranges
// ---------------------------------------------------------------------------

#[test]
fn negative_coefficient_channel_names_the_channel() {
    let text = edit("[0.08, 0.09, 0.1]", "[0.08, 0.09, -0.1]");
    assert_error(&text, "media.fog.sigma_s[2]", "must be >= 0, got -0.1");
}

#[test]
fn negative_scalar_coefficient_names_the_field() {
    let text = edit(r#""sigma_a": 0.01"#, r#""sigma_a": -0.01"#);
    assert_error(&text, "media.fog.sigma_a", "must be >= 0, got -0.01");
    let text = edit(r#""sigma_t": 3"#, r#""sigma_t": -3"#);
    assert_error(&text, "media.smoke.sigma_t", "must be >= 0");
}

#[test]
fn albedo_above_one_is_rejected() {
    let text = edit(r#""albedo": 0.8"#, r#""albedo": 1.5"#);
    assert_error(&text, "media.smoke.albedo", "must be in [0, 1], got 1.5");
    let text = edit("[0.9, 0.95, 1]", "[0.9, 0.95, 1.01]");
    assert_error(&text, "media.cloud.albedo[2]", "must be in [0, 1]");
}

#[test]
fn asymmetry_outside_open_interval_is_rejected() {
    let text = edit(r#""g": 0.3"#, r#""g": 1"#);
    assert_error(&text, "media.smoke.phase.g", "must be in the open interval (-1, 1), got 1");
    let text = edit(r#""g": 0.3"#, r#""g": -1.5"#);
    assert_error(&text, "media.smoke.phase.g", "got -1.5");
    let text = edit(r#""g2": -0.3"#, r#""g2": -1"#);
    assert_error(&text, "media.haze.phase.g2", "open interval (-1, 1)");
    let text = edit(r#""w": 0.7"#, r#""w": 1.2"#);
    assert_error(&text, "media.haze.phase.w", "must be in [0, 1]");
    let text = edit(r#""k": 0.5"#, r#""k": 1"#);
    assert_error(&text, "media.mist.phase.k", "open interval (-1, 1)");
}

#[test]
fn non_positive_scale_is_rejected() {
    let text = edit(r#""scale": 2"#, r#""scale": 0"#);
    assert_error(&text, "media.smoke.scale", "must be > 0");
}

#[test]
fn zero_width_is_rejected() {
    let text = edit(r#""width": 64"#, r#""width": 0"#);
    assert_error(&text, "camera.width", "must be at least 1 pixel");
}

#[test]
fn absurd_resolution_names_the_field_and_the_limit() {
    let text = edit(r#""width": 64"#, r#""width": 100000"#);
    assert_error(&text, "camera.width", "must be at most 16384 pixels, got 100000");
    let text = edit(r#""height": 48"#, r#""height": 10000000000"#);
    assert_error(&text, "camera.height", "expected a whole number from 0 to 4294967295");
    let text = edit(r#""width": 64, "height": 48"#, r#""width": 16384, "height": 16384"#);
    assert_error(&text, "camera", "exceeds the limit of 67108864 (2^26) pixels");
}

#[test]
fn degenerate_camera_is_rejected() {
    let text = edit(r#""target": [0, 1, 0],"#, r#""target": [0, 1, 4],"#);
    assert_error(&text, "camera.target", "must differ from `position`");
    let text = edit(r#""up": [0, 1, 0]"#, r#""up": [0, 0, -2]"#);
    assert_error(&text, "camera.up", "must not be parallel to the view direction");
    let text = edit(r#""fov_y": 35"#, r#""fov_y": 180"#);
    assert_error(&text, "camera.fov_y", "(0, 180)");
}

#[test]
fn non_finite_numbers_are_rejected_with_their_path() {
    // Beyond f64: serde_json refuses it while parsing; the scanner finds the path.
    let text = edit("[50, 45, 40]", "[50, 1e400, 40]");
    let err = assert_error(&text, "lights[1].intensity[1]", "number out of range");
    assert!(err.message.contains("line"), "{err}");
    // Beyond f32: reads as infinite and fails validation.
    let text = edit(r#""radius": 0.5"#, r#""radius": 1e39"#);
    assert_error(&text, "shapes[1].radius", "expected a finite number");
    let text = edit(r#""exposure": 0.5"#, r#""exposure": -1e300"#);
    assert_error(&text, "render.exposure", "expected a finite number");
}

#[test]
fn degenerate_shapes_are_rejected() {
    let text = edit(r#""max": [1, 2, 1]"#, r#""max": [1, 0, 1]"#);
    assert_error(&text, "shapes[0].max[1]", "must be greater than min[1] = 0");
    let text = edit(r#""radius": 0.5"#, r#""radius": 0"#);
    assert_error(&text, "shapes[1].radius", "must be > 0");
    let text = edit(r#""scale": 10"#, r#""scale": 0"#);
    assert_error(&text, "shapes[2].to_world.scale", "non-zero");
    let text = edit("[0, 0, 0, 1]]", "[0, 0, 1, 1]]");
    assert_error(&text, "shapes[3].to_world.matrix[3]", "last row must be [0, 0, 0, 1]");
    let text = edit(r#""reflectance": 0.5"#, r#""reflectance": [0.5, 1.2, 0.5]"#);
    assert_error(&text, "shapes[2].bsdf.reflectance[1]", "must be in [0, 1]");
}

#[test]
fn invalid_lights_are_rejected() {
    let text = edit(r#""cutoff_angle": 30"#, r#""cutoff_angle": 30, "beam_width": 40"#);
    assert_error(&text, "lights[2].beam_width", "must be in (0, cutoff_angle = 30]");
    let text = edit(r#""cutoff_angle": 30"#, r#""cutoff_angle": 120"#);
    assert_error(&text, "lights[2].cutoff_angle", "(0, 90]");
    let text = edit("[-0.3, -1, -0.2]", "[0, 0, 0]");
    assert_error(&text, "lights[0].direction", "non-zero");
    let text = edit(r#""irradiance": 3.0"#, r#""irradiance": -3.0"#);
    assert_error(&text, "lights[0].irradiance", "must be >= 0");
}

#[test]
fn non_positive_step_is_rejected() {
    let text = edit(r#""step": 0.05"#, r#""step": 0"#);
    assert_error(&text, "render.integrator.step", "must be > 0, got 0");
    let text = edit(r#""step": 0.05"#, r#""step": -1"#);
    assert_error(&text, "render.integrator.step", "must be > 0, got -1");
    let text = edit(r#""step": 0.05"#, r#""steps": 0"#);
    assert_error(&text, "render.integrator.steps", "must be at least 1");
}

#[test]
fn zero_spp_is_rejected() {
    let text = edit(r#""spp": 4"#, r#""spp": 0"#);
    assert_error(&text, "render.spp", "at least 1");
}

// ---------------------------------------------------------------------------
// Missing and conflicting fields
// ---------------------------------------------------------------------------

#[test]
fn missing_camera_is_reported_at_camera() {
    assert_error(r#"{"version": 1}"#, "camera", "missing required field `camera`");
}

#[test]
fn missing_required_field_in_a_tagged_object_names_it() {
    let text = edit(r#", "radius": 0.5"#, "");
    assert_error(&text, "shapes[1].radius", "missing required field `radius`");
    let text = edit(r#"{"type": "constant", "radiance": [0.05, 0.07, 0.1]}"#, r#"{"radiance": 1}"#);
    assert_error(&text, "lights[3].type", "missing required field `type`; expected one of: point");
}

#[test]
fn unsupported_version_is_rejected() {
    let text = edit(r#""version": 1"#, r#""version": 2"#);
    assert_error(&text, "version", "unsupported scene version 2");
    let text = edit(r#""version": 1"#, r#""version": "1""#);
    assert_error(&text, "version", "expected a whole number");
    let text = edit(r#""version": 1,"#, "");
    assert_error(&text, "version", "missing required field `version`");
}

#[test]
fn unknown_types_list_the_valid_ones() {
    let text = edit(r#""type": "box""#, r#""type": "cylinder""#);
    assert_error(&text, "shapes[0].type", r#"unknown shape type "cylinder"; expected one of: sphere, box, rectangle"#);
    let text = edit(r#""type": "point""#, r#""type": "laser""#);
    assert_error(
        &text,
        "lights[1].type",
        r#"unknown light type "laser"; expected one of: point, spot, directional, constant"#,
    );
    let text = edit(r#""type": "hg""#, r#""type": "mie""#);
    assert_error(
        &text,
        "media.smoke.phase.type",
        r#"unknown phase function type "mie"; expected one of: isotropic, hg,"#,
    );
    let text = edit(r#""type": "single""#, r#""type": "bidirectional""#);
    let err =
        assert_error(&text, "render.integrator.type", r#"unknown integrator type "bidirectional"; expected one of: "#);
    for name in niebla::integrator::registry::NAMES {
        assert!(err.message.contains(name), "{err} does not list {name}");
    }
    let text = edit(r#""type": "homogeneous""#, r#""type": "foam""#);
    assert_error(&text, "media.smoke.type", r#"unknown medium type "foam"; expected one of: homogeneous, grid"#);
    let text = edit(r#""type": "diffuse""#, r#""type": "plastic""#);
    assert_error(&text, "shapes[2].bsdf.type", r#"unknown bsdf type "plastic""#);
    let text = edit(r#""type": "perspective""#, r#""type": "orthographic""#);
    assert_error(&text, "camera.type", r#"unknown camera type "orthographic""#);
    let text = edit(r#""sampling": "mis""#, r#""sampling": "importance""#);
    assert_error(
        &text,
        "render.integrator.sampling",
        "unknown value `importance`, expected one of `march`, `equiangular`, `mis`",
    );
}

#[test]
fn both_coefficient_forms_are_rejected() {
    let text = edit(r#""sigma_t": 3"#, r#""sigma_t": 3, "sigma_a": 1"#);
    assert_error(&text, "media.smoke.sigma_t", "`sigma_t` cannot be combined with `sigma_a`");
}

#[test]
fn half_a_coefficient_form_names_the_missing_field() {
    let text = edit(r#", "sigma_s": [0.08, 0.09, 0.1]"#, "");
    assert_error(&text, "media.fog.sigma_s", "missing required field `sigma_s`, which goes with `sigma_a`");
    let text = edit(r#""albedo": 0.8, "#, "");
    assert_error(&text, "media.smoke.albedo", "missing required field `albedo`");
    let text = edit(r#""sigma_a": 0.01, "sigma_s": [0.08, 0.09, 0.1], "#, "");
    assert_error(&text, "media.fog", "missing coefficients");
}

#[test]
fn step_and_steps_together_are_rejected() {
    let text = edit(r#""step": 0.05"#, r#""step": 0.05, "steps": 8"#);
    assert_error(&text, "render.integrator.steps", "mutually exclusive");
}

#[test]
fn other_exclusive_pairs_are_rejected() {
    let text =
        edit(r#""target": [0, 0, 0], "intensity""#, r#""target": [0, 0, 0], "direction": [0, -1, 0], "intensity""#);
    assert_error(&text, "lights[2].direction", "mutually exclusive");
    let text = edit(r#""k": 0.5"#, r#""k": 0.5, "g": 0.2"#);
    assert_error(&text, "media.mist.phase.g", "mutually exclusive");
    let text = edit(r#"{"matrix""#, r#"{"translate": [1, 0, 0], "matrix""#);
    assert_error(&text, "shapes[3].to_world.translate", "cannot be combined with `matrix`");
}

// ---------------------------------------------------------------------------
// Grid media
// ---------------------------------------------------------------------------

/// A valid scene with grid media, one per density source, and every form of
/// grid emission.
const GRID: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 6], "target": [0, 1, 0],
             "width": 32, "height": 32},
  "render": {"integrator": {"type": "emission", "steps": 32, "transmittance": "residual_ratio"}},
  "media": {
    "smoke": {"type": "grid",
              "density": {"type": "grid", "data": [0, 0.5, 1, 2, 0, 0, 0, 3], "dims": [2, 2, 2],
                          "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}},
              "sigma_t": 30, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3},
              "to_world": {"translate": [0, 1, 0], "scale": 2},
              "emission": {"temperature": {"type": "vdb", "file": "plume.vdb", "grid": "temperature"},
                           "emission_scale": 1.5},
              "majorant_resolution": [4, 4, 2]},
    "cloud": {"type": "grid", "sigma_a": 0.1, "sigma_s": [1, 2, 3], "scale": 5,
              "density": {"type": "procedural", "shape": "plume", "seed": 42,
                          "resolution": [32, 48, 32], "coverage": 0.4},
              "emission": {"grid": {"type": "npy", "file": "glow.npy"}, "color": [1, 0.5, 0.2],
                           "emission_scale": 2}},
    "bunny": {"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "vol", "file": "bunny.vol"},
              "emission": {"L_ve": [0.1, 0.2, 0.3]}, "majorant_resolution": 8},
    "slab": {"type": "grid", "sigma_t": 1, "albedo": 0.5,
             "density": {"type": "constant", "value": 2, "bounds": {"min": [0, 0, 0], "max": [4, 1, 4]}}},
    "plume": {"type": "grid", "sigma_t": 2, "albedo": 0.9, "density": {"type": "vdb", "file": "plume.vdb"}}
  },
  "shapes": [{"type": "box", "min": [-2, -1, -2], "max": [2, 3, 2], "interior": "smoke"}]
}"#;

/// `GRID` with the one occurrence of `from` replaced by `to`.
fn edit_grid(from: &str, to: &str) -> String {
    assert_eq!(GRID.matches(from).count(), 1, "`{from}` must occur once in GRID");
    GRID.replacen(from, to, 1)
}

fn grid_medium<'a>(desc: &'a SceneDesc, name: &str) -> &'a GridMediumDesc {
    match &desc.media[name] {
        MediumDesc::Grid(g) => g,
        other => panic!("{name} is not a grid medium: {other:?}"),
    }
}

#[test]
fn grid_scene_parses_with_defaults_filled_in() {
    let desc = parse_scene_str(GRID, FILE).unwrap();
    match desc.render.integrator.settings {
        IntegratorSettings::Emission { transmittance, .. } => {
            assert_eq!(transmittance, TransmittanceMethod::ResidualRatio)
        }
        other => panic!("wrong integrator {other:?}"),
    }

    let smoke = grid_medium(&desc, "smoke");
    let (sigma_a, sigma_s) = smoke.sigma_a_sigma_s();
    assert!((sigma_s.r() - 24.0).abs() < 1e-4 && (sigma_a.g() - 6.0).abs() < 1e-4);
    assert_eq!(smoke.phase, PhaseDesc::HenyeyGreenstein { g: 0.3 });
    match &smoke.density {
        DensitySourceDesc::Grid(g) => {
            assert_eq!(g.dims, [2, 2, 2]);
            assert_eq!(g.data[7], 3.0);
            assert_eq!(g.bounds, BoundsDesc { min: [-1.0; 3], max: [1.0; 3] });
        }
        other => panic!("wrong density {other:?}"),
    }
    assert_eq!(
        smoke.to_world,
        TransformDesc::Components {
            scale: [2.0; 3],
            rotate_x: 0.0,
            rotate_y: 0.0,
            rotate_z: 0.0,
            translate: [0.0, 1.0, 0.0]
        }
    );
    assert_eq!(
        smoke.emission,
        Some(GridEmissionDesc::Temperature {
            temperature: DensitySourceDesc::Vdb { file: "plume.vdb".into(), grid: "temperature".into() },
            emission_scale: 1.5
        })
    );
    assert_eq!(smoke.majorant_resolution, Some(ResolutionDesc::PerAxis([4, 4, 2])));

    let cloud = grid_medium(&desc, "cloud");
    assert_eq!(cloud.scale, 5.0);
    assert_eq!(cloud.to_world, TransformDesc::IDENTITY);
    assert_eq!(cloud.majorant_resolution, None);
    assert_eq!(
        cloud.density,
        DensitySourceDesc::Procedural(ProceduralDesc {
            shape: ProceduralShapeDesc::Plume,
            seed: 42,
            resolution: ResolutionDesc::PerAxis([32, 48, 32]),
            octaves: 5,
            frequency: 3.0,
            lacunarity: 2.0,
            gain: 0.5,
            coverage: 0.4,
            sharpness: 4.0,
        })
    );
    assert_eq!(
        cloud.emission,
        Some(GridEmissionDesc::Field {
            grid: DensitySourceDesc::Npy { file: "glow.npy".into(), bounds: BoundsDesc::UNIT },
            color: ColorDesc::Rgb([1.0, 0.5, 0.2]),
            emission_scale: 2.0
        })
    );

    let bunny = grid_medium(&desc, "bunny");
    assert_eq!(bunny.density, DensitySourceDesc::Vol { file: "bunny.vol".into() });
    assert_eq!(bunny.emission, Some(GridEmissionDesc::ProportionalToDensity { l_ve: ColorDesc::Rgb([0.1, 0.2, 0.3]) }));
    assert_eq!(bunny.majorant_resolution, Some(ResolutionDesc::Uniform(8)));

    let slab = grid_medium(&desc, "slab");
    assert_eq!(
        slab.density,
        DensitySourceDesc::Constant { value: 2.0, bounds: BoundsDesc { min: [0.0; 3], max: [4.0, 1.0, 4.0] } }
    );
    assert_eq!(slab.emission, None);
    assert_eq!(slab.phase, PhaseDesc::Isotropic);

    let plume = grid_medium(&desc, "plume");
    assert_eq!(plume.density, DensitySourceDesc::Vdb { file: "plume.vdb".into(), grid: "density".into() });
}

#[test]
fn source_defaults_are_documented_values() {
    let text = edit_grid(
        r#""density": {"type": "constant", "value": 2, "bounds": {"min": [0, 0, 0], "max": [4, 1, 4]}}"#,
        r#""density": {"type": "constant"}"#,
    );
    let desc = parse_scene_str(&text, FILE).unwrap();
    assert_eq!(
        grid_medium(&desc, "slab").density,
        DensitySourceDesc::Constant { value: 1.0, bounds: BoundsDesc::UNIT }
    );
    let text = edit_grid(
        r#""shape": "plume", "seed": 42,
                          "resolution": [32, 48, 32], "coverage": 0.4"#,
        "",
    );
    let desc = parse_scene_str(&text.replace(r#""procedural", }"#, r#""procedural"}"#), FILE);
    let desc = desc.unwrap();
    match &grid_medium(&desc, "cloud").density {
        DensitySourceDesc::Procedural(p) => {
            assert_eq!(p.shape, ProceduralShapeDesc::Cloud);
            assert_eq!((p.seed, p.resolution), (0, ResolutionDesc::Uniform(64)));
            assert_eq!((p.coverage, p.sharpness), (0.5, 4.0));
        }
        other => panic!("wrong density {other:?}"),
    }
    let text = edit_grid(
        r#", "color": [1, 0.5, 0.2],
                           "emission_scale": 2"#,
        "",
    );
    let desc = parse_scene_str(&text, FILE).unwrap();
    match &grid_medium(&desc, "cloud").emission {
        Some(GridEmissionDesc::Field { color, emission_scale, .. }) => {
            assert_eq!((*color, *emission_scale), (ColorDesc::Gray(1.0), 1.0))
        }
        other => panic!("wrong emission {other:?}"),
    }
}

#[test]
fn every_transmittance_method_is_accepted() {
    for (name, expected) in [
        ("analytic", TransmittanceMethod::Analytic),
        ("ray_march", TransmittanceMethod::RayMarch(MarchStep::Count(32))),
        ("delta", TransmittanceMethod::Delta),
        ("ratio", TransmittanceMethod::Ratio),
        ("residual_ratio", TransmittanceMethod::ResidualRatio),
    ] {
        let text = edit_grid(r#""transmittance": "residual_ratio""#, &format!(r#""transmittance": "{name}""#));
        let desc = parse_scene_str(&text, FILE).unwrap();
        let IntegratorSettings::Emission { transmittance, .. } = desc.render.integrator.settings else {
            panic!("wrong integrator")
        };
        assert_eq!(transmittance, expected, "{name}");
    }
    let text = edit_grid(r#""transmittance": "residual_ratio""#, r#""transmittance": "residual""#);
    assert_error(
        &text,
        "render.integrator.transmittance",
        "unknown value `residual`, expected one of `analytic`, `ray_march`, `delta`, `ratio`, \
         `residual_ratio`",
    );
}

#[test]
fn inline_grid_with_wrong_length_names_both_counts() {
    let text = edit_grid("[0, 0.5, 1, 2, 0, 0, 0, 3]", "[0, 0.5, 1, 2, 0, 0, 3]");
    let err = assert_error(&text, "media.smoke.density.data", "= 8 values");
    assert!(err.message.contains("got 7"), "{err}");
    assert!(err.message.contains("dims [2, 2, 2]"), "{err}");
}

#[test]
fn bad_inline_grid_values_name_the_element() {
    let text = edit_grid("[0, 0.5, 1, 2, 0, 0, 0, 3]", "[0, 0.5, 1, 2, 0, -0.5, 0, 3]");
    assert_error(&text, "media.smoke.density.data[5]", "must be >= 0, got -0.5");
    let text = edit_grid("[0, 0.5, 1, 2, 0, 0, 0, 3]", "[0, 0.5, 1, 2, 0, 0, 0, 1e39]");
    assert_error(&text, "media.smoke.density.data[7]", "expected a finite number");
    let text = edit_grid("[0, 0.5, 1, 2, 0, 0, 0, 3]", r#"[0, 0.5, 1, "2", 0, 0, 0, 3]"#);
    assert_error(&text, "media.smoke.density.data[3]", "expected a number");
}

#[test]
fn inline_grid_dims_must_be_positive_and_bounded() {
    let text = edit_grid(r#""dims": [2, 2, 2]"#, r#""dims": [2, 2, 0]"#);
    assert_error(&text, "media.smoke.density.dims[2]", "must be at least 1, got 0");
    let text = edit_grid(r#""dims": [2, 2, 2]"#, r#""dims": [65536, 65536, 1]"#);
    assert_error(&text, "media.smoke.density.dims", "exceeds the limit of 268435456 (2^28)");
    let text = edit_grid(r#""dims": [2, 2, 2]"#, r#""dims": [2, 2]"#);
    assert_error(&text, "media.smoke.density.dims", "invalid length 2");
    let text = edit_grid(r#""dims": [2, 2, 2]"#, r#""dims": [2, -2, 2]"#);
    assert_error(&text, "media.smoke.density.dims[1]", "expected a whole number");
}

#[test]
fn source_bounds_must_be_boxes() {
    let text = edit_grid(r#""max": [1, 1, 1]"#, r#""max": [1, -1, 1]"#);
    assert_error(&text, "media.smoke.density.bounds.max[1]", "must be greater than min[1] = -1, got -1");
    let text = edit_grid(r#", "max": [1, 1, 1]"#, "");
    assert_error(&text, "media.smoke.density.bounds.max", "missing required field `max`");
    let text = edit_grid(r#""max": [1, 1, 1]"#, r#""max": [1, 1, 1], "centre": [0, 0, 0]"#);
    assert_error(&text, "media.smoke.density.bounds.centre", "unknown field `centre`");
}

#[test]
fn grid_medium_without_density_is_rejected() {
    let text = edit_grid(
        r#""plume": {"type": "grid", "sigma_t": 2, "albedo": 0.9, "density": {"type": "vdb", "file": "plume.vdb"}}"#,
        r#""plume": {"type": "grid", "sigma_t": 2, "albedo": 0.9}"#,
    );
    assert_error(
        &text,
        "media.plume.density",
        "missing required field `density`: a grid medium needs a density source",
    );
}

#[test]
fn grid_fields_in_a_homogeneous_medium_say_to_add_the_type() {
    let text = edit(r#""scale": 2,"#, r#""scale": 2, "density": {"type": "constant"},"#);
    assert_error(&text, "media.smoke.density", r#"only valid in a heterogeneous medium: add "type": "grid""#);
    let text = edit(r#""sigma_a": 0.01, "#, r#""sigma_a": 0.01, "to_world": {"scale": 2}, "#);
    assert_error(&text, "media.fog.to_world", "only valid in a heterogeneous medium");
    let text = edit(r#""scale": 2,"#, r#""scale": 2, "majorant_resolution": 4,"#);
    assert_error(&text, "media.smoke.majorant_resolution", "only valid in a heterogeneous medium");
    let text = edit(
        r#""emission": {"L_ve": [0.1, 0.05, 0.01]}"#,
        r#""emission": {"temperature": {"type": "constant", "value": 1500}}"#,
    );
    assert_error(&text, "media.smoke.emission.temperature", "needs a heterogeneous medium");
}

/// The short form of a scene file leaves out `type` on a medium with a
/// `density`: such a medium is a grid medium.
#[test]
fn untyped_medium_with_density_is_a_grid_medium() {
    let text = edit(
        r#""fog": {"sigma_a": 0.01,"#,
        r#""plume": {"density": {"type": "vdb", "file": "plume.vdb", "grid": "density"},
              "sigma_t": 30, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3},
              "emission": {"temperature": {"type": "vdb", "file": "plume.vdb", "grid": "temperature"},
                           "emission_scale": 1.0}},
    "fog": {"sigma_a": 0.01,"#,
    );
    let desc = parse_scene_str(&text, FILE).unwrap();
    let plume = match &desc.media["plume"] {
        MediumDesc::Grid(g) => g,
        other => panic!("expected a grid medium, got {other:?}"),
    };
    assert_eq!(plume.density, DensitySourceDesc::Vdb { file: "plume.vdb".into(), grid: "density".into() });
    assert!(matches!(plume.emission, Some(GridEmissionDesc::Temperature { emission_scale: 1.0, .. })));
    assert!(matches!(desc.media["fog"], MediumDesc::Homogeneous(_)));
}

#[test]
fn density_sources_reject_unknown_types_keys_and_missing_fields() {
    let text = edit_grid(r#"{"type": "vdb", "file": "plume.vdb"}"#, r#"{"type": "openvdb", "file": "plume.vdb"}"#);
    assert_error(
        &text,
        "media.plume.density.type",
        r#"unknown density source type "openvdb"; expected one of: constant, grid, npy, vol, vdb, procedural"#,
    );
    let text = edit_grid(r#"{"type": "vdb", "file": "plume.vdb"}"#, r#"{"file": "plume.vdb"}"#);
    assert_error(&text, "media.plume.density.type", "missing required field `type`");
    let text = edit_grid(
        r#"{"type": "vdb", "file": "plume.vdb"}"#,
        r#"{"type": "vdb", "file": "plume.vdb", "gird": "density"}"#,
    );
    assert_error(&text, "media.plume.density.gird", "unknown field `gird`, expected `file` or `grid`");
    let text = edit_grid(r#"{"type": "npy", "file": "glow.npy"}"#, r#"{"type": "npy"}"#);
    assert_error(&text, "media.cloud.emission.grid.file", "missing required field `file`");
    let text = edit_grid(r#""file": "bunny.vol""#, r#""file": """#);
    assert_error(&text, "media.bunny.density.file", "expected a file name");
    let text = edit_grid(r#""grid": "temperature""#, r#""grid": """#);
    assert_error(&text, "media.smoke.emission.temperature.grid", "expected a grid name");
    let text = edit_grid(r#""density": {"type": "vol", "file": "bunny.vol"}"#, r#""density": 1"#);
    assert_error(&text, "media.bunny.density", r#"expected a density source object with a "type" field"#);
    let text = edit_grid(r#""value": 2"#, r#""value": -2"#);
    assert_error(&text, "media.slab.density.value", "must be >= 0, got -2");
}

#[test]
fn procedural_parameters_are_checked() {
    let text = edit_grid(r#""coverage": 0.4"#, r#""coverage": 1.5"#);
    assert_error(&text, "media.cloud.density.coverage", "must be in [0, 1], got 1.5");
    let text = edit_grid(r#""coverage": 0.4"#, r#""coverage": 0.4, "sharpness": 0"#);
    assert_error(&text, "media.cloud.density.sharpness", "must be in (0, 1000], got 0");
    let text = edit_grid(r#""coverage": 0.4"#, r#""coverage": 0.4, "lacunarity": 0.5"#);
    assert_error(&text, "media.cloud.density.lacunarity", "must be in [1, 8], got 0.5");
    let text = edit_grid(r#""coverage": 0.4"#, r#""coverage": 0.4, "octaves": 0"#);
    assert_error(&text, "media.cloud.density.octaves", "must be from 1 to 12, got 0");
    let text = edit_grid(r#""shape": "plume""#, r#""shape": "smoke""#);
    assert_error(&text, "media.cloud.density.shape", "unknown value `smoke`, expected `cloud` or `plume`");
    let text = edit_grid(r#""seed": 42"#, r#""seed": -42"#);
    assert_error(&text, "media.cloud.density.seed", "expected a whole number >= 0");
    let text = edit_grid(r#""resolution": [32, 48, 32]"#, r#""resolution": [32, 0, 32]"#);
    assert_error(&text, "media.cloud.density.resolution[1]", "must be at least 1");
    let text = edit_grid(r#""resolution": [32, 48, 32]"#, r#""resolution": 1024"#);
    assert_error(&text, "media.cloud.density.resolution", "1024 x 1024 x 1024 = 1073741824 cells exceeds the limit");
    let text = edit_grid(r#""resolution": [32, 48, 32]"#, r#""resolution": [32, 2048, 32]"#);
    assert_error(&text, "media.cloud.density.resolution[1]", "must be at most 1024, got 2048");
    let text = edit_grid(r#""seed": 42"#, r#""seed": 42, "octave": 3"#);
    assert_error(&text, "media.cloud.density.octave", "unknown field `octave`");
}

#[test]
fn grid_emission_takes_exactly_one_form() {
    let text = edit_grid(
        r#""emission": {"L_ve": [0.1, 0.2, 0.3]}"#,
        r#""emission": {"L_ve": [0.1, 0.2, 0.3], "temperature": {"type": "constant"}}"#,
    );
    assert_error(
        &text,
        "media.bunny.emission.temperature",
        "`temperature` cannot be combined with `L_ve`: give exactly one of",
    );
    let text = edit_grid(r#""emission": {"L_ve": [0.1, 0.2, 0.3]}"#, r#""emission": {"emission_scale": 3}"#);
    assert_error(&text, "media.bunny.emission", "missing emission: give exactly one of `L_ve`");
    let text = edit_grid(
        r#""emission": {"L_ve": [0.1, 0.2, 0.3]}"#,
        r#""emission": {"L_ve": [0.1, 0.2, 0.3], "emission_scale": 3}"#,
    );
    assert_error(&text, "media.bunny.emission.emission_scale", "`emission_scale` goes with `grid` or `temperature`");
    let text = edit_grid(r#""emission_scale": 1.5"#, r#""emission_scale": 1.5, "color": 2"#);
    assert_error(&text, "media.smoke.emission.color", "`color` goes with `grid` only");
    let text = edit_grid(r#""emission_scale": 1.5"#, r#""emission_scale": -1.5"#);
    assert_error(&text, "media.smoke.emission.emission_scale", "must be >= 0, got -1.5");
    let text = edit_grid(r#""color": [1, 0.5, 0.2]"#, r#""color": [1, -0.5, 0.2]"#);
    assert_error(&text, "media.cloud.emission.color[1]", "must be >= 0");
    let text = edit_grid(r#""L_ve": [0.1, 0.2, 0.3]"#, r#""L_ve": [0.1, 0.2, -0.3]"#);
    assert_error(&text, "media.bunny.emission.L_ve[2]", "must be >= 0");
    let text = edit_grid(r#""emission_scale": 2"#, r#""emission_scale": 2, "colour": 1"#);
    assert_error(&text, "media.cloud.emission.colour", "unknown field `colour`");
    let text = edit_grid(
        r#""grid": {"type": "npy", "file": "glow.npy"}"#,
        r#""grid": {"type": "npy", "file": "glow.npy", "bounds": {"min": [0, 0, 0], "max": [0, 1, 1]}}"#,
    );
    assert_error(&text, "media.cloud.emission.grid.bounds.max[0]", "must be greater than min[0]");
}

#[test]
fn majorant_resolution_is_a_count_from_1_to_256() {
    let text = edit_grid(r#""majorant_resolution": 8"#, r#""majorant_resolution": 0"#);
    assert_error(&text, "media.bunny.majorant_resolution", "must be at least 1, got 0");
    let text = edit_grid(r#""majorant_resolution": 8"#, r#""majorant_resolution": 257"#);
    assert_error(&text, "media.bunny.majorant_resolution", "must be at most 256, got 257");
    let text = edit_grid(r#""majorant_resolution": [4, 4, 2]"#, r#""majorant_resolution": [4, 300, 2]"#);
    assert_error(&text, "media.smoke.majorant_resolution[1]", "must be at most 256, got 300");
    for bad in ["2.5", "-3", r#""16""#, "[4, 4]"] {
        let text = edit_grid(r#""majorant_resolution": 8"#, &format!(r#""majorant_resolution": {bad}"#));
        assert_error(
            &text,
            "media.bunny.majorant_resolution",
            "a whole number >= 1 or an array of 3 whole numbers [nx, ny, nz]",
        );
    }
}

#[test]
fn grid_medium_coefficients_and_transform_are_checked() {
    let text = edit_grid(r#""sigma_s": [1, 2, 3]"#, r#""sigma_s": [1, -2, 3]"#);
    assert_error(&text, "media.cloud.sigma_s[1]", "must be >= 0");
    let text = edit_grid(r#""albedo": 0.9"#, r#""albedo": 0.9, "sigma_a": 1"#);
    assert_error(&text, "media.plume.sigma_t", "`sigma_t` cannot be combined with `sigma_a`");
    let text = edit_grid(r#""scale": 5"#, r#""scale": 0"#);
    assert_error(&text, "media.cloud.scale", "must be > 0");
    let text = edit_grid(r#""scale": 2}"#, r#""scale": 0}"#);
    assert_error(&text, "media.smoke.to_world.scale", "scale factors must be non-zero");
    let text = edit_grid(r#""g": 0.3"#, r#""g": 1.3"#);
    assert_error(&text, "media.smoke.phase.g", "open interval (-1, 1)");
    let text = edit_grid(r#""majorant_resolution": 8"#, r#""majorant_res": 8"#);
    assert_error(&text, "media.bunny.majorant_res", "unknown field `majorant_res`");
}

#[test]
fn random_mutations_of_grid_scenes_never_panic() {
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    let (mut accepted, mut rejected) = (0, 0);
    for round in 0..600 {
        let mut text = GRID.to_string();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng);
        }
        let result = std::panic::catch_unwind(|| parse_scene_str(&text, FILE));
        match result {
            Err(_) => panic!("round {round}: parse_scene_str panicked on:\n{text}"),
            Ok(Ok(desc)) => {
                accepted += 1;
                assert!(desc.validate(FILE).is_ok(), "round {round}");
            }
            Ok(Err(err)) => {
                rejected += 1;
                assert_eq!(err.file, FILE);
                assert!(!err.message.is_empty(), "round {round}: {err}");
                assert!(!err.message.contains('\u{1}'), "round {round}: {err:?}");
            }
        }
    }
    assert!(accepted > 10 && rejected > 300, "accepted {accepted}, rejected {rejected}");
}

// ---------------------------------------------------------------------------
// Whole-file errors
// ---------------------------------------------------------------------------

#[test]
fn missing_file_names_the_path() {
    let path = std::path::Path::new("/nonexistent/niebla/fog_scene.json");
    let err = load_scene_file(path).unwrap_err();
    assert_eq!(err.file, "/nonexistent/niebla/fog_scene.json");
    assert_eq!(err.path, "");
    assert!(err.message.contains("cannot read scene file"), "{err}");
    assert!(err.to_string().starts_with("/nonexistent/niebla/fog_scene.json: cannot read"));
}

#[test]
fn json_syntax_error_gives_line_and_column() {
    let text = edit(r#""fov_y": 35,"#, r#""fov_y": 35"#);
    let err = assert_error(&text, "", "invalid JSON: expected `,` or `}` at line 4 column");
    assert!(err.to_string().starts_with("test.json: invalid JSON"), "{err}");
    assert_error("", "", "invalid JSON: EOF while parsing a value at line 1 column 0");
}

#[test]
fn non_object_top_level_is_rejected() {
    assert_error("[1, 2]", "", "expected a JSON object at the top level, got an array");
}

// ---------------------------------------------------------------------------
// Robustness
// ---------------------------------------------------------------------------

/// xorshift64 (Marsaglia 2003): deterministic randomness without a dependency.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Byte ranges of the numbers in `text` (ASCII only).
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() || bytes[i] == b'-' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || b"-+.eE".contains(&bytes[i])) {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// One random change: delete a character, insert junk, replace a number by
/// an extreme, or drop a key with its value.
fn mutate(text: &str, rng: &mut XorShift) -> String {
    const JUNK: &[&str] = &[
        "{",
        "}",
        "[",
        "]",
        ",",
        ":",
        "\"",
        "-",
        "1e400",
        "null",
        "\"x\"",
        "0",
        "nan",
        "\\",
        "é",
        "1e39",
        "-1",
        "true",
        "[1, 2]",
        "{\"type\": \"x\"}",
        "\"type\": \"sphere\", ",
    ];
    let chars: Vec<(usize, char)> = text.char_indices().collect();
    let at = |i: usize| chars.get(i).map_or(text.len(), |(b, _)| *b);
    match rng.below(4) {
        0 if !chars.is_empty() => {
            let i = rng.below(chars.len());
            let (start, c) = chars[i];
            format!("{}{}", &text[..start], &text[start + c.len_utf8()..])
        }
        1 => {
            let position = at(rng.below(chars.len() + 1));
            let junk = JUNK[rng.below(JUNK.len())];
            format!("{}{junk}{}", &text[..position], &text[position..])
        }
        2 => {
            let spans = number_spans(text);
            if spans.is_empty() {
                return text.to_string();
            }
            let (start, end) = spans[rng.below(spans.len())];
            let replacement = ["-1", "1e400", "1e39", "0", "-0", "1.5", "4294967296"][rng.below(7)];
            format!("{}{replacement}{}", &text[..start], &text[end..])
        }
        _ => {
            // Drop from a key's opening quote to the next comma or closing brace.
            let keys: Vec<usize> = text.match_indices("\": ").map(|(i, _)| i).collect();
            if keys.is_empty() {
                return text.to_string();
            }
            let colon = keys[rng.below(keys.len())];
            let start = text[..colon].rfind('"').unwrap_or(colon);
            let end = text[colon..]
                .find([',', '}'])
                .map_or(text.len(), |j| colon + j + usize::from(&text[colon + j..colon + j + 1] == ","));
            format!("{}{}", &text[..start], &text[end..])
        }
    }
}

#[test]
fn random_mutations_never_panic_and_always_name_the_file() {
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let (mut accepted, mut rejected) = (0, 0);
    for round in 0..600 {
        let mut text = FULL.to_string();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng);
        }
        let result = std::panic::catch_unwind(|| parse_scene_str(&text, FILE));
        match result {
            Err(_) => panic!("round {round}: parse_scene_str panicked on:\n{text}"),
            Ok(Ok(desc)) => {
                accepted += 1;
                assert!(desc.validate(FILE).is_ok(), "round {round}");
            }
            Ok(Err(err)) => {
                rejected += 1;
                assert_eq!(err.file, FILE);
                assert!(!err.message.is_empty(), "round {round}: {err}");
                assert!(!err.message.contains('\u{1}'), "round {round}: {err:?}");
                assert!(err.to_string().starts_with("test.json: "), "round {round}");
            }
        }
    }
    // The mutations exercise both outcomes.
    assert!(accepted > 10 && rejected > 300, "accepted {accepted}, rejected {rejected}");
}

#[test]
fn volpath_integrator_parses_and_rejects_a_zero_depth() {
    let text = edit(
        r#"{"type": "single", "step": 0.05, "sampling": "mis",
                            "transmittance": "analytic"}"#,
        r#"{"type": "volpath", "max_depth": 64}"#,
    );
    let desc = parse_scene_str(&text, FILE).unwrap();
    assert_eq!(desc.render.integrator.settings, IntegratorSettings::VolPath { max_depth: 64 });
    let zero = text.replace(r#""max_depth": 64"#, r#""max_depth": 0"#);
    assert_error(&zero, "render.integrator.max_depth", "at least 1");
    let typo = text.replace(r#""max_depth": 64"#, r#""max_dept": 64"#);
    assert_error(&typo, "render.integrator.max_dept", "unknown field");
}
