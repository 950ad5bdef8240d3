//! Operation sequences against the planner (issue 7, fuzz target a): the interpreter is
//! `tests/ops/mod.rs`, shared with the seeded test `tests/ops_sequences.rs`.
#![no_main]

#[path = "../../tests/ops/mod.rs"]
mod ops;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(e) = ops::run(data) {
        panic!("{e}");
    }
});
