//! TLS to Postgres, with libpq's `sslmode` and `sslrootcert` (in the `--database` URL, or
//! `PGSSLMODE` and `PGSSLROOTCERT`), over rustls:
//!
//! | `sslmode` | TLS | the server's certificate |
//! |---|---|---|
//! | `disable` | never | — |
//! | `allow`, `prefer` (default) | when the server offers it | not checked (as libpq) |
//! | `require` | always | not checked, unless a root certificate is given: then as `verify-ca` (as libpq) |
//! | `verify-ca` | always | signed by a root certificate |
//! | `verify-full` | always | signed by a root certificate and made out to the host connected to |
//!
//! The root certificates: the PEM file `sslrootcert` names (`system`: the machine's trust
//! store, `/etc/ssl/certs/ca-certificates.crt` or `SSL_CERT_FILE`), else
//! `~/.postgresql/root.crt` when it exists, as libpq looks for them. Client certificates
//! are not supported.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rustls::client::danger::{HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier};
use rustls::client::{ClientConfig, WebPkiServerVerifier};
use rustls::pki_types::pem::PemObject;
use rustls::pki_types::{CertificateDer, ServerName, UnixTime};
use rustls::{CertificateError, DigitallySignedStruct, RootCertStore, SignatureScheme};
use tokio_postgres_rustls::MakeRustlsConnect;

use crate::error::Error;

/// How the server's certificate is checked (`sslmode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Check {
    /// No TLS at all.
    Disable,
    /// TLS when offered (or required, with `require`), the certificate not checked.
    Encrypt,
    /// The certificate is signed by a root certificate.
    VerifyCa,
    /// ... and made out to the host.
    VerifyFull,
}

/// The TLS settings a `--database` URL asks for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TlsSettings {
    pub check: Check,
    /// Whether a connection without TLS is refused.
    pub required: bool,
    /// The root certificates' PEM file, or `system`.
    pub root_cert: Option<String>,
}

/// Takes `sslmode` and `sslrootcert` out of `url`'s query (rust-postgres knows only some
/// `sslmode` values and no `sslrootcert`), with `PGSSLMODE` and `PGSSLROOTCERT` for what it
/// leaves out: the URL rust-postgres reads, and the settings.
pub(crate) fn take_settings(url: &str) -> Result<(String, TlsSettings), Error> {
    let (base, query) = url.split_once('?').unwrap_or((url, ""));
    let mut kept = Vec::new();
    let (mut mode, mut root_cert) = (None, None);
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        match pair.split_once('=') {
            Some(("sslmode", value)) => mode = Some(value.to_string()),
            Some(("sslrootcert", value)) => root_cert = Some(percent_decoded(value)),
            _ => kept.push(pair),
        }
    }
    let var = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
    let mode = mode.or_else(|| var("PGSSLMODE"));
    let root_cert = root_cert.or_else(|| var("PGSSLROOTCERT")).or_else(|| {
        let home = std::env::var_os("HOME")?;
        let default = Path::new(&home).join(".postgresql/root.crt");
        default
            .is_file()
            .then(|| default.to_string_lossy().into_owned())
    });
    let (check, required) = match mode.as_deref().unwrap_or("prefer") {
        "disable" => (Check::Disable, false),
        "allow" | "prefer" => (Check::Encrypt, false),
        "require" if root_cert.is_some() => (Check::VerifyCa, true),
        "require" => (Check::Encrypt, true),
        "verify-ca" => (Check::VerifyCa, true),
        "verify-full" => (Check::VerifyFull, true),
        other => {
            return Err(Error::Config(format!(
                "--database: sslmode {other:?} is not one of disable, allow, prefer, require, \
                 verify-ca, verify-full"
            )));
        }
    };
    if matches!(check, Check::VerifyCa | Check::VerifyFull) && root_cert.is_none() {
        return Err(Error::Config(format!(
            "--database: sslmode {} needs root certificates: sslrootcert=FILE in the URL, \
             PGSSLROOTCERT, or ~/.postgresql/root.crt (sslrootcert=system: the machine's)",
            mode.unwrap_or_default()
        )));
    }
    let url = if kept.is_empty() {
        base.to_string()
    } else {
        format!("{base}?{}", kept.join("&"))
    };
    Ok((
        url,
        TlsSettings {
            check,
            required,
            root_cert,
        },
    ))
}

