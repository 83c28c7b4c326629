//! The server: storage opened, routes served, jobs resumed; on its own thread or blocking.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use crate::config::ServerConfig;
use crate::shared::Shared;
use crate::{Error, deletion, jobs, router};

/// The backend: storage opened, ready to serve.
pub struct Server {
    shared: Arc<Shared>,
}

impl Server {
    /// Opens (or creates) the data directory and its SQLite database.
    pub fn open(config: ServerConfig) -> Result<Server, Error> {
        Ok(Server {
            shared: Arc::new(Shared::open(config)?),
        })
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
        deletion::spawn_retention_sweep(self.shared.clone());
        let shared = self.shared.clone();
        axum::serve(listener, self.router())
            .with_graceful_shutdown(async move {
                shutdown.await;
                shared.stop_all();
            })
            .await
            .map_err(|e| Error::Internal(format!("server: {e}")))
    }

    /// Serves on `addr` until Ctrl-C (`sitar serve`). Blocking.
    pub fn run(config: ServerConfig, addr: SocketAddr) -> Result<(), Error> {
        let server = Server::open(config)?;
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
            log::info!("listening on http://{bound}");
            server
                .serve(listener, async {
                    let _ = tokio::signal::ctrl_c().await;
                })
                .await
        });
        runtime.shutdown_timeout(Duration::from_secs(5));
        result
    }

    /// Starts the server on its own runtime thread, bound to `addr`
    /// (port 0: a free port). Used by `sitar demo` and the tests.
    pub fn spawn(config: ServerConfig, addr: SocketAddr) -> Result<ServerHandle, Error> {
        let server = Server::open(config)?;
        let shared = server.shared.clone();
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
            shutdown: Some(tx),
            thread: Some(thread),
            shared,
        })
    }
}

/// A server running on a background thread; stops when dropped.
pub struct ServerHandle {
    addr: SocketAddr,
    shutdown: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
    shared: Arc<Shared>,
}

impl ServerHandle {
    /// The bound address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// `http://ADDR`.
    pub fn url(&self) -> String {
        format!("http://{}", self.addr)
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
