//! The server's certificate: loaded from `--cert`/`--key`, or made once (rcgen) for the
//! `--tls-name` names and kept in `DATA/tls/` (the key readable by the owner only).

use std::path::Path;
use std::sync::Arc;

use rustls::pki_types::pem::PemObject;
use rustls::pki_types::{CertificateDer, PrivateKeyDer};

use crate::config::TlsConfig;
use crate::error::Error;
use crate::storage::instance;

/// The TLS side of a server: the rustls configuration and the certificate's fingerprint.
pub(crate) struct Tls {
    pub config: Arc<rustls::ServerConfig>,
    /// `AB:CD:…`, 32 bytes in upper-case hex: `openssl x509 -noout -fingerprint -sha256`.
    pub fingerprint: String,
}

/// SHA-256 of a DER certificate as `openssl x509 -fingerprint -sha256` prints it.
pub(crate) fn fingerprint(der: &[u8]) -> String {
    ring::digest::digest(&ring::digest::SHA256, der)
        .as_ref()
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(":")
}

/// The default names of a self-signed certificate.
fn default_names() -> Vec<String> {
    let mut names = vec![
        "localhost".to_owned(),
        "127.0.0.1".to_owned(),
        "::1".to_owned(),
    ];
    if let Some(ip) = crate::http::netinfo::lan_address() {
        names.push(ip.to_string());
    }
    if let Ok(host) = std::fs::read_to_string("/etc/hostname") {
        let host = host.trim();
        if !host.is_empty() && host != "localhost" {
            names.push(host.to_owned());
        }
    }
    names
}

/// Loads (or makes) the certificate and builds the rustls configuration.
pub(crate) fn load(config: &TlsConfig, data_dir: &Path) -> Result<Tls, Error> {
    let (cert_path, key_path) = match (&config.cert, &config.key) {
        (Some(cert), Some(key)) => (cert.clone(), key.clone()),
        (None, None) => {
            let (cert, key, both) = instance::tls_pair(data_dir);
            if !both {
                let names = if config.names.is_empty() {
                    default_names()
                } else {
                    config.names.clone()
                };
                make_self_signed(data_dir, names)?;
            }
            (cert, key)
        }
        _ => {
            return Err(Error::Config(
                "--cert and --key go together (or neither: a self-signed certificate)".into(),
            ));
        }
    };
    let bad = |what: &str, path: &Path, e: &dyn std::fmt::Display| {
        Error::Config(format!("TLS {what} {}: {e}", path.display()))
    };
    let chain = CertificateDer::pem_file_iter(&cert_path)
        .map_err(|e| bad("certificate", &cert_path, &e))?
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| bad("certificate", &cert_path, &e))?;
    let first = chain
        .first()
        .ok_or_else(|| bad("certificate", &cert_path, &"no CERTIFICATE block"))?;
    let fingerprint = fingerprint(first);
    let key = PrivateKeyDer::from_pem_file(&key_path).map_err(|e| bad("key", &key_path, &e))?;
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let mut server = rustls::ServerConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| Error::Config(format!("TLS: {e}")))?
        .with_no_client_auth()
        .with_single_cert(chain, key)
        .map_err(|e| bad("certificate and key", &cert_path, &e))?;
    server.alpn_protocols = vec![b"http/1.1".to_vec()];
    Ok(Tls {
        config: Arc::new(server),
        fingerprint,
    })
}

/// Makes a self-signed certificate for `names` into the data directory (its key mode 0600).
fn make_self_signed(data_dir: &Path, names: Vec<String>) -> Result<(), Error> {
    let mut params = rcgen::CertificateParams::new(names.clone())
        .map_err(|e| Error::Config(format!("--tls-name {names:?}: {e}")))?;
    params
        .distinguished_name
        .push(rcgen::DnType::CommonName, "sitar serve");
    let pair = rcgen::KeyPair::generate()
        .map_err(|e| Error::Internal(format!("TLS key generation: {e}")))?;
    let made = params
        .self_signed(&pair)
        .map_err(|e| Error::Internal(format!("TLS self-signed certificate: {e}")))?;
    instance::write_tls_pair(data_dir, &made.pem(), &pair.serialize_pem())?;
    log::info!(
        "made a self-signed TLS certificate for {} in {}",
        names.join(", "),
        data_dir.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_certificate_is_made_once_with_a_private_key_and_a_stable_fingerprint() {
        let dir = tempfile::tempdir().unwrap();
        let config = TlsConfig {
            names: vec!["127.0.0.1".into(), "sitar.local".into()],
            ..TlsConfig::default()
        };
        let first = load(&config, dir.path()).unwrap();
        assert_eq!(first.fingerprint.len(), 32 * 3 - 1);
        assert!(
            first
                .fingerprint
                .chars()
                .all(|c| c == ':' || c.is_ascii_hexdigit())
        );
        let again = load(&config, dir.path()).unwrap();
        assert_eq!(again.fingerprint, first.fingerprint);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(dir.path().join("tls/key.pem"))
                .unwrap()
                .permissions()
                .mode();
            assert_eq!(mode & 0o777, 0o600);
        }
        // Only one of --cert/--key is refused, naming both.
        let half = TlsConfig {
            cert: Some(dir.path().join("tls/cert.pem")),
            ..TlsConfig::default()
        };
        let err = load(&half, dir.path()).err().unwrap().to_string();
        assert!(err.contains("--cert and --key"), "{err}");
        // Given files work, and a file that is no PEM is named.
        let given = TlsConfig {
            cert: Some(dir.path().join("tls/cert.pem")),
            key: Some(dir.path().join("tls/key.pem")),
            names: Vec::new(),
        };
        assert_eq!(
            load(&given, dir.path()).unwrap().fingerprint,
            first.fingerprint
        );
        std::fs::write(dir.path().join("junk.pem"), "not pem").unwrap();
        let junk = TlsConfig {
            cert: Some(dir.path().join("junk.pem")),
            ..given
        };
        let err = load(&junk, dir.path()).err().unwrap().to_string();
        assert!(err.contains("junk.pem"), "{err}");
    }
}
