//! The `moving` command (issue 27): people walking through a scenario while the agent drives
//! its first leg, under three treatments of the same walkers, and what came of it.
//!
//! Scenes (`--kinds`):
//! - `crossing`: five people pace to and fro across the agent's route at 0.5-1.5 m/s, each
//!   over the free width there (a corridor's, at most 6 m either side), timed to be near
//!   their crossing when the agent passes;
//! - `head-on`: two people walk the route backwards at 1.0-1.5 m/s, from 15-25 m and 35-45 m
//!   ahead of the start, towards the agent, turning at its corners;
//! - `door`: a door across the route (at its narrowest doorway between 25 % and 75 % of its
//!   length, walls within 10 m on both sides, whose closing leaves a way round; a band 1.5
//!   cells thick from wall to wall) closes when the agent comes within 4 m and opens
//!   [`DOOR_CLOSED_S`] later;
//! - `closed-door`: the same door, closed from the start (what not rebaking the table costs).
//!
//! Treatments (the planner, the agent and the walkers are the same; only the reports differ):
//! - `static`: the walkers re-submitted every call as still circles, nothing stated about
//!   motion ([`bi_am_rrt::Motion::NONE`]): the paper's planner with today's interface;
//! - `predicted`: their velocity as a tracker reports it, trusted for ever (a walker turns
//!   without notice), with the motion stated ([`bi_am_rrt::motion`]);
//! - `oracle`: the same, each prediction trusted exactly until the walker's next turn (it knows
//!   when its prediction ends; past it the disc grows at the stated top speed).
//!
//! The door scenes compare (no walkers, no motion stated):
//! - `static` (door): the closed door submitted as eight still circles along it, today's
//!   interface without live cells;
//! - `live`: its cells marked and cleared in the map's live overlay (`Planner::set_cells`), the
//!   diffusion table as baked from the open map;
//! - `rebaked` (closed-door): the door closed in the map itself, with a table baked for it: the
//!   difference from `live` is what not rebaking costs. Travelled / optimal is against the
//!   open map's optimum for `door` and the closed map's for `closed-door`.
//!
//! The agent drives at 1 m/s, one period (0.1 s) per call; the planner has a fixed virtual
//! budget per call. Every period is checked in continuous time (10 sub-steps, the closest
//! approach in each) against every walker: a contact's start is a collision, the agent's
//! (*moved into*) when it moved in that period and holding would have kept clear of that
//! walker, else the walker's (*ran into* a waiting agent). Writes `runs.csv`, `summary.md`,
//! `moving.png`/`.svg` (collisions, waiting time and travelled / optimal per scene and
//! treatment), and for seed 0 of each scene under `predicted` a picture and, with
//! `--animate`, a GIF.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, anyhow};
use bi_am_rrt::map::ObstacleId;
use bi_am_rrt::{Circle, Motion, Moving, Named, Point, Status, Wait};
use plotters::style::RGBColor;
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::draw::chart::{BarPanel, Bars, render};
use crate::draw::{Animation, Painter, Scene};
use crate::results::stats::median;
use crate::sim::clock::{VIRTUAL_NS_PER_UNIT, virtual_clock};
use crate::sim::scene;
use crate::sim::{Prepared, SimPlanner, with_live_planner, with_planner};

/// The agent's top speed, m/s.
pub const AGENT_SPEED: f32 = 1.0;
/// Seconds per `plan` call.
pub const PERIOD: f32 = 0.1;
/// The motion the `predicted` and `oracle` treatments state.
pub const MOTION: Motion = Motion {
    agent_speed: AGENT_SPEED,
    period: PERIOD,
    horizon: 1.5,
    obstacle_speed: 1.5,
};
/// Collision sub-steps per period.
const SUBSTEPS: u32 = 10;

/// A scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// People crossing the route.
    Crossing,
    /// People walking the route towards the agent.
    HeadOn,
    /// A door on the route closes when the agent is near and opens 20 s later.
    Door,
    /// The same door, closed from the start.
    ClosedDoor,
}

/// How the walkers are reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Treatment {
    /// Still circles, no motion stated.
    Static,
    /// Velocities trusted for ever.
    Predicted,
    /// Velocities trusted until the next turn.
    Oracle,
    /// The door's cells marked and cleared in the live overlay; the table as baked.
    Live,
    /// The door closed in the map itself, with a diffusion table baked for it.
    Rebaked,
}

impl Treatment {
    /// All of them, in the order of the charts.
    pub const ALL: [Treatment; 5] = [
        Self::Static,
        Self::Predicted,
        Self::Oracle,
        Self::Live,
        Self::Rebaked,
    ];

    fn name(self) -> &'static str {
        match self {
            Self::Static => "static",
            Self::Predicted => "predicted",
            Self::Oracle => "oracle",
            Self::Live => "live",
            Self::Rebaked => "rebaked",
        }
    }
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Self::Crossing => "crossing",
            Self::HeadOn => "head-on",
            Self::Door => "door",
            Self::ClosedDoor => "closed-door",
        }
    }

    /// The treatments compared in this scene.
    fn treatments(self) -> &'static [Treatment] {
        match self {
            Self::Crossing | Self::HeadOn => {
                &[Treatment::Static, Treatment::Predicted, Treatment::Oracle]
            }
            Self::Door => &[Treatment::Static, Treatment::Live],
            Self::ClosedDoor => &[Treatment::Live, Treatment::Rebaked],
        }
    }

    /// The treatment whose seed 0 gets pictures.
    fn pictured(self) -> Treatment {
        match self {
            Self::Crossing | Self::HeadOn => Treatment::Predicted,
            Self::Door | Self::ClosedDoor => Treatment::Live,
        }
    }
}

