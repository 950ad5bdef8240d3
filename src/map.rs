//! The world the planner moves in: a borrowed occupancy grid plus a bounded set of dynamic
//! circular obstacles, and the collision test `free_path` (paper, section 3).
//!
//! # Occupancy grid
//!
//! [`OccupancyGrid`] borrows a bit-packed byte slice: cell `(col, row)` is bit
//! `i = row * width + col`, stored in byte `i / 8` at bit `i % 8` (least significant bit first);
//! a set bit is an obstacle. Position `(x, y)` in metres lies in cell
//! `(floor(x / cell), floor(y / cell))`; the map spans `[0, width * cell] x [0, height * cell]`.
//! The grid only borrows its bytes and its constructor is a `const fn`, so firmware can keep the
//! whole map in flash:
//!
//! ```
//! use bi_am_rrt::map::OccupancyGrid;
//! static BITS: [u8; 2] = [0b0000_0000, 0b0000_0001]; // 4 x 4 cells, only (0, 2) occupied
//! static GRID: OccupancyGrid<'static> = match OccupancyGrid::new(&BITS, 4, 4, 1.0) {
//!     Ok(g) => g,
//!     Err(_) => panic!("bad grid"), // evaluated at compile time
//! };
//! assert!(GRID.is_occupied(0, 2));
//! assert!(!GRID.is_occupied(1, 2));
//! ```
//!
//! # What `free_path` means
//!
//! A segment is free when both ends lie inside the map and no occupied cell lies within
//! [`CONTACT_MARGIN`] (a thousandth of a cell, in the max-norm) of any of its points. Cells are
//! therefore closed squares with a hair of margin: a segment that grazes an occupied cell's edge,
//! or slips diagonally through the corner shared by two occupied cells, is blocked, and float
//! rounding can never let a segment through a corner that it mathematically touches. The test is
//! an exact traversal, row by row, of every cell the (slightly thickened) segment touches; its
//! cost grows with the number of rows and the number of cells crossed, never with the map's size.
//!
//! A dynamic obstacle is a closed disc: a segment is blocked by it when the distance from the
//! centre to the *segment* (not the infinite line) is at most the radius. An obstacle that moves
//! ([`Moving`], beyond the paper) blocks, for the tree, the capsule it sweeps over the edge
//! window ([`Obstacles::set_sweep`]); `free_path` uses that test, [`Map::free_now`] the discs
//! where they are.
//!
//! # Live cells
//!
//! Beyond the paper, a map may carry an [`Overlay`] ([`Map::with_overlay`]): a caller-owned
//! bitmap in the grid's layout whose set bits flip the grid's cells, so that a lidar can mark
//! cells occupied and clear them at run time ([`Map::set_cells`]) while the grid, and the
//! diffusion table baked from it, stay in flash untouched. Every test above then reads the live
//! cells ([`Map::live`]); a map whose overlay flips no cell takes the grid's own test. The
//! planner re-tests the edges near the changed cells at its next call (module `planner`).

//! # The robot's body
//!
//! Beyond the paper, which plans for a point, the robot may be a disc of radius `r`
//! ([`Map::with_body`], [`Map::with_baked_body`], [`crate::Config::robot_radius`]). Every test
//! above is then the disc's: a segment is free when the disc swept along it touches no
//! occupied live cell, stays inside the map, and meets no dynamic disc grown by `r`
//! ([`Obstacles::set_pad`]). The test has two stages, so that a call pays for the body only
//! near walls:
//!
//! 1. **Fast: the cells rule.** [`inflate`] marks every cell whose square lies closer than `r`
//!    to an occupied cell's square or to the map's edge (`gap_cols^2 + gap_rows^2 <
//!    (r / cell)^2`, `gap = max(|d| - 1, 0)`): every point of an unmarked cell has room for the
//!    disc, so a segment the ordinary test passes on the inflated cells is free. The inflated
//!    grid is made once: on the host (`host-sim export --robot-radius`, kept in flash:
//!    [`Map::with_baked_body`]) or at start-up into a caller-owned buffer ([`Map::with_body`]),
//!    which live edits re-inflate around the edited cells when they are submitted.
//! 2. **Exact, for what the first refuses.** The segment is thickened by `r` plus the contact
//!    margin, and every occupied live cell in that band is measured: free when the Euclidean
//!    distance from the segment to each such cell's square, and to the map's edge, is at least
//!    `r` plus the contact margin. So a disc passes any door wider than its diameter whatever
//!    the cell size (the cells rule alone closes a cell on each side of every wall).
//!
//! A start or goal must have room for the disc among the grid's walls
//! ([`InputError::NoRoom`]). [`Live::is_occupied`] answers whether the disc has room in a cell
//! (its centre or the middle of a side): the grid of those answers is the one to bake a metric
//! table on or to tell which places the disc can reach (not a collision test). [`Map::body_clear`]
//! is an independent check by exact distances, which the agent protocol counts collisions with.

use core::ops::ControlFlow;

use crate::error::{InputError, MapError, ObstacleError};
use crate::geometry::{Point, segment_point_dist_sq, segment_segment_dist_sq};
use crate::slots::{cell_index, sat_u32, to_u16};

/// Safety margin of the grid collision test, in cells (see the module documentation).
pub const CONTACT_MARGIN: f32 = 1.0e-3;

/// A read-only occupancy grid borrowing its bit-packed cells.
#[derive(Clone, Copy, Debug)]
pub struct OccupancyGrid<'a> {
    bits: &'a [u8],
    width: u16,
    height: u16,
    cell: f32,
    inv_cell: f32,
    /// The robot radius (metres) these cells were inflated for ([`inflate`]); 0 for a grid of
    /// the world as it is.
    inflation: f32,
}

impl<'a> OccupancyGrid<'a> {
    /// Bytes needed to hold `width * height` cells at one bit each.
    pub const fn bytes_needed(width: u16, height: u16) -> usize {
        #[allow(clippy::arithmetic_side_effects)] // u16 * u16 < 2^32 fits usize
        (width as usize * height as usize).div_ceil(8)
    }

    /// A grid of `width x height` cells of side `cell_size` metres over `bits` (layout in the
    /// module documentation). Extra bytes beyond [`Self::bytes_needed`] are ignored.
    pub const fn new(
        bits: &'a [u8],
        width: u16,
        height: u16,
        cell_size: f32,
    ) -> Result<Self, MapError> {
        if width == 0 || height == 0 {
            return Err(MapError::EmptyGrid);
        }
        // The inverse and the map's extent must be finite too: a subnormal cell (1e-40) has an
        // infinite inverse, and 65,535 huge cells overflow f32.
        let inv = 1.0 / cell_size;
        let extent = (if width > height { width } else { height }) as f32 * cell_size;
        if !(cell_size.is_finite() && cell_size > 0.0 && inv.is_finite() && extent.is_finite()) {
            return Err(MapError::BadCellSize);
        }
        if bits.len() < Self::bytes_needed(width, height) {
            return Err(MapError::BufferTooShort);
        }
        Ok(Self {
            bits,
            width,
            height,
            cell: cell_size,
            inv_cell: inv,
            inflation: 0.0,
        })
    }

