//! Random operation sequences (the fuzz target's interpreter, `tests/ops/mod.rs`) from a
//! seeded generator: tree invariants after every operation, the waypoint rule after every
//! `plan`, bounded work, and no panic. The fuzz target explores the same space without end.

mod ops;

use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

#[test]
fn random_operation_sequences_keep_every_promise() {
    let mut rng = XorShiftRng::seed_from_u64(2026);
    for case in 0..4000 {
        let len = 16 + rng.next_u32() as usize % 240;
        let data: Vec<u8> = (0..len).map(|_| rng.next_u32() as u8).collect();
        if let Err(e) = ops::run(&data) {
            panic!("case {case}: {e}\ninput: {data:?}");
        }
    }
}
