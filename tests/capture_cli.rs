//! `hprt capture` end to end: photographs written to files and a description, captured into a
//! map the rest of hprt reads; and every kind of bad input refused with the file named.

mod common;

use capture::synthetic::{CameraResponse, CapturePlan, photograph, write_capture};
use capture::{MirrorBall, ShotCamera, View};
use common::*;
use foundation::envmap::EnvMap;
use foundation::luminance;
use rand_pcg::Pcg32;
use std::fmt::Write;
use std::path::Path;

const RESPONSE: CameraResponse = CameraResponse::knee([0.9, 1.0, 1.1], 2.0, f32::INFINITY, 0.5);

/// Exposure times for the bundled interior map (its lamps to its dark corners).
const TIMES: [f32; 6] = [4e-5, 1.3e-4, 6e-4, 2.5e-3, 1.1e-2, 4.6e-2];

/// Writes a mirror ball seen from two sides at `times` as PNGs into `dir`, and a description
/// of them; returns the description's text.
fn write_ball_capture(dir: &Path, times: &[f32]) -> String {
    let map = interior(128);
    let mut rng = Pcg32::new(1, 2);
    let mut toml = String::new();
    for (v, yaw) in [0.0f32, 90.0].into_iter().enumerate() {
        let camera = ShotCamera::new((yaw, 0.0, 0.0), 25.0, (96, 96), (0.0, 0.0));
        let ball = MirrorBall::new(camera, (48.0, 48.0), 40.0, [0.6; 3]);
        for (k, t) in times.iter().enumerate() {
            let photo = photograph(&map, View::Ball(ball), (96, 96), *t, &RESPONSE, &mut rng);
            let name = format!("ball{v}_{k}.png");
            let bytes: Vec<u8> = photo.levels.iter().flatten().copied().collect();
            image::save_buffer(
                dir.join(&name),
                &bytes,
                96,
                96,
                image::ExtendedColorType::Rgb8,
            )
            .expect("a PNG");
            write!(
                toml,
                "[[ball]]\nimage = \"{name}\"\nexposure = {t}\ncentre = [48.0, 48.0]\n\
                 radius = 40.0\nfov = 25.0\nyaw = {yaw}\nreflectance = [0.6, 0.6, 0.6]\n\n"
            )
            .unwrap();
        }
    }
    std::fs::write(dir.join("capture.toml"), &toml).unwrap();
    toml
}

