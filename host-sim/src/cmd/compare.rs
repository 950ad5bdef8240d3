//! `host-sim compare`: compare results folders that differ by one switch each against a base folder
//! (the same matrix): per planner and map, the change of each mean with its Mann-Whitney p, as a
//! Markdown page.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

/// The options of `host-sim compare` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The base folder.
    #[arg(long)]
    base: PathBuf,
    /// Variants as LABEL=FOLDER.
    #[arg(required = true)]
    variants: Vec<String>,
    /// Markdown file to write.
    #[arg(long)]
    out: PathBuf,
    /// Hand-written Markdown to include after the variants' table.
    #[arg(long)]
    notes: Option<PathBuf>,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        base,
        variants,
        out,
        notes,
    } = cmd;
    let vs = variants
        .iter()
        .map(|v| {
            let (l, d) = v
                .split_once('=')
                .with_context(|| format!("variant {v:?}: expected LABEL=FOLDER"))?;
            Ok((l.to_string(), PathBuf::from(d)))
        })
        .collect::<Result<Vec<_>>>()?;
    let notes_text = notes
        .as_ref()
        .map(std::fs::read_to_string)
        .transpose()
        .context("reading --notes")?;
    let command = std::iter::once("host-sim".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    host_sim::study::report::compare(&base, &vs, &out, &command, notes_text.as_deref())?;
    println!("wrote {}", out.display());
    Ok(())
}
