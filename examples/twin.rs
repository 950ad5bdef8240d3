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

/// The firmware prints this `Display` when the mission cannot fly: it must carry the
/// library's own reason, not a bare "refused" (issue 44).
#[cfg(test)]
mod tests {
    use super::mission::Refused;
    use bi_am_rrt::error::{InputError, SetupError, TableError};

    #[test]
    fn a_refusal_names_the_librarys_reason() {
        let cases = [
            Refused::Setup(SetupError::Metric(TableError::WrongMap)),
            Refused::Setup(SetupError::Start(InputError::OutOfBounds)),
            Refused::Goal(InputError::InObstacle),
        ];
        for r in cases {
            let (text, reason) = match r {
                Refused::Setup(e) => (r.to_string(), e.to_string()),
                Refused::Goal(e) => (r.to_string(), e.to_string()),
            };
            assert!(!reason.is_empty() && text.ends_with(&reason), "{text}");
        }
    }
}
