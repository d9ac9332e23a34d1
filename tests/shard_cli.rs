//! Shards on one machine, as a batch system would run them: `hprt bake --shard`, `hprt
//! reference --shard` and `hprt report --shard`, their merges equal to one run byte for byte,
//! the scheduler's environment read, and incomplete or mixed shards refused by name.

mod common;

use common::*;
use std::path::Path;

fn run_ok(dir: &Path, args: &[&str], vars: &[(&str, &Path)]) -> String {
    let out = hprt_with_env(dir, args, vars);
    assert!(out.status.success(), "hprt {args:?}: {}", stderr(&out));
    stdout(&out)
}

fn same_bytes(dir: &Path, a: &str, b: &str) {
    let (x, y) = (
        std::fs::read(dir.join(a)).unwrap(),
        std::fs::read(dir.join(b)).unwrap(),
    );
    assert!(x == y, "{a} differs from {b}");
}

#[test]
fn bake_shards_from_the_scheduler_environment_merge_to_the_whole_bake() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let teapot = teapot.to_str().unwrap();
    let base = ["bake", teapot, "--samples", "32", "--bounces", "2"];
    // Slurm's variables name the task: an array 5-7 has tasks 0, 1, 2.
    for id in ["7", "5", "6"] {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_hprt"));
        command
            .args(base)
            .args(["--shard", "auto", "-o", "shards"])
            .current_dir(d)
            .env("SLURM_ARRAY_TASK_ID", id)
            .env("SLURM_ARRAY_TASK_MIN", "5")
            .env("SLURM_ARRAY_TASK_COUNT", "3");
        let out = command.output().unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
    }
    run_ok(d, &[&base[..], &["-o", "whole.bake"]].concat(), &[]);
    // Merged from another folder: the shards name the scene by its absolute path.
    std::fs::create_dir(d.join("elsewhere")).unwrap();
    let merged = d.join("merged.bake");
    run_ok(
        &d.join("elsewhere"),
        &[
            "bake",
            "merge",
            d.join("shards").to_str().unwrap(),
            "-o",
            merged.to_str().unwrap(),
        ],
        &[],
    );
    same_bytes(d, "merged.bake", "whole.bake");
    // A merge never writes over a shard it reads.
    let shard0 = "shards/bake-0000-of-0003.hprtshard";
    let before = std::fs::read(d.join(shard0)).unwrap();
    let out = hprt(d, &["bake", "merge", "shards", "-o", shard0]);
    assert_clean_failure(&out, &["destroy the input"]);
    assert!(std::fs::read(d.join(shard0)).unwrap() == before);

    // One shard gone: refused, naming it, and nothing written.
    std::fs::remove_file(d.join("shards/bake-0001-of-0003.hprtshard")).unwrap();
    let out = hprt(d, &["bake", "merge", "shards", "-o", "partial.bake"]);
    assert_clean_failure(&out, &["shard 1 of 3 is missing"]);
    assert!(!d.join("partial.bake").exists());
    // A shard of another job (other samples) among them: refused.
    run_ok(
        d,
        &[
            "bake",
            teapot,
            "--samples",
            "16",
            "--bounces",
            "2",
            "--shard",
            "1/3",
            "-o",
            "shards",
        ],
        &[],
    );
    let out = hprt(d, &["bake", "merge", "shards", "-o", "mixed.bake"]);
    assert_clean_failure(&out, &["different jobs", "bake settings"]);
    // A damaged shard: refused, naming the file.
    let shard = d.join("shards/bake-0000-of-0003.hprtshard");
    let bytes = std::fs::read(&shard).unwrap();
    std::fs::write(&shard, &bytes[..bytes.len() / 2]).unwrap();
    let out = hprt(d, &["bake", "merge", "shards", "-o", "damaged.bake"]);
    assert_clean_failure(&out, &["bake-0000-of-0003.hprtshard", "checksum"]);
    assert!(!d.join("mixed.bake").exists() && !d.join("damaged.bake").exists());
    // Outside a scheduler, auto has nothing to read.
    let out = hprt(d, &["bake", teapot, "--shard", "auto/3", "-o", "shards"]);
    assert_clean_failure(&out, &["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"]);
}

