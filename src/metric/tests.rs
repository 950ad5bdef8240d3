//! The metric's unit tests: the trait, the reader and the format together.

use super::table::stored_sq;
use super::*;

fn header(kind: ElementKind) -> TableHeader {
    TableHeader {
        map_hash: None,
        kind,
        dims: 2,
        cols: 3,
        rows: 2,
        cell_size: 1.0,
        scale: 0.5,
        layout: Layout::Uniform,
    }
}

/// Coordinates (col, row) except cell (2, 1), which is unreachable.
fn coords(col: u16, row: u16, out: &mut [f32]) -> bool {
    out[0] = col as f32;
    out[1] = row as f32 * 2.0;
    !(col == 2 && row == 1)
}

#[test]
fn piece_tables_keep_cells_on_their_side_of_a_wall() {
    // 4 x 2 cells, 2 x 2 blocks. Block 0: column 0 is piece 1, column 1 piece 2 (a wall
    // between them). Block 1: one piece, cell (2, 1) an obstacle.
    let piece = |c: u16, r: u16| match (c, r) {
        (0, _) => 1,
        (1, _) => 2,
        (2, 1) => 0,
        _ => 1,
    };
    let coords = |e: u32, out: &mut [f32]| {
        out[0] = e as f32 * 10.0;
        out[1] = 0.0;
        true
    };
    for kind in [ElementKind::I16, ElementKind::F32] {
        let h = TableHeader {
            map_hash: None,
            kind,
            dims: 2,
            cols: 4,
            rows: 2,
            cell_size: 1.0,
            scale: 0.5,
            layout: Layout::Pieces {
                block: 2,
                entries: 3,
            },
        };
        let mut buf = [0u8; 128];
        let n = write_piece_table(&h, &mut buf, piece, coords).unwrap();
        assert_eq!(n, 32 + 4 + 2 * 2 + 4 + 3 * 2 * kind.size());
        let t = DiffusionTable::new(&buf[..n]).unwrap();
        assert_eq!(t.header(), &h);
        let d =
            |a: (f32, f32), b: (f32, f32)| t.distance(Point::new(a.0, a.1), Point::new(b.0, b.1));
        assert_eq!(d((0.5, 0.5), (0.5, 1.5)), 0.0, "same piece");
        assert_eq!(d((0.5, 0.5), (1.5, 0.5)), 10.0, "across the wall");
        assert_eq!(d((0.5, 0.5), (3.5, 1.5)), 20.0);
        assert!(d((0.5, 0.5), (2.5, 1.5)).is_infinite(), "obstacle cell");
        assert!(!t.covers(Point::new(2.5, 1.5)) && t.covers(Point::new(2.5, 0.5)));
        // Disagreements are refused: a wrong entry count, a piece above 15.
        let wrong = TableHeader {
            map_hash: None,
            layout: Layout::Pieces {
                block: 2,
                entries: 4,
            },
            ..h
        };
        assert!(write_piece_table(&wrong, &mut buf, piece, coords).is_none());
        assert!(write_piece_table(&h, &mut buf, |_, _| 16, coords).is_none());
        // Any byte flipped is caught by the checksum; a bad block side by the header check.
        let mut bad = buf;
        bad[40] ^= 1;
        assert_eq!(
            DiffusionTable::new(&bad[..n]).unwrap_err(),
            TableError::BadChecksum
        );
        // Only the checksum is skipped without verification.
        assert!(DiffusionTable::new_unverified(&bad[..n]).is_ok());
        let mut bad = buf;
        bad[18] = 0;
        assert_eq!(
            DiffusionTable::new_unverified(&bad[..n]).unwrap_err(),
            TableError::BadHeader
        );
        assert_eq!(
            DiffusionTable::new(&bad[..n]).unwrap_err(),
            TableError::BadHeader
        );
    }
}

#[test]
fn the_block_division_by_multiplication_is_exact() {
    // Every grid index (below 2^16) by every block side the format allows.
    for b in 1..=u32::from(PIECES_MAX_BLOCK) {
        let parts = PieceParts {
            block: b,
            inv_block: PieceParts::reciprocal(b),
            block_cols: 1,
            firsts_at: 0,
            nibbles_at: 0,
            coords_at: 0,
        };
        for v in 0..=u32::from(u16::MAX) {
            assert_eq!(parts.div_block(v), v / b, "{v} / {b}");
        }
    }
}

#[test]
fn extreme_i16_coordinates_give_the_exact_squared_sum() {
    // The largest differences the format can hold, in all 32 dimensions: each square is
    // just below 2^32 and the u64 sum must not wrap.
    let a = [32767i16; 32].map(i16::to_le_bytes).concat();
    let b = [-32767i16; 32].map(i16::to_le_bytes).concat();
    let exact = 32.0 * 65534.0f64 * 65534.0;
    assert_eq!(stored_sq(ElementKind::I16, &a, &b), Some(exact as f32));
    let mut c = b.clone();
    c[..2].copy_from_slice(&i16::MIN.to_le_bytes());
    assert_eq!(stored_sq(ElementKind::I16, &a, &c), None);
}