/// A walker: a polyline walked at constant speed, to and fro or once (then standing).
#[derive(Clone, Debug)]
struct Walker {
    points: Vec<Point>,
    speed: f32,
    radius: f32,
    /// Arc length at time 0.
    phase: f32,
    to_and_fro: bool,
}

impl Walker {
    fn length(&self) -> f32 {
        self.points.windows(2).map(|w| w[0].dist(w[1])).sum()
    }

    /// Position, velocity and the time to the next turn at time `t`.
    fn at(&self, t: f32) -> (Point, Point, f32) {
        let len = self.length().max(1e-6);
        let mut u = self.phase + self.speed * t;
        let mut dir = 1.0f32;
        if self.to_and_fro {
            u = u.rem_euclid(2.0 * len);
            if u > len {
                u = 2.0 * len - u;
                dir = -1.0;
            }
        }
        match locate(&self.points, u) {
            Some((p, unit, from, to)) if self.to_and_fro || u < len => {
                let left = if dir > 0.0 { to - u } else { u - from };
                (p, unit * (self.speed * dir), left / self.speed)
            }
            // Past the end of a one-way walk (or no walk at all): standing.
            _ => (*self.points.last().unwrap(), Point::ZERO, f32::INFINITY),
        }
    }
}

/// Where arc length `s` falls on the polyline `points`: the point, the unit direction of its
/// segment, and the arc lengths at which that segment starts and ends (segments of no length
/// skipped; past the end, the end of the last segment). `None` without a segment.
fn locate(points: &[Point], s: f32) -> Option<(Point, Point, f32, f32)> {
    let mut acc = 0.0;
    let mut last = None;
    for w in points.windows(2) {
        let l = w[0].dist(w[1]);
        if l == 0.0 {
            continue;
        }
        let unit = (w[1] - w[0]) * (1.0 / l);
        if s <= acc + l {
            return Some((
                w[0].lerp(w[1], ((s - acc) / l).max(0.0)),
                unit,
                acc,
                acc + l,
            ));
        }
        last = Some((w[1], unit, acc, acc + l));
        acc += l;
    }
    last
}

/// What one run measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MovingRow {
    /// Scene.
    pub kind: Kind,
    /// Treatment.
    pub treatment: Treatment,
    /// Seed (walkers and planner).
    pub seed: u64,
    /// The agent stood on the goal.
    pub reached: bool,
    /// Seconds until it did (or the run was abandoned).
    pub time_s: f64,
    /// Seconds it held before arriving.
    pub waiting_s: f64,
    /// Contacts the agent moved into.
    pub moved_into: u32,
    /// Contacts a walker made with a waiting agent.
    pub ran_into: u32,
    /// Calls with status `Evading`.
    pub evading_calls: u32,
    /// Calls with `Wait::Cornered`.
    pub cornered_calls: u32,
    /// Metres driven over the leg's exact optimum.
    pub travelled_ratio: f64,
    /// Most work units of one call.
    pub max_work: u64,
}

impl MovingRow {
    /// The row of a run that has not started.
    fn new(kind: Kind, treatment: Treatment, seed: u64) -> Self {
        Self {
            kind,
            treatment,
            seed,
            reached: false,
            time_s: 0.0,
            waiting_s: 0.0,
            moved_into: 0,
            ran_into: 0,
            evading_calls: 0,
            cornered_calls: 0,
            travelled_ratio: f64::NAN,
            max_work: 0,
        }
    }
}

/// The GIF of a pictured run with `--animate` (`KIND.gif`), drawn by `small`.
fn animation<'a, 'g>(
    small: Option<&'a Painter<'g>>,
    pictures: Option<(&Path, Option<u32>)>,
    kind: Kind,
) -> Result<Option<Animation<'a, 'g>>> {
    match (pictures, small) {
        (Some((dir, Some(_))), Some(small)) => Ok(Some(Animation::new(
            small,
            &dir.join(format!("{}.gif", kind.name())),
            100,
        )?)),
        _ => Ok(None),
    }
}

/// Every `every` calls of a run with `--animate`, a GIF frame of `scene()` without its trees.
fn gif_frame(
    gif: &mut Option<Animation<'_, '_>>,
    pictures: Option<(&Path, Option<u32>)>,
    call: u32,
    scene: impl FnOnce() -> Scene,
) -> Result<()> {
    if let (Some(g), Some((_, Some(every)))) = (gif.as_mut(), pictures)
        && call.is_multiple_of(every)
    {
        let mut s = scene();
        s.forward.clear();
        s.reverse.clear();
        g.frame(&s)?;
    }
    Ok(())
}

/// Arguments of `moving`.
pub struct MovingArgs {
    /// Scenes to run.
    pub kinds: Vec<Kind>,
    /// Seeds per scene and treatment.
    pub seeds: u64,
    /// Planning budget per call on the virtual clock.
    pub t_exp: Duration,
    /// Output directory.
    pub out: PathBuf,
    /// GIF of seed 0 (`predicted`), one frame every N calls.
    pub animate: Option<u32>,
    /// Planning calls (of the default 150 ms) the route gets to settle before the runs
    /// ([`ROUTE_CALLS`] from the command line).
    pub route_calls: u32,
}

