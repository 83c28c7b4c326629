//! evo's text matrices (TUM, KITTI, EuRoC files) read as evo reads them: every field a
//! Python float, errors naming the file, line and column. `read_matrix` parses every field
//! at once; `matrix_rows` reads the rows and parses fields when they are first used.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes};

use crate::SitarError;

/// A text matrix as evo's `csv_read_matrix` + `np.array(...).astype(float)` reads it: lines
/// starting with `comment` are skipped, every other line is split at each `delimiter`, every
/// field is a Python float. The first row decides the width (exactly `columns`, or at least
/// `columns` when `at_least`); every row must have it. Errors name the source, line and
/// column (1-based) of the first bad row and end with `rule`, evo's message for the format.
/// Rows are parsed in parallel blocks (rayon); an error is then looked for in order.
pub(crate) fn parse_matrix(
    text: &str,
    source: &str,
    delimiter: char,
    columns: usize,
    at_least: bool,
    rule: &str,
) -> Result<(Vec<f64>, usize, usize), String> {
    use rayon::prelude::*;

    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // The newline ending the last line starts no row (as Python's line iteration).
    let body = text.strip_suffix('\n').unwrap_or(text);
    let rows: Vec<(usize, &str)> = body
        .split('\n')
        .enumerate()
        .filter(|(_, line)| !line.starts_with('#'))
        .map(|(number, line)| (number + 1, line.strip_suffix('\r').unwrap_or(line)))
        .collect();
    let Some(&(first_line, first)) = rows.first().filter(|_| !body.is_empty()) else {
        return Err(format!("{source}: no rows; {rule}"));
    };
    let first_values = first_row(
        first, first_line, source, delimiter, columns, at_least, rule,
    )?;
    let width = first_values.len();
    // Every row's values straight into its place: one allocation, no copies of blocks.
    let mut values = vec![0.0; rows.len() * width];
    values[..width].copy_from_slice(&first_values);
    let block = |chunk: &[(usize, &str)], out: &mut [f64]| -> Result<(), String> {
        let mut row = Vec::with_capacity(width);
        for (&(number, line), place) in chunk.iter().zip(out.chunks_exact_mut(width)) {
            if fast_row(line.as_bytes(), delimiter, place) {
                continue;
            }
            row.clear();
            parse_row(line, number, source, delimiter, rule, &mut row)?;
            if row.len() != width {
                return Err(format!(
                    "{source}:{number}: {} entries where the first row has {width}; {rule}",
                    row.len()
                ));
            }
            place.copy_from_slice(&row);
        }
        Ok(())
    };
    // Small files in one block: threads cost more than they give there.
    const BLOCK: usize = 1024;
    let rest = &rows[1..];
    let out = &mut values[width..];
    if rest.len() < 16 * BLOCK {
        block(rest, out)?;
    } else {
        let parsed: Vec<Result<(), String>> = rest
            .par_chunks(BLOCK)
            .zip(out.par_chunks_mut(BLOCK * width))
            .map(|(chunk, out)| block(chunk, out))
            .collect();
        // The blocks are in order: the first error is the first bad row.
        parsed.into_iter().collect::<Result<(), String>>()?;
    }
    Ok((values, rows.len(), width))
}

/// Reads a row of plain decimal fields (a digit or a point after an optional sign), each
/// followed by one `delimiter` but the last, straight into `out` (exactly `out.len()` of
/// them) in one pass; false for anything else, which the general way ([`parse_row`]) then
/// reads, with its errors. A row read here reads the same there (its fields are what
/// `split` gives, and fast-float2 reads each whole field as [`python_float`] does).
pub(crate) fn fast_row(line: &[u8], delimiter: char, out: &mut [f64]) -> bool {
    let Ok(delimiter) = u8::try_from(delimiter) else {
        return false;
    };
    delimiter.is_ascii() && fast_fields(line, delimiter, out) == Some(line.len())
}

