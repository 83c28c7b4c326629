//! A matrix file's rows read and checked, their pose fields parsed when first used: the
//! TUM and EuRoC readers of `sitar.evo`. A script that associates a 200 Hz ground truth with
//! a 20 Hz estimate needs the stamps of every row but the poses of one row in ten; parsing
//! only those is most of the reading saved (MH_04's ground truth: 158,000 fields, 10,000
//! used by the script).
//!
//! Checked when the file is read, as evo checks it then: UTF-8, every row's field count, and
//! the first column (the stamps) parsed. The other fields are checked for their characters
//! only (digits, sign, point, exponent) in one pass the compiler vectorises; a row with any
//! other character (whitespace, `nan`, `inf`, `1_000`, text) or an empty first or last field
//! is parsed whole at once, with evo's error. A field of number characters that is still no
//! number (`1.2.3`, `1e`, an empty field between two delimiters) is reported, with the same
//! message, when its row's poses are first used.
//!
//! Large texts are read in pieces cut at newlines, on all cores: first each piece's UTF-8
//! and newlines (so that every piece knows its first line number), then its rows.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyByteArray;
use rayon::prelude::*;

use crate::SitarError;
use crate::matrix::{fast_fields, first_row, parse_row, py_bytearray, python_float};

/// Bytes per piece of the parallel passes over a text; a smaller text is one piece (threads
/// cost more than they give there).
const PIECE: usize = 256 * 1024;
/// Rows per block when parsing the fields asked for, in parallel from four blocks on (fewer
/// rows parse in less time than it takes to wake the pool's threads: fr1_desk's 572 kept
/// rows, 0.17 ms for two trajectories in one thread, 0.34 ms in two).
const VALUE_BLOCK: usize = 256;

/// One data row: its bytes in the text, its 1-based line, and where its values are when it
/// was parsed whole on reading ([`NOT_PARSED`] otherwise). u32: texts over 4 GiB are refused.
#[derive(Clone, Copy)]
struct Row {
    start: u32,
    end: u32,
    line: u32,
    parsed: u32,
}

const NOT_PARSED: u32 = u32::MAX;

/// A matrix file read by evo's rules (see `matrix::parse_matrix`), its fields kept as text.
#[pyclass(frozen, module = "sitar._sitar")]
pub struct MatrixRows {
    /// The file's bytes, checked to be UTF-8.
    text: Vec<u8>,
    source: String,
    delimiter: u8,
    rule: String,
    width: usize,
    rows: Vec<Row>,
    /// The values of the rows parsed whole on reading, `width` each.
    parsed: Vec<f64>,
}

/// A row checked on reading: plain, with its first value, or parsed whole.
enum Checked {
    Plain(f64),
    Whole(Vec<f64>),
}

/// What reading gives for one piece: its line count, its rows, their stamps, and the values
/// of the rows it parsed whole (by index in the piece's rows).
struct PieceRows {
    lines: usize,
    rows: Vec<Row>,
    stamps: Vec<f64>,
    whole: Vec<(usize, Vec<f64>)>,
}

/// The delimiter as a byte: one ASCII character that cannot be part of a number.
fn delimiter_byte(delimiter: char, source: &str) -> Result<u8, String> {
    u8::try_from(delimiter)
        .ok()
        .filter(|d| d.is_ascii() && !d.is_ascii_alphanumeric() && ![b'.', b'+', b'-'].contains(d))
        .ok_or_else(|| {
            format!("{source}: the delimiter {delimiter:?} is not one ASCII punctuation or space")
        })
}

/// `[begin, end)` cut into pieces of about [`PIECE`] bytes at newlines; the newline at a
/// cut belongs to no piece.
fn pieces(text: &[u8], begin: usize, end: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::with_capacity((end - begin) / PIECE + 1);
    let mut start = begin;
    while end - start > PIECE {
        let Some(newline) = memchr::memchr(b'\n', &text[start + PIECE..end]) else {
            break;
        };
        let cut = start + PIECE + newline;
        out.push((start, cut));
        start = cut + 1;
    }
    out.push((start, end));
    out
}