    /// Declares that these cells are already inflated for a robot of `radius` metres by the
    /// rule of [`inflate`] (a grid that [`inflate`] wrote on the host, kept in flash: what
    /// `host-sim export` writes). Errors for a radius that is NaN, infinite or negative.
    pub const fn inflated_for(mut self, radius: f32) -> Result<Self, MapError> {
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(MapError::BadRadius);
        }
        self.inflation = radius;
        Ok(self)
    }

    /// The robot radius in metres these cells were inflated for (0: the world as it is).
    pub const fn inflation(&self) -> f32 {
        self.inflation
    }

    /// Width in cells.
    pub const fn cols(&self) -> u16 {
        self.width
    }

    /// Height in cells.
    pub const fn rows(&self) -> u16 {
        self.height
    }

    /// Side of a cell in metres.
    pub const fn cell_size(&self) -> f32 {
        self.cell
    }

    /// Width of the map in metres.
    pub fn width_m(&self) -> f32 {
        self.width as f32 * self.cell
    }

    /// Height of the map in metres.
    pub fn height_m(&self) -> f32 {
        self.height as f32 * self.cell
    }

    /// The borrowed bit-packed cells.
    pub const fn bits(&self) -> &'a [u8] {
        self.bits
    }

    /// Whether cell `(col, row)` is occupied. Cells outside the grid count as occupied.
    #[inline]
    pub fn is_occupied(&self, col: u16, row: u16) -> bool {
        if col >= self.width || row >= self.height {
            return true;
        }
        let i = cell_index(col, row, self.width);
        self.bits.get(i / 8).is_none_or(|b| b & (1 << (i % 8)) != 0)
    }

    /// Whether `p` is finite and inside the map's closed bounds.
    #[inline]
    pub fn contains(&self, p: Point) -> bool {
        // NaN fails every comparison, so it is rejected here too.
        p.x >= 0.0 && p.y >= 0.0 && p.x <= self.width_m() && p.y <= self.height_m()
    }

    /// The cell containing `p` (a point on the far edge belongs to the last cell), or `None`
    /// outside the map.
    pub fn cell_of(&self, p: Point) -> Option<(u16, u16)> {
        if !self.contains(p) {
            return None;
        }
        let col = to_u16(sat_u32(p.x * self.inv_cell).min(u32::from(self.width).saturating_sub(1)));
        let row =
            to_u16(sat_u32(p.y * self.inv_cell).min(u32::from(self.height).saturating_sub(1)));
        Some((col, row))
    }

    /// The centre of cell `(col, row)` in metres.
    pub fn cell_center(&self, col: u16, row: u16) -> Point {
        Point::new(
            (col as f32 + 0.5) * self.cell,
            (row as f32 + 0.5) * self.cell,
        )
    }

    /// Whether `p` lies in the map and no occupied cell is within the contact margin of it:
    /// the cells of the degenerate segment `p-p` (one, or up to four near a cell's edge), tested
    /// without the segment traversal (the steering tests a point per candidate).
    pub fn point_free(&self, p: Point) -> bool {
        self.point_spans_free(p, |row, c0, c1| self.span_free(row, c0, c1))
    }

    /// Whether segment `a-b` lies in the map and touches no occupied cell (module docs).
    pub fn segment_free(&self, a: Point, b: Point) -> bool {
        self.segment_spans_free(a, b, |row, c0, c1| self.span_free(row, c0, c1))
    }

    /// [`Self::point_free`] with the cells of `flip` (same layout) flipped ([`Overlay`]).
    fn point_free_xor(&self, p: Point, flip: &[u8]) -> bool {
        self.point_spans_free(p, |row, c0, c1| self.span_free_xor(row, c0, c1, flip))
    }

    /// [`Self::segment_free`] with the cells of `flip` (same layout) flipped ([`Overlay`]).
    fn segment_free_xor(&self, a: Point, b: Point, flip: &[u8]) -> bool {
        self.segment_spans_free(a, b, |row, c0, c1| self.span_free_xor(row, c0, c1, flip))
    }

    /// The point test with `free(row, c0, c1)` as the test of a run of cells.
    #[inline(always)]
    fn point_spans_free(&self, p: Point, free: impl Fn(u16, u16, u16) -> bool) -> bool {
        const M: f32 = CONTACT_MARGIN;
        if !self.contains(p) {
            return false;
        }
        let (x, y) = (p.x * self.inv_cell, p.y * self.inv_cell);
        let (c0, c1) = (axis_index(x - M, self.width), axis_index(x + M, self.width));
        let (r0, r1) = (
            axis_index(y - M, self.height),
            axis_index(y + M, self.height),
        );
        (r0..=r1).all(|row| free(row, c0, c1))
    }

    /// The segment test with `free(row, c0, c1)` as the test of a run of cells.
    #[inline(always)]
    fn segment_spans_free(&self, a: Point, b: Point, free: impl Fn(u16, u16, u16) -> bool) -> bool {
        if !self.contains(a) || !self.contains(b) {
            return false;
        }
        self.for_each_span(a, b, |row, c0, c1| {
            if free(row, c0, c1) {
                ControlFlow::Continue(())
            } else {
                ControlFlow::Break(())
            }
        })
        .is_continue()
    }

    /// Calls `f(col, row)` for every grid cell the segment `a-b` touches (within the contact
    /// margin), row by row; stops early when `f` breaks. Ends outside the map are allowed: only
    /// cells of the grid are visited.
    pub fn for_each_cell<F>(&self, a: Point, b: Point, mut f: F) -> ControlFlow<()>
    where
        F: FnMut(u16, u16) -> ControlFlow<()>,
    {
        self.for_each_span(a, b, |row, c0, c1| {
            for col in c0..=c1 {
                f(col, row)?;
            }
            ControlFlow::Continue(())
        })
    }

    /// The traversal: for each grid row the segment (thickened by the contact margin) crosses,
    /// the contiguous run of columns `c0..=c1` it touches in that row.
    #[inline(always)]
    fn for_each_span<F>(&self, a: Point, b: Point, f: F) -> ControlFlow<()>
    where
        F: FnMut(u16, u16, u16) -> ControlFlow<()>,
    {
        self.for_each_span_within(a, b, CONTACT_MARGIN, f)
    }

    /// [`Self::for_each_span`] with the segment thickened by `margin` cells instead of the
    /// contact margin (a robot body's exact test thickens it by its radius and the margin).
    fn for_each_span_within<F>(&self, a: Point, b: Point, margin: f32, mut f: F) -> ControlFlow<()>
    where
        F: FnMut(u16, u16, u16) -> ControlFlow<()>,
    {
        if !a.is_finite() || !b.is_finite() {
            return ControlFlow::Break(());
        }
        // Work in cell units with y increasing from a to b.
        #[allow(clippy::arithmetic_side_effects)] // `Point` * f32: float maths
        let (mut p, mut q) = (a * self.inv_cell, b * self.inv_cell);
        if p.y > q.y {
            core::mem::swap(&mut p, &mut q);
        }
        let (dx, dy) = (q.x - p.x, q.y - p.y);
        if q.y + margin < 0.0 || p.y - margin > self.height as f32 {
            return ControlFlow::Continue(());
        }
        let (row_lo, row_hi) = (
            axis_index(p.y - margin, self.height),
            axis_index(q.y + margin, self.height),
        );
        // x as a function of y is well conditioned when the segment is not (nearly) horizontal.
        // A flat segment (rise under the margin) is cut at a row band's edges only where the
        // cut is far from its ends, with the cut widened by the rounding of the cell-unit y's
        // (a few ulps of the larger |y|, over the rise): where that error would be large, the
        // piece is its whole x-range. Taking the whole x-range in every row it comes near made
        // the test refuse sub-segments of segments it passed (issue 41's maze step).
        let steep = dy > CONTACT_MARGIN;
        let slope = if steep { dx / dy } else { 0.0 };
        let slack = 4.0 * f32::EPSILON * p.y.abs().max(q.y.abs()).max(1.0);
        for row in row_lo..=row_hi {
            let (band_lo, band_hi) = (row as f32 - margin, row as f32 + 1.0 + margin);
            let (x0, x1) = if steep {
                let y0 = p.y.max(band_lo);
                let y1 = q.y.min(band_hi);
                (p.x + (y0 - p.y) * slope, p.x + (y1 - p.y) * slope)
            } else if dy > 0.0 && (p.y < band_lo || q.y > band_hi) {
                let t0 = ((band_lo - p.y - slack) / dy).clamp(0.0, 1.0);
                let t1 = ((band_hi - p.y + slack) / dy).clamp(0.0, 1.0);
                (p.x + dx * t0, p.x + dx * t1)
            } else {
                (p.x, q.x)
            };
            let (lo, hi) = (x0.min(x1) - margin, x0.max(x1) + margin);
            if hi < 0.0 || lo > self.width as f32 {
                continue;
            }
            f(row, axis_index(lo, self.width), axis_index(hi, self.width))?;
        }
        ControlFlow::Continue(())
    }

    /// Whether cells `c0..=c1` of `row` are all free (a bit-range test, a byte at a time).
    #[inline]
    fn span_free(&self, row: u16, c0: u16, c1: u16) -> bool {
        let (i0, i1) = (
            cell_index(c0, row, self.width),
            cell_index(c1, row, self.width),
        );
        let (b0, b1) = (i0 / 8, i1 / 8);
        let lo_mask = 0xffu8 << (i0 % 8);
        let hi_mask = 0xffu8 >> ((i1 % 8) ^ 7); // 7 - i1 % 8
        if b0 == b1 {
            // The common case on a steep segment: one or two cells of one byte.
            return self
                .bits
                .get(b0)
                .is_some_and(|b| b & lo_mask & hi_mask == 0);
        }
        let Some(bytes) = self.bits.get(b0..=b1) else {
            return false;
        };
        match bytes {
            [first, middle @ .., last] => {
                first & lo_mask == 0 && last & hi_mask == 0 && middle.iter().all(|&b| b == 0)
            }
            _ => false,
        }
    }

    /// [`Self::span_free`] over the cells XOR `flip`.
    fn span_free_xor(&self, row: u16, c0: u16, c1: u16, flip: &[u8]) -> bool {
        let (i0, i1) = (
            cell_index(c0, row, self.width),
            cell_index(c1, row, self.width),
        );
        let (b0, b1) = (i0 / 8, i1 / 8);
        let (Some(base), Some(flip)) = (self.bits.get(b0..=b1), flip.get(b0..=b1)) else {
            return false;
        };
        let last = b1.saturating_sub(b0);
        base.iter().zip(flip).enumerate().all(|(k, (&g, &f))| {
            let mut mask = 0xffu8;
            if k == 0 {
                mask &= 0xff << (i0 % 8);
            }
            if k == last {
                mask &= 0xff >> ((i1 % 8) ^ 7);
            }
            (g ^ f) & mask == 0
        })
    }
}

