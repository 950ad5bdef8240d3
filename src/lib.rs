//! # bi-am-rrt
//!
//! A real-time motion planner for small robots: Bi-AM-RRT*, the bidirectional RRT* guided by an
//! assisting metric with a new rewiring scheme (Zhang et al.), built on AM-RRT* (Armstrong et
//! al., 2021) and RT-RRT* (Naderi et al., 2015).
//!
//! The crate is `#![no_std]`, never allocates and contains no `unsafe`. All storage has a
//! capacity fixed at compile time (const generics), every loop is bounded, and time is whatever
//! [`clock::Clock`] the caller passes, so the same code runs in microcontroller firmware and in
//! the desktop simulator (`host-sim`, in the repository).
//!
//! ## Quick start
//!
//! A [`Planner`] borrows its [`Storage`] (two trees) and owns a [`Map`] (a borrowed
//! [`OccupancyGrid`] plus dynamic obstacles), a [`Metric`], a random generator and a
//! [`Config`]. Call [`Planner::plan`] once per control period with the agent's position: it
//! works for at most `t_exp` of the clock you pass and returns a [`Progress`] whose waypoint is
//! always reachable from the agent over a free segment.
//!
//! ```
//! use bi_am_rrt::builtin;
//! use bi_am_rrt::clock::FakeClock;
//! use bi_am_rrt::{Config, Euclidean, Map, Planner, Status, Storage};
//! use rand_core::SeedableRng;
//! use rand_xorshift::XorShiftRng;
//!
//! // Two trees of 1,024 nodes with 128 index buckets each: 46,728 bytes on a Cortex-M
//! // (`Storage::BYTES`); a firmware keeps it in a `static`.
//! let mut storage: Box<Storage<1024, 128>> = Box::default();
//! let scenario = &builtin::OPEN; // a 40 m map kept in flash
//! let map: Map<'_, 4> = Map::new(scenario.grid); // room for 4 dynamic obstacles
//! // The tuned Bi-AM-RRT* with lengths fitted to the map (`Config::paper()`: the paper's).
//! let mut cfg = Config::default().for_grid(&scenario.grid);
//! cfg.budget.t_exp = core::time::Duration::from_millis(10); // the time of one call
//! let rng = XorShiftRng::seed_from_u64(7);
//! let mut planner = Planner::new(&mut storage, map, Euclidean, rng, cfg, scenario.start).unwrap();
//! planner.set_goal(scenario.goals[0]).unwrap();
//!
//! // A virtual clock (time advances with the work done): the same run on any machine. A
//! // firmware passes a real one (`cortex::SysTickClock`, feature `cortex-m`).
//! let clock = FakeClock::nanos().with_work_cost(12).with_step(1);
//! let mut agent = scenario.start;
//! for _ in 0..400 {
//!     let progress = planner.plan(&clock, agent).unwrap();
//!     agent = agent.step_towards(progress.waypoint, 0.7); // the robot drives
//!     if progress.status == Status::Arrived {
//!         break;
//!     }
//! }
//! assert_eq!(agent, scenario.goals[0]);
//! ```
//!
//! Positions are metres in the grid's frame ([`OccupancyGrid`]: from the corner of cell
//! `(0, 0)`, `x` along columns, `y` along rows). The paper's diffusion metric is a table baked
//! on the host (`host-sim bake`; `host-sim export` writes a firmware's map, table and scenario
//! as flash data) and read in place by [`DiffusionTable`]; [`Euclidean`] needs none.
//!
//! ## A tour of the modules
//!
//! In the order data flows through a `plan` call; the file list reads the same way (modules
//! in `code` are private: the planner's own work, no API).
//!
//! 1. What the caller gives:
//!    - [`geometry`]: points, segments, uniform sampling in a disc and in the informed ellipse.
//!    - [`config`]: [`Config`], its groups and the named configurations of the paper's
//!      Table 1 (the 20 planners are configurations of one planner), the paper's Table 2
//!      values and the lengths fitted to a map.
//!    - [`map`]: the world. `map/grid.rs` borrows a bit-packed occupancy grid (it can sit in
//!      flash) and holds the exact `free_path` test; `obstacles.rs` the dynamic circles, still
//!      or moving; `live.rs` the live cells a lidar marks; `body.rs` the robot's disc; the
//!      [`clearance`] field (feature `clearance`); `mod.rs` the [`Map`] that joins them.
//!    - [`metric`]: the assisting metric `d_A` (section 3.1): the [`Metric`] trait and
//!      [`Euclidean`] (`mod.rs`), the diffusion table's reader (`table.rs`) and its binary
//!      format (`format.rs`).
//!    - [`clock`]: the caller's [`clock::Clock`], the deadlines of `t_exp`, `t_root`, `t_goal`
//!      and a fake/virtual clock; `clock/meter.rs`: the work each call charges, the work cap and the
//!      paced readings ([`clock::Meter`]); `cortex` (feature `cortex-m`): SysTick and DWT.
//! 2. What the planner keeps:
//!    - [`tree`]: the fixed-capacity arena with cached, blocked-aware costs (`Cost`,
//!      `UpdateEdge`, `SetRoot`); [`index`]: the bucket index behind `Nearest` and `Nearby`.
//!    - `store`: one tree's storage (arena, index and the rewiring sweeps' state), two of which
//!      make a [`Storage`]; `sweep`: the sweeps' bounded queue and stack.
//! 3. What one call does ([`planner`], paper Algorithm 1):
//!    - `planner/step.rs`: the call's loop, expansion and rewiring sharing `t_exp`;
//!      `planner/follow.rs`: the root follows the agent, the waypoint rule and the
//!      [`Progress`] returned; `planner/meet.rs`: meet and graft of the two trees;
//!      `planner/updates.rs`: obstacles and live cells changed between calls.
//!    - `sample`: every way a state is drawn (uniform, informed ellipse, goal, goal line).
//!    - `expand`: Algorithm 2 (sample, nearest, steer, admit by the density rule, parent,
//!      insert) and, in `expand/admit.rs`, what a full arena does.
//!    - `rewire`: Algorithms 3-6 (`root.rs`, `goal.rs`), RT-RRT*'s random rewiring
//!      (`random.rs`) and the tuned path shortcuts (`shortcuts.rs`).
//!    - [`motion`]: the waypoint rule against moving obstacles (beyond the paper).
//!    - `roadmap` (feature `roadmap`): a reduced visibility graph baked with the map and
//!      searched once per goal for the first solution (beyond the paper; the `roadmap`
//!      tactic).
//! 4. Around it: [`agent`], the papers' benchmark protocol (one leg from start to goal);
//!    [`builtin`], the built-in scenarios in flash; [`error`], the small error enums; `slots`,
//!    panic-free array access.
//!
//! ## Features
//!
//! - `defmt`: `defmt::Format` for the public types (for firmware logging).
//! - `cortex-m`: the `cortex` module, real [`clock::Clock`]s on SysTick and on the DWT cycle
//!   counter (Cortex-M3 and up).
//! - `embassy-time`: `clock::EmbassyClock`, a [`clock::Clock`] on `embassy_time::Instant`
//!   for firmware built on Embassy (the application provides the time driver).
//! - `rand-core-06`: `Rng06`, a `rand_core` 0.6 generator (a HAL's hardware RNG) as the
//!   planner's `rand_core` 0.10 `Rng`.
//! - `clearance`: the clearance preference ([`clearance`], `Config::clearance_weight`): paths
//!   keep off walls where the space allows. Off by default (a firmware without it carries
//!   none of its code).
//! - `roadmap`: the `roadmap` module and `Planner::set_roadmap`: a roadmap baked with the map
//!   (`host-sim` bakes one per scenario) gives a new goal its first path at once. Off by
//!   default (a firmware without it carries none of its code).
//! - `hw-sqrt`: the target's square-root instruction (`vsqrt.f32` on a Cortex-M4F) instead of
//!   `libm`'s routine, the same bits (IEEE 754 rounds both correctly); needs nightly Rust.
//! - `firmware-example`: builds the repository's Cortex-M firmware examples (thumb targets
//!   only); not for use as a dependency.
//!
//! ## Memory
//!
//! RAM is the [`Storage`] (42 bytes a node and 4 a bucket for both trees, plus a fixed
//! 3.2 KB: [`Storage::BYTES`]), the [`Planner`] itself and the call's stack (a few KB; the
//! repository's README has the firmware examples' measured RAM and flash). The map and the
//! diffusion table are borrowed and can sit in flash.
//!
//! ## Randomness on the chip
//!
//! The planner takes any `rand_core::Rng` (`rand_core` 0.10). For repeatable runs use a
//! seeded software generator such as `rand_xorshift::XorShiftRng::seed_from_u64`, as the
//! examples do. A HAL's hardware generator (most implement `rand_core` 0.6's `RngCore`) plugs
//! in through `Rng06` (feature `rand-core-06`); or, better for speed and repeatability, seed a
//! software generator once from it.

