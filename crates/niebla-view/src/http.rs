//! Request handling: every path starts with `/t/TOKEN/` (403 otherwise), the
//! `Host` must be the viewer's own and an `Origin`, when sent, the same
//! host (403 otherwise, against other web pages and DNS rebinding), bodies
//! are limited to [`MAX_BODY`] bytes (413), malformed bodies get 400 with a
//! JSON `{"error": ...}`; axum (over hyper) parses the HTTP itself. Only the built-in assets and the `api/` routes
//! exist; nothing is read from disk by a request.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::response::Response;
use serde_json::{json, Value};

use crate::frame::encode_half;
use crate::render_loop::with_integrator;
use crate::session::{Event, Session};
use crate::token::token_matches;

/// Largest request body accepted (a scene with inline data fits; 413 above).
pub const MAX_BODY: usize = 4 << 20;

/// How long a frame request waits for a new frame before answering 204.
pub const FRAME_WAIT: Duration = Duration::from_secs(20);

/// Most frame requests waiting at once (each holds a blocking thread); more get 503.
pub const MAX_WAITING: usize = 64;

/// What a request handler needs besides the session.
pub struct Context {
    /// The session.
    pub session: Arc<Session>,
    /// The access token.
    pub token: String,
    /// `Host` header values accepted (`None`: any, when bound to all interfaces).
    pub hosts: Option<Vec<String>>,
    /// Permits of the waiting frame requests.
    pub waiting: Arc<tokio::sync::Semaphore>,
}

/// A response under construction: status, headers and body.
struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn new(status: u16, body: Vec<u8>) -> Reply {
        Reply { status, headers: vec![("Cache-Control".into(), "no-store".into())], body }
    }

    fn with_header(mut self, name: &str, value: &str) -> Reply {
        self.headers.push((name.to_string(), value.to_string()));
        self
    }

    fn into_response(self) -> Response {
        let mut response = Response::new(Body::from(self.body));
        *response.status_mut() = StatusCode::from_u16(self.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
        let headers = response.headers_mut();
        headers.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
        for (name, value) in self.headers {
            if let (Ok(name), Ok(value)) =
                (header::HeaderName::from_bytes(name.as_bytes()), HeaderValue::from_str(&value))
            {
                headers.insert(name, value);
            }
        }
        response
    }
}

fn json_reply(status: u16, value: &Value) -> Reply {
    Reply::new(status, value.to_string().into_bytes()).with_header("Content-Type", "application/json")
}

fn error_reply(status: u16, message: impl Into<String>) -> Reply {
    json_reply(status, &json!({ "error": message.into() }))
}

fn header_value<'a>(headers: &'a HeaderMap, name: &str) -> Option<&'a str> {
    headers.get(name).map(|v| v.to_str().unwrap_or("\u{fffd}"))
}

/// Answer one request (axum's fallback handler: every path comes here).
pub async fn handle(State(context): State<Arc<Context>>, request: Request) -> Response {
    route(&context, request).await.into_response()
}

/// Why a request is refused before its route is looked at, if it is.
fn refusal(context: &Context, headers: &HeaderMap) -> Option<Reply> {
    let host = header_value(headers, "host").unwrap_or("");
    if let Some(hosts) = &context.hosts {
        if !hosts.iter().any(|h| h.eq_ignore_ascii_case(host)) {
            return Some(error_reply(403, format!("host {host:?} refused")));
        }
    }
    if let Some(origin) = header_value(headers, "origin") {
        if !origin.eq_ignore_ascii_case(&format!("http://{host}")) {
            return Some(error_reply(403, format!("origin {origin:?} refused")));
        }
    }
    if let Some(site) = header_value(headers, "sec-fetch-site") {
        if !matches!(site, "same-origin" | "none") {
            return Some(error_reply(403, format!("cross-site request ({site}) refused")));
        }
    }
    None
}