#[test]
fn reference_bands_merge_to_the_whole_composite_and_its_aux_images() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let composite = scene("teapot_composite.toml");
    let size = [
        composite.to_str().unwrap(),
        "--width",
        "48",
        "--height",
        "36",
        "--spp",
        "4",
    ];
    for i in [2, 0, 1] {
        let shard = format!("{i}/3");
        run_ok(
            d,
            &[
                &["reference"][..],
                &size,
                &["--shard", &shard, "-o", "bands"],
            ]
            .concat(),
            &[],
        );
    }
    let outputs = ["--png", "merged.png", "--aux", "merged-aux"];
    run_ok(
        d,
        &[
            &["reference", "merge", "bands", "-o", "merged.exr"][..],
            &outputs,
        ]
        .concat(),
        &[],
    );
    let outputs = ["--png", "whole.png", "--aux", "whole-aux"];
    run_ok(
        d,
        &[&["reference"][..], &size, &["-o", "whole.exr"], &outputs].concat(),
        &[],
    );
    same_bytes(d, "merged.exr", "whole.exr");
    same_bytes(d, "merged.png", "whole.png");
    let aux: Vec<_> = std::fs::read_dir(d.join("whole-aux"))
        .unwrap()
        .flatten()
        .collect();
    assert!(aux.len() >= 10, "the composite's masks and layers");
    for entry in aux {
        let name = entry.file_name().to_string_lossy().into_owned();
        same_bytes(
            d,
            &format!("whole-aux/{name}"),
            &format!("merged-aux/{name}"),
        );
    }
    // Images belong to the merge.
    let out = hprt(
        d,
        &[
            &["reference"][..],
            &size,
            &["--shard", "0/3", "-o", "b", "--png", "x.png"],
        ]
        .concat(),
    );
    assert_clean_failure(&out, &["--png", "merge"]);
}

#[test]
fn bands_of_different_jobs_or_an_incomplete_set_do_not_merge() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let band = |i: &str, spp: &str| {
        let args = ["reference", teapot.to_str().unwrap(), "--width", "16"];
        let more = ["--height", "8", "--spp", spp, "--shard", i, "-o", "bands"];
        run_ok(d, &[&args[..], &more].concat(), &[]);
    };
    band("0/2", "1");
    band("1/2", "2");
    let merge = ["reference", "merge", "bands", "-o", "m.exr"];
    assert_clean_failure(&hprt(d, &merge), &["different jobs", "shard 0/2"]);
    band("1/2", "1");
    std::fs::remove_file(d.join("bands/reference-0000-of-0002.hprtband")).unwrap();
    assert_clean_failure(&hprt(d, &merge), &["shard 0 of 2 is missing"]);
    assert!(!d.join("m.exr").exists());
    band("0/2", "1");
    run_ok(d, &merge, &[]);
}

#[test]
fn report_shards_fill_the_cache_the_report_then_reads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let vars = [("HPRT_CACHE", cache.as_path())];
    let maps = ["sunrise.exr", "city.exr", "studio.hdr"].map(|m| scene(&format!("env/{m}")));
    let mut args = vec![
        "report", "--width", "48", "--height", "36", "--spp", "8", "--frames", "1",
    ];
    let teapot = scene("teapot.toml");
    args.push(teapot.to_str().unwrap());
    args.push("--envs");
    args.extend(maps.iter().map(|m| m.to_str().unwrap()));
    let mut rendered = 0;
    for i in 0..2 {
        let shard = format!("{i}/2");
        let out = run_ok(d, &[&args[..], &["--shard", &shard]].concat(), &vars);
        rendered += out.matches("rendered in").count();
    }
    assert_eq!(
        rendered, 3,
        "each map's reference rendered once across the shards"
    );
    let out = run_ok(d, &[&args[..], &["-o", "report"]].concat(), &vars);
    assert_eq!(out.matches("reference from the cache").count(), 3, "{out}");
    assert!(d.join("report/report.html").exists());

    // A composite scene's shards render its true composites, which its report then reads.
    let composite = scene("teapot_composite.toml");
    let mut args = vec!["report", composite.to_str().unwrap(), "--envs"];
    args.extend(maps[..2].iter().map(|m| m.to_str().unwrap()));
    args.extend(["--width", "48", "--height", "36", "--spp", "8"]);
    for i in 0..2 {
        let shard = format!("{i}/2");
        let out = run_ok(d, &[&args[..], &["--shard", &shard]].concat(), &vars);
        assert_eq!(
            out.matches("the true composite rendered").count(),
            1,
            "{out}"
        );
    }
    let out = run_ok(d, &[&args[..], &["-o", "composite"]].concat(), &vars);
    assert_eq!(
        out.matches("the true composite from the cache").count(),
        2,
        "{out}"
    );
}

