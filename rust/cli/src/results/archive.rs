//! evo's result archive (`--save_results FILE.zip`): `info.json`, `stats.json` and one
//! NumPy `.npy` file per array, stored uncompressed as evo's `save_res_file` writes them, so
//! that `evo_res` reads sitar's archives and `sitar res` reads evo's.
//!
//! Reading is bounded: at most [`MAX_ENTRIES`] entries, each at most [`MAX_ENTRY_BYTES`]
//! once inflated; anything else in an archive is an error that names the archive and entry.

use std::io::{Read, Write};
use std::path::Path;

use anyhow::{Context, Result, bail};
use sitar_evo::metric::{Metric, Outcome};

/// Most entries `sitar res` reads from one archive.
pub const MAX_ENTRIES: usize = 64;
/// Most bytes one entry may inflate to (256 MiB: 33 million float64 values).
pub const MAX_ENTRY_BYTES: u64 = 256 << 20;

/// A float64 array and its shape (C order), as `.npy` holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct Array {
    /// The values, row by row.
    pub data: Vec<f64>,
    /// The shape: `[n]` or `[rows, columns]`.
    pub shape: Vec<usize>,
}

impl Array {
    /// A 1-D array.
    pub fn vector(data: Vec<f64>) -> Self {
        let n = data.len();
        Self {
            data,
            shape: vec![n],
        }
    }

    /// A 2-D array of `rows × columns` values given row by row.
    pub fn matrix(data: Vec<f64>, rows: usize, columns: usize) -> Self {
        Self {
            data,
            shape: vec![rows, columns],
        }
    }
}

/// evo's `Result`: info strings, statistics and arrays, each in evo's order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ResultArchive {
    /// `info.json`: title, ref_name, est_name, label (values as written).
    pub info: Vec<(String, String)>,
    /// `stats.json`: rmse, mean, median, std, min, max, sse.
    pub stats: Vec<(String, f64)>,
    /// The `.npy` arrays: error_array, timestamps, … .
    pub arrays: Vec<(String, Array)>,
}

impl ResultArchive {
    /// The result as evo's archive: info, stats, the arrays evo writes.
    pub fn of(outcome: &Outcome) -> ResultArchive {
        let info = vec![
            ("title".to_owned(), outcome.title.clone()),
            ("ref_name".to_owned(), outcome.ref_name.clone()),
            ("est_name".to_owned(), outcome.est_name.clone()),
            ("label".to_owned(), outcome.label()),
        ];
        let stats = outcome
            .stats_list()
            .iter()
            .map(|&(k, v)| (k.to_owned(), v))
            .collect();
        let mut arrays = vec![(
            "error_array".to_owned(),
            Array::vector(outcome.errors.errors.clone()),
        )];
        if outcome.timed {
            let ids = outcome.result_ids();
            let (reference, estimate) = (
                outcome.reference.reduce_to_ids(&ids),
                outcome.estimate.reduce_to_ids(&ids),
            );
            // RPE drops the first pose again: it only anchors the distances.
            let skip = usize::from(matches!(outcome.metric, Metric::Rpe(_)));
            // Seconds as evo holds them (floats), differences taken in floats as evo does.
            let stamps = estimate.seconds();
            let from_start: Vec<f64> = stamps.iter().map(|&t| t - stamps[0]).collect();
            arrays.push((
                "seconds_from_start".into(),
                Array::vector(from_start[skip..].to_vec()),
            ));
            arrays.push(("timestamps".into(), Array::vector(stamps[skip..].to_vec())));
            arrays.push((
                "distances_from_start".into(),
                Array::vector(reference.distances()[skip..].to_vec()),
            ));
            arrays.push((
                "distances".into(),
                Array::vector(estimate.distances()[skip..].to_vec()),
            ));
        }
        if let Some(m) = outcome.alignment_matrix {
            arrays.push((
                "alignment_transformation_sim3".into(),
                Array::matrix(m.iter().flatten().copied().collect(), 4, 4),
            ));
        }
        ResultArchive {
            info,
            stats,
            arrays,
        }
    }