#![no_std]
#![forbid(unsafe_code)]
// `hw-sqrt`: the FPU's square root through `core::f32::math` (unstable: nightly Rust).
#![cfg_attr(feature = "hw-sqrt", feature(core_float_math))]
// docs.rs (nightly, `--cfg docsrs`): each optional item is marked with the feature it needs.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![warn(missing_docs)]
// No reachable panic (promise 2): the non-test code may not index, unwrap, panic, overflow an
// integer or truncate in a cast. Local `allow`s carry a one-line reason; the panic-never build
// (`firmware/panic-never`) checks the result at link time.
#![cfg_attr(
    not(test),
    deny(
        clippy::indexing_slicing,
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::unreachable,
        clippy::todo,
        clippy::unimplemented,
        clippy::arithmetic_side_effects,
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        clippy::cast_possible_wrap
    )
)]

pub mod agent;
pub mod builtin;
pub use map::clearance;
pub mod clock;
pub mod config;
#[cfg(feature = "cortex-m")]
pub mod cortex;
pub mod error;
mod expand;
pub mod geometry;
pub mod index;
pub mod map;
pub mod metric;
pub mod motion;
pub mod planner;
mod rewire;
#[cfg(feature = "roadmap")]
#[cfg_attr(docsrs, doc(cfg(feature = "roadmap")))]
pub mod roadmap;
mod sample;
mod slots;
mod store;
mod sweep;
pub mod tree;

pub use config::{AsPrinted, Base, Config, MetricKind, Motion, Named, RewireMode, Tactics};
pub use geometry::Point;
pub use map::{Circle, Map, Moving, OccupancyGrid};
pub use metric::{DiffusionTable, Euclidean, Metric};
pub use planner::{PathInfo, Planner, Progress, Stats, Status, Storage, Wait};
#[cfg(feature = "rand-core-06")]
pub use sample::Rng06;

/// The crate's README (its page on crates.io) is compiled and run by `cargo test --doc`; the
/// repository's README by the `doctests` crate of the workspace.
#[cfg(doctest)]
#[doc = include_str!("../README-crate.md")]
struct ReadmeDoctests;