/// The first `out.len()` fields of `line` read as [`fast_row`] reads a row, each followed
/// by `delimiter` or the line's end: the bytes they take (the last one's delimiter not
/// counted), or None where a field is not a plain decimal as a whole.
pub(crate) fn fast_fields(line: &[u8], delimiter: u8, out: &mut [f64]) -> Option<usize> {
    let mut at = 0;
    for (i, place) in out.iter_mut().enumerate() {
        if i > 0 {
            at += 1; // the delimiter after the field before
        }
        let rest = line.get(at..)?;
        if !plain_start(rest) {
            return None;
        }
        let (value, used) = fast_float2::parse_partial::<f64, _>(rest).ok()?;
        if rest.get(used).is_some_and(|&b| b != delimiter) {
            return None;
        }
        *place = value;
        at += used;
    }
    Some(at)
}

/// Whether a field starts as a plain decimal does: a digit or a point, after an optional sign.
pub(crate) fn plain_start(field: &[u8]) -> bool {
    match field {
        [b'+' | b'-', b, ..] | [b, ..] => b.is_ascii_digit() || *b == b'.',
        [] => false,
    }
}

/// The first row's values: every field a number, and `columns` of them (at least, when
/// `at_least`); the first row decides the width of the rest.
pub(crate) fn first_row(
    line: &str,
    number: usize,
    source: &str,
    delimiter: char,
    columns: usize,
    at_least: bool,
    rule: &str,
) -> Result<Vec<f64>, String> {
    let mut values = Vec::new();
    parse_row(line, number, source, delimiter, rule, &mut values)?;
    let width = values.len();
    let fits = if at_least {
        width >= columns
    } else {
        width == columns
    };
    if !fits {
        return Err(format!(
            "{source}:{number}: {width} entries in the first row; {rule}"
        ));
    }
    Ok(values)
}

/// The fields of one row onto `out`; an error names the line and column of a bad field.
pub(crate) fn parse_row(
    line: &str,
    number: usize,
    source: &str,
    delimiter: char,
    rule: &str,
    out: &mut Vec<f64>,
) -> Result<(), String> {
    let mut offset = 0;
    for field in line.split(delimiter) {
        let Some(value) = python_float(field) else {
            let column = line[..offset].chars().count() + 1;
            return Err(format!(
                "{source}:{number}:{column}: '{field}' is not a number; {rule}"
            ));
        };
        out.push(value);
        offset += field.len() + delimiter.len_utf8();
    }
    Ok(())
}

/// A field as Python's `float()` reads it (surrounding whitespace, `nan`, `inf`, `1_000`).
pub(crate) fn python_float(field: &str) -> Option<f64> {
    let field = field.trim();
    // A plain decimal (a digit or a point after an optional sign): fast-float2, which
    // reads the same syntax to the same bits as Rust's and Python's parsers (correctly
    // rounded), about twice as fast as std's on 19-digit fields. Anything else (inf, nan,
    // underscores, errors) goes the general way.
    if plain_start(field.as_bytes())
        && let Ok(v) = fast_float2::parse::<f64, _>(field)
    {
        return Some(v);
    }
    if let Ok(v) = field.parse::<f64>() {
        return Some(v);
    }
    // Underscores between digits (PEP 515); anything else Rust refused is no float either.
    let bytes = field.as_bytes();
    let ok = field.contains('_')
        && bytes.iter().enumerate().all(|(i, &b)| {
            b != b'_'
                || (i > 0
                    && i + 1 < bytes.len()
                    && bytes[i - 1].is_ascii_digit()
                    && bytes[i + 1].is_ascii_digit())
        });
    if ok {
        field.replace('_', "").parse().ok()
    } else {
        None
    }
}

/// float64 values as a Python bytes object (numpy's `frombuffer` reads it), written in
/// place: one copy.
pub(crate) fn py_bytes<'py>(py: Python<'py>, values: &[f64]) -> PyResult<Bound<'py, PyBytes>> {
    PyBytes::new_with(py, 8 * values.len(), |out| write_floats(out, values))
}

