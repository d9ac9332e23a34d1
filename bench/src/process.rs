//! Another hprt run as a child process, timed, with its peak memory (`wait4`).

use crate::error::{BenchError, Result};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// One process's cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Run {
    pub seconds: f64,
    /// Its maximum resident set, MiB.
    pub peak_mib: f64,
}

/// Runs the hprt at `program` with `args`, returning its wall time and peak resident memory.
pub(crate) fn run_hprt(program: &Path, args: &[String]) -> Result<Run> {
    let start = Instant::now();
    let child = std::process::Command::new(program)
        .args(args)
        .stdout(std::process::Stdio::null())
        .spawn()
        .map_err(BenchError::Start)?;
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: rusage is plain data the call fills; pid is our own child, waited for once.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    let seconds = start.elapsed().as_secs_f64();
    if waited != pid {
        return Err(BenchError::Wait(args.join(" ")));
    }
    if !(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0) {
        return Err(BenchError::Failed(args.join(" ")));
    }
    Ok(Run {
        seconds,
        // Linux reports ru_maxrss in KiB.
        peak_mib: usage.ru_maxrss as f64 / 1024.0,
    })
}
