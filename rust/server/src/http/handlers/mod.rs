//! One file per resource; each handler takes the helpers of `crate::http` (the session
//! lookup extractor, JSON answers) and never another handler.

pub(crate) mod devices;
pub(crate) mod evidence;
pub(crate) mod health;
pub(crate) mod legacy;
pub(crate) mod pages;
pub(crate) mod phone_log;
pub(crate) mod recording;
pub(crate) mod results;
pub(crate) mod scene;
pub(crate) mod sessions;
pub(crate) mod share;
pub(crate) mod trials;
pub(crate) mod venues;
pub(crate) mod worker;
