//! `hprt report` end to end on a small configuration: teapot under sunrise.exr at a small image
//! size and low path count, plus maps that fail to load. The report is left in
//! `target/tmp/report/` for inspection.

mod common;

use common::*;
use foundation::image_io::read_exr;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Statistics recomputed here from the written EXRs, straight from CONVENTIONS.md.
struct Recomputed {
    mean: f64,
    std: f64,
    shadow_mean: f64,
    shadow_std: f64,
    penumbra_mean: f64,
    penumbra: usize,
    relative_rmse: f64,
    covered: usize,
    shadow: usize,
}

fn luminance(rgb: [f32; 3]) -> f64 {
    0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64
}

/// Tone mapping as displayed: negative radiance (SH ringing in PRT images) shows as black.
fn tonemapped_luminance(rgb: [f32; 3], exposure: f64) -> f64 {
    luminance(rgb.map(|c| (1.0 - (-exposure * c.max(0.0) as f64).exp()) as f32))
}

fn pixels(path: &Path) -> Vec<[f32; 3]> {
    read_exr(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .pixels
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect()
}

fn recompute(
    dir: &Path,
    method_file: &str,
    exposure: f64,
    shadow_threshold: f64,
    penumbra: (f64, f64),
) -> Recomputed {
    let reference = pixels(&dir.join("reference.exr"));
    let test = pixels(&dir.join(format!("{method_file}.exr")));
    let coverage = pixels(&dir.join("reference-coverage.exr"));
    let visibility = pixels(&dir.join("reference-visibility.exr"));
    let (mut all, mut shadow, mut partly_lit) = (Vec::new(), Vec::new(), Vec::new());
    let (mut squared, mut reference_sum) = (0.0, 0.0);
    for i in 0..reference.len() {
        if coverage[i][0] <= 0.5 {
            continue;
        }
        let error = (tonemapped_luminance(test[i], exposure)
            - tonemapped_luminance(reference[i], exposure))
        .abs();
        all.push(error);
        if (visibility[i][0] as f64) < shadow_threshold {
            shadow.push(error);
        }
        let v = visibility[i][0] as f64;
        if v > penumbra.0 && v < penumbra.1 {
            partly_lit.push(error);
        }
        squared += (luminance(test[i]) - luminance(reference[i])).powi(2);
        reference_sum += luminance(reference[i]);
    }
    let mean_std = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64;
        (mean, var.sqrt())
    };
    let (mean, std) = mean_std(&all);
    let (shadow_mean, shadow_std) = mean_std(&shadow);
    let n = all.len() as f64;
    Recomputed {
        penumbra_mean: mean_std(&partly_lit).0,
        penumbra: partly_lit.len(),
        mean,
        std,
        shadow_mean,
        shadow_std,
        relative_rmse: (squared / n).sqrt() / (reference_sum / n),
        covered: all.len(),
        shadow: shadow.len(),
    }
}

fn close(a: f64, b: &Value, what: &str) {
    let b = b.as_f64().unwrap_or_else(|| panic!("{what} missing"));
    assert!(
        (a - b).abs() <= 1e-5 * b.abs().max(1e-3),
        "{what}: stats.json says {b}, the images give {a}"
    );
}

