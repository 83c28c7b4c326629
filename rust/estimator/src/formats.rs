//! Trajectory file formats: TUM, EuRoC ground-truth CSV and KITTI poses.
//!
//! Every reader accepts what evo reads: a UTF-8 byte-order mark, `\n`, `\r\n` and `\r` line
//! ends, blank lines and `#` comments. Fields are separated by spaces or tabs; any other
//! control character (a NUL byte, say) is an error naming its line and column. How stamps and
//! quaternions are taken is a [`ReadOptions`]: the default is SiTAR's (integer nanoseconds by
//! [`TimeUnitRule::Auto`], increasing stamps, unit quaternions); [`ReadOptions::EVO`] is evo's
//! (seconds, stamps as written — repeated or unsorted —, any quaternion normalised).

use std::io::Write;
use std::path::Path;

use glam::{DMat3, DQuat, DVec3};

use crate::{Error, TimeUnit, Trajectory};

/// Integer TUM stamps above this magnitude are nanoseconds under [`TimeUnitRule::Auto`]:
/// 10¹¹ seconds since 1970 is the year 5138, so such a stamp cannot be seconds, while
/// ARCore's nanoseconds since boot pass it after 100 s of uptime.
pub const NANOSECOND_STAMP_THRESHOLD: i64 = 100_000_000_000;

/// How TUM stamps are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum TimeUnitRule {
    /// Nanoseconds when every stamp is an integer token and one exceeds
    /// [`NANOSECOND_STAMP_THRESHOLD`] in magnitude (ARCore's trials); seconds otherwise.
    #[default]
    Auto,
    /// Always seconds, as evo reads TUM files (integers are whole seconds).
    Seconds,
    /// Always integer nanoseconds; a decimal stamp is an error.
    Nanoseconds,
}

impl std::str::FromStr for TimeUnitRule {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "auto" => Ok(TimeUnitRule::Auto),
            "s" => Ok(TimeUnitRule::Seconds),
            "ns" => Ok(TimeUnitRule::Nanoseconds),
            other => Err(Error::InvalidArgument(format!(
                "unknown time unit '{other}' (expected s, ns or auto)"
            ))),
        }
    }
}

/// Which stamp orders a reader accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum StampOrder {
    /// Strictly increasing; a repeated or decreasing stamp is an error naming its line.
    #[default]
    Increasing,
    /// As written, repeated and decreasing stamps included (evo keeps them); the
    /// [`ReadReport`] counts them.
    AsWritten,
}

/// How a reader takes stamps and quaternions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ReadOptions {
    /// The unit of TUM stamps (EuRoC stamps are always nanoseconds, KITTI has none).
    pub time_unit: TimeUnitRule,
    /// Accepted stamp orders.
    pub stamp_order: StampOrder,
    /// Normalise any finite, non-zero quaternion (evo does); otherwise a norm further than
    /// [`crate::QUATERNION_NORM_TOLERANCE`] from 1 is an error.
    pub normalise_quaternions: bool,
}

impl ReadOptions {
    /// SiTAR's rules: [`TimeUnitRule::Auto`], increasing stamps, unit quaternions.
    pub const SITAR: ReadOptions = ReadOptions {
        time_unit: TimeUnitRule::Auto,
        stamp_order: StampOrder::Increasing,
        normalise_quaternions: false,
    };
    /// evo's rules: seconds, stamps as written, quaternions normalised.
    pub const EVO: ReadOptions = ReadOptions {
        time_unit: TimeUnitRule::Seconds,
        stamp_order: StampOrder::AsWritten,
        normalise_quaternions: true,
    };
}

/// What a reader met that a caller may want to warn about.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReadReport {
    /// Poses whose stamp equals the previous pose's.
    pub repeated_stamps: usize,
    /// Line of the first repeated stamp.
    pub first_repeated_line: Option<usize>,
    /// Poses whose stamp is below the previous pose's.
    pub decreasing_stamps: usize,
    /// Line of the first decreasing stamp.
    pub first_decreasing_line: Option<usize>,
    /// Quaternions whose norm was further than [`crate::QUATERNION_NORM_TOLERANCE`] from 1
    /// and that were normalised.
    pub normalised_quaternions: usize,
    /// Quaternions whose norm differs from 1 by more than numpy's `allclose` allows
    /// (1e-5 + 1e-8): evo's `check` calls such a trajectory's quaternions invalid.
    pub quaternions_off_unit: usize,
    /// The text started with a UTF-8 byte-order mark (skipped).
    pub byte_order_mark: bool,
}

/// Reads a TUM trajectory file (`t x y z qx qy qz qw`) by SiTAR's rules; see [`parse_tum`].
pub fn read_tum(path: &Path) -> Result<Trajectory, Error> {
    parse_tum(&read_text(path)?, &path.display().to_string())
}

