//! The firmware twin mission (`examples/shared/mission.rs`: Bi-AM-RRT*(E) across the built-in
//! 40 m field on a virtual clock) with its figures logged through `defmt` instead of
//! formatted on the chip: the core's public types implement `defmt::Format` with the `defmt`
//! feature, and `defmt-semihosting` carries the compressed log frames out of QEMU.
//!
//! `defmt` needs its linker script, so build it with `cargo rustc` (decode the output with
//! `defmt-print -e <elf>`):
//!
//! ```sh
//! cargo rustc --profile firmware --example firmware_defmt --target thumbv7em-none-eabihf \
//!     --features firmware-example,defmt -- -C link-arg=-Tdefmt.x
//! qemu-system-arm -machine netduinoplus2 -cpu cortex-m4 -nographic \
//!     -semihosting-config enable=on,target=native \
//!     -kernel target/thumbv7em-none-eabihf/firmware/examples/firmware_defmt | defmt-print -e \
//!     target/thumbv7em-none-eabihf/firmware/examples/firmware_defmt
//! ```
#![no_std]
#![no_main]

#[path = "shared/mission.rs"]
mod mission;

use bi_am_rrt::Storage;
use cortex_m_rt::entry;
use cortex_m_semihosting::debug;
use defmt_semihosting as _;
use mission::MissionStorage;
use panic_semihosting as _;
use static_cell::ConstStaticCell;

/// The planner's storage, all zero when empty: in `.bss`.
static STORAGE: ConstStaticCell<MissionStorage> = ConstStaticCell::new(Storage::new());

#[entry]
fn main() -> ! {
    let ok = match mission::fly(STORAGE.take()) {
        Ok(m) => {
            defmt::println!(
                "{} on {}: {} (work units: {})",
                defmt::Display2Format(&m.planner),
                m.scenario,
                m.result,
                m.work
            );
            m.ok()
        }
        Err(e) => {
            defmt::error!("mission: {}", defmt::Display2Format(&e));
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
