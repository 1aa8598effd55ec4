//! The viewer's server against raw HTTP requests: the token, origins and
//! hosts, size limits and malformed messages, abrupt disconnects, two
//! clients, files outside the scene's folder, edits validated as scene
//! files, saving without overwriting, and the transported frame against
//! `niebla::render::render` of the same scene, spp and seed.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use niebla_view::{ViewConfig, ViewServer};
use serde_json::{json, Value};

/// A small fog scene (homogeneous medium in a box, a point light), `single`, 8 spp, seed 3.
const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "fov_y": 45, "width": 24, "height": 16},
  "render": {"integrator": {"type": "single", "sampling": "mis"}, "spp": 8, "seed": 3},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 0.4, "phase": {"type": "hg", "g": 0.3}}},
  "shapes": [{"type": "box", "min": [-3, -1, -3], "max": [3, 4, 3], "interior": "fog"},
             {"type": "rectangle", "to_world": {"scale": 3, "rotate_x": -90}, "bsdf": {"type": "diffuse", "reflectance": 0.5}}],
  "lights": [{"type": "point", "position": [0.5, 2.5, 0.5], "intensity": [20, 18, 15]}]
}"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("niebla-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

struct Viewer {
    server: Option<ViewServer>,
    port: u16,
    token: String,
    dir: PathBuf,
}

impl Viewer {
    fn start(name: &str) -> Viewer {
        Viewer::start_with(name, SCENE)
    }

    /// A viewer of `scene`, written to `fog.json` in a new folder.
    fn start_with(name: &str, scene: &str) -> Viewer {
        let dir = temp_dir(name);
        std::fs::write(dir.join("fog.json"), scene).unwrap();
        let config = ViewConfig { scene: Some(dir.join("fog.json")), threads: Some(2), ..ViewConfig::default() };
        let server = ViewServer::start(&config).unwrap();
        let token = server.url().split("/t/").nth(1).unwrap().trim_end_matches('/').to_string();
        Viewer { port: server.port(), token, server: Some(server), dir }
    }

    fn path(&self, route: &str) -> String {
        format!("/t/{}/{route}", self.token)
    }

    /// One request with `Connection: close`: (status, headers lowercased, body).
    fn request(
        &self,
        method: &str,
        path: &str,
        extra: &[(&str, &str)],
        body: &[u8],
    ) -> (u16, Vec<(String, String)>, Vec<u8>) {
        let mut stream = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        stream.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
        let mut head = format!(
            "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nConnection: close\r\nContent-Length: {}\r\n",
            self.port,
            body.len()
        );
        for (name, value) in extra {
            head.push_str(&format!("{name}: {value}\r\n"));
        }
        head.push_str("\r\n");
        // The server may answer (413) and close before a large body is sent.
        let _ = stream.write_all(head.as_bytes()).and_then(|()| stream.write_all(body));
        let mut bytes = Vec::new();
        stream.read_to_end(&mut bytes).unwrap();
        let split = bytes.windows(4).position(|w| w == b"\r\n\r\n").expect("a complete response");
        let head = String::from_utf8_lossy(&bytes[..split]).to_string();
        let mut lines = head.lines();
        let status = lines.next().unwrap().split(' ').nth(1).unwrap().parse().unwrap();
        let headers = lines
            .filter_map(|l| l.split_once(':'))
            .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_string()))
            .collect();
        let mut body = bytes[split + 4..].to_vec();
        if head.to_ascii_lowercase().contains("transfer-encoding: chunked") {
            body = unchunk(&body);
        }
        (status, headers, body)
    }

    fn get(&self, route: &str) -> (u16, Vec<(String, String)>, Vec<u8>) {
        self.request("GET", &self.path(route), &[], b"")
    }

    fn post(&self, route: &str, body: &Value) -> (u16, Value) {
        let (status, _, body) = self.request("POST", &self.path(route), &[], body.to_string().as_bytes());
        (status, serde_json::from_slice(&body).unwrap())
    }

    /// The first frame of slot 0 with at least `spp` samples per pixel whose scene version is at least `version`.
    fn frame_with_spp(&self, spp: u64, version: u64) -> (Vec<(String, String)>, Vec<u8>) {
        let start = Instant::now();
        let mut after = 0;
        while start.elapsed() < Duration::from_secs(120) {
            let (status, headers, body) = self.get(&format!("api/frame?slot=0&after={after}"));
            assert!(status == 200 || status == 204, "status {status}");
            if status == 204 {
                continue;
            }
            let h = |name: &str| header(&headers, name);
            assert_eq!(h("x-niebla-event"), "frame", "{}", String::from_utf8_lossy(&body));
            after = h("x-niebla-id").parse().unwrap();
            if h("x-niebla-spp").parse::<u64>().unwrap() >= spp
                && h("x-niebla-version").parse::<u64>().unwrap() >= version
            {
                return (headers, body);
            }
        }
        panic!("no frame with {spp} spp within two minutes");
    }

    fn alive(&self) {
        let (status, _, body) = self.get("api/state");
        assert_eq!(status, 200);
        let state: Value = serde_json::from_slice(&body).unwrap();
        assert_eq!(state["label"], json!(self.dir.join("fog.json").display().to_string()));
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        if let Some(server) = self.server.take() {
            server.stop();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn header(headers: &[(String, String)], name: &str) -> String {
    headers.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone()).unwrap_or_default()
}

fn unchunk(mut body: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let line_end = body.windows(2).position(|w| w == b"\r\n").unwrap();
        let size = usize::from_str_radix(std::str::from_utf8(&body[..line_end]).unwrap().trim(), 16).unwrap();
        if size == 0 {
            return out;
        }
        out.extend_from_slice(&body[line_end + 2..line_end + 2 + size]);
        body = &body[line_end + 4 + size..];
    }
}