#[test]
fn a_ball_capture_becomes_a_map_hprt_reads() {
    let dir = tempfile::tempdir().unwrap();
    write_ball_capture(dir.path(), &TIMES);
    let args = [
        "capture",
        "capture.toml",
        "-o",
        "captured.exr",
        "--width",
        "128",
        "--coverage",
        "coverage.png",
        "--preview",
        "preview.png",
        "--save-response",
        "response.csv",
    ];
    let out = hprt(dir.path(), &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let map = foundation::image_io::read_exr(&dir.path().join("captured.exr")).unwrap();
    assert_eq!((map.width, map.height), (128, 64));
    assert!(
        map.pixels
            .iter()
            .all(|c| c.is_finite() && c.min_element() >= 0.0)
    );
    assert!(
        stdout(&out).contains("of the sphere resolved") && !stdout(&out).contains("-0.0%"),
        "{}",
        stdout(&out)
    );
    for png in ["coverage.png", "preview.png"] {
        let image = image::open(dir.path().join(png)).unwrap();
        assert_eq!((image.width(), image.height()), (128, 64));
    }
    // The response's spread is printed beside the map and saved with it; the recovered
    // response leaves noise, no warning.
    let spread = printed_spread(&stdout(&out));
    assert!(spread < 5.0, "{}", stdout(&out));
    assert!(!stderr(&out).contains("spread is"), "{}", stderr(&out));
    assert!(
        !stderr(&out).contains("step by one ratio"),
        "{}",
        stderr(&out)
    );
    let saved = std::fs::read_to_string(dir.path().join("response.csv")).unwrap();
    assert!(saved.starts_with("# spread 0.0"), "{saved}");
    // The rest of hprt takes it; and the saved response gives the same map back.
    let out = hprt(
        dir.path(),
        &["decompose", "captured.exr", "-o", "lights.json"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let again = [
        "capture",
        "capture.toml",
        "-o",
        "again.exr",
        "--width",
        "128",
        "--response",
        "response.csv",
    ];
    let out = hprt(dir.path(), &again);
    assert!(out.status.success(), "{}", stderr(&out));
    let second = foundation::image_io::read_exr(&dir.path().join("again.exr")).unwrap();
    for (a, b) in map.pixels.iter().zip(&second.pixels) {
        assert!(
            (*a - *b).abs().max_element() <= 1e-3 * a.max_element().max(1e-3),
            "{a} vs {b}"
        );
    }
}

/// The library's errors are values a caller can match on, each naming the file at fault.
#[test]
fn capture_errors_are_typed() {
    use capture::{CaptureError, EntryKind, EntryProblem};
    let dir = tempfile::tempdir().unwrap();
    let good = write_ball_capture(dir.path(), &TIMES[..2]);
    let path = dir.path().join("capture.toml");
    let second_ball_fov = good.replace(
        "[[ball]]\nimage = \"ball0_1.png\"\nexposure = 0.00013\ncentre = [48.0, 48.0]\n\
         radius = 40.0\nfov = 25",
        "[[ball]]\nimage = \"ball0_1.png\"\nexposure = 0.00013\ncentre = [48.0, 48.0]\n\
         radius = 40.0\nfov = 200",
    );
    assert_ne!(second_ball_fov, good);
    std::fs::write(&path, &second_ball_fov).unwrap();
    match capture::load_capture(&path) {
        Err(CaptureError::Entry {
            path: at,
            entry: EntryKind::Ball,
            index: 2,
            problem: EntryProblem::FieldOfView(fov),
        }) => assert_eq!((at, fov), (path.clone(), 200.0)),
        other => panic!("{other:?}"),
    }
    std::fs::write(&path, "").unwrap();
    assert!(matches!(
        capture::load_capture(&path),
        Err(CaptureError::NoPhotographs { path: at }) if at == path
    ));
}

/// Exposures in equal steps leave the response's shape within a step to the priors: the
/// capture still succeeds, and says so.
#[test]
fn equal_exposure_steps_are_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let times: Vec<f32> = (0..5).map(|k| 4e-5 * 8f32.powi(k)).collect();
    write_ball_capture(dir.path(), &times);
    let args = [
        "capture",
        "capture.toml",
        "-o",
        "captured.exr",
        "--width",
        "64",
    ];
    let out = hprt(dir.path(), &args);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("step by one ratio (x8.0, 3.0 stops)"),
        "{}",
        stderr(&out)
    );
}

/// The response spread `hprt capture` printed, in percent.
fn printed_spread(stdout: &str) -> f32 {
    let after = stdout.split(" spread ").nth(1).expect("a spread printed");
    after
        .split('%')
        .next()
        .and_then(|v| v.parse().ok())
        .expect("a percentage")
}

/// A response that does not fit the photographs (a linear camera's, for a camera with a
/// gamma of 2) spreads a texel's exposures apart: the spread says so, with a warning, and
/// `--coverage` marks the texels yellow.
#[test]
fn a_wrong_response_is_flagged_by_its_spread() {
    let dir = tempfile::tempdir().unwrap();
    write_ball_capture(dir.path(), &TIMES);
    let mut linear = String::from("# a linear camera\nlevel,r,g,b\n");
    for z in 0..256 {
        let g = z as f32 / 128.0;
        writeln!(linear, "{z},{g},{g},{g}").unwrap();
    }
    std::fs::write(dir.path().join("linear.csv"), linear).unwrap();
    let args = [
        "capture",
        "capture.toml",
        "-o",
        "captured.exr",
        "--width",
        "128",
        "--response",
        "linear.csv",
        "--coverage",
        "coverage.png",
    ];
    let out = hprt(dir.path(), &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let spread = printed_spread(&stdout(&out));
    assert!(spread > 10.0, "{}", stdout(&out));
    assert!(
        stderr(&out).contains("spread is") && stderr(&out).contains("linear.csv"),
        "{}",
        stderr(&out)
    );
    let coverage = image::open(dir.path().join("coverage.png"))
        .unwrap()
        .to_rgb8();
    let yellow = coverage
        .pixels()
        .filter(|p| p.0[2] == 0 && p.0[0] >= 128 && p.0[1] >= 128)
        .count();
    assert!(yellow >= 32, "{yellow} yellow texels");
}

/// Runs `hprt capture` on `toml` in a folder of the ball capture and expects a clean failure
/// naming `needles`, with no output written.
fn refused(dir: &Path, toml: &str, needles: &[&str]) {
    std::fs::write(dir.join("bad.toml"), toml).unwrap();
    let out = hprt(
        dir,
        &["capture", "bad.toml", "-o", "bad.exr", "--width", "64"],
    );
    assert_clean_failure(&out, needles);
    assert!(!dir.join("bad.exr").exists());
}

#[test]
fn bad_captures_are_refused_with_the_file_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = write_ball_capture(d, &TIMES[..2]);
    let first = good.split("\n\n").next().unwrap().to_string() + "\n";
    // One exposure: nothing to recover the response from.
    refused(d, &first, &["do not overlap in exposure"]);
    // An exposure missing.
    refused(
        d,
        &first.replace("exposure = 0.00004\n", ""),
        &["ball0_0.png", "no exposure time"],
    );
    // A ball to be found in a picture that shows none.
    let plain = ShotCamera::new((0.0, 0.0, 0.0), 60.0, (96, 96), (0.0, 0.0));
    let mut rng = Pcg32::new(3, 4);
    let photo = photograph(
        &interior(128),
        View::Shot(plain),
        (96, 96),
        6e-4,
        &RESPONSE,
        &mut rng,
    );
    let bytes: Vec<u8> = photo.levels.iter().flatten().copied().collect();
    image::save_buffer(
        d.join("room.png"),
        &bytes,
        96,
        96,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
    refused(
        d,
        "[[ball]]\nimage = \"room.png\"\nexposure = 6e-4\nfov = 25.0\n\n\
         [[ball]]\nimage = \"room.png\"\nexposure = 6e-3\nfov = 25.0\n",
        &["room.png", "no mirror ball found"],
    );
    // A ball that is not in the picture.
    refused(
        d,
        &good.replacen("centre = [48.0, 48.0]", "centre = [90.0, 48.0]", 1),
        &["ball0_0.png", "not inside"],
    );
    // Photographs of different sizes.
    image::save_buffer(
        d.join("small.png"),
        &[128u8; 3 * 96 * 90],
        96,
        90,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
    refused(
        d,
        &good.replacen("ball0_1.png", "small.png", 1),
        &["small.png", "one size"],
    );
    // A corrupt JPEG.
    std::fs::write(d.join("broken.jpg"), b"\xff\xd8\xff\xe0 not really a jpeg").unwrap();
    refused(
        d,
        &good.replacen("ball0_1.png", "broken.jpg", 1),
        &["broken.jpg", "cannot be read"],
    );
    // A photograph that is not there.
    refused(
        d,
        &good.replacen("ball0_1.png", "missing.png", 1),
        &["missing.png"],
    );
}

/// Photographs as a camera leaves them: JPEGs whose exposure is only in their EXIF. The
/// capture reads the times and gives the map the same photographs give with their times
/// written in the description.
#[test]
fn exposures_are_read_from_exif() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plan = ball_plan(vec![5e-5, 4.6e-4, 3.7e-3, 3.8e-2], 5);
    write_capture(&interior(128), &plan, d).unwrap();
    let text = std::fs::read_to_string(d.join("capture.toml")).unwrap();
    assert!(
        !text.contains("exposure =") && !text.contains("centre ="),
        "{text}"
    );
    // The outline write_capture used, given (each description in its own way).
    let (mut exif, mut given) = (String::new(), String::new());
    for (k, entry) in text.split("[[ball]]").skip(1).enumerate() {
        let entry = entry.trim_end().to_string() + "\n";
        let outline = "centre = [100.0, 100.0]\nradius = 84.0\n";
        let t = plan.times[k % plan.times.len()];
        writeln!(exif, "[[ball]]{entry}{outline}").unwrap();
        write!(given, "[[ball]]{entry}{outline}exposure = {t}\n\n").unwrap();
    }
    std::fs::write(d.join("exif.toml"), exif).unwrap();
    std::fs::write(d.join("given.toml"), given).unwrap();
    for name in ["exif", "given"] {
        let args = [
            "capture",
            &format!("{name}.toml"),
            "-o",
            &format!("{name}.exr"),
            "--width",
            "128",
        ];
        let out = hprt(d, &args);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let a = foundation::image_io::read_exr(&d.join("exif.exr")).unwrap();
    let b = foundation::image_io::read_exr(&d.join("given.exr")).unwrap();
    for (x, y) in a.pixels.iter().zip(&b.pixels) {
        assert!(
            (luminance(*x) - luminance(*y)).abs() <= 1e-3 * luminance(*y).max(1e-3),
            "{x} vs {y}"
        );
    }
}

/// A ball whose outline the description leaves out is found in its photographs, and the map
/// comes out as the true outline gives it.
#[test]
fn a_ball_found_in_the_pictures_gives_the_map_its_true_outline_gives() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_capture(&interior(128), &ball_plan(TIMES.to_vec(), 6), d).unwrap();
    // The outline write_capture drew: centred, 0.42 of the picture's side.
    with_outline(d, "given.toml", 84.0);
    for (description, output) in [("capture.toml", "found.exr"), ("given.toml", "given.exr")] {
        let out = hprt(d, &["capture", description, "-o", output, "--width", "128"]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    // Each against the map photographed (one white-balance scale per channel: the capture is
    // in relative units).
    let truth = interior(128);
    let error = |name: &str| {
        let map = foundation::image_io::read_exr(&d.join(name)).unwrap();
        log_errors(&truth, &map.pixels, map.width)
    };
    let (found, given) = (error("found.exr"), error("given.exr"));
    assert!(
        found.0 <= given.0 * 1.2 + 0.005 && found.1 <= given.1 * 1.2 + 0.01,
        "found: median {}, 90th percentile {}; given: {}, {}",
        found.0,
        found.1,
        given.0,
        given.1
    );
}

/// The median and 90th percentile over texels of `|ln(captured · s_c / truth)|` (luminance),
/// `s_c` per channel making the means agree.
fn log_errors(truth: &EnvMap, captured: &[foundation::Rgb], width: usize) -> (f32, f32) {
    let truth = truth.downsampled((truth.width() / width).max(1));
    assert_eq!(truth.texels().len(), captured.len());
    let sum = |texels: &[foundation::Rgb]| texels.iter().fold(foundation::Rgb::ZERO, |s, c| s + *c);
    let scale = sum(truth.texels()) / sum(captured);
    let mut errors: Vec<f32> = captured
        .iter()
        .zip(truth.texels())
        .map(|(c, t)| {
            (luminance(*c * scale).max(1e-6) / luminance(*t).max(1e-6))
                .ln()
                .abs()
        })
        .collect();
    errors.sort_by(f32::total_cmp);
    (errors[errors.len() / 2], errors[errors.len() * 9 / 10])
}

/// A mirror ball (0.42 of a 200-pixel picture across, centred) photographed from two sides at
/// `times` by [`write_capture`].
fn ball_plan(times: Vec<f32>, seed: u64) -> CapturePlan {
    CapturePlan {
        size: (200, 200),
        orientations: Vec::new(),
        fov: 90.0,
        ball_yaws: vec![0.0, 90.0],
        times,
        response: RESPONSE,
        samples: 4,
        seed,
        quality: 92,
        provenance: String::new(),
    }
}

/// An outline given a few pixels too large mixes the room around the ball into the response's
/// samples: the capture still writes a finite map (its merge weights once overflowed there and
/// the map came out with NaN texels, refused by the EXR writer).
#[test]
fn an_outline_given_too_large_still_gives_a_finite_map() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_capture(&interior(128), &ball_plan(TIMES.to_vec(), 6), d).unwrap();
    with_outline(d, "large.toml", 88.0);
    let out = hprt(
        d,
        &["capture", "large.toml", "-o", "large.exr", "--width", "128"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let map = foundation::image_io::read_exr(&d.join("large.exr")).unwrap();
    assert!(map.pixels.iter().all(|c| c.is_finite()));
}

/// Writes `name` beside `dir`'s `capture.toml`: the same balls with their outline given, centred
/// in the 200-pixel pictures with `radius`.
fn with_outline(dir: &Path, name: &str, radius: f32) {
    let text = std::fs::read_to_string(dir.join("capture.toml")).unwrap();
    let described: String = text
        .split("[[ball]]")
        .skip(1)
        .map(|entry| {
            format!(
                "[[ball]]\n{}\ncentre = [100.0, 100.0]\nradius = {radius:.1}\n\n",
                entry.trim()
            )
        })
        .collect();
    std::fs::write(dir.join(name), described).unwrap();
}
