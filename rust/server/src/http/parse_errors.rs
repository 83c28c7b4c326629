//! hyper answers a request it cannot parse by itself, before any of our code sees it: a
//! `Content-Length` that is no number below 2^64, a malformed request line or header → 400;
//! more than 100 headers or a header block over the read buffer → 431. Its answer has an empty
//! body (`connection: close`, `content-length: 0`). [`JsonParseErrors`] wraps a connection's
//! stream and turns exactly those answers into the JSON error shape every other refusal has.
//!
//! They are recognised by their head: a 4xx status with both `connection: close` and
//! `content-length: 0`, written as one buffer (hyper flattens its writes when the stream says
//! it does not write vectored). No answer of the router looks like that: every error of ours
//! carries a JSON body, and a route's empty answers are 2xx.

use std::io;
use std::pin::Pin;
use std::task::{Context, Poll, ready};

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};

/// A connection's stream whose hyper parse-error answers come out as JSON errors.
pub(crate) struct JsonParseErrors<Io> {
    inner: Io,
    /// A replacement answer being written, and how much of it is out; the length of the
    /// buffer hyper wrote is reported once all of it is.
    replacing: Option<(Vec<u8>, usize, usize)>,
}

impl<Io> JsonParseErrors<Io> {
    pub(crate) fn new(inner: Io) -> Self {
        JsonParseErrors {
            inner,
            replacing: None,
        }
    }
}

/// The JSON answer for hyper's empty parse-error answer `head`, or `None` for any other write.
fn json_answer(head: &[u8]) -> Option<Vec<u8>> {
    // Cheap for every other write: hyper's error head is short and starts with a 4xx line.
    if head.len() > 512 || !head.starts_with(b"HTTP/1.1 4") {
        return None;
    }
    let text = std::str::from_utf8(head).ok()?;
    let status = text.strip_prefix("HTTP/1.1 4")?.get(..2)?;
    let lower = text.to_ascii_lowercase();
    if !text.ends_with("\r\n\r\n")
        || !lower.contains("\r\nconnection: close\r\n")
        || !lower.contains("\r\ncontent-length: 0\r\n")
    {
        return None;
    }
    let (code, message) = match status {
        "31" => (
            "headers_too_large",
            "the request's headers are too many (at most 100) or too large (at most 64 KiB)",
        ),
        "00" => (
            "bad_request",
            "the request is not readable HTTP/1.1: a malformed request line or header, or a \
             Content-Length that is not a number below 2^64",
        ),
        _ => ("bad_request", "the request is not readable HTTP/1.1"),
    };
    // hyper's own status line is kept: its code and reason phrase.
    let status_line = text.lines().next()?;
    let body = serde_json::json!({ "error": { "code": code, "message": message } }).to_string();
    Some(
        format!(
            "{status_line}\r\ncontent-type: application/json\r\n\
             connection: close\r\ncontent-length: {}\r\n\r\n{body}",
            body.len()
        )
        .into_bytes(),
    )
}

impl<Io: AsyncWrite + Unpin> JsonParseErrors<Io> {
    /// Writes out the replacement in progress; `Ready(Ok(n))` with the length hyper wrote.
    fn drain(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<Option<usize>>> {
        while let Some((answer, written, reported)) = &mut self.replacing {
            if *written == answer.len() {
                let reported = *reported;
                self.replacing = None;
                return Poll::Ready(Ok(Some(reported)));
            }
            let n = ready!(Pin::new(&mut self.inner).poll_write(cx, &answer[*written..]))?;
            if n == 0 {
                return Poll::Ready(Err(io::ErrorKind::WriteZero.into()));
            }
            *written += n;
        }
        Poll::Ready(Ok(None))
    }
}

impl<Io: AsyncRead + Unpin> AsyncRead for JsonParseErrors<Io> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_read(cx, buf)
    }
}

impl<Io: AsyncWrite + Unpin> AsyncWrite for JsonParseErrors<Io> {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = &mut *self;
        if this.replacing.is_none()
            && let Some(answer) = json_answer(buf)
        {
            this.replacing = Some((answer, 0, buf.len()));
        }
        if let Some(reported) = ready!(this.drain(cx))? {
            return Poll::Ready(Ok(reported));
        }
        Pin::new(&mut this.inner).poll_write(cx, buf)
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        ready!(self.drain(cx))?;
        Pin::new(&mut self.inner).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        ready!(self.drain(cx))?;
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }

    // hyper then flattens each answer's head into one buffer, the shape `json_answer` knows.
    fn is_write_vectored(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::AsyncWriteExt;

    const HYPER_400: &[u8] = b"HTTP/1.1 400 Bad Request\r\nconnection: close\r\n\
content-length: 0\r\ndate: Wed, 02 Dec 2026 06:54:48 GMT\r\n\r\n";

    fn body_of(answer: &[u8]) -> serde_json::Value {
        let text = std::str::from_utf8(answer).unwrap();
        let (head, body) = text.split_once("\r\n\r\n").unwrap();
        assert!(
            head.contains(&format!("content-length: {}", body.len())),
            "{head}"
        );
        serde_json::from_str(body).unwrap()
    }

    #[test]
    fn hyper_s_empty_400_and_431_become_json_errors_with_their_status() {
        let answer = json_answer(HYPER_400).unwrap();
        assert!(answer.starts_with(b"HTTP/1.1 400 Bad Request\r\n"));
        assert_eq!(body_of(&answer)["error"]["code"], "bad_request");
        let h431 = b"HTTP/1.1 431 Request Header Fields Too Large\r\nconnection: close\r\n\
content-length: 0\r\ndate: x\r\n\r\n";
        let answer = json_answer(h431).unwrap();
        assert!(answer.starts_with(b"HTTP/1.1 431 "));
        assert_eq!(body_of(&answer)["error"]["code"], "headers_too_large");
    }

    #[test]
    fn answers_of_the_router_pass_unchanged() {
        for other in [
            &b"HTTP/1.1 200 OK\r\ncontent-length: 0\r\nconnection: close\r\n\r\n"[..],
            b"HTTP/1.1 204 No Content\r\ndate: x\r\n\r\n",
            b"HTTP/1.1 404 Not Found\r\ncontent-type: application/json\r\ncontent-length: 50\r\n\r\n",
            b"HTTP/1.1 400 Bad Request\r\ncontent-length: 0\r\n\r\n",
            b"{\"error\":{\"code\":\"bad_request\"}}",
        ] {
            assert_eq!(json_answer(other), None, "{}", String::from_utf8_lossy(other));
        }
    }

    #[tokio::test]
    async fn a_replacement_goes_out_whole_through_a_stream_that_takes_a_byte_at_a_time() {
        let (client, server) = tokio::io::duplex(1);
        let mut wrapped = JsonParseErrors::new(server);
        let reader = tokio::spawn(async move {
            let mut client = client;
            let mut out = Vec::new();
            tokio::io::AsyncReadExt::read_to_end(&mut client, &mut out)
                .await
                .unwrap();
            out
        });
        let n = wrapped.write(HYPER_400).await.unwrap();
        assert_eq!(n, HYPER_400.len(), "hyper sees its own buffer written");
        wrapped.write_all(b"").await.unwrap();
        wrapped.shutdown().await.unwrap();
        drop(wrapped);
        let out = reader.await.unwrap();
        assert_eq!(body_of(&out)["error"]["code"], "bad_request");
    }
}
