//! Assisting metrics `d_A` (paper, section 3.1, equations 1-2): the distance that guides the
//! tree towards the goal, while tree costs stay Euclidean.
//!
//! - [`Euclidean`]: `d_E`, straight-line distance.
//! - [`DiffusionTable`]: `d_D`, the Euclidean distance between the diffusion coordinates of the
//!   two positions' grid cells, read from a borrowed, validated byte table (which can sit in
//!   flash). The host simulator bakes the tables (`host-sim bake`). For `i16` tables the sum
//!   of squared differences is computed exactly in integers and rounded to `f32` once (the
//!   same bits on every target, and integer work only on a core without an FPU: issue 26
//!   measured +17-21 % expansions per call on the Cortex-M0+).
//! - The geodesic metric `d_G` (graph shortest paths) implements the same trait in `host-sim`,
//!   and any user type can too.
//!
//! A metric returns `f32::INFINITY` for a position it cannot place (an obstacle, outside the
//! map, a region cut off from the main free component).
//!
//! The module's parts: the trait and `d_E` here; the reader of [`DiffusionTable`] in `table`;
//! the table's binary format below (header, versions, checksums, the writers the host bakes
//! with) in `format`.
//!
//! # Table format (versions 1 to 4)
//!
//! Little-endian throughout. A 32-byte header, then the payload:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `b"BIAMDIFF"` |
//! | 8 | 2 | format version (1: uniform, 2: pieces, 3: pieces bound to a map, 4: uniform bound to a map) |
//! | 10 | 2 | element kind: 1 = `i16` quantised, 2 = `f32` |
//! | 12 | 2 | dimensions `k` (1..=32) |
//! | 14 | 2 | columns (v1, v4: table cells; v2, v3: map cells) |
//! | 16 | 2 | rows (likewise) |
//! | 18 | 2 | v1, v4: 0; v2, v3: block side `b` in cells (1..=64) |
//! | 20 | 4 | cell size in metres (`f32`, finite, positive) |
//! | 24 | 4 | scale (`f32`): coordinate = element * scale |
//! | 28 | 4 | FNV-1a 32-bit hash of the payload |
//!
//! **Version 1 (uniform).** The payload holds `cols * rows` entries of `k` elements, in
//! row-major cell order (cell `(col, row)` is entry `row * cols + col`). A table cell may cover
//! several map cells: then all of them share one entry, even when a wall splits them.
//!
//! **Version 2 (pieces).** The map's cells are grouped in `b x b` blocks; each block holds one
//! entry per *connected free piece* of it, so a coarse table never gives a cell coordinates
//! from across a wall. The payload: the entry count `E` (`u32`); for each block (row-major,
//! `ceil(cols / b) x ceil(rows / b)` of them) the index of its first entry (`u16`, so
//! `E <= 65,536`); for each map cell (row-major, two per byte, low nibble first) its piece
//! within the block, 1..=15, or 0 for none; then the `E` entries of `k` elements. Cell
//! `(col, row)` with piece `q > 0` reads entry `first[block] + q - 1`.
//!
//! **Version 3 (pieces, bound to a map).** Version 2 whose payload opens with one more `u32`:
//! the FNV-1a hash of the packed occupancy grid the table was baked from (the
//! `OccupancyGrid::bytes_needed` bytes of `map::pack_grid`'s layout), then the version-2
//! payload. `DiffusionTable::check_map` (which `Planner::new` calls through
//! `Metric::check_map`) refuses a grid of another size or cell size (every version) or, for
//! versions 3 and 4, other contents, with `TableError::WrongMap`.
//!
//! **Version 4 (uniform, bound to a map).** Version 1 whose payload opens with the map's hash
//! as in version 3, then the version-1 entries. (`host-sim` writes versions 3 and 4; versions 1
//! and 2, which a table of another map of the same size passes, are still read.)
//!
//! In all, an entry whose first element is `i16::MIN` (kind 1) or NaN (kind 2) is
//! unreachable, as is a v2/v3 cell of piece 0.

