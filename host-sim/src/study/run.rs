//! The `run` command: one planner drives the agent through a scenario (the built-in bug trap
//! by default); the result is printed, written as JSON and drawn (`draw`): `found.png` when
//! the goal joins the forward tree, `meet.png` when it joined through a meet (both trees and
//! the joining segment, the paper's Fig. 7b), `obstacle.png` just after `--obstacle` dropped a
//! disc on the path and `avoided.png` when the path first goes around it (Fig. 7c-d),
//! `final.png` and `final.svg` at the end, and with `--animate N` an animated `run.gif`.

use std::path::PathBuf;

use anyhow::Result;
use bi_am_rrt::Point;
use bi_am_rrt::agent::Protocol;
use bi_am_rrt::clock::Clock as _;
use std::time::Instant;

use crate::results::Row;
use crate::sim::row;

use crate::draw::{self, Animation, Painter, Scene};
use crate::scenario::Scenario;
use crate::sim::clock::{ClockKind, VIRTUAL_NS_PER_UNIT, WallClock, virtual_clock};
use crate::sim::scene;
use crate::sim::{GoalRun, NODES, Prepared, SizedPlanner, drive_each, with_planner_at};

/// Arguments of `run`.
pub struct RunArgs {
    /// The scenario.
    pub scenario: Scenario,
    /// The planner (a Table 1 name with its overrides).
    pub planner: crate::sim::planners::Variant,
    /// All goals or the first.
    pub all_goals: bool,
    /// Seed.
    pub seed: u64,
    /// Clock.
    pub clock: ClockKind,
    /// Radius of a disc dropped on the path once the agent moves.
    pub obstacle: Option<f32>,
    /// Output directory.
    pub out: PathBuf,
    /// Also write an animated GIF (`run.gif`), one frame every this many plan calls.
    pub animate: Option<u32>,
    /// Planning time per call (`None`: the planner's, the paper's 150 ms).
    pub t_exp: Option<std::time::Duration>,
    /// Work per call (`--pace`).
    pub pace: crate::results::Pace,
    /// Skip the exact optimum of each leg (`--no-optimum`).
    pub no_optimum: bool,
}

/// The moment goal 1 joins the forward tree, replayed with the run's seed one expansion per
/// call on the virtual clock (a `plan` call ends after the join, with the agent moving and
/// the trees changed): `(found, meet)`, the scene at the join and, for a bidirectional
/// planner that joined through a meet, the same moment with the reverse tree as it was just
/// before the meet cleared it and the joining segment (the paper's Fig. 7b).
fn join_scenes<const N: usize>(
    prep: &Prepared,
    mut cfg: bi_am_rrt::Named,
    seed: u64,
) -> Result<(Option<Scene>, Option<Scene>)> {
    cfg.cfg.budget.max_expansions = 1;
    let clock = virtual_clock(VIRTUAL_NS_PER_UNIT);
    with_planner_at::<N, _>(prep, cfg, seed, prep.scenario.start, |p| {
        p.set_goal(prep.scenario.goals[0])
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        for _ in 0..1_000_000 {
            let reverse = draw::edges(p.reverse_tree());
            if p.grow(&clock).goal_in_tree {
                let mut found = scene(p, &[prep.scenario.start], &prep.scenario, 0, String::new());
                found.reverse = reverse;
                let meet = p.stats().meet.filter(|_| cfg.cfg.bidirectional).map(|m| {
                    let mut s = found.clone();
                    s.meet = Some(m);
                    s
                });
                return Ok((Some(found), meet));
            }
        }
        Ok((None, None))
    })
}

/// One goal of `result.json`: the row, the robot's radius, the trail's clearance and the
/// trail itself.
#[derive(serde::Serialize)]
pub struct GoalJson<'a> {
    #[serde(flatten)]
    row: &'a Row,
    robot_radius_m: f32,
    /// The clearance preference's margin and weight (absent: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    clearance_margin_m: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    clearance_weight: Option<f32>,
    min_clearance_m: Option<f64>,
    median_clearance_m: Option<f64>,
    p10_clearance_m: Option<f64>,
    /// The least clearance without the trail's first and last metre.
    inner_min_clearance_m: Option<f64>,
    trail: Vec<[f64; 2]>,
}

