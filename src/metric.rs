//! Assisting metrics `d_A` (paper, section 3.1, equations 1-2): the distance that guides the
//! tree towards the goal, while tree costs stay Euclidean.
//!
//! - [`Euclidean`]: `d_E`, straight-line distance.
//! - [`DiffusionTable`]: `d_D`, the Euclidean distance between the diffusion coordinates of the
//!   two positions' grid cells, read from a borrowed, validated byte table (which can sit in
//!   flash). The host simulator bakes the tables (`host-sim bake`).
//! - The geodesic metric `d_G` (graph shortest paths) implements the same trait in `host-sim`,
//!   and any user type can too.
//!
//! A metric returns `f32::INFINITY` for a position it cannot place (an obstacle, outside the
//! map, a region cut off from the main free component).
//!
//! # Table format (version 1)
//!
//! Little-endian throughout. A 32-byte header, then the payload:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `b"BIAMDIFF"` |
//! | 8 | 2 | format version (1) |
//! | 10 | 2 | element kind: 1 = `i16` quantised, 2 = `f32` |
//! | 12 | 2 | dimensions `k` (1..=32) |
//! | 14 | 2 | table columns |
//! | 16 | 2 | table rows |
//! | 18 | 2 | reserved, 0 |
//! | 20 | 4 | cell size in metres (`f32`, finite, positive) |
//! | 24 | 4 | scale (`f32`): coordinate = element * scale |
//! | 28 | 4 | FNV-1a 32-bit hash of the payload |
//!
//! The payload holds `cols * rows * k` elements, cell-major in row-major cell order (cell
//! `(col, row)` starts at element `(row * cols + col) * k`). A cell whose first element is
//! `i16::MIN` (kind 1) or NaN (kind 2) is unreachable.

use crate::geometry::Point;
use crate::slots::{cell_index, sat_u32, to_u16};

/// The assisting metric of the planner (the paper's `d_A`).
pub trait Metric {
    /// Distance between two positions; `f32::INFINITY` when either cannot be placed.
    fn distance(&self, a: Point, b: Point) -> f32;

    /// Whether this is the Euclidean metric. The planner then never falls back from the
    /// Euclidean nearest neighbour and steers straight (paper Algorithm 2 with `d_A = d_E`).
    fn is_euclidean(&self) -> bool {
        false
    }

    /// Work done by `distance` calls since the last `take_work`, in the planner's work units
    /// (one unit: about one grid cell or graph edge visited), beyond the flat 2 units the
    /// planner charges per call. A metric whose cost varies (one computing a distance field
    /// on a cache miss) reports it here so that a virtual clock stays faithful. Default: 0.
    fn take_work(&self) -> u32 {
        0
    }
}

impl<M: Metric + ?Sized> Metric for &M {
    fn distance(&self, a: Point, b: Point) -> f32 {
        (**self).distance(a, b)
    }
    fn is_euclidean(&self) -> bool {
        (**self).is_euclidean()
    }
    fn take_work(&self) -> u32 {
        (**self).take_work()
    }
}

/// The Euclidean metric `d_E`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Euclidean;

impl Metric for Euclidean {
    #[inline]
    fn distance(&self, a: Point, b: Point) -> f32 {
        a.dist(b)
    }
    fn is_euclidean(&self) -> bool {
        true
    }
}

/// Why a diffusion table was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TableError {
    /// Fewer bytes than the header, or than the payload the header announces.
    Truncated,
    /// The magic bytes are wrong: not a table.
    BadMagic,
    /// A format version this build cannot read.
    UnsupportedVersion,
    /// A header field is out of range (element kind, dimensions, sizes, cell size, scale).
    BadHeader,
    /// The payload does not match its checksum.
    BadChecksum,
}

impl core::fmt::Display for TableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Truncated => "table truncated",
            Self::BadMagic => "not a diffusion table (bad magic)",
            Self::UnsupportedVersion => "unsupported table version",
            Self::BadHeader => "table header out of range",
            Self::BadChecksum => "table checksum mismatch",
        })
    }
}

impl core::error::Error for TableError {}

/// Magic bytes at the start of a diffusion table.
pub const TABLE_MAGIC: [u8; 8] = *b"BIAMDIFF";
/// The table format version this build reads and writes.
pub const TABLE_VERSION: u16 = 1;
/// Header size in bytes.
pub const TABLE_HEADER_LEN: usize = 32;
/// Most dimensions a table may have.
pub const TABLE_MAX_DIMS: usize = 32;

