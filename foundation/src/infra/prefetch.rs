//! Asking the cache for data a moment before it is read.

/// Asks the cache for every line of `*value` without waiting for them; never faults,
/// whatever the address.
#[inline(always)]
pub fn prefetch<T>(value: *const T) {
    prefetch_range(value, 1);
}

/// [`prefetch`] for `count` values from `first` on.
#[inline(always)]
pub fn prefetch_range<T>(first: *const T, count: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        const LINE: usize = 64;
        let start = first.cast::<i8>();
        let bytes = count * std::mem::size_of::<T>();
        // One request per line the values touch (the last one too when they end mid-line).
        let lines = (start as usize % LINE + bytes).div_ceil(LINE);
        for k in 0..lines {
            // SAFETY: a prefetch is a hint: it reads nothing and cannot fault.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(k * LINE)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (first, count);
}