/// Calls the route gets to settle: 400 x 150 ms of planning.
pub const ROUTE_CALLS: u32 = 400;

/// The route: the planner's path to goal 1 after it has had time to settle (no walkers).
fn route(prep: &Prepared, cfg: Named, calls: u32) -> Result<Vec<Point>> {
    let goal = *prep.scenario.goals.first().context("no goal")?;
    let clock = virtual_clock(VIRTUAL_NS_PER_UNIT);
    with_planner(prep, prep.fit(cfg), 0, |p| {
        p.set_goal(goal).map_err(|e| anyhow!("{e}"))?;
        for _ in 0..calls {
            p.grow(&clock);
        }
        let mut buf = vec![Point::ZERO; p.tree().len().max(2)];
        let info = p.path(&mut buf).map_err(|e| anyhow!("{e}"))?;
        if !info.to_goal {
            return Err(anyhow!("no path to goal 1 after {calls} calls"));
        }
        buf.truncate(info.len);
        Ok(buf)
    })
}

/// The point at arc length `s` along `route`, and the direction there.
fn along(route: &[Point], s: f32) -> (Point, Point) {
    locate(route, s).map_or((route[0], Point::new(1.0, 0.0)), |(p, d, _, _)| (p, d))
}

fn unit(rng: &mut XorShiftRng) -> f32 {
    (rng.next_u32() >> 8) as f32 / 16_777_216.0
}

/// The free width either side of `x` along `n` and `-n`, at most `cap` metres each (0.1 m
/// steps).
fn free_width(grid: &bi_am_rrt::OccupancyGrid<'_>, x: Point, n: Point, cap: f32) -> (f32, f32) {
    let reach = |sign: f32| {
        let mut r = 0.0f32;
        while r < cap {
            let q = x + n * (sign * (r + 0.1));
            if !grid.point_free(q) {
                break;
            }
            r += 0.1;
        }
        r
    };
    (reach(-1.0), reach(1.0))
}

/// Seconds the `door` scene's door stays closed.
pub const DOOR_CLOSED_S: f32 = 20.0;
/// A doorway has walls within this many metres on both sides of the route.
const DOOR_REACH: f32 = 10.0;
/// The `door` scene's door closes when the agent comes this near (metres).
const DOOR_NEAR: f32 = 4.0;

/// A door across the route: at its narrowest doorway between 25 % and 75 % of its length (walls
/// within [`DOOR_REACH`] on both sides) whose closing leaves a way round, a band of cells 1.5 cells (at
/// least 0.3 m) thick from wall to wall.
#[derive(Clone, Debug)]
struct Door {
    /// The free cells it closes.
    cells: Vec<(u16, u16)>,
    /// Where the route crosses it.
    centre: Point,
    /// Its ends (for the circles of the `static` treatment).
    ends: (Point, Point),
}

fn door(map: &crate::scenario::OwnedGrid, route: &[Point]) -> Result<Door> {
    let grid = map.grid();
    let total: f32 = route.windows(2).map(|w| w[0].dist(w[1])).sum();
    // Doorways: walls within DOOR_REACH on both sides, narrowest first.
    let mut candidates = Vec::new();
    let mut s = 0.25 * total;
    while s <= 0.75 * total {
        let (x, d) = along(route, s);
        let n = Point::new(-d.y, d.x);
        let (a, b) = free_width(&grid, x, n, DOOR_REACH);
        if a + b >= 0.6 && a < DOOR_REACH && b < DOOR_REACH {
            candidates.push((a + b, x, d, a, b));
        }
        s += 0.25;
    }
    candidates.sort_by(|p, q| p.0.total_cmp(&q.0));
    let (start, goal) = (route[0], route[route.len() - 1]);
    for &(_, x, d, a, b) in &candidates {
        let door = door_at(&grid, x, d, a, b);
        // Closed, it must close the way it stands in and leave another one.
        let shut = closed_grid(map, &door);
        if connected(&shut.grid(), start, goal) && !door.cells.is_empty() {
            return Ok(door);
        }
    }
    Err(anyhow!(
        "no doorway on the route (walls within {DOOR_REACH} m either side) that leaves a way round"
    ))
}

/// The door across the passage at `x` (route direction `d`, free `a` and `b` either side).
fn door_at(grid: &bi_am_rrt::OccupancyGrid<'_>, x: Point, d: Point, a: f32, b: f32) -> Door {
    let n = Point::new(-d.y, d.x);
    let cell = grid.cell_size();
    let half = (0.75 * cell).max(0.15);
    let (lo, hi) = (-a - half, b + half);
    let mut cells = Vec::new();
    let reach = hi.max(-lo) + 2.0 * cell;
    let (c0, r0) = grid.cell_of(x - Point::new(reach, reach)).unwrap_or((0, 0));
    let (c1, r1) = grid
        .cell_of(x + Point::new(reach, reach))
        .unwrap_or((grid.cols() - 1, grid.rows() - 1));
    for r in r0..=r1 {
        for c in c0..=c1 {
            let q = grid.cell_center(c, r) - x;
            let (u, v) = (q.dot(d), q.dot(n));
            if u.abs() <= half && v >= lo && v <= hi && !grid.is_occupied(c, r) {
                cells.push((c, r));
            }
        }
    }
    Door {
        cells,
        centre: x,
        ends: (x + n * lo, x + n * hi),
    }
}

