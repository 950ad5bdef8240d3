//! `host-sim merge`: join results folders of one experiment (its shards, or runs done on several
//! machines) into one: rows in canonical order, JSON and summaries.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::study::experiment;

/// The options of `host-sim merge` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Folders to join.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Replace the results an existing --out folder holds (without it, such a folder is refused).
    #[arg(long)]
    overwrite: bool,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        out,
        inputs,
        overwrite,
    } = cmd;
    let m = host_sim::results::merge(&inputs, &out, overwrite)?;
    experiment::print_summary(&m.summary, m.search_only);
    println!(
        "merged {} folders: {} runs{} -> {}",
        inputs.len(),
        m.runs,
        if m.missing > 0 {
            format!(", {} runs of the matrix missing", m.missing)
        } else {
            String::new()
        },
        out.display()
    );
    Ok(())
}
