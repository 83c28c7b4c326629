//! Lists of indices (trials, sub-trajectories) written as ranges, for the pages.

use std::fmt::Write as _;

/// `indices`, in any order, as sorted ranges: `3–5, 7, 12, 15–16`.
pub(crate) fn index_ranges(indices: &[u32]) -> String {
    let mut sorted = indices.to_vec();
    sorted.sort_unstable();
    let mut out = String::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        if !out.is_empty() {
            out.push_str(", ");
        }
        if i == j {
            let _ = write!(out, "{}", sorted[i]);
        } else {
            let _ = write!(out, "{}–{}", sorted[i], sorted[j]);
        }
        i = j + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_become_ranges_in_sorted_order() {
        assert_eq!(index_ranges(&[0, 1, 2, 5, 7, 8]), "0–2, 5, 7–8");
        assert_eq!(index_ranges(&[7, 3, 4, 5, 12, 15, 16]), "3–5, 7, 12, 15–16");
        assert_eq!(index_ranges(&[4]), "4");
        assert_eq!(index_ranges(&[]), "");
    }
}
