//! `evidence.csv` and `thumbnails/`: the session folder's record of what the camera saw.
//!
//! `evidence.csv`, one row per sub-trajectory (header below): `index`; `image` (`1` when a
//! camera image was given at the midpoint, else `0` and the image columns empty);
//! `mean_brightness`, `contrast_std`, `laplacian_var`, `corners_per_10k`, `saturated_share`
//! ([`crate::ImageProperties`]); `thumbnail_width`, `thumbnail_height` (display orientation);
//! `depth_valid_share` (empty when no depth image was given); then, informational and
//! recomputed on load, `linear_speed_m_s`, `angular_speed_deg_s`, `depth_valid`, `distance_m`
//! and `causes` (machine names separated by spaces). Thumbnails are
//! `thumbnails/<index>.jpg` (greyscale baseline JPEG). A folder without `evidence.csv`
//! (older sessions) loads with no evidence.

use std::fmt::Write as _;
use std::path::Path;

use crate::session::MidpointInput;
use crate::{Error, ImageProperties, Session};

/// The header of `evidence.csv`, the session folder's properties table: one row per
/// sub-trajectory; `image` is 1 when a camera image was given (else the image columns are
/// empty); the image columns are [`crate::ImageProperties`], the thumbnail size is in display
/// orientation (`thumbnails/<index>.jpg`), `depth_valid_share` is empty without a depth image;
/// speeds, `depth_valid`, `distance_m` and `causes` (names separated by spaces) are
/// informational, recomputed on load.
pub const EVIDENCE_HEADER: &str = "index,image,mean_brightness,contrast_std,laplacian_var,corners_per_10k,saturated_share,thumbnail_width,thumbnail_height,depth_valid_share,linear_speed_m_s,angular_speed_deg_s,depth_valid,distance_m,causes";

const SRC: &str = "evidence.csv";

impl Session {
    /// `evidence.csv` of this session (format in the module docs of `evidence_table`).
    pub fn evidence_csv(&self) -> String {
        let mut csv = format!("{EVIDENCE_HEADER}\n");
        for (e, input) in self.evidence().iter().zip(&self.inputs) {
            let _ = write!(csv, "{},", e.index);
            match &input.image {
                Some(p) => {
                    let _ = write!(
                        csv,
                        "1,{},{},{},{},{},{},{},",
                        p.mean_brightness,
                        p.contrast_std,
                        p.laplacian_var,
                        p.corners_per_10k,
                        p.saturated_share,
                        input.thumbnail_size.0,
                        input.thumbnail_size.1
                    );
                }
                None => csv.push_str("0,,,,,,,,"),
            }
            if let Some(share) = input.depth_valid_share {
                let _ = write!(csv, "{share}");
            }
            let _ = writeln!(
                csv,
                ",{},{},{},{},{}",
                e.motion.linear_speed_m_s,
                e.motion.angular_speed_deg_s,
                u8::from(e.depth.valid),
                e.depth.distance_m,
                e.causes
            );
        }
        csv
    }

    /// Writes `evidence.csv` and `thumbnails/` into `dir`.
    pub(crate) fn save_evidence(&self, dir: &Path) -> Result<(), Error> {
        let path = dir.join("evidence.csv");
        std::fs::write(&path, self.evidence_csv()).map_err(|e| Error::io(&path, e))?;
        let thumbs = dir.join("thumbnails");
        if self.inputs.iter().any(|i| !i.thumbnail.is_empty()) {
            std::fs::create_dir_all(&thumbs).map_err(|e| Error::io(&thumbs, e))?;
        }
        for (k, input) in self.inputs.iter().enumerate() {
            if !input.thumbnail.is_empty() {
                let path = thumbs.join(format!("{k}.jpg"));
                std::fs::write(&path, &input.thumbnail).map_err(|e| Error::io(&path, e))?;
            }
        }
        Ok(())
    }
}

/// Reads `evidence.csv` and the thumbnails of `dir` for `n` sub-trajectories; without
/// `evidence.csv`, `n` empty inputs.
pub(crate) fn load_evidence(dir: &Path, n: usize) -> Result<Vec<MidpointInput>, Error> {
    let mut inputs = vec![MidpointInput::default(); n];
    let path = dir.join("evidence.csv");
    if !path.exists() {
        return Ok(inputs);
    }
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let columns: Vec<&str> = EVIDENCE_HEADER.split(',').collect();
    let mut lines = text.lines().enumerate();
    if lines.next().map(|(_, h)| h.trim()) != Some(EVIDENCE_HEADER) {
        return Err(Error::parse(
            SRC,
            1,
            "header",
            format!("expected `{EVIDENCE_HEADER}`"),
        ));
    }
    let mut rows = 0;
    for (i, line) in lines {
        let line_no = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != columns.len() {
            return Err(Error::parse(
                SRC,
                line_no,
                "(row)",
                format!("{} cells, expected {}", cells.len(), columns.len()),
            ));
        }
        let cell = |name: &str| cells[columns.iter().position(|c| *c == name).unwrap_or(0)];
        fn num<T: std::str::FromStr>(line: usize, name: &str, s: &str) -> Result<T, Error> {
            s.parse::<T>()
                .map_err(|_| Error::parse(SRC, line, name, format!("`{s}` is not a valid number")))
        }
        let index: usize = num(line_no, "index", cell("index"))?;
        if index != rows || index >= n {
            return Err(Error::parse(
                SRC,
                line_no,
                "index",
                format!("{index} out of order or beyond the {n} sub-trajectories"),
            ));
        }
        rows += 1;
        let input = &mut inputs[index];
        match cell("image") {
            "1" => {
                input.image = Some(ImageProperties {
                    mean_brightness: num(line_no, "mean_brightness", cell("mean_brightness"))?,
                    contrast_std: num(line_no, "contrast_std", cell("contrast_std"))?,
                    laplacian_var: num(line_no, "laplacian_var", cell("laplacian_var"))?,
                    corners_per_10k: num(line_no, "corners_per_10k", cell("corners_per_10k"))?,
                    saturated_share: num(line_no, "saturated_share", cell("saturated_share"))?,
                });
                input.thumbnail_size = (
                    num(line_no, "thumbnail_width", cell("thumbnail_width"))?,
                    num(line_no, "thumbnail_height", cell("thumbnail_height"))?,
                );
                let thumb = dir.join("thumbnails").join(format!("{index}.jpg"));
                input.thumbnail = std::fs::read(&thumb).map_err(|e| Error::io(&thumb, e))?;
            }
            "0" => {}
            other => {
                return Err(Error::parse(
                    SRC,
                    line_no,
                    "image",
                    format!("`{other}` is neither 0 nor 1"),
                ));
            }
        }
        let share = cell("depth_valid_share");
        if !share.is_empty() {
            input.depth_valid_share = Some(num(line_no, "depth_valid_share", share)?);
        }
    }
    Ok(inputs)
}
