//! What a command writes: checked by `foundation::infra::outputs` (never over an input, never
//! two outputs at one file), opened before the work and written all together, or none.

use anyhow::Context;
use foundation::infra::atomic_file::{AtomicOutput, commit_all};
pub use foundation::infra::outputs::{Output, check_folder_output, check_outputs};
pub use report::output::{check_folder_spares_inputs, scene_inputs};

/// Opens every given output (in order) before the work that fills them, so an unwritable one
/// fails first; [`write_outputs`] then writes them all together, or none.
pub fn open_outputs(outputs: &[Output]) -> anyhow::Result<Vec<AtomicOutput>> {
    outputs
        .iter()
        .filter_map(|(_, path)| *path)
        .map(|path| {
            AtomicOutput::create(path).with_context(|| format!("cannot write {}", path.display()))
        })
        .collect()
}

/// Writes `bytes` into the outputs [`open_outputs`] opened, in the same order, all or none.
pub fn write_outputs(files: Vec<AtomicOutput>, bytes: Vec<Vec<u8>>) -> anyhow::Result<()> {
    commit_all(files.into_iter().zip(bytes).collect()).context("cannot write the outputs")
}
