//! A session's evidence (what the phone's camera saw at each sub-trajectory): validated once
//! on arrival and kept in the session folder in the server's own form.
//!
//! ```text
//! DATA/sessions/ID/evidence.json          the phone's evidence.csv, parsed (rows below)
//! DATA/sessions/ID/spans.json             the phone's subtrajectories.csv: index, start, end
//! DATA/sessions/ID/thumbnails/K.jpg       sub-trajectory K's thumbnail (K server-checked)
//! ```
//!
//! The phone's formats are sitar-core's ([`sitar_core::EVIDENCE_HEADER`] and
//! `Session::save`); every cell is checked here, and a bad one is a 422 naming its line and
//! column.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};
use sitar_core::{Causes, EVIDENCE_HEADER, ImageProperties};

use crate::error::Error;
use crate::storage::BlobStore;
use crate::storage::keys::SessionObject;

/// Body limit of `PUT …/evidence.csv` and `PUT …/subtrajectories.csv`.
pub(crate) const MAX_TABLE_BYTES: u64 = 8 << 20;
/// Body limit of one thumbnail (`PUT …/subtrajectories/{k}/image.jpg`): the phone's
/// thumbnails are at most 1024 px on the longest side, greyscale, a few tens of KiB.
pub(crate) const MAX_THUMBNAIL_BYTES: u64 = 512 << 10;
/// Most sub-trajectories a session's tables may have (a 2-hour walk at 30 fps with
/// 10-frame sub-trajectories has 21 600).
pub(crate) const MAX_SUBTRAJECTORIES: usize = 100_000;

/// One row of the phone's `evidence.csv`, as stored and served.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct EvidenceRow {
    pub index: usize,
    /// Image properties; `None` when no camera image was given at the midpoint.
    pub image: Option<ImageProperties>,
    /// Thumbnail width and height in display orientation (with `image`).
    pub thumbnail_size: Option<(u32, u32)>,
    pub depth_valid_share: Option<f64>,
    pub linear_speed_m_s: f64,
    pub angular_speed_deg_s: f64,
    pub depth_valid: bool,
    pub distance_m: f64,
    /// Machine names of the likely causes.
    pub causes: Vec<String>,
}

/// Start and end (ns) of one sub-trajectory, from the phone's `subtrajectories.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct Span {
    pub index: usize,
    pub start_ns: i64,
    pub end_ns: Option<i64>,
}

/// A CSV table: column positions by name, and the non-empty rows with their line numbers.
type Table<'a> = (HashMap<&'a str, usize>, Vec<(usize, Vec<&'a str>)>);

/// The rows of the CSV body `text` (`src` names it in errors), after a header that must
/// contain the `needed` columns; each row has as many cells as the header.
fn table<'a>(src: &str, text: &'a str, needed: &[&str]) -> Result<Table<'a>, Error> {
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines
        .next()
        .map(|(_, h)| h.trim_end_matches('\r').split(',').collect())
        .unwrap_or_default();
    let columns: HashMap<&str, usize> = header.iter().enumerate().map(|(i, c)| (*c, i)).collect();
    if let Some(missing) = needed.iter().find(|c| !columns.contains_key(*c)) {
        return Err(Error::InvalidContent(format!(
            "{src} line 1: the header has no column `{missing}`"
        )));
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let line = line.trim_end_matches('\r');
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != header.len() {
            return Err(Error::InvalidContent(format!(
                "{src} line {}: {} cells, the header has {}",
                i + 1,
                cells.len(),
                header.len()
            )));
        }
        if rows.len() == MAX_SUBTRAJECTORIES {
            return Err(Error::InvalidContent(format!(
                "{src} line {}: more than {MAX_SUBTRAJECTORIES} sub-trajectories",
                i + 1
            )));
        }
        rows.push((i + 1, cells));
    }
    Ok((columns, rows))
}

/// Reads every row of the table `text` (as [`table`]) with `row`, given the row's cells and
/// its `index` cell, which must count 0, 1, … in order.
pub(super) fn indexed_rows<T>(
    src: &'static str,
    text: &str,
    needed: &[&str],
    mut row: impl FnMut(&Cells<'_, '_>, usize) -> Result<T, Error>,
) -> Result<Vec<T>, Error> {
    let (columns, rows) = table(src, text, needed)?;
    let mut out = Vec::with_capacity(rows.len());
    for (k, (line, cells)) in rows.iter().enumerate() {
        let c = Cells {
            src,
            line: *line,
            columns: &columns,
            cells,
        };
        let index = c.index(k)?;
        out.push(row(&c, index)?);
    }
    Ok(out)
}

/// One row's cells by column name, for errors that name line and column.
pub(super) struct Cells<'a, 'b> {
    src: &'static str,
    line: usize,
    columns: &'b HashMap<&'a str, usize>,
    cells: &'b [&'a str],
}