    /// An info value.
    pub fn info(&self, key: &str) -> Option<&str> {
        self.info
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// An array.
    pub fn array(&self, key: &str) -> Option<&Array> {
        self.arrays.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// Writes the archive (created or replaced); errors name the file.
    pub fn write(&self, path: &Path) -> Result<()> {
        let file = std::fs::File::create(path)
            .with_context(|| format!("{}: cannot create the result archive", path.display()))?;
        let mut zip = zip::ZipWriter::new(file);
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        let mut entry = |name: &str, bytes: &[u8]| -> Result<()> {
            zip.start_file(name, options)
                .and_then(|()| zip.write_all(bytes).map_err(Into::into))
                .with_context(|| format!("{}: cannot write {name}", path.display()))
        };
        entry(
            "info.json",
            python_json_object(self.info.iter().map(|(k, v)| (k, json_string(v)))).as_bytes(),
        )?;
        entry(
            "stats.json",
            python_json_object(self.stats.iter().map(|(k, v)| (k, json_float(*v)))).as_bytes(),
        )?;
        for (name, array) in &self.arrays {
            entry(&format!("{name}.npy"), &npy_bytes(array))?;
        }
        zip.finish()
            .with_context(|| format!("{}: cannot finish the result archive", path.display()))?;
        Ok(())
    }

    /// Reads an archive written by evo or sitar; errors name the file and the entry.
    pub fn read(path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let file = std::fs::File::open(path).with_context(|| format!("{name}: cannot open"))?;
        let mut zip =
            zip::ZipArchive::new(file).with_context(|| format!("{name}: not a zip archive"))?;
        if zip.len() > MAX_ENTRIES {
            bail!(
                "{name}: {} entries, more than the {MAX_ENTRIES} of a result archive",
                zip.len()
            );
        }
        let names: Vec<String> = zip.file_names().map(str::to_owned).collect();
        if !names.iter().any(|n| n == "info.json") || !names.iter().any(|n| n == "stats.json") {
            bail!("{name} is not a valid result file (no info.json and stats.json)");
        }
        let mut read_entry = |entry: &str| -> Result<Vec<u8>> {
            let file = zip
                .by_name(entry)
                .with_context(|| format!("{name}: cannot read {entry}"))?;
            let mut bytes = Vec::new();
            file.take(MAX_ENTRY_BYTES + 1)
                .read_to_end(&mut bytes)
                .with_context(|| format!("{name}: cannot read {entry}"))?;
            if bytes.len() as u64 > MAX_ENTRY_BYTES {
                bail!("{name}: {entry} is larger than {MAX_ENTRY_BYTES} bytes");
            }
            Ok(bytes)
        };
        let info_text = read_entry("info.json")?;
        let info = ordered_json(&info_text)
            .with_context(|| format!("{name}: info.json"))?
            .into_iter()
            .map(|(k, v)| {
                let text = match v {
                    serde_json::Value::String(s) => s,
                    other => other.to_string(),
                };
                (k, text)
            })
            .collect();
        let stats_text = read_entry("stats.json")?;
        let stats = ordered_json(&stats_text)
            .with_context(|| format!("{name}: stats.json"))?
            .into_iter()
            .map(|(k, v)| match v.as_f64() {
                Some(x) => Ok((k, x)),
                None if v.is_null() => Ok((k, f64::NAN)),
                None => bail!("{name}: stats.json: {k} is not a number"),
            })
            .collect::<Result<Vec<_>>>()?;
        let mut arrays = Vec::new();
        for entry in names
            .iter()
            .filter(|n| n.ends_with(".npy") || n.ends_with(".npz"))
        {
            let bytes = read_entry(entry)?;
            let array = parse_npy(&bytes).with_context(|| format!("{name}: {entry}"))?;
            let stem = Path::new(entry)
                .file_stem()
                .map_or_else(|| entry.clone(), |s| s.to_string_lossy().into_owned());
            arrays.push((stem, array));
        }
        Ok(Self {
            info,
            stats,
            arrays,
        })
    }
}

/// A JSON object with Python's `json.dumps` separators (`, ` and `: `).
fn python_json_object<'a>(entries: impl Iterator<Item = (&'a String, String)>) -> String {
    let parts: Vec<String> = entries
        .map(|(k, v)| format!("{}: {v}", json_string(k)))
        .collect();
    format!("{{{}}}", parts.join(", "))
}

fn json_string(s: &str) -> String {
    serde_json::Value::String(s.to_owned()).to_string()
}

/// A float as Python's json writes it (`NaN` and `Infinity` included, which it reads back).
fn json_float(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v.is_infinite() {
        if v > 0.0 { "Infinity" } else { "-Infinity" }.into()
    } else {
        sitar_evo::pyfmt::repr(v)
    }
}

