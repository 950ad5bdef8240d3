//! Assisting metrics `d_A` (paper, section 3.1, equations 1-2): the distance that guides the
//! tree towards the goal, while tree costs stay Euclidean.
//!
//! - [`Euclidean`]: `d_E`, straight-line distance.
//! - [`DiffusionTable`]: `d_D`, the Euclidean distance between the diffusion coordinates of the
//!   two positions' grid cells, read from a borrowed, validated byte table (which can sit in
//!   flash). The host simulator bakes the tables (`host-sim bake`). For `i16` tables the sum
//!   of squared differences is computed exactly in integers and rounded to `f32` once (the
//!   same bits on every target, and integer work only on a core without an FPU: issue 26
//!   measured +17-21 % expansions per call on the Cortex-M0+).
//! - The geodesic metric `d_G` (graph shortest paths) implements the same trait in `host-sim`,
//!   and any user type can too.
//!
//! A metric returns `f32::INFINITY` for a position it cannot place (an obstacle, outside the
//! map, a region cut off from the main free component).
//!
//! # Table format (versions 1 to 3)
//!
//! Little-endian throughout. A 32-byte header, then the payload:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `b"BIAMDIFF"` |
//! | 8 | 2 | format version (1: uniform, 2: pieces, 3: pieces bound to a map) |
//! | 10 | 2 | element kind: 1 = `i16` quantised, 2 = `f32` |
//! | 12 | 2 | dimensions `k` (1..=32) |
//! | 14 | 2 | columns (v1: table cells; v2, v3: map cells) |
//! | 16 | 2 | rows (likewise) |
//! | 18 | 2 | v1: 0; v2, v3: block side `b` in cells (1..=64) |
//! | 20 | 4 | cell size in metres (`f32`, finite, positive) |
//! | 24 | 4 | scale (`f32`): coordinate = element * scale |
//! | 28 | 4 | FNV-1a 32-bit hash of the payload |
//!
//! **Version 1 (uniform).** The payload holds `cols * rows` entries of `k` elements, in
//! row-major cell order (cell `(col, row)` is entry `row * cols + col`). A table cell may cover
//! several map cells: then all of them share one entry, even when a wall splits them.
//!
//! **Version 2 (pieces).** The map's cells are grouped in `b x b` blocks; each block holds one
//! entry per *connected free piece* of it, so a coarse table never gives a cell coordinates
//! from across a wall. The payload: the entry count `E` (`u32`); for each block (row-major,
//! `ceil(cols / b) x ceil(rows / b)` of them) the index of its first entry (`u16`, so
//! `E <= 65,536`); for each map cell (row-major, two per byte, low nibble first) its piece
//! within the block, 1..=15, or 0 for none; then the `E` entries of `k` elements. Cell
//! `(col, row)` with piece `q > 0` reads entry `first[block] + q - 1`.
//!
//! **Version 3 (pieces, bound to a map).** Version 2 whose payload opens with one more `u32`:
//! the FNV-1a hash of the packed occupancy grid the table was baked from (the
//! `OccupancyGrid::bytes_needed` bytes of `map::pack_grid`'s layout), then the version-2
//! payload. `DiffusionTable::check_map` (which `Planner::new` calls through
//! `Metric::check_map`) refuses a grid of another size or cell size (every version) or, for
//! version 3, other contents, with `TableError::WrongMap`.
//!
//! In all, an entry whose first element is `i16::MIN` (kind 1) or NaN (kind 2) is
//! unreachable, as is a v2/v3 cell of piece 0.

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

    /// Whether the metric was made for `grid` (a table baked from it). `Planner::new` refuses
    /// a metric that was not. Default: any grid.
    fn check_map(&self, grid: &crate::map::OccupancyGrid<'_>) -> Result<(), TableError> {
        let _ = grid;
        Ok(())
    }

    /// One end of many distance queries, resolved once: the planner measures a whole tree, a
    /// batch of steering candidates or a goal's neighbourhood against the same position.
    /// Default: nothing is resolved.
    fn prepare(&self, p: Point) -> Prepared {
        Prepared::plain(p)
    }

    /// `distance(a, to.point())`, the same value bit for bit, using what `prepare` resolved.
    fn distance_to(&self, a: Point, to: &Prepared) -> f32 {
        self.distance(a, to.point)
    }
}

/// A position resolved by [`Metric::prepare`] for repeated [`Metric::distance_to`] queries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prepared {
    point: Point,
    /// What the metric resolved (for a diffusion table: the entry, or `u32::MAX` when the
    /// position cannot be placed); `None`: nothing.
    key: Option<u32>,
}