/// Reads a TUM trajectory file with `options`; see [`parse_tum_with`].
pub fn read_tum_with(
    path: &Path,
    options: &ReadOptions,
) -> Result<(Trajectory, ReadReport), Error> {
    parse_tum_with(&read_text(path)?, &path.display().to_string(), options)
}

/// Parses TUM text by SiTAR's rules ([`ReadOptions::SITAR`]): `#` starts a comment, blank
/// lines are skipped; integer stamps above [`NANOSECOND_STAMP_THRESHOLD`] are nanoseconds,
/// anything else is seconds (scientific notation accepted), converted exactly; stamps must
/// increase. Errors name `source`, the line and the column of the offending token.
pub fn parse_tum(text: &str, source: &str) -> Result<Trajectory, Error> {
    parse_tum_with(text, source, &ReadOptions::SITAR).map(|(t, _)| t)
}

/// Parses TUM text with `options`, returning what it met on the way.
pub fn parse_tum_with(
    text: &str,
    source: &str,
    options: &ReadOptions,
) -> Result<(Trajectory, ReadReport), Error> {
    let (text, bom) = strip_bom(text);
    let mut rows = Rows::with_capacity(text.len() / 64, options);
    rows.report.byte_order_mark = bom;
    let mut all_integer = true;
    let mut largest = 0u64;
    for (line_no, line) in numbered_lines(text) {
        let mut tokens = Tokens::new(line, source, line_no);
        let Some(first) = tokens.next_token()? else {
            continue;
        };
        let stamp = parse_stamp(first, &tokens)?;
        if let Stamp::Integer(v) = stamp {
            largest = largest.max(v.unsigned_abs());
        } else {
            all_integer = false;
        }
        let mut values = [0.0; 7];
        for value in &mut values {
            *value = tokens.expect_f64(8)?;
        }
        tokens.expect_end(8)?;
        let [x, y, z, qx, qy, qz, qw] = values;
        rows.push(
            stamp,
            DVec3::new(x, y, z),
            DQuat::from_xyzw(qx, qy, qz, qw),
            &tokens,
        )?;
    }
    let unit = match options.time_unit {
        TimeUnitRule::Auto if all_integer && largest > NANOSECOND_STAMP_THRESHOLD as u64 => {
            TimeUnit::Nanoseconds
        }
        TimeUnitRule::Auto | TimeUnitRule::Seconds => TimeUnit::Seconds,
        TimeUnitRule::Nanoseconds => TimeUnit::Nanoseconds,
    };
    let mut stamps = Vec::with_capacity(rows.stamps.len());
    for (stamp, line) in rows.stamps.iter().zip(&rows.lines) {
        let ns = match (*stamp, unit) {
            (Stamp::Integer(v), TimeUnit::Nanoseconds) => Some(v),
            (Stamp::Integer(v), TimeUnit::Seconds | TimeUnit::RosStamp) => {
                v.checked_mul(1_000_000_000)
            }
            (Stamp::Seconds(ns), TimeUnit::Seconds | TimeUnit::RosStamp) => Some(ns),
            (Stamp::Seconds(_), TimeUnit::Nanoseconds) => {
                return Err(parse_error(
                    source,
                    *line,
                    1,
                    "the stamp is not an integer, but the time unit is ns",
                ));
            }
        };
        let ns = ns.ok_or_else(|| {
            parse_error(
                source,
                *line,
                1,
                "timestamp out of range as seconds (integer nanoseconds? read them as ns)",
            )
        })?;
        stamps.push(ns);
    }
    rows.finish(stamps, unit, source)
}

/// Writes TUM text, keeping the time unit (integers for ns, 9 decimals for seconds) and
/// full round-trip precision for the pose values.
pub fn write_tum(traj: &Trajectory, out: &mut impl Write) -> std::io::Result<()> {
    let mut buffer = String::with_capacity(64 * 1024);
    for i in 0..traj.len() {
        let (p, q) = (traj.positions[i], traj.orientations[i]);
        use std::fmt::Write as _;
        let stamp = traj.time_unit.format_stamp(traj.stamps[i]);
        // Writing to a String cannot fail.
        let _ = writeln!(
            buffer,
            "{stamp} {} {} {} {} {} {} {}",
            p.x, p.y, p.z, q.x, q.y, q.z, q.w
        );
        if buffer.len() > 60 * 1024 {
            out.write_all(buffer.as_bytes())?;
            buffer.clear();
        }
    }
    out.write_all(buffer.as_bytes())
}

/// Reads a EuRoC ground-truth CSV (`#timestamp [ns], px, py, pz, qw, qx, qy, qz, ...`).
pub fn read_euroc_csv(path: &Path) -> Result<Trajectory, Error> {
    parse_euroc_csv(&read_text(path)?, &path.display().to_string())
}

