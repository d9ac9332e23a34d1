//! `hprt slurm bake|reference|report ARGS... --shards N`: the sharded job as a Slurm array
//! job (`--shard auto/N`, each task its share) and a merge job that runs when every task
//! succeeded (`--dependency=afterok`), written beside the shards and submitted with `sbatch`.
//! hprt schedules nothing itself.

use anyhow::Context;
use clap::{Parser, ValueEnum};
use std::path::{Path, PathBuf};

/// hprt slurm's own options, taken from anywhere in its arguments; the rest are the job's.
#[derive(Debug, Default, PartialEq)]
struct SlurmOptions {
    shards: Option<u32>,
    partition: Option<String>,
    sbatch: Vec<String>,
    dry_run: bool,
}

/// Which sharded job.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SlurmJob {
    Bake,
    Reference,
    Report,
}

#[derive(clap::Args)]
pub struct SlurmArgs {
    /// bake, reference or report, with its own arguments as on one machine (`-o` names the
    /// merged result), and anywhere among them: --shards N (array tasks), --partition P,
    /// --sbatch "EXTRA OPTIONS" (added to both sbatch calls), --dry-run (print the job
    /// scripts and the sbatch calls, write and submit nothing).
    pub job: SlurmJob,
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0..)]
    pub args: Vec<String>,
}

/// Splits hprt slurm's options out of `args`.
fn take_options(args: &[String]) -> anyhow::Result<(SlurmOptions, Vec<String>)> {
    let mut options = SlurmOptions::default();
    let mut rest = Vec::new();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let (name, inline) = match arg.split_once('=') {
            Some((n, v)) if n.starts_with("--") => (n, Some(v.to_owned())),
            _ => (arg.as_str(), None),
        };
        let mut value = |name: &str| -> anyhow::Result<String> {
            inline
                .clone()
                .or_else(|| it.next().cloned())
                .with_context(|| format!("{name} needs a value"))
        };
        match name {
            "--shards" => {
                let text = value(name)?;
                let n: u32 = text
                    .parse()
                    .ok()
                    .filter(|n| (1..=foundation::infra::shard::MAX_SHARDS).contains(n))
                    .with_context(|| format!("--shards must be 1 to 100000, got {text:?}"))?;
                options.shards = Some(n);
            }
            "--partition" => options.partition = Some(value(name)?),
            "--sbatch" => {
                let text = value(name)?;
                options.sbatch = shlex::split(&text)
                    .with_context(|| format!("--sbatch {text:?}: unbalanced quotes"))?;
            }
            "--dry-run" => options.dry_run = true,
            _ => rest.push(arg.clone()),
        }
    }
    Ok((options, rest))
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

/// The two commands of a sharded job: each array task's, and the merge's.
#[derive(Debug, PartialEq)]
struct JobCommands {
    /// Where the shards, scripts and logs go.
    dir: PathBuf,
    task: Vec<String>,
    merge: Vec<String>,
}

