//! `host-sim report`: turn an experiment's results folder into charts (SVG and PNG) and a
//! Markdown report in the shape of the paper's Section 5.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

/// The options of `host-sim report` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The results folder (experiment.json and runs.csv, a `moving` folder: moving.json and
    /// runs.csv, or a `bench` folder: bench.json and bench.csv).
    #[arg(long)]
    results: PathBuf,
    /// The Markdown file to write; the charts go to a folder beside it of the same name
    /// (default: RESULTS/report.md and RESULTS/report/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// A Markdown file written by hand to include after the settings (kept when the
    /// report is regenerated).
    #[arg(long)]
    notes: Option<PathBuf>,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        results,
        out,
        notes,
    } = cmd;
    let out = out.unwrap_or_else(|| results.join("report.md"));
    let mut command = format!(
        "host-sim report --results {} --out {}",
        results.display(),
        out.display()
    );
    let notes = match &notes {
        Some(n) => {
            command.push_str(&format!(" --notes {}", n.display()));
            Some(std::fs::read_to_string(n).with_context(|| format!("reading {}", n.display()))?)
        }
        None => None,
    };
    if results.join(host_sim::study::bench::SETTINGS_FILE).exists() {
        let md = host_sim::study::bench::report(&results, &command, notes.as_deref())?;
        std::fs::write(&out, md).with_context(|| format!("writing {}", out.display()))?;
        println!("wrote {} (a bench's per-leg tables)", out.display());
        return Ok(());
    }
    if results
        .join(host_sim::study::moving::SETTINGS_FILE)
        .exists()
    {
        let charts = host_sim::study::moving::report(&results, &out, &command)?;
        println!(
            "wrote {} and {} chart (SVG and PNG) of a moving run",
            out.display(),
            charts.len()
        );
        return Ok(());
    }
    let r = host_sim::study::report::report(&results, &out, &command, notes.as_deref())?;
    println!(
        "wrote {} and {} charts (SVG and PNG) in {}",
        r.markdown.display(),
        r.charts.len(),
        out.with_extension("").display()
    );
    Ok(())
}
