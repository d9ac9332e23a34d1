//! A one-machine command line as an array task's and a merge's.

use super::{SlurmError, SlurmJob};
use std::path::PathBuf;

/// The two commands of a sharded job (hprt's arguments, without the program): each array
/// task's, and the merge's.
#[derive(Debug, Clone, PartialEq)]
pub struct JobCommands {
    /// Where the shards, scripts and logs go (`-o`'s path with `.shards` added).
    pub dir: PathBuf,
    pub task: Vec<String>,
    pub merge: Vec<String>,
}

impl JobCommands {
    /// The commands of `job` run as `shards` shards, from `args`, the job's own arguments as
    /// on one machine (checked by the caller: they are passed on as they are); `-o` names the
    /// merged result.
    pub fn new(job: SlurmJob, mut args: Vec<String>, shards: u32) -> Result<Self, SlurmError> {
        let shard = vec!["--shard".to_owned(), format!("auto/{shards}")];
        let output = take_value(&mut args, &["-o", "--output"]).ok_or(SlurmError::NoOutput(job))?;
        let dir = PathBuf::from(format!("{output}.shards"));
        let dir_text = dir.display().to_string();
        let words = |list: &[&str]| list.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
        Ok(match job {
            SlurmJob::Bake => {
                let task = [words(&["bake"]), args, shard, words(&["-o", &dir_text])].concat();
                let merge = words(&["bake", "merge", &dir_text, "-o", &output]);
                JobCommands { dir, task, merge }
            }
            SlurmJob::Reference => {
                // The images' options belong to the merge, which writes them.
                let mut merge = words(&["reference", "merge", &dir_text, "-o", &output]);
                for names in [&["--png"][..], &["--aux"], &["--exposure"]] {
                    if let Some(v) = take_value(&mut args, names) {
                        merge.extend([names[0].to_owned(), v]);
                    }
                }
                let task = [
                    words(&["reference"]),
                    args,
                    shard,
                    words(&["-o", &dir_text]),
                ]
                .concat();
                JobCommands { dir, task, merge }
            }
            SlurmJob::Report => {
                let task = [words(&["report"]), args.clone(), shard].concat();
                let merge = [words(&["report"]), args, words(&["-o", &output])].concat();
                JobCommands { dir, task, merge }
            }
        })
    }
}

/// Removes option `names` (given as `-o X`, `--output X` or `--output=X`) from `args`,
/// returning its value.
fn take_value(args: &mut Vec<String>, names: &[&str]) -> Option<String> {
    let mut found = None;
    let mut i = 0;
    while i < args.len() {
        let arg = &args[i];
        if names.contains(&arg.as_str()) && i + 1 < args.len() {
            found = Some(args[i + 1].clone());
            args.drain(i..i + 2);
            continue;
        }
        if let Some(v) = names
            .iter()
            .find_map(|n| arg.strip_prefix(&format!("{n}=")))
        {
            found = Some(v.to_owned());
            args.remove(i);
            continue;
        }
        i += 1;
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(words: &[&str]) -> Vec<String> {
        words.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn jobs_shard_and_merge_the_same_command() {
        let c = JobCommands::new(
            SlurmJob::Reference,
            strings(&["s.toml", "--spp", "8", "-o", "r.exr", "--png", "r.png"]),
            3,
        )
        .unwrap();
        assert_eq!(
            c.task,
            strings(&[
                "reference",
                "s.toml",
                "--spp",
                "8",
                "--shard",
                "auto/3",
                "-o",
                "r.exr.shards"
            ])
        );
        assert_eq!(
            c.merge,
            strings(&[
                "reference",
                "merge",
                "r.exr.shards",
                "-o",
                "r.exr",
                "--png",
                "r.png"
            ])
        );
        let c =
            JobCommands::new(SlurmJob::Bake, strings(&["s.toml", "--output=b.bake"]), 2).unwrap();
        assert_eq!(
            c.merge,
            strings(&["bake", "merge", "b.bake.shards", "-o", "b.bake"])
        );
        let c = JobCommands::new(SlurmJob::Report, strings(&["s.toml", "-o", "out"]), 4).unwrap();
        assert_eq!(c.task, strings(&["report", "s.toml", "--shard", "auto/4"]));
        assert_eq!(c.merge, strings(&["report", "s.toml", "-o", "out"]));
    }

    #[test]
    fn a_job_without_its_result_is_refused() {
        let error = JobCommands::new(SlurmJob::Bake, strings(&["s.toml"]), 2).unwrap_err();
        assert_eq!(
            error.to_string(),
            "hprt slurm bake needs -o (the merged result)"
        );
    }
}
