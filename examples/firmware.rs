//! Firmware example: the paper's best planner inside Cortex-M4F firmware (an STM32F405, as on
//! the `netduinoplus2` board that `qemu-system-arm` emulates; memory map in `memory.x`).
//!
//! Two missions share one planner storage, a `static` of 4,096 nodes (two trees of 2,048) that
//! is all zero when empty, so it lands in `.bss` (no flash, no stack temporary):
//!
//! 1. **The twin** (`examples/shared/mission.rs`): Bi-AM-RRT*(E) across the built-in 40 m field
//!    on a *virtual* clock advanced by the planner's work, so it prints the same line as
//!    `examples/twin.rs` on the host, bit for bit (CI compares them).
//! 2. **Office, in real time**: Bi-AM-RRT*(D) from the office scenario's start to its goal 1
//!    (or the start and goal 1 of whichever scenario was exported last, a nav2 map say),
//!    with the occupancy grid and the diffusion table in flash (exported by
//!    `host-sim export`), `t_exp` = 150 ms measured on SysTick
//!    ([`bi_am_rrt::cortex::SysTickClock`], 168 MHz core clock), and the agent moving as in the
//!    benchmark protocol (0.7 m per call once the goal is in the tree). It reports the time of
//!    every `plan` call (median and worst), the nodes, the path travelled with a checksum of
//!    the agent's positions, and the stack high-water mark (the stack is painted at reset).
//!
//! Figures go out over semihosting; QEMU exits with status 0 when both missions reached their
//! goals without collision.
//!
//! ```sh
//! cargo run --release -p host-sim -- export --scenarios ../shared/maps/scenarios.toml \
//!     --scenario office --out target/flash
//! BIAMRRT_FLASH_DIR=$PWD/target/flash cargo run --release --example firmware \
//!     --target thumbv7em-none-eabihf --features firmware-example
//! ```
#![no_std]
#![no_main]

#[path = "shared/mission.rs"]
mod mission;

/// The scenario last exported by `host-sim export` to `BIAMRRT_FLASH_DIR` (`scenario.rs`:
/// grid and table as flash `static`s): the office in CI, or any other (a nav2 map).
#[allow(dead_code)]
mod scenario {
    include!(concat!(env!("BIAMRRT_FLASH_DIR"), "/scenario.rs"));
}

use bi_am_rrt::agent::{Protocol, run_to_goal};
use bi_am_rrt::clock::Clock;
use bi_am_rrt::cortex::{SysTickClock, on_systick_wrap};
use bi_am_rrt::metric::fnv1a32;
use bi_am_rrt::{Config, DiffusionTable, Map, MetricKind, OccupancyGrid, Planner, Point, Storage};
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::{debug, hprintln};
use mission::MissionStorage;
use panic_semihosting as _;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use static_cell::ConstStaticCell;

/// The core clock of the STM32F405 (and of QEMU's model of it).
const CORE_HZ: u32 = 168_000_000;
/// Most `plan` calls recorded (and made) in the office mission.
const MAX_CALLS: usize = 600;

/// The planner's storage: built at compile time, all zero bytes, so it lives in `.bss`.
static STORAGE: ConstStaticCell<MissionStorage> = ConstStaticCell::new(Storage::new());
/// Per-call times of the office mission, in units of 10 us.
static CALL_TIMES: ConstStaticCell<[u16; MAX_CALLS]> = ConstStaticCell::new([0; MAX_CALLS]);

#[exception]
fn SysTick() {
    on_systick_wrap();
}

