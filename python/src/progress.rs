//! Progress of a bake or a reference render, forwarded to a Python callable
//! `progress(stage, done, total)` at most once per percent of each stage: the libraries report
//! from many threads, and each call must take the interpreter's lock.

use foundation::infra::progress::Progress;
use pyo3::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

pub(crate) struct PyProgress {
    callback: Py<PyAny>,
    stage: Mutex<String>,
    total: AtomicU64,
    done: AtomicU64,
    /// The last percent reported, plus one (0: none yet in this stage).
    reported: AtomicU64,
    /// The first exception the callback raised: raised when the work is over.
    error: Mutex<Option<PyErr>>,
}

impl PyProgress {
    pub(crate) fn new(callback: Py<PyAny>, stage: &str) -> Self {
        Self {
            callback,
            stage: Mutex::new(stage.to_owned()),
            total: AtomicU64::new(0),
            done: AtomicU64::new(0),
            reported: AtomicU64::new(0),
            error: Mutex::new(None),
        }
    }

    /// The callback's first exception, if it raised one.
    pub(crate) fn into_result(self) -> PyResult<()> {
        match self.error.into_inner() {
            Ok(Some(error)) => Err(error),
            _ => Ok(()),
        }
    }

    fn report(&self, done: u64, total: u64) {
        let percent = (done.min(total) * 100).checked_div(total).unwrap_or(0);
        let previous = self.reported.fetch_max(percent + 1, Ordering::Relaxed);
        if previous > percent {
            return;
        }
        let stage = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        Python::attach(|py| {
            if let Err(error) = self.callback.call1(py, (stage, done, total))
                && let Ok(mut slot) = self.error.lock()
            {
                slot.get_or_insert(error);
            }
        });
    }
}

impl Progress for PyProgress {
    fn start(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
        self.reported.store(0, Ordering::Relaxed);
        self.report(0, total);
    }

    fn advance(&self, steps: u64) {
        let done = self.done.fetch_add(steps, Ordering::Relaxed) + steps;
        self.report(done, self.total.load(Ordering::Relaxed));
    }

    fn status(&self, text: &str) {
        if let Ok(mut stage) = self.stage.lock() {
            *stage = text.to_owned();
        }
    }
}

/// Runs `work` with the callback's progress (or none), then raises what the callback raised.
pub(crate) fn with_progress<T>(
    callback: Option<Py<PyAny>>,
    stage: &str,
    work: impl FnOnce(&dyn Progress) -> T,
) -> PyResult<T> {
    match callback {
        None => Ok(work(&foundation::infra::progress::NoProgress)),
        Some(callback) => {
            let progress = PyProgress::new(callback, stage);
            let result = work(&progress);
            progress.into_result()?;
            Ok(result)
        }
    }
}
