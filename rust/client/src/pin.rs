//! Pinning the server's TLS certificate by its SHA-256 fingerprint (`server_cert_sha256`):
//! the first call fetches the certificate over a TLS handshake that accepts nothing but a
//! certificate with that fingerprint; from then on the client's agents trust exactly that
//! certificate (it must name the host the URL uses, as `sitar serve --tls-name` made it).
//! A different certificate is [`Error::CertificateMismatch`]; nothing ever falls back to
//! plain HTTP (the URL is `https://`).

use std::net::{TcpStream, ToSocketAddrs};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use rustls::client::danger::{HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier};
use rustls::pki_types::{CertificateDer, ServerName, UnixTime};
use rustls::{DigitallySignedStruct, SignatureScheme};

use crate::Error;

/// A SHA-256 fingerprint: 32 bytes.
pub(crate) type Fingerprint = [u8; 32];

/// Parses `AB:CD:…` (as `openssl x509 -fingerprint -sha256` and `sitar serve --tls` print it,
/// with or without the `sha256 Fingerprint=` prefix), or 64 hex digits; any case.
pub(crate) fn parse_fingerprint(text: &str) -> Result<Fingerprint, Error> {
    let text = text.trim();
    let text = text
        .split_once('=')
        .filter(|(prefix, _)| prefix.to_ascii_lowercase().contains("fingerprint"))
        .map_or(text, |(_, rest)| rest);
    let hex: String = text.chars().filter(|c| *c != ':').collect();
    let bad = || {
        Error::InvalidArgument(format!(
            "server_cert_sha256 {text:?}: expected 32 bytes in hex, as AB:CD:… \
             (`openssl x509 -noout -fingerprint -sha256`)"
        ))
    };
    if hex.len() != 64 || !hex.is_ascii() {
        return Err(bad());
    }
    let mut out = [0u8; 32];
    for (i, byte) in out.iter_mut().enumerate() {
        *byte = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
    }
    Ok(out)
}

/// `AB:CD:…` of a fingerprint.
pub(crate) fn format_fingerprint(f: &[u8]) -> String {
    f.iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(":")
}

fn sha256(der: &[u8]) -> Fingerprint {
    let mut out = [0u8; 32];
    out.copy_from_slice(ring::digest::digest(&ring::digest::SHA256, der).as_ref());
    out
}

/// Accepts exactly the pinned certificate, and keeps the one the server showed.
#[derive(Debug)]
struct PinVerifier {
    pin: Fingerprint,
    seen: Mutex<Option<CertificateDer<'static>>>,
    provider: Arc<rustls::crypto::CryptoProvider>,
}

impl ServerCertVerifier for PinVerifier {
    fn verify_server_cert(
        &self,
        end_entity: &CertificateDer<'_>,
        _intermediates: &[CertificateDer<'_>],
        _server_name: &ServerName<'_>,
        _ocsp: &[u8],
        _now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        *self.seen.lock().unwrap_or_else(|e| e.into_inner()) =
            Some(end_entity.clone().into_owned());
        if sha256(end_entity) == self.pin {
            Ok(ServerCertVerified::assertion())
        } else {
            Err(rustls::Error::General(
                "certificate fingerprint differs from the pin".into(),
            ))
        }
    }

    fn verify_tls12_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        rustls::crypto::verify_tls12_signature(
            message,
            cert,
            dss,
            &self.provider.signature_verification_algorithms,
        )
    }

    fn verify_tls13_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        rustls::crypto::verify_tls13_signature(
            message,
            cert,
            dss,
            &self.provider.signature_verification_algorithms,
        )
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        self.provider
            .signature_verification_algorithms
            .supported_schemes()
    }
}

/// Host and port of an `https://host[:port][/…]` base URL.
fn host_port(base: &str) -> Result<(String, u16), Error> {
    let rest = base.strip_prefix("https://").ok_or_else(|| {
        Error::InvalidArgument("server_cert_sha256 needs an https:// server URL".into())
    })?;
    let authority = rest.split('/').next().unwrap_or("");
    let (host, port) = if let Some(v6) = authority.strip_prefix('[') {
        let (host, after) = v6
            .split_once(']')
            .ok_or_else(|| Error::InvalidUrl(base.to_owned()))?;
        (host, after.strip_prefix(':'))
    } else {
        match authority.rsplit_once(':') {
            Some((host, port)) => (host, Some(port)),
            None => (authority, None),
        }
    };
    let port = match port {
        Some(p) => p.parse().map_err(|_| Error::InvalidUrl(base.to_owned()))?,
        None => 443,
    };
    Ok((host.to_owned(), port))
}

