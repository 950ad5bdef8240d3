//! Moving obstacles (beyond the paper): the waypoint rule of Algorithm 1 generalised from
//! circles that stay put to obstacles that move with a reported velocity
//! ([`crate::map::Moving`]) and an agent with a stated top speed ([`crate::config::Motion`]).
//!
//! The paper hands the agent the root when the segment to it meets no circle present. Here a
//! point `q` is *clear* for an agent at `a` when
//!
//! 1. the segment `a-q` is free of the map;
//! 2. it meets no obstacle's sweep ([`crate::map::Moving::sweep`]) over
//!    `[0, |q - a| / agent_speed + period + horizon]`: the time the agent needs to drive it at
//!    its top speed, the wait there until the next call, and the `horizon` it keeps clear
//!    after that (so it gives way to what is predicted to cross its way soon);
//! 3. its first `agent_speed * period` metres (where the agent can be before the next call)
//!    meet no disc grown by `obstacle_speed * period`, or, for an agent already within such a
//!    disc, head away from its centre by at least that growth per metre: wherever an
//!    obstacle turns without notice, within the stated top speed, the agent's move never
//!    brings it nearer the obstacle than holding would, before it plans again.
//!
//! Clearness is monotone along a segment (a nearer `q` has a shorter segment and a shorter
//! window, so a smaller sweep to miss; rule 3's heading does not depend on `q`'s distance), so the farthest clear point of a segment is found by
//! bisection. The choice, made last in every `plan` call ([`choose`]):
//!
//! - the planned waypoint (the root) when it is clear;
//! - else, when the segment to it is free now and only the prediction blocks it, the farthest
//!   clear point of that segment (the agent moves up and stops short of the crossing);
//! - else the agent holds when its own position is clear ([`crate::Wait::GivingWay`]);
//! - else it evades ([`crate::Status::Evading`]): among points 1, 4 and 10 periods' drive away
//!   in [`ESCAPES`] directions, and the agent's own position, the one whose first contact with
//!   an obstacle comes latest (clear at least while it drives there); among those clear for
//!   the drive and the full window, the nearest the planned waypoint. An escape is judged by
//!   timing, not by the whole sweep: against where each obstacle is when the agent, driving
//!   at its top speed, is where it is (rules 1 and 3 still hold), so a step aside counts when
//!   the agent has left the spot before the obstacle gets there;
//! - when none is clear even for the drive alone, the agent holds
//!   ([`crate::Wait::Cornered`]): an obstacle may run into it, it does not drive into one.
//!
//! With still circles and nothing stated ([`crate::config::Motion::NONE`]) rule 2 is the
//! paper's test and rule 3 that the agent is outside every circle: the choice is the paper's.
//! The work is bounded: at most `3 ESCAPES + BISECTIONS + 3` tests of the `K` obstacles (an
//! escape's: three pieces of relative motion each) and as many grid segments; the planner
//! keeps time for it before its deadline ([`RULE_UNITS`] per obstacle).

// Plain `f32` arithmetic on points (no integers): nothing here can overflow or panic.
#![allow(clippy::arithmetic_side_effects)]

use crate::config::Motion;
use crate::geometry::{Point, segment_point_dist_sq};
use crate::map::{Live, Map, Moving, ObstacleId, discs_meet, sweeps_meet};

/// Escape points tried round the agent when it can neither go on nor hold.
pub const ESCAPES: u16 = 16;

/// The escapes' directions: the unit vectors at multiples of 22.5 degrees (a table: no
/// trigonometry, whose range reduction alone is 2.5 KB of flash).
const DIRECTIONS: [Point; ESCAPES as usize] = {
    const C1: f32 = 0.923_879_5; // cos 22.5
    const C2: f32 = core::f32::consts::FRAC_1_SQRT_2; // cos 45
    const C3: f32 = 0.382_683_43; // cos 67.5
    [
        Point::new(1.0, 0.0),
        Point::new(C1, C3),
        Point::new(C2, C2),
        Point::new(C3, C1),
        Point::new(0.0, 1.0),
        Point::new(-C3, C1),
        Point::new(-C2, C2),
        Point::new(-C1, C3),
        Point::new(-1.0, 0.0),
        Point::new(-C1, -C3),
        Point::new(-C2, -C2),
        Point::new(-C3, -C1),
        Point::new(0.0, -1.0),
        Point::new(C3, -C1),
        Point::new(C2, -C2),
        Point::new(C1, -C3),
    ]
};

