//! The planner end to end on the built-in maps, deterministic (virtual clock, fixed seeds).

mod common;

use std::time::Duration;

use bi_am_rrt::builtin::{self, Scenario};
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::error::InputError;
use bi_am_rrt::map::Circle;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Config, Euclidean, Map, Metric, MetricKind, Planner, Point, Storage};
use common::{Geodesic, Protocol, RunResult, drive, landmark_table, path_meets};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const N: usize = 2048;
const B: usize = 1024;
const K: usize = 4;

/// A virtual clock: 1 ns ticks, 30 ns per unit of work, 10 ns per reading.
fn clock() -> FakeClock {
    FakeClock::nanos().with_work_cost(30).with_step(10)
}

/// The test configuration: the paper's, with a shorter t_exp so runs stay quick.
fn test_config(c: Config, s: &Scenario) -> Config {
    let mut c = c.with_sigma(s.sigma);
    c.t_exp = Duration::from_millis(20);
    c
}

fn run_with<M: Metric>(
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

fn run(cfg: Config, s: &Scenario, seed: u64, proto: Protocol) -> RunResult {
    let cfg = test_config(cfg, s);
    match cfg.metric {
        MetricKind::Euclidean => run_with(cfg, s, Euclidean, seed, proto),
        MetricKind::Diffusion => {
            let table = landmark_table(&s.grid, 8);
            run_with(cfg, s, DiffusionTable::new(&table).unwrap(), seed, proto)
        }
        MetricKind::Geodesic => run_with(cfg, s, Geodesic::new(s.grid), seed, proto),
    }
}

fn all_twenty_reach(s: &Scenario) {
    let proto = Protocol {
        speed: 2.0,
        ..Protocol::default()
    };
    let mut failures = Vec::new();
    for cfg in Config::table1() {
        let r = run(cfg, s, 7, proto);
        if !r.reached || r.collisions > 0 {
            failures.push(format!("{}: {r:?}", cfg.name()));
        }
    }
    assert!(failures.is_empty(), "{}: {failures:#?}", s.name);
}

#[test]
fn all_twenty_reach_the_goal_in_the_open() {
    all_twenty_reach(&builtin::OPEN);
}

#[test]
fn all_twenty_reach_the_goal_out_of_the_bug_trap() {
    all_twenty_reach(&builtin::BUG_TRAP);
}

#[test]
fn all_twenty_reach_the_goal_through_the_maze() {
    all_twenty_reach(&builtin::MAZE);
}

#[test]
fn same_seed_same_run() {
    for cfg in [
        Config::bi_am_rrt(MetricKind::Diffusion),
        Config::rt_rrt(MetricKind::Euclidean),
    ] {
        let a = run(cfg, &builtin::MAZE, 3, Protocol::default());
        let b = run(cfg, &builtin::MAZE, 3, Protocol::default());
        assert_eq!(a, b, "{}", cfg.name());
        let c = run(cfg, &builtin::MAZE, 4, Protocol::default());
        assert_ne!(a, c, "another seed gives another run");
    }
}
