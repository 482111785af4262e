//! The engine: config, DAG, content-addressed store, scheduler. It knows no physics.

pub mod stage;
