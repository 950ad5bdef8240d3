//! One file per command: its options (`Cmd`, flattened into the clap tree of `main.rs`) and
//! what it runs (`main`).

pub mod bake;
pub mod bench;
pub mod calibrate;
pub mod compare;
pub mod experiment;
pub mod export;
pub mod frozen;
pub mod growth;
pub mod merge;
pub mod moving;
pub mod optimum;
pub mod params;
pub mod report;
pub mod run;
pub mod soak;
pub mod stress;
