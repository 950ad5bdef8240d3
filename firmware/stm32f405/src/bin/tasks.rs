//! The board example, async (embassy): the planner as one task among others, as a robot's
//! firmware runs it.
//!
//! - **Planner** (thread mode, the lowest priority): Algorithm 1's loop, one `plan` call of
//!   `t_exp` after another, through the scenario's goals. Before each call it applies the
//!   obstacle sightings that arrived; after it, it feeds the watchdog and hands the control
//!   loop the waypoint, but only if the segment from where the agent is *now* (it moved while
//!   the planner planned) is free, else it holds the agent where it is.
//! - **Control loop** (an interrupt executor at [`CONTROL_PRIORITY`], preempting the planner):
//!   every [`CONTROL_PERIOD_MS`], moves the (simulated) agent towards the waypoint at
//!   [`SPEED`], whatever the planner is doing.
//! - **Perception** (same interrupt executor): a person walks at [`PERSON_SPEED`] through the
//!   map (turning at walls, and placed anew 6-20 m from the agent every [`SPAWN_PERIOD_MS`]);
//!   every [`SIGHTING_PERIOD_MS`] its position and velocity go to the planner through a
//!   channel, as a tracker reports them ([`bi_am_rrt::Moving`]); the planner submits them with
//!   `update_obstacle` (O(K); applied at its next call) under a stated motion
//!   ([`bi_am_rrt::Motion`]: the agent's speed, the period of a call, a 1.5 s horizon, people
//!   at most 1.5 m/s), so it gives way to the person or steps aside (module `motion`).
//!
//! Priority rules for the planner's clock ([`bi_am_rrt::cortex::SysTickClock`]): SysTick must
//! preempt everything that can run for a whole SysTick period (2^24 cycles, 99.9 ms at
//! 168 MHz), or wraps are lost and calls overrun; at reset SysTick has the highest priority, so
//! leave it there. The clock reads wall time: what the control loop and perception take while
//! a call runs comes out of that call's `t_exp` (the call still ends on time, with fewer
//! expansions). embassy's time driver (TIM2 here) must preempt the planner too, which its
//! default priority does. Shared state is behind critical-section mutexes, held for a few
//! instructions, never across a `plan` call.
//!
//! ```sh
//! cd firmware/stm32f405 && BIAMRRT_FLASH_DIR=$PWD/../../target/flash cargo run --release --bin tasks
//! ```
#![no_std]
#![no_main]

use core::cell::Cell;

use bi_am_rrt::clock::Clock;
use bi_am_rrt::cortex::{SysTickClock, on_systick_wrap};
use bi_am_rrt::geometry::unit_f32;
use bi_am_rrt::{Circle, Motion, Moving, OccupancyGrid, Point};
use cortex_m_rt::exception;
use defmt_rtt as _;
use embassy_executor::{InterruptExecutor, Spawner};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_time::{Duration, Ticker, Timer};
use panic_probe as _;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use static_cell::ConstStaticCell;
use stm32f405_board::{
    BoardPlanner, BoardStorage, CORE_HZ, CallTimes, goals, planner, scenario, start,
};

/// The control loop's period.
const CONTROL_PERIOD_MS: u64 = 20;
/// The agent's speed (m/s).
const SPEED: f32 = 2.0;
/// How often perception reports the person.
const SIGHTING_PERIOD_MS: u64 = 200;
/// How often the person is placed anew near the agent.
const SPAWN_PERIOD_MS: u64 = 6_000;
/// The person's walking speed (m/s).
const PERSON_SPEED: f32 = 1.2;
/// The person's radius (m).
const PERSON_RADIUS: f32 = 1.0;
/// The control loop's and perception's interrupt priority (above thread mode, below SysTick).
const CONTROL_PRIORITY: Priority = Priority::P6;
/// How close to a goal counts as there (m).
const ARRIVED: f32 = 0.1;

