//! The session folder: what the phone keeps of a session (formats on [`Session::save`]).

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::logged_pose::LoggedPose;
use crate::session::{DepthStatus, SessionState, SubTrajectory};
use crate::subtrajectory_columns::{HEADER, header};
use crate::{DepthSample, Error, ErrorUnit, InvalidDepth, Pose, Results, Session, SessionConfig};

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Stamped {
    t_ns: i64,
    pose: Pose,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SessionFile {
    version: u32,
    state: SessionState,
    frames: u32,
    start: Option<Stamped>,
    stop: Option<Stamped>,
    last_t_ns: i64,
    last_position: DVec3,
    length_m: f64,
    sub_start_ns: i64,
    frame_intervals_ns: Vec<i64>,
    path_m: Vec<f64>,
    /// Set only when the app replaced the default lookup tolerance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lookup_tolerance_ns: Option<i64>,
}

fn write_file(path: &Path, text: &str) -> Result<(), Error> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

fn read_file(path: &Path) -> Result<String, Error> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|x| x.to_string()).unwrap_or_default()
}

impl Session {
    /// Writes the session folder `dir` (created if needed):
    ///
    /// | file | format |
    /// |---|---|
    /// | `config.json` | the [`SessionConfig`] JSON (every key) |
    /// | `trajectory.txt` | TUM `t x y z qx qy qz qw`, `t` integer ns: start, midpoints, endpoints |
    /// | `walk.txt` | the same format: the start pose and every frame's pose (the walk itself) |
    /// | `calibration.json` | the calibration given with [`Session::set_calibration`], if any |
    /// | `subtrajectories.csv` | one row per sub-trajectory, columns below |
    /// | `results.json` | the results in their JSON form (only once results were loaded) |
    /// | `evidence.csv`, `thumbnails/<k>.jpg` | what the camera saw at each midpoint (format: [`crate::EVIDENCE_HEADER`]) |
    /// | `anchors.csv` | every anchor observation: `t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking` (world-from-image pose; `none`, `limited` or `full`); a folder without it has none |
    /// | `session.json` | recorder state: `version`, `state`, `frames`, `start`/`stop` (`{t_ns, pose}`), `last_t_ns`, `last_position`, `length_m`, `sub_start_ns`, `frame_intervals_ns`, `path_m` (per logged pose), `lookup_tolerance_ns` (only if set) |
    ///
    /// `subtrajectories.csv` columns: `index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,
    /// depth_m,distance_m,cam_x,cam_y,cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class`
    /// (`error_deg` instead of `error_m` when the session's `pose_relation` is `angle_deg`);
    /// `depth` is `valid`, `missing`, `no_depth`, `out_of_bounds` or `no_valid_neighbours`;
    /// empty cells where a value does not apply; `x…nz` are the world point and normal, `cam_*`
    /// the display-oriented camera frame; the error and `class` are informational (recomputed
    /// from the results on load). Numbers are written in Rust's shortest round-trip form, so a
    /// save/load round trip is exact.
    pub fn save(&self, dir: &Path) -> Result<(), Error> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        write_file(&dir.join("config.json"), &self.config.to_json())?;
        write_file(&dir.join("trajectory.txt"), &self.trajectory_tum())?;
        write_file(&dir.join("walk.txt"), &self.walk_tum())?;
        let calibration_path = dir.join("calibration.json");
        match &self.calibration {
            Some(c) => write_file(&calibration_path, &c.to_json())?,
            None => {
                if calibration_path.exists() {
                    std::fs::remove_file(&calibration_path)
                        .map_err(|e| Error::io(&calibration_path, e))?;
                }
            }
        }
        let file = SessionFile {
            version: 1,
            state: self.state,
            frames: self.frames,
            start: self.start.map(|(t_ns, pose)| Stamped { t_ns, pose }),
            stop: self.stop.map(|(t_ns, pose)| Stamped { t_ns, pose }),
            last_t_ns: self.last_t_ns,
            last_position: self.last_position,
            length_m: self.length_m,
            sub_start_ns: self.sub_start_ns,
            frame_intervals_ns: self.frame_intervals_ns.clone(),
            path_m: self.logged.iter().map(|l| l.path_m).collect(),
            lookup_tolerance_ns: self.tolerance_override_ns,
        };
        let json = serde_json::to_string_pretty(&file)
            .map_err(|e| Error::io(dir, std::io::Error::other(e)))?;
        write_file(&dir.join("session.json"), &json)?;
        self.save_evidence(dir)?;

