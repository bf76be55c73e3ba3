//! The studio's HTTP and WebSocket server (axum on tokio), bound to loopback only.
//!
//! Routes, each behind [`guard`](super::guard)'s checks (token, `Host`, `Origin`):
//! `GET /` the page, `GET /studio.js` and `GET /studio.css` its code and style (embedded in
//! the binary), `GET /texture.png` the project's picture, `GET /ws` the WebSocket. Anything
//! else is a 404; a request that fails a check a 403 (400 without a `Host`).
//!
//! On the socket the page sends JSON requests ([`Request`]) and gets JSON state and binary
//! frames back. Requests are read in batches of whatever has arrived; a drag or scrub
//! followed by another of the same kind in the batch is dropped (a newer position supersedes
//! an older one), and the page itself keeps at most one drag and one scrub in flight, so no
//! stale work queues. A malformed or oversized message is answered with an error (or the
//! socket closed, for one over [`MAX_MESSAGE`]) and the server goes on serving.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::body::Body;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Request as HttpRequest, State};
use axum::http::{header, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;

use super::guard::{host_is_ours, origin_is_ours, token_in_query, Token};
use super::session::{Answer, Request, Session};

/// The largest WebSocket message accepted from the page (8 MiB: a keyframe's mesh file of
/// about 100,000 vertices).
pub const MAX_MESSAGE: usize = 8 << 20;

/// Requests read in one batch at most.
const BATCH: usize = 256;

const PAGE: &str = include_str!("page/index.html");
const SCRIPT: &str = include_str!("page/studio.js");
const STYLE: &str = include_str!("page/studio.css");

/// What every handler shares.
pub struct App {
    /// The per-run secret.
    pub token: Token,
    /// The port the server listens on (for the `Host` and `Origin` checks).
    pub port: u16,
    /// The engine state.
    pub session: Mutex<Session>,
    /// The texture as PNG, encoded once.
    pub texture_png: Option<Vec<u8>>,
}

/// The router with its checks.
pub fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/studio.js", get(script))
        .route("/studio.css", get(style))
        .route("/texture.png", get(texture))
        .route("/ws", get(socket))
        .fallback(not_found)
        .layer(middleware::from_fn_with_state(app.clone(), check))
        .with_state(app)
}

fn text(status: StatusCode, body: &'static str) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        body,
    )
        .into_response()
}

/// The guard: `Host` ours, `Origin` (if any) ours, the token right.
async fn check(State(app): State<Arc<App>>, request: HttpRequest, next: Next) -> Response {
    let headers = request.headers();
    let Some(host) = headers.get(header::HOST).and_then(|h| h.to_str().ok()) else {
        return text(StatusCode::BAD_REQUEST, "a Host header is required\n");
    };
    if !host_is_ours(host, app.port) {
        eprintln!("studio: refused a request for host {host:?}");
        return text(StatusCode::FORBIDDEN, "wrong host\n");
    }
    if let Some(origin) = headers.get(header::ORIGIN) {
        let ours = origin.to_str().is_ok_and(|o| origin_is_ours(o, app.port));
        if !ours {
            eprintln!("studio: refused a request from origin {origin:?}");
            return text(StatusCode::FORBIDDEN, "wrong origin\n");
        }
    }
    let query = request.uri().query().unwrap_or("");
    if !token_in_query(query).is_some_and(|t| app.token.matches(t)) {
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

async fn script() -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        SCRIPT,
    )
        .into_response()
}

async fn style() -> Response {
    ([(header::CONTENT_TYPE, "text/css; charset=utf-8")], STYLE).into_response()
}

async fn texture(State(app): State<Arc<App>>) -> Response {
    match &app.texture_png {
        Some(png) => (
            [(header::CONTENT_TYPE, "image/png")],
            Body::from(png.clone()),
        )
            .into_response(),
        None => not_found().await,
    }
}

