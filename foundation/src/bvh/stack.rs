//! The order of a traversal: the stack of children still to visit, and a node's entered
//! children sorted nearest last.

use std::mem::MaybeUninit;

/// Entries a traversal keeps on its own stack before spilling to the heap (a four-wide
/// tree pushes at most three per level: 256 holds any tree up to 85 levels deep).
const STACK: usize = 256;

/// The traversal stack: children still to visit, with what culls them when they come up (for
/// one ray, the distance at which it enters them).
pub(super) struct Stack<T> {
    /// Entries below `top` are written; the rest are not (no per-ray clearing).
    entries: [MaybeUninit<T>; STACK],
    top: usize,
    spilled: Vec<T>,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            entries: [const { MaybeUninit::uninit() }; STACK],
            top: 0,
            spilled: Vec::new(),
        }
    }

    #[inline(always)]
    pub(super) fn push(&mut self, entry: T) {
        if self.top < STACK {
            self.entries[self.top].write(entry);
            self.top += 1;
        } else {
            self.spilled.push(entry);
        }
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if let Some(entry) = self.spilled.pop() {
            return Some(entry);
        }
        if self.top == 0 {
            return None;
        }
        self.top -= 1;
        // SAFETY: entries below the old `top` were written by `push`.
        Some(unsafe { self.entries[self.top].assume_init() })
    }
}

/// Inserts `entry` into the first `n` entries of `order`, kept sorted by decreasing distance
/// (a node's entered children: the nearest last, visited next).
#[inline(always)]
pub(super) fn insert_farthest_first<T: Copy>(
    order: &mut [(f32, T); 4],
    n: &mut usize,
    entry: (f32, T),
) {
    let mut at = *n;
    while at > 0 && order[at - 1].0 < entry.0 {
        order[at] = order[at - 1];
        at -= 1;
    }
    order[at] = entry;
    *n += 1;
}