/// Whether the free cells of `a` and `b` are joined by free cells sharing sides (the
/// planner's rule blocks a slip through a corner).
fn connected(grid: &bi_am_rrt::OccupancyGrid<'_>, a: Point, b: Point) -> bool {
    let (Some(from), Some(to)) = (grid.cell_of(a), grid.cell_of(b)) else {
        return false;
    };
    let w = grid.cols() as usize;
    let mut seen = vec![false; w * grid.rows() as usize];
    let mut stack = vec![from];
    seen[from.1 as usize * w + from.0 as usize] = true;
    while let Some((c, r)) = stack.pop() {
        if (c, r) == to {
            return true;
        }
        let next = [
            (c.wrapping_sub(1), r),
            (c + 1, r),
            (c, r.wrapping_sub(1)),
            (c, r + 1),
        ];
        for (nc, nr) in next {
            if nc < grid.cols() && nr < grid.rows() && !grid.is_occupied(nc, nr) {
                let i = nr as usize * w + nc as usize;
                if !seen[i] {
                    seen[i] = true;
                    stack.push((nc, nr));
                }
            }
        }
    }
    false
}

/// The grid with the door closed.
fn closed_grid(grid: &crate::scenario::OwnedGrid, door: &Door) -> crate::scenario::OwnedGrid {
    let mut g = grid.clone();
    for &(c, r) in &door.cells {
        let i = r as usize * g.width as usize + c as usize;
        g.bits[i / 8] |= 1 << (i % 8);
    }
    g
}

/// The discs the `static` treatment submits for a closed door: eight along its line, each
/// overlapping its neighbours and at least 0.75 of a cell across.
fn door_discs(door: &Door, cell: f32) -> Vec<Circle> {
    let (p, q) = door.ends;
    let span = p.dist(q);
    let n = 8;
    let r = (0.75 * cell).max(1.3 * span / (2.0 * n as f32));
    (0..n)
        .map(|i| Circle::new(p.lerp(q, (i as f32 + 0.5) / n as f32), r))
        .collect()
}

/// The walkers of one run.
fn walkers(prep: &Prepared, route: &[Point], kind: Kind, seed: u64) -> Vec<Walker> {
    let mut rng = XorShiftRng::seed_from_u64(seed.wrapping_mul(0x9e37_79b9) ^ 0x5eed);
    let total: f32 = route.windows(2).map(|w| w[0].dist(w[1])).sum();
    let grid = prep.scenario.map.grid();
    let mut out = Vec::new();
    match kind {
        Kind::Crossing => {
            for i in 0..5 {
                // Crossings spread along the route, away from its ends.
                let s = total * (0.15 + 0.7 * (i as f32 + unit(&mut rng)) / 5.0);
                let (x, d) = along(route, s);
                let n = Point::new(-d.y, d.x);
                let (a, b) = free_width(&grid, x, n, 6.0);
                if a + b < 1.0 {
                    continue;
                }
                let speed = 0.5 + unit(&mut rng);
                let radius = 0.3 + 0.2 * unit(&mut rng);
                let (p0, p1) = (
                    x + n * (-(a - radius).max(0.0)),
                    x + n * (b - radius).max(0.0),
                );
                let width = p0.dist(p1);
                // Near the crossing when the agent gets there (at its top speed), give or
                // take a few seconds.
                let arrive = s / AGENT_SPEED + (unit(&mut rng) - 0.5) * 6.0;
                let phase = (p0.dist(x) - speed * arrive).rem_euclid(2.0 * width.max(1e-3));
                out.push(Walker {
                    points: vec![p0, p1],
                    speed,
                    radius,
                    phase,
                    to_and_fro: true,
                });
            }
        }
        Kind::Door | Kind::ClosedDoor => {}
        Kind::HeadOn => {
            for base in [15.0f32, 35.0] {
                let s0 = (base + 10.0 * unit(&mut rng)).min(total * 0.9);
                // The route from s0 back to the start.
                let mut pts = vec![along(route, s0).0];
                let mut acc = 0.0;
                let mut back: Vec<Point> = Vec::new();
                for w in route.windows(2) {
                    acc += w[0].dist(w[1]);
                    if acc < s0 {
                        back.push(w[1]);
                    }
                }
                back.reverse();
                pts.extend(back);
                pts.push(route[0]);
                out.push(Walker {
                    points: pts,
                    speed: 1.0 + 0.5 * unit(&mut rng),
                    radius: 0.3 + 0.2 * unit(&mut rng),
                    phase: 0.0,
                    to_and_fro: false,
                });
            }
        }
    }
    out
}

/// What a treatment submits for a walker at time `t`.
fn reported(w: &Walker, t: f32, treatment: Treatment) -> Moving {
    let (pos, vel, turn) = w.at(t);
    let c = Circle::new(pos, w.radius);
    match treatment {
        Treatment::Static => Moving::still(c),
        Treatment::Oracle => Moving::new(c, vel).trusted_for(turn),
        Treatment::Predicted | Treatment::Live | Treatment::Rebaked => Moving::new(c, vel),
    }
}

