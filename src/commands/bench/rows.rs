//! What every benchmark command shares: its rows printed as they are measured, and the
//! program the benchmarks that time whole commands run.

use anyhow::Context;

/// Hands each row to `F` (which prints it) as the benchmark measures it.
pub(super) struct Rows<F>(pub(super) F);

impl<R, F: Fn(&R) + Sync> bench::Reporter<R> for Rows<F> {
    fn row(&self, row: &R) {
        (self.0)(row)
    }
}

/// This hprt, which the benchmarks that time whole commands run.
pub(super) fn this_program() -> anyhow::Result<std::path::PathBuf> {
    std::env::current_exe().context("cannot find this hprt's own path")
}
