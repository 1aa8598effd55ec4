//! Scene files: a valid scene parses, and every bad input is an error that
//! names the file, the exact JSON path and what was expected, never a panic.
//!
//! The error cases are tables of [`ErrorCase`], one per part of the scene:
//! each takes a valid scene ([`FULL`] or [`GRID`]), changes one thing in its
//! text and expects an error with the right `file`, `path` and message; a few
//! [`TextCase`]s give the whole text instead. One loop runs a table and
//! reports every failing case by name.

use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::scene::{
    load_scene_file, parse_scene_str, BoundsDesc, BsdfDesc, CameraDesc, CoefficientsDesc, ColorDesc, DensitySourceDesc,
    GeometryDesc, GridEmissionDesc, GridMediumDesc, IntegratorSpec, LightDesc, MediumDesc, PhaseDesc, ProceduralDesc,
    ProceduralShapeDesc, ResolutionDesc, SceneDesc, SchlickDesc, SpotAimDesc, TransformDesc,
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

/// One bad scene: a valid scene's text with the one occurrence of `from`
/// replaced by `to` must fail at `path` with a message containing `message`
/// and every text in `also`.
struct ErrorCase {
    name: &'static str,
    from: &'static str,
    to: &'static str,
    path: &'static str,
    message: &'static str,
    also: &'static [&'static str],
}

/// One bad scene given as its whole text.
struct TextCase {
    name: &'static str,
    text: &'static str,
    path: &'static str,
    message: &'static str,
}

/// Parses `text` and checks that it is an error at `path` whose message
/// contains `message` and each of `also`, with the file name and the Display
/// form right; the `Err` says everything that is wrong.
fn check_error(text: &str, path: &str, message: &str, also: &[&str]) -> Result<(), String> {
    let err = match std::panic::catch_unwind(|| parse_scene_str(text, FILE)) {
        Err(_) => return Err("parse_scene_str panicked".into()),
        Ok(Ok(_)) => return Err(format!("expected an error at `{path}`, but the scene parsed")),
        Ok(Err(e)) => e,
    };
    let mut problems = Vec::new();
    if err.file != FILE {
        problems.push(format!("file is `{}`, expected `{FILE}`", err.file));
    }
    if err.path != path {
        problems.push(format!("path is `{}`, expected `{path}`", err.path));
    }
    for expected in std::iter::once(&message).chain(also) {
        if !err.message.contains(expected) {
            problems.push(format!("message lacks `{expected}`"));
        }
    }
    let shown = match err.path.as_str() {
        "" => format!("{FILE}: {}", err.message),
        at => format!("{FILE}: {at}: {}", err.message),
    };
    if err.to_string() != shown {
        problems.push(format!("displays as `{err}`, expected `{shown}`"));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!("{} (the error: `{err}`)", problems.join("; ")))
    }
}

/// Panics listing every failure, each naming its case, if there are any.
fn report(failures: Vec<(&str, String)>, total: usize) {
    let mut names: Vec<&str> = failures.iter().map(|(name, _)| *name).collect();
    names.dedup();
    let listed: Vec<String> = failures.iter().map(|(name, why)| format!("  {name}: {why}")).collect();
    assert!(failures.is_empty(), "{} of {total} error cases failed:\n{}", names.len(), listed.join("\n"));
}

/// Runs every case of `cases` against the valid scene `base` (named
/// `base_name`) and reports all failing cases together.
fn check_edits(base_name: &str, base: &str, cases: &[ErrorCase]) {
    let mut failures = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        if cases[..i].iter().any(|c| c.name == case.name) {
            failures.push((case.name, "another case has the same name".to_string()));
        }
        let result = match base.matches(case.from).count() {
            1 => check_error(&base.replacen(case.from, case.to, 1), case.path, case.message, case.also),
            n => Err(format!("`{}` occurs {n} times in {base_name}, not once", case.from)),
        };
        if let Err(why) = result {
            failures.push((case.name, why));
        }
    }
    report(failures, cases.len());
}

/// Runs every case of `cases` and reports all failing cases together.
fn check_texts(cases: &[TextCase]) {
    let failures = cases
        .iter()
        .filter_map(|case| check_error(case.text, case.path, case.message, &[]).err().map(|why| (case.name, why)))
        .collect();
    report(failures, cases.len());
}

/// `FULL`'s integrator.
const SINGLE: &str = r#"{"type": "single", "step": 0.05, "sampling": "mis",
                            "transmittance": "analytic"}"#;

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
// Errors in FULL: one table per part of the scene
// ---------------------------------------------------------------------------

/// The top level: keys, the version and whole-file JSON errors.
const TOP_LEVEL: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown top-level key",
        from: r#""ambient_medium": "fog""#,
        to: r#""ambient_medium": "fog", "ambient_mediun": 1"#,
        path: "ambient_mediun",
        message: "unknown field `ambient_mediun`, expected one of",
        also: &[],
    },
    ErrorCase {
        name: "unsupported version",
        from: r#""version": 1"#,
        to: r#""version": 2"#,
        path: "version",
        message: "unsupported scene version 2",
        also: &[],
    },
    ErrorCase {
        name: "version as a string",
        from: r#""version": 1"#,
        to: r#""version": "1""#,
        path: "version",
        message: "expected a whole number",
        also: &[],
    },
    ErrorCase {
        name: "missing version",
        from: r#""version": 1,"#,
        to: "",
        path: "version",
        message: "missing required field `version`",
        also: &[],
    },
    ErrorCase {
        name: "JSON syntax error gives line and column",
        from: r#""fov_y": 35,"#,
        to: r#""fov_y": 35"#,
        path: "",
        message: "invalid JSON: expected `,` or `}` at line 4 column",
        also: &[],
    },
];

#[test]
fn top_level_errors() {
    check_edits("FULL", FULL, TOP_LEVEL);
}

/// Whole texts that are not a scene.
const WHOLE_TEXTS: &[TextCase] = &[
    TextCase {
        name: "missing camera",
        text: r#"{"version": 1}"#,
        path: "camera",
        message: "missing required field `camera`",
    },
    TextCase {
        name: "empty file",
        text: "",
        path: "",
        message: "invalid JSON: EOF while parsing a value at line 1 column 0",
    },
    TextCase {
        name: "array at the top level",
        text: "[1, 2]",
        path: "",
        message: "expected a JSON object at the top level, got an array",
    },
    TextCase {
        name: "lights as an object",
        text: r#"{"version": 1, "camera": {"type": "perspective", "position": [0, 0, 5],
                  "target": [0, 0, 0], "width": 8, "height": 8}, "lights": {"type": "point"}}"#,
        path: "lights",
        message: "invalid type: map, expected a sequence",
    },
];