/// The goals of `result.json`: each row with the robot's radius, the clearance preference,
/// the clearance of the trail it drove and the trail itself (in the scenario's frame: a ROS
/// map's, or metres from the top-left corner, y down). `legs[k]`: goal `k + 1`'s trail.
pub fn result_goals<'a>(
    prep: &Prepared,
    rows: &'a [Row],
    legs: &[Vec<Point>],
) -> Vec<GoalJson<'a>> {
    let raw = prep.scenario.map.grid();
    rows.iter()
        .map(|row| {
            let trail = &legs[row.goal_index - 1];
            let c = crate::metric::clearance::trail_clearance(&raw, trail);
            GoalJson {
                row,
                robot_radius_m: prep.scenario.robot_radius,
                clearance_margin_m: prep.scenario.clearance.as_ref().map(|c| c.margin),
                clearance_weight: prep.scenario.clearance.as_ref().map(|c| c.weight),
                min_clearance_m: c.map(|c| c.min_m),
                median_clearance_m: c.map(|c| c.median_m),
                p10_clearance_m: c.map(|c| c.p10_m),
                inner_min_clearance_m: c.and_then(|c| c.inner_min_m),
                trail: trail.iter().map(|&p| prep.scenario.user_frame(p)).collect(),
            }
        })
        .collect()
}

/// Writes `result.json` in `out` ([`result_goals`]).
fn write_result(
    out: &std::path::Path,
    prep: &Prepared,
    rows: &[Row],
    legs: &[Vec<Point>],
) -> Result<()> {
    let goals_json = result_goals(prep, rows, legs);
    // Written whole, then renamed: a reader never sees half a file.
    let tmp = out.join("result.json.part");
    std::fs::write(&tmp, serde_json::to_string_pretty(&goals_json)?)?;
    std::fs::rename(&tmp, out.join("result.json"))?;
    Ok(())
}

/// Runs `run`.
pub fn run(args: &RunArgs) -> Result<()> {
    let variant = &args.planner;
    if let Some(r) = args.obstacle {
        let size = args.scenario.map.grid();
        let most = 0.25 * size.width_m().min(size.height_m());
        anyhow::ensure!(
            r.is_finite() && r > 0.0 && r <= most,
            "--obstacle {r}: the disc's radius must be above 0 and at most {most} m (a quarter of the map)"
        );
    }
    let prep = Prepared::new(args.scenario.clone());
    let prep = if args.no_optimum {
        prep.without_optimum()
    } else {
        prep
    };
    // Named -> fitted to the map -> the overrides; then the run's own budget and pace.
    let mut cfg = variant.config_for(&prep)?;
    if let Some(t) = args.t_exp {
        anyhow::ensure!(!t.is_zero(), "--t-exp-ms must be at least 1");
        cfg.cfg.budget.t_exp = t;
    }
    let paper = args.pace == crate::results::Pace::Paper;
    if paper {
        anyhow::ensure!(
            args.clock == ClockKind::Virtual,
            "--pace paper needs --clock virtual (every call lasts its full t_exp)"
        );
        crate::sim::paper_pace(&mut cfg.cfg);
    }
    // The trees' arena: the simulator's, or a bigger one when the scenario's roadmap needs it
    // (its search's scratch is the reverse arena's spare slots).
    let nodes = prep.arena_for(cfg);
    if nodes != NODES {
        println!(
            "note: the scenario's roadmap has {} nodes: the trees hold {nodes} nodes each ({NODES} \
             otherwise)",
            prep.roadmap().map_or(0, |r| r.nodes)
        );
    }
    match nodes {
        NODES => run_on::<NODES>(args, &prep, cfg, paper),
        16384 => run_on::<16384>(args, &prep, cfg, paper),
        65000 => run_on::<65000>(args, &prep, cfg, paper),
        n => Err(anyhow::anyhow!("no arena of {n} nodes")),
    }
}

