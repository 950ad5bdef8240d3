//! Built-in scenarios: small maps made of rectangles, packed into bit grids at compile time so
//! they live in flash, with a start and goals. They are the simulator's default scenarios, the
//! firmware example's map and the test suite's fixtures (the paper's reference maps are test
//! data read from outside the project).
//!
//! - [`OPEN`]: a 40 m field with three boxes.
//! - [`BUG_TRAP`]: a 60 m map with a cup around the start that opens away from the goal, the
//!   classic trap for greedy (Euclidean) guidance.
//! - [`MAZE`]: a 60 m map of walls with alternating gaps.
//!
//! Three more are of the paper's sizes (Section V: Bug_trap and Maze 100 m x 100 m, Office
//! 200 m x 200 m, six goals each), drawn here after the paper's description, not copies of its
//! maps: [`TRAP_100`], [`MAZE_100`], [`OFFICE_200`] ([`PAPER_SIZED`]). They let a user try the
//! paper's experiments without any map file.

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

const TRAP_100_BLOCKS: &[Block] = &[
    // The cup around the start, open towards small y, with a lip at each side of the opening.
    b(28, 22, 31, 78),
    b(69, 22, 72, 78),
    b(28, 75, 72, 78),
    b(31, 22, 42, 25),
    b(58, 22, 69, 25),
    // Clutter outside the cup.
    b(8, 8, 20, 16),
    b(80, 10, 92, 30),
    b(6, 40, 16, 62),
    b(84, 50, 94, 66),
    b(10, 84, 24, 94),
    b(40, 86, 60, 90),
    b(78, 84, 92, 94),
];

const MAZE_100_BLOCKS: &[Block] = &[
    // Four long walls, their gaps alternating between the right and the left edge.
    b(0, 18, 84, 21),
    b(16, 38, 100, 41),
    b(0, 58, 84, 61),
    b(16, 78, 100, 81),
    // Stubs that make the corridors turn.
    b(48, 0, 51, 10),
    b(60, 21, 63, 30),
    b(30, 41, 33, 50),
    b(22, 61, 25, 70),
    b(66, 61, 69, 70),
    b(40, 88, 43, 100),
];

#[rustfmt::skip] // four blocks a line: one wing in three lines
const OFFICE_200_BLOCKS: &[Block] = &[
    // Two 12 m corridors cross in the middle. Each wing: a corridor wall with a door per room,
    // a wall along the other corridor with one door, three rooms, each split in two by a wall
    // with a door.
    // North-west wing.
    b(0, 92, 12, 94), b(20, 92, 44, 94), b(52, 92, 76, 94), b(84, 92, 94, 94),
    b(92, 0, 94, 60), b(92, 68, 94, 92), b(30, 0, 32, 92), b(62, 0, 64, 92),
    b(0, 45, 20, 47), b(27, 45, 52, 47), b(59, 45, 84, 47), b(91, 45, 92, 47),
    // North-east wing.
    b(188, 92, 200, 94), b(156, 92, 180, 94), b(124, 92, 148, 94), b(106, 92, 116, 94),
    b(106, 0, 108, 60), b(106, 68, 108, 92), b(168, 0, 170, 92), b(136, 0, 138, 92),
    b(180, 45, 200, 47), b(148, 45, 173, 47), b(116, 45, 141, 47), b(108, 45, 109, 47),
    // South-west wing.
    b(0, 106, 12, 108), b(20, 106, 44, 108), b(52, 106, 76, 108), b(84, 106, 94, 108),
    b(92, 140, 94, 200), b(92, 108, 94, 132), b(30, 108, 32, 200), b(62, 108, 64, 200),
    b(0, 153, 20, 155), b(27, 153, 52, 155), b(59, 153, 84, 155), b(91, 153, 92, 155),
    // South-east wing.
    b(188, 106, 200, 108), b(156, 106, 180, 108), b(124, 106, 148, 108), b(106, 106, 116, 108),
    b(106, 140, 108, 200), b(106, 108, 108, 132), b(168, 108, 170, 200), b(136, 108, 138, 200),
    b(180, 153, 200, 155), b(148, 153, 173, 155), b(116, 153, 141, 155), b(108, 153, 109, 155),
    // Desks.
    b(8, 15, 22, 22), b(40, 60, 54, 70), b(140, 20, 160, 28), b(70, 120, 84, 128),
    b(150, 165, 162, 185), b(176, 120, 190, 128),
];

/// A 100 m x 100 m bug trap of the paper's size: start inside a cup that opens away from the
/// first goal, clutter outside it.
pub static TRAP_100: Scenario = Scenario {
    name: "trap_100",
    grid: grid!(TRAP_100_BITS, 100, 100, TRAP_100_BLOCKS),
    blocks: TRAP_100_BLOCKS,
    start: Point::new(50.0, 60.0),
    goals: &[
        Point::new(50.0, 95.0),
        Point::new(4.0, 4.0),
        Point::new(96.0, 40.0),
        Point::new(50.0, 45.0),
        Point::new(20.0, 70.0),
        Point::new(96.0, 96.0),
    ],
    sigma: 50.0,
};

/// A 100 m x 100 m maze of the paper's size: five corridors joined at alternating ends.
pub static MAZE_100: Scenario = Scenario {
    name: "maze_100",
    grid: grid!(MAZE_100_BITS, 100, 100, MAZE_100_BLOCKS),
    blocks: MAZE_100_BLOCKS,
    start: Point::new(50.0, 50.0),
    goals: &[
        Point::new(92.0, 92.0),
        Point::new(5.0, 5.0),
        Point::new(95.0, 30.0),
        Point::new(8.0, 70.0),
        Point::new(60.0, 8.0),
        Point::new(25.0, 92.0),
    ],
    sigma: 30.0,
};

/// A 200 m x 200 m office of the paper's size: four wings of six rooms round two corridors.
pub static OFFICE_200: Scenario = Scenario {
    name: "office_200",
    grid: grid!(OFFICE_200_BITS, 200, 200, OFFICE_200_BLOCKS),
    blocks: OFFICE_200_BLOCKS,
    start: Point::new(100.0, 30.0),
    goals: &[
        Point::new(180.0, 180.0),
        Point::new(15.0, 30.0),
        Point::new(150.0, 70.0),
        Point::new(40.0, 170.0),
        Point::new(100.0, 190.0),
        Point::new(185.0, 20.0),
    ],
    sigma: 30.0,
};

/// The small built-in scenarios (the firmware's and the tests' fixtures).
pub static ALL: [&Scenario; 3] = [&OPEN, &BUG_TRAP, &MAZE];

/// The built-in scenarios of the paper's sizes.
pub static PAPER_SIZED: [&Scenario; 3] = [&TRAP_100, &MAZE_100, &OFFICE_200];

/// Every built-in scenario: [`ALL`], then [`PAPER_SIZED`].
pub fn every() -> impl Iterator<Item = &'static Scenario> {
    ALL.iter().chain(PAPER_SIZED.iter()).copied()
}

/// The built-in scenario with this name (small or paper-sized).
pub fn by_name(name: &str) -> Option<&'static Scenario> {
    every().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_and_goals_are_free() {
        for s in every() {
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