#[test]
fn round_trip_and_distances() {
    for kind in [ElementKind::I16, ElementKind::F32] {
        let mut buf = [0u8; 128];
        let n = write_table(&header(kind), &mut buf, coords).unwrap();
        let t = DiffusionTable::new(&buf[..n]).unwrap();
        let d = t.distance(Point::new(0.5, 0.5), Point::new(1.5, 1.5));
        assert!(
            (d - crate::geometry::sqrt(1.0 + 4.0)).abs() < 1e-6,
            "{kind:?}: {d}"
        );
        assert_eq!(
            t.distance(Point::new(0.5, 0.5), Point::new(2.5, 1.5)),
            f32::INFINITY
        );
        assert_eq!(
            t.distance(Point::new(0.5, 0.5), Point::new(-1.0, 0.5)),
            f32::INFINITY
        );
        // A point on the far edge belongs to the last column.
        assert_eq!(t.distance(Point::new(3.0, 0.2), Point::new(0.5, 0.5)), 2.0);
        assert_eq!(
            t.distance(Point::new(3.0, 2.0), Point::new(0.5, 0.5)),
            f32::INFINITY
        );
        assert!(!t.covers(Point::new(2.5, 1.5)));
        // The entry-wise distance equals the element-by-element formula bit for bit.
        let by_elements = |a: Point, b: Point| {
            let (Some(ca), Some(cb)) = (t.cell(a), t.cell(b)) else {
                return f32::INFINITY;
            };
            if t.element(ca, 0).is_none() || t.element(cb, 0).is_none() {
                return f32::INFINITY;
            }
            if ca == cb {
                return 0.0;
            }
            // `i16`: the exact sum (f64 holds it exactly), rounded once; `f32`: in order.
            let (mut exact, mut sum) = (0.0f64, 0.0f32);
            for d in 0..t.header.dims as usize {
                let (Some(x), Some(y)) = (t.element(ca, d), t.element(cb, d)) else {
                    return f32::INFINITY;
                };
                exact += (f64::from(x) - f64::from(y)).powi(2);
                sum += (x - y) * (x - y);
            }
            if t.header.kind == ElementKind::I16 {
                sum = exact as f32;
            }
            crate::geometry::sqrt(sum) * t.header.scale
        };
        for i in 0..64 {
            for j in 0..64 {
                let a = Point::new((i % 8) as f32 * 0.45, (i / 8) as f32 * 0.3);
                let b = Point::new((j % 8) as f32 * 0.45, (j / 8) as f32 * 0.3);
                assert_eq!(
                    t.distance(a, b).to_bits(),
                    by_elements(a, b).to_bits(),
                    "{a:?} {b:?}"
                );
                // A prepared end gives the same value (placed, unplaced and outside).
                assert_eq!(
                    t.distance_to(a, &t.prepare(b)).to_bits(),
                    t.distance(a, b).to_bits(),
                    "prepared {a:?} {b:?}"
                );
                assert_eq!(Euclidean.distance_to(a, &Euclidean.prepare(b)), a.dist(b));
            }
        }
    }
}

/// Issue 7, case 5: on a 32-bit target `payload_len` overflowed `usize`, and a 32-byte table
/// whose header claims 8192 x 8192 cells of 32 `f32` was accepted (payload length 0). The
/// same check runs on the Cortex-M4F under QEMU (`examples/table32.rs`).
#[test]
fn regression_table_size_overflow_is_refused() {
    let claims = TableHeader {
        map_hash: None,
        kind: ElementKind::F32,
        dims: 32,
        cols: 8192,
        rows: 8192,
        cell_size: 1.0,
        scale: 1.0,
        layout: Layout::Uniform,
    };
    let bogus = claims.to_bytes(fnv1a32(&[]));
    assert_eq!(
        DiffusionTable::new(&bogus).unwrap_err(),
        TableError::Truncated
    );
    let expected = 8192u64 * 8192 * 32 * 4;
    assert_eq!(
        claims.payload_len().map(|n| n as u64),
        usize::try_from(expected).ok().map(|n| n as u64)
    );
    let largest = TableHeader {
        map_hash: None,
        cols: u16::MAX,
        rows: u16::MAX,
        ..claims
    };
    assert_eq!(
        DiffusionTable::new(&largest.to_bytes(0)).unwrap_err(),
        TableError::Truncated
    );
    let mut out = [0u8; 64];
    assert!(write_table(&largest, &mut out, |_, _, _| true).is_none());
}

#[test]
fn bad_tables_are_refused() {
    let mut buf = [0u8; 128];
    let n = write_table(&header(ElementKind::I16), &mut buf, coords).unwrap();
    assert_eq!(
        DiffusionTable::new(&buf[..n - 1]).unwrap_err(),
        TableError::Truncated
    );
    assert_eq!(
        DiffusionTable::new(&buf[..10]).unwrap_err(),
        TableError::Truncated
    );
    let mut bad = buf;
    bad[TABLE_HEADER_LEN + 3] ^= 1;
    assert_eq!(
        DiffusionTable::new(&bad[..n]).unwrap_err(),
        TableError::BadChecksum
    );
    let mut bad = buf;
    bad[0] = b'X';
    assert_eq!(
        DiffusionTable::new(&bad[..n]).unwrap_err(),
        TableError::BadMagic
    );
    let mut bad = buf;
    bad[8] = 9;
    assert_eq!(
        DiffusionTable::new(&bad[..n]).unwrap_err(),
        TableError::UnsupportedVersion
    );
    let mut bad = buf;
    bad[12] = 0;
    assert_eq!(
        DiffusionTable::new(&bad[..n]).unwrap_err(),
        TableError::BadHeader
    );
    // Every prefix and every single-byte corruption is refused or accepted without panic.
    for len in 0..n {
        assert!(DiffusionTable::new(&buf[..len]).is_err());
    }
    for i in 0..n {
        let mut b = buf;
        b[i] = b[i].wrapping_add(0x55);
        let _ = DiffusionTable::new(&b[..n]);
    }
}
