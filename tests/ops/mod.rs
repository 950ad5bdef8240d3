//! An interpreter of arbitrary byte strings as planner operation sequences, shared by the
//! fuzz target `ops` (`fuzz/fuzz_targets/ops.rs`) and the seeded test `tests/ops_sequences.rs`.
//!
//! The bytes choose a map (a built-in or a small grid drawn from the bytes), a metric
//! (Euclidean, or a diffusion-format table with coordinates from the bytes, some cells
//! unreachable), a configuration (any of the 20 planners, with bytes for the parameters that
//! may be anything valid), a tiny or small arena, and then a sequence of operations: set,
//! change or clear the goal; plan with the agent moved towards its waypoint, teleported, or
//! placed anywhere (outside the map, NaN); grow; add circles anywhere (on the agent, between
//! the agent and its waypoint, on the goal), still or moving, submit new states for them, and
//! remove them; a stated motion (agent and obstacle speeds, period, horizon); mark and clear
//! cells of a live overlay (any rectangle, some outside the grid); read the path; all with
//! frozen,
//! stepping, work-driven and jumping clocks. After every operation both trees must be valid, and
//! after every `plan` the waypoint rule must hold: the waypoint is the agent's position or
//! reachable from it over a segment free of the live map and every circle present, and no
//! edge flagged free crosses a live occupied cell.
#![allow(dead_code)]

use core::time::Duration;

use bi_am_rrt::builtin;
use bi_am_rrt::clearance::clearance_field;
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::map::{ObstacleId, OccupancyGrid, pack_grid};
use bi_am_rrt::metric::{DiffusionTable, ElementKind, TableHeader, write_table};
use bi_am_rrt::{Circle, Config, Euclidean, Map, Metric, Moving, Planner, Point, Storage};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Reads the fuzz bytes; past the end it yields zeros (so every input is a full program).
pub struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Self { data, at: 0 }
    }
    pub fn done(&self) -> bool {
        self.at >= self.data.len()
    }
    pub fn u8(&mut self) -> u8 {
        let b = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        b
    }
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }
    /// A fraction in [0, 1].
    pub fn unit(&mut self) -> f32 {
        self.u16() as f32 / u16::MAX as f32
    }
    /// A coordinate over `[-0.1, 1.1] x extent`, sometimes NaN or infinite.
    pub fn coord(&mut self, extent: f32) -> f32 {
        match self.u8() {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => -f32::INFINITY,
            3 => -0.0,
            4 => extent,
            _ => (self.unit() * 1.2 - 0.1) * extent,
        }
    }
    pub fn point(&mut self, w: f32, h: f32) -> Point {
        Point::new(self.coord(w), self.coord(h))
    }
}

const K: usize = 4;

/// Runs the program in `data`; `Err` names the broken promise.
pub fn run(data: &[u8]) -> Result<(), String> {
    let mut b = Bytes::new(data);
    let map_choice = b.u8();
    let mut own_bits = [0u8; 64];
    let grid = match map_choice % 4 {
        0 => builtin::OPEN.grid,
        1 => builtin::MAZE.grid,
        2 => builtin::BUG_TRAP.grid,
        _ => {
            // A small grid from the bytes: up to 22 x 22 cells, any cell size from 1 mm to 1 km.
            let (w, h) = (1 + (b.u8() % 22) as u16, 1 + (b.u8() % 22) as u16);
            let cell = [0.001f32, 0.25, 1.0, 3.0, 1000.0][b.u8() as usize % 5];
            let density = b.u8();
            let mut seed = b.u16() as u32 | 1;
            pack_grid(&mut own_bits, w, h, |_, _| {
                seed ^= seed << 13;
                seed ^= seed >> 17;
                seed ^= seed << 5;
                (seed & 0xff) < density as u32 / 2
            })
            .map_err(|e| format!("pack_grid: {e}"))?;
            match OccupancyGrid::new(&own_bits, w, h, cell) {
                Ok(g) => g,
                Err(e) => return Err(format!("a valid grid refused: {e}")),
            }
        }
    };
    let mut table = vec![0u8; 0];
    let use_table = b.u8() % 2 == 1;
    if use_table {
        table = table_from_bytes(&grid, &mut b);
    }
    let metric_table = if use_table {
        Some(DiffusionTable::new(&table).map_err(|e| format!("written table refused: {e}"))?)
    } else {
        None
    };
    match metric_table {
        Some(t) => run_with(grid, t, &mut b),
        None => run_with(grid, Euclidean, &mut b),
    }
}