fn output_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn report_measures_shadows_and_survives_bad_maps() {
    let dir = output_dir();
    let cache = dir.join("cache");
    let bake = dir.join("teapot.bake");
    let out = bake_cli_ok(&dir, &bake);
    assert!(out.status.success(), "bake failed: {}", stderr(&out));

    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    let sunrise = scene("env/sunrise.exr");
    let htj2k = repo().join("tests/data/htj2k.exr");
    let report_dir = dir.join("out");
    let teapot = scene("teapot.toml");
    let args = [
        "report",
        teapot.to_str().unwrap(),
        "--bake",
        bake.to_str().unwrap(),
        "--envs",
        sunrise.to_str().unwrap(),
        htj2k.to_str().unwrap(),
        garbage.to_str().unwrap(),
        "--width",
        "160",
        "--height",
        "120",
        "--spp",
        "128",
        "--thresholds",
        "0.05",
        "0.3",
        "--frames",
        "1",
        "-o",
        report_dir.to_str().unwrap(),
    ];
    let out = hprt_with_env(&dir, &args, &[("HPRT_CACHE", &cache)]);
    assert!(
        out.status.success(),
        "report failed: {}\n{}",
        stdout(&out),
        stderr(&out)
    );
    assert!(!stdout(&out).contains("from the cache"));

    let stats: Value =
        serde_json::from_slice(&std::fs::read(report_dir.join("stats.json")).unwrap()).unwrap();
    let maps = stats["maps"].as_array().unwrap();
    assert_eq!(maps.len(), 3);

    // The maps that cannot be read are reported as failed, with the reason.
    for (map, reason) in [(&maps[1], "HTJ2K256"), (&maps[2], "garbage.exr")] {
        assert_eq!(map["status"], "failed");
        let error = map["error"].as_str().unwrap();
        assert!(error.contains(reason), "{error}");
        assert!(!report_dir.join(map["name"].as_str().unwrap()).exists());
    }
    let html = std::fs::read_to_string(report_dir.join("report.html")).unwrap();
    assert!(html.contains("htj2k") && html.contains("Maps that failed"));
    let csv = std::fs::read_to_string(report_dir.join("stats.csv")).unwrap();
    assert!(csv.contains("htj2k,failed"));

    // The working map: every statistic in stats.json is what its images give.
    let sunrise_report = &maps[0];
    assert_eq!(sunrise_report["status"], "ok");
    let map_dir = report_dir.join("sunrise");
    let exposure = sunrise_report["exposure"].as_f64().unwrap();
    let threshold = stats["shadow_visibility_threshold"].as_f64().unwrap();
    let bounds = &stats["penumbra_visibility"];
    let penumbra = (bounds[0].as_f64().unwrap(), bounds[1].as_f64().unwrap());
    assert_eq!(penumbra, (0.05, 0.95), "CONVENTIONS.md's penumbra bounds");
    let methods = sunrise_report["methods"].as_array().unwrap();
    let names: Vec<&str> = methods
        .iter()
        .map(|m| m["method"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "prt",
            "hybrid/thesis",
            "hybrid/consistent",
            "median-cut/8",
            "median-cut/32",
            "sh-sun",
            "ibl"
        ]
    );
    let mut shadow_errors = Vec::new();
    for m in methods {
        let name = m["method"].as_str().unwrap();
        // Each method's lighting cost, on the first frame and on a later one of a changing map.
        for cost in ["decomposition_ms", "warm_decomposition_ms"] {
            assert!(m[cost].as_f64().unwrap() > 0.0, "{name} {cost}");
        }
        let r = recompute(
            &map_dir,
            &name.replace('/', "-"),
            exposure,
            threshold,
            penumbra,
        );
        close(r.mean, &m["mean"], &format!("{name} mean"));
        close(r.std, &m["std"], &format!("{name} std"));
        close(
            r.shadow_mean,
            &m["shadow_mean"],
            &format!("{name} shadow mean"),
        );
        close(
            r.shadow_std,
            &m["shadow_std"],
            &format!("{name} shadow std"),
        );
        close(
            r.relative_rmse,
            &m["relative_rmse"],
            &format!("{name} rmse"),
        );
        assert_eq!(m["covered_pixels"].as_u64(), Some(r.covered as u64));
        assert_eq!(m["shadow_pixels"].as_u64(), Some(r.shadow as u64));
        close(
            r.penumbra_mean,
            &m["penumbra_mean"],
            &format!("{name} penumbra mean"),
        );
        assert_eq!(m["penumbra_pixels"].as_u64(), Some(r.penumbra as u64));
        shadow_errors.push(r.shadow_mean);
        for file in [
            format!("{}.png", name.replace('/', "-")),
            format!("error-{}.png", name.replace('/', "-")),
        ] {
            assert!(map_dir.join(&file).exists(), "{file} missing");
        }
    }
    // The teapot casts a real shadow on the table under sunrise's sun.
    let shadow_pixels = methods[0]["shadow_pixels"].as_u64().unwrap();
    assert!(shadow_pixels > 200, "only {shadow_pixels} shadow pixels");
    // What the method is for: the hybrid's shadows are closer to the truth than PRT's.
    let (prt, hybrid) = (shadow_errors[0], shadow_errors[2]);
    assert!(
        hybrid < 0.7 * prt,
        "hybrid shadow error {hybrid} not well below prt's {prt}"
    );
    assert!(methods[2]["lights"].as_u64().unwrap() >= 1);
    for file in ["reference.png", "threshold.svg"] {
        assert!(map_dir.join(file).exists(), "{file} missing");
    }

    // The reference's noise floor is what its two halves give, and the warning follows it.
    let floor = recompute_noise(&map_dir, exposure);
    let noise = &sunrise_report["noise"];
    close(floor.0, &noise["mean"], "noise floor");
    close(
        floor.1,
        &noise["relative_rmse"],
        "noise floor of the relative RMSE",
    );
    assert_eq!(sunrise_report["reference_spp"], 128);
    let best = methods
        .iter()
        .map(|m| m["mean"].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    let warned = floor.0 > 0.2 * best;
    assert_eq!(sunrise_report["noise_warning"], warned);
    assert_eq!(
        stdout(&out).contains("warning: sunrise: the reference's noise floor"),
        warned
    );
    assert_eq!(
        html.contains("Warning: the reference's own noise floor"),
        warned
    );
    assert!(
        warned,
        "128 spp: the floor {} should be a large part of {best}",
        floor.0
    );
    for m in methods {
        let rmse = m["relative_rmse"].as_f64().unwrap();
        let corrected = (rmse * rmse - floor.1 * floor.1).max(0.0).sqrt();
        close(corrected, &m["relative_rmse_corrected"], "corrected RMSE");
    }

    // A rerun with the same inputs takes the reference from the cache.
    let out = hprt_with_env(&dir, &args, &[("HPRT_CACHE", &cache)]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("sunrise: reference from the cache"));
    let again: Value =
        serde_json::from_slice(&std::fs::read(report_dir.join("stats.json")).unwrap()).unwrap();
    assert_eq!(again["maps"][0]["reference_cached"], true);
    assert_eq!(
        again["maps"][0]["methods"][0]["mean"],
        stats["maps"][0]["methods"][0]["mean"]
    );

    // A stricter target continues the cached samples instead of starting over.
    let target = format!("{}", 0.8 * floor.0);
    let mut stricter = args.to_vec();
    stricter.extend(["--target-noise", target.as_str()]);
    let out = hprt_with_env(&dir, &stricter, &[("HPRT_CACHE", &cache)]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("2 × 64 → 2 × 128"),
        "{}",
        stdout(&out)
    );
    let continued: Value =
        serde_json::from_slice(&std::fs::read(report_dir.join("stats.json")).unwrap()).unwrap();
    let map = &continued["maps"][0];
    assert!(map["reference_spp"].as_u64().unwrap() >= 256);
    let continued_floor = map["noise"]["mean"].as_f64().unwrap();
    assert!(
        continued_floor <= 0.8 * floor.0,
        "{continued_floor} vs {}",
        floor.0
    );
    close(
        recompute_noise(&map_dir, exposure).0,
        &map["noise"]["mean"],
        "continued noise floor",
    );
}

/// The noise floor of `dir`'s reference from its halves (CONVENTIONS.md): the mean over
/// covered pixels of half the tone-mapped difference, and `√(mean (ΔY)²/4) / mean Y`.
fn recompute_noise(dir: &Path, exposure: f64) -> (f64, f64) {
    let a = pixels(&dir.join("reference-half0.exr"));
    let b = pixels(&dir.join("reference-half1.exr"));
    let reference = pixels(&dir.join("reference.exr"));
    let coverage = pixels(&dir.join("reference-coverage.exr"));
    let (mut sum, mut variance, mut level, mut n) = (0.0, 0.0, 0.0, 0usize);
    for i in 0..a.len() {
        for c in 0..3 {
            assert!(
                (0.5 * (a[i][c] + b[i][c]) - reference[i][c]).abs()
                    <= 1e-3 * reference[i][c].abs().max(1e-3)
            );
        }
        if coverage[i][0] > 0.5 {
            sum += 0.5
                * (tonemapped_luminance(a[i], exposure) - tonemapped_luminance(b[i], exposure))
                    .abs();
            variance += (luminance(a[i]) - luminance(b[i])).powi(2) / 4.0;
            level += 0.5 * (luminance(a[i]) + luminance(b[i]));
            n += 1;
        }
    }
    let n = n as f64;
    (sum / n, (variance / n).sqrt() / (level / n))
}

/// Bakes the teapot at test settings.
fn bake_cli_ok(dir: &Path, bake: &Path) -> std::process::Output {
    hprt(
        dir,
        &[
            "bake",
            scene("teapot.toml").to_str().unwrap(),
            "--samples",
            "256",
            "--bounces",
            "2",
            "-o",
            bake.to_str().unwrap(),
        ],
    )
}

#[test]
fn report_with_a_missing_bake_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let garbage = dir.path().join("broken.hdr");
    std::fs::write(&garbage, b"#?RADIANCE\nnonsense").unwrap();
    let out = hprt_with_env(
        dir.path(),
        &[
            "report",
            scene("teapot.toml").to_str().unwrap(),
            "--envs",
            garbage.to_str().unwrap(),
            "--bake",
            dir.path().join("missing.bake").to_str().unwrap(),
            "-o",
            "out",
        ],
        &[("HPRT_CACHE", dir.path())],
    );
    assert_clean_failure(&out, &["missing.bake"]);
    assert!(!dir.path().join("out").exists());
}

