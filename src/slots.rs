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

/// Reads a link (a node id or none) stored *zero-is-none*: slot value `id + 1`, 0 for none, so
/// that an all-zero arena is an empty one (a `static` of it lands in `.bss`). Returns the id, or
/// `u16::MAX` for none (ids are below `u16::MAX`).
#[inline(always)]
pub(crate) fn rd_link(slots: &[u16], i: usize) -> u16 {
    rd(slots, i, 0).wrapping_sub(1)
}

/// Writes a link read by [`rd_link`] (`u16::MAX` writes none).
#[inline(always)]
pub(crate) fn wr_link(slots: &mut [u16], i: usize, id: u16) {
    wr(slots, i, id.wrapping_add(1));
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

/// Sorts a short list (the planner's are at most 64 items) by `cmp`, stably, in place: an
/// insertion sort with no allocation and, unlike `core`'s sorts (which check that `cmp` is a
/// total order), no panicking branch.
pub(crate) fn sort_small_by<T, F>(v: &mut [T], mut cmp: F)
where
    F: FnMut(&T, &T) -> core::cmp::Ordering,
{
    for i in 1..v.len() {
        let Some(head) = v.get_mut(..=i) else {
            return;
        };
        // Move head[i] down while it is smaller than its left neighbour.
        let mut j = i;
        while j > 0 {
            let Some((left, right)) = head.split_at_mut_checked(j) else {
                break;
            };
            let (Some(a), Some(b)) = (left.last_mut(), right.first_mut()) else {
                break;
            };
            if cmp(b, a) != core::cmp::Ordering::Less {
                break;
            }
            core::mem::swap(a, b);
            j = j.saturating_sub(1);
        }
    }
}

/// Reverses a slice without a panicking branch.
pub(crate) fn reverse(v: &mut [impl Sized]) {
    let half = v.len() / 2;
    if let Some((front, back)) = v.split_at_mut_checked(v.len().saturating_sub(half)) {
        for (a, b) in front.iter_mut().zip(back.iter_mut().rev()) {
            core::mem::swap(a, b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_sort_and_reverse_agree_with_core() {
        let mut seed = 12345u32;
        for len in 0..70 {
            let mut v: heapless::Vec<(u8, u16), 70> = heapless::Vec::new();
            for i in 0..len {
                seed ^= seed << 13;
                seed ^= seed >> 17;
                seed ^= seed << 5;
                let _ = v.push(((seed % 7) as u8, i));
            }
            let mut expected = v.clone();
            expected.sort_by_key(|x| x.0); // stable
            sort_small_by(&mut v, |a, b| a.0.cmp(&b.0));
            assert_eq!(v, expected);
            let mut r = v.clone();
            reverse(&mut r);
            expected.reverse();
            assert_eq!(r, expected);
        }
    }
}