#[test]
fn whole_text_errors() {
    check_texts(WHOLE_TEXTS);
}

#[test]
fn json_syntax_error_is_shown_after_the_file_name() {
    let text = edit(r#""fov_y": 35,"#, r#""fov_y": 35"#);
    let err = parse_scene_str(&text, FILE).unwrap_err();
    assert!(err.to_string().starts_with("test.json: invalid JSON"), "{err}");
}

const CAMERA: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown camera key",
        from: r#""fov_y": 35"#,
        to: r#""fovy": 35"#,
        path: "camera.fovy",
        message: "unknown field `fovy`",
        also: &[],
    },
    ErrorCase {
        name: "string field of view",
        from: r#""fov_y": 35"#,
        to: r#""fov_y": "wide""#,
        path: "camera.fov_y",
        message: "invalid type: string \"wide\", expected a number",
        also: &[],
    },
    ErrorCase {
        name: "two-element position",
        from: r#""position": [0, 1, 4]"#,
        to: r#""position": [0, 1]"#,
        path: "camera.position",
        message: "invalid length 2, expected an array of 3 numbers",
        also: &[],
    },
    ErrorCase {
        name: "fractional width",
        from: r#""width": 64"#,
        to: r#""width": 64.5"#,
        path: "camera.width",
        message: "expected a whole number",
        also: &[],
    },
    ErrorCase {
        name: "negative width",
        from: r#""width": 64"#,
        to: r#""width": -64"#,
        path: "camera.width",
        message: "expected a whole number",
        also: &[],
    },
    ErrorCase {
        name: "zero width",
        from: r#""width": 64"#,
        to: r#""width": 0"#,
        path: "camera.width",
        message: "must be at least 1 pixel",
        also: &[],
    },
    ErrorCase {
        name: "absurd width",
        from: r#""width": 64"#,
        to: r#""width": 100000"#,
        path: "camera.width",
        message: "must be at most 16384 pixels, got 100000",
        also: &[],
    },
    ErrorCase {
        name: "height beyond u32",
        from: r#""height": 48"#,
        to: r#""height": 10000000000"#,
        path: "camera.height",
        message: "expected a whole number from 0 to 4294967295",
        also: &[],
    },
    ErrorCase {
        name: "too many pixels",
        from: r#""width": 64, "height": 48"#,
        to: r#""width": 16384, "height": 16384"#,
        path: "camera",
        message: "exceeds the limit of 67108864 (2^26) pixels",
        also: &[],
    },
    ErrorCase {
        name: "target at the position",
        from: r#""target": [0, 1, 0],"#,
        to: r#""target": [0, 1, 4],"#,
        path: "camera.target",
        message: "must differ from `position`",
        also: &[],
    },
    ErrorCase {
        name: "up along the view direction",
        from: r#""up": [0, 1, 0]"#,
        to: r#""up": [0, 0, -2]"#,
        path: "camera.up",
        message: "must not be parallel to the view direction",
        also: &[],
    },
    ErrorCase {
        name: "field of view of 180 degrees",
        from: r#""fov_y": 35"#,
        to: r#""fov_y": 180"#,
        path: "camera.fov_y",
        message: "(0, 180)",
        also: &[],
    },
    ErrorCase {
        name: "unknown camera type",
        from: r#""type": "perspective""#,
        to: r#""type": "orthographic""#,
        path: "camera.type",
        message: r#"unknown camera type "orthographic""#,
        also: &[],
    },
];

#[test]
fn camera_errors() {
    check_edits("FULL", FULL, CAMERA);
}

const RENDER_AND_INTEGRATOR: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown render key",
        from: r#""spp": 4"#,
        to: r#""spp": 4, "max_depth": 3"#,
        path: "render.max_depth",
        message: "unknown field `max_depth`",
        also: &[],
    },
    ErrorCase {
        name: "zero spp",
        from: r#""spp": 4"#,
        to: r#""spp": 0"#,
        path: "render.spp",
        message: "at least 1",
        also: &[],
    },
    ErrorCase {
        name: "unknown sampler",
        from: r#""seed": 7"#,
        to: r#""seed": 7, "sampler": "halton""#,
        path: "render.sampler",
        message: "unknown value `halton`, expected one of `independent`, `sobol`, `sobol_sequential`",
        also: &[],
    },
    ErrorCase {
        name: "sampler not a string",
        from: r#""seed": 7"#,
        to: r#""seed": 7, "sampler": 2"#,
        path: "render.sampler",
        message: "expected",
        also: &[],
    },
    ErrorCase {
        name: "infinite exposure",
        from: r#""exposure": 0.5"#,
        to: r#""exposure": -1e300"#,
        path: "render.exposure",
        message: "expected a finite number",
        also: &[],
    },
    ErrorCase {
        name: "unknown integrator key",
        from: r#""sampling": "mis""#,
        to: r#""sampling": "mis", "sampels": 1"#,
        path: "render.integrator.sampels",
        message: "unknown field `sampels`",
        also: &[],
    },
    ErrorCase {
        name: "unknown integrator type",
        from: r#""type": "single""#,
        to: r#""type": "bidirectional""#,
        path: "render.integrator.type",
        message: r#"unknown integrator type "bidirectional"; expected one of: "#,
        also: &[],
    },
    ErrorCase {
        name: "unknown sampling",
        from: r#""sampling": "mis""#,
        to: r#""sampling": "importance""#,
        path: "render.integrator.sampling",
        message: "unknown value `importance`, expected one of `march`, `equiangular`, `mis`",
        also: &[],
    },
    ErrorCase {
        name: "zero step",
        from: r#""step": 0.05"#,
        to: r#""step": 0"#,
        path: "render.integrator.step",
        message: "must be > 0, got 0",
        also: &[],
    },
    ErrorCase {
        name: "negative step",
        from: r#""step": 0.05"#,
        to: r#""step": -1"#,
        path: "render.integrator.step",
        message: "must be > 0, got -1",
        also: &[],
    },
    ErrorCase {
        name: "zero steps",
        from: r#""step": 0.05"#,
        to: r#""steps": 0"#,
        path: "render.integrator.steps",
        message: "must be at least 1",
        also: &[],
    },
    ErrorCase {
        name: "step and steps together",
        from: r#""step": 0.05"#,
        to: r#""step": 0.05, "steps": 8"#,
        path: "render.integrator.steps",
        message: "mutually exclusive",
        also: &[],
    },
    ErrorCase {
        name: "volpath with zero depth",
        from: SINGLE,
        to: r#"{"type": "volpath", "max_depth": 0}"#,
        path: "render.integrator.max_depth",
        message: "at least 1",
        also: &[],
    },
    ErrorCase {
        name: "unknown volpath key",
        from: SINGLE,
        to: r#"{"type": "volpath", "max_dept": 64}"#,
        path: "render.integrator.max_dept",
        message: "unknown field",
        also: &[],
    },
    ErrorCase {
        name: "ppb tube_sin out of range",
        from: SINGLE,
        to: r#"{"type": "ppb", "tube_sin": 1.5}"#,
        path: "render.integrator.tube_sin",
        message: "must be in [0, 1], got 1.5",
        also: &[],
    },
];

