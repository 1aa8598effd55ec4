//! `niebla view`: a local HTTP server that renders a scene progressively
//! and streams every pass to a page in the browser as linear half floats,
//! tone-mapped there with WebGL2. The page edits the scene (camera, media,
//! lights, integrator), each edit validated by the scene parser; a split
//! view renders a second integrator beside the first.
//!
//! ```no_run
//! let config = niebla_view::ViewConfig { scene: None, ..niebla_view::ViewConfig::default() };
//! let server = niebla_view::ViewServer::start(&config).unwrap();
//! println!("{}", server.url());
//! server.wait();
//! ```

mod assets;
pub mod frame;
mod http;
pub mod paths;
mod render_loop;
pub mod session;
pub mod token;

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime};

pub use http::{unused_name, MAX_BODY};
use session::Session;

/// How a viewer starts.
#[derive(Clone, Debug)]
pub struct ViewConfig {
    /// Scene file (`None`: the built-in default scene, saving into the current folder).
    pub scene: Option<PathBuf>,
    /// Address to listen on (127.0.0.1 unless asked).
    pub host: IpAddr,
    /// Port (0: any free port).
    pub port: u16,
    /// Render threads (`None`: all cores).
    pub threads: Option<usize>,
    /// Reload the scene when its file changes on disk (polled twice a second).
    pub watch: bool,
    /// A scene given as JSON instead of a file (used when `scene` is `None`):
    /// the Python package's `Scene.view()`.
    pub inline: Option<InlineScene>,
}

/// A scene handed over as JSON rather than read from a file.
#[derive(Clone, Debug)]
pub struct InlineScene {
    /// The scene (JSON with the schema of a scene file).
    pub value: serde_json::Value,
    /// Its name in messages (e.g. `<dict>`).
    pub label: String,
    /// The folder relative paths resolve against and saved files go to.
    pub base: PathBuf,
}

impl Default for ViewConfig {
    fn default() -> ViewConfig {
        ViewConfig {
            scene: None,
            host: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: 0,
            threads: None,
            watch: true,
            inline: None,
        }
    }
}

/// Why a viewer did not start.
#[derive(Debug)]
pub enum ViewError {
    /// The scene file does not load (the parser's message).
    Scene(String),
    /// The address could not be bound.
    Bind(String),
}

impl std::fmt::Display for ViewError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ViewError::Scene(m) => write!(f, "{m}"),
            ViewError::Bind(m) => write!(f, "cannot listen: {m}"),
        }
    }
}

impl std::error::Error for ViewError {}

/// A running viewer: the HTTP server, two render slots and the file watcher.
pub struct ViewServer {
    session: Arc<Session>,
    url: String,
    port: u16,
    shutdown: Arc<tokio::sync::Notify>,
    threads: Vec<JoinHandle<()>>,
}

/// The scene text and JSON of `config.scene` (or the default scene), validated.
fn read_scene(scene: Option<&PathBuf>) -> Result<(String, serde_json::Value), ViewError> {
    let (label, text) = match scene {
        Some(path) => {
            let label = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .map_err(|e| ViewError::Scene(format!("{label}: cannot read scene file: {e}")))?;
            (label, text)
        }
        None => ("<default>".to_string(), niebla::scene::DEFAULT_SCENE.to_string()),
    };
    niebla::scene::parse_scene_str(&text, &label).map_err(|e| ViewError::Scene(e.to_string()))?;
    let value = serde_json::from_str(&text).map_err(|e| ViewError::Scene(format!("{label}: {e}")))?;
    Ok((label, value))
}

