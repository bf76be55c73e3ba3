//! The studio's HTTP and WebSocket server (axum on tokio), bound to loopback only.
//!
//! Routes, each behind [`guard`](super::guard)'s checks (token, `Host`, `Origin`): `GET /` the
//! page, `GET /s/TOKEN/NAME` its scripts and style (embedded in the binary; the token in the
//! path, as the modules import each other by relative names), `GET /texture` the
//! document's picture, `GET /ws` the WebSocket. `GET /favicon.ico` is answered with no content
//! (it carries no token; the page names its own icon). Anything else is a 404; a request
//! that fails a check a 403 (400 without a `Host`).
//!
//! On the socket each page sends requests and gets, besides answers meant for it alone, what
//! its view of the document lacks whenever the document or the shared view changes (any
//! page's edit, a background job's progress): every tab shows the same. Requests are read in
//! batches of whatever has arrived; a drag or scrub followed by another of the same kind in
//! the batch is dropped (the newer supersedes it); every request that arrived before a Close
//! is carried out. Engine work runs on blocking threads; exports and new meshes on threads of
//! their own ([`super::jobs`]), so drags and scrubs stay answered meanwhile.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use axum::body::Body;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Path as UrlPath, Query, Request as HttpRequest, State};
use axum::http::{header, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;

use super::guard::{host_is_ours, origin_is_ours, token_in_query, Token};
use super::protocol::Request;
use super::session::{Answer, Revs, Session};

/// The largest WebSocket message accepted from the page: an upload of
/// [`super::workspace::MAX_UPLOAD`] and its header.
pub const MAX_MESSAGE: usize = super::workspace::MAX_UPLOAD + (64 << 10);

/// Requests read in one batch at most.
const BATCH: usize = 256;

/// How often a running job's progress goes to the pages.
const PROGRESS_EVERY: Duration = Duration::from_millis(200);

const PAGE: &str = include_str!("page/index.html");

/// The page's files: name, content, media type.
const FILES: &[(&str, &str, &str)] = &[
    ("studio.css", include_str!("page/studio.css"), "text/css"),
    ("main.js", include_str!("page/main.js"), "text/javascript"),
    ("net.js", include_str!("page/net.js"), "text/javascript"),
    ("view.js", include_str!("page/view.js"), "text/javascript"),
    ("gl.js", include_str!("page/gl.js"), "text/javascript"),
    (
        "overlay.js",
        include_str!("page/overlay.js"),
        "text/javascript",
    ),
    ("pose.js", include_str!("page/pose.js"), "text/javascript"),
    ("paint.js", include_str!("page/paint.js"), "text/javascript"),
    ("parts.js", include_str!("page/parts.js"), "text/javascript"),
    (
        "outline.js",
        include_str!("page/outline.js"),
        "text/javascript",
    ),
    (
        "timeline.js",
        include_str!("page/timeline.js"),
        "text/javascript",
    ),
    ("files.js", include_str!("page/files.js"), "text/javascript"),
    ("looks.js", include_str!("page/looks.js"), "text/javascript"),
    (
        "drawing.js",
        include_str!("page/drawing.js"),
        "text/javascript",
    ),
    ("onion.js", include_str!("page/onion.js"), "text/javascript"),
    (
        "easing.js",
        include_str!("page/easing.js"),
        "text/javascript",
    ),
    (
        "layout.js",
        include_str!("page/layout.js"),
        "text/javascript",
    ),
    (
        "shortcuts.js",
        include_str!("page/shortcuts.js"),
        "text/javascript",
    ),
    (
        "panels.js",
        include_str!("page/panels.js"),
        "text/javascript",
    ),
    ("icon.svg", include_str!("page/icon.svg"), "image/svg+xml"),
];

/// What every handler shares.
pub struct App {
    /// The page's secret.
    pub token: Token,
    /// The port the server listens on (for the `Host` and `Origin` checks).
    pub port: u16,
    /// The engine state.
    pub session: Mutex<Session>,
    /// Bumped whenever the session changed, waking every page's task.
    pub changed: tokio::sync::watch::Sender<u64>,
    /// Rayon threads for background jobs.
    pub job_threads: usize,
}

impl App {
    /// The session, also after a panic in another request (every change checks before it
    /// changes anything, so the state is whole).
    pub fn session(&self) -> MutexGuard<'_, Session> {
        match self.session.lock() {
            Ok(guard) => guard,
            Err(poisoned) => poisoned.into_inner(),
        }
    }

    /// Tells every page's task that the session changed.
    pub fn notify(&self) {
        self.changed.send_modify(|v| *v = v.wrapping_add(1));
    }
}

