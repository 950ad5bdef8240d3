//! Sampling of the states a tree grows towards (paper Algorithm 2, `SampleState`, and its
//! equation for `X_s`; RT-RRT*'s goal-line sampling).
//!
//! With `p` uniform in `[0, 1)`:
//! - `p > p_goal` while the goal is set but not yet in the tree: the goal itself (AM-RRT*), or
//!   a uniform point of the segment from the goal's nearest node to the goal (RT-RRT*);
//! - else, `p < p_uniform`, or no goal, or the goal not in the tree: a uniform free state;
//! - else: a uniform free state in the informed ellipse (foci root and goal, diameter the goal's
//!   current cost).
//!
//! Free states come by rejection, bounded by `attempts`; a draw that keeps failing returns
//! `None` and the expansion is simply skipped.
//!
//! With `p_gap` (the tuned set) it also draws, once the goal is in the tree, states in narrow passages of
//! the informed ellipse ([`narrow_free`]: rejection among ellipse draws for a cell with walls on
//! both sides within a few cells, after the narrow-passage samplers of PRM, e.g. the bridge
//! test of Hsu et al. 2003, here a direct test of the cell's row and column).

use rand_core::Rng;

use crate::geometry::{Ellipse, Point, unit_f32};
use crate::map::Map;

/// What the sampler needs to know about the tree's goal.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GoalView {
    /// The goal position.
    pub goal: Point,
    /// Whether the goal is already a node of the tree.
    pub in_tree: bool,
    /// The informed ellipse once a path to the goal exists (`None`: no usable bound).
    pub ellipse: Option<Ellipse>,
    /// RT-RRT*: the tree node nearest the goal, the far end of the goal line.
    pub line_from: Option<Point>,
}

/// A uniform free state of the map, or `None` after `attempts` rejected draws.
pub fn uniform_free<R: Rng + ?Sized, const K: usize>(
    rng: &mut R,
    map: &Map<'_, K>,
    attempts: u16,
) -> Option<Point> {
    let (w, h) = (map.grid().width_m(), map.grid().height_m());
    (0..attempts).find_map(|_| {
        let p = Point::new(unit_f32(rng) * w, unit_f32(rng) * h);
        map.free_point(p).then_some(p)
    })
}

/// A uniform free state inside `ellipse`, or `None` after `attempts` rejected draws.
pub fn ellipse_free<R: Rng + ?Sized, const K: usize>(
    rng: &mut R,
    map: &Map<'_, K>,
    ellipse: &Ellipse,
    attempts: u16,
) -> Option<Point> {
    (0..attempts).find_map(|_| {
        let p = ellipse.sample(rng);
        map.free_point(p).then_some(p)
    })
}

/// Ellipse draws until one is a free state in a narrow passage (a cell with occupied cells
/// within `reach` cells on both sides along its row or its column), at most `attempts` of
/// them. Returns that state (`None` if no draw was narrow), the first free state drawn (the
/// fallback when none was narrow) and the number of draws made. Before each further
/// [`NARROW_BATCH`] draws, `go_on(NARROW_BATCH)` is asked whether to continue (the caller
/// charges the draws and looks at its deadline); on `false` the draws stop with neither state.
pub fn narrow_free<R: Rng + ?Sized, const K: usize>(
    rng: &mut R,
    map: &Map<'_, K>,
    ellipse: &Ellipse,
    reach: u16,
    attempts: u16,
    mut go_on: impl FnMut(u16) -> bool,
) -> (Option<Point>, Option<Point>, u16) {
    let live = map.live();
    let grid = map.grid();
    let mut first = None;
    for n in 0..attempts {
        if n > 0 && n % NARROW_BATCH == 0 && !go_on(NARROW_BATCH) {
            return (None, None, n);
        }
        let p = ellipse.sample(rng);
        let Some((c, r)) = grid.cell_of(p) else {
            continue;
        };
        if live.is_occupied(c, r) {
            continue;
        }
        if live.narrow_at(c, r, reach) && map.free_point(p) {
            return (Some(p), first, n.saturating_add(1));
        }
        if first.is_none() && map.free_point(p) {
            first = Some(p);
        }
    }
    (None, first, attempts)
}

/// Draws [`narrow_free`] makes between two questions to its caller.
pub const NARROW_BATCH: u16 = 16;

