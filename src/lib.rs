//! # bi-am-rrt
//!
//! A real-time motion planner for small robots: Bi-AM-RRT*, the bidirectional RRT* guided by an
//! assisting metric with a new rewiring scheme (Zhang et al.), built on AM-RRT* (Armstrong et
//! al., 2021) and RT-RRT* (Naderi et al., 2015).
//!
//! The crate is `#![no_std]`, never allocates and contains no `unsafe`. All storage has a
//! capacity fixed at compile time (const generics), every loop is bounded, and time is whatever
//! [`clock::Clock`] the caller passes, so the same code runs in microcontroller firmware and in
//! the desktop simulator (`host-sim`).
//!
//! ## Architecture
//!
//! The modules in the order data flows through a `plan` call; the file list reads the same way
//! (modules in `code` are private: the planner's own work, no API).
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
//! 4. Around it: [`agent`], the papers' benchmark protocol (one leg from start to goal);
//!    [`builtin`], the built-in scenarios in flash; [`error`], the small error enums; `slots`,
//!    panic-free array access.
//!
//! ## Example
//!
//! Build a map, grow a tiny tree by hand and ask the spatial index for a neighbour:
//!
//! ```
//! use bi_am_rrt::geometry::Point;
//! use bi_am_rrt::index::SpatialIndex;
//! use bi_am_rrt::map::{pack_grid, Circle, Map, OccupancyGrid};
//! use bi_am_rrt::tree::Tree;
//!
//! // A 10 m x 10 m map of 1 m cells with a wall at column 5, rows 0..8.
//! let mut bits = [0u8; OccupancyGrid::bytes_needed(10, 10)];
//! pack_grid(&mut bits, 10, 10, |col, row| col == 5 && row < 8).unwrap();
//! let mut map: Map<'_, 4> = Map::new(OccupancyGrid::new(&bits, 10, 10, 1.0).unwrap());
//!
//! let (start, goal) = (Point::new(1.5, 1.5), Point::new(8.5, 1.5));
//! assert!(!map.free_path(start, goal)); // the wall is in the way
//! let around = Point::new(5.5, 9.5);
//! assert!(map.free_path(start, around) && map.free_path(around, goal));
//!
//! let mut tree: Tree<64> = Tree::new();
//! let root = tree.reset(start);
//! let mid = tree.add(around, root, false).unwrap();
//! let end = tree.add(goal, mid, false).unwrap();
//! let mut path = [Point::ZERO; 8];
//! let n = tree.path_points(end, &mut path).unwrap();
//! assert_eq!(&path[..n], &[start, around, goal]);
//!
//! let mut index: SpatialIndex<64, 16> = SpatialIndex::with_bounds(10.0, 10.0, 2.5).unwrap();
//! for id in tree.ids() {
//!     index.insert(id, tree.position(id).unwrap()).unwrap();
//! }
//! let (nearest, _) = index.nearest(Point::new(7.0, 3.0), tree.positions()).unwrap();
//! assert_eq!(nearest, end);
//!
//! // A dynamic obstacle appears on the second edge: its cost becomes blocked.
//! map.obstacles_mut().add(Circle::new(Point::new(7.0, 5.5), 0.5)).unwrap();
//! tree.reflag_edges(|a, b| map.obstacles().blocks_segment(a, b));
//! assert!(tree.cost(end).unwrap().blocked);
//! ```
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
//!   keep off walls where the space allows. Off by default (3.2 KB of flash when on).
//!
//! ## Randomness on the chip
//!
//! The planner takes any `rand_core::Rng` (`rand_core` 0.10, the trait behind `TryRng` with
//! an infallible error). For repeatable runs use a seeded software generator such as
//! `rand_xorshift::XorShiftRng::seed_from_u64`, as the examples do. To draw from a hardware
//! generator, wrap the HAL's driver in a type implementing `rand_core::TryRng` (most HALs
//! implement the older `rand_core` 0.6 `RngCore`; its `next_u32` maps straight onto
//! `try_next_u32`), or, better for speed and repeatability, seed a software generator once
//! from it: `XorShiftRng::from_seed(hw_bytes)`.

#![no_std]
#![forbid(unsafe_code)]
// `hw-sqrt`: the FPU's square root through `core::f32::math` (unstable: nightly Rust).
#![cfg_attr(feature = "hw-sqrt", feature(core_float_math))]
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

/// The README's example is compiled and run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