/// Work units the planner keeps per obstacle for this rule before its deadline (the escapes'
/// tests: about 50 candidates, three pieces each, plus their grid segments).
pub const RULE_UNITS: u64 = 48;

/// Bisection steps for the farthest clear point of a segment.
const BISECTIONS: u16 = 12;

/// Escape distances, in periods of driving at the top speed.
const REACHES: [f32; 3] = [1.0, 4.0, 10.0];

/// What the waypoint rule chose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Choice {
    /// The planned waypoint is clear.
    Planned,
    /// The farthest clear point on the way to the planned waypoint.
    Shortened(Point),
    /// The agent holds: its position is clear, the way is not.
    Hold,
    /// A point off the way that stays clear longer than holding would.
    Evade(Point),
    /// Nothing is clear: the agent holds.
    Cornered,
}

/// The rule's view of one call: the grid, the obstacles, their top speed past a prediction
/// and the stated motion (not generic over the map's capacity: one copy of the code).
struct Rule<'a> {
    cells: Live<'a>,
    obstacles: &'a [(ObstacleId, Moving)],
    bound: f32,
    motion: &'a Motion,
}

impl<'a> Rule<'a> {
    fn of<const K: usize>(map: &'a Map<'_, K>, motion: &'a Motion) -> Self {
        Self {
            cells: map.live(),
            obstacles: map.obstacles().as_slice(),
            bound: map.obstacles().sweep().1,
            motion,
        }
    }

    /// The segment is free of the map and of every disc where it is now.
    fn free_now(&self, a: Point, b: Point) -> bool {
        self.cells.segment_free(a, b) && !discs_meet(self.obstacles, a, b)
    }

    /// Seconds to drive `d` metres at the top speed (0 when no speed is stated).
    fn drive(&self, d: f32) -> f32 {
        if self.motion.agent_speed > 0.0 {
            d / self.motion.agent_speed
        } else {
            0.0
        }
    }

    /// Rule 3: the first period's drive along `a-q` meets no disc grown by what its obstacle
    /// can cover in a period at the stated top speed, or, for an agent already inside such a
    /// disc, heads away from it: `(q - a) . (a - c) >= |q - a| g` with `g` that growth, so
    /// that at every instant the agent is farther from any position the obstacle can take
    /// than it would be holding (a step that is never worse than holding).
    fn first_period(&self, a: Point, q: Point) -> bool {
        let m = self.motion;
        let (d, reach) = (a.dist(q), m.agent_speed * m.period);
        let prefix = if d > reach && d > 0.0 {
            a.lerp(q, reach / d)
        } else {
            q
        };
        let grow = m.obstacle_speed * m.period;
        !self.obstacles.iter().any(|&(_, Moving { circle: c, .. })| {
            let r = c.radius + grow;
            segment_point_dist_sq(a, prefix, c.center) <= r * r
                && !(d > 0.0 && (q - a).dot(a - c.center) >= d * grow && !c.contains(a))
        })
    }

    /// Whether `a-q` is clear with `extra` seconds kept clear after the drive: rules 1-3 of
    /// the module docs (the full rule is `extra = period + horizon`).
    fn clear(&self, a: Point, q: Point, extra: f32) -> bool {
        let window = self.drive(a.dist(q)) + extra;
        self.cells.segment_free(a, q)
            && !sweeps_meet(self.obstacles, a, q, window, self.bound)
            && self.first_period(a, q)
    }

    /// Rules 1 and 3 for a candidate escape
    /// (and the segment free of every disc where it is now, as every waypoint is).
    fn passable(&self, a: Point, q: Point) -> bool {
        self.free_now(a, q) && self.first_period(a, q)
    }

