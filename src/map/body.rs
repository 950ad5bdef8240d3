//! The robot's body, fast stage (the module's "The robot's body"): the disc rule and the grid
//! inflated by it.

use super::*;
use crate::error::MapError;
use crate::slots::{cell_index, sat_u32, to_u16};

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
    pub(super) fn new(radius: f32, cell: f32) -> Self {
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
    pub(super) fn mark_box(
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
    pub(super) fn grow(&self, bx: [u16; 4], width: u16, height: u16) -> [u16; 4] {
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
pub(super) fn inflate_live<'b>(
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