/// Runs `work` on every piece, on all cores when there are several.
fn each_piece<T: Send>(
    pieces: &[(usize, usize)],
    work: impl Fn((usize, usize)) -> T + Sync + Send,
) -> Vec<T> {
    if pieces.len() == 1 {
        vec![work(pieces[0])]
    } else {
        pieces.par_iter().map(|&piece| work(piece)).collect()
    }
}

impl MatrixRows {
    /// Reads `text` (a BOM skipped) and the first column of every row, checking every row.
    fn read(
        text: Vec<u8>,
        source: &str,
        delimiter: char,
        columns: usize,
        at_least: bool,
        rule: &str,
    ) -> Result<(Self, Vec<f64>), String> {
        let delimiter = delimiter_byte(delimiter, source)?;
        if u32::try_from(text.len()).is_err() {
            return Err(format!("{source}: over 4 GiB; split the file"));
        }
        let begin = if text.starts_with(b"\xEF\xBB\xBF") {
            3
        } else {
            0
        };
        // The newline ending the last line starts no row (as Python's line iteration).
        let end = if text.len() > begin && text.ends_with(b"\n") {
            text.len() - 1
        } else {
            text.len()
        };
        let pieces = pieces(&text, begin, end);
        let mut matrix = MatrixRows {
            text: Vec::new(),
            source: source.to_owned(),
            delimiter,
            rule: rule.to_owned(),
            width: 0,
            rows: Vec::new(),
            parsed: Vec::new(),
        };
        matrix.width = matrix.first_width(&text, begin, end, columns, at_least)?;
        // Every piece's rows, checked, with their stamps, their lines counted from the
        // piece's first; then numbered from the text's.
        let read = each_piece(&pieces, |piece| matrix.piece_rows(&text, piece, 1));
        let mut stamps = Vec::with_capacity(read.iter().flatten().map(|p| p.rows.len()).sum());
        let mut lines_before = 0;
        // In order: the first error is the first bad row.
        for (piece, read) in pieces.iter().zip(read) {
            let Ok(mut read) = read else {
                // Read again from its true first line, for the error's line number.
                return Err(matrix
                    .piece_rows(&text, *piece, lines_before + 1)
                    .err()
                    .unwrap_or_else(|| format!("{source}: unreadable; {rule}")));
            };
            for (index, values) in read.whole {
                read.rows[index].parsed = (matrix.parsed.len() / matrix.width) as u32;
                matrix.parsed.extend(values);
            }
            for row in &mut read.rows {
                row.line += lines_before as u32;
            }
            lines_before += read.lines;
            matrix.rows.extend(read.rows);
            stamps.extend(read.stamps);
        }
        matrix.text = text;
        Ok((matrix, stamps))
    }

    /// The width of the first row (parsed whole), checked against `columns`.
    fn first_width(
        &self,
        text: &[u8],
        begin: usize,
        end: usize,
        columns: usize,
        at_least: bool,
    ) -> Result<usize, String> {
        let (source, rule) = (&self.source, &self.rule);
        // The first row: the first line not a comment (the text is checked later).
        let mut first = None;
        let mut at = begin;
        for (number, line) in text[begin..end].split(|&b| b == b'\n').enumerate() {
            if !line.starts_with(b"#") {
                let line = line.strip_suffix(b"\r").unwrap_or(line);
                first = Some((at, at + line.len(), number + 1));
                break;
            }
            at += line.len() + 1;
        }
        let first = first.filter(|_| begin < end);
        let Some((start, stop, line)) = first else {
            return Err(format!("{source}: no rows; {rule}"));
        };
        let values = first_row(
            self.row_text(text, start, stop, line)?,
            line,
            source,
            char::from(self.delimiter),
            columns,
            at_least,
            rule,
        )?;
        Ok(values.len())
    }