/// A JSON object's entries in the order written (evo's stats order matters to `res`).
fn ordered_json(bytes: &[u8]) -> Result<Vec<(String, serde_json::Value)>> {
    struct Ordered(Vec<(String, serde_json::Value)>);
    impl<'de> serde::Deserialize<'de> for Ordered {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct Visitor;
            impl<'de> serde::de::Visitor<'de> for Visitor {
                type Value = Ordered;
                fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                    f.write_str("a JSON object")
                }
                fn visit_map<A: serde::de::MapAccess<'de>>(
                    self,
                    mut map: A,
                ) -> Result<Ordered, A::Error> {
                    let mut entries = Vec::new();
                    while let Some(entry) = map.next_entry()? {
                        entries.push(entry);
                    }
                    Ok(Ordered(entries))
                }
            }
            d.deserialize_map(Visitor)
        }
    }
    // Python writes NaN/Infinity, which JSON proper has not: read them as null.
    let text = String::from_utf8_lossy(bytes)
        .replace("-Infinity", "null")
        .replace("Infinity", "null")
        .replace("NaN", "null");
    Ok(serde_json::from_str::<Ordered>(&text)?.0)
}

/// `np.save` of a float64 array: format 1.0, header padded to 64 bytes.
pub fn npy_bytes(array: &Array) -> Vec<u8> {
    let shape = match array.shape.as_slice() {
        [n] => format!("({n},)"),
        dims => format!(
            "({})",
            dims.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + 8 * array.data.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in &array.data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Reads a `.npy` of little-endian floats or integers (1-D or 2-D, C order) as float64.
pub fn parse_npy(bytes: &[u8]) -> Result<Array> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        bail!("not a .npy array");
    }
    let (header_len, start) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => bail!(".npy format version {v} is not supported"),
    };
    let header = bytes
        .get(start..start + header_len)
        .and_then(|h| std::str::from_utf8(h).ok())
        .context("truncated .npy header")?;
    let field = |key: &str| -> Option<&str> {
        let k = header.find(&format!("'{key}'"))?;
        Some(header[k + key.len() + 2..].trim_start_matches([':', ' ']))
    };
    let descr = field("descr")
        .and_then(|d| d.strip_prefix('\''))
        .and_then(|d| d.split('\'').next());
    let descr = descr.context(".npy header without descr")?;
    if field("fortran_order").is_some_and(|f| f.starts_with("True")) {
        bail!("Fortran-ordered arrays are not supported");
    }
    let shape_text = field("shape")
        .and_then(|s| s.strip_prefix('('))
        .and_then(|s| s.split(')').next())
        .context(".npy header without shape")?;
    let shape: Vec<usize> = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().context("bad .npy shape"))
        .collect::<Result<_>>()?;
    let count: usize = shape.iter().product();
    let body = &bytes[start + header_len..];
    let (size, read): (usize, fn(&[u8]) -> f64) = match descr {
        "<f8" => (8, |b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))),
        "<f4" => (4, |b| {
            f64::from(f32::from_le_bytes(b.try_into().unwrap_or([0; 4])))
        }),
        "<i8" => (8, |b| {
            i64::from_le_bytes(b.try_into().unwrap_or([0; 8])) as f64
        }),
        "<i4" => (4, |b| {
            f64::from(i32::from_le_bytes(b.try_into().unwrap_or([0; 4])))
        }),
        other => bail!(".npy dtype {other} is not supported (float64 expected)"),
    };
    if body.len() < count * size {
        bail!(
            ".npy data truncated: {} bytes for {count} values",
            body.len()
        );
    }
    let data = body[..count * size].chunks_exact(size).map(read).collect();
    Ok(Array { data, shape })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_round_trips_and_is_aligned() {
        for array in [
            Array::vector(vec![1.5, -2.0, 1e-300]),
            Array::vector(vec![]),
            Array::matrix((0..16).map(f64::from).collect(), 4, 4),
        ] {
            let bytes = npy_bytes(&array);
            let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
            assert_eq!((10 + header_len) % 64, 0);
            assert_eq!(parse_npy(&bytes).unwrap(), array);
        }
        assert!(parse_npy(b"garbage").is_err());
        let mut truncated = npy_bytes(&Array::vector(vec![1.0, 2.0]));
        truncated.truncate(truncated.len() - 3);
        assert!(parse_npy(&truncated).is_err());
    }

    #[test]
    fn archive_round_trips_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.zip");
        let archive = ResultArchive {
            info: vec![("title".into(), "APE w.r.t. x (m)\n(not aligned)".into())],
            stats: vec![
                ("rmse".into(), 0.5),
                ("mean".into(), 0.25),
                ("max".into(), 1.0),
            ],
            arrays: vec![("error_array".into(), Array::vector(vec![0.25, 1.0]))],
        };
        archive.write(&path).unwrap();
        assert_eq!(ResultArchive::read(&path).unwrap(), archive);
        std::fs::write(&path, b"not a zip").unwrap();
        assert!(
            ResultArchive::read(&path)
                .unwrap_err()
                .to_string()
                .contains("not a zip")
        );
    }
}