        let errors = self.subtrajectory_errors();
        let mut csv = header(self.config.pose_relation.unit());
        csv.push('\n');
        for (s, e) in self.subs.iter().zip(errors) {
            let _ = write!(
                csv,
                "{},{},{},{},",
                s.index,
                s.start_ns,
                s.mid_ns,
                opt(s.end_ns)
            );
            match &s.depth {
                DepthStatus::Missing => {
                    csv.push_str("missing");
                    csv.push_str(&",".repeat(16));
                }
                DepthStatus::Invalid(why) => {
                    let (x, y) = why.pixel();
                    let _ = write!(csv, "{},{x},{y}", why.code());
                    csv.push_str(&",".repeat(14));
                }
                DepthStatus::Valid(d) => {
                    let _ = write!(
                        csv,
                        "valid,{},{},{},{}",
                        d.pixel[0], d.pixel[1], d.depth_m, d.distance_m
                    );
                    for v in [d.camera_point, d.camera_normal, d.point, d.normal] {
                        let _ = write!(csv, ",{},{},{}", v.x, v.y, v.z);
                    }
                }
            }
            let class = if e.is_some() {
                self.subtrajectory_class(s.index).name()
            } else {
                ""
            };
            let _ = writeln!(csv, ",{},{class}", opt(e));
        }
        write_file(&dir.join("subtrajectories.csv"), &csv)?;
        write_file(
            &dir.join("anchors.csv"),
            &crate::venue::anchors_csv(&self.anchors),
        )?;