mod format;
mod table;

pub use crate::error::TableError;
pub use format::*;
pub use table::DiffusionTable;

use crate::config::MetricKind;
use crate::geometry::Point;

/// The assisting metric of the planner (the paper's `d_A`).
pub trait Metric {
    /// Distance between two positions; `f32::INFINITY` when either cannot be placed.
    fn distance(&self, a: Point, b: Point) -> f32;

    /// Whether this is the Euclidean metric. The planner then never falls back from the
    /// Euclidean nearest neighbour and steers straight (paper Algorithm 2 with `d_A = d_E`).
    fn is_euclidean(&self) -> bool {
        false
    }

    /// Which kind of metric this is, for the planner's name ([`crate::Planner::name`]): the
    /// paper's `d_E`, `d_D` or `d_G`, or [`MetricKind::Other`] (the default) for a metric of
    /// the caller's own.
    fn kind(&self) -> MetricKind {
        if self.is_euclidean() {
            MetricKind::Euclidean
        } else {
            MetricKind::Other
        }
    }

    /// Work done by `distance` calls since the last `take_work`, in the planner's work units
    /// (one unit: about one grid cell or graph edge visited), beyond the flat 2 units the
    /// planner charges per call. A metric whose cost varies (one computing a distance field
    /// on a cache miss) reports it here so that a virtual clock stays faithful. Default: 0.
    fn take_work(&self) -> u32 {
        0
    }

    /// Whether the metric was made for `grid` (a table baked from it). `Planner::new` refuses
    /// a metric that was not. Default: any grid.
    fn check_map(&self, grid: &crate::map::OccupancyGrid<'_>) -> Result<(), TableError> {
        let _ = grid;
        Ok(())
    }

    /// One end of many distance queries, resolved once: the planner measures a whole tree, a
    /// batch of steering candidates or a goal's neighbourhood against the same position.
    /// Default: nothing is resolved.
    fn prepare(&self, p: Point) -> Prepared {
        Prepared::plain(p)
    }

    /// `distance(a, to.point())`, the same value bit for bit, using what `prepare` resolved.
    fn distance_to(&self, a: Point, to: &Prepared) -> f32 {
        self.distance(a, to.point)
    }
}

/// A position resolved by [`Metric::prepare`] for repeated [`Metric::distance_to`] queries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prepared {
    point: Point,
    /// What the metric resolved (for a diffusion table: the entry, or `u32::MAX` when the
    /// position cannot be placed); `None`: nothing.
    key: Option<u32>,
}

impl Prepared {
    /// A position with nothing resolved (any metric answers it through `distance`).
    pub const fn plain(point: Point) -> Self {
        Self { point, key: None }
    }

    /// The position.
    pub const fn point(&self) -> Point {
        self.point
    }
}

impl<M: Metric + ?Sized> Metric for &M {
    fn distance(&self, a: Point, b: Point) -> f32 {
        (**self).distance(a, b)
    }
    fn is_euclidean(&self) -> bool {
        (**self).is_euclidean()
    }
    fn kind(&self) -> MetricKind {
        (**self).kind()
    }
    fn take_work(&self) -> u32 {
        (**self).take_work()
    }
    fn check_map(&self, grid: &crate::map::OccupancyGrid<'_>) -> Result<(), TableError> {
        (**self).check_map(grid)
    }
    fn prepare(&self, p: Point) -> Prepared {
        (**self).prepare(p)
    }
    fn distance_to(&self, a: Point, to: &Prepared) -> f32 {
        (**self).distance_to(a, to)
    }
}

/// The Euclidean metric `d_E`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Euclidean;

impl Metric for Euclidean {
    #[inline]
    fn distance(&self, a: Point, b: Point) -> f32 {
        a.dist(b)
    }
    fn is_euclidean(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests;