#[test]
fn render_and_integrator_errors() {
    check_edits("FULL", FULL, RENDER_AND_INTEGRATOR);
}

#[test]
fn unknown_integrator_type_lists_every_integrator() {
    let text = edit(r#""type": "single""#, r#""type": "bidirectional""#);
    let err = parse_scene_str(&text, FILE).unwrap_err();
    for name in niebla::integrator::registry::NAMES {
        assert!(err.message.contains(name), "{err} does not list {name}");
    }
}

#[test]
fn ppb_tube_sin_parses() {
    let text = edit(SINGLE, r#"{"type": "ppb", "tube_sin": 0.1}"#);
    let desc = parse_scene_str(&text, FILE).unwrap();
    let IntegratorSettings::Ppb(ppb) = desc.render.integrator.settings else { panic!("not ppb") };
    assert_eq!(ppb.tube_sin, 0.1);
    let text = edit(SINGLE, r#"{"type": "ppb"}"#);
    let desc = parse_scene_str(&text, FILE).unwrap();
    let IntegratorSettings::Ppb(ppb) = desc.render.integrator.settings else { panic!("not ppb") };
    assert_eq!(ppb.tube_sin, niebla::integrator::photon::PpbSettings::DEFAULT_TUBE_SIN);
}

#[test]
fn volpath_integrator_parses() {
    let text = edit(SINGLE, r#"{"type": "volpath", "max_depth": 64}"#);
    let desc = parse_scene_str(&text, FILE).unwrap();
    assert_eq!(
        desc.render.integrator.settings,
        IntegratorSettings::VolPath { max_depth: 64, volume_light_sampling: true, emitter_guiding: true }
    );
}

/// Homogeneous media: coefficients, scale, emission and fields that only
/// grid media take.
const MEDIA: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown medium key",
        from: r#""sigma_s": [0.08"#,
        to: r#""sigam_s": [0.08"#,
        path: "media.fog.sigam_s",
        message: "unknown field `sigam_s`",
        also: &["`sigma_s`"],
    },
    ErrorCase {
        name: "unknown emission key",
        from: r#""L_ve""#,
        to: r#""L_e""#,
        path: "media.smoke.emission.L_e",
        message: "unknown field `L_e`, expected `L_ve`",
        also: &[],
    },
    ErrorCase {
        name: "unknown medium type",
        from: r#""type": "homogeneous""#,
        to: r#""type": "foam""#,
        path: "media.smoke.type",
        message: r#"unknown medium type "foam"; expected one of: homogeneous, grid, pyro"#,
        also: &[],
    },
    ErrorCase {
        name: "two-element color",
        from: "[0.08, 0.09, 0.1]",
        to: "[0.08, 0.09]",
        path: "media.fog.sigma_s",
        message: "invalid length 2, expected a number or an array of 3 numbers",
        also: &[],
    },
    ErrorCase {
        name: "negative coefficient channel",
        from: "[0.08, 0.09, 0.1]",
        to: "[0.08, 0.09, -0.1]",
        path: "media.fog.sigma_s[2]",
        message: "must be >= 0, got -0.1",
        also: &[],
    },
    ErrorCase {
        name: "negative sigma_a",
        from: r#""sigma_a": 0.01"#,
        to: r#""sigma_a": -0.01"#,
        path: "media.fog.sigma_a",
        message: "must be >= 0, got -0.01",
        also: &[],
    },
    ErrorCase {
        name: "negative sigma_t",
        from: r#""sigma_t": 3"#,
        to: r#""sigma_t": -3"#,
        path: "media.smoke.sigma_t",
        message: "must be >= 0",
        also: &[],
    },
    ErrorCase {
        name: "albedo above one",
        from: r#""albedo": 0.8"#,
        to: r#""albedo": 1.5"#,
        path: "media.smoke.albedo",
        message: "must be in [0, 1], got 1.5",
        also: &[],
    },
    ErrorCase {
        name: "albedo channel above one",
        from: "[0.9, 0.95, 1]",
        to: "[0.9, 0.95, 1.01]",
        path: "media.cloud.albedo[2]",
        message: "must be in [0, 1]",
        also: &[],
    },
    ErrorCase {
        name: "zero scale",
        from: r#""scale": 2"#,
        to: r#""scale": 0"#,
        path: "media.smoke.scale",
        message: "must be > 0",
        also: &[],
    },
    ErrorCase {
        name: "both coefficient forms",
        from: r#""sigma_t": 3"#,
        to: r#""sigma_t": 3, "sigma_a": 1"#,
        path: "media.smoke.sigma_t",
        message: "`sigma_t` cannot be combined with `sigma_a`",
        also: &[],
    },
    ErrorCase {
        name: "sigma_a without sigma_s",
        from: r#", "sigma_s": [0.08, 0.09, 0.1]"#,
        to: "",
        path: "media.fog.sigma_s",
        message: "missing required field `sigma_s`, which goes with `sigma_a`",
        also: &[],
    },
    ErrorCase {
        name: "sigma_t without albedo",
        from: r#""albedo": 0.8, "#,
        to: "",
        path: "media.smoke.albedo",
        message: "missing required field `albedo`",
        also: &[],
    },
    ErrorCase {
        name: "no coefficients",
        from: r#""sigma_a": 0.01, "sigma_s": [0.08, 0.09, 0.1], "#,
        to: "",
        path: "media.fog",
        message: "missing coefficients",
        also: &[],
    },
    ErrorCase {
        name: "density in a homogeneous medium",
        from: r#""scale": 2,"#,
        to: r#""scale": 2, "density": {"type": "constant"},"#,
        path: "media.smoke.density",
        message: r#"only valid in a heterogeneous medium: add "type": "grid""#,
        also: &[],
    },
    ErrorCase {
        name: "to_world in a homogeneous medium",
        from: r#""sigma_a": 0.01, "#,
        to: r#""sigma_a": 0.01, "to_world": {"scale": 2}, "#,
        path: "media.fog.to_world",
        message: "only valid in a heterogeneous medium",
        also: &[],
    },
    ErrorCase {
        name: "majorant_resolution in a homogeneous medium",
        from: r#""scale": 2,"#,
        to: r#""scale": 2, "majorant_resolution": 4,"#,
        path: "media.smoke.majorant_resolution",
        message: "only valid in a heterogeneous medium",
        also: &[],
    },
    ErrorCase {
        name: "temperature emission in a homogeneous medium",
        from: r#""emission": {"L_ve": [0.1, 0.05, 0.01]}"#,
        to: r#""emission": {"temperature": {"type": "constant", "value": 1500}}"#,
        path: "media.smoke.emission.temperature",
        message: "needs a heterogeneous medium",
        also: &[],
    },
];

#[test]
fn medium_errors() {
    check_edits("FULL", FULL, MEDIA);
}

const PHASE_FUNCTIONS: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown hg key",
        from: r#""g": 0.3"#,
        to: r#""g": 0.3, "gg": 1"#,
        path: "media.smoke.phase.gg",
        message: "unknown field `gg`, expected `g`",
        also: &[],
    },
    ErrorCase {
        name: "field in isotropic",
        from: r#"{"type": "isotropic"}"#,
        to: r#"{"type": "isotropic", "g": 0}"#,
        path: "media.fog.phase.g",
        message: "unknown field `g`; this type has no fields besides `type`",
        also: &[],
    },
    ErrorCase {
        name: "number as a phase function",
        from: r#""phase": {"type": "hg", "g": 0.3}"#,
        to: r#""phase": 0.3"#,
        path: "media.smoke.phase",
        message: "expected a phase function object",
        also: &[],
    },
    ErrorCase {
        name: "unknown phase function type",
        from: r#""type": "hg""#,
        to: r#""type": "mie""#,
        path: "media.smoke.phase.type",
        message: r#"unknown phase function type "mie"; expected one of: isotropic, hg,"#,
        also: &[],
    },
    ErrorCase {
        name: "g of 1",
        from: r#""g": 0.3"#,
        to: r#""g": 1"#,
        path: "media.smoke.phase.g",
        message: "must be in the open interval (-1, 1), got 1",
        also: &[],
    },
    ErrorCase {
        name: "g below -1",
        from: r#""g": 0.3"#,
        to: r#""g": -1.5"#,
        path: "media.smoke.phase.g",
        message: "got -1.5",
        also: &[],
    },
    ErrorCase {
        name: "double_hg g2 of -1",
        from: r#""g2": -0.3"#,
        to: r#""g2": -1"#,
        path: "media.haze.phase.g2",
        message: "open interval (-1, 1)",
        also: &[],
    },
    ErrorCase {
        name: "double_hg weight above 1",
        from: r#""w": 0.7"#,
        to: r#""w": 1.2"#,
        path: "media.haze.phase.w",
        message: "must be in [0, 1]",
        also: &[],
    },
    ErrorCase {
        name: "schlick k of 1",
        from: r#""k": 0.5"#,
        to: r#""k": 1"#,
        path: "media.mist.phase.k",
        message: "open interval (-1, 1)",
        also: &[],
    },
    ErrorCase {
        name: "schlick k and g together",
        from: r#""k": 0.5"#,
        to: r#""k": 0.5, "g": 0.2"#,
        path: "media.mist.phase.g",
        message: "mutually exclusive",
        also: &[],
    },
    ErrorCase {
        name: "tabulated with a file and an inline table",
        from: r#""file": "mie.csv""#,
        to: r#""file": "mie.csv", "mu": [-1, 1], "p": [1, 1]"#,
        path: "media.cloud.phase.file",
        message: "`file` and `mu`/`p` are mutually exclusive",
        also: &[],
    },
    ErrorCase {
        name: "inline table without values",
        from: r#""file": "mie.csv""#,
        to: r#""mu": [-1, 1]"#,
        path: "media.cloud.phase.p",
        message: "missing field `p`",
        also: &[],
    },
    ErrorCase {
        name: "inline table not ending at mu = 1",
        from: r#""file": "mie.csv""#,
        to: r#""mu": [-1, 0, 0.5], "p": [1, 2, 3]"#,
        path: "media.cloud.phase.mu",
        message: "phase table, row 3: the last node is mu = 0.5: expected 1",
        also: &[],
    },
    ErrorCase {
        name: "inline table with a negative value",
        from: r#""file": "mie.csv""#,
        to: r#""mu": [-1, 1], "p": [1, -1]"#,
        path: "media.cloud.phase.mu",
        message: "phase table, row 2: p = -1: expected a finite value >= 0",
        also: &[],
    },
];

