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
//!    (or the start and goal 1 of whichever scenario was exported last, a nav2 map say;
//!    exported with `--all-goals`, through all its goals in turn, `firmware/sequence.sh`),
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
//!     --maps office --planners paper --out target/flash
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

#[path = "shared/office.rs"]
mod office;

use bi_am_rrt::Storage;
use bi_am_rrt::clock::Clock;
use bi_am_rrt::cortex::{SysTickClock, on_systick_wrap};
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::debug;
pub(crate) use cortex_m_semihosting::hprintln;
use mission::MissionStorage;
use office::CallTimes;
use panic_semihosting as _;
use static_cell::ConstStaticCell;

/// The core clock of the STM32F405 (and of QEMU's model of it).
const CORE_HZ: u32 = 168_000_000;

/// The planner's storage: built at compile time, all zero bytes, so it lives in `.bss`.
static STORAGE: ConstStaticCell<MissionStorage> = ConstStaticCell::new(Storage::new());
/// Per-call times of the office mission.
static CALL_TIMES: ConstStaticCell<CallTimes> = ConstStaticCell::new(CallTimes::new());

#[exception]
fn SysTick() {
    on_systick_wrap();
}

#[entry]
fn main() -> ! {
    let ok = run();
    hprintln!("stack high-water: {} bytes", office::stack_high_water());
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
        Ok(m) => {
            hprintln!("{}", m);
            m.ok()
        }
        Err(e) => {
            hprintln!("twin mission: {}", e);
            false
        }
    };
    // 2. Office on the real clock.
    let Some(cp) = cortex_m::Peripherals::take() else {
        return false;
    };
    let clock = SysTickClock::start(cp.SYST, CORE_HZ);
    // Both missions see their clock as `&dyn Clock`: the planner's code, generic over the
    // clock, is then in flash once instead of once per clock type (8.5 KB less on this
    // firmware; a clock reading through a vtable costs a few cycles).
    let clock: &dyn Clock = &clock;
    twin_ok && office::exported_mission(storage, times, clock, CORE_HZ)
}
