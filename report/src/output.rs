//! Where a report may be written: never into a folder that holds what it reads (the output
//! folder is replaced whole, so an input inside it would be lost).

use crate::error::{ReportError, Result};
use foundation::scene::Scene;
use std::path::Path;

/// Refuses `folder` (given as `option`) when it holds any of `inputs`.
pub fn check_folder_spares_inputs(
    inputs: &[&Path],
    option: &'static str,
    folder: &Path,
) -> Result<()> {
    let Ok(folder_real) = folder.canonicalize() else {
        return Ok(()); // not there yet: it holds nothing
    };
    for input in inputs {
        if input
            .canonicalize()
            .is_ok_and(|input| input.starts_with(&folder_real))
        {
            return Err(ReportError::OutputHoldsInput {
                option,
                folder: folder.to_owned(),
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Every file `scene` reads (its sources, map and probes), with `other` inputs.
pub fn scene_inputs<'a>(scene: &'a Scene, other: &[Option<&'a Path>]) -> Vec<&'a Path> {
    scene.inputs(other)
}
