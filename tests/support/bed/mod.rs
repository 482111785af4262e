//! The randomized discovery bench: datasets drawn from a seed by the independent simulator, each
//! with a truth kept beside (never inside) the dataset folder, scored against diagnosis.json.

#[path = "../cli.rs"]
pub mod cli;
pub mod dataset;
pub mod draw;
pub mod in_process;
pub mod limit;
pub mod pipeline;
pub mod score;
pub mod shapes;
pub mod table;
pub mod whiten;
