//! The planner on a real STM32F405 board: what `examples/firmware.rs` runs under QEMU (the
//! paper's Algorithm 1 loop, Bi-AM-RRT*(D) with `t_exp` = 150 ms on the office scenario, the
//! grid and diffusion table in flash), set up as a board needs it:
//!
//! - **Clocks**: 168 MHz from the PLL on the board's crystal ([`HSE_HZ`]), five flash wait
//!   states and the ART accelerator on ([`init`]). Without this the chip runs at 16 MHz on its
//!   HSI and every "150 ms" SysTick budget lasts about 1.6 s.
//! - **Logging and panics**: `defmt` over RTT and `panic-probe` (a probe reads both; with no
//!   probe attached the firmware still runs, where semihosting would HardFault).
//! - **Watchdog**: the independent watchdog ([`WATCHDOG_US`]), fed after every `plan` call.
//! - **Stack guard**: `flip-link` places the stack below `.bss`, so an overflow faults
//!   instead of writing over the planner's trees.
//!
//! The planner code is the crate's, unchanged: the same `Planner`, storage and `SysTickClock`
//! as the QEMU firmware, so the QEMU figures carry over (a 168 MHz M4F with the ART on runs
//! about 1.1-1.5 cycles per instruction, `docs/guides/board.md`).
#![no_std]

use bi_am_rrt::cortex::SysTickClock;
use bi_am_rrt::{Config, DiffusionTable, Map, OccupancyGrid, Planner, Point, Storage};
use embassy_stm32::time::Hertz;
use embassy_stm32::wdg::IndependentWatchdog;
use rand_xorshift::XorShiftRng;

/// The scenario last exported by `host-sim export` to `BIAMRRT_FLASH_DIR` (grid and table as
/// flash `static`s): the office in CI, or any other map.
#[allow(dead_code)]
pub mod scenario {
    include!(concat!(env!("BIAMRRT_FLASH_DIR"), "/scenario.rs"));
}

/// The board's crystal: 12 MHz on the Adafruit Feather STM32F405 Express. Change it, and
/// [`PLL_PREDIV`] and [`PLL_MUL`] with it, for another board: 8 MHz with `DIV4` and `MUL168`
/// on an STM32F4-Discovery, 25 MHz with `DIV25` and `MUL336`. [`CORE_HZ`] follows from the
/// three, and the build fails if they leave the PLL's ranges or the chip's 168 MHz.
pub const HSE_HZ: u32 = 12_000_000;
/// The PLL's input divider: `HSE_HZ` / 6 = 2 MHz (the PLL wants 1-2 MHz at its input).
pub const PLL_PREDIV: embassy_stm32::rcc::PllPreDiv = embassy_stm32::rcc::PllPreDiv::DIV6;
/// The PLL's multiplier: 2 MHz x 168 = 336 MHz at the VCO (100-432 MHz).
pub const PLL_MUL: embassy_stm32::rcc::PllMul = embassy_stm32::rcc::PllMul::MUL168;
/// The core clock [`init`] sets up, derived: the VCO / 2 (and / 7 = 48 MHz for USB with a
/// 336 MHz VCO). The planner's SysTick clock counts in it, so it cannot drift from the clock
/// actually set (a 25 MHz crystal with `DIV25` and `MUL168` gives 84 MHz, and the clock
/// would count 84 MHz too).
pub const CORE_HZ: u32 = VCO_HZ / 2;
const PLL_IN_HZ: u32 = HSE_HZ / PLL_PREDIV.to_bits() as u32;
const VCO_HZ: u32 = PLL_IN_HZ * PLL_MUL.to_bits() as u32;
const _: () = {
    assert!(PLL_PREDIV.to_bits() >= 2, "PLL_PREDIV: 2 to 63");
    assert!(
        PLL_IN_HZ >= 1_000_000 && PLL_IN_HZ <= 2_000_000,
        "the PLL's input (HSE_HZ / PLL_PREDIV) must be 1-2 MHz"
    );
    assert!(
        VCO_HZ >= 100_000_000 && VCO_HZ <= 432_000_000,
        "the VCO (input x PLL_MUL) must be 100-432 MHz"
    );
    assert!(CORE_HZ <= 168_000_000, "an STM32F405 runs at most 168 MHz");
};
/// The watchdog's timeout: a `plan` call lasts `t_exp` (150 ms) and a little, so a call
/// that runs away (or a task that stops feeding it) resets the chip within half a second.
pub const WATCHDOG_US: u32 = 500_000;

/// Two trees of 2,048 nodes and 256 index buckets each (`Storage::BYTES`: 90,248 bytes in
/// `.bss`), as in the QEMU firmware.
pub type BoardStorage = Storage<2048, 256>;
/// The planner the examples fly: the diffusion metric on the scenario in flash, up to four
/// dynamic obstacles.
pub type BoardPlanner =
    Planner<'static, 'static, DiffusionTable<'static>, XorShiftRng, 2048, 256, 4>;