#[test]
fn requests_without_the_token_or_from_other_origins_are_refused() {
    let viewer = Viewer::start("token");
    assert_eq!(viewer.get("").0, 200);
    let wrong = "0".repeat(32);
    for path in
        ["/", "/api/state", "/t/", "/t/abc/api/state", &format!("/t/{wrong}/api/state"), &format!("/t/{wrong}/")]
    {
        let (status, _, body) = viewer.request("GET", path, &[], b"");
        assert_eq!(status, 403, "{path}");
        assert!(!String::from_utf8_lossy(&body).contains("\"scene\""));
    }
    let state = viewer.path("api/state");
    assert_eq!(viewer.request("GET", &state, &[("Origin", "http://evil.example")], b"").0, 403);
    assert_eq!(viewer.request("GET", &state, &[("Sec-Fetch-Site", "cross-site")], b"").0, 403);
    let origin = format!("http://127.0.0.1:{}", viewer.port);
    assert_eq!(viewer.request("GET", &state, &[("Origin", &origin), ("Sec-Fetch-Site", "same-origin")], b"").0, 200);
    // A page of another origin that resolves its own name to 127.0.0.1 (DNS rebinding) sends its own Host.
    let mut stream = TcpStream::connect(("127.0.0.1", viewer.port)).unwrap();
    write!(stream, "GET {state} HTTP/1.1\r\nHost: evil.example:{}\r\nConnection: close\r\n\r\n", viewer.port).unwrap();
    let mut reply = String::new();
    stream.read_to_string(&mut reply).unwrap();
    assert!(reply.starts_with("HTTP/1.1 403"), "{reply}");
}

#[test]
fn oversize_and_malformed_messages_get_errors_and_the_server_lives() {
    let viewer = Viewer::start("malformed");
    let big = vec![b' '; niebla_view::MAX_BODY + 1];
    let (status, _, body) = viewer.request("POST", &viewer.path("api/scene"), &[], &big);
    assert_eq!(status, 413, "{}", String::from_utf8_lossy(&body));
    viewer.alive();
    // A claimed length over the limit is refused before anything is read.
    let mut stream = TcpStream::connect(("127.0.0.1", viewer.port)).unwrap();
    write!(
        stream,
        "POST {} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nContent-Length: 999999999999\r\nConnection: close\r\n\r\n{{",
        viewer.path("api/scene"),
        viewer.port
    )
    .unwrap();
    let mut reply = String::new();
    let _ = stream.read_to_string(&mut reply);
    assert!(reply.starts_with("HTTP/1.1 413"), "{reply}");
    viewer.alive();
    for (bad, status) in [
        (&b"{not json"[..], 400),
        (b"[1, 2]", 400),
        (b"{\"interactive\": 3}", 400),
        (b"{\"max_spp\": 0}", 400),
        (b"\xff\xfe", 400),
    ] {
        let (got, _, body) = viewer.request("POST", &viewer.path("api/scene"), &[], bad);
        let reply: Value = serde_json::from_slice(&body).unwrap();
        assert_eq!(got, status, "{reply}");
        assert!(reply["error"].as_str().unwrap().starts_with("malformed message"), "{reply}");
    }
    assert_eq!(viewer.post("api/save", &json!({"format": "gif"})).0, 400);
    assert_eq!(viewer.get("api/frame?slot=7").0, 400);
    assert_eq!(viewer.request("DELETE", &viewer.path("api/scene"), &[], b"").0, 405);
    viewer.alive();
}

