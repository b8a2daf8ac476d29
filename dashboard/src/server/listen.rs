//! The accept loop of `tessera-dashboard serve`: HTTP/1.1 connections served by hyper with a
//! header read timeout, which `axum::serve` does not expose. A client that has not sent a whole
//! request head within [`Timeouts::header`] of connecting (or of its previous response, on a
//! kept-alive connection) is disconnected, so slow or idle clients cannot hold connections. Body
//! and whole-request deadlines are tower-http layers in [`super::app`]. On shutdown, open
//! connections finish their current request (hyper-util's graceful shutdown).
//!
//! Not for: routing (see [`super::app`]).

use std::future::Future;
use std::time::Duration;

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::server::graceful::GracefulShutdown;
use hyper_util::service::TowerToHyperService;
use tokio::net::TcpListener;

/// The deadlines of the write path; `serve`'s `--*-timeout-secs` options.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timeouts {
    /// From connecting (or the previous response) to the end of the request head.
    pub header: Duration,
    /// Longest pause between two chunks of a request body.
    pub body_idle: Duration,
    /// Whole request, body read and handler included; answered 408.
    pub request: Duration,
}

impl Default for Timeouts {
    fn default() -> Self {
        Timeouts {
            header: Duration::from_secs(10),
            body_idle: Duration::from_secs(30),
            request: Duration::from_secs(300),
        }
    }
}

/// Serves `app` on `listener` until `shutdown` completes, then waits for open requests.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    timeouts: Timeouts,
    shutdown: impl Future<Output = ()>,
) -> std::io::Result<()> {
    let mut builder = http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(timeouts.header);
    let graceful = GracefulShutdown::new();
    let mut shutdown = std::pin::pin!(shutdown);
    loop {
        tokio::select! {
            accepted = listener.accept() => {
                let stream = match accepted {
                    Ok((stream, _)) => stream,
                    Err(e) => {
                        // Out of file descriptors and the like: wait instead of spinning.
                        eprintln!("tessera-dashboard: accept failed: {e}");
                        tokio::time::sleep(Duration::from_millis(100)).await;
                        continue;
                    }
                };
                let _ = stream.set_nodelay(true);
                let service = TowerToHyperService::new(app.clone());
                let conn = graceful.watch(builder.serve_connection(TokioIo::new(stream), service));
                tokio::spawn(async move {
                    // Timeouts and resets end here; there is nobody to tell.
                    let _ = conn.await;
                });
            }
            _ = &mut shutdown => break,
        }
    }
    drop(listener);
    let _ = tokio::time::timeout(timeouts.request, graceful.shutdown()).await;
    Ok(())
}