/// Reads a EuRoC ground-truth CSV with `options` (its stamps are always nanoseconds).
pub fn read_euroc_csv_with(
    path: &Path,
    options: &ReadOptions,
) -> Result<(Trajectory, ReadReport), Error> {
    parse_euroc_csv_with(&read_text(path)?, &path.display().to_string(), options)
}

/// Parses EuRoC ground-truth CSV text: integer-ns stamps, position, quaternion `w x y z`;
/// further columns (velocities, biases) are ignored. Lines starting with `#` are comments.
pub fn parse_euroc_csv(text: &str, source: &str) -> Result<Trajectory, Error> {
    parse_euroc_csv_with(text, source, &ReadOptions::SITAR).map(|(t, _)| t)
}

/// [`parse_euroc_csv`] with `options` (only the stamp order and quaternion rule apply).
pub fn parse_euroc_csv_with(
    text: &str,
    source: &str,
    options: &ReadOptions,
) -> Result<(Trajectory, ReadReport), Error> {
    let (text, bom) = strip_bom(text);
    let mut rows = Rows::with_capacity(text.len() / 128, options);
    rows.report.byte_order_mark = bom;
    for (line_no, raw) in numbered_lines(text) {
        if raw.trim_start().starts_with('#') || raw.trim().is_empty() {
            continue;
        }
        check_controls(raw, source, line_no, b',')?;
        let mut fields = Vec::with_capacity(17);
        let mut offset = 0;
        for field in raw.split(',') {
            fields.push((
                field.trim(),
                offset + field.len() - field.trim_start().len() + 1,
            ));
            offset += field.len() + 1;
        }
        if fields.len() < 8 {
            return Err(parse_error(
                source,
                line_no,
                raw.len() + 1,
                &format!(
                    "expected at least 8 comma-separated fields, found {}",
                    fields.len()
                ),
            ));
        }
        let (token, column) = fields[0];
        let stamp = token.parse::<i64>().map_err(|_| {
            parse_error(
                source,
                line_no,
                column,
                &format!("timestamp '{token}' is not integer nanoseconds"),
            )
        })?;
        let mut values = [0.0; 7];
        for (k, value) in values.iter_mut().enumerate() {
            let (token, column) = fields[k + 1];
            *value = parse_finite(token, source, line_no, column)?;
        }
        let [x, y, z, qw, qx, qy, qz] = values;
        let tokens = Tokens::new("", source, line_no);
        rows.push(
            Stamp::Integer(stamp),
            DVec3::new(x, y, z),
            DQuat::from_xyzw(qx, qy, qz, qw),
            &tokens,
        )?;
    }
    let stamps = rows.stamps.iter().map(|s| match s {
        Stamp::Integer(v) | Stamp::Seconds(v) => *v,
    });
    let stamps = stamps.collect();
    rows.finish(stamps, TimeUnit::Nanoseconds, source)
}

/// Reads a KITTI pose file (12 numbers per line: the row-major 3×4 world-from-camera matrix).
pub fn read_kitti(path: &Path) -> Result<Trajectory, Error> {
    parse_kitti(&read_text(path)?, &path.display().to_string())
}

/// Parses KITTI poses. KITTI has no time: stamp `i` is the line's pose index (as nanoseconds),
/// so two KITTI paths associate index by index.
pub fn parse_kitti(text: &str, source: &str) -> Result<Trajectory, Error> {
    let (text, _) = strip_bom(text);
    let mut rows = Rows::with_capacity(text.len() / 128, &ReadOptions::SITAR);
    for (line_no, line) in numbered_lines(text) {
        let mut tokens = Tokens::new(line, source, line_no);
        let Some(first) = tokens.next_token()? else {
            continue;
        };
        let mut m = [0.0; 12];
        m[0] = match first.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            _ => parse_finite(first, source, line_no, tokens.column_of(first))?,
        };
        for value in &mut m[1..] {
            *value = tokens.expect_f64(12)?;
        }
        tokens.expect_end(12)?;
        let rotation = DMat3::from_cols(
            DVec3::new(m[0], m[4], m[8]),
            DVec3::new(m[1], m[5], m[9]),
            DVec3::new(m[2], m[6], m[10]),
        );
        let orthonormality = (rotation * rotation.transpose() - DMat3::IDENTITY)
            .abs()
            .to_cols_array();
        if orthonormality.iter().any(|&e| e > 1e-3) || rotation.determinant() <= 0.0 {
            return Err(parse_error(
                source,
                line_no,
                1,
                "rotation part is not a rotation matrix",
            ));
        }
        let q = DQuat::from_mat3(&rotation).normalize();
        let stamp = Stamp::Integer(rows.stamps.len() as i64);
        rows.push(stamp, DVec3::new(m[3], m[7], m[11]), q, &tokens)?;
    }
    let stamps = (0..rows.stamps.len() as i64).collect();
    rows.finish(stamps, TimeUnit::Nanoseconds, source)
        .map(|(t, _)| t)
}