#[test]
fn an_invalid_edit_gets_the_parsers_message_and_the_render_goes_on() {
    let viewer = Viewer::start("invalid");
    let mut scene: Value = serde_json::from_str(SCENE).unwrap();
    scene["media"]["fog"]["sigma_s"] = json!(-1.0);
    let (status, reply) = viewer.post("api/scene", &json!({ "scene": scene }));
    assert_eq!(status, 422);
    let label = viewer.dir.join("fog.json").display().to_string();
    let expected = niebla::scene::parse_scene_str(&scene.to_string(), &label).unwrap_err().to_string();
    assert_eq!(reply["error"], json!(expected));
    assert!(expected.contains("media.fog.sigma_s"), "{expected}");
    // A split view with an integrator setting that does not parse.
    let (status, reply) = viewer.post("api/scene", &json!({ "compare": {"type": "volpath", "max_depth": -2} }));
    assert_eq!(status, 422);
    assert!(reply["error"].as_str().unwrap().starts_with("split view: "), "{reply}");
    // The unedited scene still renders.
    viewer.frame_with_spp(1, 1);
}

#[test]
fn files_outside_the_scene_folder_are_neither_served_nor_read() {
    let viewer = Viewer::start("traversal");
    std::fs::write(viewer.dir.join("secret.txt"), "CONTENT-OF-THE-SECRET").unwrap();
    for route in
        ["../fog.json", "..%2F..%2Fetc%2Fpasswd", "secret.txt", "fog.json", "%2e%2e/%2e%2e/etc/passwd", "/etc/passwd"]
    {
        let (status, _, body) = viewer.get(route);
        assert!(status == 404 || status == 403, "{route}: {status}");
        let text = String::from_utf8_lossy(&body);
        assert!(
            !text.contains("CONTENT-OF") && !text.contains("root:") && !text.contains("perspective"),
            "{route}: {text}"
        );
    }
    let mut scene: Value = serde_json::from_str(SCENE).unwrap();
    for file in ["../outside.csv", "/etc/passwd", "sub/../../outside.csv"] {
        scene["media"]["fog"]["phase"] = json!({"type": "tabulated", "file": file});
        let (status, reply) = viewer.post("api/scene", &json!({ "scene": scene }));
        assert_eq!(status, 422, "{reply}");
        let error = reply["error"].as_str().unwrap();
        assert!(error.contains("media.fog.phase.file") && error.contains("outside the scene's folder"), "{error}");
    }
}

#[test]
fn abrupt_disconnects_and_two_clients_do_not_disturb_the_render() {
    let viewer = Viewer::start("clients");
    let target = ("127.0.0.1", viewer.port);
    // Half a request line, half a body, a frame request dropped while it waits.
    for partial in [
        "GET /t/".to_string(),
        format!(
            "POST {} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nContent-Length: 100\r\n\r\n{{\"sce",
            viewer.path("api/scene"),
            viewer.port
        ),
        format!(
            "GET {} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n\r\n",
            viewer.path("api/frame?slot=0&after=999"),
            viewer.port
        ),
    ] {
        let mut stream = TcpStream::connect(target).unwrap();
        stream.write_all(partial.as_bytes()).unwrap();
        std::thread::sleep(Duration::from_millis(50));
        drop(stream);
    }
    viewer.alive();
    // Two clients read the same frames.
    assert_eq!(viewer.post("api/scene", &json!({ "max_spp": 8 })).0, 200);
    let (frames_a, frames_b) = std::thread::scope(|s| {
        let a = s.spawn(|| viewer.frame_with_spp(8, 2));
        let b = s.spawn(|| viewer.frame_with_spp(8, 2));
        (a.join().unwrap(), b.join().unwrap())
    });
    assert_eq!(frames_a.1, frames_b.1);
    assert_eq!(frames_a.1.len(), 24 * 16 * 6);
    // A client that drops a frame half-read.
    let mut stream = TcpStream::connect(target).unwrap();
    write!(
        stream,
        "GET {} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n\r\n",
        viewer.path("api/frame?slot=0&after=0"),
        viewer.port
    )
    .unwrap();
    let mut some = [0u8; 64];
    let _ = stream.read(&mut some).unwrap();
    drop(stream);
    viewer.alive();
}

