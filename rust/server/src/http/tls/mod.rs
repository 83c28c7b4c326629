//! HTTPS with rustls: the certificate (given as PEM, or self-signed once into `DATA/tls/`),
//! its SHA-256 fingerprint as `openssl x509 -fingerprint -sha256` prints it, and the listener
//! that does the handshakes.

mod certificate;
mod listener;

pub(crate) use certificate::{Tls, load};
pub(crate) use listener::TlsListener;