#[test]
fn phase_function_errors() {
    check_edits("FULL", FULL, PHASE_FUNCTIONS);
}

/// Shapes, their transforms and BSDFs.
const SHAPES: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown tangent frame",
        from: r#""interior": "haze", "exterior": "smoke"}"#,
        to: r#""interior": "haze", "exterior": "smoke", "tangent_frame": "uv"}"#,
        path: "shapes[1].tangent_frame",
        message: "unknown value `uv`",
        also: &["`normal`", "`dpdu`"],
    },
    ErrorCase {
        name: "unknown shape key lists the common fields",
        from: r#""interior": "smoke"}"#,
        to: r#""interor": "smoke"}"#,
        path: "shapes[0].interor",
        message: "unknown field `interor`",
        also: &["`interior`"],
    },
    ErrorCase {
        name: "unknown bsdf key",
        from: r#""reflectance": 0.5"#,
        to: r#""reflectanse": 0.5"#,
        path: "shapes[2].bsdf.reflectanse",
        message: "unknown field `reflectanse`",
        also: &[],
    },
    ErrorCase {
        name: "unknown transform key",
        from: r#""rotate_x": -90"#,
        to: r#""rotate": -90"#,
        path: "shapes[2].to_world.rotate",
        message: "unknown field `rotate`",
        also: &[],
    },
    ErrorCase {
        name: "sphere rotation that scales",
        from: r#""radius": 0.5,"#,
        to: r#""radius": 0.5, "rotation": {"matrix": [[2, 0, 0], [0, 1, 0], [0, 0, 1]]},"#,
        path: "shapes[1].rotation.matrix",
        message: "must be a rotation (rows orthonormal to 1e-4, determinant +1",
        also: &["radius"],
    },
    ErrorCase {
        name: "sphere rotation that mirrors",
        from: r#""radius": 0.5,"#,
        to: r#""radius": 0.5, "rotation": {"matrix": [[-1, 0, 0], [0, 1, 0], [0, 0, 1]]},"#,
        path: "shapes[1].rotation.matrix",
        message: "determinant -1.0000",
        also: &["cannot be mirrored"],
    },
    ErrorCase {
        name: "sphere rotation with a matrix and angles",
        from: r#""radius": 0.5,"#,
        to: r#""radius": 0.5, "rotation": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "rotate_z": 10},"#,
        path: "shapes[1].rotation.rotate_z",
        message: "`rotate_z` cannot be combined with `matrix`",
        also: &[],
    },
    ErrorCase {
        name: "unknown sphere rotation key",
        from: r#""radius": 0.5,"#,
        to: r#""radius": 0.5, "rotation": {"angle": 30},"#,
        path: "shapes[1].rotation.angle",
        message: "unknown field `angle`",
        also: &[],
    },
    ErrorCase {
        name: "duplicate key",
        from: r#""radius": 0.5"#,
        to: r#""radius": 0.5, "radius": 2"#,
        path: "shapes[1].radius",
        message: "duplicate key `radius`",
        also: &[],
    },
    ErrorCase {
        name: "unknown shape type",
        from: r#""type": "box""#,
        to: r#""type": "cylinder""#,
        path: "shapes[0].type",
        message: r#"unknown shape type "cylinder"; expected one of: sphere, box, rectangle"#,
        also: &[],
    },
    ErrorCase {
        name: "unknown bsdf type",
        from: r#""type": "diffuse""#,
        to: r#""type": "hair""#,
        path: "shapes[2].bsdf.type",
        message: r#"unknown bsdf type "hair""#,
        also: &[],
    },
    ErrorCase {
        name: "missing radius",
        from: r#", "radius": 0.5"#,
        to: "",
        path: "shapes[1].radius",
        message: "missing required field `radius`",
        also: &[],
    },
    ErrorCase {
        name: "string radius",
        from: r#""radius": 0.5"#,
        to: r#""radius": "0.5""#,
        path: "shapes[1].radius",
        message: "expected a number",
        also: &[],
    },
    ErrorCase {
        name: "radius beyond f32",
        from: r#""radius": 0.5"#,
        to: r#""radius": 1e39"#,
        path: "shapes[1].radius",
        message: "expected a finite number",
        also: &[],
    },
    ErrorCase {
        name: "zero radius",
        from: r#""radius": 0.5"#,
        to: r#""radius": 0"#,
        path: "shapes[1].radius",
        message: "must be > 0",
        also: &[],
    },
    ErrorCase {
        name: "object as a center",
        from: r#""center": [0, 1, 0]"#,
        to: r#""center": {"x": 0}"#,
        path: "shapes[1].center",
        message: "expected an array of 3 numbers",
        also: &[],
    },
    ErrorCase {
        name: "empty box",
        from: r#""max": [1, 2, 1]"#,
        to: r#""max": [1, 0, 1]"#,
        path: "shapes[0].max[1]",
        message: "must be greater than min[1] = 0",
        also: &[],
    },
    ErrorCase {
        name: "four-element translate",
        from: r#""translate": [0, 0, 0]"#,
        to: r#""translate": [0, 0, 0, 0]"#,
        path: "shapes[2].to_world.translate",
        message: "invalid length 4",
        also: &[],
    },
    ErrorCase {
        name: "zero transform scale",
        from: r#""scale": 10"#,
        to: r#""scale": 0"#,
        path: "shapes[2].to_world.scale",
        message: "non-zero",
        also: &[],
    },
    ErrorCase {
        name: "projective matrix",
        from: "[0, 0, 0, 1]]",
        to: "[0, 0, 1, 1]]",
        path: "shapes[3].to_world.matrix[3]",
        message: "last row must be [0, 0, 0, 1]",
        also: &[],
    },
    ErrorCase {
        name: "matrix and components together",
        from: r#"{"matrix""#,
        to: r#"{"translate": [1, 0, 0], "matrix""#,
        path: "shapes[3].to_world.translate",
        message: "cannot be combined with `matrix`",
        also: &[],
    },
    ErrorCase {
        name: "reflectance above one",
        from: r#""reflectance": 0.5"#,
        to: r#""reflectance": [0.5, 1.2, 0.5]"#,
        path: "shapes[2].bsdf.reflectance[1]",
        message: "must be in [0, 1]",
        also: &[],
    },
];

