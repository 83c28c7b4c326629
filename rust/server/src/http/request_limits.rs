//! Every request's body bounded: each route's size limit checked against the declared
//! `Content-Length` before the handler runs (413 `too_large`), and every body wrapped so that
//! it ends once it stalls (no bytes for the idle timeout) or, on routes whose handler does not
//! count bytes itself, once it passes the route's limit.

use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll, ready};
use std::time::Duration;

use axum::body::{Body, Bytes};
use axum::extract::{MatchedPath, Request, State};
use axum::http::Method;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use http_body::{Frame, SizeHint};
use tokio::time::{Instant, Sleep};

use crate::app_state::App;
use crate::config::ServerConfig;
use crate::error::Error;
use crate::http::helpers::declared_length;
use crate::ingest::evidence::{MAX_TABLE_BYTES, MAX_THUMBNAIL_BYTES};
use crate::ingest::phone_log::{MAX_ANCHORS_BYTES, MAX_TRAJECTORY_BYTES};

/// A JSON body (`POST /v1/sessions`, whose handler counts the same 64 KiB itself), and the
/// body of every route that takes none: a few short keys need far less.
pub(crate) const MAX_REQUEST_BYTES: u64 = 64 << 10;
/// Multipart framing around a legacy upload's one field.
const MULTIPART_FRAMING: u64 = 64 << 10;
/// An upload handler's own idle check fires first (it keeps a recording's prefix); this
/// wrapper's is the backstop.
const UPLOAD_IDLE_MARGIN: Duration = Duration::from_secs(1);

/// A route's body bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct BodyLimit {
    /// Largest body, in bytes.
    pub bytes: u64,
    /// What the body is, named in the 413.
    pub what: &'static str,
    /// Whether the handler streams the body and counts its bytes itself (an upload: it
    /// answers its own 413 and keeps a recording's prefix); else this layer cuts it.
    pub counted_by_handler: bool,
    /// The body ends once it sends nothing for this long.
    pub idle: Duration,
}

/// The body bound of `method` on the route `pattern` (as the router spells it).
pub(crate) fn body_limit(config: &ServerConfig, method: &Method, pattern: &str) -> BodyLimit {
    let upload = |bytes, what| BodyLimit {
        bytes,
        what,
        counted_by_handler: true,
        idle: config.upload_idle_timeout + UPLOAD_IDLE_MARGIN,
    };
    match (method.as_str(), pattern) {
        ("PUT", "/v1/sessions/{id}/recording") => upload(config.max_recording_bytes, "recording"),
        ("POST", "/v1/sessions/{id}/trials") => upload(config.max_trajectory_bytes, "trajectory"),
        ("PUT", "/v1/worker/hosts/{host}/leases/{lease}/trial") => {
            upload(config.max_trajectory_bytes, "trajectory")
        }
        ("PUT", "/v1/sessions/{id}/evidence.csv") => upload(MAX_TABLE_BYTES, "evidence.csv"),
        ("PUT", "/v1/sessions/{id}/subtrajectories.csv") => {
            upload(MAX_TABLE_BYTES, "subtrajectories.csv")
        }
        ("PUT", "/v1/sessions/{id}/trajectory.txt") => {
            upload(MAX_TRAJECTORY_BYTES, "trajectory.txt")
        }
        ("PUT", "/v1/sessions/{id}/anchors.csv") => upload(MAX_ANCHORS_BYTES, "anchors.csv"),
        // Every frame of the walk: as long as a trial (a replay of the same recording).
        ("PUT", "/v1/sessions/{id}/walk.txt") => upload(config.max_trajectory_bytes, "walk.txt"),
        ("PUT", "/v1/sessions/{id}/subtrajectories/{k}/image.jpg") => {
            upload(MAX_THUMBNAIL_BYTES, "image.jpg")
        }
        ("POST", "/recording") => upload(
            config.max_recording_bytes.saturating_add(MULTIPART_FRAMING),
            "recording",
        ),
        ("POST", "/timestamps") => upload(
            config
                .max_trajectory_bytes
                .saturating_add(MULTIPART_FRAMING),
            "timestamps",
        ),
        // A few short keys: no reason to wait for them as long as for a recording.
        ("POST", "/v1/sessions") => BodyLimit {
            idle: config.body_idle_timeout,
            ..upload(MAX_REQUEST_BYTES, "session request")
        },
        ("POST", "/v1/venues") => BodyLimit {
            idle: config.body_idle_timeout,
            ..upload(MAX_REQUEST_BYTES, "venue request")
        },
        _ => BodyLimit {
            bytes: MAX_REQUEST_BYTES,
            what: "request body",
            counted_by_handler: false,
            idle: config.body_idle_timeout,
        },
    }
}

/// Middleware (inside the router, so the matched route is known).
pub(crate) async fn bound_bodies(
    State(shared): State<Arc<App>>,
    request: Request,
    next: Next,
) -> Response {
    let config = &shared.config;
    let pattern = request
        .extensions()
        .get::<MatchedPath>()
        .map_or("", |p| p.as_str());
    let limit = body_limit(config, request.method(), pattern);
    if let Some(declared) = declared_length(request.headers())
        && declared > limit.bytes
    {
        return Error::TooLarge {
            what: limit.what,
            limit: limit.bytes,
        }
        .into_response();
    }
    let cap = if limit.counted_by_handler {
        u64::MAX
    } else {
        limit.bytes
    };
    let request = request.map(|body| Body::new(Bounded::new(body, cap, limit.idle)));
    next.run(request).await
}