/// float64 values as a Python bytearray: as [`py_bytes`], but numpy's `frombuffer` gives a
/// writable array (a trajectory's own stamps).
pub(crate) fn py_bytearray<'py>(
    py: Python<'py>,
    values: &[f64],
) -> PyResult<Bound<'py, PyByteArray>> {
    PyByteArray::new_with(py, 8 * values.len(), |out| write_floats(out, values))
}

fn write_floats(out: &mut [u8], values: &[f64]) -> PyResult<()> {
    for (place, value) in out.chunks_exact_mut(8).zip(values) {
        place.copy_from_slice(&value.to_ne_bytes());
    }
    Ok(())
}

/// A matrix file (evo's rules, see `parse_matrix`): the float64 bytes, rows and columns.
/// The file is read as UTF-8 (a BOM skipped): other bytes are a SitarError naming the line;
/// reading errors become OSError.
#[pyfunction]
#[pyo3(signature = (path, delimiter, columns, at_least, rule))]
pub fn read_matrix(
    py: Python<'_>,
    path: PathBuf,
    delimiter: char,
    columns: usize,
    at_least: bool,
    rule: &str,
) -> PyResult<(Py<PyBytes>, usize, usize)> {
    let source = path.display().to_string();
    let (values, rows, width) = py.allow_threads(|| {
        let bytes = std::fs::read(&path)
            .map_err(|e| PyErr::from(std::io::Error::new(e.kind(), format!("{source}: {e}"))))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
            SitarError::new_err(format!("{source}:{line}: not UTF-8 text"))
        })?;
        parse_matrix(&text, &source, delimiter, columns, at_least, rule)
            .map_err(SitarError::new_err)
    })?;
    Ok((py_bytes(py, &values)?.unbind(), rows, width))
}

/// As `read_matrix`, on text already read (a file handle's content); `source` names it.
#[pyfunction]
#[pyo3(signature = (text, source, delimiter, columns, at_least, rule))]
pub fn parse_matrix_text(
    py: Python<'_>,
    text: &str,
    source: &str,
    delimiter: char,
    columns: usize,
    at_least: bool,
    rule: &str,
) -> PyResult<(Py<PyBytes>, usize, usize)> {
    let (values, rows, width) = parse_matrix(text, source, delimiter, columns, at_least, rule)
        .map_err(SitarError::new_err)?;
    Ok((py_bytes(py, &values)?.unbind(), rows, width))
}

#[cfg(test)]
mod tests {
    use super::*;

    const RULE: &str = "TUM rule";

    #[test]
    fn matrices_read_as_evo_reads_them() {
        let (v, rows, cols) = parse_matrix("# c\n1 2\n3 4.5\n", "f", ' ', 2, false, RULE).unwrap();
        assert_eq!((v, rows, cols), (vec![1.0, 2.0, 3.0, 4.5], 2, 2));
        let (v, ..) = parse_matrix("\u{feff}1,2,3\r\n", "f", ',', 2, true, RULE).unwrap();
        assert_eq!(v, [1.0, 2.0, 3.0]);
        assert_eq!(python_float(" 1_000.5 "), Some(1000.5));
        assert_eq!(python_float("1__0"), None);
    }

    #[test]
    fn bad_matrices_name_the_line_and_column() {
        let e = parse_matrix("1 2\n3 x\n", "f.txt", ' ', 2, false, RULE).unwrap_err();
        assert!(e.starts_with("f.txt:2:3: 'x'"), "{e}");
        let e = parse_matrix("1 2 \n", "f.txt", ' ', 2, false, RULE).unwrap_err();
        assert!(e.contains("f.txt:1:"), "{e}");
        let e = parse_matrix("1 2\n1 2 3\n", "f.txt", ' ', 2, false, RULE).unwrap_err();
        assert!(e.contains("f.txt:2: 3 entries"), "{e}");
        let e = parse_matrix("# only\n", "f.txt", ' ', 2, false, RULE).unwrap_err();
        assert!(e.contains("no rows") && e.ends_with(RULE), "{e}");
    }
}
