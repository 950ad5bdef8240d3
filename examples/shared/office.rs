//! The exported scenario's mission in real time, shared by the firmware example
//! (`examples/firmware.rs`, Cortex-M4F) and the Cortex-M0+ build (`firmware/m0-twin`): the
//! planner flies the scenario's goal 1 (or, exported with `--all-goals`, all its goals in
//! turn) on the clock it is given, and prints the per-call times, the path and its
//! checksum. The including crate provides `scenario` (the `host-sim export` statics) and
//! `hprintln!` at its root. Also built for RISC-V (`firmware/riscv-twin`'s `office`). The
//! mission is the export's (`host-sim export --planners tuned|paper --all-goals --walkers N
//! --door`: `scenario::TUNED`, `ALL_GOALS`, `WALKERS`, `DOOR`), not a build-time variable.
//!
//! Exported with `--walkers n` (1-4), `n` people pace to and fro at 1 m/s across
//! the straight line from the start to goal 1 (6 m either side, evenly along it); before every
//! call their positions and velocities are submitted (`update_obstacle`) under a stated motion
//! (issue 27: the cost of moving obstacles on the chip). One protocol call is 0.5 s of the
//! world's time (the agent's 0.7 m a call is 1.4 m/s).
//!
//! Exported with `--door` the map gets a live overlay (a buffer of the grid's size
//! on the stack): a door of 3 x 13 cells across the line from the start to goal 1, halfway,
//! closes (`set_cells`) when the agent comes within 15 m of it and opens 40 calls later (issue
//! 27: the cost of live cells on the chip).

// `WALKERS` and `DOOR` are the export's constants: comparing them is what leaves a build
// without walkers or a door free of their code.
#![allow(clippy::absurd_extreme_comparisons)]

use bi_am_rrt::agent::{Protocol, run_to_goal};
use bi_am_rrt::clock::Clock;
use bi_am_rrt::map::ObstacleId;
use bi_am_rrt::metric::fnv1a32;
use bi_am_rrt::{
    Circle, Config, DiffusionTable, Map, MetricKind, Motion, Moving, OccupancyGrid, Planner, Point,
};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

use crate::hprintln;
use crate::mission::{Metres, MissionStorage};
use crate::scenario;

/// Most `plan` calls made per goal.
const MAX_CALLS: u32 = 600;

/// Seconds of the world per protocol call with walkers.
const WORLD_PERIOD: f32 = 0.5;

/// Walkers (`host-sim export --walkers`, 0-4): a constant, so that without them none of
/// their code is built (the flash budget is tight).
const WALKERS: usize = at_most_four(scenario::WALKERS);

/// A door closing and opening across goal 1's line (`host-sim export --door`).
const DOOR: bool = scenario::DOOR;
/// Calls the door stays closed.
const DOOR_CALLS: u32 = 40;

/// `n`, or 4 if more (the walkers' arrays hold 4).
const fn at_most_four(n: usize) -> usize {
    if n > 4 { 4 } else { n }
}

/// The door's corner cells: 3 cells thick along the line from `start` to `goal`, 13 across it,
/// centred halfway (clamped to the grid).
fn door_cells(grid: &OccupancyGrid<'_>, start: Point, goal: Point) -> ((u16, u16), (u16, u16)) {
    let mid = start.lerp(goal, 0.5);
    let (c, r) = grid.cell_of(mid).unwrap_or((0, 0));
    let d = goal - start;
    let (dc, dr) = if d.x.abs() > d.y.abs() {
        (1, 6)
    } else {
        (6, 1)
    };
    let lo = (c.saturating_sub(dc), r.saturating_sub(dr));
    let hi = ((c + dc).min(grid.cols() - 1), (r + dr).min(grid.rows() - 1));
    (lo, hi)
}

/// Walker `i` of `n` at world time `t`: pacing at 1 m/s over 12 m across the start-goal line.
fn walker(i: usize, n: usize, start: Point, goal: Point, t: f32) -> Moving {
    let d = goal - start;
    let len = d.norm().max(1e-3);
    let across = Point::new(-d.y / len, d.x / len);
    let centre = start.lerp(goal, (i as f32 + 1.0) / (n as f32 + 1.0));
    // Phase by index so that they do not move in step.
    let x = t + 3.0 * i as f32;
    let u = x - 24.0 * ((x / 24.0) as u32 as f32);
    let (s, dir) = if u < 12.0 { (u, 1.0) } else { (24.0 - u, -1.0) };
    let at = centre + across * (s - 6.0);
    Moving::new(Circle::new(at, 0.5), across * dir)
}

