//! Hostile inputs, fourth round (issue 58), part one: values written into generated batch
//! scripts, names that become paths, and outputs written over inputs that were not counted as
//! inputs (photographs, probe images). Each case asserts a clean error naming the cause, no
//! input changed, nothing written outside its place and no command run that the user did not
//! write.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tiny box scene in `dir` (`box.toml`).
fn box_scene(dir: &Path) -> PathBuf {
    write_scene(
        dir,
        "box.toml",
        "box = { min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] }\nalbedo = [0.5, 0.5, 0.5]",
    )
}

/// A folder `bin/` in `dir` holding a fake `sbatch` that appends each argument it gets, one a
/// line, to `sbatch.log` in `dir` and prints a job id; returns a `PATH` that finds it first.
fn fake_sbatch(dir: &Path) -> std::ffi::OsString {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let log = dir.join("sbatch.log");
    let script = format!(
        "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\" >> '{}'; done\necho '--' >> '{}'\necho 42\n",
        log.display(),
        log.display()
    );
    let sbatch = bin.join("sbatch");
    std::fs::write(&sbatch, script).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&sbatch, std::fs::Permissions::from_mode(0o755)).unwrap();
    let mut path = bin.into_os_string();
    path.push(":");
    path.push(std::env::var_os("PATH").unwrap_or_default());
    path
}

/// Runs `hprt args` in `dir` with `PATH` set to `path`.
fn hprt_on_path(dir: &Path, path: &std::ffi::OsStr, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_hprt"))
        .args(args)
        .current_dir(dir)
        .env("PATH", path)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("HPRT_CACHE", dir.join("cache"))
        .output()
        .expect("hprt runs")
}

/// Every file under `dir` whose name starts with `PWNED` (what an injected command makes).
fn pwned(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() && !path.is_symlink() {
                stack.push(path.clone());
            }
            if entry.file_name().to_string_lossy().starts_with("PWNED") {
                found.push(path);
            }
        }
    }
    found
}

/// What the fake sbatch was given: one list of arguments per call.
fn sbatch_calls(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("sbatch.log")).unwrap_or_default();
    text.split("--\n")
        .filter(|c| !c.is_empty())
        .map(|c| c.lines().map(str::to_owned).collect())
        .collect()
}

