//! The office sequence in real time on a RISC-V MCU core (riscv32imac: no FPU, soft float),
//! the same code as the Cortex-M4F firmware's (`examples/shared/office.rs`): the scenario last
//! exported to `BIAMRRT_FLASH_DIR`, `t_exp` = 150 ms on the core's `time` counter (QEMU's
//! `virt` board: the ACLINT timer at 10 MHz). `-icount shift=3` charges 8 ns an instruction, a
//! 125 MIPS core, as the Arm runs. `firmware/sequence.sh --riscv` runs it with both
//! sets.
//!
//! ```sh
//! cd firmware/riscv-twin && BIAMRRT_FLASH_DIR=$PWD/../../target/flash cargo run --release --bin office
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

use bi_am_rrt::clock::Clock;
use panic_halt as _;
use riscv_semihosting::debug;
pub(crate) use riscv_semihosting::hprintln;
use static_cell::ConstStaticCell;

/// The `time` counter's rate on QEMU's `virt` board.
const TIME_HZ: u32 = 10_000_000;

static STORAGE: ConstStaticCell<mission::MissionStorage> =
    ConstStaticCell::new(bi_am_rrt::Storage::new());
static CALL_TIMES: ConstStaticCell<office::CallTimes> =
    ConstStaticCell::new(office::CallTimes::new());

/// A [`Clock`] on the RISC-V `time` counter (64 bits, read as two halves).
struct TimeClock;

impl Clock for TimeClock {
    fn now(&self) -> u64 {
        riscv::register::time::read64()
    }

    fn ticks_per_second(&self) -> u64 {
        u64::from(TIME_HZ)
    }
}

#[riscv_rt::entry]
fn main() -> ! {
    let ok = office::exported_mission(STORAGE.take(), CALL_TIMES.take(), &TimeClock, TIME_HZ);
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}
