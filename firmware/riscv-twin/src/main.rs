//! The twin mission (`examples/shared/mission.rs`: Bi-AM-RRT*(E) across the built-in field on
//! a virtual clock) on a RISC-V MCU core, riscv32imac: no FPU, so every float operation is
//! the compiler's soft-float routine. It prints the line `examples/twin.rs` prints on the host,
//! bit for bit (`.ci/run` compares them): promise 5 on a third instruction set.
//!
//! ```sh
//! cd firmware/riscv-twin && cargo run --release   # needs qemu-system-riscv32 (qemu-system-misc)
//! ```
#![no_std]
#![no_main]

#[path = "../../../examples/shared/mission.rs"]
mod mission;

use panic_halt as _;
use riscv_semihosting::{debug, hprintln};
use static_cell::ConstStaticCell;

/// The planner's storage: all zero bytes, so it lives in `.bss`.
static STORAGE: ConstStaticCell<mission::MissionStorage> =
    ConstStaticCell::new(bi_am_rrt::Storage::new());

#[riscv_rt::entry]
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
    loop {}
}