/// Per-call times in 10 us bins from 148.00 ms: the median without keeping every call (the
/// whole office sequence makes over a thousand), exact to 10 us when it falls in the bins.
pub struct CallTimes {
    bins: [u16; BINS],
    below: u32,
    above: u32,
    count: u32,
}

/// Bins of [`CallTimes`], 10 us each from [`FIRST_BIN`] (148.00 ms to 153.12 ms).
const BINS: usize = 512;
/// The first bin, in units of 10 us.
const FIRST_BIN: u32 = 14_800;

impl CallTimes {
    pub const fn new() -> Self {
        Self {
            bins: [0; BINS],
            below: 0,
            above: 0,
            count: 0,
        }
    }

    fn record(&mut self, tens_of_us: u32) {
        self.count += 1;
        match tens_of_us
            .checked_sub(FIRST_BIN)
            .map(|i| self.bins.get_mut(i as usize))
        {
            None => self.below += 1,
            Some(None) => self.above += 1,
            Some(Some(bin)) => *bin = bin.saturating_add(1),
        }
    }

    /// The median call in units of 10 us, `None` when it falls outside the bins.
    fn median(&self) -> Option<u32> {
        let half = self.count / 2 + 1;
        let mut seen = self.below;
        if seen >= half {
            return None;
        }
        for (i, &n) in self.bins.iter().enumerate() {
            seen += u32::from(n);
            if seen >= half {
                return Some(FIRST_BIN + i as u32);
            }
        }
        None
    }
}

/// What the office mission flies: goal 1 from the start (CI's figures), or, exported with
/// `--all-goals`, every goal of the scenario in turn.
fn goals() -> &'static [(f32, f32)] {
    let all = scenario::ALL_GOALS;
    let n = if all { scenario::GOALS.len() } else { 1 };
    scenario::GOALS.get(..n).unwrap_or(&[])
}