    /// One piece's rows, each checked, with its stamp.
    fn piece_rows(
        &self,
        text: &[u8],
        piece: (usize, usize),
        first_line: usize,
    ) -> Result<PieceRows, String> {
        let (begin, end) = piece;
        let mut out = PieceRows {
            lines: 0,
            rows: Vec::with_capacity((end - begin) / 32 + 1),
            stamps: Vec::with_capacity((end - begin) / 32 + 1),
            whole: Vec::new(),
        };
        let newlines = memchr::memchr_iter(b'\n', &text[begin..end]).map(|at| begin + at);
        let mut start = begin;
        for (number, stop) in newlines.chain(std::iter::once(end)).enumerate() {
            let line = &text[start..stop];
            let row_start = start;
            start = stop + 1;
            out.lines = number + 1;
            if line.starts_with(b"#") {
                // Checked as text (evo decodes the whole file); rows are checked in
                // check_row (a plain row is ASCII).
                self.row_text(text, row_start, stop, first_line + number)?;
                continue;
            }
            let line = line.strip_suffix(b"\r").unwrap_or(line);
            let row = Row {
                start: row_start as u32,
                end: (row_start + line.len()) as u32,
                line: (first_line + number) as u32,
                parsed: NOT_PARSED,
            };
            match self.check_row(text, &row)? {
                Checked::Plain(stamp) => out.stamps.push(stamp),
                Checked::Whole(values) => {
                    out.stamps.push(values[0]);
                    out.whole.push((out.rows.len(), values));
                }
            }
            out.rows.push(row);
        }
        Ok(out)
    }

    /// A row's text (checked UTF-8 on reading: never an error then).
    fn row_text<'t>(
        &self,
        text: &'t [u8],
        start: usize,
        end: usize,
        line: usize,
    ) -> Result<&'t str, String> {
        std::str::from_utf8(&text[start..end])
            .map_err(|_| format!("{}:{line}: not UTF-8 text", self.source))
    }

    /// Checks one row: plain (the right field count, number characters only, a first field
    /// that parses) with its first value, else its values parsed whole, or evo's error.
    fn check_row(&self, text: &[u8], row: &Row) -> Result<Checked, String> {
        let line = &text[row.start as usize..row.end as usize];
        let (delimiters, plain) = scan(line, self.delimiter);
        let edges = line.first() == Some(&self.delimiter) || line.last() == Some(&self.delimiter);
        if plain && !edges && delimiters + 1 == self.width {
            let mut first = [0.0];
            if fast_fields(line, self.delimiter, &mut first).is_some() {
                return Ok(Checked::Plain(first[0]));
            }
        }
        let mut values = Vec::with_capacity(self.width);
        parse_row(
            self.row_text(
                text,
                row.start as usize,
                row.end as usize,
                row.line as usize,
            )?,
            row.line as usize,
            &self.source,
            char::from(self.delimiter),
            &self.rule,
            &mut values,
        )?;
        if values.len() != self.width {
            return Err(format!(
                "{}:{}: {} entries where the first row has {}; {}",
                self.source,
                row.line,
                values.len(),
                self.width,
                self.rule
            ));
        }
        Ok(Checked::Whole(values))
    }

    /// The fields `columns` of one row into `out` (`fields`: scratch for the row's values);
    /// evo's error for a bad field.
    fn row_values(
        &self,
        row: &Row,
        columns: &[usize],
        fields: &mut Vec<f64>,
        out: &mut [f64],
    ) -> Result<(), String> {
        if row.parsed != NOT_PARSED {
            let values = &self.parsed[row.parsed as usize * self.width..][..self.width];
            for (place, &column) in out.iter_mut().zip(columns) {
                *place = values[column];
            }
            return Ok(());
        }
        // A plain row (checked on reading): its fields read left to right up to the last
        // column asked for, each a number followed by the delimiter (or the row's end).
        let line = &self.text[row.start as usize..row.end as usize];
        let last = columns.iter().max().map_or(0, |&c| c + 1);
        fields.resize(last, 0.0);
        if fast_fields(line, self.delimiter, fields).is_none() {
            // Not a number as a whole: evo's message (Python's rules may still read it).
            return self.row_values_slowly(row, columns, out);
        }
        for (place, &column) in out.iter_mut().zip(columns) {
            *place = fields[column];
        }
        Ok(())
    }

    /// `row_values` by Python's rules, field by field: evo's error for a bad one.
    fn row_values_slowly(
        &self,
        row: &Row,
        columns: &[usize],
        out: &mut [f64],
    ) -> Result<(), String> {
        let line = &self.text[row.start as usize..row.end as usize];
        let fields: Vec<&[u8]> = line.split(|&b| b == self.delimiter).collect();
        for (place, &column) in out.iter_mut().zip(columns) {
            let value = std::str::from_utf8(fields[column])
                .ok()
                .and_then(python_float);
            match value {
                Some(value) => *place = value,
                None => return Err(self.row_error(row)),
            }
        }
        Ok(())
    }

    /// evo's error for a row with a field of number characters that is no number.
    fn row_error(&self, row: &Row) -> String {
        let (start, end, line) = (row.start as usize, row.end as usize, row.line as usize);
        let text = match self.row_text(&self.text, start, end, line) {
            Ok(text) => text,
            Err(error) => return error,
        };
        let mut values = Vec::new();
        match parse_row(
            text,
            row.line as usize,
            &self.source,
            char::from(self.delimiter),
            &self.rule,
            &mut values,
        ) {
            Err(error) => error,
            // Not reached: a field fast-float2 and Python's rules both refuse fails here.
            Ok(()) => format!(
                "{}:{}: unreadable row; {}",
                self.source, row.line, self.rule
            ),
        }
    }

    /// The values of `columns` for the rows `ids` (every row when None), row after row.
    fn values_of(&self, ids: Option<&[usize]>, columns: &[usize]) -> Result<Vec<f64>, String> {
        let k = columns.len();
        let n = ids.map_or(self.rows.len(), <[usize]>::len);
        let mut out = vec![0.0; n * k];
        if k == 0 {
            return Ok(out);
        }
        let block = |first: usize, out: &mut [f64]| -> Result<(), String> {
            let mut fields = Vec::with_capacity(self.width);
            for (i, place) in out.chunks_exact_mut(k).enumerate() {
                let index = ids.map_or(first + i, |ids| ids[first + i]);
                self.row_values(&self.rows[index], columns, &mut fields, place)?;
            }
            Ok(())
        };
        if n < 4 * VALUE_BLOCK {
            block(0, &mut out)?;
        } else {
            let parsed: Vec<Result<(), String>> = out
                .par_chunks_mut(VALUE_BLOCK * k)
                .enumerate()
                .map(|(b, out)| block(b * VALUE_BLOCK, out))
                .collect();
            parsed.into_iter().collect::<Result<(), String>>()?;
        }
        Ok(out)
    }
}