fn read_text(path: &Path) -> Result<String, Error> {
    std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The text without a leading UTF-8 byte-order mark, and whether it had one.
fn strip_bom(text: &str) -> (&str, bool) {
    match text.strip_prefix('\u{feff}') {
        Some(rest) => (rest, true),
        None => (text, false),
    }
}

/// Lines with their 1-based numbers; `\n`, `\r\n` and a lone `\r` all end a line (as
/// Python's universal newlines, which evo reads with).
fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let has_cr = text.as_bytes().contains(&b'\r');
    let mut rest = text;
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let bytes = rest.as_bytes();
        let end = if has_cr {
            bytes.iter().position(|&b| b == b'\n' || b == b'\r')
        } else {
            bytes.iter().position(|&b| b == b'\n')
        };
        let (line, next) = match end {
            None => (rest, ""),
            Some(k) if bytes[k] == b'\r' && bytes.get(k + 1) == Some(&b'\n') => {
                (&rest[..k], &rest[k + 2..])
            }
            Some(k) => (&rest[..k], &rest[k + 1..]),
        };
        rest = next;
        Some((number, line))
    })
}

/// An error for the first control character in `line` that is not a separator (`sep`, space
/// or tab): a NUL byte or a stray escape is never a field separator.
fn check_controls(line: &str, file: &str, line_no: usize, sep: u8) -> Result<(), Error> {
    match line
        .bytes()
        .position(|b| (b < b' ' || b == 0x7f) && b != b'\t' && b != sep)
    {
        None => Ok(()),
        Some(k) => Err(control_error(line, k, file, line_no)),
    }
}

fn control_error(line: &str, byte: usize, file: &str, line_no: usize) -> Error {
    let c = line.as_bytes()[byte];
    parse_error(
        file,
        line_no,
        line[..byte].chars().count() + 1,
        &format!("control character U+{c:04X} is not a field separator"),
    )
}

fn parse_error(file: &str, line: usize, column: usize, message: &str) -> Error {
    Error::Parse {
        file: file.to_owned(),
        line,
        column,
        message: message.to_owned(),
    }
}

fn parse_finite(token: &str, file: &str, line: usize, column: usize) -> Result<f64, Error> {
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(parse_error(
            file,
            line,
            column,
            &format!("'{token}' is not a finite number"),
        )),
        Err(_) => Err(parse_error(
            file,
            line,
            column,
            &format!("'{token}' is not a number"),
        )),
    }
}

#[derive(Debug, Clone, Copy)]
enum Stamp {
    /// An integer token (nanoseconds or whole seconds, by the [`TimeUnitRule`]).
    Integer(i64),
    /// A decimal-seconds token, already converted to nanoseconds.
    Seconds(i64),
}

/// Parses a timestamp token: an integer, or decimal seconds converted exactly to ns
/// (rounded half away from zero at the 9th decimal), or scientific notation via f64.
fn parse_stamp(token: &str, tokens: &Tokens<'_>) -> Result<Stamp, Error> {
    let fail = |msg: String| parse_error(tokens.file, tokens.line, tokens.column_of(token), &msg);
    let (negative, body) = match token.as_bytes().first() {
        Some(b'-') => (true, &token[1..]),
        Some(b'+') => (false, &token[1..]),
        _ => (false, token),
    };
    if !body.is_empty() && body.bytes().all(|b| b.is_ascii_digit()) {
        let v: i64 = body
            .parse()
            .map_err(|_| fail(format!("timestamp '{token}' out of range")))?;
        return Ok(Stamp::Integer(if negative { -v } else { v }));
    }
    let (whole, frac) = body.split_once('.').unwrap_or((body, ""));
    let plain = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if !(whole.is_empty() && frac.is_empty()) && plain(whole) && plain(frac) {
        let seconds: i64 = if whole.is_empty() {
            0
        } else {
            whole
                .parse()
                .map_err(|_| fail(format!("timestamp '{token}' out of range")))?
        };
        let mut frac_ns: i64 = 0;
        for (k, b) in frac.bytes().take(9).enumerate() {
            frac_ns += i64::from(b - b'0') * 10_i64.pow(8 - k as u32);
        }
        if frac.len() > 9 && frac.as_bytes()[9] >= b'5' {
            frac_ns += 1;
        }
        let ns = seconds
            .checked_mul(1_000_000_000)
            .and_then(|s| s.checked_add(frac_ns))
            .ok_or_else(|| fail(format!("timestamp '{token}' out of range")))?;
        return Ok(Stamp::Seconds(if negative { -ns } else { ns }));
    }
    let seconds = match token.parse::<f64>() {
        Ok(v) if v.is_finite() => v,
        Ok(_) => return Err(fail(format!("timestamp '{token}' is not finite"))),
        Err(_) => return Err(fail(format!("timestamp '{token}' is not a number"))),
    };
    if seconds.abs() >= 9.2e9 {
        return Err(fail(format!("timestamp '{token}' out of range")));
    }
    // The float's exact value to the nanosecond, so that evo's float (what Python parses)
    // comes back from `TimeUnit::seconds` unchanged (EuRoC-derived TUM files write stamps
    // as `1.403715529112143517e+09`).
    Ok(Stamp::Seconds(crate::sync::seconds_to_ns(seconds)))
}

