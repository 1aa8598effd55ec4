//! `niebla view`: serve a live view of a scene to the browser (the
//! `niebla-view` crate) and print its address; Ctrl-C ends the process and
//! with it every render and connection.

use std::net::IpAddr;
use std::path::PathBuf;

use clap::Args;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla view`.
#[derive(Args, Debug)]
pub struct ViewArgs {
    /// Scene file (JSON, version 1). Without it, the built-in default scene
    /// (saved files then go to the current folder).
    pub scene: Option<PathBuf>,
    /// Port to listen on (default: any free port).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Address to listen on; anything but the loopback address lets other
    /// machines reach the viewer (they still need the token).
    #[arg(long, default_value = "127.0.0.1")]
    pub host: IpAddr,
    /// Open the page in the default browser (xdg-open, open or start).
    #[arg(long)]
    pub open: bool,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// `niebla view`.
pub fn run(args: &ViewArgs) -> Result<(), CliError> {
    if let Some(scene) = &args.scene {
        if !scene.exists() {
            return Err(CliError::SceneNotFound(scene.clone()));
        }
    }
    if !args.host.is_loopback() {
        eprintln!(
            "warning: listening on {} makes the viewer reachable from other machines; anyone with the URL can \
             edit the scene and write images into its folder",
            args.host
        );
    }
    let config = niebla_view::ViewConfig {
        scene: args.scene.clone(),
        host: args.host,
        port: args.port,
        threads: args.threads.get()?,
        watch: true,
        inline: None,
    };
    let server = niebla_view::ViewServer::start(&config).map_err(|e| CliError::View(e.to_string()))?;
    println!("niebla view: {}", server.url());
    println!("(Ctrl-C to stop)");
    if args.open {
        open_browser(server.url());
    }
    server.wait();
    Ok(())
}

/// Ask the desktop to open `url`; a failure is only reported.
fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(windows) {
        "explorer"
    } else {
        "xdg-open"
    };
    if let Err(e) = std::process::Command::new(opener).arg(url).spawn() {
        eprintln!("warning: could not open a browser ({opener}: {e}); open the address above");
    }
}