/// Fills `bits` (layout in the module docs) from `occupied(col, row)`, e.g. when building a grid
/// on the host or in a test. Bytes beyond the grid are left as they are.
pub fn pack_grid<F>(
    bits: &mut [u8],
    width: u16,
    height: u16,
    mut occupied: F,
) -> Result<(), MapError>
where
    F: FnMut(u16, u16) -> bool,
{
    if width == 0 || height == 0 {
        return Err(MapError::EmptyGrid);
    }
    let n = OccupancyGrid::bytes_needed(width, height);
    let Some(bits) = bits.get_mut(..n) else {
        return Err(MapError::BufferTooShort);
    };
    bits.fill(0);
    for row in 0..height {
        for col in 0..width {
            if occupied(col, row) {
                let i = cell_index(col, row, width);
                if let Some(b) = bits.get_mut(i / 8) {
                    *b |= 1 << (i % 8);
                }
            }
        }
    }
    Ok(())
}

/// The disc rule of a robot body in cell units (module docs, "The robot's body"): cell `c` is
/// marked when the closed squares of `c` and of an occupied cell lie less than the radius
/// apart, `gap_cols^2 + gap_rows^2 < (radius / cell)^2` with `gap = max(|d| - 1, 0)`: every
/// point of an unmarked cell has room for the disc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Disc {
    /// `(radius / cell)^2`, widened by a relative 1e-6 so that rounding marks more, never less.
    k2: f32,
    /// Rows the rule reaches on each side.
    reach: u16,
}

impl Disc {
    fn new(radius: f32, cell: f32) -> Self {
        let k = radius / cell;
        let k2 = k * k * (1.0 + 1.0e-6);
        Self {
            k2,
            reach: to_u16(sat_u32(libm::ceilf(crate::geometry::sqrt(k2)))),
        }
    }

    /// How many columns the rule reaches on each side in a row `dr` rows away (`None`: none
    /// of that row; a radius of 0 marks only the occupied cell itself).
    fn half(&self, dr: u16) -> Option<u16> {
        let gap = f32::from(dr.saturating_sub(1));
        let room = self.k2 - gap * gap;
        if room <= 0.0 {
            return (dr == 0).then_some(0);
        }
        // The largest gap g with g^2 < room is ceil(sqrt(room)) - 1; columns up to g + 1 away.
        Some(to_u16(sat_u32(libm::ceilf(crate::geometry::sqrt(room)))))
    }

    /// Whether cell `(col, row)` of a `width x height` grid is marked, with `occupied(row, c0,
    /// c1)` telling whether any cell of a run is occupied (runs that reach past the grid's
    /// edge count as occupied: the map's edge is a wall to the body).
    fn marks(
        &self,
        col: u16,
        row: u16,
        width: u16,
        height: u16,
        occupied: &impl Fn(u16, u16, u16) -> bool,
    ) -> bool {
        (0..=self.reach).any(|dr| {
            let Some(half) = self.half(dr) else {
                return false;
            };
            let run = |r: Option<u16>| match (r, col.checked_sub(half), col.checked_add(half)) {
                (Some(r), Some(c0), Some(c1)) if r < height && c1 < width => occupied(r, c0, c1),
                _ => true,
            };
            run(row.checked_sub(dr)) || (dr > 0 && run(row.checked_add(dr)))
        })
    }

    /// Writes the rule's marks for every cell of the box `[c0, r0, c1, r1]` into `out` (the
    /// grid's layout): `cells x (2 reach + 1)` run tests.
    fn mark_box(
        &self,
        out: &mut [u8],
        width: u16,
        height: u16,
        bx: [u16; 4],
        occupied: &impl Fn(u16, u16, u16) -> bool,
    ) {
        let [c0, r0, c1, r1] = bx;
        for row in r0..=r1.min(height.saturating_sub(1)) {
            for col in c0..=c1.min(width.saturating_sub(1)) {
                let i = cell_index(col, row, width);
                if let Some(b) = out.get_mut(i / 8) {
                    let bit = 1u8 << (i % 8);
                    if self.marks(col, row, width, height, occupied) {
                        *b |= bit;
                    } else {
                        *b &= !bit;
                    }
                }
            }
        }
    }

    /// The box grown by the rule's reach on every side, clipped to the grid.
    fn grow(&self, bx: [u16; 4], width: u16, height: u16) -> [u16; 4] {
        let [c0, r0, c1, r1] = bx;
        [
            c0.saturating_sub(self.reach),
            r0.saturating_sub(self.reach),
            c1.saturating_add(self.reach).min(width.saturating_sub(1)),
            r1.saturating_add(self.reach).min(height.saturating_sub(1)),
        ]
    }
}

/// Whether any of the first `cells` bits of `bits` is clear (a free cell).
fn any_free(bits: &[u8], cells: usize) -> bool {
    let (full, rest) = (cells / 8, cells % 8);
    bits.iter().take(full).any(|&b| b != 0xff)
        || (rest > 0
            && bits
                .get(full)
                .is_some_and(|&b| b | (0xffu8 << rest) != 0xff))
}

/// Inflates `grid` for a robot disc of `radius` metres into `out` (at least
/// [`OccupancyGrid::bytes_needed`] bytes, the grid's layout) and returns the inflated grid
/// (the robot's configuration space: a point there is free when the disc there touches no
/// wall). The rule, in the module docs, is conservative at cell resolution: every point of a
/// free inflated cell is at least `radius` from every occupied cell and from the map's edge.
/// O(cells x (2 radius / cell + 3)) run tests, once (on the host at export time, or at boot
/// into a RAM buffer). Errors for a radius that is NaN, infinite or negative, a short buffer,
/// or a radius that leaves no free cell.
pub fn inflate<'b>(
    grid: &OccupancyGrid<'_>,
    radius: f32,
    out: &'b mut [u8],
) -> Result<OccupancyGrid<'b>, MapError> {
    inflate_live(grid, None, radius, out)
}

/// [`inflate`] of the live cells `grid XOR flip`.
fn inflate_live<'b>(
    grid: &OccupancyGrid<'_>,
    flip: Option<&[u8]>,
    radius: f32,
    out: &'b mut [u8],
) -> Result<OccupancyGrid<'b>, MapError> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(MapError::BadRadius);
    }
    let (w, h) = (grid.cols(), grid.rows());
    let n = OccupancyGrid::bytes_needed(w, h);
    let Some(out) = out.get_mut(..n) else {
        return Err(MapError::BufferTooShort);
    };
    let disc = Disc::new(radius, grid.cell_size());
    // A disc wider than the map fits nowhere (and this bounds the work).
    if disc.reach > w.max(h) {
        return Err(MapError::NoRoom);
    }
    let occupied = |row: u16, c0: u16, c1: u16| match flip {
        None => !grid.span_free(row, c0, c1),
        Some(f) => !grid.span_free_xor(row, c0, c1, f),
    };
    let all = [0, 0, w.saturating_sub(1), h.saturating_sub(1)];
    disc.mark_box(out, w, h, all, &occupied);
    #[allow(clippy::arithmetic_side_effects)] // u16 * u16 fits usize
    if !any_free(out, usize::from(w) * usize::from(h)) {
        return Err(MapError::NoRoom);
    }
    let mut inflated = OccupancyGrid::new(out, w, h, grid.cell_size())?;
    inflated.inflation = radius;
    Ok(inflated)
}

/// Squared distance from segment `a-b` to the closed box `[lo, hi]` (0 when they meet).
fn segment_box_dist_sq(a: Point, b: Point, lo: Point, hi: Point) -> f32 {
    // Liang-Barsky clipping: do they meet?
    let d = Point::new(b.x - a.x, b.y - a.y);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    let mut meets = true;
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            meets &= q >= 0.0;
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    if meets && t0 <= t1 {
        return 0.0;
    }
    let box_dist_sq = |p: Point| {
        let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
        let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
        dx * dx + dy * dy
    };
    [lo, Point::new(hi.x, lo.y), hi, Point::new(lo.x, hi.y)]
        .into_iter()
        .map(|c| segment_point_dist_sq(a, b, c))
        .fold(box_dist_sq(a).min(box_dist_sq(b)), f32::min)
}

/// The cell index of coordinate `v` (in cells) on an axis of `len` cells: values below zero
/// truncate to 0 like a clamped floor; the far side is clamped to the last cell.
#[inline]
fn axis_index(v: f32, len: u16) -> u16 {
    to_u16(sat_u32(v).min(u32::from(len).saturating_sub(1)))
}

/// A closed disc: a dynamic obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Circle {
    /// Centre in metres.
    pub center: Point,
    /// Radius in metres.
    pub radius: f32,
}

impl Circle {
    /// A disc of `radius` around `center`.
    pub const fn new(center: Point, radius: f32) -> Self {
        Self { center, radius }
    }

    /// Whether `p` lies in the closed disc.
    pub fn contains(&self, p: Point) -> bool {
        p.dist_sq(self.center) <= self.radius * self.radius
    }

    /// Whether the closed segment `a-b` meets the closed disc (distance from the centre to the
    /// segment at most the radius).
    pub fn intersects_segment(&self, a: Point, b: Point) -> bool {
        segment_point_dist_sq(a, b, self.center) <= self.radius * self.radius
    }

    fn is_valid(&self) -> bool {
        self.center.is_finite() && self.radius.is_finite() && self.radius > 0.0
    }
}

