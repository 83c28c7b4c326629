//! The phone's own log, uploaded beside its evidence (issue 24): `trajectory.txt` (start,
//! midpoints, endpoints; TUM, integer ns), `walk.txt` (the start pose and every frame's pose,
//! the same format: the walk itself, issue 41), `anchors.csv` (its observations of image
//! anchors) and `subtrajectories.csv` (sitar-core's whole table). Each is checked whole on
//! arrival, and a bad cell is a 422 naming the file, line and column; the checked text is
//! stored as sent (`SessionObject::{PhoneTrajectory, Walk, Anchors, Subtrajectories}`), since
//! sitar-core reads these formats and the venue map reads them with it.

use sitar_core::{ErrorClass, InvalidDepth};

use crate::error::Error;
use crate::ingest::evidence::{Cells, Span, indexed_rows};

/// Body limit of `PUT …/trajectory.txt`: a 2-hour walk logs 6 poses a second, ~100 bytes
/// each (4.3 MB); 32 MiB leaves room for longer ones.
pub(crate) const MAX_TRAJECTORY_BYTES: u64 = 32 << 20;
/// Body limit of `PUT …/anchors.csv`: ~120 bytes an observation, so about 70 000 of them.
pub(crate) const MAX_ANCHORS_BYTES: u64 = 8 << 20;

/// sitar-core's `subtrajectories.csv` header (results in metres).
pub(crate) const SUBTRAJECTORIES_HEADER: &str = "index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class";

/// The depth columns after `depth`, in order.
const DEPTH_COLUMNS: [&str; 16] = [
    "pixel_x",
    "pixel_y",
    "depth_m",
    "distance_m",
    "cam_x",
    "cam_y",
    "cam_z",
    "cam_nx",
    "cam_ny",
    "cam_nz",
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
];

/// A sitar-core error as the 422 that names file, line and column.
fn invalid(e: sitar_core::Error) -> Error {
    Error::InvalidContent(e.to_string())
}

/// Checks the phone's `trajectory.txt`: TUM rows with integer-nanosecond stamps that rise
/// strictly, at least one. The number of poses.
pub(crate) fn check_trajectory(text: &str) -> Result<usize, Error> {
    check_tum_ns(text, "trajectory.txt")
}

/// Checks the phone's `walk.txt` as [`check_trajectory`] does its file (TUM, integer
/// nanoseconds rising strictly, at least one pose), and reads it as a run for the estimator,
/// each position within the trials' bounds (`ingest::trials::MAX_POSITION_M`).
pub(crate) fn parse_walk(text: &str) -> Result<sitar_estimator::Trajectory, Error> {
    const SRC: &str = "walk.txt";
    check_tum_ns(text, SRC)?;
    crate::ingest::trials::parse_run(text.as_bytes(), SRC, 1)
}

/// TUM rows with integer-nanosecond stamps that rise strictly, at least one; errors name
/// `src`, the line and the column. The number of poses.
fn check_tum_ns(text: &str, src: &str) -> Result<usize, Error> {
    let poses = sitar_core::parse_tum_ns(text, src).map_err(invalid)?;
    let lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim().starts_with('#'))
        .map(|(i, _)| i + 1);
    for (((t0, _), (t1, _)), line) in poses.iter().zip(poses.iter().skip(1)).zip(lines.skip(1)) {
        if t1 <= t0 {
            return Err(Error::InvalidContent(format!(
                "{src} line {line}, column `timestamp`: {t1} does not come after {t0}"
            )));
        }
    }
    if poses.is_empty() {
        return Err(Error::InvalidContent(format!("{src}: no poses")));
    }
    Ok(poses.len())
}

/// Checks the phone's `anchors.csv` (sitar-core's header and cells). The number of
/// observations.
pub(crate) fn check_anchors(text: &str) -> Result<usize, Error> {
    sitar_core::venue::parse_anchors_csv(text, "anchors.csv")
        .map(|observations| observations.len())
        .map_err(invalid)
}