/// Whitespace tokens of one line, remembering where each starts for error columns.
struct Tokens<'a> {
    line_text: &'a str,
    /// Byte position of the scan; a `#` ends the line (comment).
    position: usize,
    file: &'a str,
    line: usize,
    count: usize,
}

impl<'a> Tokens<'a> {
    fn new(line_text: &'a str, file: &'a str, line: usize) -> Self {
        Self {
            line_text,
            position: 0,
            file,
            line,
            count: 0,
        }
    }

    /// The next space- or tab-separated token before any `#` (a hand-rolled scan: this is
    /// the hot loop of reading 100 trials). Any other control character is an error.
    fn next_token(&mut self) -> Result<Option<&'a str>, Error> {
        let bytes = self.line_text.as_bytes();
        let mut i = self.position;
        while i < bytes.len() && (bytes[i] == b' ' || bytes[i] == b'\t') {
            i += 1;
        }
        if i == bytes.len() || bytes[i] == b'#' {
            self.position = bytes.len();
            return Ok(None);
        }
        if bytes[i] < b' ' {
            return Err(control_error(self.line_text, i, self.file, self.line));
        }
        let start = i;
        let end = token_end(bytes, i);
        if let Some(&b) = bytes.get(end)
            && b != b' '
            && b != b'\t'
            && b != b'#'
        {
            return Err(control_error(self.line_text, end, self.file, self.line));
        }
        self.position = end;
        self.count += 1;
        // Both ends are ASCII bytes or the string's ends, so they are char boundaries.
        Ok(Some(&self.line_text[start..end]))
    }

    fn column_of(&self, token: &str) -> usize {
        let offset = token.as_ptr() as usize - self.line_text.as_ptr() as usize;
        self.line_text[..offset].chars().count() + 1
    }

    fn expect_f64(&mut self, expected: usize) -> Result<f64, Error> {
        match self.next_token()? {
            Some(token) => match token.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                // Slow path only on error: find the column.
                _ => parse_finite(token, self.file, self.line, self.column_of(token)),
            },
            None => Err(parse_error(
                self.file,
                self.line,
                self.line_text
                    .split('#')
                    .next()
                    .unwrap_or("")
                    .trim_end()
                    .chars()
                    .count()
                    + 1,
                &format!("expected {expected} values, found {}", self.count),
            )),
        }
    }

    fn expect_end(&mut self, expected: usize) -> Result<(), Error> {
        match self.next_token()? {
            Some(token) => Err(parse_error(
                self.file,
                self.line,
                self.column_of(token),
                &format!("expected {expected} values, found more"),
            )),
            None => Ok(()),
        }
    }
}

