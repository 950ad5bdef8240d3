//! The `run` command: one planner drives the agent through a scenario (the built-in bug trap
//! by default); the result is printed, written as JSON and drawn: `final.png` (trees, path,
//! trail) and `found.png` (the trees when the goal joined, e.g. right after the meet).

use std::path::PathBuf;

use anyhow::{Context, Result};
use bi_am_rrt::agent::Protocol;
use bi_am_rrt::{Circle, Point};
use std::time::Instant;

use crate::experiment::row;
use crate::results::Row;

use crate::clock::{ClockKind, VIRTUAL_NS_PER_UNIT, WallClock, virtual_clock};
use crate::draw::{self, Canvas};
use crate::maps::Scenario;
use crate::sim::{GoalRun, Prepared, SimPlanner, drive, with_planner};

/// Arguments of `run`.
pub struct RunArgs {
    /// The scenario.
    pub scenario: Scenario,
    /// Table 1 name.
    pub planner: String,
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
}

fn picture(p: &SimPlanner<'_, '_>, trail: &[Point], scenario: &Scenario) -> Canvas {
    let mut c = Canvas::new(&scenario.map.grid(), 800);
    c.tree(p.tree(), draw::FORWARD);
    c.tree(p.reverse_tree(), draw::REVERSE);
    for (_, circle) in p.map().obstacles().iter() {
        c.circle(&circle);
    }
    let mut path = vec![Point::ZERO; p.tree().len().max(1)];
    if let Ok(bi_am_rrt::PathInfo { len: n, .. }) = p.path(&mut path) {
        c.polyline(&path[..n], draw::PATH);
    }
    c.polyline(trail, draw::TRAIL);
    c.dot(scenario.start, 5, Rgb::from([0, 120, 0]));
    for g in &scenario.goals {
        c.dot(*g, 4, Rgb::from([0, 0, 200]));
    }
    c
}

use image::Rgb;

/// Runs `run`.
pub fn run(args: &RunArgs) -> Result<()> {
    let cfg = crate::experiment::parse_planners(&args.planner)?
        .first()
        .copied()
        .context("no planner named")?;
    if let Some(r) = args.obstacle {
        let size = args.scenario.map.grid();
        let most = 0.25 * size.width_m().min(size.height_m());
        anyhow::ensure!(
            r.is_finite() && r > 0.0 && r <= most,
            "--obstacle {r}: the disc's radius must be above 0 and at most {most} m (a quarter of the map)"
        );
    }
    let prep = Prepared::new(args.scenario.clone());
    std::fs::create_dir_all(&args.out)?;
    let goals: Vec<usize> = if args.all_goals {
        (0..prep.scenario.goals.len()).collect()
    } else {
        vec![0]
    };
    let mut trail = vec![prep.scenario.start];
    let mut found_drawn = false;
    let mut dropped = false;
    let out = args.out.clone();
    let started = Instant::now();
    let (runs, final_nodes) = with_planner(&prep, cfg, args.seed, |p| {
        let hook = |p: &mut SimPlanner<'_, '_>, _gi: usize, agent: Point, _call: u32| {
            if trail.last() != Some(&agent) {
                trail.push(agent);
            }
            if !found_drawn && p.goal_node().is_some() {
                found_drawn = true;
                let _ = picture(p, &trail, &prep.scenario).save(&out.join("found.png"));
            }
            if let (Some(r), false) = (args.obstacle, dropped)
                && agent.dist(prep.scenario.start) > 2.0
            {
                // A disc on the path about 10 m ahead of the agent.
                let mut path = vec![Point::ZERO; p.tree().len()];
                if let Ok(bi_am_rrt::PathInfo { len: n, .. }) = p.path(&mut path) {
                    let mut ahead = 0.0;
                    for w in path[..n].windows(2) {
                        ahead += w[0].dist(w[1]);
                        if ahead > 10.0 && p.goal().is_some_and(|g| w[1].dist(g) > r + 3.0) {
                            dropped = p.add_obstacle(Circle::new(w[1], r)).is_ok();
                            if dropped {
                                println!(
                                    "dropped a disc of radius {r} m at ({:.1}, {:.1}) on the path",
                                    w[1].x, w[1].y
                                );
                            }
                            break;
                        }
                    }
                }
            }
        };
        let runs: Vec<GoalRun> = match args.clock {
            ClockKind::Wall => drive(
                p,
                &prep,
                &WallClock::new(),
                &goals,
                &Protocol::default(),
                hook,
            )?,
            ClockKind::Virtual => drive(
                p,
                &prep,
                &virtual_clock(VIRTUAL_NS_PER_UNIT),
                &goals,
                &Protocol::default(),
                hook,
            )?,
        };
        picture(p, &trail, &prep.scenario).save(&out.join("final.png"))?;
        Ok((runs, p.tree().len()))
    })?;
    let wall_s = started.elapsed().as_secs_f64();
    let rows: Vec<Row> = runs
        .iter()
        .map(|g| {
            row(
                &prep,
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
    println!(
        "{} on {} ({}), seed {}, {:?} clock",
        args.planner, prep.scenario.name, prep.scenario.source, args.seed, args.clock
    );
    for g in &rows {
        println!(
            "  goal {}: reached {}, search time {}, path {:.2} m, {} collisions, {} nodes when found, {} plan calls",
            g.goal_index,
            g.reached,
            g.search_time_s
                .map_or("-".into(), |s| format!("{:.3} ms", s * 1e3)),
            g.path_length_m,
            g.collisions,
            g.nodes_at_goal.map_or("-".into(), |n| n.to_string()),
            g.calls
        );
    }
    if let Some(s) = prep.bake_seconds.get() {
        println!("  diffusion table baked in {s:.3} s");
    }
    std::fs::write(
        args.out.join("result.json"),
        serde_json::to_string_pretty(&rows)?,
    )?;
    println!("  pictures and result.json in {}", args.out.display());
    Ok(())
}
