//! `bdmorph studio`: an animation editor in the browser, on the live engine.
//!
//! A local web server ([`server`]) serves a page (embedded in the binary: no build step) and
//! talks to it over one WebSocket: the page sends requests (pin, drag, add a keyframe, scrub,
//! save, export, ...) as JSON; the engine ([`session::Session`]) answers with state as JSON
//! and poses and frames as binary `f32` arrays. The project is one versioned JSON file
//! ([`project`]).
//!
//! Safety of a local server ([`guard`]): it binds 127.0.0.1 only, every request and the
//! socket carry a per-run random token, `Host` and `Origin` must be the server's own (against
//! DNS rebinding and other sites' pages), messages are bounded, and the studio writes only
//! into its workspace (the opened file's folder, or the current one) by plain file names,
//! atomically.

pub mod guard;
pub mod project;
pub mod server;
pub mod session;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

pub use project::Project;
pub use session::Session;

/// How to start the studio.
#[derive(Clone, Debug, Default)]
pub struct StudioOptions {
    /// A picture, mesh or project to open; `None` starts from the sample figure.
    pub file: Option<PathBuf>,
    /// The port (0: any free one).
    pub port: u16,
    /// Whether to start the system's browser on the URL.
    pub open: bool,
}

/// Why the studio could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudioError {
    /// The file could not be opened as a project, mesh or picture.
    #[error("{0}")]
    Open(String),
    /// The session could not be made from it.
    #[error(transparent)]
    Session(#[from] session::SessionError),
    /// Binding, serving or the random source failed.
    #[error("{0}")]
    Server(String),
}

/// The session for `options.file` (or the sample), its workspace and texture.
pub fn session_for(options: &StudioOptions) -> Result<(Session, Option<Vec<u8>>), StudioError> {
    let (project, texture, workspace, project_file) = match &options.file {
        Some(file) => {
            let (project, texture) = session::open(file).map_err(StudioError::Open)?;
            let folder = file
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .map_or_else(|| PathBuf::from("."), PathBuf::from);
            let is_project = file
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json"));
            (project, texture, folder, is_project.then(|| file.clone()))
        }
        None => {
            let sample = crate::generate::figure(0.01);
            (Project::new(&sample, None), None, PathBuf::from("."), None)
        }
    };
    let png = match &texture {
        Some(image) => Some(
            crate::render::raster::encode_png(image)
                .map_err(|e| StudioError::Open(format!("texture: {e}")))?,
        ),
        None => None,
    };
    let workspace = std::fs::canonicalize(&workspace).unwrap_or(workspace);
    Ok((
        Session::new(project, workspace, project_file, texture)?,
        png,
    ))
}

/// Runs the studio until Ctrl-C: prints the URL (one line on stdout), logs on stderr.
pub fn run(options: StudioOptions) -> Result<(), StudioError> {
    let (session, texture_png) = session_for(&options)?;
    let token = guard::Token::random().map_err(|e| StudioError::Server(e.to_string()))?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| StudioError::Server(e.to_string()))?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(("127.0.0.1", options.port))
            .await
            .map_err(|e| {
                StudioError::Server(format!("cannot listen on 127.0.0.1:{}: {e}", options.port))
            })?;
        let port = listener
            .local_addr()
            .map_err(|e| StudioError::Server(e.to_string()))?
            .port();
        let url = format!("http://127.0.0.1:{port}/?token={}", token.as_str());
        {
            use std::io::Write as _;
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{url}");
            let _ = out.flush();
        }
        eprintln!("studio: serving on 127.0.0.1:{port} (Ctrl-C stops it)");
        if options.open {
            open_browser(&url);
        }
        let app = Arc::new(server::App {
            token,
            port,
            session: Mutex::new(session),
            texture_png,
        });
        // Small frames go out at once (no Nagle delay): latency is the point.
        use axum::serve::ListenerExt as _;
        let listener = listener.tap_io(|stream| {
            if let Err(e) = stream.set_nodelay(true) {
                eprintln!("studio: TCP_NODELAY not set: {e}");
            }
        });
        axum::serve(listener, server::router(app))
            .with_graceful_shutdown(async {
                let _ = tokio::signal::ctrl_c().await;
                eprintln!("studio: stopping");
            })
            .await
            .map_err(|e| StudioError::Server(e.to_string()))
    })
}

/// Starts the system's browser on `url` (a note on stderr when it cannot).
fn open_browser(url: &str) {
    let command = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(target_os = "windows") {
        "explorer"
    } else {
        "xdg-open"
    };
    if let Err(e) = std::process::Command::new(command)
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
    {
        eprintln!("studio: could not start a browser ({command}: {e}); open the URL above");
    }
}
