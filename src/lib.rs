//! groove: one-command analysis of spheres in a v-groove — engine, physics, fitting, discovery, report.

pub mod discover;
pub mod engine;
pub mod fit;
pub mod ingest;
pub mod lsq;
pub mod physics;
pub mod recording;
pub mod report;
pub mod stages;
pub mod stats;
pub mod synth;
