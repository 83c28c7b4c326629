//! Numbers as Python prints them (`repr(float)`), for evo's titles and tables.

/// Python's `repr` of a float: the shortest round-trip digits, with an exponent (`1e-05`,
/// `1e+16`) below 1e-4 and from 1e16 on, and `.0` on whole numbers.
pub fn repr(v: f64) -> String {
    if v.is_nan() {
        return "nan".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf" } else { "-inf" }.into();
    }
    if v == 0.0 {
        return if v.is_sign_negative() { "-0.0" } else { "0.0" }.into();
    }
    let abs = v.abs();
    if (1e-4..1e16).contains(&abs) {
        let text = format!("{v}");
        if text.contains('.') {
            text
        } else {
            format!("{text}.0")
        }
    } else {
        // Rust's `{:e}` gives the shortest digits too: 1e-5, 1.5e16.
        let text = format!("{v:e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let (sign, digits) = match exponent.strip_prefix('-') {
            Some(d) => ('-', d),
            None => ('+', exponent),
        };
        format!("{mantissa}e{sign}{digits:0>2}")
    }
}

/// `f"{v:.6f}"` with trailing zeros trimmed to one decimal, as pandas prints a float in an
/// object column (`0.016030` → `0.01603`, `1.000000` → `1.0`).
pub fn pandas_cell(v: f64) -> String {
    if !v.is_finite() {
        return repr(v);
    }
    let text = format!("{v:.6}");
    let trimmed = text.trim_end_matches('0');
    if trimmed.ends_with('.') {
        format!("{trimmed}0")
    } else {
        trimmed.to_owned()
    }
}

/// numpy's `str()` of a float vector (`[0.14373967 1.48956924 0.52800584]`): at most 8
/// decimals, trailing zeros dropped, all cells padded to one width.
pub fn numpy_vector(values: &[f64]) -> String {
    format!("[{}]", numpy_cells(values).join(" "))
}

/// numpy's `str()` of a float matrix, one cell format for every value.
pub fn numpy_matrix(rows: &[Vec<f64>]) -> String {
    let all: Vec<f64> = rows.iter().flatten().copied().collect();
    let cells = numpy_cells(&all);
    let width = rows.first().map_or(0, Vec::len).max(1);
    let lines: Vec<String> = cells
        .chunks(width)
        .map(|row| format!("[{}]", row.join(" ")))
        .collect();
    format!("[{}]", lines.join("\n "))
}

fn numpy_cells(values: &[f64]) -> Vec<String> {
    let cells: Vec<String> = values
        .iter()
        .map(|x| format!("{x:.8}").trim_end_matches('0').to_owned())
        .collect();
    let negative = values.iter().any(|v| v.is_sign_negative() && *v != 0.0);
    let int_width = cells
        .iter()
        .map(|c| c.find('.').unwrap_or(c.len()))
        .max()
        .unwrap_or(0)
        .max(1 + usize::from(negative));
    let frac_width = cells
        .iter()
        .map(|c| c.find('.').map_or(0, |k| c.len() - k - 1))
        .max()
        .unwrap_or(0);
    cells
        .iter()
        .map(|c| {
            let (int, frac) = c.split_once('.').unwrap_or((c, ""));
            format!("{int:>int_width$}.{frac:<frac_width$}")
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn like_python() {
        for (v, want) in [
            (1.0, "1.0"),
            (0.5, "0.5"),
            (0.1, "0.1"),
            (1e-5, "1e-05"),
            (0.0001, "0.0001"),
            (1.5e16, "1.5e+16"),
            (123456.789, "123456.789"),
            (-2.0, "-2.0"),
            (0.04014299609437343, "0.04014299609437343"),
        ] {
            assert_eq!(repr(v), want);
        }
        assert_eq!(pandas_cell(0.016030410116192953), "0.01603");
        assert_eq!(pandas_cell(0.2191585784188718), "0.219159");
        assert_eq!(pandas_cell(1.0), "1.0");
        assert_eq!(pandas_cell(-0.5), "-0.5");
        assert_eq!(
            numpy_vector(&[0.14373967123, 1.48956924, 0.52800584]),
            "[0.14373967 1.48956924 0.52800584]"
        );
        assert_eq!(numpy_vector(&[0.0, 1.4, 1.2]), "[0.  1.4 1.2]");
        assert_eq!(
            numpy_vector(&[-1.02073399, 1.53012172, 0.3899944]),
            "[-1.02073399  1.53012172  0.3899944 ]"
        );
        assert_eq!(
            numpy_matrix(&[vec![0.75896322, 0.08694211], vec![-0.06289154, 0.99620009]]),
            "[[ 0.75896322  0.08694211]\n [-0.06289154  0.99620009]]"
        );
    }
}
