//! The median of luminances by a radix selection over their order-preserving bit patterns.

/// `total_cmp`'s order as unsigned integers: flip the sign bit of positives, every bit of
/// negatives.
#[inline]
pub(super) fn order_key(v: f32) -> u32 {
    let bits = v.to_bits();
    bits ^ (((bits as i32) >> 31) as u32 | 1 << 31)
}

/// Bits of an [`order_key`] counted by each level of [`median_of_keys`]' radix selection.
pub(super) const RADIX_LEVELS: [u32; 3] = [11, 11, 10];

/// Counts of a digit of keys (up to 11 bits). Neighbouring texels mostly share a digit, so
/// the keys are counted into four histograms in turn (summed at the end): increments of one
/// bin then do not wait on each other.
struct DigitCounts {
    ways: [[u32; 1 << 11]; 4],
}

impl DigitCounts {
    fn new() -> Self {
        Self {
            ways: [[0; 1 << 11]; 4],
        }
    }

    /// Counts the `bits` bits from `shift` up of each of `keys`, key `i` into histogram
    /// `i mod 4`.
    #[inline]
    fn add(&mut self, keys: &[u32], shift: u32, bits: u32) {
        let mask = (1u32 << bits) - 1;
        let digit = |k: &u32| ((k >> shift) & mask) as usize;
        let mut quads = keys.chunks_exact(4);
        for quad in &mut quads {
            for (way, key) in self.ways.iter_mut().zip(quad) {
                way[digit(key)] += 1;
            }
        }
        for key in quads.remainder() {
            self.ways[0][digit(key)] += 1;
        }
    }

    /// The counts, all histograms summed.
    fn total(&self) -> [u32; 1 << 11] {
        let [mut total, rest @ ..] = self.ways;
        for way in &rest {
            for (t, c) in total.iter_mut().zip(way) {
                *t += c;
            }
        }
        total
    }
}

/// The counts of the keys' top [`RADIX_LEVELS`]`[0]` bits: the selection's first histogram,
/// taken while the keys are gathered.
pub(super) struct TopBits(DigitCounts);

impl TopBits {
    const SHIFT: u32 = 32 - RADIX_LEVELS[0];

    pub(super) fn new() -> Self {
        Self(DigitCounts::new())
    }

    #[inline]
    pub(super) fn count(&mut self, key: u32) -> u32 {
        self.0.add(&[key], Self::SHIFT, RADIX_LEVELS[0]);
        key
    }

    /// Appends the keys `values` to `out`, counting them: first the keys (a loop that
    /// vectorizes), then their top bits.
    #[inline]
    pub(super) fn extend(&mut self, out: &mut Vec<u32>, values: impl Iterator<Item = u32>) {
        let start = out.len();
        out.extend(values);
        self.0.add(&out[start..], Self::SHIFT, RADIX_LEVELS[0]);
    }

    fn counts(&self) -> [u32; 1 << 11] {
        self.0.total()
    }
}

/// The median of the floats whose [`order_key`]s are `keys` (0 when empty): the element at
/// index `len / 2` in `total_cmp` order, found by radix selection (`top` counts the top bits;
/// then a histogram of the next bits among the keys left, and so on: no comparison sort).
/// `keys` is used as scratch.
pub(super) fn median_of_keys(keys: &mut Vec<u32>, top: &TopBits) -> f32 {
    if keys.is_empty() {
        return 0.0;
    }
    let mut rank = keys.len() / 2;
    let mut shift = 32;
    let mut prefix = 0u32;
    for (level, bits) in RADIX_LEVELS.into_iter().enumerate() {
        shift -= bits;
        let counts = if level == 0 {
            top.counts()
        } else {
            // Flat regions leave many equal keys: then they are the answer.
            let (low, high) = keys
                .iter()
                .fold((u32::MAX, 0), |(lo, hi), k| (lo.min(*k), hi.max(*k)));
            if low == high {
                break;
            }
            digit_counts(keys, shift, bits)
        };
        let mut digit = 0;
        while rank >= counts[digit] as usize {
            rank -= counts[digit] as usize;
            digit += 1;
        }
        prefix = prefix << bits | digit as u32;
        if (counts[digit] as usize) < keys.len() {
            keep_prefix(keys, shift, prefix);
        }
        if keys.len() == 1 || shift == 0 {
            break;
        }
    }
    let key = keys[rank.min(keys.len() - 1)];
    // Undo `order_key`.
    f32::from_bits(if key >> 31 == 1 { key ^ 1 << 31 } else { !key })
}

/// How many `keys` have each value of the `bits` bits from `shift` up.
fn digit_counts(keys: &[u32], shift: u32, bits: u32) -> [u32; 1 << 11] {
    let mut counts = DigitCounts::new();
    counts.add(keys, shift, bits);
    counts.total()
}

/// Keeps the keys whose bits above `shift` are `prefix`, in order. Without a branch per key:
/// every key is written at the end of those kept, which grows only when it matches.
fn keep_prefix(keys: &mut Vec<u32>, shift: u32, prefix: u32) {
    let mut kept = 0;
    for i in 0..keys.len() {
        let key = keys[i];
        keys[kept] = key;
        kept += usize::from(key >> shift == prefix);
    }
    keys.truncate(kept);
}

/// [`median_of_keys`] of keys not counted while gathered.
#[cfg(test)]
pub(super) fn median_of(keys: &mut Vec<u32>) -> f32 {
    let mut top = TopBits::new();
    keys.iter().for_each(|k| {
        top.count(*k);
    });
    median_of_keys(keys, &top)
}
