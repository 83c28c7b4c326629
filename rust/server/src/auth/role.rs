//! The roles a token can have.

/// What a token may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// Every session, the overview, the devices, deleting any session.
    Admin,
    /// Creates sessions; reads, uploads to, estimates and deletes only its own.
    App,
}

impl Role {
    /// `admin` or `app`.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Admin => "admin",
            Role::App => "app",
        }
    }
}

impl std::str::FromStr for Role {
    type Err = String;
    fn from_str(s: &str) -> Result<Role, String> {
        match s {
            "admin" => Ok(Role::Admin),
            "app" => Ok(Role::App),
            other => Err(format!("unknown role {other:?}: expected admin or app")),
        }
    }
}
