use super::submit::job_id;
use super::*;
use std::path::Path;

fn strings(words: &[&str]) -> Vec<String> {
    words.iter().map(|s| s.to_string()).collect()
}

fn bake_job(workdir: &str, output: &str) -> ArrayJob {
    ArrayJob {
        job: SlurmJob::Bake,
        commands: JobCommands::new(SlurmJob::Bake, strings(&["s.toml", "-o", output]), 3).unwrap(),
        shards: 3,
        partition: Some("cpu".into()),
        sbatch: strings(&["--time=10"]),
        hprt: "/opt/hprt".into(),
        workdir: workdir.into(),
    }
}

#[test]
fn scripts_run_the_commands_from_the_working_folder() {
    let scripts = bake_job("/work/it's here", "b.bake").scripts().unwrap();
    let dir = Path::new("/work/it's here/b.bake.shards");
    assert_eq!(scripts.dir, dir);
    assert_eq!(scripts.array.path, dir.join("array.sbatch"));
    assert_eq!(
        scripts.array.text,
        "#!/bin/bash\n#SBATCH --job-name=hprt-bake\n#SBATCH --array=0-2\nset -euo pipefail\n\
         cd -- \"/work/it's here\"\n\
         exec /opt/hprt bake s.toml --shard auto/3 -o b.bake.shards\n"
    );
    assert_eq!(
        scripts.merge.text,
        "#!/bin/bash\n#SBATCH --job-name=hprt-bake-merge\nset -euo pipefail\n\
         cd -- \"/work/it's here\"\n\
         exec /opt/hprt bake merge b.bake.shards -o b.bake\n"
    );
    assert_eq!(
        scripts.array.options,
        strings(&[
            "--parsable",
            "--partition=cpu",
            "--time=10",
            "--output=/work/it's here/b.bake.shards/bake-%A_%a.log",
            "--chdir=/work/it's here",
        ])
    );
    assert_eq!(
        scripts.merge.options[3],
        "--output=/work/it's here/b.bake.shards/bake-merge-%j.log"
    );
}

#[test]
fn a_dry_run_shows_the_scripts_as_comments_and_the_calls_quoted() {
    let text = bake_job("/w", "b.bake")
        .scripts()
        .unwrap()
        .dry_run()
        .unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "# /w/b.bake.shards/array.sbatch");
    assert_eq!(lines[1], "# #!/bin/bash");
    assert!(text.ends_with('\n'));
    assert!(
        lines
            .iter()
            .all(|l| l.starts_with("# ") || l.starts_with("sbatch ")),
        "{text}"
    );
    assert_eq!(
        lines[lines.len() - 1],
        "sbatch --parsable '--partition=cpu' '--time=10' \
         '--output=/w/b.bake.shards/bake-merge-%j.log' '--chdir=/w' \
         '--dependency=afterok:ARRAY_JOB_ID' /w/b.bake.shards/merge.sbatch"
    );
}

#[test]
fn paths_slurm_would_misread_are_refused() {
    for (workdir, output, what, found) in [
        ("/a\nb", "b.bake", SlurmPath::WorkingFolder, '\n'),
        ("/w", "x%j.bake", SlurmPath::ShardsFolder, '%'),
        ("/w", "x\\y", SlurmPath::ShardsFolder, '\\'),
    ] {
        match bake_job(workdir, output).scripts() {
            Err(SlurmError::Misread {
                what: w, found: f, ..
            }) => assert_eq!((w, f), (what, found)),
            other => panic!("{workdir:?} {output:?}: {other:?}"),
        }
    }
    let error = bake_job("/w", "x\n").scripts().unwrap_err().to_string();
    assert!(error.starts_with("the shards' folder \"/w/x\\n.shards\" holds '\\n'"));
}

#[test]
fn a_word_a_shell_script_cannot_hold_is_refused() {
    let mut job = bake_job("/w", "b.bake");
    job.commands.task.push("nul\0".into());
    assert!(matches!(
        job.scripts(),
        Err(SlurmError::Unquotable { word }) if word == "nul\0"
    ));
}

#[test]
fn job_ids_are_read_from_sbatch_parsable() {
    assert_eq!(job_id("42\n"), Some(JobId("42".into())));
    assert_eq!(job_id("42;cluster\n"), Some(JobId("42".into())));
    assert_eq!(job_id(""), None);
    assert_eq!(job_id("Submitted batch job 42"), None);
}
