//! The diffusion table's binary format (the metric module's "Table format"): its header,
//! checksums, and the writers the host bakes tables with; the reader is `table`.

use crate::slots::to_u16;

/// Magic bytes at the start of a diffusion table.
pub const TABLE_MAGIC: [u8; 8] = *b"BIAMDIFF";
/// The newest table format version this build reads and writes (it reads versions 1 to 3
/// too): 1 uniform, 2 pieces, 3 pieces bound to their map by its hash, 4 uniform bound to
/// its map.
pub const TABLE_VERSION: u16 = 4;
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
    fnv1a32_more(0x811c_9dc5, bytes)
}

/// [`fnv1a32`] continued over more bytes from the hash `h` of those before.
fn fnv1a32_more(h: u32, bytes: &[u8]) -> u32 {
    bytes
        .iter()
        .fold(h, |h, &b| (h ^ b as u32).wrapping_mul(0x0100_0193))
}

/// The hash a table records of the map it was baked for (`TableHeader::map_hash`): FNV-1a of
/// the grid's bits and, for a robot body (a grid of the world whose
/// [`crate::map::OccupancyGrid::inflation`] is the body's radius: [`crate::Map::metric_grid`]),
/// of the radius's bytes after them, so that a table baked for one body is refused for another.
pub fn map_hash(grid: &crate::map::OccupancyGrid<'_>) -> Option<u32> {
    let n = crate::map::OccupancyGrid::bytes_needed(grid.cols(), grid.rows());
    let h = fnv1a32(grid.bits().get(..n)?);
    let r = grid.inflation();
    Some(if r > 0.0 {
        fnv1a32_more(h, &r.to_le_bytes())
    } else {
        h
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
    /// How positions map to entries.
    pub layout: Layout,
    /// FNV-1a 32-bit hash of the packed occupancy grid the table was baked from (versions 3
    /// and 4: a table bound to its map, checked by
    /// [`DiffusionTable::check_map`](crate::metric::DiffusionTable::check_map); the payload
    /// opens with it); `None` in versions 1 and 2.
    pub map_hash: Option<u32>,
}

/// How a table maps positions to its entries (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Layout {
    /// Version 1: one entry per table cell.
    Uniform,
    /// Version 2: map cells in `block x block` blocks, one entry per connected free piece of a
    /// block, `entries` in all.
    Pieces {
        /// Block side in map cells (1..=64).
        block: u16,
        /// Entries stored (at most 65,536).
        entries: u32,
    },
}

/// Most entries a version-2 table may hold (block offsets are `u16`).
pub const PIECES_MAX_ENTRIES: u32 = 65_536;
/// Largest block side of a version-2 table (a block holds at most 15 pieces).
pub const PIECES_MAX_BLOCK: u16 = 64;

impl TableHeader {
    /// Payload size in bytes; `None` when it does not fit the target's `usize` (a header
    /// claiming 8192 x 8192 cells of 32 `f32` is 8 GiB: more than a 32-bit address space).
    pub fn payload_len(&self) -> Option<usize> {
        let entry = (self.dims as u64).checked_mul(self.kind.size() as u64)?;
        let len = match self.layout {
            Layout::Uniform => (self.cols as u64)
                .checked_mul(self.rows as u64)?
                .checked_mul(entry)?
                .checked_add(self.uniform_coords_at() as u64)?,
            Layout::Pieces { entries, .. } => {
                let p = self.pieces()?;
                (p.coords_at as u64).checked_add((entries as u64).checked_mul(entry)?)?
            }
        };
        usize::try_from(len).ok()
    }

    /// Where the parts of a version-2 payload start; `None` for version 1.
    pub(super) fn pieces(&self) -> Option<PieceParts> {
        let Layout::Pieces { block, .. } = self.layout else {
            return None;
        };
        let b = u32::from(block).max(1);
        let (cols, rows) = (u32::from(self.cols), u32::from(self.rows));
        let block_cols = cols.div_ceil(b);
        let blocks = block_cols.checked_mul(rows.div_ceil(b))?;
        let nibble_bytes = cols.checked_mul(rows)?.div_ceil(2);
        // Version 3 opens with the map's hash, then the entry count.
        let firsts_at: u32 = if self.map_hash.is_some() { 8 } else { 4 };
        let nibbles_at = firsts_at.checked_add(blocks.checked_mul(2)?)?;
        let coords_at = nibbles_at.checked_add(nibble_bytes)?;
        Some(PieceParts {
            block: b,
            inv_block: PieceParts::reciprocal(b),
            block_cols,
            firsts_at: usize::try_from(firsts_at).ok()?,
            nibbles_at: usize::try_from(nibbles_at).ok()?,
            coords_at: usize::try_from(coords_at).ok()?,
        })
    }

    /// Where a uniform payload's entries start: after the map's hash in version 4.
    pub(super) const fn uniform_coords_at(&self) -> usize {
        if self.map_hash.is_some() { 4 } else { 0 }
    }

    /// Payload plus header, in bytes: the table's whole size.
    pub fn table_len(&self) -> Option<usize> {
        self.payload_len()?.checked_add(TABLE_HEADER_LEN)
    }

    /// The 32 header bytes for a payload with this checksum.
    pub fn to_bytes(&self, checksum: u32) -> [u8; TABLE_HEADER_LEN] {
        let mut h = [0u8; TABLE_HEADER_LEN];
        let fields: [(usize, &[u8]); 10] = [
            (0, &TABLE_MAGIC),
            (8, &self.version().to_le_bytes()),
            (10, &self.kind.code().to_le_bytes()),
            (12, &self.dims.to_le_bytes()),
            (14, &self.cols.to_le_bytes()),
            (16, &self.rows.to_le_bytes()),
            (18, &self.block_field().to_le_bytes()),
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

impl TableHeader {
    /// The format version of this layout.
    pub const fn version(&self) -> u16 {
        match (self.layout, self.map_hash) {
            (Layout::Uniform, None) => 1,
            (Layout::Uniform, Some(_)) => 4,
            (Layout::Pieces { .. }, None) => 2,
            (Layout::Pieces { .. }, Some(_)) => 3,
        }
    }

    const fn block_field(&self) -> u16 {
        match self.layout {
            Layout::Uniform => 0,
            Layout::Pieces { block, .. } => block,
        }
    }
}

/// Offsets of the parts of a version-2 payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct PieceParts {
    pub(super) block: u32,
    /// `ceil(2^32 / block)`: `(v * inv_block) >> 32` is `v / block` for every `v < 2^16`
    /// (a multiplication instead of a division in the hot `cell` lookup).
    pub(super) inv_block: u64,
    pub(super) block_cols: u32,
    pub(super) firsts_at: usize,
    pub(super) nibbles_at: usize,
    pub(super) coords_at: usize,
}

impl PieceParts {
    /// `inv_block` for a block side `b >= 1`.
    pub(super) fn reciprocal(b: u32) -> u64 {
        (1u64 << 32).div_ceil(u64::from(b))
    }

    /// `v / block` for a row or column (`v < 2^16`, as every grid index is).
    #[inline]
    pub(super) fn div_block(&self, v: u32) -> u32 {
        // `v * inv_block < 2^16 * 2^32`: no overflow; the quotient is below 2^16.
        #[allow(clippy::cast_possible_truncation)]
        let q = (u64::from(v).wrapping_mul(self.inv_block) >> 32) as u32;
        q
    }
}

/// Copies `src` into `dst` (lengths equal by construction; `copy_from_slice` would carry a
/// panicking length check).
fn copy_bytes(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

pub(super) fn le_u16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(
        b.get(at..at.checked_add(2)?)?.try_into().ok()?,
    ))
}

pub(super) fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

/// The `i16` element of a coordinate: rounded and clamped to `-32767..=32767` (NaN gives 0).
#[allow(clippy::cast_possible_truncation)] // clamped into i16 range first; the cast saturates
fn quantise(v: f32) -> i16 {
    libm::roundf(v).clamp(-32767.0, 32767.0) as i16
}

/// Encodes one entry's coordinates (or "unreachable") at `payload[at..]`; returns the offset
/// after it.
fn put_entry(
    header: &TableHeader,
    payload: &mut [u8],
    mut at: usize,
    reachable: bool,
    coords: &[f32],
) -> Option<usize> {
    let size = header.kind.size();
    for &v in coords {
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
    Some(at)
}

/// Splits `out` into header and payload for a table of `header`'s size, after checking the
/// fields every writer needs.
fn table_parts<'o>(
    header: &TableHeader,
    out: &'o mut [u8],
) -> Option<(&'o mut [u8], &'o mut [u8])> {
    let k = header.dims as usize;
    if k == 0 || k > TABLE_MAX_DIMS || !(header.scale.is_finite() && header.scale > 0.0) {
        return None;
    }
    let total = header.table_len()?;
    out.get_mut(..total)?.split_at_mut_checked(TABLE_HEADER_LEN)
}

/// Writes a uniform table (version 1, or 4 with `header.map_hash`) into `out` from per-cell
/// coordinates given by `coords(col, row, &mut [f32]) -> bool` (false: unreachable). Returns
/// the bytes written, or `None` when `out` is too small or the header is invalid (or not
/// `Layout::Uniform`). For `ElementKind::I16` each coordinate is stored as
/// `round(value / scale)`, clamped to `-32767..=32767`.
pub fn write_table<F>(header: &TableHeader, out: &mut [u8], mut coords: F) -> Option<usize>
where
    F: FnMut(u16, u16, &mut [f32]) -> bool,
{
    if header.layout != Layout::Uniform {
        return None;
    }
    let (head, payload) = table_parts(header, out)?;
    if let Some(hash) = header.map_hash {
        copy_bytes(payload.get_mut(..4)?, &hash.to_le_bytes());
    }
    let mut buf = [0f32; TABLE_MAX_DIMS];
    let mut at: usize = header.uniform_coords_at();
    for row in 0..header.rows {
        for col in 0..header.cols {
            let c = buf.get_mut(..header.dims as usize)?;
            let reachable = coords(col, row, c);
            at = put_entry(header, payload, at, reachable, c)?;
        }
    }
    let sum = fnv1a32(payload);
    copy_bytes(head, &header.to_bytes(sum));
    header.table_len()
}

/// Writes a version-2 table (module docs) into `out`. `piece(col, row)` gives each map cell's
/// piece within its block: 0 for none, else 1..=15, numbered from 1 without gaps in each
/// block. Entries are numbered block by block (row-major blocks), pieces in order within a
/// block; `coords(entry, &mut [f32]) -> bool` gives each one's coordinates (false:
/// unreachable). `header.layout` must be `Layout::Pieces` with the right entry count. Returns
/// the bytes written, or `None` when something does not fit or disagrees.
pub fn write_piece_table<P, F>(
    header: &TableHeader,
    out: &mut [u8],
    mut piece: P,
    mut coords: F,
) -> Option<usize>
where
    P: FnMut(u16, u16) -> u8,
    F: FnMut(u32, &mut [f32]) -> bool,
{
    let parts = header.pieces()?;
    let Layout::Pieces { entries, .. } = header.layout else {
        return None;
    };
    let (head, payload) = table_parts(header, out)?;
    let count_at = match header.map_hash {
        Some(hash) => {
            copy_bytes(payload.get_mut(..4)?, &hash.to_le_bytes());
            4..8
        }
        None => 0..4,
    };
    copy_bytes(payload.get_mut(count_at)?, &entries.to_le_bytes());
    let (cols, rows, b) = (u32::from(header.cols), u32::from(header.rows), parts.block);
    let mut next: u32 = 0;
    for br in 0..rows.div_ceil(b) {
        for bc in 0..parts.block_cols {
            let block = br.checked_mul(parts.block_cols)?.checked_add(bc)?;
            let at = parts
                .firsts_at
                .checked_add(usize::try_from(block).ok()?.checked_mul(2)?)?;
            let first = u16::try_from(next).ok()?;
            copy_bytes(
                payload.get_mut(at..at.checked_add(2)?)?,
                &first.to_le_bytes(),
            );
            let mut most = 0u8;
            for r in br.checked_mul(b)?..br.checked_add(1)?.checked_mul(b)?.min(rows) {
                for c in bc.checked_mul(b)?..bc.checked_add(1)?.checked_mul(b)?.min(cols) {
                    let q = piece(to_u16(c), to_u16(r));
                    if q > 15 {
                        return None;
                    }
                    most = most.max(q);
                    let cell = usize::try_from(r.checked_mul(cols)?.checked_add(c)?).ok()?;
                    let byte = payload.get_mut(parts.nibbles_at.checked_add(cell / 2)?)?;
                    *byte = if cell.is_multiple_of(2) {
                        (*byte & 0xf0) | q
                    } else {
                        (*byte & 0x0f) | (q << 4)
                    };
                }
            }
            next = next.checked_add(u32::from(most))?;
        }
    }
    if next != entries {
        return None;
    }
    let mut buf = [0f32; TABLE_MAX_DIMS];
    let mut at = parts.coords_at;
    for e in 0..entries {
        let c = buf.get_mut(..header.dims as usize)?;
        let reachable = coords(e, c);
        at = put_entry(header, payload, at, reachable, c)?;
    }
    let sum = fnv1a32(payload);
    copy_bytes(head, &header.to_bytes(sum));
    header.table_len()
}
