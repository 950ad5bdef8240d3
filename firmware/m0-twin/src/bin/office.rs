//! The office sequence in real time on a Cortex-M0+ build (thumbv6m: no FPU, soft float),
//! the same code as the Cortex-M4F firmware's (`examples/shared/office.rs`): the scenario
//! last exported to `BIAMRRT_FLASH_DIR`, `t_exp` = 150 ms on SysTick. Under QEMU's mps2-an385
//! board (its Cortex-M3 runs ARMv6-M code unchanged) SysTick counts the board's 25 MHz clock
//! and `-icount shift=3` charges 8 ns an instruction: a 125 MIPS core, an RP2040-class M0+ at
//! 133 MHz. `firmware/sequence.sh --m0` runs it with both sets.
//!
//! ```sh
//! cd firmware/m0-twin && BIAMRRT_FLASH_DIR=$PWD/../../target/flash cargo run --release --bin office
//! ```
#![no_std]
#![no_main]

#[path = "../../../../examples/shared/mission.rs"]
#[allow(dead_code)]
mod mission;

#[path = "../../../../examples/shared/office.rs"]
mod office;

/// The scenario last exported by `host-sim export` to `BIAMRRT_FLASH_DIR`.
#[allow(dead_code)]
mod scenario {
    include!(concat!(env!("BIAMRRT_FLASH_DIR"), "/scenario.rs"));
}

use bi_am_rrt::cortex::{SysTickClock, on_systick_wrap};
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::debug;
pub(crate) use cortex_m_semihosting::hprintln;
use panic_halt as _;
use static_cell::ConstStaticCell;

/// SysTick's clock on QEMU's mps2-an385 (the board's 25 MHz system clock).
const SYSTICK_HZ: u32 = 25_000_000;

static STORAGE: ConstStaticCell<mission::MissionStorage> =
    ConstStaticCell::new(bi_am_rrt::Storage::new());
static CALL_TIMES: ConstStaticCell<office::CallTimes> =
    ConstStaticCell::new(office::CallTimes::new());

#[exception]
fn SysTick() {
    on_systick_wrap();
}

#[entry]
fn main() -> ! {
    let ok = match cortex_m::Peripherals::take() {
        Some(cp) => {
            let clock = SysTickClock::start(cp.SYST, SYSTICK_HZ);
            office::exported_mission(STORAGE.take(), CALL_TIMES.take(), &clock, SYSTICK_HZ)
        }
        None => false,
    };
    hprintln!("stack high-water: {} bytes", office::stack_high_water());
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}
