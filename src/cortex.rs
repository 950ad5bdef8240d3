//! Real clocks for Cortex-M firmware (feature `cortex-m`): the time the planner's budgets
//! (the paper's `t_exp`, `t_root`, `t_goal`, Algorithm 1) are measured on when it runs on the
//! chip.
//!
//! - [`SysTickClock`]: the core's 24-bit SysTick counting core cycles, extended to 64 bits by
//!   counting its wraps in the SysTick exception. Every Cortex-M has it, and QEMU emulates it
//!   (with `-icount`, deterministically), so it is the clock of the firmware example.
//! - [`DwtClock`]: the DWT cycle counter (Cortex-M3 and up; not built for ARMv6-M, whose
//!   cores have neither the counter nor atomic read-modify-write), 32 bits, extended in software
//!   on every read. No interrupt needed; it must be read at least once per 2^32 cycles (25.6 s
//!   at 168 MHz), which any planner call does many times over. QEMU does not emulate it (it
//!   reads 0: the clock never advances, and the planner's work cap still ends every call).
//!
//! Both read the counter directly, so reading costs a few instructions; both ignore
//! [`Clock::charge`] (real time, not work).
//!
//! ```ignore
//! use cortex_m_rt::exception;
//! #[exception]
//! fn SysTick() {
//!     bi_am_rrt::cortex::on_systick_wrap();
//! }
//! let cp = cortex_m::Peripherals::take().unwrap();
//! let clock = bi_am_rrt::cortex::SysTickClock::start(cp.SYST, 168_000_000);
//! planner.plan(&clock, agent)?;
//! ```

#[cfg(target_has_atomic = "32")]
use core::cell::Cell;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
#[cfg(target_has_atomic = "32")]
use cortex_m::peripheral::{DCB, DWT};
use cortex_m::peripheral::{SCB, SYST};

use crate::clock::Clock;

/// The SysTick reload value: the full 24 bits.
const RELOAD: u32 = 0x00FF_FFFF;

/// SysTick wraps seen by the exception handler.
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// Counts one SysTick wrap: call it from the `SysTick` exception handler (and nothing else
/// there is needed). Without it the clock would repeat every 2^24 cycles.
#[inline]
pub fn on_systick_wrap() {
    #[cfg(target_has_atomic = "32")]
    WRAPS.fetch_add(1, Ordering::AcqRel);
    // ARMv6-M (Cortex-M0/M0+) has no atomic read-modify-write: a load and a store with
    // interrupts off (only this handler writes the count).
    #[cfg(not(target_has_atomic = "32"))]
    cortex_m::interrupt::free(|_| {
        WRAPS.store(
            WRAPS.load(Ordering::Acquire).wrapping_add(1),
            Ordering::Release,
        );
    });
}

/// A [`Clock`] on SysTick, in core cycles (see the module docs).
///
/// Monotonic as long as the SysTick exception is not held off for a whole wrap period
/// (2^24 cycles: 99.9 ms at 168 MHz), i.e. the planner runs at a priority below SysTick's, as
/// thread-mode code does. A wrap whose exception is still pending is counted by the reader.
#[derive(Debug)]
pub struct SysTickClock {
    hz: u32,
}

impl SysTickClock {
    /// Takes SysTick, runs it from the core clock (`core_hz` cycles per second) over its full
    /// 24-bit range and enables its exception. Route the exception to [`on_systick_wrap`].
    pub fn start(mut syst: SYST, core_hz: u32) -> Self {
        syst.disable_counter();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
        Self { hz: core_hz.max(1) }
    }

    /// Cycles since [`SysTickClock::start`].
    pub fn cycles(&self) -> u64 {
        loop {
            let wraps = WRAPS.load(Ordering::Acquire);
            let mut value = SYST::get_current();
            // A wrap that happened but whose exception has not run yet.
            let pending = SCB::is_pendst_pending();
            if pending {
                value = SYST::get_current();
            }
            if WRAPS.load(Ordering::Acquire) != wraps {
                continue; // the handler ran meanwhile: read again
            }
            let wraps = u64::from(wraps).saturating_add(u64::from(pending));
            let within = u64::from(RELOAD.saturating_sub(value & RELOAD));
            return wraps
                .saturating_mul(u64::from(RELOAD) + 1)
                .saturating_add(within);
        }
    }
}

impl Clock for SysTickClock {
    #[inline]
    fn now(&self) -> u64 {
        self.cycles()
    }

    fn ticks_per_second(&self) -> u64 {
        u64::from(self.hz)
    }
}

/// A [`Clock`] on the DWT cycle counter, extended to 64 bits on every read (see the module
/// docs).
#[cfg(target_has_atomic = "32")]
#[derive(Debug)]
pub struct DwtClock {
    hz: u32,
    last: Cell<u32>,
    high: Cell<u64>,
}

#[cfg(target_has_atomic = "32")]
impl DwtClock {
    /// Enables tracing and the cycle counter; `core_hz` is the core clock.
    pub fn start(dcb: &mut DCB, dwt: &mut DWT, core_hz: u32) -> Self {
        dcb.enable_trace();
        dwt.enable_cycle_counter();
        Self {
            hz: core_hz.max(1),
            last: Cell::new(DWT::cycle_count()),
            high: Cell::new(0),
        }
    }
}

#[cfg(target_has_atomic = "32")]
impl Clock for DwtClock {
    fn now(&self) -> u64 {
        let now = DWT::cycle_count();
        if now < self.last.get() {
            self.high.set(self.high.get().saturating_add(1 << 32));
        }
        self.last.set(now);
        self.high.get().saturating_add(u64::from(now))
    }

    fn ticks_per_second(&self) -> u64 {
        u64::from(self.hz)
    }
}
