//! The diffusion metric `d_D` (paper, section 3.1, equation 2): a borrowed, validated table
//! read in place (it can sit in flash); its format is `format`'s.

use super::format::*;
use super::{Metric, Prepared};
use crate::error::TableError;
use crate::geometry::Point;
use crate::slots::{cell_index, sat_u32, to_u16};

/// The diffusion metric `d_D` over a borrowed, validated table (format at [`TableHeader`]).
#[derive(Clone, Copy, Debug)]
pub struct DiffusionTable<'a> {
    pub(super) header: TableHeader,
    payload: &'a [u8],
    /// The entries (all of the payload in version 1, all but the map's hash in version 4).
    coords: &'a [u8],
    parts: Option<PieceParts>,
    inv_cell: f32,
}

impl<'a> DiffusionTable<'a> {
    /// Validates `bytes` (header, sizes, checksum) and borrows them. Never panics and never
    /// reads out of bounds, whatever the bytes.
    pub fn new(bytes: &'a [u8]) -> Result<Self, TableError> {
        Self::parse(bytes, true)
    }

    /// [`DiffusionTable::new`] without the checksum pass (a hash of the whole payload, about
    /// 0.2 ms for 128 KiB on the development machine), for bytes that `new` has already
    /// accepted, such as a table borrowed again for every run of a benchmark. The header and
    /// sizes are still validated, so it never panics and never reads out of bounds, whatever
    /// the bytes; corrupted coordinates would only give wrong distances.
    pub fn new_unverified(bytes: &'a [u8]) -> Result<Self, TableError> {
        Self::parse(bytes, false)
    }

