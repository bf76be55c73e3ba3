//! The studio's accept loop: HTTP/1.1 connections served by hyper with the router, within
//! [`ConnectionLimits`].
//!
//! - At most [`ConnectionLimits::max_connections`] connections are open at once (the pages'
//!   WebSockets included, each holding its place until it closes); a connection beyond that is
//!   closed as soon as it is accepted.
//! - A connection must send a whole request head within [`ConnectionLimits::header_timeout`]
//!   of opening, and the next one within that time of the last response: a partial request,
//!   or a kept-alive connection that carries no request, is closed then. A WebSocket, once
//!   open, has no such limit (it carries the page's token).
//!
//! So a flood of idle or half-sent connections holds the server's places for at most the
//! header timeout, after which the page connects again.

use std::future::Future;
use std::io;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

/// The most connections open at once, by default.
pub const MAX_CONNECTIONS: usize = 256;

/// Seconds a connection has to send a request head, by default.
pub const HEADER_TIMEOUT_SECONDS: u64 = 10;

/// How many connections the server holds, and for how long without a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct ConnectionLimits {
    /// The most connections open at once ([`MAX_CONNECTIONS`]); more are closed at once.
    pub max_connections: usize,
    /// The time a connection has to send a whole request head, from its opening or the end of
    /// its last response ([`HEADER_TIMEOUT_SECONDS`]): so also how long an idle kept-alive
    /// connection is kept.
    pub header_timeout: Duration,
}

impl Default for ConnectionLimits {
    fn default() -> Self {
        ConnectionLimits {
            max_connections: MAX_CONNECTIONS,
            header_timeout: Duration::from_secs(HEADER_TIMEOUT_SECONDS),
        }
    }
}

impl ConnectionLimits {
    /// With at most `n` connections open at once (at least 1).
    pub fn with_max_connections(mut self, n: usize) -> Self {
        self.max_connections = n.max(1);
        self
    }

    /// With `timeout` to send a request head (at least a millisecond).
    pub fn with_header_timeout(mut self, timeout: Duration) -> Self {
        self.header_timeout = timeout.max(Duration::from_millis(1));
        self
    }

    /// The defaults, changed by `BDMORPH_STUDIO_MAX_CONNECTIONS` (a count) and
    /// `BDMORPH_STUDIO_HEADER_TIMEOUT_MS` (milliseconds) when set to numbers (for tests that
    /// cannot wait the default's seconds).
    pub fn from_env() -> Self {
        let number = |name: &str| {
            std::env::var(name)
                .ok()
                .and_then(|v| v.trim().parse::<u64>().ok())
        };
        let mut limits = ConnectionLimits::default();
        if let Some(n) = number("BDMORPH_STUDIO_MAX_CONNECTIONS") {
            limits = limits.with_max_connections(usize::try_from(n).unwrap_or(usize::MAX));
        }
        if let Some(ms) = number("BDMORPH_STUDIO_HEADER_TIMEOUT_MS") {
            limits = limits.with_header_timeout(Duration::from_millis(ms));
        }
        limits
    }
}

/// A connection holding its place among the open ones until it is dropped (also after it
/// became a WebSocket).
struct Counted {
    stream: TcpStream,
    _place: OwnedSemaphorePermit,
}

impl AsyncRead for Counted {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for Counted {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.get_mut().stream).poll_write(cx, buf)
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_shutdown(cx)
    }

    fn poll_write_vectored(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.get_mut().stream).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.stream.is_write_vectored()
    }
}

/// Whether an accept error concerns only the one connection (the loop goes straight on).
fn is_connection_error(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::ConnectionRefused
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::ConnectionReset
    )
}

/// Serves `router` on `listener` within `limits` until `shutdown` completes; then connections
/// in the middle of a request get a moment to finish (WebSockets are left to the caller).
pub async fn serve(
    listener: TcpListener,
    router: Router,
    limits: ConnectionLimits,
    shutdown: impl Future<Output = ()>,
) {
    let places = Arc::new(Semaphore::new(limits.max_connections));
    let full_said = Arc::new(AtomicBool::new(false));
    let (stop, stopping) = tokio::sync::watch::channel(false);
    let mut builder = http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(limits.header_timeout)
        .keep_alive(true);
    tokio::pin!(shutdown);
    loop {
        let accepted = tokio::select! {
            accepted = listener.accept() => accepted,
            () = &mut shutdown => break,
        };
        let stream = match accepted {
            Ok((stream, _)) => stream,
            Err(e) if is_connection_error(&e) => continue,
            Err(e) => {
                // Out of file descriptors, say: wait for some to close.
                eprintln!("studio: accepting a connection failed: {e}");
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        let Ok(place) = places.clone().try_acquire_owned() else {
            if !full_said.swap(true, Ordering::Relaxed) {
                eprintln!(
                    "studio: {} connections open: more are closed until some close",
                    limits.max_connections
                );
            }
            drop(stream);
            continue;
        };
        full_said.store(false, Ordering::Relaxed);
        // Small frames go out at once (no Nagle delay): latency is the point.
        if let Err(e) = stream.set_nodelay(true) {
            eprintln!("studio: TCP_NODELAY not set: {e}");
        }
        let io = TokioIo::new(Counted {
            stream,
            _place: place,
        });
        let connection = builder
            .serve_connection(io, TowerToHyperService::new(router.clone()))
            .with_upgrades();
        let mut stopping = stopping.clone();
        tokio::spawn(async move {
            tokio::pin!(connection);
            tokio::select! {
                _ = connection.as_mut() => return,
                _ = stopping.wait_for(|s| *s) => {}
            }
            connection.as_mut().graceful_shutdown();
            let _ = connection.await;
        });
    }
    drop(stopping);
    let _ = stop.send(true);
    // Requests in flight finish (briefly); idle connections close at once.
    let _ = tokio::time::timeout(Duration::from_secs(2), stop.closed()).await;
}
