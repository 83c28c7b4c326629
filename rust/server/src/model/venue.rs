//! A venue as the server knows it: the typed row of the `venues` table, and what a new one
//! needs.

/// The smallest and largest cell edge a venue may have (m).
pub(crate) const CELL_M_RANGE: std::ops::RangeInclusive<f64> = 0.05..=2.0;
/// The cell edge when the request names none (m).
pub(crate) const DEFAULT_CELL_M: f64 = 0.25;
/// The longest venue name, in characters.
pub(crate) const MAX_NAME_CHARS: usize = 200;

/// One venue, every column typed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Venue {
    /// Server-made id (`v` + 16 hex digits).
    pub id: String,
    /// Its name, as the owner gave it.
    pub name: String,
    /// The printed image anchor its sessions observe (`sitar_core::venue::check_anchor_id`).
    pub anchor: String,
    /// Map cell edge (m, within [`CELL_M_RANGE`]).
    pub cell_m: f64,
    /// The token that created it (`None`: made without authentication).
    pub owner: Option<i64>,
    /// When it was created (ms since the Unix epoch).
    pub created_ms: i64,
}

/// What a new venue needs (checked by the handler).
#[derive(Debug, Clone)]
pub(crate) struct NewVenue<'a> {
    pub name: &'a str,
    pub anchor: &'a str,
    pub cell_m: f64,
    pub owner: Option<i64>,
}

/// A fresh server-made venue id: `v` and 16 hex digits (the session id's generator, with the
/// venue's letter).
pub(crate) fn new_venue_id(session_style_id: &str) -> String {
    format!("v{}", &session_style_id[1..])
}

/// Whether `id` has the shape of a server-made venue id.
pub(crate) fn is_venue_id(id: &str) -> bool {
    id.len() == 17
        && id.starts_with('v')
        && id[1..]
            .bytes()
            .all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn venue_ids_are_v_and_16_lower_hex_digits() {
        let id = new_venue_id("s0123456789abcdef");
        assert_eq!(id, "v0123456789abcdef");
        assert!(is_venue_id(&id));
        for bad in [
            "s0123456789abcdef",
            "v0123456789ABCDEF",
            "v012",
            "v0123456789abcdeg",
            "",
        ] {
            assert!(!is_venue_id(bad), "{bad}");
        }
    }
}