impl Cells<'_, '_> {
    pub(super) fn raw(&self, name: &str) -> &str {
        self.columns.get(name).map_or("", |&i| self.cells[i])
    }

    pub(super) fn bad(&self, name: &str, why: impl std::fmt::Display) -> Error {
        Error::InvalidContent(format!(
            "{} line {}, column `{name}`: {why}",
            self.src, self.line
        ))
    }

    pub(super) fn parse<T: std::str::FromStr>(&self, name: &str) -> Result<T, Error> {
        let s = self.raw(name);
        s.parse()
            .map_err(|_| self.bad(name, format!("`{s}` is not a valid number")))
    }

    /// A finite, non-negative number.
    pub(super) fn measure(&self, name: &str) -> Result<f64, Error> {
        let v: f64 = self.parse(name)?;
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(self.bad(name, format!("{v} is not a finite number ≥ 0")))
        }
    }

    pub(super) fn optional_measure(&self, name: &str) -> Result<Option<f64>, Error> {
        match self.raw(name) {
            "" => Ok(None),
            _ => self.measure(name).map(Some),
        }
    }

    pub(super) fn flag(&self, name: &str) -> Result<bool, Error> {
        match self.raw(name) {
            "1" => Ok(true),
            "0" => Ok(false),
            s => Err(self.bad(name, format!("`{s}` is neither 0 nor 1"))),
        }
    }

    fn index(&self, expected: usize) -> Result<usize, Error> {
        let index: usize = self.parse("index")?;
        if index == expected {
            Ok(index)
        } else {
            Err(self.bad("index", format!("{index} where {expected} was expected")))
        }
    }
}

/// Parses the phone's `evidence.csv` (header exactly [`EVIDENCE_HEADER`], indices 0, 1, …).
pub(crate) fn parse_evidence(text: &str) -> Result<Vec<EvidenceRow>, Error> {
    const SRC: &str = "evidence.csv";
    if text.lines().next().map(|h| h.trim_end_matches('\r')) != Some(EVIDENCE_HEADER) {
        return Err(Error::InvalidContent(format!(
            "{SRC} line 1: the header is not `{EVIDENCE_HEADER}`"
        )));
    }
    let needed: Vec<&str> = EVIDENCE_HEADER.split(',').collect();
    indexed_rows(SRC, text, &needed, |c, index| {
        let (image, thumbnail_size) = if c.flag("image")? {
            let image = ImageProperties {
                mean_brightness: c.measure("mean_brightness")?,
                contrast_std: c.measure("contrast_std")?,
                laplacian_var: c.measure("laplacian_var")?,
                corners_per_10k: c.measure("corners_per_10k")?,
                saturated_share: c.measure("saturated_share")?,
            };
            let size = (c.parse("thumbnail_width")?, c.parse("thumbnail_height")?);
            (Some(image), Some(size))
        } else {
            (None, None)
        };
        let causes_cell = c.raw("causes");
        let causes = Causes::from_names(causes_cell.split_whitespace())
            .ok_or_else(|| c.bad("causes", format!("`{causes_cell}` names an unknown cause")))?;
        Ok(EvidenceRow {
            index,
            image,
            thumbnail_size,
            depth_valid_share: c.optional_measure("depth_valid_share")?,
            linear_speed_m_s: c.measure("linear_speed_m_s")?,
            angular_speed_deg_s: c.measure("angular_speed_deg_s")?,
            depth_valid: c.flag("depth_valid")?,
            distance_m: c.measure("distance_m")?,
            causes: causes.names().map(str::to_owned).collect(),
        })
    })
}

/// Parses the phone's `subtrajectories.csv`: only `index`, `start_ns` and `end_ns` are read
/// (the other columns are the phone's and informational here).
pub(crate) fn parse_spans(text: &str) -> Result<Vec<Span>, Error> {
    const SRC: &str = "subtrajectories.csv";
    indexed_rows(SRC, text, &["index", "start_ns", "end_ns"], |c, index| {
        let start_ns: i64 = c.parse("start_ns")?;
        let end_ns = match c.raw("end_ns") {
            "" => None,
            _ => Some(c.parse::<i64>("end_ns")?),
        };
        if end_ns.is_some_and(|e| e < start_ns) {
            return Err(c.bad("end_ns", "ends before it starts"));
        }
        Ok(Span {
            index,
            start_ns,
            end_ns,
        })
    })
}

/// Whether `bytes` look like a JPEG: the SOI marker `FF D8 FF` first, EOI `FF D9` last.
pub(crate) fn check_jpeg(bytes: &[u8]) -> Result<(), Error> {
    if bytes.len() >= 5 && bytes.starts_with(&[0xFF, 0xD8, 0xFF]) && bytes.ends_with(&[0xFF, 0xD9])
    {
        Ok(())
    } else {
        Err(Error::InvalidContent(
            "image.jpg is not a JPEG (it must start with the SOI marker FF D8 FF and end with FF D9)"
                .into(),
        ))
    }
}