#[test]
fn shape_errors() {
    check_edits("FULL", FULL, SHAPES);
}

/// References to media by name.
const MEDIUM_NAMES: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown interior medium",
        from: r#""interior": "mist""#,
        to: r#""interior": "fgo""#,
        path: "shapes[3].interior",
        message: r#"unknown medium "fgo"; known media: cloud, fog, haze, mist, smoke"#,
        also: &[],
    },
    ErrorCase {
        name: "unknown exterior medium",
        from: r#""exterior": "smoke""#,
        to: r#""exterior": "smok""#,
        path: "shapes[1].exterior",
        message: r#"unknown medium "smok"; known media:"#,
        also: &[],
    },
    ErrorCase {
        name: "unknown ambient medium",
        from: r#""ambient_medium": "fog""#,
        to: r#""ambient_medium": "vapor""#,
        path: "ambient_medium",
        message: r#"unknown medium "vapor"; known media: cloud"#,
        also: &[],
    },
];

#[test]
fn medium_name_errors() {
    check_edits("FULL", FULL, MEDIUM_NAMES);
}

const LIGHTS: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown light key",
        from: r#""intensity": [50"#,
        to: r#""intensty": [50"#,
        path: "lights[1].intensty",
        message: "unknown field `intensty`",
        also: &[],
    },
    ErrorCase {
        name: "unknown light type",
        from: r#""type": "point""#,
        to: r#""type": "laser""#,
        path: "lights[1].type",
        message: r#"unknown light type "laser"; expected one of: point, spot, directional, constant"#,
        also: &[],
    },
    ErrorCase {
        name: "missing light type",
        from: r#"{"type": "constant", "radiance": [0.05, 0.07, 0.1]}"#,
        to: r#"{"radiance": 1}"#,
        path: "lights[3].type",
        message: "missing required field `type`; expected one of: point",
        also: &[],
    },
    ErrorCase {
        name: "string in an intensity",
        from: "[50, 45, 40]",
        to: r#"[50, 45, "40"]"#,
        path: "lights[1].intensity[2]",
        message: "expected a number",
        also: &[],
    },
    ErrorCase {
        name: "intensity beyond f64",
        from: "[50, 45, 40]",
        to: "[50, 1e400, 40]",
        path: "lights[1].intensity[1]",
        message: "number out of range",
        also: &["line"],
    },
    ErrorCase {
        name: "object as an intensity",
        from: r#""intensity": 100"#,
        to: r#""intensity": {"r": 100}"#,
        path: "lights[2].intensity",
        message: "invalid type: map, expected a number or an array of 3 numbers",
        also: &[],
    },
    ErrorCase {
        name: "beam wider than the cutoff",
        from: r#""cutoff_angle": 30"#,
        to: r#""cutoff_angle": 30, "beam_width": 40"#,
        path: "lights[2].beam_width",
        message: "must be in (0, cutoff_angle = 30]",
        also: &[],
    },
    ErrorCase {
        name: "cutoff beyond 90 degrees",
        from: r#""cutoff_angle": 30"#,
        to: r#""cutoff_angle": 120"#,
        path: "lights[2].cutoff_angle",
        message: "(0, 90]",
        also: &[],
    },
    ErrorCase {
        name: "spot target and direction together",
        from: r#""target": [0, 0, 0], "intensity""#,
        to: r#""target": [0, 0, 0], "direction": [0, -1, 0], "intensity""#,
        path: "lights[2].direction",
        message: "mutually exclusive",
        also: &[],
    },
    ErrorCase {
        name: "zero direction",
        from: "[-0.3, -1, -0.2]",
        to: "[0, 0, 0]",
        path: "lights[0].direction",
        message: "non-zero",
        also: &[],
    },
    ErrorCase {
        name: "negative irradiance",
        from: r#""irradiance": 3.0"#,
        to: r#""irradiance": -3.0"#,
        path: "lights[0].irradiance",
        message: "must be >= 0",
        also: &[],
    },
];

