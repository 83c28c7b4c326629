//! Many users walking one venue: each phone in its own world frame, observing the venue's
//! printed anchor when it can, with the truth of where its world lies in the venue.

use glam::{DQuat, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use sitar_core::venue::heading_of;
use sitar_core::{AnchorObservation, DisplayRotation, Pose, Session, SessionConfig};

use crate::{AnchorSensor, Error, PrintedAnchor, Recording, Room, Walk};

/// RNG stream of a user's anchor observations (walks and trials use others).
const ANCHOR_STREAM: u64 = 5;

/// The most users a simulated venue takes.
pub const MAX_VENUE_USERS: usize = 1000;

/// A venue: one room with a printed anchor, walked by several users.
#[derive(Debug, Clone)]
pub struct Venue {
    /// The room, the anchor's print included.
    pub room: Room,
    /// The printed anchor.
    pub anchor: PrintedAnchor,
    /// How the phones see the anchor.
    pub sensor: AnchorSensor,
    /// The users, in order.
    pub users: Vec<VenueUser>,
}

/// Where a user's world frame lies in the venue frame: `p_world = R_y(heading) · p_venue +
/// translation`, exactly the quantity [`sitar_core::venue::align`] estimates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VenueTruth {
    /// The anchor's centre in the user's world frame (m).
    pub translation: DVec3,
    /// The turn about +Y from the venue frame to the user's world frame (radians, (−π, π]).
    pub heading_rad: f64,
}

impl VenueTruth {
    /// Position and heading error of an estimated alignment against this truth: (m, degrees).
    pub fn error_of(&self, alignment: &sitar_core::Alignment) -> (f64, f64) {
        let d = alignment.heading_rad - self.heading_rad;
        let wrapped = d.sin().atan2(d.cos());
        (
            alignment.translation.distance(self.translation),
            wrapped.abs().to_degrees(),
        )
    }
}

/// One user of a venue: their walk (in the room frame, as the recording the backend plays),
/// their phone's world frame, and what their phone saw of the anchor.
#[derive(Debug, Clone)]
pub struct VenueUser {
    /// 0-based.
    pub index: usize,
    /// The seed of this user's walk, trials and observations.
    pub seed: u64,
    /// The walk through the room and its trials (room frame: trials are compared pairwise,
    /// so the frame does not matter to them).
    pub recording: Recording,
    /// World-from-room: the phone's world frame is where it started, gravity-aligned, its
    /// −Z the camera's levelled initial view.
    pub world_from_room: Pose,
    /// The anchor observations the phone reported, in its world frame, in time order.
    pub observations: Vec<AnchorObservation>,
    /// Where this user's world lies in the venue frame.
    pub truth: VenueTruth,
}

impl Venue {
    /// The demo venue: the demo room with [`PrintedAnchor::demo`] beside the painting, and
    /// `users` handheld walks of `seconds` at `fps` (user `i` from seed `seed + i`), each
    /// starting wherever its walk starts.
    ///
    /// A walk of at least 18.75 s visits every surface of interest, the anchor included;
    /// shorter ones may miss it (that user's session then cannot be aligned).
    pub fn demo(users: usize, seconds: f64, fps: f64, seed: u64) -> Result<Self, Error> {
        let anchor = PrintedAnchor::demo();
        let room = Room::demo().with_anchor(&anchor)?;
        Self::new(
            room,
            anchor,
            AnchorSensor::default(),
            users,
            seconds,
            fps,
            seed,
        )
    }

