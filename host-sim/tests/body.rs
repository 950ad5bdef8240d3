//! The simulator with a robot body (issue 41): a leg the disc cannot drive is refused when the
//! scenario loads, naming it; `--snap-to-room` moves a start without room; `run` keeps the
//! disc's clearance along the driven trail (measured by `host_sim::metric::clearance`) and writes it
//! with the trail to `result.json`; the door scenes run with a body; and, in the opt-in suite,
//! the MovingAI maze that once counted a collision drives seeds 1-10 without one.

use std::path::Path;

mod common;

use bi_am_rrt::Point;
use host_sim::scenario::{OwnedGrid, Scenario};

/// A 20 m x 10 m hall at 0.25 m cells split by a wall at x = 10 m with one door of `door` m.
fn hall(door: f32) -> Scenario {
    let cells = (door / 0.25).round() as u16;
    let map = OwnedGrid::from_fn(80, 40, 0.25, |c, r| {
        (c == 40 || c == 41) && !(18..18 + cells).contains(&r)
    })
    .unwrap();
    Scenario::new(
        "hall",
        map,
        "test",
        Point::new(3.0, 5.0),
        vec![Point::new(17.0, 5.0), Point::new(4.0, 8.0)],
        Some(6.0),
    )
}

#[test]
fn a_door_narrower_than_the_disc_is_refused_by_name() {
    // 1 m door: a 0.3 m disc passes, a 0.6 m one does not.
    assert!(hall(1.0).with_robot_radius(0.3).is_ok());
    let e = hall(1.0).with_robot_radius(0.6).unwrap_err().to_string();
    assert!(
        e.contains("goal 1")
            && e.contains("cannot be reached from the start")
            && e.contains("1.2 m"),
        "{e}"
    );
    // A start too close to the wall: named, with where it would fit; snapped on request.
    let mut near = hall(1.0);
    near.start = Point::new(9.8, 2.0);
    let e = near.clone().with_robot_radius(0.3).unwrap_err().to_string();
    assert!(
        e.contains("start") && e.contains("nearest position with room"),
        "{e}"
    );
    let snapped = near.with_body(0.3, true).unwrap();
    assert!(
        snapped.start.x <= 10.0 - 0.3 + 1e-3 && snapped.start.dist(Point::new(9.8, 2.0)) < 0.2,
        "{:?}",
        snapped.start
    );
    for bad in [-1.0, f32::NAN, f32::INFINITY] {
        assert!(hall(1.0).with_robot_radius(bad).is_err());
    }
}

#[test]
fn run_keeps_the_disc_clear_and_writes_the_trail() {
    let dir = tempfile::tempdir().unwrap();
    let sc = hall(1.0).with_robot_radius(0.3).unwrap();
    host_sim::study::run::run(&host_sim::study::run::RunArgs {
        scenario: sc.clone(),
        planner: host_sim::sim::planners::one("Bi-AM-RRT*(D) tuned").unwrap(),
        all_goals: true,
        seed: 3,
        clock: host_sim::sim::clock::ClockKind::Virtual,
        obstacle: None,
        out: dir.path().to_path_buf(),
        animate: None,
        t_exp: Some(std::time::Duration::from_millis(5)),
        pace: host_sim::results::Pace::Full,
        no_optimum: false,
    })
    .unwrap();
    let text = std::fs::read_to_string(dir.path().join("result.json")).unwrap();
    let rows: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    assert_eq!(rows.len(), 2);
    for row in &rows {
        assert_eq!(row["reached"], true, "{row}");
        assert_eq!(row["collisions"], 0, "{row}");
        assert!(
            (row["robot_radius_m"].as_f64().unwrap() - 0.3).abs() < 1e-6,
            "{row}"
        );
        let least = row["min_clearance_m"].as_f64().unwrap();
        assert!(least >= 0.3 - 1e-4, "least clearance {least}");
        // The trail in the file is the one measured: its clearance again, from the file.
        let trail: Vec<Point> = row["trail"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| Point::new(p[0].as_f64().unwrap() as f32, p[1].as_f64().unwrap() as f32))
            .collect();
        assert!(trail.len() > 2);
        let c = host_sim::metric::clearance::trail_clearance(&sc.map.grid(), &trail).unwrap();
        assert!((c.min_m - least).abs() < 1e-6, "{c:?} vs {least}");
    }
    // Leg 1 goes through the door: the path is longer than the point's optimum would need.
    assert!(rows[0]["travelled_ratio"].as_f64().unwrap() < 1.1);
}

