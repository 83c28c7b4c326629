//! Users of a simulated venue are put into the venue frame from their phones' own anchor
//! observations (saved and read back as the phone's session folder), within a few
//! centimetres and degrees of the simulator's truth.

use sitar_core::{DisplayRotation, Session, SessionConfig, venue::align};
use sitar_sim::{DEMO_ANCHOR_ID, Venue};

#[test]
fn phone_sessions_align_to_the_venue_within_5_cm_and_2_degrees() {
    let venue = Venue::demo(4, 20.0, 30.0, 21).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    for user in &venue.users {
        let config = SessionConfig::from_json(r#"{"convention":"arcore","images":false}"#).unwrap();
        let session = user.phone_session(config, DisplayRotation::Deg90).unwrap();
        assert_eq!(session.anchors().len(), user.observations.len());
        // Through the folder, as the upload reads it.
        let folder = dir.join(format!("user_{}", user.index));
        session.save(&folder).unwrap();
        let csv = std::fs::read_to_string(folder.join("anchors.csv")).unwrap();
        let read = sitar_core::venue::parse_anchors_csv(&csv, "anchors.csv").unwrap();
        assert_eq!(read.len(), user.observations.len());
        let alignment = align(&read, DEMO_ANCHOR_ID).unwrap();
        let (position_m, heading_deg) = user.truth.error_of(&alignment);
        println!(
            "user {}: {} full observations ({} rejected), error {:.1} mm, {:.2}°",
            user.index,
            alignment.observations,
            alignment.rejected,
            position_m * 1000.0,
            heading_deg
        );
        assert!(position_m < 0.05, "user {}: {position_m} m", user.index);
        assert!(heading_deg < 2.0, "user {}: {heading_deg}°", user.index);
        // Without the anchor the session is not aligned, and says why.
        let other = align(&read, "another-anchor").unwrap_err();
        assert!(other.reason.contains("never observed"), "{other}");
    }
}

/// The session's surface points are in the phone's own world: mapped through the truth into
/// the venue frame, every user's depth samples of the blank wall land on the same plane.
#[test]
fn surface_points_of_different_users_meet_in_the_venue_frame() {
    let venue = Venue::demo(3, 20.0, 30.0, 5).unwrap();
    let wall = venue.room.surface("blank wall").unwrap();
    let anchor = venue.anchor.pose;
    let mut on_wall = 0;
    for user in &venue.users {
        let config = SessionConfig::from_json(r#"{"convention":"arcore","images":false}"#).unwrap();
        let session: Session = user.phone_session(config, DisplayRotation::Deg0).unwrap();
        let truth = sitar_core::Alignment {
            translation: user.truth.translation,
            heading_rad: user.truth.heading_rad,
            observations: 0,
            rejected: 0,
            position_spread_m: 0.0,
            heading_spread_deg: 0.0,
        };
        for sample in session
            .subtrajectories()
            .iter()
            .filter_map(|s| s.depth.sample())
        {
            // Venue → room through the anchor's levelled pose in the room.
            let heading = sitar_core::venue::heading_of(anchor.rotation).unwrap();
            let room = anchor.position
                + glam::DQuat::from_rotation_y(heading) * truth.to_venue(sample.point);
            if wall.distance_to(room) < 0.03 {
                on_wall += 1;
            }
            let (nearest, d) = venue.room.nearest_surface(room).unwrap();
            assert!(
                d < 0.03,
                "user {}: {room} is {d} m from {}",
                user.index,
                nearest.name
            );
        }
    }
    assert!(on_wall > 0, "no user's depth sample fell on the blank wall");
}