#[test]
fn slurm_dry_run_prints_the_jobs_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let out = run_ok(
        d,
        &[
            "slurm",
            "reference",
            teapot.to_str().unwrap(),
            "--spp",
            "8",
            "-o",
            "r.exr",
            "--png",
            "r.png",
            "--shards",
            "6",
            "--partition",
            "gpu",
            "--sbatch",
            "--time=30",
            "--dry-run",
        ],
        &[],
    );
    assert!(out.contains("#SBATCH --array=0-5"), "{out}");
    assert!(out.contains("--shard auto/6 -o r.exr.shards"), "{out}");
    assert!(
        out.contains("reference merge r.exr.shards -o r.exr --png r.png"),
        "{out}"
    );
    // Every word of the printed sbatch calls is quoted as a shell needs it.
    assert!(out.contains("'--partition=gpu' '--time=30'"), "{out}");
    assert!(out.contains("--dependency=afterok:"), "{out}");
    assert!(
        std::fs::read_dir(d).unwrap().next().is_none(),
        "a dry run writes nothing"
    );
    // A typo in the job's own arguments fails before anything is submitted.
    let out = hprt(
        d,
        &[
            "slurm",
            "bake",
            teapot.to_str().unwrap(),
            "-o",
            "x",
            "--sample",
            "3",
            "--shards",
            "2",
        ],
    );
    assert_clean_failure(&out, &["--sample"]);
}

/// A scene with a glossy teapot and a textured crate on a floor (absolute paths into
/// `scenes/`).
fn glossy_and_textured_scene(dir: &Path) -> std::path::PathBuf {
    let scenes = repo().join("scenes");
    let text = format!(
        r#"name = "glossy-and-textured"
[camera]
position = [6.5, 7.5, 11.0]
target = [0.3, 0.9, 0.0]
fov_y_deg = 38.0
width = 64
height = 48
[environment]
map = "{env}"
[bake]
order = 3
samples = 16
bounces = 1
[[object]]
name = "teapot"
mesh = "{teapot}"
patch_segments = 4
albedo = [0.45, 0.45, 0.45]
specular = [0.4, 0.4, 0.4]
shininess = 60.0
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}
[[object]]
name = "crate"
mesh = "{crate}"
transform = {{ translate = [2.5, 0.0, 0.0] }}
[[object]]
name = "floor"
box = {{ min = [-5.0, -0.3, -4.0], max = [5.0, 0.0, 4.0], segments = [16, 1, 12] }}
albedo = [0.6, 0.5, 0.4]
"#,
        env = scenes.join("env/city.exr").display(),
        teapot = scenes.join("meshes/teapot.bpt").display(),
        crate = scenes.join("models/crate.glb").display(),
    );
    let path = dir.join("mixed.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn merges_equal_one_run_for_every_shard_count_on_plain_glossy_and_textured_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let mixed = glossy_and_textured_scene(d);
    for (name, path) in [("teapot", &teapot), ("mixed", &mixed)] {
        let scene = path.to_str().unwrap();
        let bake = ["bake", scene, "--samples", "16", "--bounces", "1"];
        let reference = [
            "reference",
            scene,
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "2",
        ];
        run_ok(
            d,
            &[&bake[..], &["-o", &format!("{name}.bake")]].concat(),
            &[],
        );
        run_ok(
            d,
            &[&reference[..], &["-o", &format!("{name}.exr")]].concat(),
            &[],
        );
        for count in [1, 2, 3, 8] {
            let (bakes, bands) = (
                format!("{name}-{count}-bake"),
                format!("{name}-{count}-bands"),
            );
            for i in 0..count {
                let shard = format!("{i}/{count}");
                run_ok(
                    d,
                    &[&bake[..], &["--shard", &shard, "-o", &bakes]].concat(),
                    &[],
                );
                run_ok(
                    d,
                    &[&reference[..], &["--shard", &shard, "-o", &bands]].concat(),
                    &[],
                );
            }
            let merged = format!("{name}-{count}.bake");
            run_ok(d, &["bake", "merge", &bakes, "-o", &merged], &[]);
            same_bytes(d, &merged, &format!("{name}.bake"));
            let merged = format!("{name}-{count}.exr");
            run_ok(d, &["reference", "merge", &bands, "-o", &merged], &[]);
            same_bytes(d, &merged, &format!("{name}.exr"));
        }
    }
}