/// The clearance preference (`--clearance-margin`, `--clearance-weight`): the same runs keep
/// further from the walls over their tightest tenth, every goal still reached without a
/// collision, and `result.json` names the preference.
#[test]
fn a_clearance_preference_keeps_the_trail_off_the_walls() {
    let p10 = |sc: Scenario| -> Vec<f64> {
        let dir = tempfile::tempdir().unwrap();
        host_sim::study::run::run(&host_sim::study::run::RunArgs {
            scenario: sc,
            planner: host_sim::sim::planners::one("Bi-AM-RRT*(D) tuned").unwrap(),
            all_goals: true,
            seed: 3,
            clock: host_sim::sim::clock::ClockKind::Virtual,
            obstacle: None,
            out: dir.path().to_path_buf(),
            animate: None,
            t_exp: Some(std::time::Duration::from_millis(5)),
            pace: host_sim::results::Pace::Full,
            no_optimum: false,
        })
        .unwrap();
        let text = std::fs::read_to_string(dir.path().join("result.json")).unwrap();
        let rows: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
        rows.iter()
            .map(|row| {
                assert_eq!(row["reached"], true, "{row}");
                assert_eq!(row["collisions"], 0, "{row}");
                row["p10_clearance_m"].as_f64().unwrap()
            })
            .collect()
    };
    let body = hall(1.5).with_robot_radius(0.2).unwrap();
    let plain = p10(body.clone());
    let kept = p10(body.clone().with_clearance(1.0, 4.0).unwrap());
    println!("10th percentile clearance per leg: without {plain:?}, with {kept:?}");
    let sum = |v: &[f64]| v.iter().sum::<f64>();
    // Measured: 0.674 and 0.489 m without, 0.772 and 0.829 m with.
    assert!(sum(&kept) > sum(&plain) + 0.2, "{plain:?} -> {kept:?}");
    assert!(body.clone().with_clearance(0.5, f32::NAN).is_err());
    assert!(body.with_clearance(-1.0, 1.0).is_err());
}

/// The door scenes (issue 27) with a 0.3 m body: every run arrives, and no run with live cells
/// or the rebaked map brings the disc within its radius of the closed door.
#[test]
fn door_scenes_run_with_a_body() {
    use host_sim::study::moving::{Kind, MovingArgs, Treatment, moving};
    let dir = tempfile::tempdir().unwrap();
    let scenario = common::two_doors().with_robot_radius(0.3).unwrap();
    let prep = host_sim::sim::Prepared::new(scenario);
    let rows = moving(
        &prep,
        &MovingArgs {
            kinds: vec![Kind::Door, Kind::ClosedDoor],
            seeds: 1,
            t_exp: std::time::Duration::from_millis(2),
            out: dir.path().to_path_buf(),
            animate: None,
            route_calls: 20,
        },
    )
    .unwrap();
    assert_eq!(rows.len(), 4);
    for r in &rows {
        assert!(r.reached, "{r:?}");
        if r.treatment != Treatment::Static {
            assert_eq!(r.moved_into + r.ran_into, 0, "{r:?}");
        }
    }
}

/// Issue 41's repro: the 512 x 512 MovingAI maze at 0.5 m counted a collision on goal 3 with
/// seed 1 (`run --all-goals --clock virtual --seed 1 --t-exp-ms 5`). Seeds 1-4 (`MAZE512_SEEDS`
/// sets how many: issue 41's note measured 10), every goal: reached, no collision (the
/// protocol's exact check).
#[test]
#[ignore = "long: 12 legs of the 512 x 512 maze, about 1.5 minutes on 2 cores (CI runs it)"]
fn regression_maze512_no_collisions() {
    use rayon::prelude::*;
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/maps/external/scenarios.toml");
    if !file.exists() {
        eprintln!("skipped: {} not found", file.display());
        return;
    }
    let sc = host_sim::scenario::load_scenarios(&file, Some(&["maze512_8_0".into()]))
        .unwrap()
        .remove(0);
    let prep = host_sim::sim::Prepared::new(sc);
    prep.diffusion().unwrap();
    let mut cfg = host_sim::sim::planners::parse_variants("Bi-AM-RRT*(D) tuned").unwrap()[0].cfg;
    cfg.cfg.budget.t_exp = std::time::Duration::from_millis(5);
    let goals: Vec<usize> = (0..prep.scenario.goals.len()).collect();
    let seeds: u64 = std::env::var("MAZE512_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4);
    let bad: Vec<String> = (1..=seeds)
        .into_par_iter()
        .flat_map_iter(|seed| {
            let clock =
                host_sim::sim::clock::virtual_clock(host_sim::sim::clock::VIRTUAL_NS_PER_UNIT);
            let runs = host_sim::sim::with_planner(&prep, prep.fit(cfg), seed, |p| {
                host_sim::sim::drive(
                    p,
                    &prep,
                    &clock,
                    &goals,
                    &bi_am_rrt::agent::Protocol::default(),
                    |_, _, _, _| {},
                )
            })
            .unwrap();
            let mut bad = Vec::new();
            if runs.len() != goals.len() {
                bad.push(format!(
                    "seed {seed}: {} of {} goals",
                    runs.len(),
                    goals.len()
                ));
            }
            for g in runs {
                if !g.result.reached || g.result.collisions > 0 {
                    bad.push(format!(
                        "seed {seed} goal {}: {:?}",
                        g.goal_index + 1,
                        g.result
                    ));
                }
            }
            bad
        })
        .collect();
    assert!(bad.is_empty(), "{bad:#?}");
}