/// Flies the exported scenario on `clock`, whose ticks are cycles of a `core_hz` core (the
/// overrun and the per-call bins are printed in those). True when every goal was reached
/// without a collision. Not inlined, as the twin's `mission::fly`: each mission's planner
/// then has its own frame, popped before the next one starts.
#[inline(never)]
pub fn exported_mission<C: Clock + ?Sized>(
    storage: &mut MissionStorage,
    times: &mut CallTimes,
    clock: &C,
    core_hz: u32,
) -> bool {
    let grid = match OccupancyGrid::new(
        &scenario::GRID,
        scenario::COLS,
        scenario::ROWS,
        scenario::CELL,
    ) {
        Ok(g) => g,
        Err(e) => {
            hprintln!("scenario: the grid in flash refused: {}", e);
            return false;
        }
    };
    let table = match DiffusionTable::new(&scenario::TABLE) {
        Ok(t) => t,
        Err(e) => {
            hprintln!("scenario: the table in flash refused: {}", e);
            return false;
        }
    };
    let mut overlay = [0u8; if DOOR { scenario::GRID.len() } else { 0 }];
    let map: Map<'_, 4> = if DOOR {
        match Map::new(grid).with_overlay(&mut overlay) {
            Ok(m) => m,
            Err(e) => {
                hprintln!("scenario: overlay refused: {}", e);
                return false;
            }
        }
    } else {
        Map::new(grid)
    };
    // A robot body: the grid `host-sim export --robot-radius` inflated, from flash (with the
    // door's live cells, re-inflated into RAM as they change).
    let radius = scenario::ROBOT_RADIUS;
    let mut space_ram = [0u8; if DOOR { scenario::SPACE.len() } else { 0 }];
    let map = if radius <= 0.0 {
        Ok(map)
    } else if DOOR {
        map.with_body(radius, &mut space_ram)
    } else {
        OccupancyGrid::new(
            &scenario::SPACE,
            scenario::COLS,
            scenario::ROWS,
            scenario::CELL,
        )
        .and_then(|s| s.inflated_for(radius))
        .and_then(|s| map.with_baked_body(s))
    };
    let map = match map {
        Ok(m) => m,
        Err(e) => {
            hprintln!("scenario: the robot's inflated grid refused: {}", e);
            return false;
        }
    };
    // Lengths that follow the map (Table 2's on the office), `sigma` as the scenario gives it.
    // `host-sim export --planners tuned` flies the tuned set, `paper` the paper's.
    let base = Config::bi_am_rrt();
    let base = if scenario::TUNED { base.tuned() } else { base };
    let mut cfg = base.for_grid(&grid).with_sigma(scenario::SIGMA);
    cfg.robot_radius = radius;
    let walkers = WALKERS;
    if WALKERS > 0 {
        cfg.motion = Motion {
            agent_speed: 0.7 / WORLD_PERIOD,
            period: WORLD_PERIOD,
            horizon: 1.5,
            obstacle_speed: 1.5,
        };
    }
    let rng = XorShiftRng::seed_from_u64(1);
    let start = Point::new(scenario::START.0, scenario::START.1);
    let mut planner = match Planner::new(storage, map, table, rng, cfg, start) {
        Ok(p) => p,
        Err(e) => {
            hprintln!("scenario: planner refused: {}", e);
            return false;
        }
    };
    // The export's roadmap, flown when the core is built with its `roadmap` feature: the tuned
    // set joins each goal over it in its first call (`set_roadmap` refuses one of another map
    // or larger than the arena; the planner then searches without it).
    #[cfg(feature = "roadmap")]
    if !scenario::ROADMAP.is_empty() {
        let attached = bi_am_rrt::roadmap::Roadmap::from_bytes(&scenario::ROADMAP)
            .and_then(|rm| planner.set_roadmap(Some(rm)));
        if let Err(e) = attached {
            hprintln!("scenario: roadmap refused, flying without it: {}", e);
        }
    }
    let first_goal = scenario::GOALS
        .first()
        .map_or(start, |&(x, y)| Point::new(x, y));
    let mut ids = [ObstacleId(0); 4];
    for (i, id) in ids.iter_mut().enumerate().take(walkers) {
        match planner.add_moving_obstacle(walker(i, walkers, start, first_goal, 0.0)) {
            Ok(got) => *id = got,
            Err(_) => {
                hprintln!("scenario: walker {} refused", i);
                return false;
            }
        }
    }
    let mut world_calls = 0u32;
    let door = door_cells(&grid, start, first_goal);
    let door_centre = start.lerp(first_goal, 0.5);
    // Calls since the door closed (`None`: open).
    let (mut closed_for, mut door_done, mut door_cells_marked) = (None::<u32>, false, 0u32);
    let protocol = Protocol {
        max_calls: MAX_CALLS,
        ..Protocol::default()
    };
    let cycles_per_10us = u64::from(core_hz / 100_000);
    let mut worst = 0u64;
    let mut trail = 0x811c_9dc5u32;
    let mut nodes = 0usize;
    let (mut ok, mut reached, mut calls, mut travelled) = (true, 0, 0u32, 0f32);
    let mut expansions = 0u64;
    let mut result = None;
    let goals = goals();
    for (i, &(x, y)) in goals.iter().enumerate() {
        let mut last = clock.now();
        let run = run_to_goal(
            &mut planner,
            clock,
            Point::new(x, y),
            &protocol,
            |p, agent, _| {
                let now = clock.now();
                let dt = now.saturating_sub(last);
                worst = worst.max(dt);
                times.record(u32::try_from(dt / cycles_per_10us).unwrap_or(u32::MAX));
                nodes = p.tree().len();
                // FNV-1a over the agent's positions: the path's checksum.
                let mut bytes = [0u8; 8];
                bytes[..4].copy_from_slice(&agent.x.to_bits().to_le_bytes());
                bytes[4..].copy_from_slice(&agent.y.to_bits().to_le_bytes());
                trail = bytes
                    .iter()
                    .fold(trail, |h, &b| (h ^ u32::from(b)).wrapping_mul(0x0100_0193));
                // The door closes near the agent and opens DOOR_CALLS calls later.
                if DOOR && !door_done {
                    match closed_for {
                        None if agent.dist(door_centre) < 15.0 => {
                            door_cells_marked = p.set_cells(door.0, door.1, true).unwrap_or(0);
                            closed_for = Some(0);
                        }
                        Some(n) if n >= DOOR_CALLS => {
                            let _ = p.set_cells(door.0, door.1, false);
                            closed_for = None;
                            door_done = true;
                        }
                        Some(n) => closed_for = Some(n + 1),
                        None => {}
                    }
                }
                // The walkers move on and are reported for the next call.
                if WALKERS > 0 {
                    world_calls += 1;
                    let t = world_calls as f32 * WORLD_PERIOD;
                    for (i, &id) in ids.iter().enumerate().take(walkers) {
                        let _ = p.update_obstacle(id, walker(i, walkers, start, first_goal, t));
                    }
                }
                last = clock.now();
            },
        );
        let Ok(r) = run else {
            hprintln!("scenario: goal {} refused", i + 1);
            return false;
        };
        if goals.len() > 1 {
            hprintln!(
                "goal {}: reached {}, path {} m, {} collisions, {} plan calls",
                i + 1,
                r.reached,
                Metres(r.travelled),
                r.collisions,
                r.calls
            );
        }
        // Counted per goal (`set_goal` starts the stats again).
        expansions += planner.stats().expansions;
        ok &= r.reached && r.collisions == 0;
        reached += usize::from(r.reached);
        calls += r.calls;
        travelled += r.travelled;
        result.get_or_insert(r);
    }
    let Some(r) = result else {
        return false;
    };
    let budget = clock.ticks(cfg.budget.t_exp);
    let ms = u64::from(core_hz / 1_000);
    let us = u64::from(core_hz / 1_000_000);
    if goals.len() > 1 {
        hprintln!(
            "{} on {} (real clock, t_exp {} ms): {}/{} goals reached, path {} m, {} plan calls, \
             {} expansions ({}.{} per call), {} nodes at the end",
            cfg.name(MetricKind::Diffusion),
            scenario::NAME,
            cfg.budget.t_exp.as_millis(),
            reached,
            goals.len(),
            Metres(travelled),
            calls,
            expansions,
            expansions / u64::from(calls.max(1)),
            expansions * 10 / u64::from(calls.max(1)) % 10,
            nodes
        );
    } else {
        let search_ms = r.search_ticks.map_or(0, |t| t / ms);
        hprintln!(
            "{} on {} (real clock, t_exp {} ms): reached {}, search {} ms, path {} m, \
             {} collisions, {} nodes at goal, {} nodes at the end, {} plan calls",
            cfg.name(MetricKind::Diffusion),
            scenario::NAME,
            cfg.budget.t_exp.as_millis(),
            r.reached,
            search_ms,
            Metres(r.travelled),
            r.collisions,
            r.nodes_at_goal.unwrap_or(0),
            nodes,
            r.calls
        );
    }
    if DOOR {
        hprintln!(
            "a door of {} cells closed across the way for {} calls ({})",
            door_cells_marked,
            DOOR_CALLS,
            if door_done {
                "and opened again"
            } else {
                "still closed at the end"
            }
        );
    }
    if WALKERS > 0 {
        hprintln!(
            "{} walkers at 1 m/s across the way, updated before every call (motion stated)",
            walkers
        );
    }
    let median = times.median();
    hprintln!(
        "per-call time: median {}, worst {}.{:03} ms ({} cycles, overrun {} us); path checksum {:08x}",
        Median(median),
        worst / ms,
        (worst % ms) / us,
        worst,
        worst.saturating_sub(budget) / us,
        trail
    );
    hprintln!(
        "grid {} bytes and table {} bytes in flash (table checksum {:08x})",
        scenario::GRID.len(),
        scenario::TABLE.len(),
        fnv1a32(&scenario::TABLE)
    );
    if radius > 0.0 {
        hprintln!(
            "a robot of radius {} m: its inflated grid {} bytes in flash",
            Metres(radius),
            scenario::SPACE.len()
        );
    }
    ok
}

/// A median of [`CallTimes`] as `150.04 ms`.
struct Median(Option<u32>);

impl core::fmt::Display for Median {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some(m) => write!(f, "{}.{:02} ms", m / 100, m % 100),
            None => write!(f, "outside 148.00-153.12 ms"),
        }
    }
}

/// Bytes of stack ever used (Cortex-M builds): `cortex-m-rt` (feature `paint-stack`) fills the stack with
/// `0xCCCC_CCCC` at reset; the lowest word that no longer holds it marks the deepest use.
#[cfg(target_arch = "arm")]
pub fn stack_high_water() -> usize {
    unsafe extern "C" {
        static _stack_start: u32;
        static _stack_end: u32;
    }
    let top = &raw const _stack_start as usize;
    let bottom = &raw const _stack_end as usize;
    let mut at = bottom;
    while at < top {
        // SAFETY: `at` is a word-aligned address inside the stack region, which is RAM that
        // this program owns; reading it (volatile, so it is not optimised away) is harmless.
        let word = unsafe { core::ptr::read_volatile(at as *const u32) };
        if word != 0xCCCC_CCCC {
            break;
        }
        at += 4;
    }
    top - at
}
