//! Promise 5: same seed, same clock, same result. On the host here; across targets the twin
//! line (`examples/twin.rs`) is compared bit for bit with the Cortex-M4F firmware, the
//! Cortex-M0+ and the RISC-V builds by `.ci/run` (`firmware/`).

mod common;

use bi_am_rrt::Named;
use bi_am_rrt::builtin::{self};
use common::Protocol;
use common::e2e::run;

#[test]
fn same_seed_same_run() {
    // A faster agent (fewer calls per run); every call is still a full t_exp of planning.
    let proto = Protocol {
        speed: 2.0,
        ..Protocol::default()
    };
    for cfg in [
        Named::from_name("Bi-AM-RRT*(D)").unwrap(),
        Named::from_name("RT-RRT*").unwrap(),
    ] {
        let a = run(cfg, &builtin::MAZE, 3, proto);
        let b = run(cfg, &builtin::MAZE, 3, proto);
        assert_eq!(a, b, "{}", cfg.name());
        let c = run(cfg, &builtin::MAZE, 4, proto);
        assert_ne!(a, c, "another seed gives another run");
    }
}