/// The frame at 8 spp, decoded from half floats, equals the one-shot render of
/// the same scene, spp and seed rounded to half floats, bit for bit.
#[test]
fn the_transported_frame_is_the_render_rounded_to_half_floats() {
    let viewer = Viewer::start("equal");
    let (status, reply) = viewer.post("api/scene", &json!({ "max_spp": 8 }));
    assert_eq!(status, 200, "{reply}");
    let (headers, body) = viewer.frame_with_spp(8, reply["version"].as_u64().unwrap());
    assert_eq!(header(&headers, "x-niebla-integrator"), "single");
    assert_eq!(header(&headers, "x-niebla-spp"), "8");
    let built = niebla::scene::load_scene(&viewer.dir.join("fog.json")).unwrap();
    let options = niebla::render::RenderOptions {
        spp: 8,
        seed: 3,
        first_sample: 0,
        threads: Some(1),
        sampler: built.settings.sampler,
    };
    let image = niebla::render::render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
    let decoded = niebla_view::frame::decode_half(&body);
    assert_eq!(decoded.len(), image.pixels.len() * 3);
    let mut nonzero = 0;
    for (i, value) in decoded.iter().enumerate() {
        let exact = image.pixels[i / 3][i % 3];
        assert_eq!(value.to_bits(), half::f16::from_f32(exact).to_f32().to_bits(), "value {i}: {value} vs {exact}");
        nonzero += (exact > 0.0) as usize;
    }
    assert!(nonzero > decoded.len() / 2, "the test scene is mostly black");
    let estimate: f64 = header(&headers, "x-niebla-relative-error").parse().unwrap();
    assert!(estimate > 0.0 && estimate < 1.0, "{estimate}");
}

/// A procedural cloud (grid medium) lit by a directional light and the sky.
const CLOUD: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1.2, 4], "target": [0, 1, 0], "fov_y": 45, "width": 20, "height": 14},
  "render": {"integrator": {"type": "volpath"}, "spp": 4, "seed": 2},
  "media": {"cloud": {"type": "grid", "density": {"type": "procedural", "shape": "cloud", "seed": 3, "resolution": 16},
                      "sigma_t": 6, "albedo": 0.9, "phase": {"type": "hg", "g": 0.4},
                      "to_world": {"scale": 2, "translate": [-1, 0, -1]}}},
  "ambient_medium": "cloud",
  "lights": [{"type": "directional", "direction": [-0.6, -0.8, -0.3], "irradiance": [3, 2.8, 2.5]},
             {"type": "constant", "radiance": [0.1, 0.15, 0.2]}]
}"#;