/// Element encoding of a table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ElementKind {
    /// `i16` times the scale; `i16::MIN` marks an unreachable cell.
    I16,
    /// `f32` (the scale multiplies it too); NaN marks an unreachable cell.
    F32,
}

impl ElementKind {
    /// Bytes per element.
    pub const fn size(self) -> usize {
        match self {
            Self::I16 => 2,
            Self::F32 => 4,
        }
    }

    const fn code(self) -> u16 {
        match self {
            Self::I16 => 1,
            Self::F32 => 2,
        }
    }
}

/// FNV-1a, 32 bits: the table checksum.
pub fn fnv1a32(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0x811c_9dc5u32, |h, &b| {
        (h ^ b as u32).wrapping_mul(0x0100_0193)
    })
}

/// The header fields of a table.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableHeader {
    /// Element encoding.
    pub kind: ElementKind,
    /// Coordinates per cell.
    pub dims: u16,
    /// Table columns.
    pub cols: u16,
    /// Table rows.
    pub rows: u16,
    /// Side of a table cell in metres.
    pub cell_size: f32,
    /// Multiplier from stored element to coordinate.
    pub scale: f32,
}

impl TableHeader {
    /// Payload size in bytes; `None` when it does not fit the target's `usize` (a header
    /// claiming 8192 x 8192 cells of 32 `f32` is 8 GiB: more than a 32-bit address space).
    pub fn payload_len(&self) -> Option<usize> {
        let len = (self.cols as u64)
            .checked_mul(self.rows as u64)?
            .checked_mul(self.dims as u64)?
            .checked_mul(self.kind.size() as u64)?;
        usize::try_from(len).ok()
    }

    /// Payload plus header, in bytes: the table's whole size.
    pub fn table_len(&self) -> Option<usize> {
        self.payload_len()?.checked_add(TABLE_HEADER_LEN)
    }

    /// The 32 header bytes for a payload with this checksum.
    pub fn to_bytes(&self, checksum: u32) -> [u8; TABLE_HEADER_LEN] {
        let mut h = [0u8; TABLE_HEADER_LEN];
        let fields: [(usize, &[u8]); 9] = [
            (0, &TABLE_MAGIC),
            (8, &TABLE_VERSION.to_le_bytes()),
            (10, &self.kind.code().to_le_bytes()),
            (12, &self.dims.to_le_bytes()),
            (14, &self.cols.to_le_bytes()),
            (16, &self.rows.to_le_bytes()),
            (20, &self.cell_size.to_le_bytes()),
            (24, &self.scale.to_le_bytes()),
            (28, &checksum.to_le_bytes()),
        ];
        for (at, bytes) in fields {
            if let Some(dst) = h.get_mut(at..at.saturating_add(bytes.len())) {
                copy_bytes(dst, bytes);
            }
        }
        h
    }
}

/// Copies `src` into `dst` (lengths equal by construction; `copy_from_slice` would carry a
/// panicking length check).
fn copy_bytes(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

fn le_u16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(
        b.get(at..at.checked_add(2)?)?.try_into().ok()?,
    ))
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

/// The diffusion metric `d_D` over a borrowed, validated table (format in the module docs).
#[derive(Clone, Copy, Debug)]
pub struct DiffusionTable<'a> {
    header: TableHeader,
    payload: &'a [u8],
    inv_cell: f32,
}

