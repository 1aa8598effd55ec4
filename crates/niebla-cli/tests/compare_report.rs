//! `niebla compare` as a user meets it: a real child process writes a real
//! report, which is checked as text and, where Chromium is installed, in a
//! headless browser (scripts/test.sh installs it on Debian when it can;
//! this test installs nothing).

use std::path::{Path, PathBuf};
use std::process::Command;

use base64::Engine as _;

const TINY_SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 32, "height": 24},
  "render": {"integrator": {"type": "single", "sampling": "mis"}, "spp": 2},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 0.6}},
  "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}],
  "lights": [{"type": "point", "position": [1, 3, 1], "intensity": 10}, {"type": "constant", "radiance": 0.1}]
}"#;

const CHROMIUM: &str = "/usr/bin/chromium";

fn niebla() -> Command {
    Command::new(env!("CARGO_BIN_EXE_niebla"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The base64 payloads of the report's `data:image/png` URIs.
fn embedded_pngs(html: &str) -> Vec<Vec<u8>> {
    html.split("data:image/png;base64,")
        .skip(1)
        .map(|rest| {
            let end = rest.find('"').expect("a data URI ends with a quote");
            base64::engine::general_purpose::STANDARD.decode(&rest[..end]).expect("valid base64")
        })
        .collect()
}

fn png_size(bytes: &[u8]) -> (u32, u32) {
    let reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().expect("a valid PNG");
    (reader.info().width, reader.info().height)
}

/// Runs `niebla compare` and returns the report's text.
fn compare(dir: &Path, args: &[&str]) -> String {
    let out = niebla().current_dir(dir).arg("compare").args(args).arg("--quiet").output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::read_to_string(dir.join("report.html")).unwrap()
}

/// The value of attribute `name` on the report's `<body>` in a DOM dump.
fn body_attribute(dom: &str, name: &str) -> Option<String> {
    let body = &dom[dom.find("<body")?..];
    let body = &body[..body.find('>')?];
    let start = body.find(&format!("{name}=\""))? + name.len() + 2;
    Some(body[start..start + body[start..].find('"')?].to_string())
}

#[test]
fn compare_writes_a_self_contained_report_with_images_table_and_plot() {
    let dir = temp_dir("compare_tiny");
    std::fs::write(dir.join("tiny.json"), TINY_SCENE).unwrap();
    let html = compare(
        &dir,
        &["tiny.json", "--integrators", "volpath,single:mis,emission", "--time-budget", "0.2"]
            .into_iter()
            .chain(["--reference-spp", "16", "--save-reference", "ref.exr", "-o", "report.html"])
            .collect::<Vec<_>>(),
    );
    // Reference + three images + three error maps, each a PNG of the scene's size.
    let pngs = embedded_pngs(&html);
    assert_eq!(pngs.len(), 7);
    assert!(pngs.iter().all(|p| png_size(p) == (32, 24)));
    // The convergence plot and the color bar are inline SVG drawn by plotters.
    assert_eq!(html.matches("<svg class=\"plot\"").count(), 2);
    assert!(html.contains("relative MSE against render time"));
    for label in ["volpath", "single:mis", "emission"] {
        assert!(html.contains(&format!("<tr><td>{label}</td>")), "no table row for {label}");
    }
    // Nothing is fetched from elsewhere: every source is a data URI.
    assert_eq!(html.matches("src=\"").count(), html.matches("src=\"data:image/png;base64,").count());
    assert!(!html.contains("<link") && !html.contains("url(") && !html.contains("href="));

    // The saved reference can be given back; the report then names it.
    let html =
        compare(&dir, &["tiny.json", "--integrators", "single", "--time-budget", "0.1", "--reference", "ref.exr"]);
    assert_eq!(embedded_pngs(&html).len(), 3);
    assert!(html.contains("ref.exr (given)"));
}

#[test]
fn compare_rejects_bad_integrators_and_references() {
    let dir = temp_dir("compare_errors");
    std::fs::write(dir.join("tiny.json"), TINY_SCENE).unwrap();
    let run = |args: &[&str]| {
        let out =
            niebla().current_dir(&dir).arg("compare").arg("tiny.json").args(args).arg("--quiet").output().unwrap();
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let stderr = run(&["--integrators", "volpath,warp-drive"]);
    assert!(stderr.contains("render.integrator.type") && stderr.contains("warp-drive"), "{stderr}");
    let stderr = run(&["--integrators", "single:sideways"]);
    assert!(stderr.contains("render.integrator.sampling"), "{stderr}");
    let stderr = run(&["--reference", "missing.exr"]);
    assert!(stderr.contains("missing.exr: reference image not found"), "{stderr}");
    let stderr = run(&["--time-budget", "0"]);
    assert!(stderr.contains("--time-budget"), "{stderr}");
    assert!(!dir.join("report.html").exists());
}

#[test]
fn smoke_report_opens_in_headless_chromium_with_every_image_and_plot() {
    let dir = temp_dir("compare_smoke");
    let scene = repo_root().join("scenes/smoke.json");
    let html = compare(
        &dir,
        &[scene.to_str().unwrap(), "--integrators", "volpath,single:mis", "--time-budget", "0.5"]
            .into_iter()
            .chain(["--reference-spp", "8", "-o", "report.html"])
            .collect::<Vec<_>>(),
    );
    assert_eq!(embedded_pngs(&html).len(), 5);
    if !Path::new(CHROMIUM).exists() {
        eprintln!("note: {CHROMIUM} is missing, so the report was not opened in a browser");
        return;
    }
    let report = dir.join("report.html").canonicalize().unwrap();
    let url = format!("file://{}", report.display());
    let browser = |extra: &[&str]| {
        let profile = dir.join("chromium-profile");
        let out = Command::new(CHROMIUM)
            .args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"])
            .args(["--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars"])
            .arg(format!("--user-data-dir={}", profile.display()))
            .args(extra)
            .arg(&url)
            .output()
            .expect("chromium runs");
        assert!(out.status.success(), "chromium failed: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    // The DOM after the load event: the report's script has counted the
    // images the browser decoded and the plots it found.
    let dom = browser(&["--dump-dom"]);
    assert_eq!(body_attribute(&dom, "data-images").as_deref(), Some("5"), "{}", &dom[..dom.len().min(400)]);
    assert_eq!(body_attribute(&dom, "data-images-decoded").as_deref(), Some("5"));
    assert_eq!(body_attribute(&dom, "data-plots").as_deref(), Some("2"));
    // And it draws: a screenshot of the page has many distinct colors.
    let shot = dir.join("shot.png");
    browser(&["--window-size=1200,1600", &format!("--screenshot={}", shot.display())]);
    let decoder = png::Decoder::new(std::fs::File::open(&shot).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut buffer).unwrap();
    let bytes = &buffer[..frame.buffer_size()];
    let channels = frame.color_type.samples();
    let mut colors: Vec<&[u8]> = bytes.chunks(channels).collect();
    colors.sort_unstable();
    colors.dedup();
    assert!(colors.len() > 1000, "the screenshot has only {} colors", colors.len());
}
