//! Work per call with a clock that never advances (promise 3, issue 7): the planner at the
//! start of a scenario's first leg, `plan` called again and again with a frozen clock, so only
//! the per-call work cap (`Budget::max_work`) and the expansion cap end each call.
//! Reports the work units and the thread CPU time of the calls, for two arena sizes and both
//! rewiring modes.

use std::time::Duration;

use anyhow::{Result, anyhow};
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::{Config, Named, Planner, RewireMode, Storage};
use cpu_time::ThreadTime;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Serialize;

use crate::sim::Prepared;

/// One configuration's frozen-clock calls.
#[derive(Clone, Debug, Serialize)]
pub struct FrozenRow {
    /// Map name.
    pub map: String,
    /// Planner name.
    pub planner: String,
    /// Arena nodes per tree.
    pub nodes: usize,
    /// Rewiring mode.
    pub mode: String,
    /// Calls measured.
    pub calls: u32,
    /// Most work units in one call.
    pub max_units: u64,
    /// Median work units per call.
    pub median_units: u64,
    /// Most CPU milliseconds in one call.
    pub max_cpu_ms: f64,
    /// Median CPU milliseconds per call.
    pub median_cpu_ms: f64,
    /// Most expansions in one call.
    pub max_expansions: u32,
    /// The configuration's work cap.
    pub cap: u32,
}

/// Frozen-clock calls for `base` on `prep` with 2,048 and 8,192 nodes, in both rewiring modes.
pub fn frozen(prep: &Prepared, base: Named, calls: u32) -> Result<Vec<FrozenRow>> {
    let mut rows = Vec::new();
    for mode in [base.cfg.rewiring.mode, RewireMode::Faithful] {
        let mut cfg = prep.fit(base);
        cfg.cfg = cfg.cfg.with_rewire_mode(mode);
        rows.push(measure::<2048, 1024>(prep, cfg, calls)?);
        rows.push(measure::<8192, 2048>(prep, cfg, calls)?);
    }
    Ok(rows)
}

fn measure<const N: usize, const B: usize>(
    prep: &Prepared,
    named: Named,
    calls: u32,
) -> Result<FrozenRow> {
    let cfg = named.cfg;
    let mut storage: Box<Storage<N, B>> = Box::default();
    let metric = prep.metric(named.metric)?;
    let sc = &prep.scenario;
    let mut p = Planner::<_, _, N, B, 8>::new(
        &mut storage,
        sc.planner_map()?,
        metric,
        XorShiftRng::seed_from_u64(1),
        Config {
            robot_radius: sc.robot_radius,
            ..cfg
        },
        sc.start,
    )
    .map_err(|e| anyhow!("{e}"))?;
    p.set_goal(sc.goals[0]).map_err(|e| anyhow!("{e}"))?;
    let frozen = FakeClock::nanos();
    let (mut units, mut cpu, mut expansions) = (Vec::new(), Vec::new(), 0);
    for _ in 0..calls {
        let t0 = ThreadTime::now();
        let pr = p.plan(&frozen, sc.start).map_err(|e| anyhow!("{e}"))?;
        cpu.push(t0.elapsed());
        units.push(pr.work);
        expansions = expansions.max(pr.expansions);
    }
    units.sort_unstable();
    cpu.sort_unstable();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    Ok(FrozenRow {
        map: sc.name.clone(),
        planner: named.name().to_string(),
        nodes: N,
        mode: match cfg.rewiring.mode {
            RewireMode::Faithful => "faithful".into(),
            RewireMode::PerExpansion { visits } => format!("per-expansion({visits})"),
        },
        calls,
        max_units: units.last().copied().unwrap_or(0),
        median_units: units.get(units.len() / 2).copied().unwrap_or(0),
        max_cpu_ms: cpu.last().copied().map_or(0.0, ms),
        median_cpu_ms: cpu.get(cpu.len() / 2).copied().map_or(0.0, ms),
        max_expansions: expansions,
        cap: cfg.budget.max_work,
    })
}

/// `host-sim frozen`: [`frozen`] on each scenario, printed as CSV lines.
pub fn print_frozen(scs: Vec<crate::scenario::Scenario>, base: Named, calls: u32) -> Result<()> {
    println!(
        "map, planner, nodes, mode, calls, max units, median units, max CPU ms, median CPU ms, max expansions, cap"
    );
    for sc in scs {
        let prep = crate::sim::Prepared::new(sc);
        for r in frozen(&prep, base, calls)? {
            println!(
                "{}, {}, {}, {}, {}, {}, {}, {:.1}, {:.1}, {}, {}",
                r.map,
                r.planner,
                r.nodes,
                r.mode,
                r.calls,
                r.max_units,
                r.median_units,
                r.max_cpu_ms,
                r.median_cpu_ms,
                r.max_expansions,
                r.cap
            );
        }
    }
    Ok(())
}
