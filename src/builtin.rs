//! Built-in scenarios: small maps made of rectangles, packed into bit grids at compile time so
//! they live in flash, with a start and goals. They are the simulator's default scenarios, the
//! firmware example's map and the test suite's fixtures (the paper's reference maps are test
//! data read from outside the project).
//!
//! - [`OPEN`]: a 40 m field with three boxes.
//! - [`BUG_TRAP`]: a 60 m map with a cup around the start that opens away from the goal, the
//!   classic trap for greedy (Euclidean) guidance.
//! - [`MAZE`]: a 60 m map of walls with alternating gaps.

use crate::geometry::Point;
use crate::map::OccupancyGrid;

/// An axis-aligned block of occupied cells: columns `x0..x1`, rows `y0..y1` (ends excluded).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// First column.
    pub x0: u16,
    /// First row.
    pub y0: u16,
    /// Column past the last.
    pub x1: u16,
    /// Row past the last.
    pub y1: u16,
}

const fn b(x0: u16, y0: u16, x1: u16, y1: u16) -> Block {
    Block { x0, y0, x1, y1 }
}

/// Packs blocks into the bit layout of [`OccupancyGrid`] at compile time. `BYTES` must be
/// `ceil(width * height / 8)`.
#[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)] // const-evaluated for the built-in statics: a bad block fails the build
pub const fn pack_blocks<const BYTES: usize>(
    width: u16,
    height: u16,
    blocks: &[Block],
) -> [u8; BYTES] {
    assert!(
        BYTES == OccupancyGrid::bytes_needed(width, height),
        "BYTES must match the grid"
    );
    let mut bits = [0u8; BYTES];
    let mut k = 0;
    while k < blocks.len() {
        let blk = blocks[k];
        let mut y = blk.y0;
        while y < blk.y1 && y < height {
            let mut x = blk.x0;
            while x < blk.x1 && x < width {
                let i = y as usize * width as usize + x as usize;
                bits[i / 8] |= 1 << (i % 8);
                x += 1;
            }
            y += 1;
        }
        k += 1;
    }
    bits
}

/// A built-in scenario: a map, a start and a sequence of goals.
#[derive(Clone, Copy, Debug)]
pub struct Scenario {
    /// Short name.
    pub name: &'static str,
    /// The map (in flash).
    pub grid: OccupancyGrid<'static>,
    /// Blocks the map is made of.
    pub blocks: &'static [Block],
    /// Start position.
    pub start: Point,
    /// Goals, visited in order.
    pub goals: &'static [Point],
    /// Suggested connection distance of the two trees.
    pub sigma: f32,
}

macro_rules! grid {
    ($bits:ident, $w:expr, $h:expr, $blocks:expr) => {{
        static $bits: [u8; OccupancyGrid::bytes_needed($w, $h)] = pack_blocks($w, $h, $blocks);
        match OccupancyGrid::new(&$bits, $w, $h, 1.0) {
            Ok(g) => g,
            Err(_) => panic!("built-in grid"),
        }
    }};
}

const OPEN_BLOCKS: &[Block] = &[b(10, 10, 14, 14), b(24, 6, 27, 20), b(15, 26, 30, 29)];

const BUG_TRAP_BLOCKS: &[Block] = &[
    // The cup: two side walls and a bottom, open towards small y.
    b(18, 14, 20, 44),
    b(40, 14, 42, 44),
    b(18, 42, 42, 44),
    // A lip at each side of the opening.
    b(20, 14, 24, 16),
    b(36, 14, 40, 16),
];

const MAZE_BLOCKS: &[Block] = &[
    b(0, 12, 48, 14),
    b(12, 24, 60, 26),
    b(0, 36, 48, 38),
    b(12, 48, 60, 50),
    b(30, 0, 32, 8),
    b(24, 38, 26, 44),
];

/// A 40 m x 40 m field with three boxes.
pub static OPEN: Scenario = Scenario {
    name: "open",
    grid: grid!(OPEN_BITS, 40, 40, OPEN_BLOCKS),
    blocks: OPEN_BLOCKS,
    start: Point::new(3.0, 3.0),
    goals: &[
        Point::new(36.0, 35.0),
        Point::new(5.0, 36.0),
        Point::new(35.0, 4.0),
    ],
    sigma: 30.0,
};

/// A 60 m x 60 m bug trap: start inside the cup, goal beyond its bottom.
pub static BUG_TRAP: Scenario = Scenario {
    name: "bug_trap",
    grid: grid!(BUG_TRAP_BITS, 60, 60, BUG_TRAP_BLOCKS),
    blocks: BUG_TRAP_BLOCKS,
    start: Point::new(30.0, 36.0),
    goals: &[
        Point::new(30.0, 54.0),
        Point::new(5.0, 5.0),
        Point::new(55.0, 30.0),
    ],
    sigma: 50.0,
};

/// A 60 m x 60 m maze of walls with alternating gaps.
pub static MAZE: Scenario = Scenario {
    name: "maze",
    grid: grid!(MAZE_BITS, 60, 60, MAZE_BLOCKS),
    blocks: MAZE_BLOCKS,
    start: Point::new(5.0, 5.0),
    goals: &[
        Point::new(55.0, 55.0),
        Point::new(55.0, 5.0),
        Point::new(5.0, 30.0),
    ],
    sigma: 30.0,
};

/// All built-in scenarios.
pub static ALL: [&Scenario; 3] = [&OPEN, &BUG_TRAP, &MAZE];

/// The built-in scenario with this name.
pub fn by_name(name: &str) -> Option<&'static Scenario> {
    ALL.iter().copied().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_and_goals_are_free() {
        for s in ALL {
            assert!(s.grid.point_free(s.start), "{}", s.name);
            for g in s.goals {
                assert!(s.grid.point_free(*g), "{} {g:?}", s.name);
            }
        }
        assert!(BUG_TRAP.grid.is_occupied(19, 30));
        assert!(!BUG_TRAP.grid.is_occupied(30, 30));
        // The trap: no straight line from the start to the goal.
        assert!(
            !BUG_TRAP
                .grid
                .segment_free(BUG_TRAP.start, BUG_TRAP.goals[0])
        );
    }
}