/// Brings the chip up: the PLL on the crystal at 168 MHz (APB1 42 MHz, APB2 84 MHz), the
/// flash wait states for it, then the ART accelerator (prefetch, instruction and data caches).
pub fn init() -> embassy_stm32::Peripherals {
    use embassy_stm32::rcc::{
        AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllPDiv, PllQDiv, PllSource, Sysclk,
    };
    let mut config = embassy_stm32::Config::default();
    config.rcc.hse = Some(Hse {
        freq: Hertz(HSE_HZ),
        mode: HseMode::Oscillator,
    });
    config.rcc.pll_src = PllSource::HSE;
    config.rcc.pll = Some(Pll {
        prediv: PLL_PREDIV,
        mul: PLL_MUL,
        divp: Some(PllPDiv::DIV2),
        divq: Some(PllQDiv::DIV7),
        divr: None,
    });
    config.rcc.sys = Sysclk::PLL1_P;
    config.rcc.ahb_pre = AHBPrescaler::DIV1;
    config.rcc.apb1_pre = APBPrescaler::DIV4;
    config.rcc.apb2_pre = APBPrescaler::DIV2;
    let p = embassy_stm32::init(config);
    // embassy-stm32 0.6 writes FLASH_ACR whole when it sets the wait states, which leaves the
    // ART accelerator off (code from flash would then stall 5 cycles on most fetches).
    embassy_stm32::pac::FLASH.acr().modify(|w| {
        w.set_prften(true);
        w.set_icen(true);
        w.set_dcen(true);
    });
    p
}

/// The board as both examples start it: the chip at 168 MHz ([`init`]), the independent
/// watchdog unleashed ([`WATCHDOG_US`]: feed it after every call) and the planner's clock on
/// SysTick (route the `SysTick` exception to `bi_am_rrt::cortex::on_systick_wrap`). Run once.
pub fn bring_up() -> (
    IndependentWatchdog<'static, embassy_stm32::peripherals::IWDG>,
    SysTickClock,
) {
    let p = init();
    // The watchdog stops while a debugger halts the core (DBGMCU_APB1_FZ.DBG_IWDG_STOP): a
    // breakpoint held for more than WATCHDOG_US would otherwise reset the chip under it.
    embassy_stm32::pac::DBGMCU
        .apb1fzr()
        .modify(|w| w.set_iwdg(true));
    let mut dog = IndependentWatchdog::new(p.IWDG, WATCHDOG_US);
    dog.unleash();
    let Some(cp) = cortex_m::Peripherals::take() else {
        defmt::panic!("core peripherals taken twice");
    };
    (dog, SysTickClock::start(cp.SYST, CORE_HZ))
}

/// What can stop the planner from starting, with the library's reason.
#[derive(Clone, Copy, Debug, defmt::Format)]
pub enum BoardError {
    /// The grid (or the robot's inflated grid) in flash does not decode.
    Grid(bi_am_rrt::error::MapError),
    /// The diffusion table in flash does not decode.
    Table(bi_am_rrt::error::TableError),
    /// The planner refused its configuration, map or start.
    Setup(bi_am_rrt::error::SetupError),
}

/// The planner at the scenario's start: Bi-AM-RRT*(D) with lengths that follow the map,
/// `sigma` from the scenario, the paper's set or (`tuned`) the tuned one, seed 1.
pub fn planner(
    storage: &'static mut BoardStorage,
    tuned: bool,
    motion: bi_am_rrt::Motion,
) -> Result<BoardPlanner, BoardError> {
    use rand_core::SeedableRng;
    let grid = OccupancyGrid::new(
        &scenario::GRID,
        scenario::COLS,
        scenario::ROWS,
        scenario::CELL,
    )
    .map_err(BoardError::Grid)?;
    let table = DiffusionTable::new(&scenario::TABLE).map_err(BoardError::Table)?;
    let base = Config::bi_am_rrt();
    let base = if tuned { base.tuned() } else { base };
    let mut cfg = base.for_grid(&grid).with_sigma(scenario::SIGMA);
    cfg.motion = motion;
    // A robot body: the grid `host-sim export --robot-radius` inflated, kept in flash.
    cfg.robot_radius = scenario::ROBOT_RADIUS;
    let map = if scenario::ROBOT_RADIUS > 0.0 {
        OccupancyGrid::new(
            &scenario::SPACE,
            scenario::COLS,
            scenario::ROWS,
            scenario::CELL,
        )
        .and_then(|s| s.inflated_for(scenario::ROBOT_RADIUS))
        .and_then(|s| Map::new(grid).with_baked_body(s))
        .map_err(BoardError::Grid)?
    } else {
        Map::new(grid)
    };
    let rng = XorShiftRng::seed_from_u64(1);
    Planner::new(storage, map, table, rng, cfg, start()).map_err(BoardError::Setup)
}

/// The scenario's start.
pub fn start() -> Point {
    Point::new(scenario::START.0, scenario::START.1)
}

/// The scenario's goals in order.
pub fn goals() -> impl Iterator<Item = Point> {
    scenario::GOALS.iter().map(|&(x, y)| Point::new(x, y))
}

/// Per-call times of a run, in microseconds, for a median without allocation.
pub struct CallTimes<const M: usize> {
    us: [u32; M],
    len: usize,
    worst: u32,
}

impl<const M: usize> CallTimes<M> {
    /// No calls yet.
    pub const fn new() -> Self {
        Self {
            us: [0; M],
            len: 0,
            worst: 0,
        }
    }

    /// Records one call of `us` microseconds (beyond `M` calls only the worst is kept).
    pub fn record(&mut self, us: u32) {
        self.worst = self.worst.max(us);
        if let Some(slot) = self.us.get_mut(self.len) {
            *slot = us;
            self.len += 1;
        }
    }

    /// Calls recorded.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether none was.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The worst call.
    pub fn worst(&self) -> u32 {
        self.worst
    }

    /// The median call (sorts what was recorded).
    pub fn median(&mut self) -> u32 {
        let recorded = &mut self.us[..self.len];
        recorded.sort_unstable();
        recorded.get(recorded.len() / 2).copied().unwrap_or(0)
    }

    /// Forgets the calls.
    pub fn clear(&mut self) {
        self.len = 0;
        self.worst = 0;
    }
}

impl<const M: usize> Default for CallTimes<M> {
    fn default() -> Self {
        Self::new()
    }
}