#[pymethods]
impl MatrixRows {
    fn __len__(&self) -> usize {
        self.rows.len()
    }

    /// The fields per row (the first row's count; every row has it).
    #[getter]
    fn width(&self) -> usize {
        self.width
    }

    /// The values of `columns` (0-based field indices) of the rows `ids` (int64 bytes,
    /// numpy's `tobytes`; None: every row), row after row, as a bytearray of float64 (numpy's
    /// `frombuffer` gives a writable array). A bad field raises SitarError with evo's message.
    #[pyo3(signature = (ids, columns))]
    fn values<'py>(
        &self,
        py: Python<'py>,
        ids: Option<&[u8]>,
        columns: Vec<usize>,
    ) -> PyResult<Bound<'py, PyByteArray>> {
        if let Some(&bad) = columns.iter().find(|&&c| c >= self.width) {
            return Err(PyValueError::new_err(format!(
                "{}: column {bad} of rows of {} fields",
                self.source, self.width
            )));
        }
        let ids = match ids {
            None => None,
            Some(bytes) => Some(row_ids(bytes, self.rows.len())?),
        };
        let values = py
            .allow_threads(|| self.values_of(ids.as_deref(), &columns))
            .map_err(SitarError::new_err)?;
        py_bytearray(py, &values)
    }

    /// The rows are never changed: a copy is this object.
    fn __copy__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __deepcopy__(slf: Py<Self>, _memo: &Bound<'_, PyAny>) -> Py<Self> {
        slf
    }
}

