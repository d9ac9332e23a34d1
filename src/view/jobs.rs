//! Work the viewer hands to a thread of its own (bakes, the room's opening, the empty room's
//! picture) so that the window never waits: polled once a frame, with its progress in the
//! panel.

use foundation::infra::progress::{Progress, SharedProgress};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};

/// A piece of work running on its own thread.
pub(super) struct Job<T> {
    /// What it is doing, for the panel ("baking the proxies alone").
    pub(super) what: &'static str,
    pub(super) progress: Arc<SharedProgress>,
    result: Receiver<anyhow::Result<T>>,
}

impl<T: Send + 'static> Job<T> {
    /// Starts `work` on a new thread, its progress kept for the panel.
    pub(super) fn start(
        what: &'static str,
        work: impl FnOnce(&dyn Progress) -> anyhow::Result<T> + Send + 'static,
    ) -> Self {
        let progress = Arc::new(SharedProgress::default());
        let shared = Arc::clone(&progress);
        let (sender, result) = channel();
        std::thread::spawn(move || {
            // The receiver may be gone (the work was superseded): nothing to tell.
            let _ = sender.send(work(shared.as_ref()));
        });
        Self {
            what,
            progress,
            result,
        }
    }

    /// The work's result once it is done (`None` while it runs).
    pub(super) fn poll(&self) -> Option<anyhow::Result<T>> {
        match self.result.try_recv() {
            Ok(result) => Some(result),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(anyhow::anyhow!(
                "{} stopped without a result",
                self.what
            ))),
        }
    }
}

/// A report's (or the room's) observer on a job's thread: its lines printed as on the
/// command line, its long steps' progress into the job's.
pub(super) struct JobObserver<'a>(pub(super) &'a dyn Progress);

impl report::Observer for JobObserver<'_> {
    fn line(&self, text: &str) {
        println!("{text}");
    }

    fn progress(&self, _what: &str) -> Box<dyn Progress + '_> {
        Box::new(self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_reports_its_result_once_done() {
        let job = Job::start("counting", |progress| {
            progress.start(2);
            progress.advance(2);
            Ok(41 + 1)
        });
        let result = loop {
            if let Some(result) = job.poll() {
                break result;
            }
            std::thread::yield_now();
        };
        assert_eq!(result.unwrap(), 42);
        assert_eq!(job.progress.fraction(), 1.0);
    }

    #[test]
    fn a_failing_job_reports_its_error() {
        let job: Job<()> = Job::start("failing", |_| anyhow::bail!("no"));
        let result = loop {
            if let Some(result) = job.poll() {
                break result;
            }
            std::thread::yield_now();
        };
        assert_eq!(result.unwrap_err().to_string(), "no");
    }
}
