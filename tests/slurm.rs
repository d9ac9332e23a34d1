//! Sharded work through a real Slurm: `tests/run.sh` installs Slurm from Debian's packages and
//! starts a one-node cluster on localhost (`tests/slurm/start-cluster.sh`); this test runs a
//! 4-shard bake and a 4-shard reference of the teapot through `hprt slurm`, waits for their
//! merge jobs, and compares the results byte for byte with one-machine runs. Without a
//! running cluster it fails and says how to start one (it never skips).

mod common;

use common::*;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// Fails with the way to start a cluster unless one answers.
fn require_cluster() {
    let sinfo = Command::new("sinfo").args(["-h", "-o", "%T"]).output();
    let up = sinfo
        .as_ref()
        .is_ok_and(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).contains("idle"));
    assert!(
        up,
        "no Slurm cluster answers (sinfo: {}): tests/run.sh installs slurm-wlm and munge and \
         starts a one-node cluster with tests/slurm/start-cluster.sh (as root; its messages \
         are in target/slurm-start.log); run that",
        match &sinfo {
            Ok(o) => format!("{}{}", stdout(o), stderr(o)),
            Err(e) => e.to_string(),
        }
    );
}

/// Submits `hprt slurm ARGS` from `dir`, returning the merge job's id.
fn submit(dir: &Path, args: &[&str]) -> String {
    let out = hprt_with_env(dir, args, &[("HPRT_CACHE", &dir.join("cache"))]);
    assert!(out.status.success(), "hprt slurm failed: {}", stderr(&out));
    let ids = stdout(&out);
    let last = ids.lines().last().unwrap_or_default().to_owned();
    let (_, merge) = last.split_once(' ').expect("the two job ids");
    merge.to_owned()
}

/// Waits until Slurm no longer lists `jobs`, then requires them completed.
fn wait_for(jobs: &[String], logs: &[&Path]) {
    let list = jobs.join(",");
    let start = Instant::now();
    loop {
        let out = Command::new("squeue")
            .args(["-h", "-j", &list])
            .output()
            .unwrap();
        if String::from_utf8_lossy(&out.stdout).trim().is_empty() {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(900),
            "the jobs {list} did not finish in 15 minutes"
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    for job in jobs {
        let out = Command::new("scontrol")
            .args(["show", "job", job])
            .output()
            .unwrap();
        let text = stdout(&out);
        let logs: String = logs
            .iter()
            .flat_map(|dir| std::fs::read_dir(dir).into_iter().flatten().flatten())
            .filter(|e| e.path().extension().is_some_and(|x| x == "log"))
            .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
            .collect();
        assert!(
            text.contains("JobState=COMPLETED"),
            "merge job {job} did not complete: {text}\nlogs:\n{logs}"
        );
    }
}

#[test]
fn sharded_bake_and_reference_through_slurm_equal_one_machine_runs() {
    require_cluster();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let teapot = teapot.to_str().unwrap();
    let bake_job = submit(
        d,
        &[
            "slurm",
            "bake",
            teapot,
            "--samples",
            "64",
            "-o",
            "sharded.bake",
            "--shards",
            "4",
        ],
    );
    let reference_args = [teapot, "--width", "64", "--height", "48", "--spp", "8"];
    let mut args = vec!["slurm", "reference"];
    args.extend(reference_args);
    args.extend(["-o", "sharded.exr", "--png", "sharded.png", "--shards", "4"]);
    let reference_job = submit(d, &args);

    // The same on one machine, while the cluster works.
    let out = hprt(d, &["bake", teapot, "--samples", "64", "-o", "whole.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let mut args = vec!["reference"];
    args.extend(reference_args);
    args.extend(["-o", "whole.exr", "--png", "whole.png"]);
    let out = hprt(d, &args);
    assert!(out.status.success(), "{}", stderr(&out));

    wait_for(
        &[bake_job, reference_job],
        &[
            &d.join("sharded.bake.shards"),
            &d.join("sharded.exr.shards"),
        ],
    );
    for (sharded, whole) in [
        ("sharded.bake", "whole.bake"),
        ("sharded.exr", "whole.exr"),
        ("sharded.png", "whole.png"),
    ] {
        let a = std::fs::read(d.join(sharded)).unwrap();
        let b = std::fs::read(d.join(whole)).unwrap();
        assert!(a == b, "{sharded} differs from {whole}");
    }
    let shards = std::fs::read_dir(d.join("sharded.bake.shards"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "hprtshard"))
        })
        .count();
    assert_eq!(shards, 4, "four array tasks, four shards");
}
