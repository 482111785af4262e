//! `ingest:skipped`: the runs ingest left out (`skip_bad_runs`), each with the reason.

pub use crate::ingest::Skipped;