type Shared<T> = Mutex<CriticalSectionRawMutex, Cell<T>>;

/// The agent's position, written by the control loop.
static AGENT: Shared<Point> =
    Mutex::new(Cell::new(Point::new(scenario::START.0, scenario::START.1)));
/// The waypoint the control loop steers to, written by the planner.
static WAYPOINT: Shared<Point> =
    Mutex::new(Cell::new(Point::new(scenario::START.0, scenario::START.1)));
/// Sightings from perception to the planner.
static SIGHTINGS: Channel<CriticalSectionRawMutex, Moving, 4> = Channel::new();
static CONTROL: InterruptExecutor = InterruptExecutor::new();
static STORAGE: ConstStaticCell<BoardStorage> = ConstStaticCell::new(BoardStorage::new());
static TIMES: ConstStaticCell<CallTimes<2048>> = ConstStaticCell::new(CallTimes::new());

#[interrupt]
unsafe fn UART4() {
    // SAFETY: UART4 is not used as a peripheral here; its vector runs only this executor.
    unsafe { CONTROL.on_interrupt() }
}

#[exception]
fn SysTick() {
    on_systick_wrap();
}

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let (dog, clock) = stm32f405_board::bring_up();
    // The motion the planner is told: the agent's top speed, a call's period (t_exp plus the
    // other tasks' share), how far ahead to give way, the people's top speed.
    let motion = Motion {
        agent_speed: SPEED,
        period: 0.2,
        horizon: 1.5,
        obstacle_speed: 1.5,
    };
    let planner = match planner(STORAGE.take(), stm32f405_board::scenario::TUNED, motion) {
        Ok(planner) => planner,
        Err(e) => defmt::panic!("planner: {}", e),
    };
    interrupt::UART4.set_priority(CONTROL_PRIORITY);
    let control = CONTROL.start(interrupt::UART4);
    match (control_loop(), perception()) {
        (Ok(c), Ok(s)) => {
            control.spawn(c);
            control.spawn(s);
        }
        _ => defmt::panic!("tasks spawned twice"),
    }
    match planning(planner, clock, dog) {
        Ok(t) => spawner.spawn(t),
        Err(_) => defmt::panic!("planner task spawned twice"),
    }
}

/// Moves the agent towards the waypoint, `SPEED` x the period per tick.
#[embassy_executor::task]
async fn control_loop() {
    let step = SPEED * CONTROL_PERIOD_MS as f32 / 1_000.0;
    let mut ticker = Ticker::every(Duration::from_millis(CONTROL_PERIOD_MS));
    loop {
        ticker.next().await;
        let target = WAYPOINT.lock(Cell::get);
        AGENT.lock(|agent| {
            let at = agent.get();
            agent.set(at.step_towards(target, step));
        });
    }
}