/// `%XX` sequences of a URL query value decoded (a path with spaces or `&`).
fn percent_decoded(value: &str) -> String {
    let bytes = value.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(byte)) => {
                out.push(byte);
                i += 3;
            }
            (byte, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The connector for `settings` (rustls with ring).
pub(crate) fn connector(settings: &TlsSettings) -> Result<MakeRustlsConnect, Error> {
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let builder = ClientConfig::builder_with_provider(provider.clone())
        .with_safe_default_protocol_versions()
        .map_err(|e| Error::Internal(format!("TLS to Postgres: {e}")))?;
    let verifier: Arc<dyn ServerCertVerifier> = match settings.check {
        Check::Disable | Check::Encrypt => Arc::new(Unchecked(provider)),
        Check::VerifyCa | Check::VerifyFull => {
            let roots = root_store(settings.root_cert.as_deref().unwrap_or("system"))?;
            let webpki = WebPkiServerVerifier::builder_with_provider(Arc::new(roots), provider)
                .build()
                .map_err(|e| Error::Config(format!("--database: root certificates: {e}")))?;
            Arc::new(Verified {
                webpki,
                host_checked: settings.check == Check::VerifyFull,
            })
        }
    };
    let config = builder
        .dangerous()
        .with_custom_certificate_verifier(verifier)
        .with_no_client_auth();
    Ok(MakeRustlsConnect::new(config))
}

/// The certificates of a PEM file (`system`: the machine's trust store).
fn root_store(source: &str) -> Result<RootCertStore, Error> {
    let file = match source {
        "system" => std::env::var_os("SSL_CERT_FILE")
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("/etc/ssl/certs/ca-certificates.crt")),
        path => PathBuf::from(path),
    };
    let named = |why: String| Error::Config(format!("--database: sslrootcert {file:?}: {why}"));
    let mut store = RootCertStore::empty();
    let certs = CertificateDer::pem_file_iter(&file).map_err(|e| named(e.to_string()))?;
    for cert in certs {
        let cert = cert.map_err(|e| named(e.to_string()))?;
        store.add(cert).map_err(|e| named(e.to_string()))?;
    }
    if store.is_empty() {
        return Err(named("no certificate in it".into()));
    }
    Ok(store)
}

/// `prefer` and `require` without root certificates: the link is encrypted, the server not
/// authenticated (libpq's behaviour); the handshake's signatures are still checked.
#[derive(Debug)]
struct Unchecked(Arc<rustls::crypto::CryptoProvider>);

impl ServerCertVerifier for Unchecked {
    fn verify_server_cert(
        &self,
        _end_entity: &CertificateDer<'_>,
        _intermediates: &[CertificateDer<'_>],
        _server_name: &ServerName<'_>,
        _ocsp: &[u8],
        _now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        Ok(ServerCertVerified::assertion())
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
            &self.0.signature_verification_algorithms,
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
            &self.0.signature_verification_algorithms,
        )
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        self.0.signature_verification_algorithms.supported_schemes()
    }
}

/// `verify-ca` and `verify-full`: the chain to a root certificate, and for `verify-full`
/// the host name too.
#[derive(Debug)]
struct Verified {
    webpki: Arc<WebPkiServerVerifier>,
    host_checked: bool,
}

impl ServerCertVerifier for Verified {
    fn verify_server_cert(
        &self,
        end_entity: &CertificateDer<'_>,
        intermediates: &[CertificateDer<'_>],
        server_name: &ServerName<'_>,
        ocsp: &[u8],
        now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        let verified =
            self.webpki
                .verify_server_cert(end_entity, intermediates, server_name, ocsp, now);
        match verified {
            Err(rustls::Error::InvalidCertificate(
                CertificateError::NotValidForName | CertificateError::NotValidForNameContext { .. },
            )) if !self.host_checked => Ok(ServerCertVerified::assertion()),
            other => other,
        }
    }

    fn verify_tls12_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        self.webpki.verify_tls12_signature(message, cert, dss)
    }

    fn verify_tls13_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        self.webpki.verify_tls13_signature(message, cert, dss)
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        self.webpki.supported_verify_schemes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn libpq_ssl_settings_are_taken_out_of_the_url() {
        let (url, settings) =
            take_settings("postgres://u@db:5432/sitar?sslmode=verify-full&sslrootcert=%2Fetc%2Fca.pem&application_name=x")
                .unwrap();
        assert_eq!(url, "postgres://u@db:5432/sitar?application_name=x");
        assert_eq!(settings.check, Check::VerifyFull);
        assert!(settings.required);
        assert_eq!(settings.root_cert.as_deref(), Some("/etc/ca.pem"));
        let (url, settings) =
            take_settings("postgres://u@db/sitar?sslmode=require&sslrootcert=/ca.pem").unwrap();
        assert_eq!(url, "postgres://u@db/sitar");
        assert_eq!(
            settings.check,
            Check::VerifyCa,
            "libpq: require + a root = verify-ca"
        );
        let (_, settings) = take_settings("postgres://u@db/sitar?sslmode=disable").unwrap();
        assert_eq!(settings.check, Check::Disable);
        let err = take_settings("postgres://u@db/sitar?sslmode=sometimes")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("sometimes") && err.contains("verify-full"),
            "{err}"
        );
        let err = take_settings("postgres://u@db/sitar?sslmode=verify-ca&sslrootcert=/nope/ca.pem")
            .and_then(|(_, s)| connector(&s).map(drop))
            .unwrap_err()
            .to_string();
        assert!(err.contains("/nope/ca.pem"), "{err}");
    }
}