#[entry]
fn main() -> ! {
    let ok = run();
    hprintln!("stack high-water: {} bytes", stack_high_water());
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

fn run() -> bool {
    let storage = STORAGE.take();
    let times = CALL_TIMES.take();
    // 1. The twin: same line as the host's.
    let twin_ok = match mission::fly(storage) {
        Some(m) => {
            hprintln!("{}", m);
            m.ok()
        }
        None => {
            hprintln!("twin mission refused its start or goal");
            false
        }
    };
    // 2. Office on the real clock.
    let Some(cp) = cortex_m::Peripherals::take() else {
        return false;
    };
    let clock = SysTickClock::start(cp.SYST, CORE_HZ);
    twin_ok && exported_mission(storage, times, &clock)
}

fn exported_mission(storage: &mut MissionStorage, times: &mut [u16], clock: &SysTickClock) -> bool {
    let (Ok(grid), Ok(table)) = (
        OccupancyGrid::new(
            &scenario::GRID,
            scenario::COLS,
            scenario::ROWS,
            scenario::CELL,
        ),
        DiffusionTable::new(&scenario::TABLE),
    ) else {
        hprintln!("scenario: bad grid or table in flash");
        return false;
    };
    let map: Map<'static, 4> = Map::new(grid);
    // Lengths that follow the map (Table 2's on the office), `sigma` as the scenario gives it.
    // `BIAMRRT_TUNED=1` at build time flies the tuned set instead of the paper's.
    let base = Config::bi_am_rrt(MetricKind::Diffusion);
    let base = if option_env!("BIAMRRT_TUNED").is_some() {
        base.tuned()
    } else {
        base
    };
    let cfg = base.for_grid(&grid).with_sigma(scenario::SIGMA);
    let rng = XorShiftRng::seed_from_u64(1);
    let start = Point::new(scenario::START.0, scenario::START.1);
    let goal = Point::new(scenario::GOALS[0].0, scenario::GOALS[0].1);
    let Ok(mut planner) = Planner::new(storage, map, table, rng, cfg, start) else {
        hprintln!("scenario: planner refused its start");
        return false;
    };
    let protocol = Protocol {
        max_calls: MAX_CALLS as u32,
        ..Protocol::default()
    };
    let cycles_per_10us = u64::from(CORE_HZ / 100_000);
    let mut last = clock.now();
    let mut worst = 0u64;
    let mut calls = 0usize;
    let mut trail = 0x811c_9dc5u32;
    let mut nodes = 0usize;
    let result = run_to_goal(&mut planner, clock, goal, &protocol, |p, agent, _| {
        let now = clock.now();
        let dt = now.saturating_sub(last);
        worst = worst.max(dt);
        if let Some(slot) = times.get_mut(calls) {
            *slot = u16::try_from(dt / cycles_per_10us).unwrap_or(u16::MAX);
        }
        calls += 1;
        nodes = p.tree().len();
        // FNV-1a over the agent's positions: the path's checksum.
        let mut bytes = [0u8; 8];
        bytes[..4].copy_from_slice(&agent.x.to_bits().to_le_bytes());
        bytes[4..].copy_from_slice(&agent.y.to_bits().to_le_bytes());
        trail = bytes
            .iter()
            .fold(trail, |h, &b| (h ^ u32::from(b)).wrapping_mul(0x0100_0193));
        last = clock.now();
    });
    let Ok(r) = result else {
        hprintln!("scenario: goal refused");
        return false;
    };
    let recorded = &mut times[..calls.min(MAX_CALLS)];
    recorded.sort_unstable();
    let median = recorded.get(recorded.len() / 2).copied().unwrap_or(0);
    let budget = clock.ticks(cfg.t_exp);
    let search_ms = r.search_ticks.map_or(0, |t| t / u64::from(CORE_HZ / 1_000));
    hprintln!(
        "{} on {} (real clock, t_exp {} ms): reached {}, search {} ms, path {} m, \
         {} collisions, {} nodes at goal, {} nodes at the end, {} plan calls",
        cfg.name(),
        scenario::NAME,
        cfg.t_exp.as_millis(),
        r.reached,
        search_ms,
        r.travelled,
        r.collisions,
        r.nodes_at_goal.unwrap_or(0),
        nodes,
        r.calls
    );
    hprintln!(
        "per-call time: median {}.{:02} ms, worst {}.{:03} ms ({} cycles, overrun {} us); path checksum {:08x}",
        median / 100,
        median % 100,
        worst / u64::from(CORE_HZ / 1_000),
        (worst % u64::from(CORE_HZ / 1_000)) / u64::from(CORE_HZ / 1_000_000),
        worst,
        worst.saturating_sub(budget) / u64::from(CORE_HZ / 1_000_000),
        trail
    );
    hprintln!(
        "grid {} bytes and table {} bytes in flash (table checksum {:08x})",
        scenario::GRID.len(),
        scenario::TABLE.len(),
        fnv1a32(&scenario::TABLE)
    );
    r.reached && r.collisions == 0
}

/// Bytes of stack ever used: `cortex-m-rt` (feature `paint-stack`) fills the stack with
/// `0xCCCC_CCCC` at reset; the lowest word that no longer holds it marks the deepest use.
fn stack_high_water() -> usize {
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