/// Where a session's evidence lives; every path from a server-made id and a checked index.
pub(crate) struct EvidenceFiles<'a> {
    pub blobs: &'a dyn BlobStore,
    pub id: &'a str,
}

impl EvidenceFiles<'_> {
    /// Whether sub-trajectory `k` has a stored thumbnail (`k` is a number, never a client
    /// string).
    pub fn has_thumbnail(&self, k: usize) -> bool {
        self.blobs.exists(self.id, SessionObject::Thumbnail(k))
    }

    /// Sub-trajectory `k`'s stored thumbnail bytes, `None` when there is none.
    pub fn read_thumbnail(&self, k: usize) -> Result<Option<Vec<u8>>, Error> {
        self.blobs.get(self.id, SessionObject::Thumbnail(k))
    }

    pub fn store_evidence(&self, rows: &[EvidenceRow]) -> Result<(), Error> {
        let json = serde_json::to_vec(rows).map_err(|e| Error::Internal(e.to_string()))?;
        self.blobs.put(self.id, SessionObject::Evidence, &json)
    }

    pub fn store_spans(&self, spans: &[Span]) -> Result<(), Error> {
        let json = serde_json::to_vec(spans).map_err(|e| Error::Internal(e.to_string()))?;
        self.blobs.put(self.id, SessionObject::Spans, &json)
    }

    pub fn store_thumbnail(&self, k: usize, jpeg: &[u8]) -> Result<(), Error> {
        self.blobs.put(self.id, SessionObject::Thumbnail(k), jpeg)
    }

    /// The stored evidence rows; `None` before the phone sent `evidence.csv`.
    pub fn evidence_rows(&self) -> Result<Option<Vec<EvidenceRow>>, Error> {
        self.read_json(SessionObject::Evidence)
    }

    /// The stored spans; `None` before the phone sent `subtrajectories.csv`.
    pub fn stored_spans(&self) -> Result<Option<Vec<Span>>, Error> {
        self.read_json(SessionObject::Spans)
    }

    fn read_json<T: serde::de::DeserializeOwned>(
        &self,
        object: SessionObject,
    ) -> Result<Option<T>, Error> {
        let Some(bytes) = self.blobs.get(self.id, object)? else {
            return Ok(None);
        };
        serde_json::from_slice(&bytes)
            .map(Some)
            .map_err(|e| Error::Internal(format!("{}: {e}", object.relative_path())))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(index: usize, image: bool, causes: &str) -> String {
        let img = if image {
            "1,120.5,30,400,12.5,0.01,160,120,"
        } else {
            "0,,,,,,,,"
        };
        format!("{index},{img}0.9,0.5,20,1,1.5,{causes}")
    }

    #[test]
    fn evidence_rows_parse_and_keep_their_values() {
        let text = format!(
            "{EVIDENCE_HEADER}\n{}\n{}\n",
            row(0, true, "low_texture no_depth"),
            row(1, false, "")
        );
        let rows = parse_evidence(&text).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].image.unwrap().mean_brightness, 120.5);
        assert_eq!(rows[0].thumbnail_size, Some((160, 120)));
        assert_eq!(rows[0].causes, ["low_texture", "no_depth"]);
        assert_eq!(rows[1].image, None);
        assert!(rows[1].causes.is_empty());
    }

    #[test]
    fn a_bad_cell_names_its_line_and_column() {
        let bad = row(1, true, "").replace("120.5", "bright");
        let text = format!("{EVIDENCE_HEADER}\n{}\n{bad}\n", row(0, false, ""));
        let e = parse_evidence(&text).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("mean_brightness"), "{e}");
        let text = format!("{EVIDENCE_HEADER}\n{}\n", row(0, false, "glass"));
        let e = parse_evidence(&text).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("causes"), "{e}");
        let text = format!("{EVIDENCE_HEADER}\n{}\n", row(3, false, ""));
        let e = parse_evidence(&text).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("index"), "{e}");
        let e = parse_evidence("index,image\n0,0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1"), "{e}");
    }

    #[test]
    fn spans_take_start_and_end() {
        let spans =
            parse_spans("index,start_ns,mid_ns,end_ns,x\n0,10,15,20,\n1,20,25,,\n").unwrap();
        assert_eq!(spans[1].start_ns, 20);
        assert_eq!(spans[0].end_ns, Some(20));
        assert_eq!(spans[1].end_ns, None);
        let e = parse_spans("index,start_ns,end_ns\n0,10,5\n").unwrap_err();
        assert!(e.to_string().contains("line 2, column `end_ns`"), "{e}");
    }

    #[test]
    fn jpeg_is_checked_by_its_markers() {
        assert!(check_jpeg(&[0xFF, 0xD8, 0xFF, 0xE0, 0, 0xFF, 0xD9]).is_ok());
        assert!(check_jpeg(b"GIF89a....").is_err());
        assert!(check_jpeg(&[0xFF, 0xD8, 0xFF]).is_err());
    }
}
