//! The repository's Markdown documents whose Rust code blocks are compiled and run as doctests
//! (`cargo test --workspace`, or `cargo test -p doctests --doc`): the README and the guides
//! here, the crate's own README in the core (`src/lib.rs`, it ships with the package). Nothing
//! else: this crate is not published and has no API.

#![no_std]

/// The repository's README.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct Readme;

/// The guide to using the core (`docs/guides/core.md`).
#[cfg(doctest)]
#[doc = include_str!("../../docs/guides/core.md")]
pub struct CoreGuide;