/// Whether a robot of radius `r` moving along `a-b` touches an occupied cell of `grid` (for a
/// point, the grid's own test; for a disc, exact distances: `host_sim::metric::clearance`).
fn touches(grid: &bi_am_rrt::OccupancyGrid<'_>, a: Point, b: Point, r: f32) -> bool {
    if r > 0.0 {
        crate::metric::clearance::segment_clearance(grid, a, b) < f64::from(r) - 1e-4
    } else {
        !grid.segment_free(a, b)
    }
}

/// Whether the point moving `a0 -> a1` comes within `r` of the one moving `o0 -> o1`.
fn contact(a0: Point, a1: Point, o0: Point, o1: Point, r: f32) -> bool {
    let m = r - 1e-4;
    bi_am_rrt::geometry::segment_point_dist_sq(a0 - o0, a1 - o1, Point::ZERO) < m * m
}

/// One run.
#[allow(clippy::too_many_arguments)]
fn one(
    prep: &Prepared,
    base: Named,
    route: &[Point],
    kind: Kind,
    treatment: Treatment,
    seed: u64,
    t_exp: Duration,
    pictures: Option<(&Path, Option<u32>)>,
) -> Result<MovingRow> {
    let goal = prep.scenario.goals[0];
    let optimum = prep.optima().first().copied().flatten().unwrap_or(f64::NAN);
    let mut cfg = prep.fit(base);
    cfg.cfg.budget.t_exp = t_exp;
    cfg.cfg.motion = if treatment == Treatment::Static {
        Motion::NONE
    } else {
        MOTION
    };
    let mut people = walkers(prep, route, kind, seed);
    let total: f32 = route.windows(2).map(|w| w[0].dist(w[1])).sum();
    let max_calls = ((total / AGENT_SPEED / PERIOD) * 4.0) as u32 + 1200;
    let clock = virtual_clock(VIRTUAL_NS_PER_UNIT);
    with_planner(prep, cfg, seed, |p| {
        let ids: Vec<ObstacleId> = people
            .iter()
            .map(|w| p.add_moving_obstacle(reported(w, 0.0, treatment)))
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| anyhow!("{e}"))?;
        p.set_goal(goal).map_err(|e| anyhow!("{e}"))?;
        let mut agent = prep.scenario.start;
        let mut trail = vec![agent];
        let mut contacts = vec![false; people.len()];
        let painter = pictures.map(|_| Painter::for_scenario(&prep.scenario, 900));
        // The GIF is smaller and shows no tree (the frames then compress well).
        let small = pictures.map(|_| Painter::for_scenario(&prep.scenario, 560));
        let mut gif = animation(small.as_ref(), pictures, kind)?;
        let title = |call: u32| {
            format!(
                "{} {}, {} walkers, seed {seed}, t = {:.1} s",
                prep.scenario.name,
                kind.name(),
                treatment.name(),
                call as f32 * PERIOD
            )
        };
        let mut row = MovingRow::new(kind, treatment, seed);
        let mut travelled = 0.0f64;
        for call in 0..max_calls {
            let t = call as f32 * PERIOD;
            for (w, &id) in people.iter().zip(&ids) {
                p.update_obstacle(id, reported(w, t, treatment))
                    .map_err(|e| anyhow!("{e}"))?;
            }
            let pr = p.plan(&clock, agent).map_err(|e| anyhow!("{e}"))?;
            row.max_work = row.max_work.max(pr.work);
            match pr.status {
                Status::Arrived => {
                    row.reached = true;
                    break;
                }
                Status::Evading => row.evading_calls += 1,
                Status::Waiting(Wait::Cornered) => row.cornered_calls += 1,
                _ => {}
            }
            let next = agent.step_towards(pr.waypoint, AGENT_SPEED * PERIOD);
            let moved = next != agent;
            if !moved {
                row.waiting_s += PERIOD as f64;
            }
            let d = agent.dist(next);
            let at = |f: f32| {
                let along = (f * AGENT_SPEED * PERIOD).min(d);
                if d > 0.0 {
                    agent.lerp(next, along / d)
                } else {
                    agent
                }
            };
            for (w, touching) in people.iter_mut().zip(contacts.iter_mut()) {
                let (mut hit, mut hit_holding) = (false, false);
                for s in 0..SUBSTEPS {
                    let (f0, f1) = (s as f32 / SUBSTEPS as f32, (s + 1) as f32 / SUBSTEPS as f32);
                    let o0 = w.at(t + f0 * PERIOD).0;
                    let o1 = w.at(t + f1 * PERIOD).0;
                    // A robot with a body touches a walker a radius sooner.
                    let reach = w.radius + prep.scenario.robot_radius;
                    hit |= contact(at(f0), at(f1), o0, o1, reach);
                    hit_holding |= contact(agent, agent, o0, o1, reach);
                }
                if hit && !*touching {
                    if moved && !hit_holding {
                        row.moved_into += 1;
                    } else {
                        row.ran_into += 1;
                    }
                }
                *touching = hit;
            }
            travelled += d as f64;
            agent = next;
            trail.push(agent);
            gif_frame(&mut gif, pictures, call, || {
                scene(p, &trail, &prep.scenario, 0, title(call))
            })?;
            row.time_s = (call + 1) as f64 * PERIOD as f64;
        }
        row.travelled_ratio = travelled / optimum;
        if let (Some((dir, _)), Some(painter)) = (pictures, painter.as_ref()) {
            let mut s = scene(
                p,
                &trail,
                &prep.scenario,
                0,
                title((row.time_s / PERIOD as f64) as u32),
            );
            s.reverse.clear();
            painter.png(&s, &dir.join(format!("{}.png", kind.name())))?;
        }
        people.clear();
        Ok(row)
    })
}

