//! A planner on a built-in scenario end to end: the test configuration (the paper's, with a
//! 20 ms budget), runs of the agent protocol with any of the three metrics, and a planner
//! built for a test to drive by hand.

use std::time::Duration;

use bi_am_rrt::builtin::Scenario;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Config, Euclidean, Map, Metric, MetricKind, Named, Planner, Storage};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

use super::{Geodesic, Protocol, RunResult, drive, landmark_table};
pub use super::{K, clock};

pub const N: usize = 2048;

pub const B: usize = 1024;

/// The test configuration: the paper's, with a shorter t_exp so runs stay quick.
pub fn test_config(c: Config, s: &Scenario) -> Config {
    let mut c = c.with_sigma(s.sigma);
    c.budget.t_exp = Duration::from_millis(20);
    c
}

pub fn run_with<M: Metric>(
    cfg: Config,
    s: &Scenario,
    metric: M,
    seed: u64,
    proto: Protocol,
) -> RunResult {
    let mut storage = Box::new(Storage::<N, B>::new());
    let map = Map::<K>::new(s.grid);
    let rng = XorShiftRng::seed_from_u64(seed);
    let mut planner = Planner::new(&mut storage, map, metric, rng, cfg, s.start).unwrap();
    let clock = clock();
    drive(&mut planner, &clock, s.goals[0], proto, |_, _, _| {})
}

pub fn run(planner: Named, s: &Scenario, seed: u64, proto: Protocol) -> RunResult {
    let cfg = test_config(planner.cfg, s);
    match planner.metric {
        MetricKind::Euclidean => run_with(cfg, s, Euclidean, seed, proto),
        MetricKind::Diffusion => {
            let table = landmark_table(&s.grid, 8);
            run_with(cfg, s, DiffusionTable::new(&table).unwrap(), seed, proto)
        }
        MetricKind::Geodesic => run_with(cfg, s, Geodesic::new(s.grid), seed, proto),
        MetricKind::Other => unreachable!("the tests' planners are Table 1's"),
    }
}

pub fn all_twenty_reach(s: &Scenario) {
    let proto = Protocol {
        speed: 2.0,
        ..Protocol::default()
    };
    let mut failures = Vec::new();
    for cfg in Named::table1() {
        let r = run(cfg, s, 7, proto);
        if !r.reached || r.collisions > 0 {
            failures.push(format!("{}: {r:?}", cfg.name()));
        }
    }
    assert!(failures.is_empty(), "{}: {failures:#?}", s.name);
}

pub fn planner_on<'s, M: Metric, const NN: usize, const BB: usize>(
    storage: &'s mut Storage<NN, BB>,
    s: &'static Scenario,
    metric: M,
    cfg: Config,
    seed: u64,
) -> Planner<'s, 'static, M, XorShiftRng, NN, BB, K> {
    let cfg = test_config(cfg, s);
    Planner::new(
        storage,
        Map::new(s.grid),
        metric,
        XorShiftRng::seed_from_u64(seed),
        cfg,
        s.start,
    )
    .unwrap()
}

/// A 30 m map with a closed room (walls all round) holding the goal.
pub fn room_map() -> Vec<u8> {
    use bi_am_rrt::builtin::{Block, pack_blocks};
    let blk = |x0, y0, x1, y1| Block { x0, y0, x1, y1 };
    pack_blocks::<{ bi_am_rrt::OccupancyGrid::bytes_needed(30, 30) }>(
        30,
        30,
        &[
            blk(18, 18, 28, 19),
            blk(18, 27, 28, 28),
            blk(18, 18, 19, 28),
            blk(27, 18, 28, 28),
        ],
    )
    .to_vec()
}

/// The most one expansion step may add after the call's last check (`Planner::plan` docs):
/// O(N) with a generous constant.
pub fn step_bound(n: usize) -> u64 {
    64 * n as u64 + 100_000
}