/// A dynamic obstacle as a perception stack reports it (beyond the paper: its obstacles stay
/// put): a disc where it is at the next `plan` call, its velocity, and how long that
/// prediction may be trusted. A still circle is `Moving::still(circle)`.
///
/// Over a time window `[0, w]` the obstacle sweeps the capsule from `center` to
/// `center + velocity * min(w, trusted_for)` of radius `radius + bound * max(0, w -
/// trusted_for)`, where `bound` is the stated top speed of any obstacle
/// ([`crate::config::Motion::obstacle_speed`]): past its horizon the obstacle may have turned
/// anywhere at that speed ([`Moving::sweep`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Moving {
    /// The disc at the time of the next `plan` call.
    pub circle: Circle,
    /// Velocity in metres per second.
    pub velocity: Point,
    /// Seconds for which the straight-line prediction holds (`f32::INFINITY`: for ever).
    pub trusted_for: f32,
}

impl Moving {
    /// A circle that does not move.
    pub const fn still(circle: Circle) -> Self {
        Self {
            circle,
            velocity: Point::ZERO,
            trusted_for: f32::INFINITY,
        }
    }

    /// A circle moving at `velocity` (m/s), trusted for ever.
    pub const fn new(circle: Circle, velocity: Point) -> Self {
        Self {
            circle,
            velocity,
            trusted_for: f32::INFINITY,
        }
    }

    /// The same, its prediction trusted for `seconds` only.
    pub const fn trusted_for(mut self, seconds: f32) -> Self {
        self.trusted_for = seconds;
        self
    }

    /// The capsule swept over `[0, window]` seconds by an obstacle whose speed is at most
    /// `bound` once its prediction ends: `(from, to, radius)`.
    pub fn sweep(&self, window: f32, bound: f32) -> (Point, Point, f32) {
        let c = self.circle.center;
        let trusted = window.min(self.trusted_for).max(0.0);
        let beyond = (window - self.trusted_for).max(0.0);
        let to = Point::new(
            c.x + self.velocity.x * trusted,
            c.y + self.velocity.y * trusted,
        );
        (c, to, self.circle.radius + bound * beyond)
    }

    /// Whether the closed segment `a-b` meets the capsule swept over `[0, window]`.
    pub fn sweep_meets(&self, a: Point, b: Point, window: f32, bound: f32) -> bool {
        let (from, to, r) = self.sweep(window, bound);
        if from == to {
            segment_point_dist_sq(a, b, from) <= r * r
        } else {
            segment_segment_dist_sq(a, b, from, to) <= r * r
        }
    }

    fn is_valid(&self) -> bool {
        self.circle.is_valid() && self.velocity.is_finite() && self.trusted_for >= 0.0
    }
}

/// Identifies a dynamic obstacle for its removal. Ids are not reused until 2^32 further
/// additions have been made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ObstacleId(pub u32);

/// A bounded set of at most `K` dynamic obstacles, still or moving.
///
/// Two tests: *now* ([`Obstacles::blocks_now`], [`Obstacles::contains_now`]) against the
/// discs where they are, and the *tree's* ([`Obstacles::blocks_segment`],
/// [`Obstacles::contains`]) against what each sweeps over the edge window
/// ([`Obstacles::set_sweep`]: the planner sets it to [`crate::config::Motion::horizon`]): a
/// tree edge is judged against where its obstacles will be within that window, so the path
/// passes behind a walking person rather than in front. With still circles, or a window of 0,
/// both tests are the paper's.
#[derive(Clone, Debug)]
pub struct Obstacles<const K: usize> {
    items: heapless::Vec<(ObstacleId, Moving), K>,
    next_id: u32,
    /// Edge window in seconds and the obstacles' top speed past a prediction, in m/s.
    window: f32,
    bound: f32,
    /// The robot's radius: every disc is kept grown by it ([`Obstacles::set_pad`]).
    pad: f32,
}

impl<const K: usize> Default for Obstacles<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize> Obstacles<K> {
    /// An empty set.
    pub const fn new() -> Self {
        Self {
            items: heapless::Vec::new(),
            next_id: 0,
            window: 0.0,
            bound: 0.0,
            pad: 0.0,
        }
    }

    /// Grows every disc, present and to come, by the robot's `radius` (a circle of radius R
    /// then blocks R + r: the tests below are the robot disc's). The planner sets it from its
    /// map's body ([`Map::radius`]); non-finite or negative values count as 0. What
    /// [`Obstacles::get`], [`Obstacles::iter`] and [`Obstacles::remove`] return is the disc as
    /// given; [`Obstacles::as_slice`] holds the grown ones.
    pub fn set_pad(&mut self, radius: f32) {
        let radius = if radius.is_finite() && radius > 0.0 {
            radius
        } else {
            0.0
        };
        let delta = radius - self.pad;
        for (_, m) in self.items.iter_mut() {
            m.circle.radius += delta;
        }
        self.pad = radius;
    }

    /// The robot's radius the discs are grown by.
    pub fn pad(&self) -> f32 {
        self.pad
    }

    /// `obstacle` grown by the pad.
    fn padded(&self, mut obstacle: Moving) -> Moving {
        obstacle.circle.radius += self.pad;
        obstacle
    }

    /// A grown disc as given.
    fn unpadded(&self, mut circle: Circle) -> Circle {
        circle.radius -= self.pad;
        circle
    }

    /// Sets the tree's edge window (seconds) and the obstacles' top speed past a prediction
    /// (m/s); non-finite or negative values count as 0.
    pub fn set_sweep(&mut self, window: f32, bound: f32) {
        let ok = |v: f32| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        self.window = ok(window);
        self.bound = ok(bound);
    }

    /// The edge window and top speed ([`Obstacles::set_sweep`]).
    pub fn sweep(&self) -> (f32, f32) {
        (self.window, self.bound)
    }

    /// Adds a still circle and returns its id; `Err(Full)` when `K` circles are present,
    /// `Err(BadCircle)` for a non-finite centre or a radius that is not finite and positive.
    pub fn add(&mut self, circle: Circle) -> Result<ObstacleId, ObstacleError> {
        self.add_moving(Moving::still(circle))
    }

    /// Adds an obstacle that may move; `Err(BadCircle)` also for a non-finite velocity or a
    /// horizon that is negative or NaN.
    pub fn add_moving(&mut self, obstacle: Moving) -> Result<ObstacleId, ObstacleError> {
        if !obstacle.is_valid() {
            return Err(ObstacleError::BadCircle);
        }
        if self.items.is_full() {
            return Err(ObstacleError::Full);
        }
        // Skip ids still in use after a wrap-around (at most K of them).
        let mut id = ObstacleId(self.next_id);
        while self.get(id).is_some() {
            id = ObstacleId(id.0.wrapping_add(1));
        }
        self.next_id = id.0.wrapping_add(1);
        let obstacle = self.padded(obstacle);
        self.items
            .push((id, obstacle))
            .map_err(|_| ObstacleError::Full)?;
        Ok(id)
    }

    /// Replaces what is known of an obstacle (a new position, velocity or horizon): O(K).
    pub fn update(&mut self, id: ObstacleId, obstacle: Moving) -> Result<(), ObstacleError> {
        if !obstacle.is_valid() {
            return Err(ObstacleError::BadCircle);
        }
        let obstacle = self.padded(obstacle);
        let slot = self
            .items
            .iter_mut()
            .find(|(i, _)| *i == id)
            .ok_or(ObstacleError::UnknownId)?;
        slot.1 = obstacle;
        Ok(())
    }

    /// Removes the obstacle with this id and returns its disc.
    pub fn remove(&mut self, id: ObstacleId) -> Result<Circle, ObstacleError> {
        let pos = self
            .items
            .iter()
            .position(|(i, _)| *i == id)
            .ok_or(ObstacleError::UnknownId)?;
        let circle = self.items.swap_remove(pos).1.circle;
        Ok(self.unpadded(circle))
    }

    /// The disc of the obstacle with this id (as given, not grown by the pad).
    pub fn get(&self, id: ObstacleId) -> Option<Circle> {
        self.get_moving(id).map(|m| m.circle)
    }

    /// What is known of the obstacle with this id (its disc as given).
    pub fn get_moving(&self, id: ObstacleId) -> Option<Moving> {
        self.items
            .iter()
            .find(|(i, _)| *i == id)
            .map(|(_, m)| Moving {
                circle: self.unpadded(m.circle),
                ..*m
            })
    }

