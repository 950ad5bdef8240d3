//! Firmware example: the planner inside Cortex-M4F firmware (an STM32F405, as on the
//! `netduinoplus2` board that `qemu-system-arm` emulates; memory map in `memory.x`).
//!
//! The map is the built-in 40 m field, packed into a `static` at compile time (flash); the
//! planner's storage is a `static` in RAM; time is a virtual clock advanced by the planner's
//! work, so the run is the same on the MCU as on the host (`examples/twin.rs` prints the same
//! line). The agent is driven to the goal with the core's benchmark protocol, the figures are
//! printed over semihosting, and QEMU exits with status 0 when the goal was reached without
//! collision.
//!
//! ```sh
//! cargo run --release --example firmware --target thumbv7em-none-eabihf --features firmware-example
//! ```
#![no_std]
#![no_main]

#[path = "shared/mission.rs"]
mod mission;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use mission::MissionStorage;
use panic_semihosting as _;

#[entry]
fn main() -> ! {
    let ok = match cortex_m::singleton!(: MissionStorage = MissionStorage::new()) {
        Some(storage) => match mission::fly(storage) {
            Some(m) => {
                hprintln!("{}", m);
                m.ok()
            }
            None => {
                hprintln!("mission refused its start or goal");
                false
            }
        },
        None => false,
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}