/// A person walking through the map, reported every `SIGHTING_PERIOD_MS` with its velocity;
/// placed anew at a free place 6-20 m from the agent every `SPAWN_PERIOD_MS`.
#[embassy_executor::task]
async fn perception() {
    let Ok(grid) = OccupancyGrid::new(
        &scenario::GRID,
        scenario::COLS,
        scenario::ROWS,
        scenario::CELL,
    ) else {
        return;
    };
    let mut rng = XorShiftRng::seed_from_u64(7);
    let dt = SIGHTING_PERIOD_MS as f32 / 1_000.0;
    let mut person: Option<(Point, Point)> = None;
    let mut since_spawn = SPAWN_PERIOD_MS;
    loop {
        Timer::after_millis(SIGHTING_PERIOD_MS).await;
        since_spawn += SIGHTING_PERIOD_MS;
        let agent = AGENT.lock(Cell::get);
        let heading = |rng: &mut XorShiftRng| {
            let a = core::f32::consts::TAU * unit_f32(rng);
            Point::new(PERSON_SPEED * libm::cosf(a), PERSON_SPEED * libm::sinf(a))
        };
        if since_spawn >= SPAWN_PERIOD_MS {
            since_spawn = 0;
            // Bounded: at most 64 draws; none free means no person until the next spawn.
            person = (0..64).find_map(|_| {
                let r = 6.0 + 14.0 * unit_f32(&mut rng);
                let a = core::f32::consts::TAU * unit_f32(&mut rng);
                let c = agent + Point::new(r * libm::cosf(a), r * libm::sinf(a));
                grid.point_free(c).then(|| (c, heading(&mut rng)))
            });
        } else if let Some((c, v)) = person.as_mut() {
            // Walk on; at a wall, turn to a free heading (at most 8 tries, else stand).
            let next = *c + *v * dt;
            if grid.segment_free(*c, next) {
                *c = next;
            } else {
                *v = (0..8)
                    .map(|_| heading(&mut rng))
                    .find(|h| grid.segment_free(*c, *c + *h * dt))
                    .unwrap_or(Point::ZERO);
            }
        }
        if let Some((c, v)) = person {
            // A full channel means the planner is behind: drop this sighting.
            let _ = SIGHTINGS.try_send(Moving::new(Circle::new(c, PERSON_RADIUS), v));
        }
    }
}

/// Algorithm 1's loop through the scenario's goals.
#[embassy_executor::task]
async fn planning(
    mut planner: BoardPlanner,
    clock: SysTickClock,
    mut dog: IndependentWatchdog<'static, IWDG>,
) {
    let times = TIMES.take();
    let us = |ticks: u64| u32::try_from(ticks / u64::from(CORE_HZ / 1_000_000)).unwrap_or(u32::MAX);
    let mut person = None;
    let mut held = 0u32;
    defmt::info!(
        "{} on {=str} (async), {} MHz, t_exp {} ms",
        defmt::Display2Format(&planner.name()),
        scenario::NAME,
        CORE_HZ / 1_000_000,
        planner.config().budget.t_exp.as_millis() as u32
    );
    let mut from = start();
    for (i, goal) in goals().enumerate() {
        if let Err(e) = planner.set_goal(goal) {
            defmt::warn!("goal {}: refused ({})", i + 1, e);
            continue;
        }
        times.clear();
        let mut sightings = 0u32;
        loop {
            while let Ok(seen) = SIGHTINGS.try_receive() {
                // O(K) to submit; the planner applies it at its next call.
                person = match person {
                    Some(id) if planner.update_obstacle(id, seen).is_ok() => Some(id),
                    _ => planner.add_moving_obstacle(seen).ok(),
                };
                sightings += 1;
            }
            let agent = AGENT.lock(Cell::get);
            if agent.dist(goal) <= ARRIVED {
                break;
            }
            let t0 = clock.now();
            let progress = match planner.plan(&clock, agent) {
                Ok(progress) => progress,
                Err(e) => defmt::panic!("plan refused the agent's position: {}", e),
            };
            times.record(us(clock.now().saturating_sub(t0)));
            dog.pet();
            // The agent moved while the planner planned: hand over the waypoint only if the
            // segment from where it is now is free too, else hold it there.
            let now = AGENT.lock(Cell::get);
            let waypoint = if planner.map().free_now(now, progress.waypoint) {
                progress.waypoint
            } else {
                held += 1;
                now
            };
            WAYPOINT.lock(|w| w.set(waypoint));
            // Let the other thread-mode tasks (none here) run between calls.
            embassy_futures::yield_now().await;
        }
        defmt::info!(
            "goal {}: {} calls, {} m straight from the last goal, {} sightings; call median {} us, worst {} us; {} holds so far",
            i + 1,
            times.len(),
            from.dist(goal),
            sightings,
            times.median(),
            times.worst(),
            held
        );
        from = goal;
    }
    defmt::info!("all goals done");
    loop {
        dog.pet();
        Timer::after_millis(100).await;
    }
}
