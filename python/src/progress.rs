//! The long calls (bakes, reference renders): their progress, forwarded to a Python callable
//! `progress(stage, done, total)` at most once per percent of each stage, and Ctrl-C.
//!
//! The work runs on a thread of its own while the calling (main) thread waits, checking for
//! signals every [`SIGNAL_POLL`]: CPython runs signal handlers on the main thread only, so a
//! check from the threads doing the work would never see one. When a handler raises
//! (`KeyboardInterrupt` for Ctrl-C), or the callback does, the progress answers
//! [`Progress::cancelled`], the libraries stop at their next check (a chunk of vertices, an
//! image row), and the call raises that exception.

use foundation::infra::progress::Progress;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyString};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

/// How often the waiting thread checks for signals (Ctrl-C).
const SIGNAL_POLL: Duration = Duration::from_millis(50);

pub(crate) struct PyProgress {
    callback: Option<Py<PyAny>>,
    stage: Mutex<String>,
    total: AtomicU64,
    done: AtomicU64,
    /// The last percent reported, plus one (0: none yet in this stage).
    reported: AtomicU64,
    /// Held while the callback runs (taken before the interpreter's lock): calls one at a time,
    /// each with the count as it is then, so a callback sees counts that never go down.
    calling: Mutex<()>,
    /// Set with the first `error`: the work should stop.
    stop: AtomicBool,
    /// The first exception raised (by a signal handler or the callback): raised when the work
    /// is over.
    error: Mutex<Option<PyErr>>,
}

impl PyProgress {
    fn new(callback: Option<Py<PyAny>>, stage: &str) -> Self {
        Self {
            callback,
            stage: Mutex::new(stage.to_owned()),
            total: AtomicU64::new(0),
            done: AtomicU64::new(0),
            reported: AtomicU64::new(0),
            calling: Mutex::new(()),
            stop: AtomicBool::new(false),
            error: Mutex::new(None),
        }
    }

    /// Keeps `error` (the first one only) and asks the work to stop.
    fn fail(&self, error: PyErr) {
        if let Ok(mut slot) = self.error.lock() {
            slot.get_or_insert(error);
        }
        self.stop.store(true, Ordering::Relaxed);
    }

    fn report(&self, total: u64) {
        let Some(callback) = &self.callback else {
            return;
        };
        let done = self.done.load(Ordering::Relaxed).min(total);
        let percent = (done * 100).checked_div(total).unwrap_or(0);
        let previous = self.reported.fetch_max(percent + 1, Ordering::Relaxed);
        if previous > percent {
            return;
        }
        let _calling = self.calling.lock();
        // The count now: at least what any earlier call was given.
        let done = self.done.load(Ordering::Relaxed).min(total);
        let stage = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        Python::attach(|py| {
            if let Err(error) = callback.call1(py, (stage, done, total)) {
                self.fail(error);
            }
        });
    }
}

impl Progress for PyProgress {
    fn start(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
        self.reported.store(0, Ordering::Relaxed);
        self.report(total);
    }

    fn advance(&self, steps: u64) {
        self.done.fetch_add(steps, Ordering::Relaxed);
        self.report(self.total.load(Ordering::Relaxed));
    }

    fn status(&self, text: &str) {
        if let Ok(mut stage) = self.stage.lock() {
            *stage = text.to_owned();
        }
    }

    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// The `progress=` argument: a callable, `"tqdm"` or `True` (bars drawn by
/// `hprt.TqdmProgress`, closed when the call ends), `None` or `False` (nothing shown).
fn callback(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Option<Py<PyAny>>, bool)> {
    let Some(progress) = progress.filter(|p| !p.is_none()) else {
        return Ok((None, false));
    };
    let tqdm = if let Ok(flag) = progress.cast::<PyBool>() {
        if !flag.is_true() {
            return Ok((None, false));
        }
        true
    } else if let Ok(name) = progress.cast::<PyString>() {
        if name.to_cow()? != "tqdm" {
            return Err(PyValueError::new_err(format!(
                "progress: {name:?} is no way of showing progress (\"tqdm\", True, or a callable \
                 progress(stage, done, total))"
            )));
        }
        true
    } else {
        false
    };
    if tqdm {
        let bars = py.import("hprt")?.getattr("TqdmProgress")?.call0()?;
        return Ok((Some(bars.unbind()), true));
    }
    if !progress.is_callable() {
        return Err(PyValueError::new_err(format!(
            "progress: expected a callable progress(stage, done, total), \"tqdm\" or True, got {}",
            progress.get_type().name()?
        )));
    }
    Ok((Some(progress.clone().unbind()), false))
}

/// Runs `work` on a thread of its own with the `progress=` argument's progress (see
/// [`callback`]), checking for signals meanwhile, then raises the first exception a signal
/// handler or the callback raised (the work having stopped early, see the module's notes).
pub(crate) fn with_progress<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    stage: &str,
    work: impl FnOnce(&dyn Progress) -> T + Send,
) -> PyResult<T> {
    let (callback, owned) = callback(py, progress)?;
    let progress = PyProgress::new(callback, stage);
    let waiting = std::thread::current();
    let result = std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            let result = work(&progress);
            waiting.unpark();
            result
        });
        while !worker.is_finished() {
            py.detach(|| std::thread::park_timeout(SIGNAL_POLL));
            if let Err(error) = py.check_signals() {
                progress.fail(error);
            }
        }
        worker.join()
    });
    let result = result.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
    if owned && let Some(bars) = &progress.callback {
        bars.call_method0(py, "close")?;
    }
    match progress.error.into_inner() {
        Ok(Some(error)) => Err(error),
        _ => Ok(result),
    }
}
