//! Unfinished deletes in Postgres (`unfinished_deletes`, migration 0008). A claim locks the
//! rows it takes with `FOR UPDATE SKIP LOCKED`: instances sweeping at once never take one
//! delete twice, and none waits for another.

use super::PgStore;
use crate::error::Error;
use crate::storage::deletes::{Claim, DeleteStore};

impl DeleteStore for PgStore {
    fn claim_unfinished_deletes(
        &self,
        claim: Claim<'_>,
        now_ms: i64,
        limit: u32,
    ) -> Result<Vec<String>, Error> {
        let (instance, until_ms) = (claim.instance.to_string(), claim.until_ms);
        let limit = i64::from(limit);
        self.pool.run(move |c| {
            let rows = c.query(
                "UPDATE unfinished_deletes SET claimed_by = $1, claimed_until_ms = $2 \
                 WHERE session_id IN (SELECT session_id FROM unfinished_deletes \
                 WHERE claimed_until_ms < $3 ORDER BY deleted_ms, session_id LIMIT $4 \
                 FOR UPDATE SKIP LOCKED) RETURNING session_id",
                &[&instance, &until_ms, &now_ms, &limit],
            )?;
            let mut ids: Vec<String> = rows.iter().map(|r| r.get(0)).collect();
            ids.sort();
            Ok(ids)
        })
    }

    fn finish_delete(&self, id: &str) -> Result<(), Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            c.execute(
                "DELETE FROM unfinished_deletes WHERE session_id = $1",
                &[&id],
            )?;
            Ok(())
        })
    }

    #[cfg(test)]
    fn unfinished_deletes(&self) -> Result<Vec<String>, Error> {
        self.pool.run(|c| {
            Ok(c.query(
                "SELECT session_id FROM unfinished_deletes ORDER BY session_id",
                &[],
            )?
            .iter()
            .map(|r| r.get(0))
            .collect())
        })
    }
}