/// Checks `args` as the job's own command line and builds its two commands.
fn job_commands(job: SlurmJob, mut args: Vec<String>, shards: u32) -> anyhow::Result<JobCommands> {
    let name = job
        .to_possible_value()
        .map(|v| v.get_name().to_owned())
        .unwrap_or_default();
    // The arguments must parse as the one-machine command does.
    check_parses(&name, &args)?;
    let shard = vec!["--shard".to_owned(), format!("auto/{shards}")];
    let output = take_value(&mut args, &["-o", "--output"])
        .with_context(|| format!("hprt slurm {name} needs -o (the merged result)"))?;
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

/// Parses `hprt NAME ARGS` with hprt's own parser, so a typo fails now, not on the cluster.
fn check_parses(name: &str, args: &[String]) -> anyhow::Result<()> {
    #[derive(Parser)]
    #[command(name = "hprt")]
    struct Check {
        #[command(subcommand)]
        command: Commands,
    }
    #[derive(clap::Subcommand)]
    enum Commands {
        Bake(super::bake::BakeArgs),
        Reference(super::reference::ReferenceArgs),
        Report(super::report::ReportArgs),
    }
    let argv = ["hprt", name]
        .into_iter()
        .map(str::to_owned)
        .chain(args.iter().cloned());
    Check::try_parse_from(argv).map_err(|e| {
        let message = e.render().to_string();
        anyhow::anyhow!("hprt {name}: {}", message.trim_start_matches("error: "))
    })?;
    Ok(())
}

fn quote(word: &str) -> anyhow::Result<String> {
    Ok(shlex::try_quote(word)
        .with_context(|| format!("{word:?} cannot be written in a shell script"))?
        .into_owned())
}

/// `words` as one shell command line, each quoted: what `--dry-run` prints can be pasted into
/// a shell and runs exactly these words, whatever they hold.
fn command_line(words: &[String]) -> anyhow::Result<String> {
    Ok(words
        .iter()
        .map(|w| quote(w))
        .collect::<anyhow::Result<Vec<_>>>()?
        .join(" "))
}

/// Refuses a path Slurm itself would misread: Slurm takes `%` in a log path as a pattern and
/// a `\` as "no patterns", and a control character (a newline) has no safe form in its
/// options. `what` names the path for the message.
fn check_slurm_path(what: &str, path: &Path) -> anyhow::Result<()> {
    let text = path.to_str().with_context(|| {
        format!(
            "{what} {} is not UTF-8, which Slurm cannot be given",
            path.display()
        )
    })?;
    if let Some(c) = text
        .chars()
        .find(|c| c.is_control() || matches!(c, '%' | '\\'))
    {
        anyhow::bail!(
            "{what} {text:?} holds {c:?}, which Slurm would misread in a job's working folder \
             or log path; use a folder and an -o path without it"
        );
    }
    Ok(())
}

/// How one batch job is submitted: its script, and the options that say where it runs and
/// logs (given to sbatch as arguments, never written into the script, so no path can become
/// a line of it).
struct Submission {
    script: String,
    /// `--output=LOG` and `--chdir=WORKDIR`.
    placement: Vec<String>,
}

/// A batch script running `hprt ARGS` from `workdir`, its log in `dir`.
fn script(
    hprt: &Path,
    workdir: &Path,
    dir: &Path,
    name: &str,
    array: Option<u32>,
    command: &[String],
) -> anyhow::Result<Submission> {
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
    lines.push(format!("cd -- {}", quote(&workdir.display().to_string())?));
    let words: Vec<String> = std::iter::once(hprt.display().to_string())
        .chain(command.iter().cloned())
        .collect();
    lines.push(format!("exec {}", command_line(&words)?));
    Ok(Submission {
        script: lines.join("\n") + "\n",
        placement: vec![
            format!("--output={}", log.display()),
            format!("--chdir={}", workdir.display()),
        ],
    })
}

pub fn run(args: SlurmArgs) -> anyhow::Result<()> {
    let (options, rest) = take_options(&args.args)?;
    let shards = options
        .shards
        .context("hprt slurm needs --shards N (the array job's tasks)")?;
    let commands = job_commands(args.job, rest, shards)?;
    let hprt = std::env::current_exe().context("cannot find this hprt's own path")?;
    let workdir = std::env::current_dir().context("cannot read the current folder")?;
    let dir = workdir.join(&commands.dir);
    check_slurm_path("the working folder", &workdir)?;
    check_slurm_path("the shards' folder", &dir)?;
    let name = format!("{:?}", args.job).to_lowercase();
    let task = script(&hprt, &workdir, &dir, &name, Some(shards), &commands.task)?;
    let merge = script(
        &hprt,
        &workdir,
        &dir,
        &format!("{name}-merge"),
        None,
        &commands.merge,
    )?;
    let (task_path, merge_path) = (dir.join("array.sbatch"), dir.join("merge.sbatch"));
    let mut common = vec!["--parsable".to_owned()];
    if let Some(p) = &options.partition {
        common.push(format!("--partition={p}"));
    }
    common.extend(options.sbatch.iter().cloned());
    let task_call = [common.clone(), task.placement.clone()].concat();
    let merge_call = [common, merge.placement.clone()].concat();
    if options.dry_run {
        return print_dry_run(
            (&task_path, &task, &task_call),
            (&merge_path, &merge, &merge_call),
        );
    }
    crate::support::create_folder(&dir)?;
    for (path, text) in [(&task_path, &task.script), (&merge_path, &merge.script)] {
        foundation::infra::atomic_file::write_atomic(path, text.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let array_id = sbatch(&task_call, &task_path)?;
    let dependency = format!("--dependency=afterok:{array_id}");
    let merge_id = sbatch(&[merge_call, vec![dependency]].concat(), &merge_path)?;
    println!(
        "submitted the array job {array_id} ({shards} tasks) and the merge job {merge_id} \
         (after every task succeeded); logs in {}",
        dir.display()
    );
    println!("{array_id} {merge_id}");
    Ok(())
}

/// What `--dry-run` prints: each script, then the two sbatch calls as quoted command lines.
fn print_dry_run(
    (task_path, task, task_call): (&Path, &Submission, &[String]),
    (merge_path, merge, merge_call): (&Path, &Submission, &[String]),
) -> anyhow::Result<()> {
    let call = |options: &[String], extra: &[&str], script: &Path| {
        let words: Vec<String> = std::iter::once("sbatch".to_owned())
            .chain(options.iter().cloned())
            .chain(extra.iter().map(|w| (*w).to_owned()))
            .chain(std::iter::once(script.display().to_string()))
            .collect();
        command_line(&words)
    };
    // The scripts are shown as comments, one `# ` per line: pasting the whole output into a
    // shell runs only the two sbatch calls.
    let commented = |text: &str| {
        text.lines()
            .map(|l| format!("# {l}"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    for (path, submission) in [(task_path, task), (merge_path, merge)] {
        println!("{}", commented(&path.display().to_string()));
        println!("{}", commented(&submission.script));
    }
    println!("{}", call(task_call, &[], task_path)?);
    println!(
        "{}",
        call(
            merge_call,
            &["--dependency=afterok:ARRAY_JOB_ID"],
            merge_path
        )?
    );
    Ok(())
}

/// Submits `script`, returning the job id `sbatch --parsable` prints (`ID` or `ID;CLUSTER`).
fn sbatch(options: &[String], script: &Path) -> anyhow::Result<String> {
    let output = std::process::Command::new("sbatch")
        .args(options)
        .arg(script)
        .output()
        .context("cannot run sbatch (is Slurm installed and on the PATH?)")?;
    anyhow::ensure!(
        output.status.success(),
        "sbatch {} failed: {}",
        script.display(),
        String::from_utf8_lossy(&output.stderr).trim()
    );
    let text = String::from_utf8_lossy(&output.stdout);
    let id = text.trim().split(';').next().unwrap_or_default().to_owned();
    anyhow::ensure!(
        !id.is_empty() && id.chars().all(|c| c.is_ascii_digit()),
        "sbatch {} printed {:?}, not a job id",
        script.display(),
        text.trim()
    );
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(words: &[&str]) -> Vec<String> {
        words.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn slurm_options_come_out_of_the_job_arguments() {
        let (options, rest) = take_options(&strings(&[
            "scene.toml",
            "--shards",
            "4",
            "-o",
            "x.bake",
            "--sbatch=--time=10 --mem=2G",
            "--dry-run",
            "--samples",
            "64",
        ]))
        .unwrap();
        assert_eq!(options.shards, Some(4));
        assert_eq!(options.sbatch, strings(&["--time=10", "--mem=2G"]));
        assert!(options.dry_run);
        assert_eq!(
            rest,
            strings(&["scene.toml", "-o", "x.bake", "--samples", "64"])
        );
        assert!(take_options(&strings(&["--shards", "0"])).is_err());
        assert!(take_options(&strings(&["--shards"])).is_err());
    }

    #[test]
    fn jobs_shard_and_merge_the_same_command() {
        let c = job_commands(
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
        let c = job_commands(SlurmJob::Bake, strings(&["s.toml", "--output=b.bake"]), 2).unwrap();
        assert_eq!(
            c.merge,
            strings(&["bake", "merge", "b.bake.shards", "-o", "b.bake"])
        );
        // A typo fails here, not on the cluster.
        assert!(
            job_commands(
                SlurmJob::Bake,
                strings(&["s.toml", "-o", "b", "--sample", "3"]),
                2
            )
            .is_err()
        );
        assert!(job_commands(SlurmJob::Bake, strings(&["s.toml"]), 2).is_err());
    }
}
