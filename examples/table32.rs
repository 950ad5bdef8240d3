//! The diffusion-table reader on a 32-bit target (issue 7, case 5): on a Cortex-M4F `usize` is
//! 32 bits, and a 32-byte table whose header claims 8192 x 8192 cells of 32 `f32` (8 GiB) was
//! once accepted with a payload length of 0 (release) or panicked (overflow checks). Built
//! with overflow checks on (the dev profile, or release with them turned on for the crate, as
//! CI does) and run under QEMU, this checks that such headers are refused as truncated and that
//! a real table still reads back; QEMU exits with status 0 when every check holds.
//!
//! ```sh
//! cargo run --example table32 --target thumbv7em-none-eabihf --features firmware-example
//! cargo run --release --example table32 --target thumbv7em-none-eabihf --features firmware-example \
//!   --config 'profile.release.package.bi-am-rrt.overflow-checks=true'
//! ```
#![no_std]
#![no_main]

use bi_am_rrt::Point;
use bi_am_rrt::metric::{
    DiffusionTable, ElementKind, Metric, TableError, TableHeader, fnv1a32, write_table,
};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;

fn checks() -> Result<u32, &'static str> {
    if usize::BITS != 32 {
        return Err("not a 32-bit target");
    }
    let mut passed = 0;
    for (dims, cols, rows, kind) in [
        (32u16, 8192u16, 8192u16, ElementKind::F32),
        (32, u16::MAX, u16::MAX, ElementKind::F32),
        (32, u16::MAX, u16::MAX, ElementKind::I16),
        (2, u16::MAX, u16::MAX, ElementKind::I16),
    ] {
        let h = TableHeader {
            map_hash: None,
            kind,
            dims,
            cols,
            rows,
            cell_size: 1.0,
            scale: 1.0,
            layout: bi_am_rrt::metric::Layout::Uniform,
        };
        let bytes = h.to_bytes(fnv1a32(&[]));
        if DiffusionTable::new(&bytes).err() != Some(TableError::Truncated) {
            return Err("a bogus header was accepted");
        }
        passed += 1;
    }
    // An 8 GiB payload does not fit a 32-bit usize.
    let huge = TableHeader {
        map_hash: None,
        kind: ElementKind::F32,
        dims: 32,
        cols: 8192,
        rows: 8192,
        cell_size: 1.0,
        scale: 1.0,
        layout: bi_am_rrt::metric::Layout::Uniform,
    };
    if huge.payload_len().is_some() || huge.table_len().is_some() {
        return Err("an 8 GiB payload length fit a 32-bit usize");
    }
    passed += 1;
    // A real table reads back.
    let h = TableHeader {
        map_hash: None,
        kind: ElementKind::I16,
        dims: 2,
        cols: 4,
        rows: 3,
        cell_size: 1.0,
        scale: 0.5,
        layout: bi_am_rrt::metric::Layout::Uniform,
    };
    let mut buf = [0u8; 32 + 4 * 3 * 2 * 2];
    let n = write_table(&h, &mut buf, |c, r, out| {
        out[0] = c as f32;
        out[1] = r as f32;
        true
    })
    .ok_or("write_table refused a small table")?;
    let t = DiffusionTable::new(&buf[..n]).map_err(|_| "a valid table was refused")?;
    let d = t.distance(Point::new(0.5, 0.5), Point::new(3.5, 2.5));
    if (d - libm::sqrtf(13.0)).abs() > 1e-5 {
        return Err("wrong distance");
    }
    Ok(passed + 1)
}

#[entry]
fn main() -> ! {
    let ok = match checks() {
        Ok(n) => {
            hprintln!("table32: {} checks passed on a 32-bit target", n);
            true
        }
        Err(e) => {
            hprintln!("table32: FAILED: {}", e);
            false
        }
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}