/// One draw of `X_s` (module docs). `p_goal` and `p_uniform` are the two thresholds.
pub(crate) fn sample_state<R: Rng + ?Sized, const K: usize>(
    rng: &mut R,
    map: &Map<'_, K>,
    goal: Option<&GoalView>,
    p_goal: f32,
    p_uniform: f32,
    attempts: u16,
) -> Option<Point> {
    let p = unit_f32(rng);
    let Some(g) = goal else {
        return uniform_free(rng, map, attempts);
    };
    if p > p_goal && !g.in_tree {
        return match g.line_from {
            Some(from) => Some(from.lerp(g.goal, unit_f32(rng))),
            None => Some(g.goal),
        };
    }
    if p < p_uniform || !g.in_tree {
        return uniform_free(rng, map, attempts);
    }
    match &g.ellipse {
        Some(e) => ellipse_free(rng, map, e, attempts).or_else(|| uniform_free(rng, map, attempts)),
        None => uniform_free(rng, map, attempts),
    }
}

/// A `rand_core` 0.6 generator (what most HAL drivers of hardware random generators
/// implement) as the `rand_core` 0.10 [`Rng`] the planner takes (feature `rand-core-06`):
/// `Rng06(hal_rng)`. Hardware generators are slow and never repeat a run; seeding a software
/// generator once from one (`XorShiftRng::from_seed`) is usually the better choice.
#[cfg(feature = "rand-core-06")]
#[derive(Debug)]
pub struct Rng06<R>(pub R);

#[cfg(feature = "rand-core-06")]
impl<R: rand_core_06::RngCore> rand_core::TryRng for Rng06<R> {
    type Error = core::convert::Infallible;

    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        Ok(self.0.next_u32())
    }

    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        Ok(self.0.next_u64())
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        self.0.fill_bytes(dst);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{OccupancyGrid, pack_grid};
    use rand_core::SeedableRng;

    /// A 40 x 20 grid at 0.1 m: a wall at column 20 with a slit of rows 9-10; the ellipse
    /// spans the whole width.
    #[test]
    fn narrow_draws_land_in_the_slit_and_inside_the_ellipse() {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(40, 20)];
        pack_grid(&mut bits, 40, 20, |c, r| c == 20 && !(9..=10).contains(&r)).unwrap();
        let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 40, 20, 0.1).unwrap());
        let e = Ellipse::new(Point::new(0.5, 1.0), Point::new(3.5, 1.0), 3.4).unwrap();
        let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(3);
        let (mut narrow, mut fallbacks) = (0, 0);
        for _ in 0..200 {
            let (n, first, draws) = narrow_free(&mut rng, &map, &e, 2, 256, |_| true);
            assert!((1..=256).contains(&draws));
            match n {
                Some(p) => {
                    narrow += 1;
                    assert!(e.contains(p) && map.free_point(p));
                    // Reach 2: only the slit's two cells have walls on both sides (the
                    // wall's ends above and below them); beside the wall, the row is open.
                    let (c, r) = map.grid().cell_of(p).unwrap();
                    assert!(c == 20 && (9..=10).contains(&r), "({c}, {r})");
                }
                None => {
                    fallbacks += 1;
                    assert_eq!(draws, 256);
                    assert!(first.is_some_and(|p| e.contains(p) && map.free_point(p)));
                }
            }
        }
        // The slit is 2 of about 430 cells in the ellipse: 256 draws find it 70 % of the time.
        assert!(
            narrow > 40 && fallbacks > 10,
            "{narrow} narrow, {fallbacks} fallbacks"
        );
    }

    /// Issue 42: on a Cortex-M4F the tuned set's gap samples (256 draws, 22 us each) ran
    /// 5.8 ms without a look at the clock and calls overran by as much. The draws now ask
    /// their caller every [`NARROW_BATCH`]: on an open map (no narrow cell) all 256 draws ask
    /// 15 times, and a caller that says stop after the first batch gets nothing.
    #[test]
    fn regression_gap_samples_ask_their_caller_between_batches() {
        let bits = [0u8; OccupancyGrid::bytes_needed(40, 20)];
        let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 40, 20, 0.1).unwrap());
        let e = Ellipse::new(Point::new(0.5, 1.0), Point::new(3.5, 1.0), 3.4).unwrap();
        let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(5);
        let mut asked = 0u32;
        let (n, first, draws) = narrow_free(&mut rng, &map, &e, 2, 256, |b| {
            assert_eq!(b, NARROW_BATCH);
            asked += 1;
            true
        });
        assert_eq!((n, draws, asked), (None, 256, 15));
        assert!(first.is_some());
        let (n, first, draws) = narrow_free(&mut rng, &map, &e, 2, 256, |_| false);
        assert_eq!((n, first, draws), (None, None, NARROW_BATCH));
    }
}
