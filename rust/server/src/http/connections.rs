//! The accept loop behind both listeners (plain TCP and TLS): every connection served by
//! hyper's HTTP/1 with a header read timeout (a client dribbling its headers is cut off), and
//! at most `max_connections` at once — one more is accepted, answered 503 `busy` in the JSON
//! error shape and closed, so a flood of idle sockets cannot grow the server's memory.

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt};
use tokio::sync::{Semaphore, watch};

use crate::http::parse_errors::JsonParseErrors;

/// How the accept loop bounds connections.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ConnectionLimits {
    /// Connections served at once; more get the 503 answer.
    pub max_connections: usize,
    /// A request's headers must arrive whole in this time (from the first byte of the
    /// request, and for an idle keep-alive connection from the end of the previous answer).
    pub header_read_timeout: Duration,
}

/// Connections beyond the cap being answered 503 at once; more are closed unanswered.
const MAX_REFUSALS: usize = 64;
/// A refused client gets this long to take its 503 answer.
const REFUSAL_TIMEOUT: Duration = Duration::from_secs(2);
/// hyper's read buffer per connection (its default is ~400 KiB): bounds what a client can
/// make the server hold for headers and for body bytes not yet taken by the handler.
const MAX_READ_BUFFER: usize = 64 << 10;

const BUSY_ANSWER: &[u8] =
    b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\n\
Connection: close\r\nRetry-After: 1\r\nContent-Length: 87\r\n\r\n\
{\"error\":{\"code\":\"busy\",\"message\":\"too many connections to the server: retry shortly\"}}";

/// Serves `router` on every connection `listener` accepts until `shutdown` resolves; then
/// accepts no more and waits for the requests in progress.
pub(crate) async fn serve<L>(
    mut listener: L,
    router: Router,
    limits: ConnectionLimits,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) where
    L: axum::serve::Listener,
    L::Io: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let slots = Arc::new(Semaphore::new(limits.max_connections.max(1)));
    let refusals = Arc::new(Semaphore::new(MAX_REFUSALS));
    // Every connection holds a receiver; the sender's `closed()` is "all connections gone".
    let (stop_tx, stop_rx) = watch::channel(false);
    tokio::pin!(shutdown);
    loop {
        let (io, _peer) = tokio::select! {
            accepted = listener.accept() => accepted,
            () = &mut shutdown => break,
        };
        let Ok(slot) = slots.clone().try_acquire_owned() else {
            if let Ok(permit) = refusals.clone().try_acquire_owned() {
                tokio::spawn(async move {
                    let _permit = permit;
                    let _ = tokio::time::timeout(REFUSAL_TIMEOUT, refuse(io)).await;
                });
            }
            continue;
        };
        let service = TowerToHyperService::new(router.clone());
        let mut stop = stop_rx.clone();
        tokio::spawn(async move {
            let _slot = slot;
            let mut builder = hyper::server::conn::http1::Builder::new();
            builder
                .timer(TokioTimer::new())
                .header_read_timeout(limits.header_read_timeout)
                .max_buf_size(MAX_READ_BUFFER);
            let conn = builder
                .serve_connection(TokioIo::new(JsonParseErrors::new(io)), service)
                .with_upgrades();
            tokio::pin!(conn);
            tokio::select! {
                result = conn.as_mut() => {
                    if let Err(e) = result {
                        log::debug!("connection: {e}");
                    }
                    return;
                }
                _ = stop.wait_for(|stopping| *stopping) => conn.as_mut().graceful_shutdown(),
            }
            if let Err(e) = conn.await {
                log::debug!("connection: {e}");
            }
        });
    }
    drop(stop_rx);
    let _ = stop_tx.send(true);
    stop_tx.closed().await;
}

/// The 503 answer to a connection beyond the cap, without reading its request.
async fn refuse<Io: AsyncWrite + Unpin>(mut io: Io) {
    let _ = io.write_all(BUSY_ANSWER).await;
    let _ = io.shutdown().await;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_busy_answer_declares_its_json_length() {
        let text = std::str::from_utf8(BUSY_ANSWER).unwrap();
        let (head, body) = text.split_once("\r\n\r\n").unwrap();
        assert!(head.contains(&format!("Content-Length: {}", body.len())));
        let json: serde_json::Value = serde_json::from_str(body).unwrap();
        assert_eq!(json["error"]["code"], "busy");
    }
}
