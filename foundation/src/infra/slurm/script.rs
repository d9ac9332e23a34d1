//! The batch scripts and the sbatch calls, as text.

use super::{ArrayJob, SlurmError, SlurmPath};
use std::path::{Path, PathBuf};

/// One batch job: its script, and how sbatch is called for it.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchScript {
    /// Where the script is written.
    pub path: PathBuf,
    pub text: String,
    /// sbatch's options (the script's path follows them): `--parsable`, the partition, the
    /// extra options, then where the job runs and logs (`--output=LOG`, `--chdir=WORKDIR`:
    /// given as options, never written into the script, so no path can become a line of it).
    pub options: Vec<String>,
}

/// The array job's script and the merge's, in the shards' folder.
#[derive(Debug, Clone, PartialEq)]
pub struct JobScripts {
    /// The shards' folder, where the scripts and the logs go.
    pub dir: PathBuf,
    pub array: BatchScript,
    pub merge: BatchScript,
}

/// The option that holds the merge until every task succeeded.
pub(super) fn dependency(array_id: &str) -> String {
    format!("--dependency=afterok:{array_id}")
}

impl ArrayJob {
    /// The two scripts and their sbatch calls; refuses a working folder or a shards' folder
    /// Slurm would misread, and a word no shell script can hold.
    pub fn scripts(&self) -> Result<JobScripts, SlurmError> {
        let dir = self.workdir.join(&self.commands.dir);
        check_slurm_path(SlurmPath::WorkingFolder, &self.workdir)?;
        check_slurm_path(SlurmPath::ShardsFolder, &dir)?;
        let name = self.job.name();
        let mut common = vec!["--parsable".to_owned()];
        if let Some(p) = &self.partition {
            common.push(format!("--partition={p}"));
        }
        common.extend(self.sbatch.iter().cloned());
        let script = |name: &str, array: Option<u32>, command: &[String], file: &str| {
            let (text, placement) = self.script(&dir, name, array, command)?;
            Ok::<_, SlurmError>(BatchScript {
                path: dir.join(file),
                text,
                options: [common.clone(), placement].concat(),
            })
        };
        let array = script(name, Some(self.shards), &self.commands.task, "array.sbatch")?;
        let merge = script(
            &format!("{name}-merge"),
            None,
            &self.commands.merge,
            "merge.sbatch",
        )?;
        Ok(JobScripts { dir, array, merge })
    }

    /// A batch script running `hprt COMMAND` from the working folder, its log in `dir`, and
    /// the sbatch options that place it.
    fn script(
        &self,
        dir: &Path,
        name: &str,
        array: Option<u32>,
        command: &[String],
    ) -> Result<(String, Vec<String>), SlurmError> {
        let log = match array {
            Some(_) => dir.join(format!("{name}-%A_%a.log")),
            None => dir.join(format!("{name}-%j.log")),
        };
        let mut lines = vec![
            "#!/bin/bash".to_owned(),
            format!("#SBATCH --job-name=hprt-{name}"),
        ];
        if let Some(n) = array {
            lines.push(format!("#SBATCH --array=0-{}", n - 1));
        }
        lines.push("set -euo pipefail".to_owned());
        lines.push(format!(
            "cd -- {}",
            quote(&self.workdir.display().to_string())?
        ));
        let words: Vec<String> = std::iter::once(self.hprt.display().to_string())
            .chain(command.iter().cloned())
            .collect();
        lines.push(format!("exec {}", command_line(&words)?));
        let placement = vec![
            format!("--output={}", log.display()),
            format!("--chdir={}", self.workdir.display()),
        ];
        Ok((lines.join("\n") + "\n", placement))
    }
}

impl JobScripts {
    /// What a dry run shows: each script's path and text as comments, one `# ` per line,
    /// then the two sbatch calls as quoted command lines, so that pasting the whole text into
    /// a shell runs exactly those two calls, whatever their words hold. Each line ends in a
    /// newline.
    pub fn dry_run(&self) -> Result<String, SlurmError> {
        let commented = |text: &str| {
            let lines: Vec<String> = text.lines().map(|l| format!("# {l}")).collect();
            lines.join("\n") + "\n"
        };
        let mut out = String::new();
        for script in [&self.array, &self.merge] {
            out += &commented(&script.path.display().to_string());
            out += &commented(&script.text);
        }
        out += &sbatch_line(&self.array, None)?;
        out += &sbatch_line(&self.merge, Some(&dependency("ARRAY_JOB_ID")))?;
        Ok(out)
    }
}

/// `sbatch OPTIONS [EXTRA] SCRIPT` as a quoted command line, with its newline.
fn sbatch_line(script: &BatchScript, extra: Option<&str>) -> Result<String, SlurmError> {
    let words: Vec<String> = std::iter::once("sbatch".to_owned())
        .chain(script.options.iter().cloned())
        .chain(extra.map(str::to_owned))
        .chain(std::iter::once(script.path.display().to_string()))
        .collect();
    Ok(command_line(&words)? + "\n")
}

fn quote(word: &str) -> Result<String, SlurmError> {
    Ok(shlex::try_quote(word)
        .map_err(|_| SlurmError::Unquotable {
            word: word.to_owned(),
        })?
        .into_owned())
}

/// `words` as one shell command line, each quoted: it runs exactly these words, whatever they
/// hold.
fn command_line(words: &[String]) -> Result<String, SlurmError> {
    Ok(words
        .iter()
        .map(|w| quote(w))
        .collect::<Result<Vec<_>, _>>()?
        .join(" "))
}

/// Refuses a path Slurm itself would misread: Slurm takes `%` in a log path as a pattern and
/// a `\` as "no patterns", and a control character (a newline) has no safe form in its
/// options.
fn check_slurm_path(what: SlurmPath, path: &Path) -> Result<(), SlurmError> {
    let text = path.to_str().ok_or_else(|| SlurmError::NotUtf8 {
        what,
        path: path.to_path_buf(),
    })?;
    match text
        .chars()
        .find(|c| c.is_control() || matches!(c, '%' | '\\'))
    {
        Some(found) => Err(SlurmError::Misread {
            what,
            text: text.to_owned(),
            found,
        }),
        None => Ok(()),
    }
}
