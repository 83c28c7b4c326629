//! The worker store's hosts and phones in Postgres (`worker_hosts`, `worker_phones`), shared
//! by every instance: a host may register on one instance and heartbeat on another. Each call
//! is one transaction; a registration is one upsert on `(token_id, name)`, so two instances
//! registering the same worker at once agree on its id.

use super::{PgStore, u32_column};
use crate::error::Error;
use crate::storage::workers::{
    FAILURES_OUT_OF_SERVICE, HostRow, HostStore, PhoneRow, PhoneState, random_id,
};

fn host_row(r: &postgres::Row) -> HostRow {
    HostRow {
        id: r.get(0),
        name: r.get(1),
        token: r.get(2),
        playback: r.get(3),
        last_seen_ms: r.get(4),
    }
}

impl HostStore for PgStore {
    fn register_host(
        &self,
        token: i64,
        name: &str,
        playback: &str,
        phones: &[String],
        now_ms: i64,
    ) -> Result<String, Error> {
        let fresh = random_id('h')?;
        let (name, playback, phones) = (name.to_string(), playback.to_string(), phones.to_vec());
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            let id: String = tx
                .query_one(
                    "INSERT INTO worker_hosts (id, token_id, name, playback, registered_ms, \
                     last_seen_ms) VALUES ($1, $2, $3, $4, $5, $5) \
                     ON CONFLICT (token_id, name) DO UPDATE SET playback = EXCLUDED.playback, \
                     last_seen_ms = EXCLUDED.last_seen_ms RETURNING id",
                    &[&fresh, &token, &name, &playback, &now_ms],
                )?
                .get(0);
            // A restarted worker: its phones are back in service, its old leases played by
            // nobody now.
            tx.execute("DELETE FROM worker_phones WHERE host_id = $1", &[&id])?;
            for serial in &phones {
                tx.execute(
                    "INSERT INTO worker_phones (host_id, serial, state) VALUES ($1, $2, 'ready')",
                    &[&id, serial],
                )?;
            }
            tx.execute(
                "UPDATE trial_leases SET state = 'pending', lease_id = NULL, host_id = NULL, \
                 phone = NULL, expires_ms = NULL WHERE host_id = $1 AND state = 'leased'",
                &[&id],
            )?;
            tx.commit()?;
            Ok(id)
        })
    }

    fn host(&self, id: &str) -> Result<Option<HostRow>, Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            Ok(c.query_opt(
                "SELECT id, name, token_id, playback, last_seen_ms FROM worker_hosts WHERE id = $1",
                &[&id],
            )?
            .as_ref()
            .map(host_row))
        })
    }

    fn heartbeat(
        &self,
        id: &str,
        phones: &[String],
        held: &[String],
        now_ms: i64,
        lease_ms: i64,
    ) -> Result<Vec<String>, Error> {
        let (id, phones, held) = (id.to_string(), phones.to_vec(), held.to_vec());
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            let seen = tx.execute(
                "UPDATE worker_hosts SET last_seen_ms = $2 WHERE id = $1",
                &[&id, &now_ms],
            )?;
            if seen == 0 {
                return Err(Error::NotFound(format!("no host {id:?}: register again")));
            }
            // Unlisted phones are missing; listed ones present (a missing one ready again,
            // one out of service stays so).
            tx.execute(
                "UPDATE worker_phones SET state = 'missing' WHERE host_id = $1 AND state = 'ready'",
                &[&id],
            )?;
            for serial in &phones {
                tx.execute(
                    "INSERT INTO worker_phones (host_id, serial, state) VALUES ($1, $2, 'ready') \
                     ON CONFLICT (host_id, serial) DO UPDATE SET state = CASE \
                     WHEN worker_phones.state = 'out_of_service' THEN worker_phones.state \
                     ELSE 'ready' END",
                    &[&id, serial],
                )?;
            }
            // Only live leases are renewed: one past its time belongs to the reaper.
            tx.execute(
                "UPDATE trial_leases SET expires_ms = $2 \
                 WHERE host_id = $1 AND state = 'leased' AND expires_ms >= $3",
                &[&id, &(now_ms + lease_ms), &now_ms],
            )?;
            let live: Vec<String> = tx
                .query(
                    "SELECT lease_id FROM trial_leases WHERE host_id = $1 AND state = 'leased' \
                     AND lease_id = ANY($2)",
                    &[&id, &held],
                )?
                .iter()
                .map(|r| r.get(0))
                .collect();
            tx.commit()?;
            Ok(held
                .iter()
                .filter(|l| !live.contains(*l))
                .cloned()
                .collect())
        })
    }

    fn hosts(&self) -> Result<Vec<HostRow>, Error> {
        self.pool.run(|c| {
            Ok(c.query(
                "SELECT id, name, token_id, playback, last_seen_ms FROM worker_hosts \
                 ORDER BY name, id",
                &[],
            )?
            .iter()
            .map(host_row)
            .collect())
        })
    }

    fn phones(&self) -> Result<Vec<PhoneRow>, Error> {
        self.pool.run(|c| {
            c.query(
                "SELECT p.host_id, p.serial, p.state, p.failures, p.last_error \
                 FROM worker_phones p JOIN worker_hosts h ON h.id = p.host_id \
                 ORDER BY h.name, p.host_id, p.serial",
                &[],
            )?
            .iter()
            .map(|r| {
                Ok(PhoneRow {
                    host: r.get(0),
                    serial: r.get(1),
                    state: PhoneState::parse(r.get(2)),
                    failures: u32_column(r, 3, "worker_phones.failures")
                        .map_err(Error::Database)?,
                    last_error: r.get(4),
                })
            })
            .collect()
        })
    }

    fn phone_result(
        &self,
        host: &str,
        serial: &str,
        error: Option<&str>,
    ) -> Result<PhoneState, Error> {
        let (host, serial, error) = (
            host.to_string(),
            serial.to_string(),
            error.map(str::to_string),
        );
        let limit = i64::from(FAILURES_OUT_OF_SERVICE);
        self.pool.run(move |c| {
            let row = match &error {
                None => c.query_opt(
                    "UPDATE worker_phones SET failures = 0 WHERE host_id = $1 AND serial = $2 \
                     RETURNING state",
                    &[&host, &serial],
                )?,
                Some(why) => c.query_opt(
                    "UPDATE worker_phones SET failures = failures + 1, last_error = $3, \
                     state = CASE WHEN failures + 1 >= $4 THEN 'out_of_service' ELSE state END \
                     WHERE host_id = $1 AND serial = $2 RETURNING state",
                    &[&host, &serial, why, &limit],
                )?,
            };
            Ok(row.map_or(PhoneState::Missing, |r| PhoneState::parse(r.get(0))))
        })
    }
}
