//! Tables read at random, far apart, stored in 2 MiB pages where the OS allows it.
//!
//! A path's rays, hits and environment lookups land anywhere in the BVH, the shading
//! records and the map's texels. With 4 KiB pages most of those reads miss the TLB as
//! well as the cache, and the page walk waits on memory too. On Linux, transparent huge
//! pages in their default `madvise` mode back only memory that asks for them, and only
//! whole 2 MiB-aligned pages of it: so each large table gets a mapping of its own, aligned,
//! which asks before it is first written.

use std::fmt;
use std::marker::PhantomData;
use std::ops::Deref;

/// One huge page (x86-64, and ARM64 with 4 KiB base pages).
const HUGE_PAGE: usize = 2 << 20;

/// A fixed table of plain values (`Copy`: nothing to drop), in huge pages when it spans
/// at least one; a smaller one, or one the OS will not map, is an ordinary vector.
pub struct HugePageTable<T: Copy> {
    storage: Storage<T>,
}

enum Storage<T> {
    Heap(Vec<T>),
    Mapped {
        map: memmap2::MmapMut,
        /// Where the values start in `map`: its first 2 MiB boundary.
        offset: usize,
        len: usize,
        values: PhantomData<T>,
    },
}

impl<T: Copy> HugePageTable<T> {
    /// The table of `values`.
    pub fn new(values: impl ExactSizeIterator<Item = T>) -> Self {
        let bytes = values.len() * size_of::<T>();
        if bytes < HUGE_PAGE || align_of::<T>() > HUGE_PAGE {
            return Self::heap(values);
        }
        // One huge page more than the values need, so that they can start on a boundary.
        let Ok(mut map) = memmap2::MmapOptions::new()
            .len(bytes + HUGE_PAGE)
            .map_anon()
        else {
            return Self::heap(values);
        };
        #[cfg(target_os = "linux")]
        // A hint: the table works the same in 4 KiB pages.
        let _ = map.advise(memmap2::Advice::HugePage);
        let offset = (map.as_ptr() as usize).next_multiple_of(HUGE_PAGE) - map.as_ptr() as usize;
        let first = map.as_mut_ptr().wrapping_add(offset).cast::<T>();
        let capacity = values.len();
        let mut len = 0;
        for value in values.take(capacity) {
            // SAFETY: `first` is aligned for `T` (a 2 MiB boundary) and the mapping holds
            // `capacity` values past it; each is written once, before any is read.
            unsafe { first.add(len).write(value) };
            len += 1;
        }
        Self {
            storage: Storage::Mapped {
                map,
                offset,
                len,
                values: PhantomData,
            },
        }
    }

    fn heap(values: impl Iterator<Item = T>) -> Self {
        Self {
            storage: Storage::Heap(values.collect()),
        }
    }

    /// Whether the table has a mapping of its own (which asked for huge pages).
    #[cfg(test)]
    pub(crate) fn is_mapped(&self) -> bool {
        matches!(self.storage, Storage::Mapped { .. })
    }
}

impl<T: Copy> Deref for HugePageTable<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        match &self.storage {
            Storage::Heap(values) => values,
            Storage::Mapped {
                map, offset, len, ..
            } => {
                // SAFETY: `new` wrote `len` values of `T` from this aligned address; the
                // mapping lives as long as `self` and is only read from here on.
                unsafe { std::slice::from_raw_parts(map.as_ptr().add(*offset).cast(), *len) }
            }
        }
    }
}

impl<T: Copy> Clone for HugePageTable<T> {
    fn clone(&self) -> Self {
        Self::new(self.iter().copied())
    }
}

impl<T: Copy + fmt::Debug> fmt::Debug for HugePageTable<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<T: Copy> From<Vec<T>> for HugePageTable<T> {
    fn from(values: Vec<T>) -> Self {
        Self::new(values.into_iter())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(i: u32) -> u32 {
        i.wrapping_mul(2_654_435_761)
    }

    /// The table holds its values, and the advice reaches the kernel: its mapping carries
    /// the `hg` flag (MADV_HUGEPAGE) wherever transparent huge pages are not switched off.
    #[test]
    #[cfg(target_os = "linux")]
    fn large_tables_ask_for_huge_pages() {
        let n = 3 << 20; // 12 MiB: spans several huge pages whatever the alignment.
        let table = HugePageTable::new((0..n).map(value));
        assert!(table.is_mapped());
        assert_eq!(table.len(), n as usize);
        assert!(table.iter().enumerate().all(|(i, &v)| v == value(i as u32)));
        assert!((table.as_ptr() as usize).is_multiple_of(HUGE_PAGE));
        let copy = table.clone();
        assert_eq!(&copy[..], &table[..]);
        let thp = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled");
        if thp.as_deref().map_or(true, |mode| mode.contains("[never]")) {
            eprintln!("transparent huge pages are off here: no advice to check");
            return;
        }
        let flags = mapping_flags(table.as_ptr() as usize + 4 * table.len() / 2);
        assert!(flags.iter().any(|f| f == "hg"), "{flags:?}");
    }

    /// The `VmFlags` of the mapping holding `address`, from /proc/self/smaps.
    #[cfg(target_os = "linux")]
    fn mapping_flags(address: usize) -> Vec<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap();
        let mut inside = false;
        for line in smaps.lines() {
            let range = line.split_once(' ').and_then(|(r, _)| r.split_once('-'));
            if let Some((from, to)) = range
                && let (Ok(from), Ok(to)) = (
                    usize::from_str_radix(from, 16),
                    usize::from_str_radix(to, 16),
                )
            {
                inside = (from..to).contains(&address);
            } else if inside && let Some(flags) = line.strip_prefix("VmFlags:") {
                return flags.split_whitespace().map(str::to_owned).collect();
            }
        }
        panic!("no mapping holds {address:#x}");
    }

    #[test]
    fn small_tables_stay_on_the_heap() {
        let table = HugePageTable::new((0..1000).map(value));
        assert!(!table.is_mapped());
        assert_eq!(table.to_vec(), (0..1000).map(value).collect::<Vec<_>>());
        let empty = HugePageTable::<u32>::new(std::iter::empty());
        assert!(empty.is_empty());
    }
}
