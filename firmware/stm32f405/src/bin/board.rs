//! The board example, blocking: the paper's Algorithm 1 loop as a bare-metal main. The chip is
//! brought up at 168 MHz ([`stm32f405_board::init`]), the watchdog is unleashed, and the planner
//! drives a simulated agent through the scenario's goals in order (the benchmark protocol: 0.7 m
//! towards the waypoint per call), feeding the watchdog after every call and logging per goal
//! the calls, the median and worst call and the nodes over RTT.
//!
//! ```sh
//! cargo run --release -p host-sim -- export --scenarios ../shared/maps/scenarios.toml \
//!     --maps office --planners paper --out target/flash
//! cd firmware/stm32f405 && BIAMRRT_FLASH_DIR=$PWD/../../target/flash cargo run --release --bin board
//! ```
//!
//! Exported with `--planners tuned` it flies the tuned set, with `--planners paper` the paper's.
#![no_std]
#![no_main]

use bi_am_rrt::agent::{Protocol, run_to_goal};
use bi_am_rrt::clock::Clock;
use bi_am_rrt::cortex::on_systick_wrap;
use cortex_m_rt::{entry, exception};
use defmt_rtt as _;
use panic_probe as _;
use static_cell::ConstStaticCell;
use stm32f405_board::{BoardStorage, CORE_HZ, CallTimes, goals, planner};

static STORAGE: ConstStaticCell<BoardStorage> = ConstStaticCell::new(BoardStorage::new());
static TIMES: ConstStaticCell<CallTimes<600>> = ConstStaticCell::new(CallTimes::new());

#[exception]
fn SysTick() {
    on_systick_wrap();
}

#[entry]
fn main() -> ! {
    let (mut dog, clock) = stm32f405_board::bring_up();
    let tuned = stm32f405_board::scenario::TUNED;
    let mut planner = match planner(STORAGE.take(), tuned, bi_am_rrt::Motion::NONE) {
        Ok(planner) => planner,
        Err(e) => defmt::panic!("planner: {}", e),
    };
    defmt::info!(
        "{} on {=str}, {} MHz, t_exp {} ms",
        defmt::Display2Format(&planner.name()),
        stm32f405_board::scenario::NAME,
        CORE_HZ / 1_000_000,
        planner.config().budget.t_exp.as_millis() as u32
    );
    let times = TIMES.take();
    let protocol = Protocol::default();
    let us = |ticks: u64| u32::try_from(ticks / u64::from(CORE_HZ / 1_000_000)).unwrap_or(u32::MAX);
    for (i, goal) in goals().enumerate() {
        times.clear();
        let mut last = clock.now();
        let result = run_to_goal(&mut planner, &clock, goal, &protocol, |_, _, _| {
            let now = clock.now();
            times.record(us(now.saturating_sub(last)));
            dog.pet();
            last = clock.now();
        });
        match result {
            Ok(r) => defmt::info!(
                "goal {}: reached {}, {} calls, path {} m, {} collisions, {} nodes; call median {} us, worst {} us",
                i + 1,
                r.reached,
                r.calls,
                r.travelled,
                r.collisions,
                planner.tree().len(),
                times.median(),
                times.worst()
            ),
            Err(e) => defmt::warn!("goal {}: refused ({})", i + 1, e),
        }
    }
    defmt::info!("all goals done");
    loop {
        dog.pet();
        embassy_time::block_for(embassy_time::Duration::from_millis(100));
    }
}
