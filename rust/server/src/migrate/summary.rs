//! What a run of `sitar migrate` did and found, printed as its last lines.

use std::fmt;

/// One table: rows here, copied now, and found equal in the database afterwards.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TableCount {
    /// The table.
    pub table: &'static str,
    /// Rows of the embedded store.
    pub rows: usize,
    /// Rows this run inserted.
    pub copied: usize,
    /// Embedded rows the database holds equal after the run.
    pub equal: usize,
    /// Rows the database's table holds in all (other instances' rows included).
    pub in_database: usize,
}

/// What a run did and found.
#[derive(Debug, Clone, Default)]
pub struct Summary {
    /// Per copied table.
    pub tables: Vec<TableCount>,
    /// Sessions of the embedded store.
    pub sessions: usize,
    /// Objects (files) of those sessions, and their bytes.
    pub files: usize,
    /// Their bytes.
    pub bytes: u64,
    /// Objects this run stored, and their bytes.
    pub files_copied: usize,
    /// Their bytes.
    pub bytes_copied: u64,
    /// What was left behind, and why (files that are no object, rows of no session).
    pub left_behind: Vec<String>,
    /// What differs between the two sides after the run; empty when verified.
    pub differences: Vec<String>,
}

impl Summary {
    /// Whether every row and file is equal on both sides.
    pub fn verified(&self) -> bool {
        self.differences.is_empty() && self.tables.iter().all(|t| t.equal == t.rows)
    }

    /// Whether this run copied nothing (everything was there already).
    pub fn copied_nothing(&self) -> bool {
        self.files_copied == 0 && self.tables.iter().all(|t| t.copied == 0)
    }
}

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:<18} {:>8} {:>8} {:>8} {:>12}",
            "table", "rows", "copied", "equal", "in database"
        )?;
        for t in &self.tables {
            writeln!(
                f,
                "{:<18} {:>8} {:>8} {:>8} {:>12}",
                t.table, t.rows, t.copied, t.equal, t.in_database
            )?;
        }
        writeln!(
            f,
            "files              {} of {} sessions ({}), {} copied ({}), SHA-256 compared on both sides",
            self.files,
            self.sessions,
            mib(self.bytes),
            self.files_copied,
            mib(self.bytes_copied)
        )?;
        for left in &self.left_behind {
            writeln!(f, "left behind        {left}")?;
        }
        if self.verified() {
            write!(
                f,
                "verified           every row and file is equal in the cluster stores"
            )
        } else {
            let unequal: Vec<String> = self
                .tables
                .iter()
                .filter(|t| t.equal != t.rows)
                .map(|t| format!("{} ({} of {} rows equal)", t.table, t.equal, t.rows))
                .collect();
            write!(
                f,
                "NOT VERIFIED       {} difference(s)",
                self.differences.len() + unequal.len()
            )?;
            for d in unequal.iter().chain(&self.differences) {
                write!(f, "\n  {d}")?;
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(table: &'static str, rows: usize, copied: usize, equal: usize) -> TableCount {
        TableCount {
            table,
            rows,
            copied,
            equal,
            in_database: equal,
        }
    }

    #[test]
    fn a_table_short_of_rows_or_a_named_difference_is_not_verified() {
        let mut summary = Summary {
            tables: vec![count("tokens", 3, 0, 3), count("sessions", 2, 0, 2)],
            files: 4,
            ..Default::default()
        };
        assert!(summary.verified() && summary.copied_nothing());
        assert!(summary.to_string().ends_with("equal in the cluster stores"));
        summary.tables[1] = count("sessions", 2, 1, 1);
        assert!(!summary.verified() && !summary.copied_nothing());
        summary
            .differences
            .push("sessions/s1/results.csv: SHA-256 a here but b".into());
        let text = summary.to_string();
        assert!(
            text.contains("NOT VERIFIED       2 difference(s)"),
            "{text}"
        );
        assert!(text.contains("sessions (1 of 2 rows equal)"), "{text}");
        assert!(text.contains("results.csv: SHA-256"), "{text}");
    }
}