fn modified(path: &PathBuf) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl ViewServer {
    /// Load the scene, bind the address and start serving.
    pub fn start(config: &ViewConfig) -> Result<ViewServer, ViewError> {
        let (label, scene, base) = match (&config.scene, &config.inline) {
            (None, Some(inline)) => {
                let text = inline.value.to_string();
                niebla::scene::parse_scene_str(&text, &inline.label).map_err(|e| ViewError::Scene(e.to_string()))?;
                (inline.label.clone(), inline.value.clone(), inline.base.clone())
            }
            (scene, _) => {
                let (label, value) = read_scene(scene.as_ref())?;
                let base = match scene {
                    Some(path) => {
                        path.parent().filter(|p| !p.as_os_str().is_empty()).map_or(PathBuf::from("."), PathBuf::from)
                    }
                    None => PathBuf::from("."),
                };
                (label, value, base)
            }
        };
        let session = Arc::new(Session::new(config.scene.clone(), base, label, scene, config.threads));
        let listener = std::net::TcpListener::bind(SocketAddr::new(config.host, config.port))
            .and_then(|l| l.set_nonblocking(true).map(|()| l))
            .map_err(|e| ViewError::Bind(format!("{}:{}: {e}", config.host, config.port)))?;
        let port = listener.local_addr().map_or(config.port, |a| a.port());
        let token = token::new_token();
        let shown_host = match config.host {
            IpAddr::V6(a) => format!("[{a}]"),
            IpAddr::V4(a) if a.is_unspecified() => "127.0.0.1".to_string(),
            IpAddr::V4(a) => a.to_string(),
        };
        let hosts = (!config.host.is_unspecified()).then(|| {
            let mut hosts = vec![format!("{shown_host}:{port}"), format!("localhost:{port}")];
            if config.host.is_loopback() {
                hosts.extend([format!("127.0.0.1:{port}"), format!("[::1]:{port}")]);
            }
            hosts
        });
        let url = format!("http://{shown_host}:{port}/t/{token}/");
        let waiting = Arc::new(tokio::sync::Semaphore::new(http::MAX_WAITING));
        let context = Arc::new(http::Context { session: session.clone(), token, hosts, waiting });
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("niebla-view-http")
            .enable_all()
            .build()
            .map_err(|e| ViewError::Bind(format!("cannot start the server's threads: {e}")))?;
        let shutdown = Arc::new(tokio::sync::Notify::new());
        let mut threads = Vec::new();
        for index in 0..2 {
            let session = session.clone();
            threads.push(std::thread::spawn(move || render_loop::run_slot(session, index)));
        }
        let notified = shutdown.clone();
        threads.push(std::thread::spawn(move || serve(runtime, listener, context, notified)));
        if let (Some(path), true) = (config.scene.clone(), config.watch) {
            let session = session.clone();
            threads.push(std::thread::spawn(move || watch(session, path)));
        }
        Ok(ViewServer { session, url, port, shutdown, threads })
    }

    /// Stop serving from another thread (the shared handle of [`ViewServer::stop`]).
    pub fn stopper(&self) -> impl Fn() + Send + Sync + 'static {
        let (session, shutdown) = (self.session.clone(), self.shutdown.clone());
        move || {
            session.shut_down();
            shutdown.notify_one();
        }
    }

    /// The page's address, access token included.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// The port listened on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Serve until the process ends.
    pub fn wait(self) {
        for thread in self.threads {
            let _ = thread.join();
        }
    }

    /// Stop serving and rendering and wait for the threads to end.
    pub fn stop(self) {
        self.session.shut_down();
        self.shutdown.notify_one();
        for thread in self.threads {
            let _ = thread.join();
        }
    }
}

/// Serve HTTP on `listener` until `shutdown` is notified: every request
/// goes to [`http::handle`], which answers on the runtime's two threads
/// (blocking work, such as waiting for a frame, on its blocking pool).
fn serve(
    runtime: tokio::runtime::Runtime,
    listener: std::net::TcpListener,
    context: Arc<http::Context>,
    shutdown: Arc<tokio::sync::Notify>,
) {
    runtime.block_on(async move {
        let listener = match tokio::net::TcpListener::from_std(listener) {
            Ok(l) => l,
            Err(e) => {
                eprintln!("niebla view: cannot serve: {e}");
                return;
            }
        };
        let app = axum::Router::new().fallback(http::handle).with_state(context);
        let stopped = async move { shutdown.notified().await };
        if let Err(e) = axum::serve(listener, app).with_graceful_shutdown(stopped).await {
            eprintln!("niebla view: server stopped: {e}");
        }
    });
    runtime.shutdown_timeout(std::time::Duration::from_secs(1));
}

/// Poll the scene file's modification time; when it changes, read it again
/// and, if it validates, make it the scene (page edits are replaced);
/// otherwise show the parser's message and keep the current scene.
fn watch(session: Arc<Session>, path: PathBuf) {
    let mut stamp = modified(&path);
    while !session.stop.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(500));
        let now = modified(&path);
        if now == stamp {
            continue;
        }
        stamp = now;
        match read_scene(Some(&path)) {
            Ok((_, scene)) => {
                session.update_job(|job| {
                    job.scene = Arc::new(scene);
                    job.edited_at = None;
                    job.validate_seconds = 0.0;
                });
                session.note_reload();
            }
            Err(e) => {
                let version = session.job().version;
                session.slots[0]
                    .publish_error(version, format!("{e} (the file changed on disk; keeping the previous version)"));
            }
        }
    }
}