/// One run of a door scene. `closed`: the scenario with the door closed in its map (and its
/// own diffusion table), for `closed-door`.
#[allow(clippy::too_many_arguments)]
fn door_one(
    prep: &Prepared,
    closed: Option<&Prepared>,
    base: Named,
    door: &Door,
    kind: Kind,
    treatment: Treatment,
    seed: u64,
    t_exp: Duration,
    pictures: Option<(&Path, Option<u32>)>,
) -> Result<MovingRow> {
    let mut cfg = prep.fit(base);
    cfg.cfg.budget.t_exp = t_exp;
    cfg.cfg.motion = Motion::NONE;
    let shut = closed_grid(&prep.scenario.map, door);
    let optimum = match kind {
        Kind::ClosedDoor => closed.context("closed-door needs its map")?.optima()[0],
        _ => prep.optima()[0],
    }
    .unwrap_or(f64::NAN);
    let body = |p: &mut SimPlanner<'_, '_>| -> Result<MovingRow> {
        let goal = prep.scenario.goals[0];
        let mut row = MovingRow::new(kind, treatment, seed);
        let set = |p: &mut SimPlanner<'_, '_>, occupied: bool| -> Result<()> {
            for &c in &door.cells {
                p.set_cells(c, c, occupied).map_err(|e| anyhow!("{e}"))?;
            }
            Ok(())
        };
        // `closed_since`: when the door closed (while it is closed).
        let mut closed_since = None;
        if kind == Kind::ClosedDoor && treatment == Treatment::Live {
            set(p, true)?;
            closed_since = Some(0.0f32);
        }
        p.set_goal(goal).map_err(|e| anyhow!("{e}"))?;
        let mut agent = prep.scenario.start;
        let mut trail = vec![agent];
        let mut discs = Vec::new();
        let mut opened = false;
        let mut touching = false;
        let small = pictures.map(|_| Painter::for_scenario(&prep.scenario, 560));
        let mut gif = animation(small.as_ref(), pictures, kind)?;
        let shown = |s: &mut crate::draw::Scene, closed: bool| {
            if closed {
                let r = 0.6 * prep.scenario.map.grid().cell_size();
                s.circles.extend(
                    door.cells
                        .iter()
                        .map(|&(c, w)| Circle::new(prep.scenario.map.grid().cell_center(c, w), r)),
                );
            }
        };
        let title = |call: u32| {
            format!(
                "{} {}, {}, seed {seed}, t = {:.1} s",
                prep.scenario.name,
                kind.name(),
                treatment.name(),
                call as f32 * PERIOD
            )
        };
        let max_calls = 6000;
        let clock = virtual_clock(VIRTUAL_NS_PER_UNIT);
        let mut travelled = 0.0f64;
        for call in 0..max_calls {
            let t = call as f32 * PERIOD;
            if kind == Kind::Door {
                if closed_since.is_none() && !opened && agent.dist(door.centre) < DOOR_NEAR {
                    closed_since = Some(t);
                    if treatment == Treatment::Static {
                        for c in door_discs(door, prep.scenario.map.grid().cell_size()) {
                            discs.push(p.add_obstacle(c).map_err(|e| anyhow!("{e}"))?);
                        }
                    } else {
                        set(p, true)?;
                    }
                    if touches(&shut.grid(), agent, agent, prep.scenario.robot_radius) {
                        row.ran_into += 1;
                    }
                } else if closed_since.is_some_and(|c| t - c >= DOOR_CLOSED_S) {
                    closed_since = None;
                    opened = true;
                    for id in discs.drain(..) {
                        p.remove_obstacle(id).map_err(|e| anyhow!("{e}"))?;
                    }
                    if treatment == Treatment::Live {
                        set(p, false)?;
                    }
                }
            }
            let pr = p.plan(&clock, agent).map_err(|e| anyhow!("{e}"))?;
            row.max_work = row.max_work.max(pr.work);
            if pr.status == Status::Arrived {
                row.reached = true;
                break;
            }
            let next = agent.step_towards(pr.waypoint, AGENT_SPEED * PERIOD);
            let moved = next != agent;
            if !moved {
                row.waiting_s += PERIOD as f64;
            }
            // Closed (or closed in the map): a move that touches the door's cells.
            let shut_now = closed_since.is_some() || treatment == Treatment::Rebaked;
            let hit =
                shut_now && moved && touches(&shut.grid(), agent, next, prep.scenario.robot_radius);
            if hit && !touching {
                row.moved_into += 1;
            }
            touching = hit;
            travelled += agent.dist(next) as f64;
            agent = next;
            trail.push(agent);
            gif_frame(&mut gif, pictures, call, || {
                let mut s = scene(p, &trail, &prep.scenario, 0, title(call));
                shown(&mut s, closed_since.is_some());
                s
            })?;
            row.time_s = (call + 1) as f64 * PERIOD as f64;
        }
        row.travelled_ratio = travelled / optimum;
        if let Some((dir, _)) = pictures {
            let painter = Painter::for_scenario(&prep.scenario, 900);
            let mut s = scene(
                p,
                &trail,
                &prep.scenario,
                0,
                title((row.time_s / PERIOD as f64) as u32),
            );
            s.reverse.clear();
            shown(&mut s, closed_since.is_some());
            painter.png(&s, &dir.join(format!("{}.png", kind.name())))?;
        }
        Ok(row)
    };
    match treatment {
        Treatment::Rebaked => {
            let closed = closed.context("rebaked needs the closed map")?;
            with_planner(closed, cfg, seed, body)
        }
        Treatment::Live => with_live_planner(prep, cfg, seed, body),
        _ => with_planner(prep, cfg, seed, body),
    }
}