        let results_path = dir.join("results.json");
        match &self.results {
            Some(r) => write_file(&results_path, &r.to_json(self.config.class_thresholds()))?,
            None => {
                if results_path.exists() {
                    std::fs::remove_file(&results_path).map_err(|e| Error::io(&results_path, e))?;
                }
            }
        }
        Ok(())
    }

    /// Reads a session folder written by [`Session::save`].
    pub fn load(dir: &Path) -> Result<Session, Error> {
        let config = SessionConfig::from_json(&read_file(&dir.join("config.json"))?)?;
        let session_path = dir.join("session.json");
        let file: SessionFile = serde_json::from_str(&read_file(&session_path)?)
            .map_err(|e| Error::parse("session.json", e.line(), "(document)", e.to_string()))?;
        if file.version != 1 {
            return Err(Error::parse(
                "session.json",
                0,
                "version",
                format!("unsupported version {}", file.version),
            ));
        }
        let poses =
            crate::tum::parse_tum_ns(&read_file(&dir.join("trajectory.txt"))?, "trajectory.txt")?;
        if poses.len() != file.path_m.len() {
            return Err(Error::parse(
                "session.json",
                0,
                "path_m",
                format!(
                    "{} entries for {} logged poses in trajectory.txt",
                    file.path_m.len(),
                    poses.len()
                ),
            ));
        }
        let half = config.subtrajectory_frames / 2;
        // The start pose, then one every `half` frames; an idle session has neither.
        let expected_poses = match file.state {
            SessionState::Idle if file.frames == 0 => Some(0),
            SessionState::Idle => None,
            _ => Some(1 + (file.frames / half) as usize),
        };
        if expected_poses != Some(poses.len()) {
            return Err(Error::parse(
                "session.json",
                0,
                "frames",
                format!(
                    "{} frames in state {:?} do not match the {} logged poses in trajectory.txt",
                    file.frames,
                    file.state,
                    poses.len()
                ),
            ));
        }
        let logged = poses
            .into_iter()
            .zip(&file.path_m)
            .enumerate()
            .map(|(i, ((t_ns, pose), &path_m))| LoggedPose {
                t_ns,
                frame: i as u32 * half,
                pose,
                path_m,
            })
            .collect();
        let subs = parse_table(&read_file(&dir.join("subtrajectories.csv"))?)?;
        if subs.len() * 2 > file.path_m.len() {
            return Err(Error::parse(
                "subtrajectories.csv",
                0,
                "index",
                format!(
                    "{} sub-trajectories but only {} logged poses in trajectory.txt",
                    subs.len(),
                    file.path_m.len()
                ),
            ));
        }
        let results_path = dir.join("results.json");
        let results = if results_path.exists() {
            Some(Results::parse(&read_file(&results_path)?)?)
        } else {
            None
        };

        let mut session = Session::new(config);
        session.state = file.state;
        session.frames = file.frames;
        session.start = file.start.map(|s| (s.t_ns, s.pose));
        session.stop = file.stop.map(|s| (s.t_ns, s.pose));
        session.last_t_ns = file.last_t_ns;
        session.last_position = file.last_position;
        session.length_m = file.length_m;
        session.sub_start_ns = file.sub_start_ns;
        session.frame_intervals_ns = file.frame_intervals_ns;
        session.logged = logged;
        session.inputs = crate::evidence_table::load_evidence(dir, subs.len())?;
        session.subs = subs;
        if let Some(r) = &results {
            session.check_results(r)?;
        }
        session.results = results;
        // A folder saved before walks were kept has none: the session works without.
        let walk_path = dir.join("walk.txt");
        if walk_path.exists() {
            let walk = crate::tum::parse_tum_ns(&read_file(&walk_path)?, "walk.txt")?;
            let frames = if session.start.is_some() {
                1 + file.frames as usize
            } else {
                0
            };
            if walk.len() != frames {
                return Err(Error::parse(
                    "walk.txt",
                    0,
                    "poses",
                    format!(
                        "{} poses for the start and {} frames of session.json",
                        walk.len(),
                        file.frames
                    ),
                ));
            }
            session.walk = walk;
        }
        let calibration_path = dir.join("calibration.json");
        if calibration_path.exists() {
            session.calibration = Some(crate::calibration::Calibration::from_json(
                &read_file(&calibration_path)?,
                "calibration.json",
            )?);
        }
        let anchors_path = dir.join("anchors.csv");
        if anchors_path.exists() {
            session.anchors =
                crate::venue::parse_anchors_csv(&read_file(&anchors_path)?, "anchors.csv")?;
        }
        session.tolerance_ns = None;
        session
            .set_lookup_tolerance_ns(file.lookup_tolerance_ns)
            .map_err(|e| Error::parse("session.json", 0, "lookup_tolerance_ns", e.to_string()))?;
        if session.state == SessionState::Stopped {
            session.tolerance_ns = Some(session.compute_tolerance_ns());
        }
        session.refresh_markers();
        Ok(session)
    }
}