/// After a drag of the camera (interactive frames) and a change of the
/// density scale, albedo and phase, which the render slot applies to the
/// scene and precomputation it kept, the frame at 4 spp equals
/// `niebla::render::render` of the edited scene built from scratch.
#[test]
fn frames_after_camera_and_medium_edits_equal_a_render_of_the_edited_scene() {
    for integrator in [
        json!({"type": "hegeman", "resolution": 8}),
        // Resolution 16: interactive medium edits light a preview lattice of 8.
        json!({"type": "zhou", "resolution": 16, "rbf_count": 12, "fit_iterations": 4, "cache": false}),
        json!({"type": "volpath", "max_depth": 16}),
    ] {
        let mut scene: Value = serde_json::from_str(CLOUD).unwrap();
        scene["render"]["integrator"] = integrator.clone();
        let viewer = Viewer::start_with("edits", &scene.to_string());
        let (_, first) = viewer.post("api/scene", &json!({ "max_spp": 4 }));
        viewer.frame_with_spp(4, first["version"].as_u64().unwrap());
        for (i, x) in [0.3, 0.6, 0.9].into_iter().enumerate() {
            scene["camera"]["position"] = json!([x, 1.3, 3.8]);
            let (status, reply) = viewer.post("api/scene", &json!({ "scene": scene, "interactive": true }));
            assert_eq!(status, 200, "{reply}");
            if i == 2 {
                viewer.frame_with_spp(1, reply["version"].as_u64().unwrap());
            }
        }
        // A slider drag of the medium (interactive frames: zhou's preview
        // lighting), then the same scene as a finished edit: the frame must
        // be the full precomputation's.
        scene["media"]["cloud"]["scale"] = json!(1.6);
        scene["media"]["cloud"]["albedo"] = json!([0.8, 0.85, 0.95]);
        scene["media"]["cloud"]["phase"]["g"] = json!(-0.2);
        let (status, reply) = viewer.post("api/scene", &json!({ "scene": scene, "interactive": true }));
        assert_eq!(status, 200, "{reply}");
        let (headers, _) = viewer.frame_with_spp(1, reply["version"].as_u64().unwrap());
        let timing = header(&headers, "x-niebla-timing");
        assert!(timing.contains("pass=") && timing.contains("server="), "{timing}");
        let (status, reply) = viewer.post("api/scene", &json!({ "scene": scene, "interactive": false, "max_spp": 4 }));
        assert_eq!(status, 200, "{reply}");
        let (headers, body) = viewer.frame_with_spp(4, reply["version"].as_u64().unwrap());
        assert_eq!(header(&headers, "x-niebla-width"), "20", "{integrator}");
        std::fs::write(viewer.dir.join("edited.json"), scene.to_string()).unwrap();
        let built = niebla::scene::load_scene(&viewer.dir.join("edited.json")).unwrap();
        let options = niebla::render::RenderOptions {
            spp: 4,
            seed: 2,
            first_sample: 0,
            threads: Some(1),
            sampler: built.settings.sampler,
        };
        let image =
            niebla::render::render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
        let decoded = niebla_view::frame::decode_half(&body);
        assert_eq!(decoded.len(), image.pixels.len() * 3);
        for (i, value) in decoded.iter().enumerate() {
            let exact = image.pixels[i / 3][i % 3];
            let want = half::f16::from_f32(exact).to_f32();
            assert_eq!(value.to_bits(), want.to_bits(), "{integrator}: value {i}: {value} vs {exact}");
        }
    }
}

#[test]
fn saved_files_go_beside_the_scene_and_never_overwrite() {
    let viewer = Viewer::start("save");
    viewer.frame_with_spp(1, 1);
    let mut scene: Value = serde_json::from_str(SCENE).unwrap();
    scene["media"]["fog"]["scale"] = json!(2.5);
    assert_eq!(viewer.post("api/scene", &json!({ "scene": scene })).0, 200);
    let first = viewer.post("api/save", &json!({"format": "scene"})).1;
    let second = viewer.post("api/save", &json!({"format": "scene"})).1;
    let (a, b) = (PathBuf::from(first["file"].as_str().unwrap()), PathBuf::from(second["file"].as_str().unwrap()));
    assert_eq!(a, viewer.dir.join("fog.view-1.json"));
    assert_eq!(b, viewer.dir.join("fog.view-2.json"));
    assert_eq!(std::fs::read_to_string(viewer.dir.join("fog.json")).unwrap(), SCENE);
    let saved = niebla::scene::load_scene_file(&a).unwrap();
    let niebla::scene::MediumDesc::Homogeneous(fog) = &saved.media["fog"] else { panic!("fog is homogeneous") };
    assert_eq!(fog.scale, 2.5);
    viewer.frame_with_spp(2, 2);
    let exr = viewer.post("api/save", &json!({"format": "exr"})).1;
    let read = niebla::film::read_exr(std::path::Path::new(exr["file"].as_str().unwrap())).unwrap();
    assert_eq!((read.image.width, read.image.height), (24, 16));
    let attribute: Value = serde_json::from_str(&read.text_attributes["niebla:scene"]).unwrap();
    assert_eq!(attribute["media"]["fog"]["scale"], json!(2.5));
    let png = viewer.post("api/save", &json!({"format": "png", "exposure": 1.0})).1;
    assert!(png["file"].as_str().unwrap().ends_with("fog.view-1.png"));
}

#[test]
fn the_page_reloads_the_scene_when_its_file_changes() {
    let viewer = Viewer::start("reload");
    viewer.alive();
    std::thread::sleep(Duration::from_millis(1100)); // a later modification time on coarse clocks
    std::fs::write(viewer.dir.join("fog.json"), SCENE.replace("\"seed\": 3", "\"seed\": 4")).unwrap();
    let start = Instant::now();
    loop {
        let state: Value = serde_json::from_slice(&viewer.get("api/state").2).unwrap();
        if state["reloads"] == json!(1) {
            assert_eq!(state["scene"]["render"]["seed"], json!(4));
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(10), "no reload");
        std::thread::sleep(Duration::from_millis(100));
    }
}
