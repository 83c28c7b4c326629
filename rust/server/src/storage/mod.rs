//! Where bytes are kept: the metadata database (`db`), the data directory's files
//! (`files`) and the disk quotas that bound them (`quota`).

pub(crate) mod db;
pub(crate) mod files;
pub(crate) mod quota;
