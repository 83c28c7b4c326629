//! `sitar traj`'s statistics table (`--save_table`, as evo_traj writes it) and the speeds its
//! plots draw.

use anyhow::Result;
use sitar_estimator::Trajectory;

use crate::evo::traj::bundle::{Bundle, Kind};
use crate::evo::traj::info::statistics;

/// evo's `--save_table` CSV: one column per trajectory, one row per number (transposed, as
/// evo's default `table_export_transpose`).
pub(super) fn stats_table(bundle: &Bundle, kind: Kind) -> Result<String> {
    let timed = kind != Kind::Kitti;
    let mut columns = Vec::new();
    for (name, t) in &bundle.trajectories {
        let mut rows = vec![
            ("nr. of poses".to_owned(), t.len() as f64),
            ("path length (m)".to_owned(), t.path_length()),
        ];
        if timed {
            let (first, last) = (t.stamps[0], t.stamps[t.len() - 1]);
            rows.push((
                "duration (s)".into(),
                t.time_unit.seconds(last) - t.time_unit.seconds(first),
            ));
            rows.push(("t_start (s)".into(), t.time_unit.seconds(first)));
            rows.push(("t_end (s)".into(), t.time_unit.seconds(last)));
        }
        rows.extend(statistics(t, timed).unwrap_or_default());
        columns.push((name.clone(), rows));
    }
    let mut out = String::from(",");
    out += &columns
        .iter()
        .map(|c| c.0.clone())
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    let keys: Vec<String> = columns
        .first()
        .map(|c| c.1.iter().map(|r| r.0.clone()).collect())
        .unwrap_or_default();
    for key in keys {
        out += &key;
        for (_, rows) in &columns {
            out.push(',');
            if let Some((_, v)) = rows.iter().find(|r| r.0 == key) {
                out += &sitar_evo::pyfmt::repr(*v);
            }
        }
        out.push('\n');
    }
    Ok(out)
}

/// evo's speeds plot of `t`: the speed between each pose and the one before, at the newer
/// pose's `x`. As evo, a step whose stamps do not increase leaves the whole trajectory out
/// of the plot: `Err` carries the first such pair of stamps (seconds) for the warning.
pub(super) fn speeds(
    t: &Trajectory,
    x: impl Fn(usize) -> f64,
) -> Result<Vec<(f64, f64)>, (f64, f64)> {
    (1..t.len())
        .map(|i| {
            let (t0, t1) = (
                t.time_unit.seconds(t.stamps[i - 1]),
                t.time_unit.seconds(t.stamps[i]),
            );
            if t1 - t0 > 0.0 {
                Ok((
                    x(i),
                    (t.positions[i] - t.positions[i - 1]).length() / (t1 - t0),
                ))
            } else {
                Err((t0, t1))
            }
        })
        .collect()
}

/// A float as Python's `str` prints it (shortest round trip, `1.0` not `1`), for evo's
/// words in warnings.
pub(super) fn python_str(v: f64) -> String {
    let s = v.to_string();
    if v.is_finite() && !s.contains(['.', 'e']) {
        format!("{s}.0")
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use glam::{DQuat, DVec3};
    use sitar_estimator::TimeUnit;

    use super::*;

    fn line(stamps: Vec<i64>, time_unit: TimeUnit) -> Trajectory {
        let n = stamps.len();
        Trajectory {
            stamps,
            positions: (0..n)
                .map(|i| DVec3::new(i as f64, (i * i) as f64, 0.0))
                .collect(),
            orientations: vec![DQuat::IDENTITY; n],
            time_unit,
        }
    }
    #[test]
    fn speeds_leave_out_a_trajectory_with_a_repeated_stamp_as_evo() {
        let s = TimeUnit::Seconds;
        let t = line(vec![0, 1_000_000_000, 3_000_000_000], s);
        let points = speeds(&t, |i| i as f64).unwrap();
        // (1,1)-(0,0) over 1 s; (2,4)-(1,1) over 2 s, each at the newer pose.
        assert_eq!(points, vec![(1.0, 2f64.sqrt()), (2.0, 10f64.sqrt() / 2.0)]);
        let repeated = line(vec![0, 1_000_000_000, 1_000_000_000, 3_000_000_000], s);
        assert_eq!(speeds(&repeated, |i| i as f64), Err((1.0, 1.0)));
        assert_eq!(python_str(1.0), "1.0");
        assert_eq!(python_str(1311868229.576), "1311868229.576");
    }
}