/// What a `subtrajectories.csv` brought.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SubtrajectoryTable {
    /// Start and end of each sub-trajectory.
    pub spans: Vec<Span>,
    /// With sitar-core's whole header: how many rows have a valid depth sample (surface
    /// point and normal); `None` for a table of spans only (`index,start_ns,end_ns`, read as
    /// before).
    pub depth_samples: Option<usize>,
}

/// Whether `text` starts with sitar-core's whole header (errors in metres or degrees).
fn has_whole_header(text: &str) -> bool {
    let first = text.lines().next().unwrap_or("").trim_end_matches('\r');
    first == SUBTRAJECTORIES_HEADER
        || first == SUBTRAJECTORIES_HEADER.replace(",error_m,", ",error_deg,")
}

/// Parses the phone's `subtrajectories.csv`. With sitar-core's header every cell is checked
/// (times, the depth status and its sample, error and class); a table with other columns
/// must have `index`, `start_ns` and `end_ns`, and only those are read.
pub(crate) fn parse_subtrajectories(text: &str) -> Result<SubtrajectoryTable, Error> {
    if !has_whole_header(text) {
        return Ok(SubtrajectoryTable {
            spans: crate::ingest::evidence::parse_spans(text)?,
            depth_samples: None,
        });
    }
    const SRC: &str = "subtrajectories.csv";
    let error_column = if text.contains(",error_deg,") {
        "error_deg"
    } else {
        "error_m"
    };
    let mut columns: Vec<&str> = SUBTRAJECTORIES_HEADER.split(',').collect();
    columns[21] = error_column;
    let mut depth_samples = 0;
    let spans = indexed_rows(SRC, text, &columns, |c, index| {
        let start_ns: i64 = c.parse("start_ns")?;
        let mid_ns: i64 = c.parse("mid_ns")?;
        let end_ns = match c.raw("end_ns") {
            "" => None,
            _ => Some(c.parse::<i64>("end_ns")?),
        };
        if mid_ns < start_ns {
            return Err(c.bad("mid_ns", "comes before start_ns"));
        }
        if end_ns.is_some_and(|e| e < mid_ns) {
            return Err(c.bad("end_ns", "comes before mid_ns"));
        }
        if check_depth(c)? {
            depth_samples += 1;
        }
        if !c.raw(error_column).is_empty() {
            c.measure(error_column)?;
        }
        let class = c.raw("class");
        if !class.is_empty() && ErrorClass::from_name(class).is_none() {
            return Err(c.bad(
                "class",
                format!("`{class}` is not low, medium, high or unknown"),
            ));
        }
        Ok(Span {
            index,
            start_ns,
            end_ns,
        })
    })?;
    Ok(SubtrajectoryTable {
        spans,
        depth_samples: Some(depth_samples),
    })
}

