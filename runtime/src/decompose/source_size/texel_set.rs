//! A set of texels as a bitset, for the flood fill of a source's region.

/// A set of texels of one map, one bit each.
#[derive(Default)]
pub(super) struct TexelSet {
    pub(super) width: usize,
    pub(super) bits: Vec<u64>,
}

impl TexelSet {
    /// Makes the set empty and fit for a `width × height` map.
    pub(super) fn fit(&mut self, width: usize, height: usize) {
        let words = (width * height).div_ceil(64);
        if self.width != width || self.bits.len() != words {
            self.width = width;
            self.bits = vec![0; words];
        }
    }

    pub(super) fn index(&self, (i, j): (usize, usize)) -> (usize, u64) {
        let n = j * self.width + i;
        (n / 64, 1 << (n % 64))
    }

    pub(super) fn contains(&self, t: (usize, usize)) -> bool {
        let (word, bit) = self.index(t);
        self.bits[word] & bit != 0
    }

    /// Adds `t`; whether it was new.
    pub(super) fn insert(&mut self, t: (usize, usize)) -> bool {
        let (word, bit) = self.index(t);
        let new = self.bits[word] & bit == 0;
        self.bits[word] |= bit;
        new
    }

    /// Removes `members` (empties the set when they are all it holds).
    pub(super) fn clear(&mut self, members: &[(usize, usize)]) {
        for &t in members {
            let (word, bit) = self.index(t);
            self.bits[word] &= !bit;
        }
    }
}
