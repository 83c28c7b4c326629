//! Figures: how well `sitar_core::venue::align` puts simulated users into the venue frame.
//!
//! `cargo run --release -p sitar-sim --example venue_alignment [USERS] [SEED]` (default 20
//! users, seed 1): each user walks the demo room for 20 s in their own world frame, the phone
//! session reports the anchor as the phone does, `align` estimates the world-from-venue
//! transform from the `full` observations, and the error against the simulator's truth is
//! printed per user with the median and worst position (m) and heading (degrees).

use sitar_core::{DisplayRotation, SessionConfig, venue::align};
use sitar_sim::{DEMO_ANCHOR_ID, Venue};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let users: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(20);
    let seed: u64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(1);
    let venue = Venue::demo(users, 20.0, 30.0, seed)?;
    let (mut position, mut heading) = (Vec::new(), Vec::new());
    println!("user  observations  full  used  rejected  position_mm  heading_deg");
    for user in &venue.users {
        let config = SessionConfig::from_json(r#"{"convention":"arcore","images":false}"#)?;
        let session = user.phone_session(config, DisplayRotation::Deg90)?;
        let full = session
            .anchors()
            .iter()
            .filter(|o| o.tracking == sitar_core::Tracking::Full)
            .count();
        match align(session.anchors(), DEMO_ANCHOR_ID) {
            Ok(a) => {
                let (p, h) = user.truth.error_of(&a);
                println!(
                    "{:>4}  {:>12}  {full:>4}  {:>4}  {:>8}  {:>11.2}  {:>11.3}",
                    user.index,
                    session.anchors().len(),
                    a.observations,
                    a.rejected,
                    p * 1000.0,
                    h
                );
                position.push(p);
                heading.push(h);
            }
            Err(e) => println!("{:>4}  not aligned: {e}", user.index),
        }
    }
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        (median, v[n - 1])
    };
    if position.is_empty() {
        return Err("no user could be aligned".into());
    }
    let (pm, pw) = stats(&mut position);
    let (hm, hw) = stats(&mut heading);
    println!(
        "aligned {}/{users} users; position error median {:.4} m, worst {:.4} m; heading error median {:.3}°, worst {:.3}°",
        position.len(),
        pm,
        pw,
        hm,
        hw
    );
    Ok(())
}
