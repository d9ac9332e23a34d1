//! Writing the scripts and submitting them.

use super::script::dependency;
use super::{BatchScript, JobScripts, SlurmError};
use crate::infra::atomic_file::write_atomic;
use std::path::Path;

/// A Slurm job's id, as `sbatch --parsable` printed it (without a cluster name).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobId(pub String);

impl std::fmt::Display for JobId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// The two jobs a submission queued.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Submitted {
    pub array: JobId,
    /// The merge, held until every task of the array succeeded.
    pub merge: JobId,
}

impl JobScripts {
    /// Writes both scripts into the shards' folder (created if missing), each atomically.
    pub fn write(&self) -> Result<(), SlurmError> {
        create_folder(&self.dir)?;
        for script in [&self.array, &self.merge] {
            write_atomic(&script.path, script.text.as_bytes()).map_err(|source| {
                SlurmError::Write {
                    path: script.path.clone(),
                    source,
                }
            })?;
        }
        Ok(())
    }

    /// Writes the scripts and submits them with `sbatch` (found on the `PATH`): the array
    /// job, then the merge, held until every task succeeded.
    pub fn submit(&self) -> Result<Submitted, SlurmError> {
        self.write()?;
        let array = sbatch(&self.array, None)?;
        let merge = sbatch(&self.merge, Some(dependency(&array.0)))?;
        Ok(Submitted { array, merge })
    }
}

fn create_folder(dir: &Path) -> Result<(), SlurmError> {
    if dir.exists() && !dir.is_dir() {
        return Err(SlurmError::NotAFolder(dir.to_path_buf()));
    }
    std::fs::create_dir_all(dir).map_err(|source| SlurmError::CreateFolder {
        path: dir.to_path_buf(),
        source,
    })
}

/// Submits `script`, returning the job id `sbatch --parsable` prints.
fn sbatch(script: &BatchScript, extra: Option<String>) -> Result<JobId, SlurmError> {
    let output = std::process::Command::new("sbatch")
        .args(&script.options)
        .args(extra)
        .arg(&script.path)
        .output()
        .map_err(SlurmError::RunSbatch)?;
    if !output.status.success() {
        return Err(SlurmError::SbatchFailed {
            script: script.path.clone(),
            stderr: String::from_utf8_lossy(&output.stderr).trim().to_owned(),
        });
    }
    let text = String::from_utf8_lossy(&output.stdout);
    job_id(&text).ok_or_else(|| SlurmError::NotAJobId {
        script: script.path.clone(),
        printed: text.trim().to_owned(),
    })
}

/// The job id in what `sbatch --parsable` printed: `ID` or `ID;CLUSTER`.
pub(super) fn job_id(printed: &str) -> Option<JobId> {
    let id = printed.trim().split(';').next().unwrap_or_default();
    (!id.is_empty() && id.chars().all(|c| c.is_ascii_digit())).then(|| JobId(id.to_owned()))
}