/// A request body that fails once it passes `cap` bytes or sends nothing for `idle`.
struct Bounded {
    inner: Body,
    cap: u64,
    seen: u64,
    idle: Duration,
    last_data: Instant,
    /// One timer for the whole body, pushed back only when it fires (a reset per chunk
    /// costs upload throughput).
    stall: Pin<Box<Sleep>>,
    failed: bool,
}

impl Bounded {
    fn new(inner: Body, cap: u64, idle: Duration) -> Bounded {
        Bounded {
            inner,
            cap,
            seen: 0,
            idle,
            last_data: Instant::now(),
            stall: Box::pin(tokio::time::sleep(idle)),
            failed: false,
        }
    }
}

impl http_body::Body for Bounded {
    type Data = Bytes;
    type Error = std::io::Error;

    fn poll_frame(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, std::io::Error>>> {
        let this = &mut *self;
        if this.failed {
            return Poll::Ready(None);
        }
        match Pin::new(&mut this.inner).poll_frame(cx) {
            Poll::Ready(Some(Ok(frame))) => {
                if let Some(data) = frame.data_ref() {
                    this.seen += data.len() as u64;
                    this.last_data = Instant::now();
                    if this.seen > this.cap {
                        this.failed = true;
                        return Poll::Ready(Some(Err(std::io::Error::other(format!(
                            "the body is larger than the limit of {} bytes",
                            this.cap
                        )))));
                    }
                }
                Poll::Ready(Some(Ok(frame)))
            }
            Poll::Ready(Some(Err(e))) => Poll::Ready(Some(Err(std::io::Error::other(e)))),
            Poll::Ready(None) => Poll::Ready(None),
            Poll::Pending => loop {
                ready!(this.stall.as_mut().poll(cx));
                let deadline = this.last_data + this.idle;
                if deadline <= Instant::now() {
                    this.failed = true;
                    return Poll::Ready(Some(Err(std::io::Error::new(
                        std::io::ErrorKind::TimedOut,
                        format!("no data for {} s", this.idle.as_secs_f64()),
                    ))));
                }
                this.stall.as_mut().reset(deadline);
            },
        }
    }

    fn is_end_stream(&self) -> bool {
        self.inner.is_end_stream()
    }

    fn size_hint(&self) -> SizeHint {
        self.inner.size_hint()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use futures_util::StreamExt;

    #[test]
    fn uploads_keep_their_own_limits_and_everything_else_is_small() {
        let config = ServerConfig::new("/nonexistent");
        let recording = body_limit(&config, &Method::PUT, "/v1/sessions/{id}/recording");
        assert_eq!(recording.bytes, config.max_recording_bytes);
        assert!(recording.counted_by_handler);
        let other = body_limit(&config, &Method::POST, "/v1/sessions/{id}/estimate");
        assert_eq!((other.bytes, other.counted_by_handler), (64 << 10, false));
        let get = body_limit(&config, &Method::GET, "/v1/sessions/{id}/recording");
        assert_eq!(get.bytes, 64 << 10);
        let create = body_limit(&config, &Method::POST, "/v1/sessions");
        assert_eq!(create.idle, config.body_idle_timeout);
        assert!(recording.idle > config.upload_idle_timeout);
    }

    #[tokio::test]
    async fn a_body_past_its_cap_fails() {
        let chunks = futures_util::stream::iter(
            (0..3).map(|_| Ok::<_, std::io::Error>(Bytes::from(vec![1u8; 100]))),
        );
        let body = Body::new(Bounded::new(
            Body::from_stream(chunks),
            250,
            Duration::from_secs(5),
        ));
        let got: Vec<_> = body.into_data_stream().collect().await;
        assert_eq!(got.len(), 3);
        assert!(got[0].is_ok() && got[1].is_ok());
        let err = got[2].as_ref().unwrap_err().to_string();
        assert!(err.contains("250 bytes"), "{err}");
    }

    #[tokio::test]
    async fn a_stalled_body_fails_after_the_idle_time() {
        let (tx, rx) = tokio::sync::mpsc::channel::<Result<Bytes, std::io::Error>>(1);
        tx.send(Ok(Bytes::from_static(b"abc"))).await.unwrap();
        let stream = tokio_stream_from(rx);
        let mut data = Body::new(Bounded::new(
            Body::from_stream(stream),
            u64::MAX,
            Duration::from_millis(300),
        ))
        .into_data_stream();
        assert_eq!(data.next().await.unwrap().unwrap(), "abc");
        let started = Instant::now();
        let err = data.next().await.unwrap().unwrap_err();
        assert!(err.to_string().contains("no data for 0.3 s"), "{err}");
        let waited = started.elapsed();
        assert!(waited >= Duration::from_millis(250), "{waited:?}");
        assert!(waited < Duration::from_secs(5), "{waited:?}");
        drop(tx);
    }

    fn tokio_stream_from(
        mut rx: tokio::sync::mpsc::Receiver<Result<Bytes, std::io::Error>>,
    ) -> impl futures_util::Stream<Item = Result<Bytes, std::io::Error>> {
        futures_util::stream::poll_fn(move |cx| rx.poll_recv(cx))
    }
}
