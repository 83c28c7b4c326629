//! Where HTTP lives: the route table and its middleware (`router`; finding each request's
//! caller, `authenticate`; the per-token limits, `upload_limits`), serving on plain TCP or
//! TLS (`server`, `connections`, `tls`), the bounds on every request (`request_limits`,
//! `parse_errors`), the JSON error shape (`json_errors`), pages of long JSON documents
//! (`pagination`), a session's status document (`session_status`), the pages' scripts and
//! styles (`assets`), the helpers every handler uses (`helpers`) and one handler file per
//! resource (`handlers`).

pub(crate) mod assets;
pub(crate) mod authenticate;
pub(crate) mod connections;
pub(crate) mod handlers;
pub(crate) mod helpers;
pub(crate) mod json_errors;
pub(crate) mod netinfo;
pub(crate) mod pagination;
pub(crate) mod parse_errors;
pub(crate) mod request_limits;
pub(crate) mod router;
pub(crate) mod server;
pub(crate) mod session_status;
pub(crate) mod stored_zip;
pub(crate) mod tls;
pub(crate) mod upload_limits;
