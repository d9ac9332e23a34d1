//! `hprt slurm bake|reference|report ARGS... --shards N`: the sharded job as a Slurm array
//! job (`--shard auto/N`, each task its share) and a merge job that runs when every task
//! succeeded (`--dependency=afterok`), written beside the shards and submitted with `sbatch`
//! (`foundation::infra::slurm`). hprt schedules nothing itself.

use anyhow::Context;
use clap::Parser;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use foundation::infra::slurm::{ArrayJob, JobCommands, SlurmJob};

/// hprt slurm's own options, taken from anywhere in its arguments; the rest are the job's.
#[derive(Debug, Default, PartialEq)]
struct SlurmOptions {
    shards: Option<u32>,
    partition: Option<String>,
    sbatch: Vec<String>,
    dry_run: bool,
}

#[derive(clap::Args)]
pub struct SlurmArgs {
    /// bake, reference or report, with its own arguments as on one machine (`-o` names the
    /// merged result), and anywhere among them: --shards N (array tasks), --partition P,
    /// --sbatch "EXTRA OPTIONS" (added to both sbatch calls), --dry-run (print the job
    /// scripts and the sbatch calls, write and submit nothing).
    #[arg(value_parser = PossibleValuesParser::new(SlurmJob::ALL.map(SlurmJob::name))
        .try_map(|name| name.parse::<SlurmJob>()))]
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

/// Parses `hprt NAME ARGS` with hprt's own parser, so a typo fails now, not on the cluster.
fn check_parses(job: SlurmJob, args: &[String]) -> anyhow::Result<()> {
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
    let name = job.name();
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

pub fn run(args: SlurmArgs) -> anyhow::Result<()> {
    let (options, rest) = take_options(&args.args)?;
    let shards = options
        .shards
        .context("hprt slurm needs --shards N (the array job's tasks)")?;
    // The arguments must parse as the one-machine command does.
    check_parses(args.job, &rest)?;
    let job = ArrayJob {
        job: args.job,
        commands: JobCommands::new(args.job, rest, shards)?,
        shards,
        partition: options.partition,
        sbatch: options.sbatch,
        hprt: std::env::current_exe().context("cannot find this hprt's own path")?,
        workdir: std::env::current_dir().context("cannot read the current folder")?,
    };
    let scripts = job.scripts()?;
    if options.dry_run {
        print!("{}", scripts.dry_run()?);
        return Ok(());
    }
    let submitted = scripts.submit()?;
    println!(
        "submitted the array job {} ({shards} tasks) and the merge job {} \
         (after every task succeeded); logs in {}",
        submitted.array,
        submitted.merge,
        scripts.dir.display()
    );
    println!("{} {}", submitted.array, submitted.merge);
    Ok(())
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
    fn a_typo_in_the_jobs_arguments_fails_here_not_on_the_cluster() {
        assert!(
            check_parses(
                SlurmJob::Bake,
                &strings(&["s.toml", "-o", "b", "--samples", "3"])
            )
            .is_ok()
        );
        assert!(
            check_parses(
                SlurmJob::Bake,
                &strings(&["s.toml", "-o", "b", "--sample", "3"])
            )
            .is_err()
        );
    }
}