#[test]
fn hostile_values_never_become_commands_in_slurm_scripts() {
    let dir = tempfile::tempdir().unwrap();
    // A working folder whose name a shell would run: quotes, a command substitution, a space.
    let work = dir
        .path()
        .join("it's $(touch PWNED_dir) `touch PWNED_tick`");
    std::fs::create_dir(&work).unwrap();
    box_scene(&work);
    let path = fake_sbatch(dir.path());
    let output = "out $(touch PWNED_o)/b;touch PWNED_semi.bake";
    let args = [
        "slurm",
        "bake",
        "box.toml",
        "-o",
        output,
        "--shards",
        "2",
        "--partition",
        "x; touch PWNED_partition",
        "--sbatch",
        "'--comment=$(touch PWNED_sbatch)'",
    ];
    // The dry run prints command lines a user may paste into a shell: run them there.
    let dry = hprt_on_path(&work, &path, &[&args[..], &["--dry-run"]].concat());
    assert!(dry.status.success(), "{}", stderr(&dry));
    let shell = Command::new("bash")
        .arg("-c")
        .arg(stdout(&dry))
        .current_dir(&work)
        .env("PATH", &path)
        .output()
        .unwrap();
    assert!(
        shell.status.success(),
        "{}",
        String::from_utf8_lossy(&shell.stderr)
    );
    let calls = sbatch_calls(dir.path());
    assert_eq!(calls.len(), 2, "{calls:?}");
    assert!(calls[0].contains(&"--partition=x; touch PWNED_partition".to_owned()));
    assert!(calls[0].contains(&"--comment=$(touch PWNED_sbatch)".to_owned()));
    assert!(
        calls[0].contains(&format!("--chdir={}", work.display())),
        "{calls:?}"
    );
    std::fs::remove_file(dir.path().join("sbatch.log")).unwrap();

    // Submitted for real (to the fake sbatch), then the written scripts run as Slurm would.
    let out = hprt_on_path(&work, &path, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let shards = work.join(format!("{output}.shards"));
    for task in ["0", "1"] {
        let run = Command::new("bash")
            .arg(shards.join("array.sbatch"))
            .current_dir(dir.path())
            .env("SLURM_ARRAY_TASK_ID", task)
            .env("SLURM_ARRAY_TASK_MIN", "0")
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let merge = Command::new("bash")
        .arg(shards.join("merge.sbatch"))
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(
        merge.status.success(),
        "{}",
        String::from_utf8_lossy(&merge.stderr)
    );
    assert!(
        work.join(output).is_file(),
        "the merge wrote the bake where -o said"
    );
    let calls = sbatch_calls(dir.path());
    assert!(
        calls[1].contains(&"--dependency=afterok:42".to_owned()),
        "{calls:?}"
    );
    assert_eq!(
        pwned(dir.path()),
        Vec::<PathBuf>::new(),
        "an injected command ran"
    );
}

#[test]
fn paths_slurm_would_misread_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = fake_sbatch(dir.path());
    box_scene(dir.path());
    // A newline in -o would start a line of its own in any script or option.
    let out = hprt_on_path(
        dir.path(),
        &path,
        &[
            "slurm",
            "bake",
            "box.toml",
            "-o",
            "x\ntouch PWNED\n#",
            "--shards",
            "2",
            "--dry-run",
        ],
    );
    assert_clean_failure(&out, &["holds '\\n'", "Slurm"]);
    let out = hprt_on_path(
        dir.path(),
        &path,
        &[
            "slurm", "bake", "box.toml", "-o", "x%j.bake", "--shards", "2",
        ],
    );
    assert_clean_failure(&out, &["holds '%'"]);
    // So would a working folder with a newline.
    let work = dir.path().join("a\ntouch PWNED\nb");
    std::fs::create_dir(&work).unwrap();
    box_scene(&work);
    let out = hprt_on_path(
        &work,
        &path,
        &["slurm", "bake", "box.toml", "-o", "b.bake", "--shards", "2"],
    );
    assert_clean_failure(&out, &["working folder", "holds '\\n'"]);
    assert!(sbatch_calls(dir.path()).is_empty(), "nothing was submitted");
    assert_eq!(pwned(dir.path()), Vec::<PathBuf>::new());
}

#[test]
fn names_that_would_leave_their_folder_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("cache")).unwrap();
    for name in ["../escaped/evil", "/tmp/hprt-absolute-evil", "..", "a\nb"] {
        let text = std::fs::read_to_string(box_scene(d)).unwrap();
        let toml_name = name.replace('\n', "\\n");
        std::fs::write(
            d.join("named.toml"),
            format!("name = \"{toml_name}\"\n{text}"),
        )
        .unwrap();
        let out = hprt_on_path(
            d,
            &std::env::var_os("PATH").unwrap(),
            &[
                "report",
                "named.toml",
                "--envs",
                &scene("env/sunrise.exr").to_string_lossy(),
                "-o",
                "rep",
            ],
        );
        assert_clean_failure(&out, &["named.toml", "the scene's name"]);
    }
    assert!(!d.join("escaped").exists());
    let escaped = std::fs::read_dir("/tmp").unwrap().flatten();
    let names: Vec<_> = escaped
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.starts_with("hprt-absolute-evil")),
        "{names:?}"
    );
    assert!(std::fs::read_dir(d.join("cache")).unwrap().next().is_none());
}

/// A room (open on +x) with `probes`, lit by `map.exr` copied beside it.
fn room(dir: &Path, probes: &str) {
    std::fs::copy(scene("env/sunrise.exr"), dir.join("map.exr")).unwrap();
    let text = format!(
        "[camera]\nposition = [-3, 1.6, 2]\ntarget = [0, 0.8, 0]\nfov_y_deg = 60\nwidth = 32\nheight = 24\n\
         [environment]\nmap = \"map.exr\"\n[backplate]\nimage = \"environment\"\n\
         [[object]]\nname = \"model\"\nbox = {{ min = [-0.3, 0, -0.3], max = [0.3, 0.6, 0.3] }}\nalbedo = [0.7, 0.6, 0.5]\n\
         [[object]]\nname = \"room\"\nrole = \"proxy\"\nbox = {{ min = [-4, 0, -3], max = [4, 2.8, 3], skip_faces = [\"+x\"] }}\nalbedo = [0.6, 0.6, 0.6]\n{probes}"
    );
    std::fs::write(dir.join("room.toml"), text).unwrap();
}

