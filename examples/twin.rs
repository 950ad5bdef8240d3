//! The host twin of the firmware example: the same mission (`examples/shared/mission.rs`) on
//! the host. Its output line must equal the firmware's under QEMU, bit for bit (CI checks).
//!
//! ```sh
//! cargo run --release --example twin
//! ```

#[path = "shared/mission.rs"]
mod mission;

fn main() {
    let mut storage: Box<mission::MissionStorage> = Box::default();
    match mission::fly(&mut storage) {
        Ok(m) => {
            println!("{m}");
            std::process::exit(if m.ok() { 0 } else { 1 });
        }
        Err(e) => {
            eprintln!("mission: {e}");
            std::process::exit(1);
        }
    }
}