    /// Evasion's test: like [`Rule::clear`], but against where each obstacle is when the
    /// agent, driving `a-q` at its top speed and then waiting at `q`, is where it is (the
    /// relative motion, piece by piece), not against the whole sweep: a step aside counts when
    /// the agent has left the spot before the obstacle gets there. Returns the first time
    /// (seconds from now) any obstacle touches the agent, or `end` when none does before.
    /// Rules 1 and 3 are checked once per candidate ([`Rule::passable`]), not here.
    fn first_contact(&self, a: Point, q: Point, end: f32) -> f32 {
        let t_drive = self.drive(a.dist(q)).min(end);
        let at = |t: f32| {
            if t_drive > 0.0 && t < t_drive {
                a.lerp(q, t / t_drive)
            } else {
                q
            }
        };
        let bound = self.bound;
        let mut first = end;
        for (_, o) in self.obstacles {
            let h = o.trusted_for;
            let place = |t: f32| o.circle.center + o.velocity * t.min(h);
            // Pieces end where a motion changes: the end of the drive and of the prediction.
            let (c0, c1) = (t_drive, h.min(end));
            let mut t0 = 0.0f32;
            for t1 in [c0.min(c1), c0.max(c1), end] {
                if t0 >= first {
                    break;
                }
                // The radius at the piece's end (it only grows): conservative within it.
                let r = o.circle.radius + bound * (t1 - h).max(0.0);
                let p0 = at(t0) - place(t0);
                let d = at(t1) - place(t1) - p0;
                let (aa, b, c) = (d.dot(d), p0.dot(d), p0.dot(p0) - r * r);
                let s = if c <= 0.0 {
                    Some(0.0)
                } else if aa > 0.0 && b < 0.0 && b * b - aa * c >= 0.0 {
                    let s = (-b - crate::geometry::sqrt(b * b - aa * c)) / aa;
                    (s <= 1.0).then_some(s.max(0.0))
                } else {
                    None
                };
                if let Some(s) = s {
                    first = first.min(t0 + s * (t1 - t0));
                }
                t0 = t1;
            }
        }
        first
    }
}

/// The waypoint rule (module docs) for an agent at `agent` whose planned waypoint is
/// `planned` (the root, or the agent's own position when it holds).
pub fn choose<const K: usize>(
    map: &Map<'_, K>,
    motion: &Motion,
    agent: Point,
    planned: Point,
) -> Choice {
    decide(&Rule::of(map, motion), agent, planned)
}

