//! How long-running library work (bakes, reference renders) reports its progress, without the
//! library choosing how it is shown: the command line draws a terminal bar, the viewer a panel
//! widget, tests nothing.
//!
//! The same object carries cancellation the other way: work that may run long asks
//! [`Progress::cancelled`] at coarse points (a chunk of vertices, an image row) and stops with
//! its own `Cancelled` error when it answers true (the Python module answers true after Ctrl-C).
//! Asking never changes what is computed: work that is not cancelled gives the same bits.

use std::sync::atomic::{AtomicU64, Ordering};

/// Receives progress from work that may run on many threads.
pub trait Progress: Sync {
    /// The work has `total` steps (vertices, image rows...).
    fn start(&self, _total: u64) {}
    /// `steps` more steps are done.
    fn advance(&self, _steps: u64) {}
    /// What the work is doing now ("bounce 2/3").
    fn status(&self, _text: &str) {}
    /// The work is over.
    fn finish(&self) {}
    /// Whether the work should stop now (its result is then an error, never a partial one).
    /// Asked from any of the work's threads, often: keep it cheap.
    fn cancelled(&self) -> bool {
        false
    }
}

/// A borrowed progress is one: work can be lent its caller's (`Box::new(progress)` where a
/// boxed progress is asked for), cancellation included.
impl<P: Progress + ?Sized> Progress for &P {
    fn start(&self, total: u64) {
        (**self).start(total);
    }
    fn advance(&self, steps: u64) {
        (**self).advance(steps);
    }
    fn status(&self, text: &str) {
        (**self).status(text);
    }
    fn finish(&self) {
        (**self).finish();
    }
    fn cancelled(&self) -> bool {
        (**self).cancelled()
    }
}

/// Progress that goes nowhere.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}

/// Progress kept in two counters, for a reader on another thread (a window's progress bar).
#[derive(Debug, Default)]
pub struct SharedProgress {
    total: AtomicU64,
    done: AtomicU64,
}

impl SharedProgress {
    /// The share of the work done, in `[0, 1]` (0 before the work starts).
    pub fn fraction(&self) -> f32 {
        let total = self.total.load(Ordering::Relaxed);
        if total == 0 {
            return 0.0;
        }
        (self.done.load(Ordering::Relaxed) as f64 / total as f64).min(1.0) as f32
    }
}

impl Progress for SharedProgress {
    fn start(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
    }
    fn advance(&self, steps: u64) {
        self.done.fetch_add(steps, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_borrowed_progress_forwards_everything() {
        let counted = SharedProgress::default();
        let lent: Box<dyn Progress + '_> = Box::new(&counted);
        lent.start(4);
        lent.advance(1);
        assert_eq!(counted.fraction(), 0.25);
        assert!(!lent.cancelled());
    }

    #[test]
    fn shared_progress_counts_from_many_threads() {
        let progress = SharedProgress::default();
        assert_eq!(progress.fraction(), 0.0);
        progress.start(400);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| (0..50).for_each(|_| progress.advance(1)));
            }
        });
        assert_eq!(progress.fraction(), 0.5);
    }
}
