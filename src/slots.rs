//! Panic-free access and conversions for the fixed-capacity arrays of the tree arena and the spatial index
//! (paper section 3's `Tree` and `Nearest` storage): every read and write goes through
//! `get`/`get_mut`, so no indexing branch can panic and the crate's link-time panic-never
//! check holds. The fallbacks are never taken by correct callers.

/// Reads slot `i` of one of the arena's arrays. Callers pass indices they know to be in range (ids checked against the
/// arena's length, or read from links, which stay in range): the fallback is never used, but it
/// keeps every access free of a panicking branch (the crate's panic-never check links only so).
#[inline(always)]
pub(crate) fn rd<T: Copy>(slots: &[T], i: usize, fallback: T) -> T {
    slots.get(i).copied().unwrap_or(fallback)
}

/// Copies slot `from` to slot `to` (ignored out of range; see [`rd`]).
#[inline(always)]
pub(crate) fn copy_slot<T: Copy>(slots: &mut [T], from: usize, to: usize) {
    if let Some(&v) = slots.get(from) {
        wr(slots, to, v);
    }
}

/// Writes slot `i` of one of the arena's arrays (ignored out of range; see [`rd`]).
#[inline(always)]
pub(crate) fn wr<T>(slots: &mut [T], i: usize, value: T) {
    if let Some(s) = slots.get_mut(i) {
        *s = value;
    }
}

/// Row-major index of cell `(col, row)` in a grid `width` cells wide. With `u16` operands the
/// result is below 2^32, so it fits a `usize` on every 32- and 64-bit target.
#[inline(always)]
#[allow(clippy::arithmetic_side_effects)] // u16 * u16 + u16 < 2^32: cannot overflow
pub(crate) fn cell_index(col: u16, row: u16, width: u16) -> usize {
    row as usize * width as usize + col as usize
}

/// A non-negative float as an index or count: Rust's float-to-integer casts saturate (NaN and
/// negatives give 0, huge values `u32::MAX`), which is the clamping every caller wants.
#[inline(always)]
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // saturating by definition
pub(crate) fn sat_u32(v: f32) -> u32 {
    v as u32
}

/// A count as work units (saturating).
#[inline(always)]
pub(crate) fn units(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// A `u32` known to be below a `u16` bound, as `u16` (saturating).
#[inline(always)]
pub(crate) fn to_u16(v: impl TryInto<u16>) -> u16 {
    v.try_into().unwrap_or(u16::MAX)
}
