//! The server: storage opened, routes served, jobs resumed; on its own thread or blocking.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use crate::app_state::App;
use crate::config::ServerConfig;
use crate::error::Error;
use crate::jobs::{delete_sweep, deletion};
use crate::{auth, http::router, http::tls, jobs::playback as jobs};

/// The backend: storage opened, ready to serve.
pub struct Server {
    shared: Arc<App>,
    /// The admin token this start made for a new data directory, shown once by `run`.
    new_admin_token: Option<String>,
    /// The certificate and rustls configuration with `ServerConfig::tls`.
    tls: Option<tls::Tls>,
}

impl Server {
    /// Opens (or creates) the data directory and its SQLite database; registers the preset
    /// tokens, and gives a new data directory its admin token (`DATA/admin.token`).
    pub fn open(config: ServerConfig) -> Result<Server, Error> {
        let mut shared = App::open(config)?;
        let tls = match &shared.config.tls {
            Some(tls_config) => Some(tls::load(tls_config, &shared.config.data_dir)?),
            None => None,
        };
        shared.tls_fingerprint = tls.as_ref().map(|t| t.fingerprint.clone());
        shared.secure_cookies = tls.is_some();
        let new_admin_token = if shared.config.insecure_no_auth {
            None
        } else {
            auth::ensure_admin_token(
                &shared.config.data_dir,
                &*shared.db,
                &shared.config.preset_tokens,
            )?
        };
        Ok(Server {
            shared: Arc::new(shared),
            new_admin_token,
            tls,
        })
    }

    /// Refuses `--insecure-no-auth` on an address other machines can reach.
    fn check_exposure(&self, addr: SocketAddr) -> Result<(), Error> {
        if self.shared.config.insecure_no_auth && !addr.ip().is_loopback() {
            return Err(Error::Config(format!(
                "--insecure-no-auth is only allowed on a loopback address (127.0.0.1, ::1), \
                 not {addr}"
            )));
        }
        Ok(())
    }

    /// The axum router of every route (for embedding or tests).
    pub fn router(&self) -> axum::Router {
        router::router(self.shared.clone())
    }

    /// Serves on `listener` until `shutdown` resolves. Sessions a previous
    /// process left in flight are resumed first (or marked failed with a reason).
    pub async fn serve(
        self,
        listener: tokio::net::TcpListener,
        shutdown: impl std::future::Future<Output = ()> + Send + 'static,
    ) -> Result<(), Error> {
        jobs::recover(&self.shared)?;
        if self.shared.clustered() {
            // Heartbeat, adoption of dead instances' sessions, stop requests from others.
            crate::jobs::instances::spawn(self.shared.clone());
        }
        deletion::spawn_retention_sweep(self.shared.clone());
        // Deletes a crash cut off, on every instance (the embedded one's own, after a restart).
        delete_sweep::spawn(self.shared.clone());
        let shared = self.shared.clone();
        let stop = async move {
            shutdown.await;
            shared.stop_all();
        };
        let limits = crate::http::connections::ConnectionLimits {
            max_connections: self.shared.config.max_connections,
            header_read_timeout: self.shared.config.header_read_timeout,
        };
        match &self.tls {
            Some(tls) => {
                let listener = tls::TlsListener::new(listener, tls.config.clone())
                    .map_err(|e| Error::Config(format!("listener: {e}")))?;
                crate::http::connections::serve(listener, self.router(), limits, stop).await;
            }
            None => crate::http::connections::serve(listener, self.router(), limits, stop).await,
        }
        Ok(())
    }