/// Fetches the server's certificate, accepting it only if its fingerprint is `pin`.
pub(crate) fn fetch_pinned(
    base: &str,
    pin: &Fingerprint,
    timeout: Duration,
) -> Result<CertificateDer<'static>, Error> {
    let (host, port) = host_port(base)?;
    let network = |message: String| Error::Network {
        url: base.to_owned(),
        attempts: 1,
        message,
    };
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let verifier = Arc::new(PinVerifier {
        pin: *pin,
        seen: Mutex::new(None),
        provider: provider.clone(),
    });
    let config = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| network(format!("TLS: {e}")))?
        .dangerous()
        .with_custom_certificate_verifier(verifier.clone())
        .with_no_client_auth();
    let name =
        ServerName::try_from(host.clone()).map_err(|_| Error::InvalidUrl(base.to_owned()))?;
    let mut conn = rustls::ClientConnection::new(Arc::new(config), name)
        .map_err(|e| network(format!("TLS: {e}")))?;
    let addr = (host.as_str(), port)
        .to_socket_addrs()
        .map_err(|e| network(format!("cannot resolve {host}: {e}")))?
        .next()
        .ok_or_else(|| network(format!("no address for {host}")))?;
    let mut tcp = TcpStream::connect_timeout(&addr, timeout.min(Duration::from_secs(10)))
        .map_err(|e| network(e.to_string()))?;
    tcp.set_read_timeout(Some(timeout)).ok();
    tcp.set_write_timeout(Some(timeout)).ok();
    let mut handshake = || -> std::io::Result<()> {
        while conn.is_handshaking() {
            conn.complete_io(&mut tcp)?;
        }
        Ok(())
    };
    let outcome = handshake();
    let seen = verifier
        .seen
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .take();
    match (outcome, seen) {
        (Ok(()), Some(cert)) => Ok(cert),
        (_, Some(cert)) if &sha256(&cert) != pin => Err(Error::CertificateMismatch {
            url: base.to_owned(),
            expected: format_fingerprint(pin),
            found: format_fingerprint(&sha256(&cert)),
        }),
        (Err(e), _) => Err(network(format!("TLS handshake: {e}"))),
        (Ok(()), None) => Err(network("TLS handshake without a certificate".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fingerprints_parse_in_openssls_spelling_and_plain_hex() {
        let colon = "AB:".repeat(31) + "CD";
        assert_eq!(parse_fingerprint(&colon).unwrap()[31], 0xCD);
        let openssl = format!("sha256 Fingerprint={colon}");
        assert_eq!(
            parse_fingerprint(&openssl).unwrap(),
            parse_fingerprint(&colon).unwrap()
        );
        let plain = "ab".repeat(32);
        assert_eq!(parse_fingerprint(&plain).unwrap(), [0xAB; 32]);
        assert_eq!(format_fingerprint(&[0xAB; 32]), "AB:".repeat(31) + "AB");
        for bad in ["", "AB:CD", &"ZZ".repeat(32), &"é".repeat(32)] {
            let err = parse_fingerprint(bad).unwrap_err().to_string();
            assert!(err.contains("server_cert_sha256"), "{bad:?}: {err}");
        }
    }

    #[test]
    fn host_and_port_come_from_https_urls_only() {
        assert_eq!(
            host_port("https://10.0.0.2:8443").unwrap(),
            ("10.0.0.2".into(), 8443)
        );
        assert_eq!(
            host_port("https://lab.local").unwrap(),
            ("lab.local".into(), 443)
        );
        assert_eq!(host_port("https://[::1]:9/x").unwrap(), ("::1".into(), 9));
        assert!(host_port("http://10.0.0.2:8000").is_err());
    }
}
