//! The configuration's own tests: names, lengths, validation.

use super::*;

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
    for (c, n) in Config::table1().iter().zip(names) {
        assert!(c.name() == n, "{n}");
        assert_eq!(Config::from_name(n), Some(*c));
    }
    assert_eq!(
        Config::from_name("Bi-AM-RRT*(D)"),
        Some(Config::bi_am_rrt(MetricKind::Diffusion))
    );
    assert!(Config::from_name("Bi-AM-RRT*").is_none());
    let tuned = Config::from_name("Bi-AM-RRT*(D) tuned").unwrap();
    assert_eq!(tuned, Config::bi_am_rrt(MetricKind::Diffusion).tuned());
    assert_eq!(tuned.tactics, Tactics::TUNED);
    assert_eq!(tuned.validate(), Ok(()));
    assert!(Config::from_name("AM-RRT*(D)-12").is_none());
}

#[test]
fn lengths_follow_the_map_and_keep_table_2_on_the_papers() {
    for c in Config::table1()
        .into_iter()
        .chain(Config::table1().map(Config::tuned))
    {
        // The paper's maps: 100 m and 200 m at 1 m cells, bit for bit.
        for side in [100.0, 150.0, 200.0] {
            assert_eq!(c.for_map(side, side, 1.0), c, "{}", c.name());
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
    for c in Config::table1() {
        assert_eq!(c.validate(), Ok(()));
    }
    let base = Config::bi_am_rrt(MetricKind::Diffusion);
    type Case = (fn(&mut Config), ConfigError);
    let cases: [Case; 14] = [
        (|c| c.search.e_max = f32::NAN, ConfigError::EMax),
        (|c| c.search.e_max = -1.0, ConfigError::EMax),
        (|c| c.search.e_max = f32::INFINITY, ConfigError::EMax),
        (|c| c.search.sigma = f32::NAN, ConfigError::Sigma),
        (|c| c.search.sigma = -3.0, ConfigError::Sigma),
        (|c| c.budget.t_exp = Duration::ZERO, ConfigError::TExp),
        (|c| c.search.p_goal = 1.5, ConfigError::PGoal),
        (|c| c.search.p_beacon = f32::NAN, ConfigError::PBeacon),
        (|c| c.search.p_gap = -0.1, ConfigError::PGap),
        (|c| c.search.p_uniform = f32::NAN, ConfigError::PUniform),
        (|c| c.memory.n_max = 0, ConfigError::NMax),
        (
            |c| c.search.sample_attempts = 0,
            ConfigError::SampleAttempts,
        ),
        (|c| c.budget.max_expansions = 0, ConfigError::MaxExpansions),
        (|c| c.budget.max_work = 0, ConfigError::MaxWork),
    ];
    for (set, want) in cases {
        let mut c = base;
        set(&mut c);
        assert_eq!(c.validate(), Err(want));
    }
}