    /// The discs present with their ids (as given), in no particular order.
    pub fn iter(&self) -> impl Iterator<Item = (ObstacleId, Circle)> + '_ {
        self.items
            .iter()
            .map(|(i, m)| (*i, self.unpadded(m.circle)))
    }

    /// The obstacles present with their ids and motion, as a slice (discs grown by the pad).
    pub fn as_slice(&self) -> &[(ObstacleId, Moving)] {
        &self.items
    }

    /// Number of obstacles present.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether no obstacle is present.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Removes every obstacle.
    pub fn clear(&mut self) {
        self.items.clear();
    }

    /// The tree's test: whether any obstacle's sweep over the edge window meets `a-b` (the
    /// disc itself when still or with a window of 0).
    pub fn blocks_segment(&self, a: Point, b: Point) -> bool {
        self.blocks_within(a, b, self.window)
    }

    /// Whether any obstacle's sweep over `[0, window]` seconds meets `a-b`.
    #[inline(never)]
    pub fn blocks_within(&self, a: Point, b: Point, window: f32) -> bool {
        !self.items.is_empty() && sweeps_meet(&self.items, a, b, window, self.bound)
    }

    /// The tree's test: whether any obstacle's sweep over the edge window contains `p`.
    pub fn contains(&self, p: Point) -> bool {
        self.blocks_segment(p, p)
    }

    /// Whether any disc, where it is now, meets `a-b`.
    pub fn blocks_now(&self, a: Point, b: Point) -> bool {
        discs_meet(&self.items, a, b)
    }

    /// Whether any disc, where it is now, contains `p`.
    pub fn contains_now(&self, p: Point) -> bool {
        self.items.iter().any(|(_, m)| m.circle.contains(p))
    }
}

/// Whether any of `items` sweeps `a-b` over `[0, window]` (one copy for every capacity `K`;
/// also the waypoint rule's, module `motion`).
#[inline(never)]
pub(crate) fn sweeps_meet(
    items: &[(ObstacleId, Moving)],
    a: Point,
    b: Point,
    window: f32,
    bound: f32,
) -> bool {
    items
        .iter()
        .any(|(_, m)| m.sweep_meets(a, b, window, bound))
}

/// Whether any of `items`' discs, where they are now, meets `a-b`.
pub(crate) fn discs_meet(items: &[(ObstacleId, Moving)], a: Point, b: Point) -> bool {
    items.iter().any(|(_, m)| m.circle.intersects_segment(a, b))
}

/// Live cell edits (beyond the paper): a caller-owned bitmap in the grid's layout whose set
/// bits flip the borrowed grid's cells, so the live map is `grid XOR overlay`. A lidar marks a
/// free cell occupied or clears an occupied one ([`Map::set_cells`]); the static grid, and the
/// diffusion table baked from it, stay as they are. Each edit grows the box of cells changed
/// since the planner last repaired its trees (the planner takes it at its next call).
#[derive(Debug)]
pub struct Overlay<'a> {
    bits: &'a mut [u8],
    /// Cells flipped now (set bits), so a live map with none takes the grid's own test.
    flipped: u32,
    /// Cells flipped from free to occupied now.
    marked: u32,
    /// `[col0, row0, col1, row1]` of the cells changed since the last `take_changed`.
    changed: Option<[u16; 4]>,
}

/// The live occupancy the planner tests against: the grid with the overlay's cells flipped
/// (a copyable view; [`Map::live`]).
#[derive(Clone, Copy, Debug)]
pub struct Live<'a> {
    /// The grid tested: the static grid, or with a robot body its inflated live cells.
    grid: OccupancyGrid<'a>,
    /// The overlay's bits while it flips any cell.
    flip: Option<&'a [u8]>,
    /// With a robot body: the exact test a segment the inflated cells refuse gets.
    exact: Option<Exact<'a>>,
}

/// Where in a cell (fractions of its side from its lowest corner) a robot body's
/// [`Live::is_occupied`] looks for room: the centre and the middles of the four sides.
pub const ROOM_SAMPLES: [(f32, f32); 5] =
    [(0.5, 0.5), (0.5, 0.0), (0.0, 0.5), (1.0, 0.5), (0.5, 1.0)];

/// A robot body's exact test (module docs, "The robot's body"): a segment is free when it lies
/// in the map, keeps `reach` cells (the radius plus the contact margin) from the map's edge,
/// and keeps `reach` from the square of every occupied live cell (Euclidean, in cell units).
#[derive(Clone, Copy, Debug)]
struct Exact<'a> {
    /// The live cells as the world has them (no inflation).
    raw: OccupancyGrid<'a>,
    flip: Option<&'a [u8]>,
    /// The radius in cells plus the contact margin.
    reach: f32,
}

impl Exact<'_> {
    fn segment_free(&self, a: Point, b: Point) -> bool {
        self.segment_free_work(a, b).0
    }

    /// The test and its work: a unit per row of the band, per 8 cells of a run with an
    /// occupied cell, and per occupied cell measured.
    fn segment_free_work(&self, a: Point, b: Point) -> (bool, u32) {
        let g = &self.raw;
        if !g.contains(a) || !g.contains(b) {
            return (false, 1);
        }
        let (p, q) = (
            Point::new(a.x * g.inv_cell, a.y * g.inv_cell),
            Point::new(b.x * g.inv_cell, b.y * g.inv_cell),
        );
        let (w, h, k) = (f32::from(g.cols()), f32::from(g.rows()), self.reach);
        // The edge is a wall to the disc (a segment's nearest points to it are its ends).
        if p.x.min(q.x) < k || p.y.min(q.y) < k || w - p.x.max(q.x) < k || h - p.y.max(q.y) < k {
            return (false, 1);
        }
        let k2 = k * k;
        let mut work = 0u32;
        let free = g
            .for_each_span_within(a, b, k, |row, c0, c1| {
                work = work.saturating_add(1);
                let free = match self.flip {
                    None => g.span_free(row, c0, c1),
                    Some(f) => g.span_free_xor(row, c0, c1, f),
                };
                if free {
                    return ControlFlow::Continue(());
                }
                // Only the occupied cells of a run the thick segment's box touches are measured.
                work = work.saturating_add(u32::from(c1.saturating_sub(c0)) / 8);
                let clear = (c0..=c1).all(|col| {
                    let occupied = match self.flip {
                        None => !g.span_free(row, col, col),
                        Some(f) => !g.span_free_xor(row, col, col, f),
                    };
                    if !occupied {
                        return true;
                    }
                    work = work.saturating_add(1);
                    let (x, y) = (f32::from(col), f32::from(row));
                    segment_box_dist_sq(p, q, Point::new(x, y), Point::new(x + 1.0, y + 1.0)) >= k2
                });
                if clear {
                    ControlFlow::Continue(())
                } else {
                    ControlFlow::Break(())
                }
            })
            .is_continue();
        (free, work)
    }
}

impl<'a> Live<'a> {
    /// The grid under the edits (with a robot body: the inflated live cells, which hold
    /// the edits already).
    pub fn grid(&self) -> &OccupancyGrid<'a> {
        &self.grid
    }

    /// [`OccupancyGrid::segment_free`] on the live cells (one copy of the code: it is called
    /// from many places, and the firmware's flash is counted).
    /// With a robot body: free when the inflated cells pass it (the fast test), or else when
    /// the exact test does (near walls).
    #[inline(never)]
    pub fn segment_free(&self, a: Point, b: Point) -> bool {
        let fast = match self.flip {
            None => self.grid.segment_free(a, b),
            Some(f) => self.grid.segment_free_xor(a, b, f),
        };
        fast || self.exact.is_some_and(|e| e.segment_free(a, b))
    }

    /// [`Live::segment_free`] and the work units of its exact stage (0 when the first
    /// decides): what the planner charges a body's segment test beyond the point's.
    #[inline(never)]
    pub fn segment_free_work(&self, a: Point, b: Point) -> (bool, u32) {
        let fast = match self.flip {
            None => self.grid.segment_free(a, b),
            Some(f) => self.grid.segment_free_xor(a, b, f),
        };
        match self.exact {
            Some(e) if !fast => e.segment_free_work(a, b),
            _ => (fast, 0),
        }
    }

    /// [`OccupancyGrid::point_free`] on the live cells (with a body, as `segment_free`).
    #[inline(never)]
    pub fn point_free(&self, p: Point) -> bool {
        let fast = match self.flip {
            None => self.grid.point_free(p),
            Some(f) => self.grid.point_free_xor(p, f),
        };
        fast || self.exact.is_some_and(|e| e.segment_free(p, p))
    }

    /// Whether cell `(col, row)` is occupied now (outside the grid: occupied). With a robot
    /// body: whether the disc has no room in the cell, as far as [`ROOM_SAMPLES`] tell (the
    /// inflated cells, and for the margin they add next to walls the exact test at the
    /// cell's centre and the middles of its sides), so that a passage the disc fits through
    /// reads as open however the cells fall across it.
    pub fn is_occupied(&self, col: u16, row: u16) -> bool {
        let base = self.grid.is_occupied(col, row);
        let i = cell_index(col, row, self.grid.cols());
        let flipped = self
            .flip
            .and_then(|f| f.get(i / 8))
            .is_some_and(|b| b & (1 << (i % 8)) != 0);
        let occupied = base != (flipped && col < self.grid.cols() && row < self.grid.rows());
        match self.exact {
            Some(e) if occupied && col < self.grid.cols() && row < self.grid.rows() => {
                let cell = self.grid.cell_size();
                let corner = Point::new(f32::from(col) * cell, f32::from(row) * cell);
                !ROOM_SAMPLES.iter().any(|&(u, v)| {
                    let p = Point::new(corner.x + u * cell, corner.y + v * cell);
                    e.segment_free(p, p)
                })
            }
            _ => occupied,
        }
    }

    /// Whether free cell `(col, row)` lies in a passage at most about `2 * reach` cells wide:
    /// an occupied cell (or the map's edge) within `reach` cells on both sides, along its
    /// row or along its column.
    pub fn narrow_at(&self, col: u16, row: u16, reach: u16) -> bool {
        let side = |dc: i32, dr: i32| {
            (1..=i32::from(reach)).any(|k| {
                // |k| <= 65,535 and the cell's indices fit `u16`: no overflow in `i32`.
                let (c, r) = (
                    i32::from(col).wrapping_add(k.wrapping_mul(dc)),
                    i32::from(row).wrapping_add(k.wrapping_mul(dr)),
                );
                match (u16::try_from(c), u16::try_from(r)) {
                    (Ok(c), Ok(r)) => self.is_occupied(c, r),
                    _ => true,
                }
            })
        };
        (side(1, 0) && side(-1, 0)) || (side(0, 1) && side(0, -1))
    }

    /// Whether any cell is flipped (a live map that differs from its grid).
    pub fn edited(&self) -> bool {
        self.flip.is_some()
    }
}