/// Row indices from int64 bytes, each checked against `rows`.
fn row_ids(bytes: &[u8], rows: usize) -> PyResult<Vec<usize>> {
    if !bytes.len().is_multiple_of(8) {
        return Err(PyValueError::new_err(format!(
            "{} bytes are not int64 row indices",
            bytes.len()
        )));
    }
    bytes
        .chunks_exact(8)
        .map(|c| {
            let id = i64::from_ne_bytes(c.try_into().expect("8 bytes"));
            usize::try_from(id)
                .ok()
                .filter(|&id| id < rows)
                .ok_or_else(|| PyValueError::new_err(format!("row {id} of {rows} rows")))
        })
        .collect()
}

/// The delimiters in `line` and whether every byte is a delimiter or a number's character
/// (digit, sign, point, exponent): one branch-free pass the compiler vectorises. Counted in
/// u8 per block of 128 bytes (no overflow), so that a vector holds 16 bytes, not 2 counts.
fn scan(line: &[u8], delimiter: u8) -> (usize, bool) {
    let mut delimiters = 0usize;
    let mut other = 0u8;
    for block in line.chunks(128) {
        let mut count = 0u8;
        for &b in block {
            let is_delimiter = b == delimiter;
            count += u8::from(is_delimiter);
            let number = (b.wrapping_sub(b'0') < 10)
                | (b == b'.')
                | (b == b'-')
                | (b == b'+')
                | ((b | 0x20) == b'e');
            other |= u8::from(!(number | is_delimiter));
        }
        delimiters += usize::from(count);
    }
    (delimiters, other == 0)
}

/// A matrix file's rows (evo's rules; see the module): the rows object and the first column
/// (float64 bytearray). The file is read as UTF-8 (a BOM skipped); reading errors are OSError.
#[pyfunction]
#[pyo3(signature = (path, delimiter, columns, at_least, rule))]
pub fn read_matrix_rows<'py>(
    py: Python<'py>,
    path: PathBuf,
    delimiter: char,
    columns: usize,
    at_least: bool,
    rule: &str,
) -> PyResult<(MatrixRows, Bound<'py, PyByteArray>)> {
    let source = path.display().to_string();
    let (rows, stamps) = py.allow_threads(|| {
        let text = std::fs::read(&path)
            .map_err(|e| PyErr::from(std::io::Error::new(e.kind(), format!("{source}: {e}"))))?;
        MatrixRows::read(text, &source, delimiter, columns, at_least, rule)
            .map_err(SitarError::new_err)
    })?;
    Ok((rows, py_bytearray(py, &stamps)?))
}