    /// `https` with TLS, else `http`.
    fn scheme(&self) -> &'static str {
        if self.tls.is_some() { "https" } else { "http" }
    }

    /// Serves on `addr` until Ctrl-C or SIGTERM (`sitar serve`): no new connections, requests
    /// in progress finish, jobs stop where the next start resumes them. Blocking.
    pub fn run(config: ServerConfig, addr: SocketAddr) -> Result<(), Error> {
        let server = Server::open(config)?;
        server.check_exposure(addr)?;
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .enable_all()
            .build()
            .map_err(|e| Error::Internal(format!("runtime: {e}")))?;
        let result = runtime.block_on(async {
            let listener = tokio::net::TcpListener::bind(addr)
                .await
                .map_err(|e| Error::Config(format!("cannot listen on {addr}: {e}")))?;
            // The bound address: with port 0 the system chose the port.
            let bound = listener.local_addr().unwrap_or(addr);
            let scheme = server.scheme();
            log::info!("listening on {scheme}://{bound}");
            if let Some(tls) = &server.tls {
                // What a phone pins (`server_cert_sha256`); compare with
                // `openssl x509 -noout -fingerprint -sha256 -in DATA/tls/cert.pem`.
                log::info!("TLS certificate SHA-256 fingerprint: {}", tls.fingerprint);
                println!("sitar serve: TLS certificate SHA-256 fingerprint {}", tls.fingerprint);
            }
            if let Some(token) = &server.new_admin_token {
                // Shown once, on stdout, never logged: the token is also in DATA/admin.token.
                println!(
                    "sitar serve: a new admin token is in {}; the overview: {scheme}://{}/?token={token}",
                    crate::storage::instance::admin_token_file(&server.shared.config.data_dir).display(),
                    url_host(bound),
                );
            }
            server
                .serve(listener, stop_signal())
                .await
        });
        runtime.shutdown_timeout(Duration::from_secs(5));
        result
    }

    /// Starts the server on its own runtime thread, bound to `addr`
    /// (port 0: a free port). Used by `sitar demo` and the tests.
    pub fn spawn(config: ServerConfig, addr: SocketAddr) -> Result<ServerHandle, Error> {
        let server = Server::open(config)?;
        server.check_exposure(addr)?;
        let shared = server.shared.clone();
        let scheme = server.scheme();
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .map_err(|e| Error::Internal(format!("runtime: {e}")))?;
        let listener = runtime
            .block_on(tokio::net::TcpListener::bind(addr))
            .map_err(|e| Error::Config(format!("cannot listen on {addr}: {e}")))?;
        let addr = listener
            .local_addr()
            .map_err(|e| Error::Config(format!("listener: {e}")))?;
        let (tx, rx) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name("sitar-server".into())
            .spawn(move || {
                let result = runtime.block_on(server.serve(listener, async {
                    let _ = rx.await;
                }));
                if let Err(e) = result {
                    log::error!("{e}");
                }
                // Blocking playback threads see the cancel flag within ~20 ms.
                runtime.shutdown_timeout(Duration::from_secs(5));
            })
            .map_err(|e| Error::Internal(format!("server thread: {e}")))?;
        Ok(ServerHandle {
            addr,
            scheme,
            shutdown: Some(tx),
            thread: Some(thread),
            shared,
        })
    }
}

/// A server running on a background thread; stops when dropped.
pub struct ServerHandle {
    addr: SocketAddr,
    scheme: &'static str,
    shutdown: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
    shared: Arc<App>,
}

impl ServerHandle {
    /// The bound address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// `http://ADDR`, or `https://ADDR` with TLS.
    pub fn url(&self) -> String {
        format!("{}://{}", self.scheme, self.addr)
    }

    /// The TLS certificate's SHA-256 fingerprint (`AB:CD:…`, as `openssl x509 -fingerprint
    /// -sha256` prints it), with TLS.
    pub fn tls_fingerprint(&self) -> Option<&str> {
        self.shared.tls_fingerprint.as_deref()
    }

    /// Makes a token with `role` named `name` (the demo's own tokens) and returns it.
    pub fn create_token(&self, role: crate::model::Role, name: &str) -> Result<String, Error> {
        let token = auth::new_token()?;
        self.shared.db.insert_token(name, role, &token)?;
        Ok(token)
    }

    /// Stops serving and every job; sessions in flight stay so for the next start.
    pub fn stop(mut self) {
        self.stop_inner();
    }

    fn stop_inner(&mut self) {
        self.shared.stop_all();
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for ServerHandle {
    fn drop(&mut self) {
        self.stop_inner();
    }
}

/// `HOST:PORT` to put in a URL for `bound`: an unspecified address (`0.0.0.0`, `::`) becomes
/// this machine's address on its default route, which a phone on the LAN can reach.
pub(crate) fn url_host(bound: SocketAddr) -> String {
    let ip = if bound.ip().is_unspecified() {
        crate::http::netinfo::lan_address().unwrap_or(bound.ip())
    } else {
        bound.ip()
    };
    SocketAddr::new(ip, bound.port()).to_string()
}

/// Resolves at the first Ctrl-C (SIGINT) or SIGTERM (what `docker stop`, systemd and
/// `kill` send).
async fn stop_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => log::info!("Ctrl-C: stopping"),
                    _ = term.recv() => log::info!("SIGTERM: stopping"),
                }
            }
            Err(e) => {
                log::warn!("cannot watch for SIGTERM ({e}); Ctrl-C stops");
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
        log::info!("Ctrl-C: stopping");
    }
}