/// [`run`] with trees of `N` nodes each. Not inlined: each arena's storage (2.7 MB at 65,000
/// nodes, made on the stack before it is boxed) stays in the frame of its own call.
#[inline(never)]
fn run_on<const N: usize>(
    args: &RunArgs,
    prep: &Prepared,
    cfg: bi_am_rrt::Named,
    paper: bool,
) -> Result<()> {
    std::fs::create_dir_all(&args.out)?;
    let goals: Vec<usize> = if args.all_goals {
        (0..prep.scenario.goals.len()).collect()
    } else {
        vec![0]
    };
    let mut trail = vec![prep.scenario.start];
    // Each goal's driven trail, from where its leg began (result.json, clearance).
    let legs: std::cell::RefCell<Vec<Vec<Point>>> =
        std::cell::RefCell::new(vec![Vec::new(); prep.scenario.goals.len()]);
    let mut disc = args.obstacle.map(crate::sim::DiscTrack::new);
    let mut avoided_drawn = false;
    let wall_clock = WallClock::new();
    let cpu_clock = crate::sim::clock::CpuClock::new();
    let cpu_mono_clock = crate::sim::clock::CpuMonoClock::new();
    let virtual_clock = virtual_clock(VIRTUAL_NS_PER_UNIT);
    let now_s = || match args.clock {
        ClockKind::Wall => wall_clock.now() as f64 / wall_clock.ticks_per_second() as f64,
        ClockKind::Cpu => cpu_clock.now() as f64 / cpu_clock.ticks_per_second() as f64,
        ClockKind::CpuMono => {
            cpu_mono_clock.now() as f64 / cpu_mono_clock.ticks_per_second() as f64
        }
        ClockKind::Virtual => virtual_clock.peek() as f64 / virtual_clock.ticks_per_second() as f64,
    };
    let leg_starts = crate::metric::optimum::leg_starts(&prep.scenario);
    let t_exp_ticks = virtual_clock.ticks(cfg.cfg.budget.t_exp);
    let call_end = std::cell::Cell::new(0u64);
    let mut pictures: Vec<String> = Vec::new();
    let out = args.out.clone();
    let painter = Painter::for_scenario(&prep.scenario, 800);
    let gif = out.join("run.gif");
    // Animation frames are smaller: a GIF of full-size frames runs to megabytes.
    let small = Painter::for_scenario(&prep.scenario, 480);
    let mut animation = match args.animate {
        Some(_) => Some(Animation::new(&small, &gif, 80)?),
        None => None,
    };
    let title = |moment: &str| {
        format!(
            "{} on {}, seed {}: {moment}",
            cfg.name(),
            prep.scenario.name,
            args.seed
        )
    };
    // Legs through long narrow corridors: said before the run, not after it.
    prep.warn_narrow_legs(cfg, N, &|k| {
        goals.contains(&k).then(|| {
            format!(
                "within the leg's {} calls",
                prep.leg_calls(k, &Protocol::default())
            )
        })
    });
    let started = Instant::now();
    // On a terminal, a bar per leg (calls against the leg's cap, with an ETA); elsewhere
    // nothing but the line per goal.
    let protocol = Protocol::default();
    let bar = indicatif::ProgressBar::new(0).with_style(
        indicatif::ProgressStyle::with_template(
            "  goal {msg} [{elapsed_precise}] {bar:30} {pos}/{len} calls (at most; ETA {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut failure: Option<anyhow::Error> = None;
    let (runs, final_nodes) = with_planner_at::<N, _>(
        prep,
        cfg,
        args.seed,
        prep.scenario.start,
        |p| {
            let hook = |p: &mut SizedPlanner<'_, '_, N>, gi: usize, agent: Point, call: u32| {
                if call == 0 {
                    bar.reset();
                    bar.set_length(u64::from(prep.leg_calls(gi, &protocol)));
                    bar.set_message(format!("{}/{}", gi + 1, prep.scenario.goals.len()));
                }
                bar.set_position(u64::from(call));
                // At the paper's pace every call lasts its full t_exp (as `experiment`).
                if paper {
                    let end = call_end
                        .get()
                        .saturating_add(t_exp_ticks)
                        .max(virtual_clock.peek());
                    virtual_clock.set(end);
                    call_end.set(end);
                }
                if trail.last() != Some(&agent) {
                    trail.push(agent);
                }
                let mut legs = legs.borrow_mut();
                let leg = &mut legs[gi];
                if leg.is_empty() {
                    leg.push(leg_starts[gi]);
                }
                if leg.last() != Some(&agent) {
                    leg.push(agent);
                }
                let mut save = |name: &str, s: &Scene| {
                    let r = painter.png(s, &out.join(name));
                    match r {
                        Ok(()) => pictures.push(name.to_string()),
                        Err(e) => {
                            failure.get_or_insert(e);
                        }
                    }
                };
                let dropped = disc.as_ref().is_some_and(|d| d.disc.is_some());
                if dropped && !avoided_drawn {
                    let mut path = vec![Point::ZERO; p.tree().len().max(1)];
                    if p.path(&mut path).is_ok_and(|i| i.to_goal && !i.blocked) {
                        avoided_drawn = true;
                        save(
                            "avoided.png",
                            &scene(p, &trail, &prep.scenario, gi, title("path around the disc")),
                        );
                    }
                }
                if let Some(d) = disc.as_mut().filter(|_| gi == goals[0])
                    && let Some(c) = d.on_call(p, agent, leg_starts[gi], now_s())
                {
                    println!(
                        "dropped a disc of radius {} m at ({:.1}, {:.1}) on the path",
                        c.radius, c.center.x, c.center.y
                    );
                    save(
                        "obstacle.png",
                        &scene(
                            p,
                            &trail,
                            &prep.scenario,
                            gi,
                            title("a disc drops on the path"),
                        ),
                    );
                }
                if let (Some(every), Some(a)) = (args.animate, animation.as_mut())
                    && call.is_multiple_of(every.max(1))
                    && failure.is_none()
                {
                    let s = scene(
                        p,
                        &trail,
                        &prep.scenario,
                        gi,
                        title(&format!("goal {}, call {call}", gi + 1)),
                    );
                    if let Err(e) = a.frame(&s) {
                        failure = Some(e);
                    }
                }
            };
            // As each goal ends: a line, and result.json with the goals so far (the optimum, a
            // separate step, comes last: a run is never lost to it).
            let mut done: Vec<Row> = Vec::new();
            let mut write_error: Option<anyhow::Error> = None;
            let on_goal = |g: &GoalRun| {
                let r = crate::sim::row_with_optimum(
                    prep,
                    None,
                    cfg,
                    args.seed,
                    g,
                    args.clock,
                    0,
                    None,
                    started.elapsed().as_secs_f64(),
                );
                bar.suspend(|| {
                println!(
                    "  goal {} of {}: reached {}, travelled {:.2} m, {} collisions, {} plan calls of at most {} ({:.1} s)",
                    g.goal_index + 1,
                    prep.scenario.goals.len(),
                    g.result.reached,
                    g.result.travelled,
                    g.result.collisions,
                    g.result.calls,
                    prep.leg_calls(g.goal_index, &protocol),
                    started.elapsed().as_secs_f64()
                )
            });
                done.push(r);
                if let Err(e) = write_result(&args.out, prep, &done, &legs.borrow()) {
                    write_error.get_or_insert(e);
                }
            };
            let runs: Vec<GoalRun> = match args.clock {
                ClockKind::Wall => {
                    drive_each(p, prep, &wall_clock, &goals, &protocol, hook, on_goal)?
                }
                ClockKind::Cpu => {
                    drive_each(p, prep, &cpu_clock, &goals, &protocol, hook, on_goal)?
                }
                ClockKind::CpuMono => {
                    drive_each(p, prep, &cpu_mono_clock, &goals, &protocol, hook, on_goal)?
                }
                ClockKind::Virtual => {
                    drive_each(p, prep, &virtual_clock, &goals, &protocol, hook, on_goal)?
                }
            };
            bar.finish_and_clear();
            if let Some(e) = write_error {
                return Err(e.context("writing result.json"));
            }
            let last = runs.last().map_or(0, |g| g.goal_index);
            let s = scene(p, &trail, &prep.scenario, last, title("the end"));
            painter.png(&s, &out.join("final.png"))?;
            painter.svg(&s, &out.join("final.svg"))?;
            Ok((runs, p.tree().len()))
        },
    )?;
    if let Some(e) = failure {
        return Err(e.context("drawing a picture"));
    }
    let (found, meet) = join_scenes::<N>(prep, cfg, args.seed)?;
    if let Some(mut s) = found {
        s.title = title("goal 1 joins the tree (replayed one expansion per call)");
        painter.png(&s, &args.out.join("found.png"))?;
        pictures.insert(0, "found.png".into());
    }
    if let Some(mut s) = meet {
        s.title = title("the trees meet (replayed one expansion per call)");
        painter.png(&s, &args.out.join("meet.png"))?;
        pictures.insert(0, "meet.png".into());
    }
    if let Some(a) = &animation {
        println!("  animation: {} frames in {}", a.frames, gif.display());
    }
    drop(animation);
    if disc.as_ref().is_some_and(|d| d.disc.is_none()) {
        println!(
            "no disc was dropped: the path never ran 10 m ahead of the agent with the goal further \
             than the radius + 3 m"
        );
    }
    let wall_s = started.elapsed().as_secs_f64();
    if prep.optima_if_known().is_none() && !prep.no_optimum {
        println!(
            "  the exact optimum of {} leg(s) (a step of its own: --no-optimum skips it) ...",
            runs.len()
        );
    }
    let rows: Vec<Row> = runs
        .iter()
        .map(|g| {
            row(
                prep,
                cfg,
                args.seed,
                g,
                args.clock,
                final_nodes,
                None,
                wall_s,
            )
        })
        .collect();
    let mut rows = rows;
    if let (Some(d), Some(r)) = (disc.as_ref(), rows.first_mut()) {
        d.finish(r, prep, prep.scenario.goals[goals[0]]);
    }
    println!(
        "{} on {} ({}), seed {}, {:?} clock",
        args.planner.name, prep.scenario.name, prep.scenario.source, args.seed, args.clock
    );
    let used = cfg;
    println!(
        "  lengths {} (scale {:.3}): e_max {:.3} m, e_search {:.3} m, root step {:.3} m, sigma {:.3} m",
        if prep.scenario.paper_lengths {
            "as Table 2 prints them (--paper-lengths)"
        } else {
            "that follow the map"
        },
        prep.scenario.length_scale(),
        used.cfg.search.e_max,
        used.cfg.search_step(),
        used.cfg.rewiring.root_step,
        used.cfg.search.sigma
    );
    let legs = legs.into_inner();
    let raw = prep.scenario.map.grid();
    let clearances: Vec<_> = rows
        .iter()
        .map(|g| crate::metric::clearance::trail_clearance(&raw, &legs[g.goal_index - 1]))
        .collect();
    if prep.scenario.robot_radius > 0.0 {
        println!(
            "  robot radius {} m: the map inflated for its disc; the optimum is the inflated map's",
            prep.scenario.robot_radius
        );
    }
    if let Some(c) = &prep.scenario.clearance {
        println!(
            "  clearance preference: {} m beyond the body, weight {} (a metre at the body's edge costs {})",
            c.margin,
            c.weight,
            1.0 + c.weight
        );
    }
    for (g, c) in rows.iter().zip(&clearances) {
        let goal = prep.scenario.show(prep.scenario.goals[g.goal_index - 1]);
        let clear = c.map_or(String::new(), |c| {
            format!(
                ", clearance min {:.3} m / 10th percentile {:.3} m / median {:.3} m",
                c.min_m, c.p10_m, c.median_m
            )
        });
        println!(
            "  goal {} {goal}: reached {}, search time {}, travelled {} m, exact optimum {}, {} collisions{clear}, {} nodes when found, {} plan calls",
            g.goal_index,
            g.reached,
            g.search_time_s
                .map_or("-".into(), |s| format!("{:.3} ms", s * 1e3)),
            g.path_length_m.map_or("-".into(), |l| format!("{l:.2}")),
            match (g.optimal_m, g.travelled_ratio) {
                (Some(o), Some(r)) => format!("{o:.2} m (travelled / optimum {r:.3})"),
                (Some(o), None) => format!("{o:.2} m"),
                _ => "- (unreachable)".into(),
            },
            g.collisions,
            g.nodes_at_goal.map_or("-".into(), |n| n.to_string()),
            g.calls
        );
    }
    if let Some(r) = rows.first()
        && let (Some(x), Some(y), Some(rad)) = (r.disc_x_m, r.disc_y_m, r.disc_r_m)
    {
        let m = |v: Option<f32>| v.map_or("-".into(), |v| format!("{v:.2} m"));
        println!(
            "  disc of {rad} m at {}: path cost before {}, free path again after {} (cost {}), \
             travelled from the drop {} against an exact optimum around the disc of {}",
            prep.scenario.show(bi_am_rrt::Point::new(x, y)),
            m(r.cost_before_drop_m),
            r.replan_s
                .map_or("- (never)".into(), |s| format!("{:.1} ms", s * 1e3)),
            m(r.replanned_cost_m),
            m(r.travelled_after_drop_m),
            m(r.optimal_after_drop_m),
        );
    }
    if let Some(s) = prep.bake_seconds.get() {
        println!("  diffusion table baked in {s:.3} s");
    }
    write_result(&args.out, prep, &rows, &legs)?;
    pictures.push("final.png".into());
    pictures.push("final.svg".into());
    println!(
        "  pictures ({}) and result.json in {}",
        pictures.join(", "),
        args.out.display()
    );
    Ok(())
}
