//! The roles a token can have.

/// What a token may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// Every session, the overview, the devices, deleting any session.
    Admin,
    /// Creates sessions; reads, uploads to, estimates and deletes only its own.
    App,
    /// A playback host (`sitar worker`): the `/v1/worker/…` routes and nothing else.
    Worker,
}

impl Role {
    /// `admin`, `app` or `worker`.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Admin => "admin",
            Role::App => "app",
            Role::Worker => "worker",
        }
    }
}

impl std::str::FromStr for Role {
    type Err = String;
    fn from_str(s: &str) -> Result<Role, String> {
        match s {
            "admin" => Ok(Role::Admin),
            "app" => Ok(Role::App),
            "worker" => Ok(Role::Worker),
            other => Err(format!(
                "unknown role {other:?}: expected admin, app or worker"
            )),
        }
    }
}