/// Where the cells inflated for the robot's body live.
#[derive(Debug)]
enum Space<'a> {
    /// Inflated on the host and kept read-only (flash): [`Map::with_baked_body`].
    Baked(OccupancyGrid<'a>),
    /// Inflated into a caller-owned buffer, and kept up to date with the live cells:
    /// [`Map::with_body`].
    Buffer(&'a mut [u8]),
}

/// The robot's body: its radius, its disc rule and its inflated cells.
#[derive(Debug)]
struct Body<'a> {
    radius: f32,
    disc: Disc,
    space: Space<'a>,
}

/// The planner's world: a borrowed static grid, optionally a live [`Overlay`] of edited cells,
/// a robot body (the cells inflated for its radius), and up to `K` dynamic circles.
#[derive(Debug)]
pub struct Map<'a, const K: usize> {
    grid: OccupancyGrid<'a>,
    overlay: Option<Overlay<'a>>,
    body: Option<Body<'a>>,
    /// The clearance field, a byte per cell ([`crate::clearance`]).
    clearance: Option<&'a [u8]>,
    obstacles: Obstacles<K>,
}

impl<'a, const K: usize> Map<'a, K> {
    /// A world with this grid and no dynamic obstacle.
    pub const fn new(grid: OccupancyGrid<'a>) -> Self {
        Self {
            grid,
            overlay: None,
            body: None,
            clearance: None,
            obstacles: Obstacles::new(),
        }
    }

    /// This world with a clearance field (a byte per cell, row-major: written by
    /// [`crate::clearance::clearance_field`] into RAM, or baked into flash), which a
    /// configuration's [`crate::Config::clearance_weight`] turns into a preference for paths
    /// away from walls. Errors when `field` holds fewer bytes than the grid has cells.
    pub fn with_clearance(mut self, field: &'a [u8]) -> Result<Self, MapError> {
        let n = usize::from(self.grid.cols()).saturating_mul(usize::from(self.grid.rows()));
        self.clearance = Some(field.get(..n).ok_or(MapError::FieldTooShort)?);
        Ok(self)
    }

    /// Whether the map carries a clearance field ([`Map::with_clearance`]).
    pub fn has_clearance(&self) -> bool {
        self.clearance.is_some()
    }

    /// The clearance class (0-7) of segment `a-b` and the work it took
    /// ([`crate::clearance::class_of`]); `(0, 0)` without a clearance field.
    pub fn clearance_class(&self, a: Point, b: Point) -> (u8, u32) {
        match self.clearance {
            Some(f) => crate::clearance::class_of(&self.grid, f, a, b),
            None => (0, 0),
        }
    }

    /// This world for a robot that is a disc of `radius` metres: the live cells are inflated
    /// into `buffer` (caller-owned, at least [`OccupancyGrid::bytes_needed`] bytes; in RAM, as
    /// live cell edits re-inflate it when they are submitted) by the rule of [`inflate`], and
    /// every test of the map ([`Map::free_path`], [`Map::free_now`], [`Map::free_point`],
    /// [`Map::live`]) is then the disc's. The dynamic circles grow by the radius when the
    /// planner is made ([`Obstacles::set_pad`]). A radius of 0 leaves the map as it is.
    /// Errors as [`inflate`] does.
    pub fn with_body(mut self, radius: f32, buffer: &'a mut [u8]) -> Result<Self, MapError> {
        let flip = self.overlay.as_ref().map(|o| &*o.bits);
        inflate_live(&self.grid, flip, radius, &mut *buffer)?;
        if radius > 0.0 {
            let n = OccupancyGrid::bytes_needed(self.grid.cols(), self.grid.rows());
            self.body = Some(Body {
                radius,
                disc: Disc::new(radius, self.grid.cell_size()),
                space: Space::Buffer(buffer.get_mut(..n).ok_or(MapError::BufferTooShort)?),
            });
        }
        Ok(self)
    }

    /// This world for a robot whose disc the grid `space` was inflated for on the host
    /// ([`inflate`], then [`OccupancyGrid::inflated_for`]: `host-sim export` writes it), kept
    /// read-only (flash). Live cell edits then need [`Map::with_body`] instead. Errors when
    /// `space` differs from the grid in size or cell size.
    pub fn with_baked_body(mut self, space: OccupancyGrid<'a>) -> Result<Self, MapError> {
        let g = &self.grid;
        if space.cols() != g.cols()
            || space.rows() != g.rows()
            || space.cell_size().to_bits() != g.cell_size().to_bits()
        {
            return Err(MapError::BodyMismatch);
        }
        let radius = space.inflation();
        if radius > 0.0 {
            self.body = Some(Body {
                radius,
                disc: Disc::new(radius, g.cell_size()),
                space: Space::Baked(space),
            });
        }
        Ok(self)
    }

