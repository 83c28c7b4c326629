//! The one error type of `sitar-scene`.

/// What can go wrong building a scene.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The session logged no pose yet: there is nothing to draw.
    #[error("the session has no trajectory yet (start it and log frames before exporting a scene)")]
    NoTrajectory,
    /// A number does not fit glTF (non-finite coordinate, more than 4 GiB of data).
    #[error("cannot encode the scene as glTF: {0}")]
    Encode(String),
}
