//! The median of luminances, selected among their order-preserving bit patterns.

/// `total_cmp`'s order as unsigned integers: flip the sign bit of positives, every bit of
/// negatives.
#[inline]
pub(super) fn order_key(v: f32) -> u32 {
    let bits = v.to_bits();
    bits ^ (((bits as i32) >> 31) as u32 | 1 << 31)
}

/// The float whose [`order_key`] is `key`.
fn from_order_key(key: u32) -> f32 {
    f32::from_bits(if key >> 31 == 1 { key ^ 1 << 31 } else { !key })
}

/// The median of the floats whose [`order_key`]s are `keys` (0 when empty): the element at
/// index `len / 2` in `total_cmp` order, selected in linear time (integer comparisons, no
/// sort). `keys` is reordered.
pub(super) fn median_of_keys(keys: &mut [u32]) -> f32 {
    if keys.is_empty() {
        return 0.0;
    }
    let middle = keys.len() / 2;
    from_order_key(*keys.select_nth_unstable(middle).1)
}
