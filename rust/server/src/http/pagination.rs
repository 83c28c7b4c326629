//! Pages of a JSON document's per-window array (`results.json`'s `windows`), so a very long
//! session never makes one huge answer. The document is cut as text: every other key keeps
//! its bytes and order, the array holds the page's elements, and a `page` object
//! (`{"offset","limit","total","next"}`) is added — only when the answer is not the whole
//! array, so a normal session's answer is the stored document unchanged.

use serde_json::value::RawValue;

use crate::error::Error;

/// Elements in one page at most, and by default (a 10 000-window page of `results.json` is
/// about 1.5 MB).
pub(crate) const MAX_PAGE: usize = 10_000;

/// `?offset=N&limit=M` of a paged route.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PageRequest {
    pub offset: usize,
    pub limit: usize,
}

impl PageRequest {
    /// Parses the query: `offset` ≥ 0 (default 0), `limit` 1 to [`MAX_PAGE`] (default
    /// [`MAX_PAGE`]); other keys are left to the route.
    pub fn parse(query: Option<&str>) -> Result<PageRequest, Error> {
        let mut page = PageRequest {
            offset: 0,
            limit: MAX_PAGE,
        };
        for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
            let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
            let number = || {
                value.parse::<usize>().map_err(|_| {
                    Error::BadRequest(format!(
                        "{key}: {} is not a whole number",
                        crate::error::short(value, 32)
                    ))
                })
            };
            match key {
                "offset" => page.offset = number()?,
                "limit" => {
                    page.limit = number()?;
                    if !(1..=MAX_PAGE).contains(&page.limit) {
                        return Err(Error::BadRequest(format!(
                            "limit: {} is not in 1..={MAX_PAGE}",
                            page.limit
                        )));
                    }
                }
                _ => {}
            }
        }
        Ok(page)
    }
}

/// `doc` with its top-level array `key` cut to `page`. A document without that array is
/// returned as it is.
pub(crate) fn page_of(doc: String, key: &str, page: PageRequest) -> Result<String, Error> {
    let bad = |e: serde_json::Error| Error::Internal(format!("stored JSON: {e}"));
    // Borrowed raw slices: the elements are never parsed into values (memory stays about
    // the document's size).
    let top: std::collections::HashMap<&str, &RawValue> =
        serde_json::from_str(&doc).map_err(bad)?;
    let Some(array) = top.get(key) else {
        return Ok(doc);
    };
    let elements: Vec<&RawValue> = serde_json::from_str(array.get()).map_err(bad)?;
    if page.offset == 0 && elements.len() <= page.limit {
        return Ok(doc);
    }
    let start = array.get().as_ptr() as usize - doc.as_ptr() as usize;
    let end = start + array.get().len();
    let close = doc
        .rfind('}')
        .ok_or_else(|| Error::Internal("stored JSON is not an object".into()))?;
    let from = page.offset.min(elements.len());
    let to = from.saturating_add(page.limit).min(elements.len());
    let info = serde_json::json!({
        "offset": from,
        "limit": page.limit,
        "total": elements.len(),
        "next": (to < elements.len()).then_some(to),
    });
    let mut out = String::with_capacity(doc.len().min(start + (to - from) * 256 + 4096));
    out.push_str(&doc[..start]);
    out.push('[');
    for (i, element) in elements[from..to].iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(element.get());
    }
    out.push(']');
    out.push_str(doc[end..close].trim_end());
    out.push_str(",\"page\":");
    out.push_str(&info.to_string());
    out.push_str(&doc[close..]);
    Ok(out)
}

/// `?limit=N` of the list routes (`GET /v1/sessions`, `GET /v1/venues`): default and cap.
const DEFAULT_LIMIT: u32 = 50;
const MAX_LIMIT: u32 = 500;

/// `?limit=N` (1 … 500, default 50); anything else is a 400 naming the parameter.
pub(crate) fn list_limit(query: Option<&str>) -> Result<u32, Error> {
    let mut limit = DEFAULT_LIMIT;
    for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        if key != "limit" {
            return Err(Error::BadRequest(format!(
                "unknown query parameter {key:?}: only limit is known"
            )));
        }
        limit = value
            .parse()
            .ok()
            .filter(|n| (1..=MAX_LIMIT).contains(n))
            .ok_or_else(|| {
                Error::BadRequest(format!(
                    "limit {value:?} is not a whole number from 1 to {MAX_LIMIT}"
                ))
            })?;
    }
    Ok(limit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{Value, json};

    fn doc(n: usize) -> String {
        let windows: Vec<Value> = (0..n)
            .map(|i| json!({"start": i, "error_m": 0.01}))
            .collect();
        json!({"version": 1, "windows": windows, "unit": "m"}).to_string()
    }

    #[test]
    fn a_short_document_is_answered_unchanged() {
        let text = doc(5);
        let page = PageRequest::parse(None).unwrap();
        assert_eq!(page_of(text.clone(), "windows", page).unwrap(), text);
    }

    #[test]
    fn pages_cover_every_window_once_and_keep_the_other_keys() {
        let text = doc(25);
        let mut seen = Vec::new();
        let mut offset = Some(0);
        while let Some(at) = offset {
            let page = PageRequest::parse(Some(&format!("offset={at}&limit=10"))).unwrap();
            let v: Value =
                serde_json::from_str(&page_of(text.clone(), "windows", page).unwrap()).unwrap();
            assert_eq!(
                (v["version"].clone(), v["unit"].clone()),
                (json!(1), json!("m"))
            );
            assert_eq!(v["page"]["total"], 25);
            seen.extend(
                v["windows"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|w| w["start"].as_u64().unwrap()),
            );
            offset = v["page"]["next"].as_u64().map(|n| n as usize);
        }
        assert_eq!(seen, (0..25).collect::<Vec<u64>>());
        // Past the end: an empty page.
        let page = PageRequest::parse(Some("offset=99")).unwrap();
        let v: Value = serde_json::from_str(&page_of(text, "windows", page).unwrap()).unwrap();
        assert_eq!(v["windows"], json!([]));
        assert_eq!(v["page"]["next"], Value::Null);
    }

    #[test]
    fn bad_page_parameters_are_named() {
        for (query, needle) in [
            ("limit=0", "limit: 0"),
            ("limit=10001", "limit"),
            ("offset=-1", "offset"),
        ] {
            let err = PageRequest::parse(Some(query)).unwrap_err().to_string();
            assert!(err.contains(needle), "{query}: {err}");
        }
    }

    #[test]
    fn limit_takes_one_number_in_range_and_names_what_is_wrong() {
        assert_eq!(list_limit(None).unwrap(), DEFAULT_LIMIT);
        assert_eq!(list_limit(Some("")).unwrap(), DEFAULT_LIMIT);
        assert_eq!(list_limit(Some("limit=7")).unwrap(), 7);
        assert_eq!(list_limit(Some("limit=500")).unwrap(), 500);
        for bad in [
            "limit=0",
            "limit=501",
            "limit=-1",
            "limit=",
            "limit=x",
            "page=2",
        ] {
            let err = list_limit(Some(bad)).unwrap_err().to_string();
            let named = if bad.starts_with("page") {
                "page"
            } else {
                "limit"
            };
            assert!(err.contains(named), "{bad}: {err}");
        }
    }
}