/// Runs `moving` on `prep` with the tuned planner.
pub fn moving(prep: &Prepared, args: &MovingArgs) -> Result<Vec<MovingRow>> {
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}", args.out.display()))?;
    let base = Named::default();
    let route = route(prep, base, args.route_calls)?;
    let mut jobs = Vec::new();
    for &kind in &args.kinds {
        for &treatment in kind.treatments() {
            for seed in 0..args.seeds {
                jobs.push((kind, treatment, seed));
            }
        }
    }
    let doors = args
        .kinds
        .iter()
        .any(|k| matches!(k, Kind::Door | Kind::ClosedDoor));
    let door = doors
        .then(|| door(&prep.scenario.map, &route))
        .transpose()?;
    // The scenario with the door closed in its map: its table is baked here, once.
    let closed = match &door {
        Some(d) if args.kinds.contains(&Kind::ClosedDoor) => {
            let mut sc = prep.scenario.clone();
            sc.map = closed_grid(&prep.scenario.map, d);
            // Inflated again for the robot's body, on the map with the door in it.
            let sc = sc.with_robot_radius(prep.scenario.robot_radius)?;
            let closed = Prepared::with_table(sc, prep.table);
            if base.metric == bi_am_rrt::MetricKind::Diffusion {
                closed.diffusion()?;
            }
            Some(closed)
        }
        _ => None,
    };
    if let Some(d) = &door {
        println!(
            "door: {} cells across the route at ({:.2}, {:.2}), {:.2} m wide{}",
            d.cells.len(),
            d.centre.x,
            d.centre.y,
            d.ends.0.dist(d.ends.1),
            closed
                .as_ref()
                .and_then(|c| c.bake_seconds.get())
                .map_or(String::new(), |s| format!(
                    "; rebaking the table took {s:.2} s"
                ))
        );
    }
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    let rows: Vec<MovingRow> = jobs
        .par_iter()
        .map(|&(kind, treatment, seed)| {
            let pictures = (seed == 0 && treatment == kind.pictured())
                .then_some((args.out.as_path(), args.animate));
            let r = match (&door, kind) {
                (Some(d), Kind::Door | Kind::ClosedDoor) => door_one(
                    prep,
                    closed.as_ref(),
                    base,
                    d,
                    kind,
                    treatment,
                    seed,
                    args.t_exp,
                    pictures,
                ),
                _ => one(
                    prep, base, &route, kind, treatment, seed, args.t_exp, pictures,
                ),
            };
            // Off a terminal the bar draws nothing: a plain line per run instead.
            if bar.is_hidden() {
                eprintln!(
                    "run {}/{}: {kind:?}, {treatment:?}, seed {seed} ({:.1} s)",
                    bar.position() + 1,
                    bar.length().unwrap_or(0),
                    bar.elapsed().as_secs_f64()
                );
            }
            bar.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    let mut w = csv::Writer::from_path(args.out.join("runs.csv"))?;
    for r in &rows {
        w.serialize(r)?;
    }
    w.flush()?;
    let settings = MovingSettings {
        map: prep.scenario.name.clone(),
        kinds: args.kinds.clone(),
        seeds: args.seeds,
        t_exp_ms: args.t_exp.as_secs_f64() * 1e3,
    };
    std::fs::write(
        args.out.join(SETTINGS_FILE),
        serde_json::to_string_pretty(&settings)?,
    )?;
    let summary = summarise(&settings, &rows);
    std::fs::write(args.out.join("summary.md"), &summary)?;
    chart(&rows, &args.kinds, &args.out.join("moving"))?;
    print!("{summary}");
    Ok(rows)
}

/// The settings file `moving` writes beside its runs.csv (`report` recognises the folder by it).
pub const SETTINGS_FILE: &str = "moving.json";

/// What a `moving` results folder was run with.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MovingSettings {
    /// The scenario.
    pub map: String,
    /// Scenes run.
    pub kinds: Vec<Kind>,
    /// Seeds per scene and treatment.
    pub seeds: u64,
    /// Virtual planning budget per call, ms.
    pub t_exp_ms: f64,
}

