//! cortex-m-rt's `link.x` includes `memory.x`: use the project's (STM32F405).
fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    println!("cargo:rustc-link-search={}", root.display());
    println!("cargo:rerun-if-changed=../../memory.x");
}
