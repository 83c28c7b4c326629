//! sitar-core's results parser (`Results::parse`: legacy CSV `start,error` or JSON) and
//! lookups on what it accepts. Accepted results must survive their own JSON form.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_core::{Results, Thresholds};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = Results::parse_csv(text);
    let _ = Results::parse_json(text);
    let Ok(results) = Results::parse(text) else {
        return;
    };
    assert!(results.windows.is_sorted_by_key(|w| w.start));
    assert!(
        results
            .windows
            .iter()
            .all(|w| w.error.is_finite() && w.error >= 0.0)
    );
    let json = results.to_json(Thresholds::DEFAULT_M);
    assert_eq!(Results::parse(&json).ok(), Some(results.clone()));
    let mut times: Vec<i64> = results.windows.iter().map(|w| w.start).collect();
    times.extend([i64::MIN, -1, 0, 1, i64::MAX]);
    for tolerance in [i64::MIN, 0, 1, i64::MAX] {
        let _ = results.lookup_many(&times, tolerance);
        for &t in &times {
            let _ = results.lookup(t, tolerance);
        }
    }
    let _ = results.mean_error();
});