impl Prepared {
    /// A position with nothing resolved (any metric answers it through `distance`).
    pub const fn plain(point: Point) -> Self {
        Self { point, key: None }
    }

    /// The position.
    pub const fn point(&self) -> Point {
        self.point
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
    fn check_map(&self, grid: &crate::map::OccupancyGrid<'_>) -> Result<(), TableError> {
        (**self).check_map(grid)
    }
    fn prepare(&self, p: Point) -> Prepared {
        (**self).prepare(p)
    }
    fn distance_to(&self, a: Point, to: &Prepared) -> f32 {
        (**self).distance_to(a, to)
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
    /// The table was baked from another map than the one it is used with
    /// ([`DiffusionTable::check_map`]).
    WrongMap,
}

impl core::fmt::Display for TableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Truncated => "table truncated",
            Self::BadMagic => "not a diffusion table (bad magic)",
            Self::UnsupportedVersion => "unsupported table version",
            Self::BadHeader => "table header out of range",
            Self::BadChecksum => "table checksum mismatch",
            Self::WrongMap => {
                "the table was baked from another map (its size, cell size or contents differ)"
            }
        })
    }
}

impl core::error::Error for TableError {}

/// Magic bytes at the start of a diffusion table.
pub const TABLE_MAGIC: [u8; 8] = *b"BIAMDIFF";
/// The newest table format version this build reads and writes (it reads versions 1 and 2
/// too).
pub const TABLE_VERSION: u16 = 3;
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
    /// FNV-1a 32-bit hash of the packed occupancy grid the table was baked from (version 3:
    /// a pieces table bound to its map, checked by [`DiffusionTable::check_map`]); `None` in
    /// versions 1 and 2.
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
                .checked_mul(entry)?,
            Layout::Pieces { entries, .. } => {
                let p = self.pieces()?;
                (p.coords_at as u64).checked_add((entries as u64).checked_mul(entry)?)?
            }
        };
        usize::try_from(len).ok()
    }

    /// Where the parts of a version-2 payload start; `None` for version 1.
    fn pieces(&self) -> Option<PieceParts> {
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
            (Layout::Uniform, _) => 1,
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
struct PieceParts {
    block: u32,
    /// `ceil(2^32 / block)`: `(v * inv_block) >> 32` is `v / block` for every `v < 2^16`
    /// (a multiplication instead of a division in the hot `cell` lookup).
    inv_block: u64,
    block_cols: u32,
    firsts_at: usize,
    nibbles_at: usize,
    coords_at: usize,
}

impl PieceParts {
    /// `inv_block` for a block side `b >= 1`.
    fn reciprocal(b: u32) -> u64 {
        (1u64 << 32).div_ceil(u64::from(b))
    }

    /// `v / block` for a row or column (`v < 2^16`, as every grid index is).
    #[inline]
    fn div_block(&self, v: u32) -> u32 {
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
    /// The entries (all of the payload in version 1).
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
        if !(1..=3).contains(&version) {
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
        let layout = if version == 1 {
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
        let map_hash = if version == 3 {
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
            .get(parts.map_or(0, |p| p.coords_at)..)
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
    /// cells for version 1) and, for a version-3 table, the same grid bytes (their FNV-1a
    /// hash: one pass over the packed grid). `Planner::new` checks it through
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
    fn element(&self, cell: usize, d: usize) -> Option<f32> {
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
fn stored_sq(kind: ElementKind, a: &[u8], b: &[u8]) -> Option<f32> {
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

/// Writes a version-1 table (header and payload) into `out` from per-cell coordinates given
/// by `coords(col, row, &mut [f32]) -> bool` (false: unreachable). Returns the bytes written,
/// or `None` when `out` is too small or the header is invalid (or not `Layout::Uniform`). For
/// `ElementKind::I16` each coordinate is stored as `round(value / scale)`, clamped to
/// `-32767..=32767`.
pub fn write_table<F>(header: &TableHeader, out: &mut [u8], mut coords: F) -> Option<usize>
where
    F: FnMut(u16, u16, &mut [f32]) -> bool,
{
    if header.layout != Layout::Uniform || header.map_hash.is_some() {
        return None;
    }
    let (head, payload) = table_parts(header, out)?;
    let mut buf = [0f32; TABLE_MAX_DIMS];
    let mut at: usize = 0;
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

#[cfg(test)]
mod tests {
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
            let d = |a: (f32, f32), b: (f32, f32)| {
                t.distance(Point::new(a.0, a.1), Point::new(b.0, b.1))
            };
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
}
