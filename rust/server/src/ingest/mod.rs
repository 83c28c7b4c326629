//! What arrives from phones and outside SLAM runs, checked once on arrival: recordings (the
//! MP4 check `mp4_check`; accepting one starts a job: `jobs::recordings`), trials
//! (`trials`), the camera evidence (`evidence`) and the phone's own log (`phone_log`).

pub(crate) mod evidence;
#[cfg(test)]
pub(crate) mod minimal_mp4;
pub(crate) mod mp4_check;
pub(crate) mod phone_log;
pub(crate) mod trials;
