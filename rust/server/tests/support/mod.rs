//! What the server's integration tests share.

use std::path::Path;

use sitar_server::{Server, ServerConfig, ServerHandle};

/// The server with its default configuration on data directory `data`, on a free loopback
/// port, and the admin token it keeps there (written on its first start).
#[allow(dead_code)] // not every test file starts the default server
pub fn spawn_with_admin(data: &Path) -> (ServerHandle, String) {
    let server = Server::spawn(ServerConfig::new(data), "127.0.0.1:0".parse().unwrap()).unwrap();
    let admin = std::fs::read_to_string(data.join(sitar_server::ADMIN_TOKEN_FILE)).unwrap();
    (server, admin.trim().to_owned())
}

#[allow(dead_code)]
pub mod http;