/// [`choose`] on the rule's view.
#[inline(never)]
fn decide(rule: &Rule<'_>, agent: Point, planned: Point) -> Choice {
    let motion = rule.motion;
    let full = motion.period + motion.horizon;
    if rule.clear(agent, planned, full) {
        return Choice::Planned;
    }
    if planned != agent && rule.free_now(agent, planned) {
        // Bisection on the fraction of the way: `lo` clear, `hi` not.
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if rule.clear(agent, agent.lerp(planned, mid), full) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let q = agent.lerp(planned, lo);
        let cell = rule.cells.grid().cell_size();
        // `lo` > 0 was tested clear in the loop.
        if lo > 0.0 && q.dist_sq(agent) > 1e-4 * cell * cell {
            return Choice::Shortened(q);
        }
    }
    if rule.clear(agent, agent, full) {
        return Choice::Hold;
    }
    // Evade: the candidate whose first contact comes latest (clear during the drive at
    // least); among those clear for the drive and the full window, the nearest the planned
    // waypoint.
    let step = motion.agent_speed * motion.period;
    let mut best: Option<(f32, f32, Point)> = None;
    // The agent's own position first, then the escapes.
    let spots = core::iter::once(None).chain(DIRECTIONS.iter().map(Some));
    for dir in spots {
        let reaches = if dir.is_none() || step <= 0.0 {
            1
        } else {
            REACHES.len()
        };
        for &k in REACHES.iter().take(reaches) {
            let q = match dir {
                Some(&u) if step > 0.0 => agent + u * (step * k),
                _ => agent,
            };
            if !rule.passable(agent, q) {
                continue;
            }
            let drive = rule.drive(agent.dist(q));
            let end = drive + full;
            let contact = rule.first_contact(agent, q, end);
            if contact <= drive {
                continue;
            }
            // Clear for the whole window: rank by nearness, ahead of every partial one.
            let (time, near) = if contact >= end {
                (f32::INFINITY, -q.dist_sq(planned))
            } else {
                (contact, 0.0)
            };
            if best.is_none_or(|(t, n, _)| time > t || (time == t && near > n)) {
                best = Some((time, near, q));
            }
        }
        if step <= 0.0 {
            break;
        }
    }
    match best {
        Some((_, _, q)) if q == agent => Choice::Hold,
        Some((_, _, q)) => Choice::Evade(q),
        None => Choice::Cornered,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{Circle, Moving, OccupancyGrid};

    /// An open 10 m x 10 m map of 0.1 m cells.
    fn open() -> OccupancyGrid<'static> {
        static BITS: [u8; OccupancyGrid::bytes_needed(100, 100)] =
            [0; OccupancyGrid::bytes_needed(100, 100)];
        OccupancyGrid::new(&BITS, 100, 100, 0.1).unwrap()
    }

    fn walking() -> Motion {
        Motion {
            agent_speed: 1.0,
            period: 0.1,
            horizon: 1.0,
            obstacle_speed: 1.5,
        }
    }

    #[test]
    fn still_circles_with_nothing_stated_keep_the_papers_rule() {
        let mut map: Map<'_, 4> = Map::new(open());
        map.obstacles_mut()
            .add(Circle::new(Point::new(5.0, 5.0), 0.5))
            .unwrap();
        let (a, none) = (Point::new(2.0, 5.0), Motion::NONE);
        assert_eq!(
            choose(&map, &none, a, Point::new(8.0, 8.0)),
            Choice::Planned
        );
        // Blocked now: the agent holds (no creeping up to a circle that stays).
        assert_eq!(choose(&map, &none, a, Point::new(8.0, 5.0)), Choice::Hold);
        assert_eq!(choose(&map, &none, a, a), Choice::Planned);
    }

    #[test]
    fn a_crossing_walker_shortens_the_way() {
        let mut map: Map<'_, 4> = Map::new(open());
        let m = walking();
        map.obstacles_mut().set_sweep(m.horizon, m.obstacle_speed);
        // A walker 3 m below the way, crossing it at 1 m/s.
        let walker = Moving::new(Circle::new(Point::new(5.0, 2.0), 0.5), Point::new(0.0, 1.0));
        map.obstacles_mut().add_moving(walker).unwrap();
        let (a, root) = (Point::new(2.0, 5.0), Point::new(8.0, 5.0));
        // Still, it would not be in the way.
        assert!(map.free_now(a, root));
        // On a collision course (both at x = 5 at t = 3 s): the way is clear up to where the
        // walker's line is within its radius, x = 4.5 (its sweep over the drive and 1.1 s
        // reaches y = 4.5 from x = 3.4 on).
        match choose(&map, &m, a, root) {
            Choice::Shortened(q) => {
                assert!(
                    (q.y - 5.0).abs() < 1e-4 && q.x > 4.45 && q.x <= 4.5,
                    "{q:?}"
                );
            }
            other => panic!("{other:?}"),
        }
        // Once it has passed (moving away, its sweep behind the way), the root is clear.
        let past = Moving::new(Circle::new(Point::new(5.0, 6.0), 0.5), Point::new(0.0, 1.0));
        let mut map2: Map<'_, 4> = Map::new(open());
        map2.obstacles_mut().set_sweep(m.horizon, m.obstacle_speed);
        map2.obstacles_mut().add_moving(past).unwrap();
        assert_eq!(choose(&map2, &m, a, root), Choice::Planned);
    }

    #[test]
    fn a_walker_head_on_makes_the_agent_step_aside() {
        let mut map: Map<'_, 4> = Map::new(open());
        let m = walking();
        map.obstacles_mut().set_sweep(m.horizon, m.obstacle_speed);
        // 1.2 m ahead, walking at the agent at 1.5 m/s (faster than the agent).
        let walker = Moving::new(
            Circle::new(Point::new(6.2, 5.0), 0.4),
            Point::new(-1.5, 0.0),
        );
        map.obstacles_mut().add_moving(walker).unwrap();
        let a = Point::new(5.0, 5.0);
        match choose(&map, &m, a, a) {
            Choice::Evade(q) => {
                // Aside: off the walker's line by more than its radius once there.
                assert!((q.y - 5.0).abs() > 0.4, "{q:?}");
                let rule = Rule::of(&map, &m);
                let drive = rule.drive(a.dist(q));
                assert!(rule.first_contact(a, q, drive + 1.0) > drive, "{q:?}");
                assert!(map.free_now(a, q));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn regression_within_reach_the_agent_may_step_away() {
        let mut map: Map<'_, 4> = Map::new(open());
        let m = walking();
        map.obstacles_mut().set_sweep(m.horizon, m.obstacle_speed);
        // Still, but 0.6 m away with radius 0.5: within 0.5 + 0.15 of the agent.
        let c = Point::new(5.6, 5.0);
        map.obstacles_mut().add(Circle::new(c, 0.5)).unwrap();
        let a = Point::new(5.0, 5.0);
        let rule = Rule::of(&map, &m);
        assert!(!rule.first_period(a, a), "holding is within its reach");
        assert!(rule.first_period(a, Point::new(4.0, 5.0)), "straight away");
        assert!(
            !rule.first_period(a, Point::new(5.0, 6.0)),
            "sideways is not away enough"
        );
        assert!(!rule.first_period(a, Point::new(5.3, 5.0)), "towards it");
    }
}
