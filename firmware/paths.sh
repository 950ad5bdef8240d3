# Sourced by .ci/run and the firmware scripts before any embedded build.
#
# A panic message keeps the path of the source file it comes from, and the sources of
# registry crates live under cargo's home, which differs between machines (/root/.cargo here,
# another home on a CI runner). The firmware's size would then depend on the machine that
# built it by a few bytes, and the documented flash figures could not be compared. Every
# embedded build names cargo's home `/cargo` instead. (Cargo appends these flags to the
# targets' `rustflags` in .cargo/config.toml; it does not replace them.)
cargo_home="${CARGO_HOME:-$HOME/.cargo}"
for target in THUMBV7EM_NONE_EABIHF THUMBV6M_NONE_EABI RISCV32IMAC_UNKNOWN_NONE_ELF; do
  export "CARGO_TARGET_${target}_RUSTFLAGS=--remap-path-prefix=${cargo_home}=/cargo"
done
unset cargo_home target