/// The router with its checks.
pub fn router(app: Arc<App>) -> Router {
    let guarded = Router::new()
        .route("/", get(page))
        .route("/s/{token}/{name}", get(file))
        .route("/texture", get(texture))
        .route("/drawing", get(drawing))
        .route("/picture", get(picture))
        .route("/ws", get(socket))
        .fallback(not_found)
        .layer(middleware::from_fn_with_state(app.clone(), check))
        .with_state(app.clone());
    Router::new()
        .route("/favicon.ico", get(favicon))
        .layer(middleware::from_fn_with_state(app.clone(), check_host))
        .with_state(app)
        .merge(guarded)
}

fn text(status: StatusCode, body: &'static str) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        body,
    )
        .into_response()
}

/// `Host` ours; the reason for refusing if not.
fn host_refusal(app: &App, request: &HttpRequest) -> Option<Response> {
    let Some(host) = request
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
    else {
        return Some(text(StatusCode::BAD_REQUEST, "a Host header is required\n"));
    };
    if !host_is_ours(host, app.port) {
        eprintln!("studio: refused a request for host {host:?}");
        return Some(text(StatusCode::FORBIDDEN, "wrong host\n"));
    }
    None
}

async fn check_host(State(app): State<Arc<App>>, request: HttpRequest, next: Next) -> Response {
    match host_refusal(&app, &request) {
        Some(refused) => refused,
        None => next.run(request).await,
    }
}

/// The guard: `Host` ours, `Origin` (if any) ours, the token right.
async fn check(State(app): State<Arc<App>>, request: HttpRequest, next: Next) -> Response {
    if let Some(refused) = host_refusal(&app, &request) {
        return refused;
    }
    if let Some(origin) = request.headers().get(header::ORIGIN) {
        let ours = origin.to_str().is_ok_and(|o| origin_is_ours(o, app.port));
        if !ours {
            eprintln!("studio: refused a request from origin {origin:?}");
            return text(StatusCode::FORBIDDEN, "wrong origin\n");
        }
    }
    // The token in the query, or (for the page's files, whose modules import each other by
    // relative names) as the path's second segment: /s/TOKEN/NAME.
    let query = request.uri().query().unwrap_or("");
    let in_path = request
        .uri()
        .path()
        .strip_prefix("/s/")
        .and_then(|rest| rest.split_once('/'))
        .map(|(token, _)| token);
    if !token_in_query(query)
        .or(in_path)
        .is_some_and(|t| app.token.matches(t))
    {
        return text(
            StatusCode::FORBIDDEN,
            "missing or wrong token: open the URL the studio printed\n",
        );
    }
    let mut response = next.run(request).await;
    let h = response.headers_mut();
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    h.insert(
        "x-content-type-options",
        HeaderValue::from_static("nosniff"),
    );
    h.insert("referrer-policy", HeaderValue::from_static("no-referrer"));
    response
}

async fn not_found() -> Response {
    text(StatusCode::NOT_FOUND, "not found\n")
}

async fn favicon() -> Response {
    StatusCode::NO_CONTENT.into_response()
}

async fn page(State(app): State<Arc<App>>) -> Response {
    let body = PAGE.replace("{{TOKEN}}", app.token.as_str());
    (
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8"),
            (
                header::CONTENT_SECURITY_POLICY,
                "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; style-src 'self'; script-src 'self'",
            ),
        ],
        body,
    )
        .into_response()
}

async fn file(UrlPath((_, name)): UrlPath<(String, String)>) -> Response {
    match FILES.iter().find(|(n, _, _)| *n == name) {
        Some((_, body, media)) => (
            [(header::CONTENT_TYPE, format!("{media}; charset=utf-8"))],
            *body,
        )
            .into_response(),
        None => not_found().await,
    }
}

async fn texture(State(app): State<Arc<App>>) -> Response {
    let picture = app.session().texture().cloned();
    match picture {
        Some(t) => (
            [(header::CONTENT_TYPE, t.content_type)],
            Body::from(t.bytes.clone()),
        )
            .into_response(),
        None => not_found().await,
    }
}

