//! A session's alignment to its venue's frame, as `GET /v1/sessions/{id}` reports it:
//! sitar-core's [`sitar_core::venue::align`] over the phone's uploaded `anchors.csv`
//! (checked whole when it arrived), for the venue's anchor.

use serde_json::{Value, json};

use crate::error::Error;
use crate::model::Session;
use crate::storage::keys::SessionObject;
use crate::storage::{BlobStore, VenueStore};

/// `"alignment"` of `session`'s status: `null` when it is in no venue or the phone sent no
/// `anchors.csv`; `{"anchor","observations","position_spread_m","heading_spread_deg"}` when
/// it is aligned; `{"error": why}` when not.
pub(crate) fn alignment_json(
    venues: &dyn VenueStore,
    blobs: &dyn BlobStore,
    session: &Session,
) -> Result<Value, Error> {
    let Some(venue) = session.venue.as_deref() else {
        return Ok(Value::Null);
    };
    let Some(venue) = venues.venue(venue)? else {
        return Ok(Value::Null);
    };
    let Some(bytes) = blobs.get(&session.id, SessionObject::Anchors)? else {
        return Ok(Value::Null);
    };
    let text = String::from_utf8_lossy(&bytes);
    let observations = sitar_core::venue::parse_anchors_csv(&text, "anchors.csv")
        .map_err(|e| Error::Internal(format!("stored anchors.csv of {}: {e}", session.id)))?;
    Ok(
        match sitar_core::venue::align(&observations, &venue.anchor) {
            Ok(a) => json!({
                "anchor": venue.anchor,
                "observations": a.observations,
                "position_spread_m": a.position_spread_m,
                "heading_spread_deg": a.heading_spread_deg,
            }),
            Err(not) => json!({"error": not.reason}),
        },
    )
}