    /// The grid and the body a metric table is baked for: the static grid, its
    /// [`OccupancyGrid::inflation`] the body's radius (what `Planner::new` checks a table
    /// against: [`crate::metric::map_hash`]).
    pub fn metric_grid(&self) -> OccupancyGrid<'a> {
        OccupancyGrid {
            inflation: self.radius(),
            ..self.grid
        }
    }

    /// The robot's radius in metres the map is inflated for (0: a point).
    pub fn radius(&self) -> f32 {
        self.body.as_ref().map_or(0.0, |b| b.radius)
    }

    /// This world with live cell edits in `bits`, a caller-owned buffer of at least
    /// [`OccupancyGrid::bytes_needed`] bytes (the grid's size again: 23 KB for a 604 x 307
    /// nav2 map), which is cleared: the live map starts as the grid.
    pub fn with_overlay(mut self, bits: &'a mut [u8]) -> Result<Self, MapError> {
        let n = OccupancyGrid::bytes_needed(self.grid.cols(), self.grid.rows());
        let Some(used) = bits.get_mut(..n) else {
            return Err(MapError::BufferTooShort);
        };
        used.fill(0);
        self.overlay = Some(Overlay {
            bits: used,
            flipped: 0,
            marked: 0,
            changed: None,
        });
        Ok(self)
    }

    /// The live cells: the grid with the overlay's edits, inflated for the robot's body.
    pub fn live(&self) -> Live<'_> {
        if let Some(body) = &self.body {
            let grid = match &body.space {
                Space::Baked(g) => *g,
                Space::Buffer(bits) => OccupancyGrid {
                    bits,
                    inflation: body.radius,
                    ..self.grid
                },
            };
            let raw = self.raw_live();
            let exact = Exact {
                raw: raw.grid,
                flip: raw.flip,
                reach: body.radius * self.grid.inv_cell + CONTACT_MARGIN,
            };
            return Live {
                grid,
                flip: None,
                exact: Some(exact),
            };
        }
        self.raw_live()
    }

    /// Whether the map carries a live overlay ([`Map::with_overlay`]).
    pub fn has_overlay(&self) -> bool {
        self.overlay.is_some()
    }

    /// Cells the overlay turned from free to occupied, now.
    pub fn marked_cells(&self) -> u32 {
        self.overlay.as_ref().map_or(0, |o| o.marked)
    }

    /// Sets every cell of the rectangle with corners `a` and `b` (`(col, row)`, inclusive, in
    /// any order) occupied or free in the live map: O(cells). Returns how many cells changed.
    /// Errors, changing nothing, without an overlay or with a corner outside the grid. The
    /// planner's own [`crate::Planner::set_cells`] also repairs its trees at the next call.
    pub fn set_cells(
        &mut self,
        a: (u16, u16),
        b: (u16, u16),
        occupied: bool,
    ) -> Result<u32, MapError> {
        let grid = self.grid;
        let Some(o) = self.overlay.as_mut() else {
            return Err(MapError::NoOverlay);
        };
        if matches!(
            self.body,
            Some(Body {
                space: Space::Baked(_),
                ..
            })
        ) {
            return Err(MapError::BodyInFlash);
        }
        let (w, h) = (grid.cols(), grid.rows());
        if a.0 >= w || b.0 >= w || a.1 >= h || b.1 >= h {
            return Err(MapError::CellOutside);
        }
        let (c0, c1) = (a.0.min(b.0), a.0.max(b.0));
        let (r0, r1) = (a.1.min(b.1), a.1.max(b.1));
        let mut changed = 0u32;
        for row in r0..=r1 {
            for col in c0..=c1 {
                let i = cell_index(col, row, w);
                let Some(byte) = o.bits.get_mut(i / 8) else {
                    continue;
                };
                let bit = 1u8 << (i % 8);
                let base = grid.is_occupied(col, row);
                if (base != (*byte & bit != 0)) == occupied {
                    continue;
                }
                *byte ^= bit;
                let now_flipped = *byte & bit != 0;
                o.flipped = if now_flipped {
                    o.flipped.saturating_add(1)
                } else {
                    o.flipped.saturating_sub(1)
                };
                if !base {
                    o.marked = if occupied {
                        o.marked.saturating_add(1)
                    } else {
                        o.marked.saturating_sub(1)
                    };
                }
                changed = changed.saturating_add(1);
                o.changed = Some(match o.changed {
                    None => [col, row, col, row],
                    Some([x0, y0, x1, y1]) => [x0.min(col), y0.min(row), x1.max(col), y1.max(row)],
                });
            }
        }
        // A body's inflated cells follow at once: every cell within the disc's reach of the
        // edited rectangle is marked again from the live cells, and the planner re-tests the
        // edges near that grown box.
        if let (
            Some(Body {
                disc,
                space: Space::Buffer(out),
                ..
            }),
            true,
        ) = (self.body.as_mut(), changed > 0)
        {
            let flip = &*o.bits;
            let occupied = |row: u16, c0: u16, c1: u16| !grid.span_free_xor(row, c0, c1, flip);
            let grown = disc.grow([c0, r0, c1, r1], w, h);
            disc.mark_box(out, w, h, grown, &occupied);
            let [g0, h0, g1, h1] = grown;
            o.changed = Some(match o.changed {
                None => grown,
                Some([x0, y0, x1, y1]) => [x0.min(g0), y0.min(h0), x1.max(g1), y1.max(h1)],
            });
        }
        Ok(changed)
    }

    /// The box `[col0, row0, col1, row1]` of the cells changed since the last call, and forgets
    /// it (the planner re-tests the edges near it).
    pub(crate) fn take_changed(&mut self) -> Option<[u16; 4]> {
        self.overlay.as_mut().and_then(|o| o.changed.take())
    }

    /// The static occupancy grid.
    pub const fn grid(&self) -> &OccupancyGrid<'a> {
        &self.grid
    }

    /// The dynamic obstacles.
    pub const fn obstacles(&self) -> &Obstacles<K> {
        &self.obstacles
    }

    /// The dynamic obstacles, mutably (adding one does not update any tree by itself: the
    /// planner's own `add_obstacle` does that).
    pub fn obstacles_mut(&mut self) -> &mut Obstacles<K> {
        &mut self.obstacles
    }

    /// `free_path(a, b)` of the paper: the segment is inside the map, touches no occupied cell
    /// and meets no dynamic circle (for a moving one: its sweep over the edge window,
    /// [`Obstacles::blocks_segment`]).
    pub fn free_path(&self, a: Point, b: Point) -> bool {
        self.live().segment_free(a, b) && !self.obstacles.blocks_segment(a, b)
    }

    /// [`Map::free_path`] and the work units of a body's exact stage
    /// ([`Live::segment_free_work`]).
    pub fn free_path_work(&self, a: Point, b: Point) -> (bool, u32) {
        let (free, work) = self.live().segment_free_work(a, b);
        (free && !self.obstacles.blocks_segment(a, b), work)
    }

    /// Whether the segment is inside the map, touches no occupied cell and meets no dynamic
    /// disc where it is now (not its sweep: [`Obstacles::blocks_now`]).
    pub fn free_now(&self, a: Point, b: Point) -> bool {
        self.live().segment_free(a, b) && !self.obstacles.blocks_now(a, b)
    }

    /// Whether a single position is free (the degenerate segment `p-p`).
    pub fn free_point(&self, p: Point) -> bool {
        self.live().point_free(p) && !self.obstacles.blocks_segment(p, p)
    }

    /// Whether `p` is in a wall: occupied in the grid and not cleared by the overlay. A cell
    /// the overlay marked is not a wall (it may clear again, like a person who stands still).
    pub fn in_wall(&self, p: Point) -> bool {
        !self.grid.point_free(p) && !self.live().point_free(p)
    }

    /// Validates a position given at the API edge: finite, inside the map, not in an obstacle
    /// (a dynamic one where it is now, or a marked cell, is not: a goal on a person's way is
    /// still a goal), and with a body, with room for the disc among the static walls
    /// ([`InputError::NoRoom`]).
    pub fn check_point(&self, p: Point) -> Result<(), InputError> {
        if !p.is_finite() {
            Err(InputError::NotFinite)
        } else if !self.grid.contains(p) {
            Err(InputError::OutOfBounds)
        } else if self.in_wall(p) || self.obstacles.contains_now(p) {
            Err(InputError::InObstacle)
        } else if !self.static_room(p) {
            Err(InputError::NoRoom)
        } else {
            Ok(())
        }
    }

    /// Whether the body's disc fits at `p` among the static grid's walls (the exact test on
    /// the grid: live edits do not count).
    fn static_room(&self, p: Point) -> bool {
        self.body.as_ref().is_none_or(|body| {
            Exact {
                raw: self.grid,
                flip: None,
                reach: body.radius * self.grid.inv_cell + CONTACT_MARGIN,
            }
            .segment_free(p, p)
        })
    }

    /// Whether a robot disc of the map's radius, moved along `a-b`, keeps that radius from
    /// every occupied live cell and the map's edge and meets no dynamic disc where it is now:
    /// exact distances from the segment to each cell's square (shrunk by 1e-4 cell, for the
    /// rounding of a driven position), not the planner's inflated grid. With no body, whether
    /// the point's segment stays out of every occupied cell's interior. The agent protocol
    /// counts a move that fails it as a collision ([`crate::agent`]). O(cells of the
    /// segment's box grown by the radius).
    pub fn body_clear(&self, a: Point, b: Point) -> bool {
        let g = &self.grid;
        let r = self.radius();
        let cell = g.cell_size();
        let tau = 1.0e-4 * cell;
        let inset = (r - tau).max(0.0);
        let inside = |p: Point| {
            p.is_finite()
                && p.x >= inset
                && p.y >= inset
                && p.x <= g.width_m() - inset
                && p.y <= g.height_m() - inset
        };
        if !inside(a) || !inside(b) || self.obstacles.blocks_now(a, b) {
            return false;
        }
        let reach = r + cell;
        let (lo, hi) = (
            Point::new(a.x.min(b.x) - reach, a.y.min(b.y) - reach),
            Point::new(a.x.max(b.x) + reach, a.y.max(b.y) + reach),
        );
        let (Some((c0, r0)), Some((c1, r1))) = (
            g.cell_of(Point::new(lo.x.max(0.0), lo.y.max(0.0))),
            g.cell_of(Point::new(hi.x.min(g.width_m()), hi.y.min(g.height_m()))),
        ) else {
            return false;
        };
        let live = self.raw_live();
        let r2 = r * r;
        (r0..=r1).all(|row| {
            (c0..=c1).all(|col| {
                if !live.is_occupied(col, row) {
                    return true;
                }
                let (x, y) = (f32::from(col) * cell, f32::from(row) * cell);
                let d2 = segment_box_dist_sq(
                    a,
                    b,
                    Point::new(x + tau, y + tau),
                    Point::new(x + cell - tau, y + cell - tau),
                );
                if r > 0.0 { d2 >= r2 } else { d2 > 0.0 }
            })
        })
    }

    /// The live cells as the world has them (the grid with the overlay's edits, no body).
    fn raw_live(&self) -> Live<'_> {
        Live {
            grid: self.grid,
            flip: self
                .overlay
                .as_ref()
                .filter(|o| o.flipped > 0)
                .map(|o| &*o.bits),
            exact: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_with<'a>(buf: &'a mut [u8], w: u16, h: u16, occ: &[(u16, u16)]) -> OccupancyGrid<'a> {
        pack_grid(buf, w, h, |c, r| occ.contains(&(c, r))).unwrap();
        OccupancyGrid::new(buf, w, h, 1.0).unwrap()
    }

    #[test]
    fn constructor_rejects_bad_grids() {
        let buf = [0u8; 2];
        assert_eq!(
            OccupancyGrid::new(&buf, 0, 4, 1.0).unwrap_err(),
            MapError::EmptyGrid
        );
        assert_eq!(
            OccupancyGrid::new(&buf, 5, 4, 1.0).unwrap_err(),
            MapError::BufferTooShort
        );
        assert_eq!(
            OccupancyGrid::new(&buf, 4, 4, 0.0).unwrap_err(),
            MapError::BadCellSize
        );
        assert_eq!(
            OccupancyGrid::new(&buf, 4, 4, f32::NAN).unwrap_err(),
            MapError::BadCellSize
        );
        assert!(OccupancyGrid::new(&buf, 4, 4, 0.5).is_ok());
    }

    #[test]
    fn diagonal_through_a_shared_corner_is_blocked() {
        let mut buf = [0u8; 2];
        // Occupied (1, 0) and (0, 1) share the corner (1, 1).
        let g = grid_with(&mut buf, 4, 4, &[(1, 0), (0, 1)]);
        assert!(!g.segment_free(Point::new(0.5, 0.5), Point::new(1.5, 1.5)));
        // The other diagonal through the same corner also touches both cells.
        assert!(!g.segment_free(Point::new(0.5, 1.5), Point::new(1.5, 0.5)));
        // A segment that stays clear of both is free.
        assert!(g.segment_free(Point::new(2.5, 0.5), Point::new(3.5, 3.5)));
    }

    #[test]
    fn grazing_an_edge_counts_as_touching() {
        let mut buf = [0u8; 2];
        let g = grid_with(&mut buf, 4, 4, &[(1, 1)]);
        // Along the top edge of cell (1, 1) (the line y = 1).
        assert!(!g.segment_free(Point::new(0.2, 1.0), Point::new(3.8, 1.0)));
        // Just clear of it.
        assert!(g.segment_free(Point::new(0.2, 0.99), Point::new(3.8, 0.99)));
        // Vertical along x = 2 touches the right edge of (1, 1).
        assert!(!g.segment_free(Point::new(2.0, 0.5), Point::new(2.0, 3.5)));
        assert!(g.segment_free(Point::new(2.01, 0.5), Point::new(2.01, 3.5)));
    }

    /// Issue 41: on the MovingAI maze at 0.5 m the simulator counted a collision for goal 3's
    /// call 666, a step from (99.72903, 50.000484) to (99.02903, 50.000843) that runs 0.48-0.84
    /// mm above the wall cells' edge at y = 50 m. A nearly flat segment (its rise under the
    /// contact margin) was tested against its whole x-range in every row it comes near, so
    /// the wall cell (198, 99), which the segment passes 1.2 mm above, was found "touched"
    /// though only the step's first 0.04 cells come within the margin, above the free cell
    /// (199, 99). The longer segment the planner had checked passed; its sub-segment did not.
    #[test]
    fn regression_maze512_flat_step_graze() {
        let (w, h) = (256u16, 128u16);
        let mut buf = [0u8; OccupancyGrid::bytes_needed(256, 128)];
        // Row 99 (y in [49.5, 50) m) is a wall up to column 198; column 199 is free.
        pack_grid(&mut buf, w, h, |c, r| r == 99 && c <= 198).unwrap();
        let g = OccupancyGrid::new(&buf, w, h, 0.5).unwrap();
        let (a, b) = (
            Point::new(99.72903, 50.000484),
            Point::new(99.02903, 50.000843),
        );
        assert!(
            g.segment_free(a, b),
            "the step stays clear of the wall cell"
        );
        assert!(g.segment_free(b, a));
        // The parent segment the planner tested (further along the same line) passes too.
        let far = a + (b - a) * 1.5;
        assert!(g.segment_free(a, far));
        // Any piece of a segment that passes passes (sub-segments of the step).
        for k in 1..20 {
            let m = a.lerp(b, k as f32 / 20.0);
            assert!(g.segment_free(a, m) && g.segment_free(m, b), "{k}");
        }
        // A flat segment that really comes within the margin of the wall cell is blocked.
        let low = Point::new(99.3, 50.0001);
        assert!(!g.segment_free(a, low));
    }

    /// Issue 7, case 3: a subnormal cell size (1e-40) was accepted and `1 / cell` was infinite.
    #[test]
    fn regression_subnormal_and_overflowing_cell_sizes_are_refused() {
        let bits = [0u8; 2];
        for cell in [1.0e-40, f32::MIN_POSITIVE / 8.0, 1.0e38, f32::MAX] {
            assert_eq!(
                OccupancyGrid::new(&bits, 4, 4, cell).unwrap_err(),
                MapError::BadCellSize,
                "{cell}"
            );
        }
        let g = OccupancyGrid::new(&bits, 4, 4, 1.0e19).unwrap();
        assert!(g.width_m().is_finite());
        assert!(g.segment_free(Point::new(1.0e19, 1.0e19), Point::new(3.0e19, 2.0e19)));
    }

    #[test]
    fn bounds_and_nan_are_not_free() {
        let mut buf = [0u8; 2];
        let g = grid_with(&mut buf, 4, 4, &[]);
        assert!(g.segment_free(Point::new(0.0, 0.0), Point::new(4.0, 4.0)));
        assert!(!g.segment_free(Point::new(0.5, 0.5), Point::new(4.5, 0.5)));
        assert!(!g.segment_free(Point::new(f32::NAN, 0.5), Point::new(1.0, 0.5)));
        assert!(!g.point_free(Point::new(-0.001, 1.0)));
        assert_eq!(g.cell_of(Point::new(4.0, 4.0)), Some((3, 3)));
    }

    #[test]
    fn circle_uses_the_segment_distance() {
        let c = Circle::new(Point::new(5.0, 0.0), 1.0);
        // The infinite line through the segment passes through the centre; the segment does not.
        assert!(!c.intersects_segment(Point::new(0.0, 0.0), Point::new(3.9, 0.0)));
        assert!(c.intersects_segment(Point::new(0.0, 0.0), Point::new(4.0, 0.0)));
        assert!(c.intersects_segment(Point::new(4.0, -3.0), Point::new(4.0, 3.0)));
        assert!(!c.intersects_segment(Point::new(3.9, -3.0), Point::new(3.9, 3.0)));
    }

    #[test]
    fn obstacle_set_is_bounded_and_ids_are_stable() {
        let mut o = Obstacles::<2>::new();
        let a = o.add(Circle::new(Point::new(1.0, 1.0), 0.5)).unwrap();
        let b = o.add(Circle::new(Point::new(2.0, 1.0), 0.5)).unwrap();
        assert_ne!(a, b);
        assert_eq!(
            o.add(Circle::new(Point::new(3.0, 1.0), 0.5)),
            Err(ObstacleError::Full)
        );
        assert_eq!(
            o.add(Circle::new(Point::new(3.0, 1.0), -1.0)),
            Err(ObstacleError::BadCircle)
        );
        assert_eq!(o.remove(a).unwrap().center, Point::new(1.0, 1.0));
        assert_eq!(o.remove(a), Err(ObstacleError::UnknownId));
        let c = o.add(Circle::new(Point::new(3.0, 1.0), 0.5)).unwrap();
        assert!(c != a && c != b);
        assert_eq!(o.get(b).unwrap().center, Point::new(2.0, 1.0));
        assert_eq!(o.len(), 2);
    }

    #[test]
    fn map_checks_points_at_the_edge() {
        let mut buf = [0u8; 2];
        let mut m = Map::<'_, 4>::new(grid_with(&mut buf, 4, 4, &[(3, 3)]));
        assert_eq!(
            m.check_point(Point::new(f32::NAN, 1.0)),
            Err(InputError::NotFinite)
        );
        assert_eq!(
            m.check_point(Point::new(5.0, 1.0)),
            Err(InputError::OutOfBounds)
        );
        assert_eq!(
            m.check_point(Point::new(3.5, 3.5)),
            Err(InputError::InObstacle)
        );
        assert_eq!(m.check_point(Point::new(1.5, 1.5)), Ok(()));
        m.obstacles_mut()
            .add(Circle::new(Point::new(1.5, 1.5), 0.2))
            .unwrap();
        assert_eq!(
            m.check_point(Point::new(1.5, 1.5)),
            Err(InputError::InObstacle)
        );
        assert!(!m.free_path(Point::new(0.5, 1.5), Point::new(2.5, 1.5)));
    }

    #[test]
    fn narrow_cells_have_walls_on_both_sides_within_reach() {
        // A 12 x 6 grid: a wall at column 6 from row 0 to row 3; a post at (2, 4).
        let mut buf = [0u8; OccupancyGrid::bytes_needed(12, 6)];
        let occ = [(6, 0), (6, 1), (6, 2), (6, 3), (2, 4)];
        let g = grid_with(&mut buf, 12, 6, &occ);
        let live = Map::<'_, 1>::new(g);
        let live = live.live();
        // (2, 5): the map's top edge and the post, each one cell away along the column.
        assert!(live.narrow_at(2, 5, 1));
        // (2, 3): the post 1 up, the bottom edge 4 down; the left edge 3 away, the wall 4.
        assert!(live.narrow_at(2, 3, 4) && !live.narrow_at(2, 3, 3));
        // (5, 1): the wall beside it but the left edge 6 away; the bottom edge 2 down, the
        // top edge 5 up: narrow along its column at reach 5.
        assert!(live.narrow_at(5, 1, 5) && !live.narrow_at(5, 1, 4));
        // (9, 5): the top edge above, the bottom edge 6 below; the row is open 10 cells left.
        assert!(live.narrow_at(9, 5, 6) && !live.narrow_at(9, 5, 5));
        // An occupied cell's own test is about its neighbours only (callers test it first).
        assert!(live.narrow_at(6, 1, 6));
    }
}
