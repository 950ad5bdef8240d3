//! The configuration's own tests: names, lengths, validation.

use super::*;

extern crate std;
use std::string::ToString;

#[test]
fn table1_names() {
    let names: [&str; 20] = [
        "RT-RRT*",
        "RT-RRT*(D)",
        "AM-RRT*(E)",
        "AM-RRT*(D)",
        "AM-RRT*(G)",
        "RT-RRT*-1",
        "RT-RRT*(D)-1",
        "AM-RRT*(E)-1",
        "AM-RRT*(D)-1",
        "AM-RRT*(G)-1",
        "RT-RRT*-2",
        "RT-RRT*(D)-2",
        "AM-RRT*(E)-2",
        "AM-RRT*(D)-2",
        "AM-RRT*(G)-2",
        "Bi-RT-RRT*",
        "Bi-RT-RRT*(D)",
        "Bi-AM-RRT*(E)",
        "Bi-AM-RRT*(D)",
        "Bi-AM-RRT*(G)",
    ];
    for (c, n) in Named::table1().iter().zip(names) {
        assert!(c.name() == n, "{n}");
        assert_eq!(Named::from_name(n), Some(*c));
    }
    assert_eq!(
        Named::from_name("Bi-AM-RRT*(D)"),
        Some(Named {
            metric: MetricKind::Diffusion,
            cfg: Config::paper()
        })
    );
    assert!(Named::from_name("Bi-AM-RRT*").is_none());
    let tuned = Named::from_name("Bi-AM-RRT*(D) tuned").unwrap();
    assert_eq!(tuned.cfg, Config::default());
    assert_eq!(tuned.cfg.tactics, Tactics::TUNED);
    assert_eq!(tuned.cfg.validate(), Ok(()));
    assert!(Named::from_name("AM-RRT*(D)-12").is_none());
    // The paper's version of each tuned planner is the Table 1 planner.
    for n in Named::table1() {
        assert_eq!(n.tuned().paper(), n);
    }
    // Some tactics: named one by one; a metric of the caller's own: (?).
    let mut some = Config::paper();
    some.tactics.connect = true;
    some.tactics.corner_cuts = true;
    assert!(some.name(MetricKind::Other) == "Bi-AM-RRT*(?) +connect +corner_cuts");
}

#[test]
fn lengths_follow_the_map_and_keep_table_2_on_the_papers() {
    for n in Named::table1()
        .into_iter()
        .chain(Named::table1().map(Named::tuned))
    {
        let c = n.cfg;
        // The paper's maps: 100 m and 200 m at 1 m cells, bit for bit.
        for side in [100.0, 150.0, 200.0] {
            assert_eq!(c.for_map(side, side, 1.0), c, "{}", n.name());
        }
        // A 20 m map at 0.05 m: a fifth of every length.
        let f = c.for_map(20.0, 15.0, 0.05);
        assert!((f.search.e_max - c.search.e_max * 0.2).abs() < 1e-6);
        assert!((f.search.sigma - c.search.sigma * 0.2).abs() < 1e-5);
        assert!((f.search.e_search - c.search.e_search * 0.2).abs() < 1e-5);
        assert!((f.rewiring.root_step - c.rewiring.root_step * 0.2).abs() < 1e-6);
        assert_eq!(f.validate(), Ok(()));
        // 400 m: twice; a tiny coarse map keeps steps of 4 cells.
        assert_eq!(
            c.for_map(400.0, 100.0, 1.0).search.e_max,
            c.search.e_max * 2.0
        );
        assert_eq!(c.for_map(8.0, 8.0, 0.5).search.e_max, 2.0);
    }
    assert_eq!(length_scale(f32::NAN), 1.0);
    assert_eq!(length_scale(50.0), 0.5);
}

