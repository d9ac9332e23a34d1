//! What a report tells its caller while it runs, without choosing how it is shown: the
//! command line prints each line and draws a progress bar, the Python module forwards them
//! to a callback, tests keep nothing.

use foundation::infra::progress::{NoProgress, Progress};

/// Receives a report's lines ("sunrise: reference from the cache") and the progress of its
/// long steps (bakes, references).
pub trait Observer: Sync {
    /// One line of what the report is doing or found.
    fn line(&self, _text: &str) {}
    /// Progress of a long step named `what` ("baking", "reference").
    fn progress(&self, _what: &str) -> Box<dyn Progress + '_> {
        Box::new(NoProgress)
    }
}

/// An observer that keeps nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {}