/// The value of `name` in a query string (as sent: not decoded).
fn query_value<'a>(query: &'a str, name: &str) -> Option<&'a str> {
    query
        .split('&')
        .filter_map(|pair| pair.split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v)
}

/// A picture of the workspace, `?name=NAME` (a plain name), as the file's bytes.
async fn picture(
    State(app): State<Arc<App>>,
    Query(query): Query<std::collections::HashMap<String, String>>,
) -> Response {
    let Some(name) = query.get("name") else {
        return text(StatusCode::BAD_REQUEST, "give the picture: ?name=NAME\n");
    };
    let found = app.session().workspace_picture(name);
    match found {
        Ok(t) => (
            [(header::CONTENT_TYPE, t.content_type)],
            Body::from(t.bytes.clone()),
        )
            .into_response(),
        Err(_) => not_found().await,
    }
}

/// A keyframe's drawing: `?k=K` its picture as the file's bytes, `?k=K&uv=1` its texture
/// coordinates as little-endian `f32` pairs.
async fn drawing(State(app): State<Arc<App>>, request: HttpRequest) -> Response {
    let query = request.uri().query().unwrap_or("");
    let value = |name: &str| query_value(query, name);
    let Some(k) = value("k").and_then(|k| k.parse::<usize>().ok()) else {
        return text(StatusCode::BAD_REQUEST, "give the keyframe: ?k=N\n");
    };
    // The session's lock is let go before answering.
    let found: Option<(&'static str, Vec<u8>)> = {
        let mut session = app.session();
        if value("uv").is_some() {
            session
                .drawing_texcoords(k)
                .map(|bytes| ("application/octet-stream", bytes))
        } else {
            session
                .drawing_picture(k)
                .map(|t| (t.content_type, t.bytes.clone()))
        }
    };
    match found {
        Some((media, bytes)) => {
            ([(header::CONTENT_TYPE, media)], Body::from(bytes)).into_response()
        }
        None => not_found().await,
    }
}

async fn socket(State(app): State<Arc<App>>, ws: WebSocketUpgrade) -> Response {
    ws.max_message_size(MAX_MESSAGE)
        .max_frame_size(MAX_MESSAGE)
        .on_upgrade(move |socket| serve_socket(app, socket))
}

/// One message from a page, parsed.
enum Item {
    Request(Request),
    Upload(Vec<u8>),
}

/// Starts background work: its thread, and a task that sends its progress to the pages.
fn spawn_work(app: &Arc<App>, work: super::jobs::Work, progress: Arc<super::jobs::Progress>) {
    let runner = app.clone();
    std::thread::spawn(move || {
        let result = work.run(&progress, runner.job_threads);
        runner.session().finish(result);
        runner.notify();
    });
    let ticker = app.clone();
    tokio::spawn(async move {
        loop {
            tokio::time::sleep(PROGRESS_EVERY).await;
            let running = {
                let mut session = ticker.session();
                session.job_progressed();
                session.job().is_some()
            };
            ticker.notify();
            if !running {
                return;
            }
        }
    });
}

async fn send_all(socket: &mut WebSocket, answers: Vec<Answer>) -> bool {
    for answer in answers {
        let message = match answer {
            Answer::Text(t) => Message::Text(t.into()),
            Answer::Binary(b) => Message::Binary(b.into()),
        };
        if socket.send(message).await.is_err() {
            return false;
        }
    }
    true
}

