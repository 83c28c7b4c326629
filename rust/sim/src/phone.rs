//! The user's phone during a simulated walk: sitar-core fed exactly as an app feeds it.

use sitar_core::{
    AnchorObservation, DepthImage, DisplayRotation, LumaImage, Pose, Session, SessionConfig,
};

use crate::{DepthCamera, Error, LumaCamera, Recording};

impl Recording {
    /// Records the walk with the phone logic: [`Session::start`] at the first ground-truth
    /// pose, [`Session::frame`] for every later one, a depth image of the room (rendered in
    /// the sensor orientation of a phone held with `display` rotation) and, when the config
    /// asks for camera images (`images`, the default), the camera's luminance plane at every
    /// midpoint (an unusable depth sample, as on glass, is recorded and the walk goes on, as on
    /// a phone),
    /// [`Session::stop`] at the last pose. This is the session the user's phone keeps: the
    /// demo and the backend's report and scene use it for simulated recordings.
    pub fn phone_session(
        &self,
        config: SessionConfig,
        display: DisplayRotation,
    ) -> Result<Session, Error> {
        self.phone_session_in(config, display, Pose::IDENTITY, &[])
    }

    /// [`Recording::phone_session`] with the phone's world frame `world_from_room` (every
    /// pose given to the session is `world_from_room ∘ pose`; depth is relative to the
    /// camera, so surface points follow), and `anchors` (already in that world frame, in time
    /// order) reported through [`Session::anchor`] after the frame of the same or an earlier
    /// timestamp, as an app reports an image tracker's updates after the camera frame.
    pub fn phone_session_in(
        &self,
        config: SessionConfig,
        display: DisplayRotation,
        world_from_room: Pose,
        anchors: &[AnchorObservation],
    ) -> Result<Session, Error> {
        let core = |e: sitar_core::Error| Error::InvalidArgument(format!("phone session: {e}"));
        let gt = &self.walk().ground_truth;
        if gt.len() < 3 {
            return Err(Error::InvalidArgument(format!(
                "the walk has {} poses; the phone needs at least 3 (start, a frame, stop)",
                gt.len()
            )));
        }
        let images = config.images;
        let mut session = Session::try_new(config).map_err(core)?;
        let camera = DepthCamera::phone();
        let luma_camera = LumaCamera::phone();
        let k = camera.intrinsics;
        let pose = |i: usize| {
            crate::venue_users::compose(
                world_from_room,
                Pose::new(gt.positions[i], gt.orientations[i]),
            )
        };
        let last = gt.len() - 1;
        let mut pending = anchors.iter().peekable();
        let mut report_until = |session: &mut Session, t_ns: i64| -> Result<(), Error> {
            while let Some(o) = pending.next_if(|o| o.t_ns <= t_ns) {
                session
                    .anchor(o.t_ns, &o.anchor, o.pose, o.tracking)
                    .map_err(core)?;
            }
            Ok(())
        };
        session.start(gt.stamps[0], pose(0)).map_err(core)?;
        report_until(&mut session, gt.stamps[0])?;
        for i in 1..last {
            let flags = session.frame(gt.stamps[i], pose(i)).map_err(core)?;
            report_until(&mut session, gt.stamps[i])?;
            if flags.is_midpoint() {
                let depth = self.room().render_depth_mm_rotated(
                    gt.positions[i],
                    gt.orientations[i],
                    &camera,
                    display,
                );
                if images {
                    let luma = self.room().render_luma_rotated(
                        gt.positions[i],
                        gt.orientations[i],
                        &luma_camera,
                        display,
                        i as u64,
                    );
                    let (w, h) = (luma_camera.width, luma_camera.height);
                    let luma = LumaImage::new(&luma, w, h, w).map_err(core)?;
                    session.image(&luma, display).map_err(core)?;
                }
                let image = DepthImage::new(&depth, camera.width, camera.height, camera.width * 2)
                    .map_err(core)?;
                match session.depth(&image, &k, display) {
                    Ok(()) | Err(sitar_core::Error::InvalidDepth(_)) => {}
                    Err(other) => return Err(core(other)),
                }
            }
        }
        // Whatever is left (the last frame's, or stamps past the walk) goes before stop.
        report_until(&mut session, i64::MAX)?;
        session.stop(gt.stamps[last], pose(last)).map_err(core)?;
        Ok(session)
    }
}