/// Index of the first byte at or after `i` that ends a token: a control byte, space or `#`.
/// Eight bytes at a time (SWAR): tokenizing is a large part of reading 100 trials.
fn token_end(bytes: &[u8], mut i: usize) -> usize {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    while let Some(chunk) = bytes.get(i..i + 8) {
        let mut word = [0u8; 8];
        word.copy_from_slice(chunk);
        let w = u64::from_le_bytes(word);
        // High bit set in a byte < 0x21 (for ASCII bytes), or in a byte equal to '#'; the
        // lowest flagged byte is exact (borrows only corrupt bytes above it).
        let below = w.wrapping_sub(ONES * 0x21) & !w & HIGHS;
        let hash = w ^ (ONES * u64::from(b'#'));
        let hash = hash.wrapping_sub(ONES) & !hash & HIGHS;
        let flags = below | hash;
        if flags != 0 {
            return i + (flags.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    while i < bytes.len() && bytes[i] > b' ' && bytes[i] != b'#' {
        i += 1;
    }
    i
}

/// Accumulated rows with per-row line numbers, so late checks can still name the line.
struct Rows {
    stamps: Vec<Stamp>,
    positions: Vec<DVec3>,
    orientations: Vec<DQuat>,
    lines: Vec<usize>,
    options: ReadOptions,
    report: ReadReport,
}

impl Rows {
    fn with_capacity(n: usize, options: &ReadOptions) -> Self {
        Self {
            stamps: Vec::with_capacity(n),
            positions: Vec::with_capacity(n),
            orientations: Vec::with_capacity(n),
            lines: Vec::with_capacity(n),
            options: *options,
            report: ReadReport::default(),
        }
    }

    fn push(&mut self, stamp: Stamp, p: DVec3, q: DQuat, tokens: &Tokens<'_>) -> Result<(), Error> {
        let norm = q.length();
        if (norm - 1.0).abs() > 1e-8 + 1e-5 {
            self.report.quaternions_off_unit += 1;
        }
        let tolerance = crate::trajectory::QUATERNION_NORM_TOLERANCE;
        if (norm - 1.0).abs() > tolerance {
            if !(self.options.normalise_quaternions && norm > f64::EPSILON && norm.is_finite()) {
                let rule = if self.options.normalise_quaternions {
                    "a quaternion must not be zero".to_owned()
                } else {
                    format!("tolerance {tolerance}")
                };
                return Err(parse_error(
                    tokens.file,
                    tokens.line,
                    1,
                    &format!("quaternion norm {norm} is not 1 ({rule})"),
                ));
            }
            self.report.normalised_quaternions += 1;
        }
        self.stamps.push(stamp);
        self.positions.push(p);
        self.orientations.push(q / norm);
        self.lines.push(tokens.line);
        Ok(())
    }

    fn finish(
        mut self,
        stamps: Vec<i64>,
        unit: TimeUnit,
        source: &str,
    ) -> Result<(Trajectory, ReadReport), Error> {
        for (i, w) in stamps.windows(2).enumerate() {
            if w[1] > w[0] {
                continue;
            }
            let line = self.lines[i + 1];
            if self.options.stamp_order == StampOrder::Increasing {
                let what = if w[1] == w[0] {
                    "duplicate"
                } else {
                    "decreasing"
                };
                return Err(parse_error(
                    source,
                    line,
                    1,
                    &format!("{what} timestamp (previous pose on line {})", self.lines[i]),
                ));
            }
            let report = &mut self.report;
            if w[1] == w[0] {
                report.repeated_stamps += 1;
                report.first_repeated_line.get_or_insert(line);
            } else {
                report.decreasing_stamps += 1;
                report.first_decreasing_line.get_or_insert(line);
            }
        }
        let trajectory = Trajectory {
            stamps,
            positions: self.positions,
            orientations: self.orientations,
            time_unit: unit,
        };
        Ok((trajectory, self.report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_err(text: &str) -> (usize, usize, String) {
        match parse_tum(text, "t.txt") {
            Err(Error::Parse {
                file,
                line,
                column,
                message,
            }) => {
                assert_eq!(file, "t.txt");
                (line, column, message)
            }
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    fn evo(text: &str) -> (Trajectory, ReadReport) {
        parse_tum_with(text, "x", &ReadOptions::EVO).unwrap()
    }

    #[test]
    fn large_integer_stamps_are_nanoseconds() {
        let text = "# hdr\n1000000000100 0 0 0 0 0 0 1\n\n1000000000200 1 2 3 0 0 0 1 # c\n";
        let t = parse_tum(text, "x").unwrap();
        assert_eq!(t.time_unit, TimeUnit::Nanoseconds);
        assert_eq!(t.stamps, vec![1_000_000_000_100, 1_000_000_000_200]);
        assert_eq!(t.positions[1], DVec3::new(1.0, 2.0, 3.0));
        // Small integers are whole seconds (evo's reading), by the rule or explicitly.
        let t = parse_tum("100 0 0 0 0 0 0 1\n101 0 0 0 0 0 0 1\n", "x").unwrap();
        assert_eq!(t.time_unit, TimeUnit::Seconds);
        assert_eq!(t.stamps, vec![100_000_000_000, 101_000_000_000]);
        // evo reads them as seconds, beyond i64 nanoseconds: an error that says what to do.
        let err = parse_tum_with(text, "x", &ReadOptions::EVO)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("x:2:1: timestamp out of range") && err.contains("ns"),
            "{err}"
        );
        let ns = ReadOptions {
            time_unit: TimeUnitRule::Nanoseconds,
            ..ReadOptions::SITAR
        };
        let (t, _) = parse_tum_with("100 0 0 0 0 0 0 1\n", "x", &ns).unwrap();
        assert_eq!((t.stamps[0], t.time_unit), (100, TimeUnit::Nanoseconds));
        assert!(parse_tum_with("1.5 0 0 0 0 0 0 1\n", "x", &ns).is_err());
        // The threshold itself is still seconds; one above is nanoseconds.
        let at = format!("{NANOSECOND_STAMP_THRESHOLD} 0 0 0 0 0 0 1\n");
        assert!(parse_tum(&at, "x").is_err(), "10^11 s overflows i64 ns");
        let above = format!("{} 0 0 0 0 0 0 1\n", NANOSECOND_STAMP_THRESHOLD + 1);
        assert_eq!(
            parse_tum(&above, "x").unwrap().time_unit,
            TimeUnit::Nanoseconds
        );
        assert_eq!(
            "ns".parse::<TimeUnitRule>().unwrap(),
            TimeUnitRule::Nanoseconds
        );
        assert!("min".parse::<TimeUnitRule>().is_err());
    }

    #[test]
    fn decimal_stamps_are_seconds_exactly() {
        let t = parse_tum("1403636579.763555527 0 0 0 0 0 0 1\n1403636580 0 0 0 0 0 0 1\n1.4036365805e9 0 0 0 0 0 0 1\n", "x").unwrap();
        assert_eq!(t.time_unit, TimeUnit::Seconds);
        assert_eq!(
            t.stamps,
            vec![
                1_403_636_579_763_555_527,
                1_403_636_580_000_000_000,
                1_403_636_580_500_000_000
            ]
        );
        let t = parse_tum(".5 0 0 0 0 0 0 1\n0.6000000005 0 0 0 0 0 0 1\n", "x").unwrap();
        assert_eq!(t.stamps, vec![500_000_000, 600_000_001]);
    }

    #[test]
    fn errors_name_line_and_column() {
        assert_eq!(parse_err("1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n").0, 2);
        assert_eq!(parse_err("1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n").1, 5);
        let (line, column, msg) = parse_err("1 0 0 nan 0 0 0 1\n");
        assert_eq!((line, column), (1, 7));
        assert!(msg.contains("finite"), "{msg}");
        assert_eq!(parse_err("1 0 0 inf 0 0 0 1\n").1, 7);
        let (_, column, msg) = parse_err("1 0 0 0 0 0 0\n");
        assert_eq!(column, 14);
        assert!(msg.contains("expected 8"), "{msg}");
        assert_eq!(parse_err("1 0 0 0 0 0 0 1 9\n").1, 17);
        assert!(parse_err("1 0 0 0 0 0 0 1.1\n").2.contains("quaternion"));
        let (line, _, msg) = parse_err("5 0 0 0 0 0 0 1\n5 0 0 0 0 0 0 1\n");
        assert_eq!(line, 2);
        assert!(msg.contains("duplicate"));
        assert!(
            parse_err("5 0 0 0 0 0 0 1\n4 0 0 0 0 0 0 1\n")
                .2
                .contains("decreasing")
        );
        assert_eq!(parse_err("abc 0 0 0 0 0 0 1\n").1, 1);
    }

    #[test]
    fn a_nul_byte_is_not_a_separator() {
        for (text, column) in [
            ("1 0 0 0 0 0 0 1\n2\x000 0 0 0 0 0 1\n", 2),
            ("1 0 0 0 0 0 0 1\n2 0 0\x00 0 0 0 0 1\n", 6),
            ("1 0 0 0 0 0 0 1\n\x002 0 0 0 0 0 0 1\n", 1),
            ("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\x1b\n", 16),
        ] {
            let (line, col, msg) = parse_err(text);
            assert_eq!((line, col), (2, column), "{text:?}: {msg}");
            assert!(msg.contains("control character U+00"), "{msg}");
        }
        assert!(parse_euroc_csv("10,1,2,3\x00,1,0,0,0\n", "gt.csv").is_err());
        assert!(parse_kitti("1 0 0 5 0 1 0 6 0 0 1\x007\n", "k").is_err());
        // Tabs separate, as spaces do.
        assert_eq!(parse_tum("1\t0 0 0\t0 0 0 1\n", "x").unwrap().len(), 1);
    }

    #[test]
    fn bom_and_every_line_end() {
        let lf = "# c\n1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n\n3 2 0 0 0 0 0 1\n";
        let want = parse_tum(lf, "x").unwrap();
        for text in [
            lf.to_owned(),
            lf.replace('\n', "\r\n"),
            lf.replace('\n', "\r"),
            format!("\u{feff}{lf}"),
            format!("\u{feff}{}", lf.replace('\n', "\r")),
        ] {
            let (t, report) = evo(&text);
            assert_eq!(t.stamps, want.stamps, "{text:?}");
            assert_eq!(t.positions, want.positions);
            assert_eq!(report.byte_order_mark, text.starts_with('\u{feff}'));
        }
        // Line numbers count CR-only and CRLF lines once each.
        let err = parse_tum(
            "1 0 0 0 0 0 0 1\r\n2 0 0 0 0 0 0 1\r\n3 0 x 0 0 0 0 1\r\n",
            "x",
        );
        assert!(
            matches!(
                err,
                Err(Error::Parse {
                    line: 3,
                    column: 5,
                    ..
                })
            ),
            "{err:?}"
        );
        let err = parse_tum("1 0 0 0 0 0 0 1\r2 0 x 0 0 0 0 1\r", "x");
        assert!(
            matches!(
                err,
                Err(Error::Parse {
                    line: 2,
                    column: 5,
                    ..
                })
            ),
            "{err:?}"
        );
        let csv = "\u{feff}#t,x,y,z,qw,qx,qy,qz\r10,1,2,3,1,0,0,0\r20,1,2,3,1,0,0,0\r";
        assert_eq!(parse_euroc_csv(csv, "gt.csv").unwrap().stamps, vec![10, 20]);
    }

    #[test]
    fn evo_rules_keep_repeated_and_unsorted_stamps() {
        let (t, report) =
            evo("1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n1.5 3 0 0 0 0 0 1\n");
        assert_eq!(
            t.stamps,
            vec![1_000_000_000, 2_000_000_000, 2_000_000_000, 1_500_000_000]
        );
        assert_eq!(
            (report.repeated_stamps, report.first_repeated_line),
            (1, Some(3))
        );
        assert_eq!(
            (report.decreasing_stamps, report.first_decreasing_line),
            (1, Some(4))
        );
        // Any quaternion norm is normalised, as evo's rotation matrices are; zero is not.
        let (t, report) = evo("1 0 0 0 0 0 0 1.01\n2 0 0 0 0.1 0 0 0.995\n");
        assert!((t.orientations[0].length() - 1.0).abs() < 1e-15);
        assert_eq!(report.normalised_quaternions, 1);
        assert_eq!(report.quaternions_off_unit, 2);
        assert!(parse_tum_with("1 0 0 0 0 0 0 0\n", "x", &ReadOptions::EVO).is_err());
    }

    #[test]
    fn normalises_quaternions_within_tolerance() {
        let t = parse_tum("1 0 0 0 0 0 0 1.0004\n", "x").unwrap();
        assert!((t.orientations[0].length() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn write_round_trips() {
        for text in [
            "1403636579.763555527 0.1 -2 3e-7 0 0 0.6 0.8\n",
            "17 0.1 -2 3e-7 0 0.6 0 0.8\n",
            "1000000000017 0.1 -2 3e-7 0 0.6 0 0.8\n",
        ] {
            let t = parse_tum(text, "x").unwrap();
            let mut out = Vec::new();
            write_tum(&t, &mut out).unwrap();
            let back = parse_tum(std::str::from_utf8(&out).unwrap(), "y").unwrap();
            assert_eq!(back, t);
        }
        let mut out = Vec::new();
        write_tum(&parse_tum("2.5 1 2 3 0 0 0 1\n", "x").unwrap(), &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "2.500000000 1 2 3 0 0 0 1\n"
        );
    }

    #[test]
    fn euroc_and_kitti() {
        let csv = "#timestamp, p_x, p_y, p_z, q_w, q_x, q_y, q_z, v\n10, 1, 2, 3, 1, 0, 0, 0, 9\n20,1,2,3,0,1,0,0,9\n";
        let t = parse_euroc_csv(csv, "gt.csv").unwrap();
        assert_eq!(t.stamps, vec![10, 20]);
        assert_eq!(t.orientations[1], DQuat::from_xyzw(1.0, 0.0, 0.0, 0.0));
        match parse_euroc_csv("10, 1, 2, x, 1, 0, 0, 0\n", "gt.csv") {
            Err(Error::Parse {
                line: 1,
                column: 11,
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let kitti = "1 0 0 5 0 1 0 6 0 0 1 7\n0 -1 0 1 1 0 0 2 0 0 1 3\n";
        let t = parse_kitti(kitti, "k.txt").unwrap();
        assert_eq!(t.stamps, vec![0, 1]);
        assert_eq!(t.positions[0], DVec3::new(5.0, 6.0, 7.0));
        let expected = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        assert!(t.orientations[1].angle_between(expected) < 1e-12);
        assert!(parse_kitti("2 0 0 5 0 1 0 6 0 0 1 7\n", "k").is_err());
        assert!(parse_kitti("x 0 0 5 0 1 0 6 0 0 1 7\n", "k").is_err());
    }

    proptest::proptest! {
        #[test]
        fn token_end_equals_the_byte_loop(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..40), start in 0usize..40) {
            let start = start.min(bytes.len());
            let mut expected = start;
            while expected < bytes.len() && bytes[expected] > b' ' && bytes[expected] != b'#' {
                expected += 1;
            }
            // Bytes >= 0x80 do not end tokens in either version.
            proptest::prop_assert_eq!(token_end(&bytes, start), expected);
        }

        #[test]
        fn never_panics_on_garbage(text in "[0-9 .eE+#\\-na,\n\r\t\u{0}\u{feff}]{0,200}") {
            let _ = parse_tum(&text, "fuzz");
            let _ = parse_tum_with(&text, "fuzz", &ReadOptions::EVO);
            let _ = parse_euroc_csv(&text, "fuzz");
            let _ = parse_kitti(&text, "fuzz");
        }
    }
}
