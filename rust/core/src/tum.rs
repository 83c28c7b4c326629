//! TUM trajectory text (`t x y z qx qy qz qw`) with integer-nanosecond stamps.

use std::fmt::Write as _;

use glam::{DQuat, DVec3};

use crate::{Error, Pose};

/// Appends one TUM line; f64 `Display` is the shortest text that parses back to the same value.
pub(crate) fn push_line(out: &mut String, t_ns: i64, pose: &Pose) {
    let (p, q) = (pose.position, pose.rotation);
    let _ = writeln!(
        out,
        "{t_ns} {} {} {} {} {} {} {}",
        p.x, p.y, p.z, q.x, q.y, q.z, q.w
    );
}

/// Formats poses as TUM text with integer-nanosecond stamps.
pub fn to_tum<'a>(poses: impl IntoIterator<Item = (i64, &'a Pose)>) -> String {
    let mut out = String::new();
    for (t, pose) in poses {
        push_line(&mut out, t, pose);
    }
    out
}

const COLUMNS: [&str; 8] = ["timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"];

/// Parses TUM text whose stamps are integer nanoseconds (`#` comments and blank lines
/// skipped). Errors name `source`, the line and the column.
pub fn parse_tum_ns(text: &str, source: &str) -> Result<Vec<(i64, Pose)>, Error> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let tokens: Vec<&str> = line.split_whitespace().collect();
        if tokens.len() != 8 {
            return Err(Error::parse(
                source,
                line_no,
                "row",
                format!("expected 8 columns, found {}", tokens.len()),
            ));
        }
        let t: i64 = tokens[0].parse().map_err(|_| {
            Error::parse(
                source,
                line_no,
                COLUMNS[0],
                format!("`{}` is not integer nanoseconds", tokens[0]),
            )
        })?;
        let mut v = [0.0f64; 7];
        for (j, slot) in v.iter_mut().enumerate() {
            let tok = tokens[j + 1];
            *slot = tok
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    Error::parse(
                        source,
                        line_no,
                        COLUMNS[j + 1],
                        format!("`{tok}` is not a finite number"),
                    )
                })?;
        }
        let pose = Pose::new(
            DVec3::new(v[0], v[1], v[2]),
            DQuat::from_xyzw(v[3], v[4], v[5], v[6]),
        );
        if pose.rotation.length_squared() < 1e-12 {
            return Err(Error::parse(source, line_no, "qw", "zero quaternion"));
        }
        out.push((t, pose));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact() {
        let poses = [
            (
                1_700_000_000_000_000_001i64,
                Pose::new(
                    DVec3::new(0.1, -2.0 / 3.0, 1e-7),
                    DQuat::from_rotation_y(0.3),
                ),
            ),
            (1_700_000_000_033_333_333, Pose::IDENTITY),
        ];
        let text = to_tum(poses.iter().map(|(t, p)| (*t, p)));
        assert!(text.starts_with("1700000000000000001 0.1 "));
        let back = parse_tum_ns(&text, "t.txt").unwrap();
        assert_eq!(back, poses.to_vec());
    }

    #[test]
    fn errors_name_line_and_column() {
        match parse_tum_ns("# c\n1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n", "t.txt") {
            Err(Error::Parse {
                line,
                field,
                source_name,
                ..
            }) => {
                assert_eq!(
                    (line, field.as_str(), source_name.as_str()),
                    (3, "ty", "t.txt")
                )
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            parse_tum_ns("1.5 0 0 0 0 0 0 1\n", "t"),
            Err(Error::Parse { line: 1, .. })
        ));
        assert!(matches!(
            parse_tum_ns("1 0 0 0 0 0 1\n", "t"),
            Err(Error::Parse { line: 1, .. })
        ));
    }
}
