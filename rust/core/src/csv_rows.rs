//! The rows of the session folder's comma-separated tables.

use crate::Error;

/// The data rows of a table whose first line is one of `headers` (all with the same number of
/// columns; the first is the one an error names): `(1-based line, cells)`, blank lines skipped.
/// Another header, or a row with another number of cells, is an [`Error::Parse`] naming
/// `source`, the line and `header` or `row`.
pub(crate) fn rows<'a>(
    text: &'a str,
    source: &str,
    headers: &[&str],
) -> Result<Vec<(usize, Vec<&'a str>)>, Error> {
    let expected = headers.first().copied().unwrap_or_default();
    let columns = expected.split(',').count();
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if headers.contains(&h.trim()) => {}
        _ => {
            return Err(Error::parse(
                source,
                1,
                "header",
                format!("expected `{expected}`"),
            ));
        }
    }
    let mut out = Vec::new();
    for (i, line) in lines {
        let line_no = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != columns {
            return Err(Error::parse(
                source,
                line_no,
                "row",
                format!("expected {columns} fields, found {}", cells.len()),
            ));
        }
        out.push((line_no, cells));
    }
    Ok(out)
}
