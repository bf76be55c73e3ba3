//! `bdmorph studio`: an animation editor in the browser, on the live engine.
//!
//! A local web server ([`server`]) serves a page (embedded in the binary: no build step) and
//! talks to it over one WebSocket. The page is a view of one document on the server (the
//! project: mesh, picture, outline, keyframes, settings; [`project`]); every change to it is an
//! undoable [`edit::Edit`] on one history ([`history`]), carried out by the session
//! ([`session`]), which keeps the engine's caches in step ([`engine`]) and tells every open
//! page what changed. Long work runs in the background ([`jobs`]). The document is autosaved
//! into the workspace while it has unsaved changes, and work a studio could not save (killed,
//! crashed) is offered back at the next start ([`workspace`]).
//!
//! Safety of a local server ([`guard`]): it binds 127.0.0.1 only, every request and the
//! socket carry a secret token (kept owner-only in the workspace so that pages reconnect after
//! a restart), `Host` and `Origin` must be the server's own (against DNS rebinding and other
//! sites' pages), messages are bounded, and the studio writes only into its workspace (the
//! opened file's folder, or the current one) by plain file names, atomically; a name that is
//! a link leading out of the workspace is refused, for reading as for writing
//! ([`workspace`]). Pictures are read only as regular files of bounded size, without blocking
//! on a pipe, and a project opened from the page may name only a picture inside the workspace
//! ([`open`]). At most [`listen::MAX_CONNECTIONS`] connections are open at once, and each
//! must send a request within [`listen::HEADER_TIMEOUT_SECONDS`] seconds of opening or of its
//! last answer ([`listen`]).

pub mod carry;
pub mod cleanup;
pub mod edit;
pub mod engine;
pub mod export;
pub mod guard;
pub mod history;
pub mod jobs;
pub mod listen;
pub mod loops;
pub mod messages;
pub mod open;
pub mod part_flags;
pub mod pictures;
/// The project file (the crate's [`crate::project`], with the feature `project`).
pub use crate::project;
pub mod protocol;
pub mod recovery;
pub mod rig;
pub mod scene;
pub mod server;
pub mod session;
pub mod workspace;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

pub use project::Project;
pub use session::Session;

