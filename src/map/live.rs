//! Live cells (the module's "Live cells") and the body's exact test on them.

use core::ops::ControlFlow;

use super::*;
use crate::geometry::Point;
use crate::slots::cell_index;

/// Live cell edits (beyond the paper): a caller-owned bitmap in the grid's layout whose set
/// bits flip the borrowed grid's cells, so the live map is `grid XOR overlay`. A lidar marks a
/// free cell occupied or clears an occupied one ([`Map::set_cells`]); the static grid, and the
/// diffusion table baked from it, stay as they are. Each edit grows the box of cells changed
/// since the planner last repaired its trees (the planner takes it at its next call).
#[derive(Debug)]
pub struct Overlay<'a> {
    pub(super) bits: &'a mut [u8],
    /// Cells flipped now (set bits), so a live map with none takes the grid's own test.
    pub(super) flipped: u32,
    /// Cells flipped from free to occupied now.
    pub(super) marked: u32,
    /// `[col0, row0, col1, row1]` of the cells changed since the last `take_changed`.
    pub(super) changed: Option<[u16; 4]>,
}

/// The live occupancy the planner tests against: the grid with the overlay's cells flipped
/// (a copyable view; [`Map::live`]).
#[derive(Clone, Copy, Debug)]
pub struct Live<'a> {
    /// The grid tested: the static grid, or with a robot body its inflated live cells.
    pub(super) grid: OccupancyGrid<'a>,
    /// The overlay's bits while it flips any cell.
    pub(super) flip: Option<&'a [u8]>,
    /// With a robot body: the exact test a segment the inflated cells refuse gets.
    pub(super) exact: Option<Exact<'a>>,
}

/// Where in a cell (fractions of its side from its lowest corner) a robot body's
/// [`Live::is_occupied`] looks for room: the centre and the middles of the four sides.
pub const ROOM_SAMPLES: [(f32, f32); 5] =
    [(0.5, 0.5), (0.5, 0.0), (0.0, 0.5), (1.0, 0.5), (0.5, 1.0)];

/// A robot body's exact test (module docs, "The robot's body"): a segment is free when it lies
/// in the map, keeps `reach` cells (the radius plus the contact margin) from the map's edge,
/// and keeps `reach` from the square of every occupied live cell (Euclidean, in cell units).
#[derive(Clone, Copy, Debug)]
pub(super) struct Exact<'a> {
    /// The live cells as the world has them (no inflation).
    pub(super) raw: OccupancyGrid<'a>,
    pub(super) flip: Option<&'a [u8]>,
    /// The radius in cells plus the contact margin.
    pub(super) reach: f32,
}

impl Exact<'_> {
    pub(super) fn segment_free(&self, a: Point, b: Point) -> bool {
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