async fn route(context: &Arc<Context>, request: Request) -> Reply {
    let (parts, body) = request.into_parts();
    if let Some(reply) = refusal(context, &parts.headers) {
        return reply;
    }
    let path = parts.uri.path();
    let query = parts.uri.query().unwrap_or("");
    let Some(rest) = path.strip_prefix("/t/") else { return error_reply(403, "missing access token") };
    let (given, route) = rest.split_once('/').unwrap_or((rest, ""));
    if !token_matches(given, &context.token) {
        return error_reply(403, "wrong access token");
    }
    let session = context.session.clone();
    match (&parts.method, route) {
        (&Method::GET, "api/state") => state(&session),
        (&Method::GET, "api/frame") => {
            let Ok(permit) = context.waiting.clone().try_acquire_owned() else {
                return error_reply(503, "too many waiting frame requests");
            };
            let query = query.to_string();
            tokio::task::spawn_blocking(move || {
                let reply = frame(&session, &query);
                drop(permit);
                reply
            })
            .await
            .unwrap_or_else(|e| error_reply(500, e.to_string()))
        }
        (&Method::POST, "api/scene" | "api/save") => {
            let arrived = std::time::Instant::now();
            let body = match body_json(&parts.headers, body).await {
                Ok(body) => body,
                Err(reply) => return reply,
            };
            let save_request = route == "api/save";
            tokio::task::spawn_blocking(move || {
                if save_request {
                    save(&session, &body)
                } else {
                    edit(&session, &body, arrived)
                }
            })
            .await
            .unwrap_or_else(|e| error_reply(500, e.to_string()))
        }
        (&Method::GET, asset) => match crate::assets::asset(if asset.is_empty() { "index.html" } else { asset }) {
            Some((bytes, mime)) => Reply::new(200, bytes.to_vec())
                .with_header("Content-Type", mime)
                .with_header("Content-Security-Policy", "default-src 'self'; style-src 'self' 'unsafe-inline'"),
            None => error_reply(404, format!("no such page: {asset}")),
        },
        (method, route) => error_reply(405, format!("{method} {route} is not supported")),
    }
}

/// Read a JSON body of at most [`MAX_BODY`] bytes (a larger claimed
/// `Content-Length` is refused before anything is read or allocated).
async fn body_json(headers: &HeaderMap, body: Body) -> Result<Value, Reply> {
    let too_large = || error_reply(413, format!("message larger than {MAX_BODY} bytes"));
    let claimed = header_value(headers, "content-length").and_then(|v| v.parse::<u64>().ok());
    if claimed.is_some_and(|n| n > MAX_BODY as u64) {
        return Err(too_large());
    }
    let bytes = axum::body::to_bytes(body, MAX_BODY).await.map_err(|_| too_large())?;
    serde_json::from_slice(&bytes).map_err(|e| error_reply(400, format!("malformed message: {e}")))
}

/// `GET api/state`: the scene, the integrators, the split-view state.
fn state(session: &Session) -> Reply {
    let job = session.job();
    let integrators: Vec<Value> = niebla::integrator::registry::INTEGRATORS
        .iter()
        .map(|e| json!({"name": e.name, "summary": e.summary, "interactive": e.interactive}))
        .collect();
    json_reply(
        200,
        &json!({
            "label": session.label,
            "scene": *job.scene,
            "compare": job.compare.as_deref(),
            "version": job.version,
            "reloads": session.reloads(),
            "max_spp": job.max_spp,
            "preview_scale": job.preview_scale,
            "integrators": integrators,
        }),
    )
}

fn query_number(query: &str, key: &str) -> Option<u64> {
    query.split('&').find_map(|kv| kv.strip_prefix(key)?.strip_prefix('=')?.parse().ok())
}