/// How to start the studio.
#[derive(Clone, Debug, Default)]
pub struct StudioOptions {
    /// A picture, mesh or project to open; `None` starts from the sample figure.
    pub file: Option<PathBuf>,
    /// The port (`None`: the one the last studio in this workspace used, if free, else any).
    pub port: Option<u16>,
    /// Whether to start the system's browser on the URL.
    pub open: bool,
    /// How a picture is opened and a mesh textured.
    pub opening: open::OpenOptions,
    /// How many connections the server holds, and for how long without a request.
    pub limits: listen::ConnectionLimits,
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

/// The session for `options.file` (or the sample), with its notes said.
pub fn session_for(options: &StudioOptions) -> Result<Session, StudioError> {
    let (opened, workspace, source) = match &options.file {
        Some(file) => {
            let folder = file
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .map_or_else(|| PathBuf::from("."), PathBuf::from);
            let workspace = std::fs::canonicalize(&folder).unwrap_or(folder);
            let opened =
                open::open(file, &workspace, &options.opening).map_err(StudioError::Open)?;
            let source = file.file_name().map(|n| n.to_string_lossy().into_owned());
            (opened, workspace, source)
        }
        None => {
            let sample = crate::generate::figure(0.01);
            let here = PathBuf::from(".");
            let workspace = std::fs::canonicalize(&here).unwrap_or(here);
            (
                open::Opened {
                    project: Project::new(&sample, None),
                    texture: None,
                    project_file: None,
                    notes: Vec::new(),
                },
                workspace,
                None,
            )
        }
    };
    let mut session = Session::new(
        opened.project,
        workspace,
        opened.project_file,
        opened.texture,
    )?;
    session.set_source(source);
    for note in opened.notes {
        eprintln!("studio: {note}");
        session.note(note, false);
    }
    Ok(session)
}

/// Runs the studio until Ctrl-C: prints the URL (one line on stdout), logs on stderr.
pub fn run(options: StudioOptions) -> Result<(), StudioError> {
    let started = std::time::SystemTime::now();
    let mut session = session_for(&options)?;
    // Temporary files of saves and exports a killed studio left.
    let mut cleaned = cleanup::Cleaned::default();
    for dir in [
        session.workspace().root().to_path_buf(),
        session.workspace().state_folder(),
    ] {
        let c = cleanup::remove_stale_temporaries(&dir, started);
        cleaned.files += c.files;
        cleaned.bytes += c.bytes;
    }
    if cleaned.files > 0 {
        eprintln!(
            "studio: removed {} temporary files ({:.1} MB) left by interrupted saves and exports",
            cleaned.files,
            cleaned.bytes as f64 / 1e6
        );
    }
    session.offer_recoveries();
    for r in session.recovered() {
        eprintln!(
            "studio: unsaved work a studio in this folder kept when it stopped ({} keyframes{}) is offered in the page",
            r.keyframes,
            r.source
                .as_ref()
                .map_or_else(String::new, |s| format!(", from {s}"))
        );
    }
    let workspace = session.workspace().clone();
    let (token, token_note) = workspace
        .token()
        .map_err(|e| StudioError::Server(e.to_string()))?;
    if let Some(note) = token_note {
        eprintln!("studio: {note}");
    }
    let threads = rayon::current_num_threads();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| StudioError::Server(e.to_string()))?;
    runtime.block_on(async move {
        let listener = match options.port {
            Some(port) => tokio::net::TcpListener::bind(("127.0.0.1", port))
                .await
                .map_err(|e| {
                    StudioError::Server(format!("cannot listen on 127.0.0.1:{port}: {e}"))
                })?,
            None => {
                let last = match workspace.last_port() {
                    Some(port) => tokio::net::TcpListener::bind(("127.0.0.1", port)).await.ok(),
                    None => None,
                };
                match last {
                    Some(l) => l,
                    None => tokio::net::TcpListener::bind(("127.0.0.1", 0))
                        .await
                        .map_err(|e| StudioError::Server(format!("cannot listen on 127.0.0.1: {e}")))?,
                }
            }
        };
        let port = listener
            .local_addr()
            .map_err(|e| StudioError::Server(e.to_string()))?
            .port();
        workspace.remember_port(port);
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
        let (changed, _) = tokio::sync::watch::channel(0u64);
        let app = Arc::new(server::App {
            token,
            port,
            session: Mutex::new(session),
            changed,
            job_threads: (threads / 2).max(1),
        });
        tokio::spawn(autosave(app.clone()));
        listen::serve(listener, server::router(app.clone()), options.limits, async {
            let _ = tokio::signal::ctrl_c().await;
            eprintln!("studio: stopping");
        })
        .await;
        // Unsaved work is kept for the next start, with its undo history.
        let last = app.session().autosave_copy(None);
        match last {
            Some(copy) => match workspace.keep(&copy, None) {
                Ok(_) => eprintln!(
                    "studio: unsaved changes kept in {} (the next studio in this folder offers them)",
                    workspace.autosave_path().display()
                ),
                Err(e) => eprintln!("studio: unsaved changes could not be kept: {e}"),
            },
            None => workspace.clear_autosave(),
        }
        Ok(())
    })
}

/// Writes the document to the workspace's autosave every
/// [`workspace::AUTOSAVE_SECONDS`] while it has unsaved changes.
async fn autosave(app: Arc<server::App>) {
    let mut written = u64::MAX;
    // The generation of the undo history last written beside it.
    let mut history: Option<u64> = None;
    let mut interval =
        tokio::time::interval(std::time::Duration::from_secs(workspace::AUTOSAVE_SECONDS));
    loop {
        interval.tick().await;
        let copy = {
            let session = app.session();
            // The history is copied (its edits shared, not cloned) only when it changed.
            let kept = history.filter(|_| session.workspace().autosave_history_path().is_file());
            match session.autosave_copy(kept) {
                Some(c) if c.version != written || c.history.is_some() => {
                    Some((c, session.workspace().clone()))
                }
                Some(_) => None,
                None => {
                    if written != 0 {
                        session.workspace().clear_autosave();
                        written = 0;
                        history = None;
                    }
                    None
                }
            }
        };
        if let Some((copy, workspace)) = copy {
            let version = copy.version;
            let done = tokio::task::spawn_blocking(move || workspace.keep(&copy, history)).await;
            match done {
                Ok(Ok(h)) => {
                    written = version;
                    history = h;
                }
                Ok(Err(e)) => eprintln!("studio: autosave failed: {e}"),
                Err(_) => {}
            }
        }
    }
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