    fn parse(bytes: &'a [u8], verify: bool) -> Result<Self, TableError> {
        let Some(head) = bytes.get(..TABLE_HEADER_LEN) else {
            return Err(TableError::Truncated);
        };
        if head.get(..8) != Some(&TABLE_MAGIC[..]) {
            return Err(TableError::BadMagic);
        }
        let field = |at| le_u16(head, at).ok_or(TableError::Truncated);
        let version = field(8)?;
        if !(1..=4).contains(&version) {
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
        let block = field(18)?;
        let layout = if version == 1 || version == 4 {
            if block != 0 {
                return Err(TableError::BadHeader);
            }
            Layout::Uniform
        } else {
            if block == 0 || block > PIECES_MAX_BLOCK {
                return Err(TableError::BadHeader);
            }
            let at = if version == 3 { 4 } else { 0 };
            let entries = bytes
                .get(TABLE_HEADER_LEN..)
                .and_then(|p| le_u32(p, at))
                .ok_or(TableError::Truncated)?;
            if entries > PIECES_MAX_ENTRIES {
                return Err(TableError::BadHeader);
            }
            Layout::Pieces { block, entries }
        };
        let map_hash = if version >= 3 {
            let hash = bytes.get(TABLE_HEADER_LEN..).and_then(|p| le_u32(p, 0));
            Some(hash.ok_or(TableError::Truncated)?)
        } else {
            None
        };
        let header = TableHeader {
            kind,
            dims,
            cols,
            rows,
            cell_size,
            scale,
            layout,
            map_hash,
        };
        // A payload larger than the address space cannot be present: truncated.
        let end = header.table_len().ok_or(TableError::Truncated)?;
        let payload = bytes
            .get(TABLE_HEADER_LEN..end)
            .ok_or(TableError::Truncated)?;
        if verify && fnv1a32(payload) != checksum {
            return Err(TableError::BadChecksum);
        }
        let parts = header.pieces();
        let coords = payload
            .get(parts.map_or(header.uniform_coords_at(), |p| p.coords_at)..)
            .ok_or(TableError::Truncated)?;
        Ok(Self {
            header,
            payload,
            coords,
            parts,
            inv_cell: 1.0 / cell_size,
        })
    }

    /// Whether this table was baked from `grid`: the same cell size and extent (in table
    /// cells for a uniform table) and, for a version-3 or -4 table, the same grid bytes (their
    /// FNV-1a hash: one pass over the packed grid). `Planner::new` checks it through
    /// [`Metric::check_map`].
    pub fn check_map(&self, grid: &crate::map::OccupancyGrid<'_>) -> Result<(), TableError> {
        let h = &self.header;
        let (cols, rows) = match h.layout {
            Layout::Pieces { .. } => (grid.cols(), grid.rows()),
            Layout::Uniform => {
                // Table cells are whole multiples of the map's.
                let ratio = libm::roundf(h.cell_size / grid.cell_size());
                let c = sat_u32(ratio).max(1);
                let up = |n: u16| to_u16(u32::from(n).div_ceil(c));
                (up(grid.cols()), up(grid.rows()))
            }
        };
        let cell_ok = match h.layout {
            Layout::Pieces { .. } => h.cell_size == grid.cell_size(),
            Layout::Uniform => {
                let ratio = h.cell_size / grid.cell_size();
                libm::fabsf(ratio - libm::roundf(ratio)) <= 1e-3 * ratio && ratio >= 0.999
            }
        };
        let hash_ok = h.map_hash.is_none_or(|m| map_hash(grid) == Some(m));
        if cell_ok && hash_ok && (h.cols, h.rows) == (cols, rows) {
            Ok(())
        } else {
            Err(TableError::WrongMap)
        }
    }

    /// The validated header.
    pub fn header(&self) -> &TableHeader {
        &self.header
    }

    /// The table cell of a position, `None` outside the table.
    pub(super) fn cell(&self, p: Point) -> Option<usize> {
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
        if c >= cols || r >= rows {
            return None;
        }
        let cell = cell_index(to_u16(c), to_u16(r), to_u16(cols));
        let Some(parts) = self.parts else {
            return Some(cell);
        };
        // Version 2: the cell's piece within its block, then the block's first entry.
        let byte = *self.payload.get(parts.nibbles_at.checked_add(cell / 2)?)?;
        let piece = if cell.is_multiple_of(2) {
            byte & 0x0f
        } else {
            byte >> 4
        };
        if piece == 0 {
            return None;
        }
        let block = parts
            .div_block(r)
            .checked_mul(parts.block_cols)?
            .checked_add(parts.div_block(c))?;
        let at = parts
            .firsts_at
            .checked_add(usize::try_from(block).ok()?.checked_mul(2)?)?;
        let first = le_u16(self.payload, at)?;
        usize::from(first)
            .checked_add(usize::from(piece))?
            .checked_sub(1)
    }

    /// Reads coordinate `d` of `cell` as stored (before scaling); `None` if unreachable.
    #[inline]
    pub(super) fn element(&self, cell: usize, d: usize) -> Option<f32> {
        // Checked: on a 32-bit target a bogus cell could overflow the offset (a validated
        // table never does, since the whole payload fits the address space).
        let k = self.header.dims as usize;
        let size = self.header.kind.size();
        let at = cell.checked_mul(k)?.checked_add(d)?.checked_mul(size)?;
        let bytes = self.coords.get(at..at.checked_add(size)?)?;
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

impl DiffusionTable<'_> {
    /// The stored bytes of one entry's coordinates.
    #[inline]
    fn entry(&self, cell: usize) -> Option<&[u8]> {
        let len = (self.header.dims as usize).checked_mul(self.header.kind.size())?;
        let at = cell.checked_mul(len)?;
        self.coords.get(at..at.checked_add(len)?)
    }
}

/// Squared distance between two entries as stored (`None`: an unreachable coordinate).
///
/// `i16` entries: the sum is exact (each difference squared fits a `u32`, their sum a
/// `u64`), so it does not depend on the order of the additions and is rounded to `f32` once.
/// The additions are independent, so they pipeline (or vectorise) instead of waiting on a
/// chain of float additions, and a core without an FPU does integer work only; every target
/// gets the same bits. `f32` entries: summed in coordinate order.
#[inline]
pub(super) fn stored_sq(kind: ElementKind, a: &[u8], b: &[u8]) -> Option<f32> {
    // No early exit in the loops: the sentinel is or-ed into a flag.
    let mut unreachable = false;
    let sum = match kind {
        ElementKind::I16 => {
            let (a, _) = a.as_chunks::<2>();
            let (b, _) = b.as_chunks::<2>();
            let mut sum = 0u64;
            for (&x, &y) in a.iter().zip(b) {
                let (x, y) = (i16::from_le_bytes(x), i16::from_le_bytes(y));
                unreachable |= (x == i16::MIN) | (y == i16::MIN);
                // |x - y| <= 65,535, whose square is below 2^32; at most 32 of them.
                let d = i32::from(x).abs_diff(i32::from(y));
                sum = sum.wrapping_add(u64::from(d.wrapping_mul(d)));
            }
            // Rounded once, on purpose. Below 2^32 (the usual case) through `u32`: the same
            // value, and one instruction on an FPU core where `u64` to `f32` is a library call.
            #[allow(clippy::cast_precision_loss)]
            let s = match u32::try_from(sum) {
                Ok(small) => small as f32,
                Err(_) => sum as f32,
            };
            s
        }
        ElementKind::F32 => {
            let (a, _) = a.as_chunks::<4>();
            let (b, _) = b.as_chunks::<4>();
            let mut sum = 0.0f32;
            for (&x, &y) in a.iter().zip(b) {
                let (x, y) = (f32::from_le_bytes(x), f32::from_le_bytes(y));
                unreachable |= x.is_nan() | y.is_nan();
                sum += (x - y) * (x - y);
            }
            sum
        }
    };
    (!unreachable).then_some(sum)
}

impl DiffusionTable<'_> {
    /// The entry of a position that has coordinates.
    fn placed(&self, p: Point) -> Option<usize> {
        self.cell(p).filter(|&c| self.element(c, 0).is_some())
    }

    /// `d_D` between two placed entries.
    fn entry_distance(&self, ca: usize, cb: usize) -> f32 {
        if ca == cb {
            return 0.0;
        }
        // One slice per entry and the element kind matched once: the hot loop of the metric
        // nearest scan and of goal rewiring.
        match (self.entry(ca), self.entry(cb)) {
            (Some(ea), Some(eb)) => match stored_sq(self.header.kind, ea, eb) {
                Some(sum) => crate::geometry::sqrt(sum) * self.header.scale,
                None => f32::INFINITY,
            },
            _ => f32::INFINITY,
        }
    }
}

impl Metric for DiffusionTable<'_> {
    fn kind(&self) -> crate::config::MetricKind {
        crate::config::MetricKind::Diffusion
    }
    fn check_map(&self, grid: &crate::map::OccupancyGrid<'_>) -> Result<(), TableError> {
        DiffusionTable::check_map(self, grid)
    }
    fn distance(&self, a: Point, b: Point) -> f32 {
        match (self.placed(a), self.placed(b)) {
            (Some(ca), Some(cb)) => self.entry_distance(ca, cb),
            _ => f32::INFINITY,
        }
    }

    fn prepare(&self, p: Point) -> Prepared {
        let key = self
            .placed(p)
            .and_then(|c| u32::try_from(c).ok())
            .unwrap_or(u32::MAX);
        Prepared {
            point: p,
            key: Some(key),
        }
    }

    fn distance_to(&self, a: Point, to: &Prepared) -> f32 {
        let cb = match to.key {
            None => return self.distance(a, to.point),
            Some(u32::MAX) => return f32::INFINITY,
            Some(k) => k as usize,
        };
        // `cell`, not `placed`: `cb` has coordinates (`prepare` placed it), so an entry `a`
        // without them is a different entry, and `entry_distance` reads its sentinel as
        // infinite: the same answer without a separate look at the first coordinate.
        match self.cell(a) {
            Some(ca) => self.entry_distance(ca, cb),
            None => f32::INFINITY,
        }
    }
}