/// A table over the grid whose coordinates are the cell's position plus noise from the bytes;
/// cells whose noise byte is 0 are unreachable.
fn table_from_bytes(grid: &OccupancyGrid<'_>, b: &mut Bytes<'_>) -> Vec<u8> {
    let header = TableHeader {
        map_hash: None,
        kind: if b.u8().is_multiple_of(2) {
            ElementKind::I16
        } else {
            ElementKind::F32
        },
        dims: 2,
        cols: grid.cols(),
        rows: grid.rows(),
        cell_size: grid.cell_size(),
        scale: grid.cell_size() / 16.0,
        layout: bi_am_rrt::metric::Layout::Uniform,
    };
    let noise: Vec<u8> = (0..32).map(|_| b.u8()).collect();
    let mut out = vec![0u8; header.table_len().unwrap()];
    let cell = grid.cell_size();
    write_table(&header, &mut out, |c, r, coords| {
        let n = noise[(c as usize * 7 + r as usize * 13) % noise.len()];
        coords[0] = (c as f32 + n as f32 / 64.0) * cell;
        coords[1] = r as f32 * cell;
        n != 0
    })
    .unwrap();
    out
}

fn run_with<M: Metric>(
    grid: OccupancyGrid<'_>,
    metric: M,
    b: &mut Bytes<'_>,
) -> Result<(), String> {
    let configs = bi_am_rrt::Named::table1();
    let mut cfg = configs[b.u8() as usize % configs.len()].cfg;
    let (w, h) = (grid.width_m(), grid.height_m());
    let span = w.max(h);
    cfg.search.e_max = span * (0.01 + b.unit() * 0.3);
    cfg.search.sigma = span * b.unit();
    cfg.memory.n_max = 1 + b.u8() as u16 % 30;
    cfg.search.p_goal = b.unit();
    cfg.search.p_uniform = b.unit();
    cfg.budget.t_exp = Duration::from_micros(1 + b.u16() as u64 * 4);
    cfg.budget.max_work = 2_000 + b.u16() as u32 * 2;
    cfg.budget.max_expansions = 1 + b.u8() as u32 * 4;
    // One byte of switches: the tactics (then each one by one from two more bytes), then
    // the tuned set's parameters one by one.
    let flags = b.u8();
    if flags & 1 != 0 {
        let bits = b.u16();
        for (i, name) in bi_am_rrt::Tactics::NAMES.iter().enumerate() {
            let on = if bits & (1 << i) != 0 {
                "true"
            } else {
                "false"
            };
            bi_am_rrt::config::set(&mut cfg, name, on).map_err(|e| format!("{name}: {e}"))?;
        }
    }
    if flags & 2 != 0 {
        cfg.memory.recycle_cover = (flags >> 2) as u16 % 4;
    }
    if flags & 8 != 0 {
        cfg.budget.clock_every = 256;
        // Paced readings up to 256 + 512 k units (k = 0: not paced).
        cfg.budget.clock_every_max = 256 + (b.u8() as u32 % 8) * 512;
    }
    if flags & 16 != 0 {
        cfg.memory.n_max_informed = cfg.memory.n_max.saturating_mul(4);
    }
    if flags & 32 != 0 {
        cfg.search.e_search = cfg.search.e_max * 3.0;
    }
    if flags & 128 != 0 {
        cfg.rewiring.path_shortcuts = 4;
        cfg.search.p_beacon = 0.2;
        cfg.search.p_gap = 0.4;
    }
    // A second byte: the steering's candidate count, and the root's step: off (the paper) or
    // from 5 % of e_max (a root within e_max / 10 of the agent, so `follow` steps past several
    // nodes in one call) to 1.05 e_max.
    let more = b.u8();
    if more & 16 != 0 {
        // Few candidates: a fan of one, or a batch split unevenly.
        cfg.search.steer_candidates = 1 + (more >> 5) as u16 * 7;
    }
    if more & 1 != 0 {
        cfg.rewiring.root_step = cfg.search.e_max * (0.05 + b.unit());
    }
    // A third byte: the paper's Meet over every pair, and Algorithms 4 and 6 as printed,
    // switch by switch.
    let third = b.u8();
    cfg.as_printed = bi_am_rrt::AsPrinted {
        alg4_takes_x_r2: third & 16 != 0,
        alg6_takes_x_r2: third & 32 != 0,
        alg6_cost: third & 64 != 0,
        alg6_clear: third & 128 != 0,
        meet_all_pairs: third & 8 != 0,
        alg4_free_enqueue: third & 4 != 0,
        alg5_gate: third & 2 != 0,
        alg6_clear_outside: third & 1 != 0,
    };
    // A fourth byte: a stated motion (module `motion`), any valid values.
    if b.u8() & 1 != 0 {
        cfg.motion = bi_am_rrt::Motion {
            agent_speed: b.unit() * 3.0,
            period: b.unit() * 0.5,
            horizon: b.unit() * 3.0,
            obstacle_speed: b.unit() * 3.0,
        };
    }
    let seed = b.u16() as u64;
    let start = b.point(w, h);
    match b.u8() % 3 {
        0 => drive::<_, 64, 16>(grid, metric, cfg, seed, start, b),
        1 => drive::<_, 8, 2>(grid, metric, cfg, seed, start, b),
        _ => drive::<_, 2, 1>(grid, metric, cfg, seed, start, b),
    }
}