/// `GET api/frame?slot=S&after=ID`: the first event of slot `S` newer than
/// `ID` (waiting up to [`FRAME_WAIT`]; 204 when none came): a frame as half
/// floats with its figures in `X-Niebla-*` headers, or an error as JSON.
fn frame(session: &Session, query: &str) -> Reply {
    let Some(slot) = query_number(query, "slot").filter(|&s| s < 2) else {
        return error_reply(400, "slot must be 0 or 1");
    };
    let after = query_number(query, "after").unwrap_or(0);
    let event = session.slots[slot as usize].wait_after(after, FRAME_WAIT, &session.stop);
    let reloads = session.reloads().to_string();
    match event {
        Event::None => Reply::new(204, Vec::new()).with_header("X-Niebla-Reloads", &reloads),
        Event::Error(version, id, message) => json_reply(200, &json!({"error": message, "version": version, "id": id}))
            .with_header("X-Niebla-Event", "error")
            .with_header("X-Niebla-Reloads", &reloads),
        Event::Frame(f) => {
            let taken = std::time::Instant::now();
            let wait = taken.duration_since(f.timing.published).as_secs_f64();
            let bytes = encode_half(&f.image);
            let encode = taken.elapsed().as_secs_f64();
            let server = f.timing.edited_at.map(|t| t.elapsed().as_secs_f64());
            let mut reply = Reply::new(200, bytes)
                .with_header("Content-Type", "application/octet-stream")
                .with_header("X-Niebla-Event", "frame")
                .with_header("X-Niebla-Reloads", &reloads);
            let figures = [
                ("Id", f.id.to_string()),
                ("Version", f.version.to_string()),
                ("Width", f.width.to_string()),
                ("Height", f.height.to_string()),
                ("Spp", f.spp.to_string()),
                ("Elapsed", format!("{:.6}", f.elapsed)),
                ("Samples-Per-Second", format!("{:.1}", f.samples_per_second)),
                ("Relative-Error", f.relative_error.map_or("".into(), |e| format!("{e:.6e}"))),
                ("Interactive", f.interactive.to_string()),
                ("Integrator", f.integrator.clone()),
                ("Timing", f.timing.header(wait, encode, server)),
            ];
            for (name, value) in figures {
                reply = reply.with_header(&format!("X-Niebla-{name}"), &value);
            }
            reply
        }
    }
}

/// Validate an edited scene as a scene file would be: the `file` fields
/// stay in the folder, then the scene parser reads the JSON text. The
/// error is the message the command line prints (after `error: `).
pub fn validate_scene(session: &Session, scene: &Value) -> Result<(), String> {
    if !scene.is_object() {
        return Err(format!("{}: the scene must be a JSON object", session.label));
    }
    crate::paths::check_scene_files(scene, &session.base, &session.original_files)
        .map_err(|e| format!("{}: {e}", session.label))?;
    let text = serde_json::to_string(scene).map_err(|e| e.to_string())?;
    niebla::scene::parse_scene_str(&text, &session.label).map(|_| ()).map_err(|e| e.to_string())
}

/// `POST api/scene`: `{"scene": {...}, "compare": {...} | null, "interactive":
/// bool, "preview_scale": n, "max_spp": n}`; absent fields keep their value.
/// 422 with the parser's message when the scene (or the scene with the
/// comparison integrator) does not validate.
fn edit(session: &Session, body: &Value, arrived: std::time::Instant) -> Reply {
    let Some(body) = body.as_object() else { return error_reply(400, "malformed message: expected a JSON object") };
    let current = session.job();
    let scene = body.get("scene").cloned().unwrap_or_else(|| (*current.scene).clone());
    if let Err(message) = validate_scene(session, &scene) {
        return error_reply(422, message);
    }
    let compare = match body.get("compare") {
        None => current.compare.as_deref().cloned(),
        Some(Value::Null) => None,
        Some(object) => Some(object.clone()),
    };
    if let Some(integrator) = &compare {
        if let Err(message) = validate_scene(session, &with_integrator(&scene, integrator)) {
            return error_reply(422, format!("split view: {message}"));
        }
    }
    let flag = |key: &str| body.get(key).map(|v| v.as_bool().ok_or(format!("{key} must be true or false"))).transpose();
    let number = |key: &str, max: u64| {
        body.get(key)
            .map(|v| {
                v.as_u64().filter(|n| (1..=max).contains(n)).ok_or(format!("{key} must be an integer from 1 to {max}"))
            })
            .transpose()
    };
    let (interactive, preview_scale, max_spp) =
        match (flag("interactive"), number("preview_scale", 16), number("max_spp", 1 << 20)) {
            (Ok(i), Ok(p), Ok(m)) => (i.unwrap_or(false), p, m),
            (Err(e), ..) | (_, Err(e), _) | (.., Err(e)) => return error_reply(400, format!("malformed message: {e}")),
        };
    let version = session.update_job(|job| {
        job.scene = Arc::new(scene);
        job.compare = compare.map(Arc::new);
        job.interactive = interactive;
        job.preview_scale = preview_scale.map_or(job.preview_scale, |p| p as u32);
        job.max_spp = max_spp.map_or(job.max_spp, |m| m as u32);
        job.edited_at = Some(arrived);
        job.validate_seconds = arrived.elapsed().as_secs_f64();
    });
    json_reply(200, &json!({ "version": version }))
}

