//! The occupancy grid (the module's "Occupancy grid" and "What `free_path` means"): a
//! borrowed bit-packed grid and its exact segment test.

use core::ops::ControlFlow;

use crate::error::MapError;
use crate::geometry::{Point, segment_point_dist_sq};
use crate::slots::{cell_index, sat_u32, to_u16};

/// Safety margin of the grid collision test, in cells (see the module documentation).
pub const CONTACT_MARGIN: f32 = 1.0e-3;

/// A read-only occupancy grid borrowing its bit-packed cells.
///
/// **Frame.** Positions are in metres from the corner of cell `(0, 0)`: `x` along the columns,
/// `y` along the rows, so `(x, y)` lies in cell `(floor(x / cell), floor(y / cell))` and the map
/// spans `[0, width * cell] x [0, height * cell]`. Row 0 is the first row of the bytes: for a
/// map drawn as an image, its top row, so `y` grows downwards (`host-sim` converts a ROS map's
/// frame, `y` up from its `origin`, to this one). Bit layout: the module documentation.
#[derive(Clone, Copy, Debug)]
pub struct OccupancyGrid<'a> {
    pub(super) bits: &'a [u8],
    pub(super) width: u16,
    pub(super) height: u16,
    pub(super) cell: f32,
    pub(super) inv_cell: f32,
    /// The robot radius (metres) these cells were inflated for ([`inflate`]); 0 for a grid of
    /// the world as it is.
    pub(super) inflation: f32,
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
    /// rule of [`inflate`](crate::map::inflate) (a grid that [`inflate`](crate::map::inflate) wrote on the host, kept in flash: what
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
    pub(super) fn point_free_xor(&self, p: Point, flip: &[u8]) -> bool {
        self.point_spans_free(p, |row, c0, c1| self.span_free_xor(row, c0, c1, flip))
    }

    /// [`Self::segment_free`] with the cells of `flip` (same layout) flipped ([`Overlay`]).
    pub(super) fn segment_free_xor(&self, a: Point, b: Point, flip: &[u8]) -> bool {
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
    pub(super) fn for_each_span_within<F>(
        &self,
        a: Point,
        b: Point,
        margin: f32,
        mut f: F,
    ) -> ControlFlow<()>
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
    pub(super) fn span_free(&self, row: u16, c0: u16, c1: u16) -> bool {
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
    pub(super) fn span_free_xor(&self, row: u16, c0: u16, c1: u16, flip: &[u8]) -> bool {
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

/// Squared distance from segment `a-b` to the closed box `[lo, hi]` (0 when they meet).
pub(super) fn segment_box_dist_sq(a: Point, b: Point, lo: Point, hi: Point) -> f32 {
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