async fn socket(State(app): State<Arc<App>>, ws: WebSocketUpgrade) -> Response {
    ws.max_message_size(MAX_MESSAGE)
        .max_frame_size(MAX_MESSAGE)
        .on_upgrade(move |socket| serve_socket(app, socket))
}

/// One page's conversation: batches of requests, stale drags and scrubs dropped, each
/// carried out on a blocking thread (the engine's work is CPU-bound), answers sent in order.
async fn serve_socket(app: Arc<App>, mut socket: WebSocket) {
    loop {
        let first = match socket.recv().await {
            Some(Ok(message)) => message,
            _ => return,
        };
        let mut batch = vec![first];
        // Whatever else has already arrived (a zero timeout polls the socket once).
        while batch.len() < BATCH {
            match tokio::time::timeout(Duration::ZERO, socket.recv()).await {
                Ok(Some(Ok(message))) => batch.push(message),
                Ok(_) => return,
                Err(_) => break,
            }
        }
        let mut requests = Vec::with_capacity(batch.len());
        for message in batch {
            match message {
                Message::Text(text) => match serde_json::from_str::<Request>(text.as_str()) {
                    Ok(request) => requests.push(request),
                    Err(e) => {
                        let said = serde_json::json!({"type": "error", "message": format!("bad request: {e}")});
                        if socket
                            .send(Message::Text(said.to_string().into()))
                            .await
                            .is_err()
                        {
                            return;
                        }
                    }
                },
                Message::Binary(_) => {
                    let said = serde_json::json!({"type": "error", "message": "binary requests are not accepted"});
                    if socket
                        .send(Message::Text(said.to_string().into()))
                        .await
                        .is_err()
                    {
                        return;
                    }
                }
                Message::Close(_) => return,
                Message::Ping(_) | Message::Pong(_) => {}
            }
        }
        for request in latest_only(requests) {
            let app = app.clone();
            let answers = tokio::task::spawn_blocking(move || {
                let mut session = match app.session.lock() {
                    Ok(guard) => guard,
                    // A panic while another request held the lock: the state is still
                    // whole (every operation checks before it changes anything).
                    Err(poisoned) => poisoned.into_inner(),
                };
                session.handle(request)
            })
            .await
            .unwrap_or_else(|_| {
                vec![Answer::Text(
                    serde_json::json!({"type": "error", "message": "internal error"}).to_string(),
                )]
            });
            for answer in answers {
                let message = match answer {
                    Answer::Text(t) => Message::Text(t.into()),
                    Answer::Binary(b) => Message::Binary(b.into()),
                };
                if socket.send(message).await.is_err() {
                    return;
                }
            }
        }
    }
}

/// Drops each drag directly followed by another drag, and each scrub directly followed by
/// another scrub: the newer position supersedes the older.
pub fn latest_only(requests: Vec<Request>) -> Vec<Request> {
    let mut out: Vec<Request> = Vec::with_capacity(requests.len());
    for request in requests {
        let superseded = matches!(
            (out.last(), &request),
            (Some(Request::Drag { .. }), Request::Drag { .. })
                | (Some(Request::Scrub { .. }), Request::Scrub { .. })
        );
        if superseded {
            out.pop();
        }
        out.push(request);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newer_drags_and_scrubs_supersede_older_ones() {
        let drag = |seq| Request::Drag {
            seq,
            targets: vec![],
        };
        let scrub = |seq| Request::Scrub { seq, time: 0.0 };
        let kept = latest_only(vec![
            drag(1),
            drag(2),
            drag(3),
            Request::DragEnd,
            scrub(4),
            scrub(5),
            drag(6),
        ]);
        let seqs: Vec<String> = kept
            .iter()
            .map(|r| match r {
                Request::Drag { seq, .. } => format!("d{seq}"),
                Request::Scrub { seq, .. } => format!("s{seq}"),
                _ => "end".into(),
            })
            .collect();
        assert_eq!(seqs, ["d3", "end", "s5", "d6"]);
    }
}