/// Issue 7, case 7: NaN or negative `e_max`, `sigma`, zero budgets and `p_goal > 1` were
/// accepted and gave a planner that silently never grew.
#[test]
fn regression_silent_misconfiguration_is_refused() {
    for n in Named::table1() {
        assert_eq!(n.cfg.validate(), Ok(()));
    }
    let base = Config::bi_am_rrt();
    type Case = (fn(&mut Config), &'static str);
    let cases: [Case; 14] = [
        (|c| c.search.e_max = f32::NAN, "e_max"),
        (|c| c.search.e_max = -1.0, "e_max"),
        (|c| c.search.e_max = f32::INFINITY, "e_max"),
        (|c| c.search.sigma = f32::NAN, "sigma"),
        (|c| c.search.sigma = -3.0, "sigma"),
        (|c| c.budget.t_exp = Duration::ZERO, "t_exp"),
        (|c| c.search.p_goal = 1.5, "p_goal"),
        (|c| c.search.p_beacon = f32::NAN, "p_beacon"),
        (|c| c.search.p_gap = -0.1, "p_gap"),
        (|c| c.search.p_uniform = f32::NAN, "p_uniform"),
        (|c| c.memory.n_max = 0, "n_max"),
        (|c| c.search.sample_attempts = 0, "sample_attempts"),
        (|c| c.budget.max_expansions = 0, "max_expansions"),
        (|c| c.budget.max_work = 0, "max_work"),
    ];
    for (set, want) in cases {
        let mut c = base;
        set(&mut c);
        let e = c.validate().unwrap_err();
        assert_eq!(e.param, want);
        assert_eq!(e, param(want).unwrap().error());
    }
}

/// A configuration that differs from `Config::paper()` in every value, written as a struct
/// literal: a field added to `Config` must be added here, and then the table must hold it for
/// [`the_table_holds_every_value`] to pass.
fn every_value_changed() -> Config {
    Config {
        base: Base::AmRrt,
        bidirectional: false,
        new_rewiring: false,
        tactics: Tactics::TUNED,
        search: Search {
            e_max: 7.5,
            e_search: 11.0,
            sigma: 17.0,
            steer_candidates: 9,
            sample_attempts: 33,
            p_goal: 0.25,
            p_uniform: 0.125,
            p_beacon: 0.375,
            p_gap: 0.625,
        },
        rewiring: Rewiring {
            t_root: Duration::from_micros(2500),
            t_goal: Duration::from_nanos(1_000_001),
            mode: RewireMode::PerExpansion { visits: 7 },
            path_shortcuts: 3,
            root_step: 2.25,
        },
        budget: Budget {
            t_exp: Duration::from_millis(40),
            max_expansions: 123,
            max_work: 456_789,
            clock_every: 64,
            clock_every_max: 4096,
        },
        memory: Memory {
            n_max: 11,
            n_max_informed: 44,
            recycle_cover: 5,
        },
        as_printed: AsPrinted::ALL,
        motion: Motion {
            agent_speed: 1.5,
            period: 0.1,
            horizon: 2.0,
            obstacle_speed: 0.75,
        },
        robot_radius: 0.3,
        clearance_weight: 1.25,
    }
}

/// Every value of a configuration is in the parameter table: copying each value through its
/// text onto the paper's configuration gives the other configuration exactly (durations to
/// the nanosecond, reals bit for bit).
#[test]
fn the_table_holds_every_value() {
    let target = every_value_changed();
    let mut c = Config::paper();
    for p in PARAMS {
        // `faithful` and `visits` share one field: the target is off the faithful mode.
        if p.name != "faithful" {
            assert_ne!(
                p.get(&c),
                p.get(&target),
                "{}: pick a value that differs",
                p.name
            );
        }
        let text = p.get(&target).to_string();
        p.set_text(&mut c, &text)
            .unwrap_or_else(|e| panic!("{} = {text}: {e}", p.name));
        assert_eq!(p.get(&c), p.get(&target), "{} = {text}", p.name);
    }
    assert_eq!(c, target);
    // And the faithful mode, which `visits` ends.
    set(&mut c, "faithful", "true").unwrap();
    assert_eq!(c.rewiring.mode, RewireMode::Faithful);
    assert_eq!(param("visits").unwrap().get(&c), Value::Count(0));
    set(&mut c, "faithful", "false").unwrap();
    assert_eq!(
        c.rewiring.mode,
        RewireMode::PerExpansion {
            visits: NAMED_SET_VISITS
        }
    );
}

#[test]
fn the_table_names_each_value_once_and_every_switch() {
    for (i, p) in PARAMS.iter().enumerate() {
        assert!(
            PARAMS.iter().skip(i + 1).all(|q| q.name != p.name),
            "{} twice",
            p.name
        );
        assert!(!p.doc.is_empty() && !p.doc.contains('\n'), "{}", p.name);
        assert_eq!(param(p.name).map(|q| q.name), Some(p.name));
    }
    for name in Tactics::NAMES {
        assert_eq!(param(name).unwrap().group, "tactics", "{name}");
    }
    let switches = PARAMS.iter().filter(|p| p.group == "as_printed").count();
    assert_eq!(switches, AsPrinted::NAMES.len());
}

/// The validation the table generates checks each value with a rule, and names it.
#[test]
fn validate_checks_every_rule_of_the_table() {
    use crate::error::Rule;
    for p in PARAMS.iter().filter(|p| p.rule != Rule::Any) {
        let bad = match p.get(&Config::paper()) {
            Value::Real(_) => Value::Real(f32::NAN),
            Value::Count(_) => Value::Count(0),
            Value::Millis(_) => Value::Millis(Duration::ZERO),
            Value::Switch(_) => unreachable!("{}: a switch has no rule", p.name),
        };
        let mut c = Config::paper();
        p.set_value(&mut c, bad).unwrap();
        assert_eq!(c.validate(), Err(p.error()), "{}", p.name);
        assert!(!p.keeps_rule(bad));
    }
}

#[test]
fn set_refuses_bad_text_and_leaves_the_configuration() {
    let before = Config::paper();
    let mut c = before;
    let refused = [
        (
            "e_max",
            "-1",
            SetError::Rule(param("e_max").unwrap().error()),
        ),
        ("e_max", "five", SetError::Syntax),
        (
            "p_goal",
            "1.5",
            SetError::Rule(param("p_goal").unwrap().error()),
        ),
        ("n_max", "70000", SetError::TooLarge),
        (
            "n_max",
            "0",
            SetError::Rule(param("n_max").unwrap().error()),
        ),
        ("n_max", "-3", SetError::Syntax),
        (
            "t_exp",
            "0",
            SetError::Rule(param("t_exp").unwrap().error()),
        ),
        ("t_exp", "1.2345678", SetError::Syntax),
        ("t_exp", ".5", SetError::Syntax),
        ("t_exp", "5ms", SetError::Syntax),
        ("connect", "yes", SetError::Syntax),
        ("profile", "tuned", SetError::Unknown),
    ];
    for (name, text, want) in refused {
        assert_eq!(set(&mut c, name, text), Err(want), "{name} = {text}");
        assert_eq!(c, before, "{name} = {text}");
    }
    set(&mut c, "t_exp", " 2.5 ").unwrap();
    assert_eq!(c.budget.t_exp, Duration::from_micros(2500));
    assert_eq!(param("t_exp").unwrap().get(&c).to_string(), "2.5");
    assert_eq!(
        ConfigError {
            param: "t_exp",
            rule: crate::error::Rule::NonZero
        }
        .to_string(),
        "t_exp must be longer than zero"
    );
}
