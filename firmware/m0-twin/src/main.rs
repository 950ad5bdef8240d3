//! The twin mission (`examples/shared/mission.rs`: Bi-AM-RRT*(E) across the built-in field on
//! a virtual clock) built for a Cortex-M0+ (thumbv6m: no FPU, no hardware divide, so every
//! float operation is a soft-float routine). It prints the line `examples/twin.rs` prints on
//! the host, bit for bit (`.ci/run` compares them): promise 5 on the smallest Cortex-M. It
//! also prints the virtual instructions it took (QEMU's `-icount` clock through SysTick) and
//! its stack high-water mark.
//!
//! ```sh
//! cd firmware/m0-twin && cargo run --release   # needs qemu-system-arm
//! ```
#![no_std]
#![no_main]

#[path = "../../../examples/shared/mission.rs"]
mod mission;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_halt as _;
use static_cell::ConstStaticCell;

/// The planner's storage: all zero bytes, so it lives in `.bss`.
static STORAGE: ConstStaticCell<mission::MissionStorage> =
    ConstStaticCell::new(bi_am_rrt::Storage::new());

#[entry]
fn main() -> ! {
    let ok = match mission::fly(STORAGE.take()) {
        Ok(m) => {
            hprintln!("{}", m);
            m.ok()
        }
        Err(e) => {
            hprintln!("mission: {}", e);
            false
        }
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}