/// `report` on a `moving` results folder: the summary table and the chart (collisions,
/// waiting time, travelled / optimal per scene and treatment) rebuilt from its runs.csv, into
/// `out` (a `.md` file) and a folder beside it of the same name. Returns the chart stems.
pub fn report(results: &Path, out: &Path, command: &str) -> Result<Vec<PathBuf>> {
    let settings: MovingSettings = serde_json::from_str(
        &std::fs::read_to_string(results.join(SETTINGS_FILE))
            .with_context(|| format!("{}", results.join(SETTINGS_FILE).display()))?,
    )?;
    let mut rd = csv::Reader::from_path(results.join("runs.csv"))
        .with_context(|| format!("{}", results.join("runs.csv").display()))?;
    let rows: Vec<MovingRow> = rd.deserialize().collect::<std::result::Result<_, _>>()?;
    let stem = out.with_extension("");
    std::fs::create_dir_all(&stem).with_context(|| format!("{}", stem.display()))?;
    let chart_stem = stem.join("moving");
    chart(&rows, &settings.kinds, &chart_stem)?;
    let rel = stem
        .file_name()
        .map_or("report".into(), |n| n.to_string_lossy().into_owned());
    let md = format!(
        "{}\n![collisions, waiting and travelled / optimal]({rel}/moving.svg)\n\nRegenerate: `{command}`\n",
        summarise(&settings, &rows)
    );
    std::fs::write(out, md).with_context(|| format!("{}", out.display()))?;
    Ok(vec![chart_stem])
}

/// Per scene and treatment: runs, arrivals, collisions by kind, waiting, travelled / optimal.
fn summarise(settings: &MovingSettings, rows: &[MovingRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Moving obstacles on {}: {} seeds per scene and treatment, {} ms (virtual) per call\n",
        settings.map, settings.seeds, settings.t_exp_ms
    );
    let _ = writeln!(
        s,
        "| scene | treatment | runs | reached | collisions: moved into | ran into | runs with a collision | waiting s (median) | time s (median) | travelled / optimal (median) | evading calls | cornered calls | most work per call |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for &kind in &settings.kinds {
        for &treatment in kind.treatments() {
            let mine: Vec<&MovingRow> = rows
                .iter()
                .filter(|r| r.kind == kind && r.treatment == treatment)
                .collect();
            let med = |f: &dyn Fn(&MovingRow) -> f64| {
                let mut v: Vec<f64> = mine.iter().map(|r| f(r)).collect();
                median(&mut v).map_or("-".into(), |m| format!("{m:.3}"))
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                kind.name(),
                treatment.name(),
                mine.len(),
                mine.iter().filter(|r| r.reached).count(),
                mine.iter().map(|r| r.moved_into).sum::<u32>(),
                mine.iter().map(|r| r.ran_into).sum::<u32>(),
                mine.iter()
                    .filter(|r| r.moved_into + r.ran_into > 0)
                    .count(),
                med(&|r| r.waiting_s),
                med(&|r| r.time_s),
                med(&|r| r.travelled_ratio),
                mine.iter().map(|r| r.evading_calls).sum::<u32>(),
                mine.iter().map(|r| r.cornered_calls).sum::<u32>(),
                mine.iter().map(|r| r.max_work).max().unwrap_or(0),
            );
        }
    }
    s
}

/// Collisions, waiting time and travelled / optimal per scene, one bar per treatment.
fn chart(rows: &[MovingRow], kinds: &[Kind], stem: &Path) -> Result<()> {
    // The treatments of the scenes run, each in its own colour.
    let colour = |t: Treatment| match t {
        Treatment::Static => RGBColor(150, 150, 150),
        Treatment::Predicted => RGBColor(40, 110, 200),
        Treatment::Oracle => RGBColor(230, 140, 20),
        Treatment::Live => RGBColor(40, 160, 90),
        Treatment::Rebaked => RGBColor(140, 80, 170),
    };
    let shown: Vec<Treatment> = Treatment::ALL
        .into_iter()
        .filter(|t| kinds.iter().any(|k| k.treatments().contains(t)))
        .collect();
    let series: Vec<(RGBColor, String)> = shown
        .iter()
        .map(|&t| (colour(t), t.name().to_string()))
        .collect();
    let groups: Vec<String> = kinds.iter().map(|k| k.name().to_string()).collect();
    let panel = |title: &str,
                 y: &str,
                 from_zero: bool,
                 f: &dyn Fn(&[&MovingRow]) -> Option<f64>| BarPanel {
        title: title.into(),
        y_label: y.into(),
        log: false,
        groups: groups.clone(),
        series: series.clone(),
        reference: None,
        from_zero,
        values: kinds
            .iter()
            .map(|&k| {
                shown
                    .iter()
                    .map(|&t| {
                        let mine: Vec<&MovingRow> = rows
                            .iter()
                            .filter(|r| r.kind == k && r.treatment == t)
                            .collect();
                        if mine.is_empty() { None } else { f(&mine) }
                    })
                    .collect()
            })
            .collect(),
        notes: vec![None; kinds.len()],
    };
    let med = |mine: &[&MovingRow], f: fn(&MovingRow) -> f64| {
        let mut v: Vec<f64> = mine
            .iter()
            .map(|r| f(r))
            .filter(|v| v.is_finite())
            .collect();
        median(&mut v)
    };
    let bars = Bars {
        title: "Moving obstacles and live cells, by treatment".into(),
        cols: 3,
        panels: vec![
            panel("Collisions (all runs)", "contacts", true, &|m| {
                Some(m.iter().map(|r| (r.moved_into + r.ran_into) as f64).sum())
            }),
            panel("Waiting time (median)", "s", true, &|m| {
                med(m, |r| r.waiting_s)
            }),
            panel("Travelled / optimal (median)", "ratio", false, &|m| {
                med(m, |r| r.travelled_ratio)
            }),
        ],
    };
    render(&bars, stem)
}