#[test]
fn probes_are_never_written_over_what_the_command_reads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let map_before = std::fs::read(scene("env/sunrise.exr")).unwrap();
    let probes_args = ["probes", "room.toml", "--spp", "1", "--width", "64"];
    // A name that climbs out of probes/ onto the scene's own map.
    room(d, "[[probe]]\nname = \"../map\"\nposition = [0, 1.2, 0]\n");
    assert_clean_failure(
        &hprt(d, &probes_args),
        &["room.toml", "\"../map\"", "separator"],
    );
    // A name --at uses for its own probes.
    room(d, "[[probe]]\nname = \"at-1\"\nposition = [0, 1.2, 0]\n");
    let out = hprt(d, &[&probes_args[..], &["--at", "1,1,0"]].concat());
    assert_clean_failure(&out, &["\"at-1\"", "--at"]);
    // A probe image that is a link to the map.
    room(d, "[[probe]]\nname = \"p\"\nposition = [0, 1.2, 0]\n");
    std::fs::create_dir(d.join("probes")).unwrap();
    std::os::unix::fs::symlink("../map.exr", d.join("probes/p.exr")).unwrap();
    assert_clean_failure(&hprt(d, &probes_args), &["probes/p.exr", "is a link"]);
    // A hard link to the map: the same file under the probe's name.
    std::fs::remove_file(d.join("probes/p.exr")).unwrap();
    std::fs::hard_link(d.join("map.exr"), d.join("probes/p.exr")).unwrap();
    assert_clean_failure(
        &hprt(d, &probes_args),
        &["probes/p.exr", "which this command reads"],
    );
    // A link to a file outside the scene, which the command does not read.
    std::fs::remove_file(d.join("probes/p.exr")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let victim = outside.path().join("victim.exr");
    std::fs::write(&victim, b"keep").unwrap();
    std::os::unix::fs::symlink(&victim, d.join("probes/p.exr")).unwrap();
    assert_clean_failure(&hprt(d, &probes_args), &["probes/p.exr", "is a link"]);
    assert_eq!(std::fs::read(&victim).unwrap(), b"keep");
    // A distance map that is a link to another probe's image, which the command reads.
    std::fs::remove_file(d.join("probes/p.exr")).unwrap();
    let _ = outside;
    std::fs::copy(d.join("map.exr"), d.join("other.exr")).unwrap();
    room(
        d,
        "[[probe]]\nname = \"p\"\nposition = [0, 1.2, 0]\n\
         [[probe]]\nname = \"q\"\nposition = [1, 1.2, 0]\nimage = \"other.exr\"\n",
    );
    std::os::unix::fs::symlink("../other.exr", d.join("probes/p.distance.exr")).unwrap();
    let other_before = std::fs::read(d.join("other.exr")).unwrap();
    assert_clean_failure(&hprt(d, &probes_args), &["p.distance.exr", "is a link"]);
    assert_eq!(std::fs::read(d.join("other.exr")).unwrap(), other_before);
    assert_eq!(std::fs::read(d.join("map.exr")).unwrap(), map_before);
}

#[test]
fn capture_outputs_never_replace_its_photographs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for entry in std::fs::read_dir(scene("capture")).unwrap().flatten() {
        std::fs::copy(entry.path(), d.join(entry.file_name())).unwrap();
    }
    let photo = std::fs::read(d.join("shot00_0.jpg")).unwrap();
    for (option, file) in [
        ("-o", "shot00_0.jpg"),
        ("--preview", "shot00_0.jpg"),
        ("--save-response", "shot00_0.jpg"),
        ("--coverage", "shot00_0.jpg"),
    ] {
        let mut args = vec!["capture", "capture.toml", "--width", "64"];
        if option != "-o" {
            args.extend(["-o", "map.exr"]);
        }
        args.extend([option, file]);
        let out = hprt(d, &args);
        assert_clean_failure(
            &out,
            &[&format!("{option} {file}"), "which this command reads"],
        );
        assert_eq!(
            std::fs::read(d.join("shot00_0.jpg")).unwrap(),
            photo,
            "{option}"
        );
        assert!(!d.join("map.exr").exists());
    }
    // Through a link too.
    std::os::unix::fs::symlink("shot00_0.jpg", d.join("link.png")).unwrap();
    let out = hprt(
        d,
        &[
            "capture",
            "capture.toml",
            "--width",
            "64",
            "-o",
            "m.exr",
            "--preview",
            "link.png",
        ],
    );
    assert_clean_failure(&out, &["which this command reads"]);
    assert_eq!(std::fs::read(d.join("shot00_0.jpg")).unwrap(), photo);
}