impl<'a> DiffusionTable<'a> {
    /// Validates `bytes` (header, sizes, checksum) and borrows them. Never panics and never
    /// reads out of bounds, whatever the bytes.
    pub fn new(bytes: &'a [u8]) -> Result<Self, TableError> {
        let Some(head) = bytes.get(..TABLE_HEADER_LEN) else {
            return Err(TableError::Truncated);
        };
        if head.get(..8) != Some(&TABLE_MAGIC[..]) {
            return Err(TableError::BadMagic);
        }
        let field = |at| le_u16(head, at).ok_or(TableError::Truncated);
        if field(8)? != TABLE_VERSION {
            return Err(TableError::UnsupportedVersion);
        }
        let kind = match field(10)? {
            1 => ElementKind::I16,
            2 => ElementKind::F32,
            _ => return Err(TableError::BadHeader),
        };
        let (dims, cols, rows) = (field(12)?, field(14)?, field(16)?);
        let f32_at = |at| {
            le_u32(head, at)
                .map(f32::from_bits)
                .ok_or(TableError::Truncated)
        };
        let (cell_size, scale) = (f32_at(20)?, f32_at(24)?);
        let checksum = le_u32(head, 28).ok_or(TableError::Truncated)?;
        if dims == 0
            || dims as usize > TABLE_MAX_DIMS
            || cols == 0
            || rows == 0
            || !(cell_size.is_finite() && cell_size > 0.0)
            || !(scale.is_finite() && scale > 0.0)
        {
            return Err(TableError::BadHeader);
        }
        let header = TableHeader {
            kind,
            dims,
            cols,
            rows,
            cell_size,
            scale,
        };
        // A payload larger than the address space cannot be present: truncated.
        let end = header.table_len().ok_or(TableError::Truncated)?;
        let payload = bytes
            .get(TABLE_HEADER_LEN..end)
            .ok_or(TableError::Truncated)?;
        if fnv1a32(payload) != checksum {
            return Err(TableError::BadChecksum);
        }
        Ok(Self {
            header,
            payload,
            inv_cell: 1.0 / cell_size,
        })
    }

    /// The validated header.
    pub fn header(&self) -> &TableHeader {
        &self.header
    }

    /// The table cell of a position, `None` outside the table.
    fn cell(&self, p: Point) -> Option<usize> {
        let (x, y) = (p.x * self.inv_cell, p.y * self.inv_cell);
        // NaN fails both comparisons.
        if !(x >= 0.0 && y >= 0.0) {
            return None;
        }
        let (c, r) = (sat_u32(x), sat_u32(y));
        let (cols, rows) = (self.header.cols as u32, self.header.rows as u32);
        // A point on the far edge of the map belongs to the last cell.
        let c = if c == cols && x == cols as f32 {
            c.saturating_sub(1)
        } else {
            c
        };
        let r = if r == rows && y == rows as f32 {
            r.saturating_sub(1)
        } else {
            r
        };
        (c < cols && r < rows).then(|| cell_index(to_u16(c), to_u16(r), to_u16(cols)))
    }

    /// Reads coordinate `d` of `cell` as stored (before scaling); `None` if unreachable.
    #[inline]
    fn element(&self, cell: usize, d: usize) -> Option<f32> {
        // Checked: on a 32-bit target a bogus cell could overflow the offset (a validated
        // table never does, since the whole payload fits the address space).
        let k = self.header.dims as usize;
        let size = self.header.kind.size();
        let at = cell.checked_mul(k)?.checked_add(d)?.checked_mul(size)?;
        let bytes = self.payload.get(at..at.checked_add(size)?)?;
        match self.header.kind {
            ElementKind::I16 => {
                let v = i16::from_le_bytes(bytes.try_into().ok()?);
                (v != i16::MIN).then_some(v as f32)
            }
            ElementKind::F32 => {
                let v = f32::from_le_bytes(bytes.try_into().ok()?);
                (!v.is_nan()).then_some(v)
            }
        }
    }

    /// The scaled diffusion coordinates of the cell containing `p` written into `out` (its
    /// first `dims` entries); `false` when `p` has none.
    pub fn coordinates(&self, p: Point, out: &mut [f32]) -> bool {
        let Some(cell) = self.cell(p) else {
            return false;
        };
        if self.element(cell, 0).is_none() {
            return false;
        }
        for (d, slot) in out.iter_mut().take(self.header.dims as usize).enumerate() {
            match self.element(cell, d) {
                Some(v) => *slot = v * self.header.scale,
                None => return false,
            }
        }
        true
    }

    /// Whether `p` has diffusion coordinates (lies on the main free component).
    pub fn covers(&self, p: Point) -> bool {
        self.cell(p).is_some_and(|c| self.element(c, 0).is_some())
    }
}