/// As `read_matrix_rows`, on text already read (a file handle's content); `source` names it.
#[pyfunction]
#[pyo3(signature = (text, source, delimiter, columns, at_least, rule))]
pub fn matrix_rows_of_text<'py>(
    py: Python<'py>,
    text: String,
    source: &str,
    delimiter: char,
    columns: usize,
    at_least: bool,
    rule: &str,
) -> PyResult<(MatrixRows, Bound<'py, PyByteArray>)> {
    let (rows, stamps) = MatrixRows::read(
        text.into_bytes(),
        source,
        delimiter,
        columns,
        at_least,
        rule,
    )
    .map_err(SitarError::new_err)?;
    Ok((rows, py_bytearray(py, &stamps)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    const RULE: &str = "TUM rule";

    fn read(text: &str, columns: usize, at_least: bool) -> Result<(MatrixRows, Vec<f64>), String> {
        MatrixRows::read(
            text.as_bytes().to_vec(),
            "f.txt",
            ' ',
            columns,
            at_least,
            RULE,
        )
    }

    #[test]
    fn stamps_at_once_fields_when_asked() {
        let (rows, stamps) = read("# c\n1 2 3\n4 5.5 6e1\r\n7 -8 +9\n", 3, false).unwrap();
        assert_eq!(stamps, [1.0, 4.0, 7.0]);
        assert_eq!(
            rows.values_of(None, &[2, 1]).unwrap(),
            [3.0, 2.0, 60.0, 5.5, 9.0, -8.0]
        );
        assert_eq!(rows.values_of(Some(&[2, 0]), &[1]).unwrap(), [-8.0, 2.0]);
    }

    #[test]
    fn odd_rows_are_parsed_whole_on_reading() {
        let (rows, stamps) = read("1 2\n3 nan\n5 1_0\n", 2, false).unwrap();
        assert_eq!(stamps, [1.0, 3.0, 5.0]);
        let v = rows.values_of(None, &[1]).unwrap();
        assert!(v[1].is_nan());
        assert_eq!((v[0], v[2]), (2.0, 10.0));
        let e = read("1 2\n3 x\n", 2, false).err().unwrap();
        assert!(e.starts_with("f.txt:2:3: 'x'"), "{e}");
    }

    #[test]
    fn counts_and_stamps_are_checked_on_reading() {
        let e = read("1 2\n1 2 3\n", 2, false).err().unwrap();
        assert!(e.contains("f.txt:2: 3 entries"), "{e}");
        let e = read("1 2\n3 4 \n", 2, false).err().unwrap();
        assert!(e.starts_with("f.txt:2:5: ''"), "{e}");
        let e = read("1 2\n1.2.3 4\n", 2, false).err().unwrap();
        assert!(e.starts_with("f.txt:2:1: '1.2.3'"), "{e}");
        let e = read("1 2 3\n", 2, false).err().unwrap();
        assert!(e.contains("f.txt:1: 3 entries in the first row"), "{e}");
        let e = read("# only\n", 2, false).err().unwrap();
        assert!(e.contains("no rows") && e.ends_with(RULE), "{e}");
        let (rows, _) = read("1 2 3 4\n", 2, true).unwrap();
        assert_eq!(rows.width, 4);
    }

    #[test]
    fn a_bad_number_is_reported_when_its_row_is_used() {
        let (rows, _) = read("1 2\n3 4.5.6\n7 8\n", 2, false).unwrap();
        assert_eq!(rows.values_of(Some(&[0, 2]), &[1]).unwrap(), [2.0, 8.0]);
        let e = rows.values_of(None, &[1]).err().unwrap();
        assert!(e.starts_with("f.txt:2:3: '4.5.6' is not a number"), "{e}");
    }

    #[test]
    fn large_texts_read_in_pieces_as_in_one() {
        // About 3.5 pieces of rows, comments and CRLF rows among them.
        let rows = 3 * PIECE / 20 + PIECE / 40;
        let text: String = (0..rows)
            .map(|i| match i % 1000 {
                7 => format!("# comment {i}\n{i}.25 {} -{i}e-3\r\n", i * 2),
                _ => format!("{i}.25 {} -{i}e-3\n", i * 2),
            })
            .collect();
        assert!(pieces(text.as_bytes(), 0, text.len()).len() >= 3);
        let (read_rows, stamps) = read(&text, 3, false).unwrap();
        assert_eq!(stamps.len(), rows);
        assert_eq!(stamps[rows - 7], (rows - 7) as f64 + 0.25);
        let all = read_rows.values_of(None, &[1, 2]).unwrap();
        let i = rows - 5;
        let third: f64 = format!("-{i}e-3").parse().unwrap();
        assert_eq!((all[2 * i], all[2 * i + 1]), ((2 * i) as f64, third));
        // The line of a row in the last piece: one line per row, one more per comment.
        let line = i + 1 + (i + 993) / 1000;
        let bad = text.replace(&format!("\n{i}.25 "), &format!("\n{i}.25x "));
        let e = read(&bad, 3, false).err().unwrap();
        assert!(e.starts_with(&format!("f.txt:{line}:1:")), "{e}");
        assert_eq!(read_rows.rows[i].line as usize, line);
        let mut bytes = text.clone().into_bytes();
        let at = text.find(&format!("\n{i}.25 ")).unwrap() + 2;
        bytes[at] = 0xFF;
        let e = MatrixRows::read(bytes, "f.txt", ' ', 3, false, RULE)
            .err()
            .unwrap();
        assert_eq!(e, format!("f.txt:{line}: not UTF-8 text"));
    }

    #[test]
    fn scan_counts_delimiters_and_finds_other_characters() {
        assert_eq!(scan(b"1.5 -2e3 +4", b' '), (2, true));
        assert_eq!(scan(b"1,2,x", b','), (2, false));
        assert_eq!(scan(b"1 2", b','), (0, false));
    }
}