/// The first `STEM.view-N.EXT` (N = 1, 2, ...) in `folder` that does not exist.
pub fn unused_name(folder: &Path, stem: &str, ext: &str) -> PathBuf {
    (1u32..).map(|n| folder.join(format!("{stem}.view-{n}.{ext}"))).find(|p| !p.exists()).expect("a free name")
}

/// JSON text with every non-ASCII character escaped (`\uXXXX`), for EXR text attributes.
fn ascii_json(value: &Value) -> String {
    let mut out = String::new();
    for c in serde_json::to_string(value).unwrap_or_default().chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut units = [0u16; 2];
            for unit in c.encode_utf16(&mut units) {
                out.push_str(&format!("\\u{unit:04x}"));
            }
        }
    }
    out
}

/// `POST api/save`: `{"format": "exr" | "png" | "scene", "slot": 0 | 1,
/// "exposure": stops}`: the slot's latest image (EXR with the scene as the
/// text attribute `niebla:scene`, or PNG), or the edited scene (pretty JSON),
/// written beside the original scene as `STEM.view-N.EXT`, never over an
/// existing file. Answers `{"file": path}`.
fn save(session: &Session, body: &Value) -> Reply {
    let format = body.get("format").and_then(Value::as_str).unwrap_or("");
    let slot = body.get("slot").and_then(Value::as_u64).unwrap_or(0);
    let exposure = body.get("exposure").and_then(Value::as_f64).unwrap_or(0.0);
    if slot > 1 || !exposure.is_finite() {
        return error_reply(400, "malformed message: slot must be 0 or 1 and exposure a number");
    }
    let stem = session
        .scene_path
        .as_ref()
        .and_then(|p| p.file_stem())
        .map_or("default".to_string(), |s| s.to_string_lossy().into_owned());
    let job = session.job();
    let written = match format {
        "scene" => {
            let path = unused_name(&session.base, &stem, "json");
            let text = serde_json::to_string_pretty(&*job.scene).unwrap_or_default() + "\n";
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
                .and_then(|mut f| std::io::Write::write_all(&mut f, text.as_bytes()))
                .map(|()| path.clone())
                .map_err(|e| format!("{}: {e}", path.display()))
        }
        "exr" | "png" => {
            let Event::Frame(frame) = session.slots[slot as usize].latest() else {
                return error_reply(409, "no image rendered yet");
            };
            let path = unused_name(&session.base, &stem, format);
            let result = if format == "exr" {
                let scene = crate::render_loop::slot_scene(&job, slot as usize).unwrap_or_default();
                let attributes = [("niebla:scene", ascii_json(&scene)), ("niebla:spp", frame.spp.to_string())];
                niebla::film::write_exr_with_attributes(&frame.image, &path, &attributes)
            } else {
                niebla::film::write_png(&frame.image, &path, exposure as f32)
            };
            result.map(|()| path.clone()).map_err(|e| e.to_string())
        }
        _ => return error_reply(400, "malformed message: format must be \"exr\", \"png\" or \"scene\""),
    };
    match written {
        Ok(path) => json_reply(200, &json!({ "file": path.display().to_string() })),
        Err(message) => error_reply(500, message),
    }
}