impl Metric for DiffusionTable<'_> {
    fn distance(&self, a: Point, b: Point) -> f32 {
        let (Some(ca), Some(cb)) = (self.cell(a), self.cell(b)) else {
            return f32::INFINITY;
        };
        if self.element(ca, 0).is_none() || self.element(cb, 0).is_none() {
            return f32::INFINITY;
        }
        if ca == cb {
            return 0.0;
        }
        let mut sum = 0.0f32;
        for d in 0..self.header.dims as usize {
            let (Some(x), Some(y)) = (self.element(ca, d), self.element(cb, d)) else {
                return f32::INFINITY;
            };
            sum += (x - y) * (x - y);
        }
        libm::sqrtf(sum) * self.header.scale
    }
}

/// The `i16` element of a coordinate: rounded and clamped to `-32767..=32767` (NaN gives 0).
#[allow(clippy::cast_possible_truncation)] // clamped into i16 range first; the cast saturates
fn quantise(v: f32) -> i16 {
    libm::roundf(v).clamp(-32767.0, 32767.0) as i16
}

/// Writes a table (header and payload) into `out` from per-cell coordinates given by
/// `coords(col, row, &mut [f32]) -> bool` (false: unreachable). Returns the bytes written, or
/// `None` when `out` is too small or the header is invalid. For `ElementKind::I16` each
/// coordinate is stored as `round(value / scale)`, clamped to `-32767..=32767`.
pub fn write_table<F>(header: &TableHeader, out: &mut [u8], mut coords: F) -> Option<usize>
where
    F: FnMut(u16, u16, &mut [f32]) -> bool,
{
    let k = header.dims as usize;
    if k == 0 || k > TABLE_MAX_DIMS || !(header.scale.is_finite() && header.scale > 0.0) {
        return None;
    }
    let total = header.table_len()?;
    let out = out.get_mut(..total)?;
    let (head, payload) = out.split_at_mut_checked(TABLE_HEADER_LEN)?;
    let mut buf = [0f32; TABLE_MAX_DIMS];
    let size = header.kind.size();
    let mut at: usize = 0;
    for row in 0..header.rows {
        for col in 0..header.cols {
            let coords_of_cell = buf.get_mut(..k)?;
            let reachable = coords(col, row, coords_of_cell);
            for &v in coords_of_cell.iter() {
                let dst = payload.get_mut(at..at.checked_add(size)?)?;
                match header.kind {
                    ElementKind::I16 => {
                        let q = if reachable {
                            quantise(v / header.scale)
                        } else {
                            i16::MIN
                        };
                        copy_bytes(dst, &q.to_le_bytes());
                    }
                    ElementKind::F32 => {
                        let q = if reachable {
                            v / header.scale
                        } else {
                            f32::NAN
                        };
                        copy_bytes(dst, &q.to_le_bytes());
                    }
                }
                at = at.checked_add(size)?;
            }
        }
    }
    let sum = fnv1a32(payload);
    copy_bytes(head, &header.to_bytes(sum));
    Some(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(kind: ElementKind) -> TableHeader {
        TableHeader {
            kind,
            dims: 2,
            cols: 3,
            rows: 2,
            cell_size: 1.0,
            scale: 0.5,
        }
    }

    /// Coordinates (col, row) except cell (2, 1), which is unreachable.
    fn coords(col: u16, row: u16, out: &mut [f32]) -> bool {
        out[0] = col as f32;
        out[1] = row as f32 * 2.0;
        !(col == 2 && row == 1)
    }

    #[test]
    fn round_trip_and_distances() {
        for kind in [ElementKind::I16, ElementKind::F32] {
            let mut buf = [0u8; 128];
            let n = write_table(&header(kind), &mut buf, coords).unwrap();
            let t = DiffusionTable::new(&buf[..n]).unwrap();
            let d = t.distance(Point::new(0.5, 0.5), Point::new(1.5, 1.5));
            assert!((d - libm::sqrtf(1.0 + 4.0)).abs() < 1e-6, "{kind:?}: {d}");
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
        }
    }

    /// Issue 7, case 5: on a 32-bit target `payload_len` overflowed `usize`, and a 32-byte table
    /// whose header claims 8192 x 8192 cells of 32 `f32` was accepted (payload length 0). The
    /// same check runs on the Cortex-M4F under QEMU (`examples/table32.rs`).
    #[test]
    fn regression_table_size_overflow_is_refused() {
        let claims = TableHeader {
            kind: ElementKind::F32,
            dims: 32,
            cols: 8192,
            rows: 8192,
            cell_size: 1.0,
            scale: 1.0,
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
}
