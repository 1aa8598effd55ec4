//! The page's files, built into the binary (the viewer works offline and
//! reads no file from disk to serve a request).

/// The bytes and MIME type of the built-in asset `name`, if there is one.
pub fn asset(name: &str) -> Option<(&'static [u8], &'static str)> {
    Some(match name {
        "index.html" => (include_bytes!("../assets/index.html"), "text/html; charset=utf-8"),
        "style.css" => (include_bytes!("../assets/style.css"), "text/css; charset=utf-8"),
        "app.js" => (include_bytes!("../assets/app.js"), "text/javascript; charset=utf-8"),
        "gl.js" => (include_bytes!("../assets/gl.js"), "text/javascript; charset=utf-8"),
        "controls.js" => (include_bytes!("../assets/controls.js"), "text/javascript; charset=utf-8"),
        "camera.js" => (include_bytes!("../assets/camera.js"), "text/javascript; charset=utf-8"),
        _ => return None,
    })
}