fn parse_table(text: &str) -> Result<Vec<SubTrajectory>, Error> {
    const SRC: &str = "subtrajectories.csv";
    let columns: Vec<&str> = HEADER.split(',').collect();
    let degrees = header(ErrorUnit::Degrees);
    let mut subs = Vec::new();
    for (line_no, cells) in crate::csv_rows::rows(text, SRC, &[HEADER, &degrees])? {
        let cell =
            |name: &str| -> &str { cells[columns.iter().position(|c| *c == name).unwrap_or(0)] };
        fn num<T: std::str::FromStr>(line: usize, name: &str, s: &str) -> Result<T, Error> {
            s.parse::<T>()
                .map_err(|_| Error::parse(SRC, line, name, format!("`{s}` is not a valid number")))
        }
        let vec3 = |a: &str, b: &str, c: &str| -> Result<DVec3, Error> {
            Ok(DVec3::new(
                num(line_no, a, cell(a))?,
                num(line_no, b, cell(b))?,
                num(line_no, c, cell(c))?,
            ))
        };
        let index: u32 = num(line_no, "index", cell("index"))?;
        if index as usize != subs.len() {
            return Err(Error::parse(
                SRC,
                line_no,
                "index",
                format!("expected {}, found {index}", subs.len()),
            ));
        }
        let end_ns = match cell("end_ns") {
            "" => None,
            s => Some(num(line_no, "end_ns", s)?),
        };
        let depth = match cell("depth") {
            "missing" => DepthStatus::Missing,
            "valid" => DepthStatus::Valid(DepthSample {
                pixel: [
                    num(line_no, "pixel_x", cell("pixel_x"))?,
                    num(line_no, "pixel_y", cell("pixel_y"))?,
                ],
                depth_m: num(line_no, "depth_m", cell("depth_m"))?,
                distance_m: num(line_no, "distance_m", cell("distance_m"))?,
                camera_point: vec3("cam_x", "cam_y", "cam_z")?,
                camera_normal: vec3("cam_nx", "cam_ny", "cam_nz")?,
                point: vec3("x", "y", "z")?,
                normal: vec3("nx", "ny", "nz")?,
            }),
            code => {
                let x = num(line_no, "pixel_x", cell("pixel_x"))?;
                let y = num(line_no, "pixel_y", cell("pixel_y"))?;
                DepthStatus::Invalid(InvalidDepth::from_code(code, x, y).ok_or_else(|| {
                    Error::parse(
                        SRC,
                        line_no,
                        "depth",
                        format!("unknown depth status `{code}`"),
                    )
                })?)
            }
        };
        subs.push(SubTrajectory {
            index,
            start_ns: num(line_no, "start_ns", cell("start_ns"))?,
            mid_ns: num(line_no, "mid_ns", cell("mid_ns"))?,
            end_ns,
            depth,
        });
    }
    Ok(subs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DepthImage, DisplayRotation, Intrinsics};
    use glam::DQuat;

    fn recorded(convention: &str) -> Session {
        let config = SessionConfig::from_json(&format!(
            r#"{{"convention":"{convention}","server_url":"http://x:1"}}"#
        ))
        .unwrap();
        let mut s = Session::new(config);
        let n = DQuat::from_rotation_y(0.4) * DVec3::NEG_Z;
        let k = Intrinsics {
            fx: 211.0,
            fy: 210.0,
            cx: 127.3,
            cy: 95.9,
        };
        let data = crate::depth::testing::render_plane(256, 192, &k, n, -1.7);
        let mut holey = data.clone();
        holey[96 * 256 + 128] = 0;
        let dt = 33_333_334;
        let pose = |i: i64| {
            Pose::new(
                DVec3::new(0.013 * i as f64, 1.5, -0.007 * i as f64),
                DQuat::from_rotation_y(0.01 * i as f64),
            )
        };
        s.start(1_700_000_000_000_000_000, pose(0)).unwrap();
        for i in 1..=47 {
            let t = 1_700_000_000_000_000_000 + i * dt + (i % 3);
            if s.frame(t, pose(i)).unwrap().is_midpoint() && i != 25 {
                let img =
                    DepthImage::new(if i == 15 { &holey } else { &data }, 256, 192, 512).unwrap();
                let _ = s.depth(&img, &k, DisplayRotation::Deg90);
            }
        }
        s
    }

    #[test]
    fn save_and_load_round_trip_exactly() {
        let dir = tempfile::tempdir().unwrap();
        for convention in ["unity", "arcore"] {
            let mut s = recorded(convention);
            // Mid-recording state round-trips too.
            let path = dir.path().join(format!("{convention}-recording"));
            s.save(&path).unwrap();
            assert_eq!(Session::load(&path).unwrap(), s);

            s.stop(1_700_000_000_000_000_000 + 48 * 33_333_334, Pose::IDENTITY)
                .unwrap();
            let starts: Vec<i64> = s.subtrajectories().iter().map(|x| x.start_ns).collect();
            let csv: String = std::iter::once("start,error\n".to_owned())
                .chain(
                    starts
                        .iter()
                        .enumerate()
                        .map(|(i, t)| format!("{t},{}\n", 0.04 * i as f64)),
                )
                .collect();
            s.load_results(&csv).unwrap();
            if convention == "arcore" {
                s.set_lookup_tolerance_ns(Some(1_000_000)).unwrap();
            }
            let path = dir.path().join(convention);
            s.save(&path).unwrap();
            let back = Session::load(&path).unwrap();
            assert_eq!(back, s);
            assert_eq!(back.markers().unwrap(), s.markers().unwrap());
            assert_eq!(back.render_plan(), s.render_plan());
            let table = std::fs::read_to_string(path.join("subtrajectories.csv")).unwrap();
            let rows: Vec<&str> = table.lines().collect();
            assert_eq!(rows.len(), 6);
            assert!(
                rows[2].starts_with("1,") && rows[2].contains(",no_depth,128,96,"),
                "{}",
                rows[2]
            );
            assert!(rows[3].contains(",missing,"));
            assert!(
                rows[5].starts_with("4,") && rows[5].ends_with(",0.16,high"),
                "{}",
                rows[5]
            );
        }
    }

    #[test]
    fn calibrated_results_and_classify_by_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = recorded("arcore");
        s.config.classify_by = crate::ClassifyBy::Upper;
        s.stop(1_700_000_000_000_000_000 + 48 * 33_333_334, Pose::IDENTITY)
            .unwrap();
        let windows: Vec<String> = s
            .subtrajectories()
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let e = 0.01 * i as f64;
                format!(
                    r#"{{"start":{},"error_m":{e},"lower_m":{},"raw_m":{},"upper_m":{}}}"#,
                    x.start_ns,
                    e / 2.0,
                    e * 0.7,
                    e * 4.0
                )
            })
            .collect();
        let json = format!(
            r#"{{"calibration":"pixel7","window_frames":10,"windows":[{}]}}"#,
            windows.join(",")
        );
        s.load_results(&json).unwrap();
        s.save(dir.path()).unwrap();
        let back = Session::load(dir.path()).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.config().classify_by, crate::ClassifyBy::Upper);
        assert_eq!(
            back.results().unwrap().calibration.as_deref(),
            Some("pixel7")
        );
        assert_eq!(back.markers().unwrap(), s.markers().unwrap());
        // Sub 3: error 3 cm (low), upper 12 cm: high by the upper bound; the table keeps
        // the error and the class shown.
        let table = std::fs::read_to_string(dir.path().join("subtrajectories.csv")).unwrap();
        assert!(
            table.lines().nth(4).unwrap().ends_with(",0.03,high"),
            "{table}"
        );
    }

    #[test]
    fn degree_results_round_trip_and_unfit_results_are_refused_on_load() {
        let dir = tempfile::tempdir().unwrap();
        let mut config = recorded("unity").config().clone();
        config.pose_relation = crate::PoseRelation::AngleDeg;
        let mut s = recorded("unity");
        s.config = config;
        s.stop(1_700_000_000_000_000_000 + 48 * 33_333_334, Pose::IDENTITY)
            .unwrap();
        let windows: Vec<String> = s
            .subtrajectories()
            .iter()
            .enumerate()
            .map(|(i, x)| {
                format!(
                    r#"{{"start":{},"error_deg":{}}}"#,
                    x.start_ns,
                    1.5 * i as f64
                )
            })
            .collect();
        let json = format!(
            r#"{{"window_frames":10,"pose_relation":"angle_deg","windows":[{}]}}"#,
            windows.join(",")
        );
        s.load_results(&json).unwrap();
        s.save(dir.path()).unwrap();
        let back = Session::load(dir.path()).unwrap();
        assert_eq!(back, s);
        let table = std::fs::read_to_string(dir.path().join("subtrajectories.csv")).unwrap();
        assert!(table.lines().next().unwrap().ends_with(",error_deg,class"));
        // 4 × 1.5° = 6°: high from 4°.
        assert!(
            table.lines().nth(5).unwrap().ends_with(",6,high"),
            "{table}"
        );

        // A results.json edited to another window length no longer fits the session.
        let edited = json.replace(r#""window_frames":10"#, r#""window_frames":20"#);
        std::fs::write(dir.path().join("results.json"), edited).unwrap();
        let err = Session::load(dir.path()).unwrap_err();
        assert!(err.to_string().contains("window_frames 20"), "{err}");
    }

    #[test]
    fn load_errors_name_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let s = recorded("unity");
        s.save(dir.path()).unwrap();
        let table = dir.path().join("subtrajectories.csv");
        let text = std::fs::read_to_string(&table).unwrap();
        let broken = text.replacen(",valid,", ",valid,x", 1);
        std::fs::write(&table, broken).unwrap();
        match Session::load(dir.path()) {
            Err(Error::Parse {
                source_name,
                line,
                field,
                ..
            }) => {
                assert_eq!(
                    (source_name.as_str(), line, field.as_str()),
                    ("subtrajectories.csv", 2, "pixel_x")
                )
            }
            other => panic!("{other:?}"),
        }
        std::fs::write(&table, text).unwrap();
        std::fs::write(dir.path().join("config.json"), r#"{"colour":"red"}"#).unwrap();
        assert!(
            matches!(Session::load(dir.path()), Err(Error::Config { key, .. }) if key == "colour")
        );
        assert!(matches!(
            Session::load(&dir.path().join("nope")),
            Err(Error::Io { .. })
        ));
    }

    #[test]
    fn frame_count_must_match_the_logged_poses() {
        // Found with the fuzz target `persist`: a recording session.json claiming u32::MAX
        // frames loaded, and the next `frame` call overflowed the frame counter (a panic in
        // debug builds, a wrap to frame 0 in release).
        let dir = tempfile::tempdir().unwrap();
        let mut s = recorded("unity");
        s.save(dir.path()).unwrap();
        let file = dir.path().join("session.json");
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.contains("\"frames\": 47,"));
        for (state, frames) in [
            ("recording", "4294967295"),
            ("recording", "57"),
            ("idle", "47"),
        ] {
            let broken = text
                .replacen("\"frames\": 47,", &format!("\"frames\": {frames},"), 1)
                .replacen(
                    "\"state\": \"recording\"",
                    &format!("\"state\": \"{state}\""),
                    1,
                );
            std::fs::write(&file, broken).unwrap();
            match Session::load(dir.path()) {
                Err(Error::Parse {
                    source_name,
                    field,
                    message,
                    ..
                }) => {
                    assert_eq!(
                        (source_name.as_str(), field.as_str()),
                        ("session.json", "frames")
                    );
                    assert!(message.contains("10 logged poses"), "{message}");
                }
                other => panic!("{state} {frames}: {other:?}"),
            }
        }
        // 47 and 49 frames both log 10 poses (every fifth frame): consistent, loads, records on
        // (walk.txt, one pose per frame, would say otherwise: a folder without it loads).
        let walk = dir.path().join("walk.txt");
        let walk_text = std::fs::read_to_string(&walk).unwrap();
        std::fs::remove_file(&walk).unwrap();
        std::fs::write(
            &file,
            text.replacen("\"frames\": 47,", "\"frames\": 49,", 1),
        )
        .unwrap();
        assert!(Session::load(dir.path()).is_ok());
        std::fs::write(&walk, &walk_text).unwrap();
        let err = Session::load(dir.path()).unwrap_err().to_string();
        assert!(
            err.contains("walk.txt") && err.contains("49 frames"),
            "{err}"
        );
        std::fs::write(&file, text).unwrap();
        let mut back = Session::load(dir.path()).unwrap();
        let t = 1_700_000_000_000_000_000 + 48 * 33_333_334;
        assert_eq!(
            back.frame(t, Pose::IDENTITY).unwrap(),
            s.frame(t, Pose::IDENTITY).unwrap()
        );
    }
}