/// A moving obstacle's report from the bytes: a velocity up to the map's size per second and
/// a horizon, either sometimes not finite.
fn moving(b: &mut Bytes<'_>, c: Circle, w: f32, h: f32) -> Moving {
    let v = Point::new(b.coord(w) - 0.5 * w, b.coord(h) - 0.5 * h);
    let m = Moving::new(c, v);
    match b.u8() % 4 {
        0 => m,
        1 => m.trusted_for(b.unit() * 5.0),
        2 => m.trusted_for(f32::NAN),
        _ => m.trusted_for(-1.0),
    }
}

fn drive<M: Metric, const N: usize, const B: usize>(
    grid: OccupancyGrid<'_>,
    metric: M,
    cfg: Config,
    seed: u64,
    start: Point,
    b: &mut Bytes<'_>,
) -> Result<(), String> {
    let mut storage = Box::new(Storage::<N, B>::new());
    let n = OccupancyGrid::bytes_needed(grid.cols(), grid.rows());
    let (mut overlay, mut space) = (vec![0u8; n], vec![0u8; n]);
    let map = if b.u8().is_multiple_of(2) {
        Map::<K>::new(grid)
            .with_overlay(&mut overlay)
            .map_err(|e| format!("overlay refused: {e}"))?
    } else {
        Map::<K>::new(grid)
    };
    // A robot body (issue 41): mostly none, else up to three cells, sometimes not valid (the
    // map then stays a point's and the planner must refuse the configuration's radius).
    let radius = match b.u8() % 8 {
        0..=3 => 0.0,
        4 => f32::NAN,
        5 => -grid.cell_size(),
        _ => b.unit() * 3.0 * grid.cell_size(),
    };
    let mut cfg = cfg;
    cfg.robot_radius = radius;
    let map = match map.with_body(radius, &mut space) {
        Ok(m) => m,
        Err(_) => {
            // Refused by name (bad radius, or no room): a point's map cannot hold the body.
            let plain = Map::<K>::new(grid);
            if Planner::new(
                &mut storage,
                plain,
                metric,
                XorShiftRng::seed_from_u64(seed),
                cfg,
                start,
            )
            .is_ok()
                && radius != 0.0
            {
                return Err(format!("a planner for radius {radius} on a point's map"));
            }
            return Ok(());
        }
    };
    // A clearance preference: mostly none, else a field for a margin up to four cells and a
    // weight up to 8 (sometimes a weight without a field, which must be refused by name).
    let mut field = vec![0u8; usize::from(grid.cols()) * usize::from(grid.rows())];
    let map = match b.u8() % 4 {
        0 | 1 => map,
        2 => {
            cfg.clearance_weight = b.unit() * 8.0;
            map
        }
        _ if cfg!(feature = "clearance") => {
            let margin = b.unit() * 4.0 * grid.cell_size();
            if clearance_field(&grid, radius, margin, &mut field).is_err() {
                return Err(format!("clearance field refused margin {margin}"));
            }
            cfg.clearance_weight = b.unit() * 8.0;
            map.with_clearance(&field)
                .map_err(|e| format!("clearance field refused: {e}"))?
        }
        _ => map,
    };
    let rng = XorShiftRng::seed_from_u64(seed);
    let Ok(mut p) = Planner::new(&mut storage, map, metric, rng, cfg, start) else {
        return Ok(()); // refused with an error: fine
    };
    let (w, h) = (grid.width_m(), grid.height_m());
    let clock = FakeClock::nanos().with_work_cost(b.u8() as u64 % 40);
    let mut agent = start;
    let mut waypoint = start;
    let mut ids: Vec<ObstacleId> = Vec::new();
    let mut path = vec![Point::ZERO; N];
    for _ in 0..64 {
        if b.done() {
            break;
        }
        // A call ran (and applied every edit).
        let mut called = false;
        let op = b.u8();
        match op % 14 {
            0 => {
                let g = b.point(w, h);
                let _ = p.set_goal(g);
            }
            1 => p.clear_goal(),
            2..=5 => {
                // Plan: the agent moves towards its last waypoint (most often), teleports, or
                // is placed anywhere.
                let next = match op % 14 {
                    2 | 3 => agent.step_towards(waypoint, 0.1 + b.unit() * cfg.search.e_max),
                    4 => b.point(w, h),
                    _ => p.root_position(),
                };
                match b.u8() % 4 {
                    0 => {}
                    1 => clock.advance(b.u16() as u64 * 1_000),
                    2 => clock.advance(u64::MAX / 2),
                    _ => clock.advance(b.u16() as u64),
                }
                match p.plan(&clock, next) {
                    Ok(pr) => {
                        called = true;
                        agent = next;
                        waypoint = pr.waypoint;
                        if pr.waypoint != agent && !p.map().free_now(agent, pr.waypoint) {
                            return Err(format!(
                                "waypoint {:?} not reachable from {agent:?}: {pr:?}",
                                pr.waypoint
                            ));
                        }
                        // The body's own check, by exact distances to the live cells.
                        if pr.waypoint != agent && !p.map().body_clear(agent, pr.waypoint) {
                            return Err(format!(
                                "waypoint {:?} brings the disc of {radius} m too near a wall \
                                 from {agent:?}: {pr:?}",
                                pr.waypoint
                            ));
                        }
                        if pr.work > cfg.budget.max_work as u64 + 64 * N as u64 + 100_000 {
                            return Err(format!("unbounded call: {pr:?}"));
                        }
                    }
                    Err(_) => {
                        if next.is_finite() && grid.contains(next) && !p.map().in_wall(next) {
                            return Err(format!("a valid agent position {next:?} refused"));
                        }
                    }
                }
            }
            6 => {
                let _ = p.grow(&clock);
                called = true;
            }
            7..=9 => {
                // A circle: anywhere, on the agent, between agent and waypoint, on the goal.
                let r = b.unit() * w.max(h) * 0.1;
                let c = match op % 14 {
                    7 => b.point(w, h),
                    8 => agent.lerp(waypoint, b.unit()),
                    _ => p.goal().unwrap_or(agent),
                };
                let added = if b.u8().is_multiple_of(2) {
                    p.add_obstacle(Circle::new(c, r))
                } else {
                    p.add_moving_obstacle(moving(b, Circle::new(c, r), w, h))
                };
                if let Ok(id) = added {
                    ids.push(id);
                }
            }
            10 => {
                if !ids.is_empty() {
                    let id = ids.remove(b.u8() as usize % ids.len());
                    p.remove_obstacle(id).map_err(|e| format!("remove: {e}"))?;
                }
            }
            11 => {
                let _ = p.path(&mut path);
            }
            13 => {
                // Mark or clear a rectangle of cells, sometimes reaching outside the grid.
                let corner = |b: &mut Bytes<'_>, n: u16| b.u16() % n.saturating_add(2);
                let a = (corner(b, grid.cols()), corner(b, grid.rows()));
                let c = (corner(b, grid.cols()), corner(b, grid.rows()));
                let _ = p.set_cells(a, c, b.u8().is_multiple_of(2));
            }
            _ => {
                // Submit a new state for an obstacle (or an unknown id): moved anywhere, any
                // velocity and horizon, sometimes not finite.
                let id = if ids.is_empty() || b.u8() == 0 {
                    ObstacleId(b.u16() as u32)
                } else {
                    ids[b.u8() as usize % ids.len()]
                };
                let r = b.unit() * w.max(h) * 0.1;
                let c = b.point(w, h);
                let _ = p.update_obstacle(id, moving(b, Circle::new(c, r), w, h));
            }
        }
        if called {
            // The call applied every edit: an edge flagged free crosses no live occupied cell.
            let live = p.map().live();
            for t in [p.tree(), p.reverse_tree()] {
                for id in t.ids() {
                    if let (Some(q), Some(false)) = (t.parent(id), t.edge_blocked(id)) {
                        let (a, c) = (t.position(q).unwrap(), t.position(id).unwrap());
                        if !live.segment_free(a, c) {
                            return Err(format!("edge {a:?}-{c:?} flagged free crosses a cell"));
                        }
                    }
                }
            }
        }
        p.tree()
            .validate()
            .map_err(|e| format!("forward tree: {e:?}"))?;
        p.reverse_tree()
            .validate()
            .map_err(|e| format!("reverse tree: {e:?}"))?;
    }
    Ok(())
}
