//! Figures: a venue map's problem cells against the simulator's hard surfaces, for maps of
//! 1, 3 and 10 users.
//!
//! `cargo run --release -p sitar-sim --example venue_problem_cells [VENUES] [TRIALS]`
//! (default 3 venues of 10 users, 8 trials): per venue seed, each user walks the demo room
//! for 20 s in their own world frame; their recording is played as `TRIALS` simulated trials
//! and estimated pairwise (trim_mean_30, translation RPE over 10 frames, as the backend); the
//! phone's session folder (trajectory.txt, anchors.csv, subtrajectories.csv) and the results
//! become a `Contribution`; `build_map` (0.25 m cells) makes the map of the first 1, 3 and 10
//! users (and, for 3 and 10, of the cells seen by at least 2 sessions). A surface cell classed high or medium is a problem cell; it is on a hard surface
//! when the room surface nearest its centre is the blank wall or the glass pane. Precision is
//! problem cells on hard surfaces over problem cells; recall is hard-surface cells flagged
//! over hard-surface cells in the map. Counts are summed over the venues.

use sitar_core::Convention;
use sitar_core::venue::{VenueSpec, build_map};
use sitar_sim::{ProblemCellScore, Venue};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// (users, min_sessions): the maps compared.
const MAPS: [(usize, u32); 5] = [(1, 1), (3, 1), (10, 1), (3, 2), (10, 2)];

fn main() -> Res<()> {
    let mut args = std::env::args().skip(1);
    let venues: u64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(3);
    let trials: u32 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(8);
    let scratch = std::env::temp_dir().join(format!("sitar-venue-figures-{}", std::process::id()));
    let mut totals = [(0usize, 0usize, 0usize, 0usize, 0usize); MAPS.len()];
    println!(
        "venue  users  min_sessions  surface_cells  problem  on_hard  hard_cells  precision  recall  hard_surfaces_found"
    );
    for v in 0..venues {
        let venue = Venue::demo(10, 20.0, 30.0, 1000 * (v + 1))?;
        let contributions = venue
            .users
            .iter()
            .map(|u| {
                let id = format!("s{:016x}", u.seed);
                u.contribution(&id, &venue.anchor.id, trials, &scratch.join(&id))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let spec = VenueSpec {
            id: "v0000000000000001".into(),
            name: "demo room".into(),
            anchor: venue.anchor.id.clone(),
            cell_m: 0.25,
            convention: Convention::Arcore,
        };
        for (k, &(n, min_sessions)) in MAPS.iter().enumerate() {
            let map = build_map(&spec, &contributions[..n], min_sessions);
            let s = venue.score_problem_cells(&map);
            print_row(&format!("{v:>5}"), n, min_sessions, &s);
            let t = &mut totals[k];
            t.0 += s.surface_cells;
            t.1 += s.problem_cells;
            t.2 += s.problem_on_hard;
            t.3 += s.hard_cells;
            t.4 += s.hard_surfaces_found.len();
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    println!("summed over {venues} venues ({trials} trials per session):");
    for (k, &(n, min_sessions)) in MAPS.iter().enumerate() {
        let t = totals[k];
        let ratio = |a: usize, b: usize| {
            if b == 0 {
                f64::NAN
            } else {
                a as f64 / b as f64
            }
        };
        println!(
            "{n:>2} user(s), cells seen by ≥ {min_sessions}: {} surface cells, {} problem cells, precision {:.3}, recall {:.3}, hard surfaces found {}/{}",
            t.0,
            t.1,
            ratio(t.2, t.1),
            ratio(t.2, t.3),
            t.4,
            2 * venues
        );
    }
    Ok(())
}

fn print_row(venue: &str, users: usize, min_sessions: u32, s: &ProblemCellScore) {
    let f = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.3}"));
    println!(
        "{venue}  {users:>5}  {min_sessions:>12}  {:>13}  {:>7}  {:>7}  {:>10}  {:>9}  {:>6}  {}",
        s.surface_cells,
        s.problem_cells,
        s.problem_on_hard,
        s.hard_cells,
        f(s.precision()),
        f(s.recall()),
        s.hard_surfaces_found.join(", ")
    );
    if !s.problem_elsewhere.is_empty() {
        let elsewhere: Vec<String> = s
            .problem_elsewhere
            .iter()
            .map(|(name, n)| format!("{name} ×{n}"))
            .collect();
        println!(
            "{:>21}problem cells elsewhere: {}",
            "",
            elsewhere.join(", ")
        );
    }
}