#[test]
fn light_errors() {
    check_edits("FULL", FULL, LIGHTS);
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

/// Density sources: inline grids, files, constants and procedural noise.
const GRID_DENSITY: &[ErrorCase] = &[
    ErrorCase {
        name: "inline grid of the wrong length",
        from: "[0, 0.5, 1, 2, 0, 0, 0, 3]",
        to: "[0, 0.5, 1, 2, 0, 0, 3]",
        path: "media.smoke.density.data",
        message: "= 8 values",
        also: &["got 7", "dims [2, 2, 2]"],
    },
    ErrorCase {
        name: "negative inline value",
        from: "[0, 0.5, 1, 2, 0, 0, 0, 3]",
        to: "[0, 0.5, 1, 2, 0, -0.5, 0, 3]",
        path: "media.smoke.density.data[5]",
        message: "must be >= 0, got -0.5",
        also: &[],
    },
    ErrorCase {
        name: "inline value beyond f32",
        from: "[0, 0.5, 1, 2, 0, 0, 0, 3]",
        to: "[0, 0.5, 1, 2, 0, 0, 0, 1e39]",
        path: "media.smoke.density.data[7]",
        message: "expected a finite number",
        also: &[],
    },
    ErrorCase {
        name: "string inline value",
        from: "[0, 0.5, 1, 2, 0, 0, 0, 3]",
        to: r#"[0, 0.5, 1, "2", 0, 0, 0, 3]"#,
        path: "media.smoke.density.data[3]",
        message: "expected a number",
        also: &[],
    },
    ErrorCase {
        name: "zero dims",
        from: r#""dims": [2, 2, 2]"#,
        to: r#""dims": [2, 2, 0]"#,
        path: "media.smoke.density.dims[2]",
        message: "must be at least 1, got 0",
        also: &[],
    },
    ErrorCase {
        name: "too many cells",
        from: r#""dims": [2, 2, 2]"#,
        to: r#""dims": [65536, 65536, 1]"#,
        path: "media.smoke.density.dims",
        message: "exceeds the limit of 268435456 (2^28)",
        also: &[],
    },
    ErrorCase {
        name: "two dims",
        from: r#""dims": [2, 2, 2]"#,
        to: r#""dims": [2, 2]"#,
        path: "media.smoke.density.dims",
        message: "invalid length 2",
        also: &[],
    },
    ErrorCase {
        name: "negative dims",
        from: r#""dims": [2, 2, 2]"#,
        to: r#""dims": [2, -2, 2]"#,
        path: "media.smoke.density.dims[1]",
        message: "expected a whole number",
        also: &[],
    },
    ErrorCase {
        name: "empty bounds",
        from: r#""max": [1, 1, 1]"#,
        to: r#""max": [1, -1, 1]"#,
        path: "media.smoke.density.bounds.max[1]",
        message: "must be greater than min[1] = -1, got -1",
        also: &[],
    },
    ErrorCase {
        name: "bounds without max",
        from: r#", "max": [1, 1, 1]"#,
        to: "",
        path: "media.smoke.density.bounds.max",
        message: "missing required field `max`",
        also: &[],
    },
    ErrorCase {
        name: "unknown bounds key",
        from: r#""max": [1, 1, 1]"#,
        to: r#""max": [1, 1, 1], "centre": [0, 0, 0]"#,
        path: "media.smoke.density.bounds.centre",
        message: "unknown field `centre`",
        also: &[],
    },
    ErrorCase {
        name: "grid medium without density",
        from: r#""plume": {"type": "grid", "sigma_t": 2, "albedo": 0.9, "density": {"type": "vdb", "file": "plume.vdb"}}"#,
        to: r#""plume": {"type": "grid", "sigma_t": 2, "albedo": 0.9}"#,
        path: "media.plume.density",
        message: "missing required field `density`: a grid medium needs a density source",
        also: &[],
    },
    ErrorCase {
        name: "unknown density source type",
        from: r#"{"type": "vdb", "file": "plume.vdb"}"#,
        to: r#"{"type": "openvdb", "file": "plume.vdb"}"#,
        path: "media.plume.density.type",
        message: r#"unknown density source type "openvdb"; expected one of: constant, grid, npy, vol, vdb, procedural"#,
        also: &[],
    },
    ErrorCase {
        name: "density source without type",
        from: r#"{"type": "vdb", "file": "plume.vdb"}"#,
        to: r#"{"file": "plume.vdb"}"#,
        path: "media.plume.density.type",
        message: "missing required field `type`",
        also: &[],
    },
    ErrorCase {
        name: "unknown vdb key",
        from: r#"{"type": "vdb", "file": "plume.vdb"}"#,
        to: r#"{"type": "vdb", "file": "plume.vdb", "gird": "density"}"#,
        path: "media.plume.density.gird",
        message: "unknown field `gird`, expected `file` or `grid`",
        also: &[],
    },
    ErrorCase {
        name: "npy without file",
        from: r#"{"type": "npy", "file": "glow.npy"}"#,
        to: r#"{"type": "npy"}"#,
        path: "media.cloud.emission.grid.file",
        message: "missing required field `file`",
        also: &[],
    },
    ErrorCase {
        name: "empty file name",
        from: r#""file": "bunny.vol""#,
        to: r#""file": """#,
        path: "media.bunny.density.file",
        message: "expected a file name",
        also: &[],
    },
    ErrorCase {
        name: "empty grid name",
        from: r#""grid": "temperature""#,
        to: r#""grid": """#,
        path: "media.smoke.emission.temperature.grid",
        message: "expected a grid name",
        also: &[],
    },
    ErrorCase {
        name: "number as a density source",
        from: r#""density": {"type": "vol", "file": "bunny.vol"}"#,
        to: r#""density": 1"#,
        path: "media.bunny.density",
        message: r#"expected a density source object with a "type" field"#,
        also: &[],
    },
    ErrorCase {
        name: "negative constant density",
        from: r#""value": 2"#,
        to: r#""value": -2"#,
        path: "media.slab.density.value",
        message: "must be >= 0, got -2",
        also: &[],
    },
    ErrorCase {
        name: "coverage above one",
        from: r#""coverage": 0.4"#,
        to: r#""coverage": 1.5"#,
        path: "media.cloud.density.coverage",
        message: "must be in [0, 1], got 1.5",
        also: &[],
    },
    ErrorCase {
        name: "zero sharpness",
        from: r#""coverage": 0.4"#,
        to: r#""coverage": 0.4, "sharpness": 0"#,
        path: "media.cloud.density.sharpness",
        message: "must be in (0, 1000], got 0",
        also: &[],
    },
    ErrorCase {
        name: "lacunarity below one",
        from: r#""coverage": 0.4"#,
        to: r#""coverage": 0.4, "lacunarity": 0.5"#,
        path: "media.cloud.density.lacunarity",
        message: "must be in [1, 8], got 0.5",
        also: &[],
    },
    ErrorCase {
        name: "zero octaves",
        from: r#""coverage": 0.4"#,
        to: r#""coverage": 0.4, "octaves": 0"#,
        path: "media.cloud.density.octaves",
        message: "must be from 1 to 12, got 0",
        also: &[],
    },
    ErrorCase {
        name: "unknown procedural shape",
        from: r#""shape": "plume""#,
        to: r#""shape": "smoke""#,
        path: "media.cloud.density.shape",
        message: "unknown value `smoke`, expected `cloud` or `plume`",
        also: &[],
    },
    ErrorCase {
        name: "negative seed",
        from: r#""seed": 42"#,
        to: r#""seed": -42"#,
        path: "media.cloud.density.seed",
        message: "expected a whole number >= 0",
        also: &[],
    },
    ErrorCase {
        name: "zero procedural resolution",
        from: r#""resolution": [32, 48, 32]"#,
        to: r#""resolution": [32, 0, 32]"#,
        path: "media.cloud.density.resolution[1]",
        message: "must be at least 1",
        also: &[],
    },
    ErrorCase {
        name: "too many procedural cells",
        from: r#""resolution": [32, 48, 32]"#,
        to: r#""resolution": 1024"#,
        path: "media.cloud.density.resolution",
        message: "1024 x 1024 x 1024 = 1073741824 cells exceeds the limit",
        also: &[],
    },
    ErrorCase {
        name: "procedural resolution above 1024",
        from: r#""resolution": [32, 48, 32]"#,
        to: r#""resolution": [32, 2048, 32]"#,
        path: "media.cloud.density.resolution[1]",
        message: "must be at most 1024, got 2048",
        also: &[],
    },
    ErrorCase {
        name: "unknown procedural key",
        from: r#""seed": 42"#,
        to: r#""seed": 42, "octave": 3"#,
        path: "media.cloud.density.octave",
        message: "unknown field `octave`",
        also: &[],
    },
];

#[test]
fn grid_density_errors() {
    check_edits("GRID", GRID, GRID_DENSITY);
}

/// Grid emission takes exactly one form.
const GRID_EMISSION: &[ErrorCase] = &[
    ErrorCase {
        name: "temperature and L_ve together",
        from: r#""emission": {"L_ve": [0.1, 0.2, 0.3]}"#,
        to: r#""emission": {"L_ve": [0.1, 0.2, 0.3], "temperature": {"type": "constant"}}"#,
        path: "media.bunny.emission.temperature",
        message: "`temperature` cannot be combined with `L_ve`: give exactly one of",
        also: &[],
    },
    ErrorCase {
        name: "no emission form",
        from: r#""emission": {"L_ve": [0.1, 0.2, 0.3]}"#,
        to: r#""emission": {"emission_scale": 3}"#,
        path: "media.bunny.emission",
        message: "missing emission: give exactly one of `L_ve`",
        also: &[],
    },
    ErrorCase {
        name: "emission_scale with L_ve",
        from: r#""emission": {"L_ve": [0.1, 0.2, 0.3]}"#,
        to: r#""emission": {"L_ve": [0.1, 0.2, 0.3], "emission_scale": 3}"#,
        path: "media.bunny.emission.emission_scale",
        message: "`emission_scale` goes with `grid` or `temperature`",
        also: &[],
    },
    ErrorCase {
        name: "color with temperature",
        from: r#""emission_scale": 1.5"#,
        to: r#""emission_scale": 1.5, "color": 2"#,
        path: "media.smoke.emission.color",
        message: "`color` goes with `grid` only",
        also: &[],
    },
    ErrorCase {
        name: "negative emission_scale",
        from: r#""emission_scale": 1.5"#,
        to: r#""emission_scale": -1.5"#,
        path: "media.smoke.emission.emission_scale",
        message: "must be >= 0, got -1.5",
        also: &[],
    },
    ErrorCase {
        name: "negative color channel",
        from: r#""color": [1, 0.5, 0.2]"#,
        to: r#""color": [1, -0.5, 0.2]"#,
        path: "media.cloud.emission.color[1]",
        message: "must be >= 0",
        also: &[],
    },
    ErrorCase {
        name: "negative L_ve channel",
        from: r#""L_ve": [0.1, 0.2, 0.3]"#,
        to: r#""L_ve": [0.1, 0.2, -0.3]"#,
        path: "media.bunny.emission.L_ve[2]",
        message: "must be >= 0",
        also: &[],
    },
    ErrorCase {
        name: "unknown emission key",
        from: r#""emission_scale": 2"#,
        to: r#""emission_scale": 2, "colour": 1"#,
        path: "media.cloud.emission.colour",
        message: "unknown field `colour`",
        also: &[],
    },
    ErrorCase {
        name: "empty emission grid bounds",
        from: r#""grid": {"type": "npy", "file": "glow.npy"}"#,
        to: r#""grid": {"type": "npy", "file": "glow.npy", "bounds": {"min": [0, 0, 0], "max": [0, 1, 1]}}"#,
        path: "media.cloud.emission.grid.bounds.max[0]",
        message: "must be greater than min[0]",
        also: &[],
    },
];

#[test]
fn grid_emission_errors() {
    check_edits("GRID", GRID, GRID_EMISSION);
}

/// Grid media's own fields, and the integrator of `GRID`.
const GRID_MEDIA: &[ErrorCase] = &[
    ErrorCase {
        name: "unknown transmittance",
        from: r#""transmittance": "residual_ratio""#,
        to: r#""transmittance": "residual""#,
        path: "render.integrator.transmittance",
        message: "unknown value `residual`, expected one of `analytic`, `ray_march`, `delta`, `ratio`, \
                  `residual_ratio`",
        also: &[],
    },
    ErrorCase {
        name: "zero majorant resolution",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_resolution": 0"#,
        path: "media.bunny.majorant_resolution",
        message: "must be at least 1, got 0",
        also: &[],
    },
    ErrorCase {
        name: "majorant resolution above 256",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_resolution": 257"#,
        path: "media.bunny.majorant_resolution",
        message: "must be at most 256, got 257",
        also: &[],
    },
    ErrorCase {
        name: "majorant resolution axis above 256",
        from: r#""majorant_resolution": [4, 4, 2]"#,
        to: r#""majorant_resolution": [4, 300, 2]"#,
        path: "media.smoke.majorant_resolution[1]",
        message: "must be at most 256, got 300",
        also: &[],
    },
    ErrorCase {
        name: "fractional majorant resolution",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_resolution": 2.5"#,
        path: "media.bunny.majorant_resolution",
        message: "a whole number >= 1 or an array of 3 whole numbers [nx, ny, nz]",
        also: &[],
    },
    ErrorCase {
        name: "negative majorant resolution",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_resolution": -3"#,
        path: "media.bunny.majorant_resolution",
        message: "a whole number >= 1 or an array of 3 whole numbers [nx, ny, nz]",
        also: &[],
    },
    ErrorCase {
        name: "string majorant resolution",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_resolution": "16""#,
        path: "media.bunny.majorant_resolution",
        message: "a whole number >= 1 or an array of 3 whole numbers [nx, ny, nz]",
        also: &[],
    },
    ErrorCase {
        name: "two-element majorant resolution",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_resolution": [4, 4]"#,
        path: "media.bunny.majorant_resolution",
        message: "a whole number >= 1 or an array of 3 whole numbers [nx, ny, nz]",
        also: &[],
    },
    ErrorCase {
        name: "unknown grid medium key",
        from: r#""majorant_resolution": 8"#,
        to: r#""majorant_res": 8"#,
        path: "media.bunny.majorant_res",
        message: "unknown field `majorant_res`",
        also: &[],
    },
    ErrorCase {
        name: "negative sigma_s channel",
        from: r#""sigma_s": [1, 2, 3]"#,
        to: r#""sigma_s": [1, -2, 3]"#,
        path: "media.cloud.sigma_s[1]",
        message: "must be >= 0",
        also: &[],
    },
    ErrorCase {
        name: "both coefficient forms",
        from: r#""albedo": 0.9"#,
        to: r#""albedo": 0.9, "sigma_a": 1"#,
        path: "media.plume.sigma_t",
        message: "`sigma_t` cannot be combined with `sigma_a`",
        also: &[],
    },
    ErrorCase {
        name: "zero scale",
        from: r#""scale": 5"#,
        to: r#""scale": 0"#,
        path: "media.cloud.scale",
        message: "must be > 0",
        also: &[],
    },
    ErrorCase {
        name: "zero transform scale",
        from: r#""scale": 2}"#,
        to: r#""scale": 0}"#,
        path: "media.smoke.to_world.scale",
        message: "scale factors must be non-zero",
        also: &[],
    },
    ErrorCase {
        name: "g above 1",
        from: r#""g": 0.3"#,
        to: r#""g": 1.3"#,
        path: "media.smoke.phase.g",
        message: "open interval (-1, 1)",
        also: &[],
    },
];

#[test]
fn grid_medium_errors() {
    check_edits("GRID", GRID, GRID_MEDIA);
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
