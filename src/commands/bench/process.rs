//! Another hprt run as a child process, timed, with its peak memory (`wait4`).

use anyhow::Context;
use std::time::Instant;

/// One process's cost.
pub(super) struct Run {
    pub(super) seconds: f64,
    pub(super) peak_mib: f64,
}

/// Runs this hprt with `args`, returning its wall time and peak resident memory.
pub(super) fn run_hprt(args: &[String]) -> anyhow::Result<Run> {
    let exe = std::env::current_exe().context("cannot find this hprt's own path")?;
    let start = Instant::now();
    let child = std::process::Command::new(exe)
        .args(args)
        .stdout(std::process::Stdio::null())
        .spawn()
        .context("cannot start hprt")?;
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: rusage is plain data the call fills; pid is our own child, waited for once.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    let seconds = start.elapsed().as_secs_f64();
    anyhow::ensure!(waited == pid, "cannot wait for hprt {}", args.join(" "));
    anyhow::ensure!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "hprt {} failed",
        args.join(" ")
    );
    Ok(Run {
        seconds,
        // Linux reports ru_maxrss in KiB.
        peak_mib: usage.ru_maxrss as f64 / 1024.0,
    })
}
