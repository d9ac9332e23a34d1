//! Slurm: a sharded job (a bake, a reference, a report) as an array job whose tasks each run
//! their shard (`--shard auto/N`) and a merge job that runs when every task succeeded
//! (`--dependency=afterok`). This module writes the two batch scripts beside the shards and
//! submits them with `sbatch`; it schedules nothing itself.
//!
//! [`JobCommands::new`] turns a one-machine command line into the task's and the merge's,
//! [`ArrayJob::scripts`] renders the scripts and the sbatch calls, and [`JobScripts`] prints,
//! writes or submits them.

mod commands;
mod script;
mod submit;

pub use commands::JobCommands;
pub use script::{BatchScript, JobScripts};
pub use submit::{JobId, Submitted};

use std::path::PathBuf;

crate::named_enum! {
    /// Which sharded job.
    pub enum SlurmJob ("job") {
        Bake = "bake",
        Reference = "reference",
        Report = "report",
    }
}

/// A job to submit: its commands and what sbatch is told.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayJob {
    pub job: SlurmJob,
    pub commands: JobCommands,
    /// The array's tasks, one shard each.
    pub shards: u32,
    /// `--partition` for both jobs.
    pub partition: Option<String>,
    /// More sbatch options, given to both jobs.
    pub sbatch: Vec<String>,
    /// The hprt program the jobs run.
    pub hprt: PathBuf,
    /// The folder the jobs run in, and that the commands' relative paths start from.
    pub workdir: PathBuf,
}

/// A path [`ArrayJob::scripts`] gives to Slurm, named in its errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlurmPath {
    WorkingFolder,
    ShardsFolder,
}

impl std::fmt::Display for SlurmPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SlurmPath::WorkingFolder => "the working folder",
            SlurmPath::ShardsFolder => "the shards' folder",
        })
    }
}

/// Why a job cannot be written or submitted.
#[derive(Debug, thiserror::Error)]
pub enum SlurmError {
    #[error("hprt slurm {0} needs -o (the merged result)")]
    NoOutput(SlurmJob),
    #[error("{word:?} cannot be written in a shell script")]
    Unquotable { word: String },
    #[error("{what} {} is not UTF-8, which Slurm cannot be given", path.display())]
    NotUtf8 { what: SlurmPath, path: PathBuf },
    #[error(
        "{what} {text:?} holds {found:?}, which Slurm would misread in a job's working folder \
         or log path; use a folder and an -o path without it"
    )]
    Misread {
        what: SlurmPath,
        text: String,
        found: char,
    },
    #[error("{} exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    #[error("cannot create the folder {}", path.display())]
    CreateFolder {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot run sbatch (is Slurm installed and on the PATH?)")]
    RunSbatch(#[source] std::io::Error),
    /// sbatch failed; `stderr` is what it said.
    #[error("sbatch {} failed: {stderr}", script.display())]
    SbatchFailed { script: PathBuf, stderr: String },
    /// sbatch succeeded but printed no job id; `printed` is what it printed.
    #[error("sbatch {} printed {printed:?}, not a job id", script.display())]
    NotAJobId { script: PathBuf, printed: String },
}

#[cfg(test)]
mod tests;
