//! This machine's address on the LAN: what the overview URL and the default TLS names use
//! when the server listens on every interface.

use std::net::{IpAddr, UdpSocket};

/// The local address of the default route, found by "connecting" a UDP socket to a
/// documentation address (no packet is sent); `None` without a route.
pub(crate) fn lan_address() -> Option<IpAddr> {
    let socket = UdpSocket::bind("0.0.0.0:0").ok()?;
    socket.connect("192.0.2.1:9").ok()?;
    let ip = socket.local_addr().ok()?.ip();
    (!ip.is_unspecified()).then_some(ip)
}
