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

mod body;
pub mod clearance;
mod grid;
mod live;
mod obstacles;

pub use body::inflate;
pub use grid::{CONTACT_MARGIN, OccupancyGrid, pack_grid};
pub use live::{Live, Overlay, ROOM_SAMPLES};
pub use obstacles::{Circle, Moving, ObstacleId, Obstacles};

use body::{Disc, inflate_live};
use grid::segment_box_dist_sq;
use live::Exact;
pub(crate) use obstacles::{discs_meet, sweeps_meet};

use crate::error::{InputError, MapError};
use crate::geometry::Point;
use crate::slots::cell_index;

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
///
/// Every position (the agent, goals, obstacles' centres, waypoints) is in the grid's frame:
/// metres from the corner of cell `(0, 0)`, `x` along columns, `y` along rows
/// ([`OccupancyGrid`]'s frame).
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
    /// [`crate::map::clearance::clearance_field`] into RAM, or baked into flash), which a
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
    /// ([`crate::map::clearance::class_of`]); `(0, 0)` without a clearance field.
    pub fn clearance_class(&self, a: Point, b: Point) -> (u8, u32) {
        match self.clearance {
            Some(f) => crate::map::clearance::class_of(&self.grid, f, a, b),
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
mod tests;