    /// A venue of `room` (with `anchor` already printed in it) walked by `users` users.
    pub fn new(
        room: Room,
        anchor: PrintedAnchor,
        sensor: AnchorSensor,
        users: usize,
        seconds: f64,
        fps: f64,
        seed: u64,
    ) -> Result<Self, Error> {
        if !(1..=MAX_VENUE_USERS).contains(&users) {
            return Err(Error::InvalidArgument(format!(
                "a venue needs 1 to {MAX_VENUE_USERS} users, got {users}"
            )));
        }
        let users = (0..users)
            .map(|index| {
                let seed = seed.wrapping_add(index as u64);
                let walk = Walk::handheld(&room, seconds, fps, seed)?;
                let recording = Recording::new(room.clone(), walk, seed);
                Ok(VenueUser::new(index, seed, recording, &anchor, &sensor))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        Ok(Self {
            room,
            anchor,
            sensor,
            users,
        })
    }
}

impl VenueUser {
    fn new(
        index: usize,
        seed: u64,
        recording: Recording,
        anchor: &PrintedAnchor,
        sensor: &AnchorSensor,
    ) -> Self {
        let gt = &recording.walk().ground_truth;
        let forward = gt.orientations[0] * DVec3::NEG_Z;
        // Yaw about +Y with 0 looking along −Z (as `look_rotation`).
        let yaw = (-forward.x).atan2(-forward.z);
        let room_from_world = Pose::new(gt.positions[0], DQuat::from_rotation_y(yaw));
        let world_from_room = inverse(room_from_world);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(ANCHOR_STREAM);
        let room = recording.room();
        let mut observations = Vec::new();
        for i in 0..gt.len() {
            let (p, q) = (gt.positions[i], gt.orientations[i]);
            if let Some(sighting) = sensor.sighting(room, anchor, p, q) {
                let seen = sensor.noisy_pose(anchor, &sighting, p, &mut rng);
                observations.push(AnchorObservation {
                    t_ns: gt.stamps[i],
                    anchor: anchor.id.clone(),
                    pose: compose(world_from_room, seen),
                    tracking: sighting.tracking,
                });
            }
        }
        let true_image = compose(world_from_room, anchor.pose);
        let truth = VenueTruth {
            translation: true_image.position,
            heading_rad: heading_of(true_image.rotation)
                .expect("a print on a wall has a horizontal +X"),
        };
        Self {
            index,
            seed,
            recording,
            world_from_room,
            observations,
            truth,
        }
    }

    /// This user's phone session, recorded as a phone records it (see
    /// [`Recording::phone_session`]) but in the phone's own world frame, with every anchor
    /// observation reported through [`Session::anchor`] between the frames it came with.
    pub fn phone_session(
        &self,
        config: SessionConfig,
        display: DisplayRotation,
    ) -> Result<Session, Error> {
        self.recording
            .phone_session_in(config, display, self.world_from_room, &self.observations)
    }

    /// `truth.json`: the user, the anchor, and the world-from-venue transform (translation in
    /// metres, heading in radians and degrees), plus world-from-room (position, quaternion
    /// `[x, y, z, w]`). ARCore convention, metres.
    pub fn truth_json(&self, anchor: &str) -> String {
        let w = self.world_from_room;
        let json = serde_json::json!({
            "format": "sitar-venue-truth",
            "version": 1,
            "user": self.index,
            "seed": self.seed,
            "anchor": anchor,
            "convention": "arcore",
            "world_from_venue": {
                "translation": self.truth.translation.to_array(),
                "heading_rad": self.truth.heading_rad,
                "heading_deg": self.truth.heading_rad.to_degrees(),
            },
            "world_from_room": {
                "position": w.position.to_array(),
                "rotation_xyzw": w.rotation.to_array(),
            },
            "observations": {
                "total": self.observations.len(),
                "full": self.observations.iter()
                    .filter(|o| o.tracking == sitar_core::Tracking::Full).count(),
            },
        });
        format!("{json:#}\n")
    }
}

/// `a ∘ b` for rigid poses.
pub(crate) fn compose(a: Pose, b: Pose) -> Pose {
    Pose::new(
        a.position + a.rotation * b.position,
        (a.rotation * b.rotation).normalize(),
    )
}

fn inverse(a: Pose) -> Pose {
    let r = a.rotation.inverse();
    Pose::new(-(r * a.position), r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sitar_core::Tracking;

    #[test]
    fn each_world_starts_at_its_phone_levelled_and_the_truth_maps_the_anchor() {
        let venue = Venue::demo(4, 20.0, 30.0, 3).unwrap();
        for user in &venue.users {
            let gt = &user.recording.walk().ground_truth;
            let first = compose(
                user.world_from_room,
                Pose::new(gt.positions[0], gt.orientations[0]),
            );
            assert!(first.position.length() < 1e-9);
            // Levelled: the first camera looks along −Z, give or take pitch.
            let f = first.rotation * DVec3::NEG_Z;
            assert!(f.x.abs() < 1e-9 && f.z < 0.0, "{f}");
            // The truth maps the venue origin onto the anchor and venue +X onto its right.
            let a = sitar_core::Alignment {
                translation: user.truth.translation,
                heading_rad: user.truth.heading_rad,
                observations: 0,
                rejected: 0,
                position_spread_m: 0.0,
                heading_spread_deg: 0.0,
            };
            let anchor_world = compose(user.world_from_room, venue.anchor.pose);
            assert!(a.to_venue(anchor_world.position).length() < 1e-9);
            let right = anchor_world.position + anchor_world.rotation * DVec3::X;
            assert!((a.to_venue(right) - DVec3::X).length() < 1e-9);
        }
        // Different users, different frames.
        let t: Vec<DVec3> = venue.users.iter().map(|u| u.truth.translation).collect();
        assert!(t.windows(2).all(|w| w[0].distance(w[1]) > 0.05), "{t:?}");
    }

    #[test]
    fn observations_come_only_from_frames_that_see_the_anchor() {
        let venue = Venue::demo(3, 20.0, 30.0, 11).unwrap();
        for user in &venue.users {
            assert!(
                user.observations
                    .iter()
                    .any(|o| o.tracking == Tracking::Full),
                "user {} never fully tracked the anchor",
                user.index
            );
            let gt = &user.recording.walk().ground_truth;
            let seen = (0..gt.len())
                .filter(|&i| {
                    venue
                        .sensor
                        .sighting(
                            &venue.room,
                            &venue.anchor,
                            gt.positions[i],
                            gt.orientations[i],
                        )
                        .is_some()
                })
                .count();
            assert_eq!(seen, user.observations.len());
            assert!(
                seen < gt.len() / 2,
                "the anchor is in view most of the walk"
            );
        }
    }
}