/// Checks a row's depth cells as sitar-core writes them; whether the sample is valid.
fn check_depth(c: &Cells<'_, '_>) -> Result<bool, Error> {
    let empty_from = |first: usize| -> Result<(), Error> {
        match DEPTH_COLUMNS[first..]
            .iter()
            .find(|name| !c.raw(name).is_empty())
        {
            Some(name) => Err(c.bad(name, "must be empty without a valid depth sample")),
            None => Ok(()),
        }
    };
    match c.raw("depth") {
        "missing" => empty_from(0).map(|_| false),
        "valid" => {
            for name in DEPTH_COLUMNS {
                let v: f64 = c.parse(name)?;
                if !v.is_finite() {
                    return Err(c.bad(name, format!("{v} is not finite")));
                }
            }
            for name in ["depth_m", "distance_m"] {
                if c.parse::<f64>(name)? <= 0.0 {
                    return Err(c.bad(name, "is not above 0"));
                }
            }
            for (axis, name) in [("cam_nx", "cam_n"), ("nx", "n")] {
                let n: f64 = ["x", "y", "z"]
                    .iter()
                    .map(|a| c.parse::<f64>(&format!("{name}{a}")).unwrap_or(0.0).powi(2))
                    .sum::<f64>()
                    .sqrt();
                if (n - 1.0).abs() > 0.01 {
                    return Err(c.bad(axis, format!("the normal's length is {n}, not 1")));
                }
            }
            Ok(true)
        }
        code => {
            let (x, y) = (c.parse::<u32>("pixel_x")?, c.parse::<u32>("pixel_y")?);
            InvalidDepth::from_code(code, x, y).ok_or_else(|| {
                c.bad(
                    "depth",
                    format!(
                        "`{code}` is not valid, missing, no_depth, out_of_bounds or \
                         no_valid_neighbours"
                    ),
                )
            })?;
            empty_from(2).map(|_| false)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = "valid,128,96,1.5,1.52,0.1,0.2,-1.5,0,0,1,0.3,1.4,-2.1,0,0,1";

    fn table(rows: &[String]) -> String {
        let mut t = format!("{SUBTRAJECTORIES_HEADER}\n");
        for r in rows {
            t.push_str(r);
            t.push('\n');
        }
        t
    }

    #[test]
    fn a_whole_table_counts_its_depth_samples() {
        let missing = format!("missing{}", ",".repeat(16));
        let text = table(&[
            format!("0,100,150,200,{VALID},0.03,low"),
            format!("1,200,250,300,{missing},,"),
            format!("2,300,350,,no_depth,12,40{},,", ",".repeat(14)),
        ]);
        let t = parse_subtrajectories(&text).unwrap();
        assert_eq!(t.depth_samples, Some(1));
        assert_eq!(t.spans.len(), 3);
        assert_eq!((t.spans[2].start_ns, t.spans[2].end_ns), (300, None));
        let degrees = text.replacen(",error_m,", ",error_deg,", 1);
        assert_eq!(
            parse_subtrajectories(&degrees).unwrap().depth_samples,
            Some(1)
        );
    }

    #[test]
    fn a_bad_cell_of_a_whole_table_names_line_and_column() {
        let good = format!("0,100,150,200,{VALID},0.03,low");
        for (bad, column) in [
            (good.replace("0,0,1,0.03", "0,0,7,0.03"), "`nx`"),
            (good.replace(",1.5,1.52,", ",-1.5,1.52,"), "`depth_m`"),
            (good.replace("valid,", "sideways,"), "`depth`"),
            (good.replace(",0.03,low", ",0.03,severe"), "`class`"),
            (good.replace(",0.03,", ",-2,"), "`error_m`"),
            (good.replace("0,100,150", "0,100,50"), "`mid_ns`"),
            (good.replace(",0.3,1.4,", ",x,1.4,"), "`x`"),
        ] {
            let text = table(&[format!("0,0,0,100,{VALID},,"), bad.replacen("0,", "1,", 1)]);
            let e = parse_subtrajectories(&text).unwrap_err().to_string();
            assert!(e.contains("line 3") && e.contains(column), "{column}: {e}");
        }
    }

    #[test]
    fn a_table_of_spans_only_is_read_as_before() {
        let t = parse_subtrajectories("index,start_ns,end_ns\n0,10,20\n").unwrap();
        assert_eq!(t.depth_samples, None);
        assert_eq!(t.spans[0].end_ns, Some(20));
    }

    #[test]
    fn a_trajectory_has_integer_rising_stamps() {
        assert_eq!(
            check_trajectory("# t x y z qx qy qz qw\n10 0 0 0 0 0 0 1\n20 1 0 0 0 0 0 1\n")
                .unwrap(),
            2
        );
        let e = check_trajectory("10 0 0 0 0 0 0 1\n\n10 1 0 0 0 0 0 1\n").unwrap_err();
        assert!(e.to_string().contains("line 3, column `timestamp`"), "{e}");
        let e = check_trajectory("10.5 0 0 0 0 0 0 1\n").unwrap_err();
        assert!(
            e.to_string().contains("line 1") && e.to_string().contains("timestamp"),
            "{e}"
        );
        let e = check_trajectory("10 0 0 zero 0 0 0 1\n").unwrap_err();
        assert!(
            e.to_string().contains("line 1") && e.to_string().contains("tz"),
            "{e}"
        );
        assert!(check_trajectory("# nothing\n").is_err());
    }
}