/// A sequence report on a small sun sequence: every frame measured, temporal errors from the
/// second frame on, the sun's light checked against the true sun, an animated GIF of all
/// frames; and `render --env-sequence --frame` draws one frame of the same sequence.
#[test]
fn sequence_report_measures_every_frame_over_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bake = bake_teapot(d, "t.bake", &["--samples", "64", "--bounces", "1"]);
    let base = repo().join("scenes/env/forest.exr");
    let sequence = d.join("sun.toml");
    std::fs::write(
        &sequence,
        format!(
            "[sun]\nbase = {base:?}\nframes = 5\nfrom = [-40, 10]\nto = [-10, 30]\n\
             angular_radius_deg = 0.5\npower = [7, 6.6, 6]\n"
        ),
    )
    .unwrap();
    let out = hprt_with_env(
        d,
        &[
            "report",
            scene("teapot.toml").to_str().unwrap(),
            "--env-sequence",
            sequence.to_str().unwrap(),
            "--bake",
            bake.to_str().unwrap(),
            "--width",
            "48",
            "--height",
            "36",
            "--spp",
            "8",
            "-o",
            "seq",
        ],
        &[("HPRT_CACHE", d)],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("seq/sequence.json")).unwrap())
            .unwrap();
    let frames = report["per_frame"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    for (k, frame) in frames.iter().enumerate() {
        let methods = frame["methods"].as_array().unwrap();
        let names: Vec<&str> = methods
            .iter()
            .map(|m| m["method"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["prt", "hybrid/tracked", "hybrid/untracked"]);
        for m in methods {
            assert_eq!(m["temporal"].is_null(), k == 0, "{m}");
            assert!(m["mean"].as_f64().unwrap() > 0.0);
        }
        // The sun's light follows the sun.
        assert!(frame["sun"]["angle_deg"].as_f64().unwrap() < 0.5, "{frame}");
    }
    assert_eq!(report["methods"][0]["light_count_changes"], 0);
    let gif = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(d.join("seq/sequence.gif")).unwrap(),
    ))
    .unwrap();
    use image::AnimationDecoder;
    assert_eq!(gif.into_frames().count(), 5);
    for file in ["report.html", "sequence.csv", "error.svg", "temporal.svg"] {
        assert!(d.join("seq").join(file).exists(), "{file}");
    }

    let render = |frame: &str| {
        hprt(
            d,
            &[
                "render",
                scene("teapot.toml").to_str().unwrap(),
                "--bake",
                bake.to_str().unwrap(),
                "--env-sequence",
                sequence.to_str().unwrap(),
                "--frame",
                frame,
                "--width",
                "48",
                "--height",
                "36",
                "-o",
                &format!("frame{frame}.png"),
            ],
        )
    };
    assert!(render("4").status.success());
    assert_clean_failure(&render("5"), &["--frame 5", "frames 0 to 4"]);
}