/// One page's conversation.
async fn serve_socket(app: Arc<App>, mut socket: WebSocket) {
    let mut seen = Revs::default();
    let mut changed = app.changed.subscribe();
    loop {
        tokio::select! {
            message = socket.recv() => {
                let Some(Ok(first)) = message else { return };
                let mut batch = vec![first];
                let mut closing = false;
                // Whatever else has already arrived (a zero timeout polls the socket once).
                while batch.len() < BATCH {
                    match tokio::time::timeout(Duration::ZERO, socket.recv()).await {
                        Ok(Some(Ok(message))) => batch.push(message),
                        Ok(_) => {
                            closing = true;
                            break;
                        }
                        Err(_) => break,
                    }
                }
                let mut items = Vec::with_capacity(batch.len());
                let mut refusals = Vec::new();
                for message in batch {
                    match message {
                        Message::Text(text) => {
                            let parsed = super::messages::parse_request(text.as_str());
                            // The text goes before the refusal is sent.
                            drop(text);
                            match parsed {
                                Ok(request) => items.push(Item::Request(request)),
                                Err(e) => refusals.push(Answer::Text(
                                    serde_json::json!({"type": "error", "message": e.to_string()}).to_string(),
                                )),
                            }
                        }
                        Message::Binary(bytes) => items.push(Item::Upload(bytes.to_vec())),
                        // Everything before the Close is carried out.
                        Message::Close(_) => {
                            closing = true;
                            break;
                        }
                        Message::Ping(_) | Message::Pong(_) => {}
                    }
                }
                let items = latest_only(items);
                let worker = app.clone();
                // For each request: what others changed, its answers, then what it changed.
                let done = tokio::task::spawn_blocking(move || {
                    let mut session = worker.session();
                    let mut out = Vec::new();
                    let mut works = Vec::new();
                    for item in items {
                        // What other pages changed comes first, so that an answer is never
                        // read before the state it was given in (a hello is sent it all after).
                        if !matches!(item, Item::Request(Request::Hello)) {
                            out.extend(session.updates(&mut seen, 0));
                        }
                        let mut seq = 0;
                        let reply = match item {
                            Item::Request(request) => {
                                match &request {
                                    Request::Hello => seen = Revs::default(),
                                    Request::Drag { seq: s, .. } | Request::Scrub { seq: s, .. } => seq = *s,
                                    _ => {}
                                }
                                session.handle(request)
                            }
                            Item::Upload(bytes) => session.handle_upload(&bytes),
                        };
                        let answered = !reply.answers.is_empty();
                        out.extend(reply.answers);
                        works.extend(reply.work);
                        let updates = session.updates(&mut seen, seq);
                        let framed = updates.iter().any(|a| matches!(a, Answer::Binary(_)));
                        out.extend(updates);
                        if seq != 0 && !framed && !answered {
                            out.push(Answer::Text(
                                serde_json::json!({"type": "ack", "seq": seq}).to_string(),
                            ));
                        }
                    }
                    (out, works, seen)
                })
                .await;
                let Ok((answers, works, now_seen)) = done else {
                    let said = serde_json::json!({"type": "error", "message": "internal error"});
                    let _ = socket.send(Message::Text(said.to_string().into())).await;
                    continue;
                };
                seen = now_seen;
                for (work, progress) in works {
                    spawn_work(&app, work, progress);
                }
                let mut all = refusals;
                all.extend(answers);
                let sent = send_all(&mut socket, all).await;
                app.notify();
                if closing || !sent {
                    return;
                }
            }
            moved = changed.changed() => {
                if moved.is_err() {
                    return;
                }
                let worker = app.clone();
                let done = tokio::task::spawn_blocking(move || {
                    let updates = worker.session().updates(&mut seen, 0);
                    (updates, seen)
                })
                .await;
                let Ok((updates, now_seen)) = done else { continue };
                seen = now_seen;
                if !send_all(&mut socket, updates).await {
                    return;
                }
            }
        }
    }
}

/// Drops each drag directly followed by another drag, and each scrub directly followed by
/// another scrub: the newer position supersedes the older.
fn latest_only(items: Vec<Item>) -> Vec<Item> {
    let mut out: Vec<Item> = Vec::with_capacity(items.len());
    for item in items {
        let superseded = matches!(
            (out.last(), &item),
            (
                Some(Item::Request(Request::Drag { .. })),
                Item::Request(Request::Drag { .. })
            ) | (
                Some(Item::Request(Request::Scrub { .. })),
                Item::Request(Request::Scrub { .. })
            )
        );
        if superseded {
            out.pop();
        }
        out.push(item);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newer_drags_and_scrubs_supersede_older_ones() {
        let drag = |seq| {
            Item::Request(Request::Drag {
                seq,
                pins: vec![],
                targets: vec![],
                moving: None,
            })
        };
        let scrub = |seq| Item::Request(Request::Scrub { seq, time: 0.0 });
        let kept = latest_only(vec![
            drag(1),
            drag(2),
            drag(3),
            Item::Request(Request::DragEnd),
            scrub(4),
            scrub(5),
            drag(6),
        ]);
        let seqs: Vec<String> = kept
            .iter()
            .map(|r| match r {
                Item::Request(Request::Drag { seq, .. }) => format!("d{seq}"),
                Item::Request(Request::Scrub { seq, .. }) => format!("s{seq}"),
                _ => "end".into(),
            })
            .collect();
        assert_eq!(seqs, ["d3", "end", "s5", "d6"]);
    }
}
