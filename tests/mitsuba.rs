//! hprt's path-traced reference against Mitsuba 3, on every test run.
//!
//! `tests/run.sh` installs Mitsuba 3 into a private virtual environment (`target/mitsuba-venv`)
//! and points `HPRT_MITSUBA_PYTHON` at its interpreter. Without it the test fails and says why:
//! a cross-check that skips itself silently protects nothing.
//!
//! The scene is small and deliberately asymmetric: a cube on a floor, seen from one side, under
//! a sky with one bright sun off every axis, so a mirrored or rotated map, a flipped camera or a
//! wrong sign anywhere moves the shadow and the shading and fails block by block. Beside it
//! stands an open bin whose inner walls are the backs of its triangles: Mitsuba renders the
//! export with the `thinsheet` plugin `hprt export` writes, which shows the front on both sides
//! as hprt does (CONVENTIONS.md, "Surfaces"); Mitsuba's own `twosided` fails the test there.
//! On the floor lies a poster textured with four colours, one per quadrant (an OBJ with
//! `map_Kd`): a texture exported mirrored, turned or as its mean moves colour between blocks.
//! The cube is glossy (a Phong lobe of shininess 40 over its diffuse colour): Mitsuba renders it
//! with the `hprtphong` plugin the export writes (CONVENTIONS.md, "Glossy materials"). In front
//! lie a copper ingot and a green slab of glTF's metallic-roughness material (a metal of
//! roughness 0.35, a dielectric of 0.6): Mitsuba renders them with the
//! `hprtmetallicroughness` plugin, which evaluates the formula itself and samples GGX's
//! visible normals with Mitsuba's own sampler. A second scene stands Khronos'
//! NormalTangentMirrorTest model (textures, a normal map, mirrored texture coordinates) in the
//! sun: Mitsuba draws its normal map through the `hprtnormalmap` plugin.

mod common;

use common::*;
use foundation::color::Rgb;
use foundation::image_io::{RgbImageF32, read_exr, write_exr};
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::process::Command;

const WIDTH: usize = 128;
const HEIGHT: usize = 96;
/// Samples per pixel of each of the two independent renders per renderer.
const SPP: u32 = 128;
const BLOCKS: usize = 8;
/// Systematic differences allowed per block, relative: Mitsuba jitters samples over the pixel
/// (hprt uses its centre) and interpolates the map bilinearly (hprt: constant per texel).
/// Measured on this scene: 1.8% at most in one block and channel. The blocks' noise (one standard error: 0.3–0.5%)
/// comes from the samples themselves, so the tolerance needs no tuning when `SPP` changes.
const BIAS: f32 = 0.02;
/// Noise allowance: this many standard errors of the difference of the two block means.
const SIGMAS: f32 = 4.0;

/// The sun in the map: 4° in radius, 30° high, off every axis; it carries most of the map's
/// power. The scene turns the map by 70°, so the test also pins the rotation's sense.
fn sun_direction() -> Vec3 {
    let (elevation, azimuth) = (30f32.to_radians(), 305f32.to_radians());
    Vec3::new(
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
        -elevation.cos() * azimuth.cos(),
    )
}

fn sky(w: Vec3) -> Rgb {
    if w.angle_between(sun_direction()) < 4f32.to_radians() {
        return Rgb::new(400.0, 360.0, 300.0);
    }
    if w.y >= 0.0 {
        Rgb::new(0.3, 0.4, 0.6) * (0.5 + 0.5 * w.y) + Rgb::splat(0.1 * w.x.max(0.0))
    } else {
        Rgb::new(0.15, 0.12, 0.1)
    }
}

/// The map as an equirectangular EXR (CONVENTIONS.md's mapping), 512 × 256.
fn write_map(path: &Path) {
    let (w, h) = (512, 256);
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let u = (x as f32 + 0.5) / w as f32;
            let v = (y as f32 + 0.5) / h as f32;
            sky(foundation::envmap::direction_of_uv(u, v))
        })
        .collect();
    write_exr(path, &RgbImageF32::new(w, h, pixels)).unwrap();
}

fn write_scene_file(dir: &Path) -> PathBuf {
    let path = dir.join("cube.toml");
    std::fs::write(
        &path,
        format!(
            r#"[camera]
position = [2.2, 2.6, 3.6]
target = [-0.2, 0.3, 0.0]
fov_y_deg = 45
width = {WIDTH}
height = {HEIGHT}

[environment]
map = "sky.exr"
rotation_deg = 70

[[object]]
name = "floor"
box = {{ min = [-4, -0.05, -4], max = [4, 0, 4], skip_faces = ["-y"] }}
albedo = [0.6, 0.6, 0.6]

[[object]]
name = "poster"
mesh = "poster.obj"

[[object]]
name = "bin"
box = {{ min = [-2.1, 0, -0.9], max = [-1.1, 0.7, 0.1], skip_faces = ["+y", "-y"] }}
albedo = [0.3, 0.6, 0.8]

[[object]]
name = "cube"
box = {{ min = [-0.5, 0, -0.6], max = [0.5, 1.2, 0.4], skip_faces = ["-y"] }}
albedo = [0.6, 0.3, 0.15]
specular = [0.3, 0.4, 0.5]
shininess = 40

[[object]]
name = "ingot"
box = {{ min = [-1.7, 0, 0.8], max = [-0.7, 0.45, 1.6], skip_faces = ["-y"] }}
base_color = [0.95, 0.64, 0.54]
metallic = 1
roughness = 0.35

[[object]]
name = "slab"
box = {{ min = [-0.4, 0, 1.2], max = [0.5, 0.25, 2.0], skip_faces = ["-y"] }}
base_color = [0.2, 0.5, 0.3]
metallic = 0
roughness = 0.6
"#
        ),
    )
    .unwrap();
    path
}

/// A 1.6 m square lying 1 cm above the floor, textured with four colours (sRGB PNG, 4 × 4
/// texels, one colour per 2 × 2 quadrant), through an OBJ material library.
fn write_poster(dir: &Path) {
    let quadrants: [[u8; 3]; 4] = [[220, 40, 40], [40, 200, 60], [40, 60, 220], [230, 210, 40]];
    let pixels: Vec<u8> = (0..16)
        .flat_map(|i| quadrants[(i / 8) * 2 + (i % 4) / 2])
        .collect();
    image::RgbImage::from_raw(4, 4, pixels)
        .unwrap()
        .save(dir.join("poster.png"))
        .unwrap();
    std::fs::write(
        dir.join("poster.mtl"),
        "newmtl poster\nKd 0.9 0.9 0.9\nmap_Kd poster.png\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("poster.obj"),
        "mtllib poster.mtl\no poster\n\
         v 0.7 0.01 -0.2\nv 2.3 0.01 -0.2\nv 2.3 0.01 1.4\nv 0.7 0.01 1.4\n\
         vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nvn 0 1 0\nusemtl poster\n\
         f 1/1/1 4/4/1 3/3/1 2/2/1\n",
    )
    .unwrap();
}

/// The Python interpreter with Mitsuba 3, or a panic that says how to get one.
fn mitsuba_python() -> String {
    let python = std::env::var("HPRT_MITSUBA_PYTHON").unwrap_or_else(|_| "python3".into());
    let check = Command::new(&python)
        .args(["-c", "import mitsuba; print(mitsuba.__version__)"])
        .output();
    match check {
        Ok(out) if out.status.success() => {
            println!("Mitsuba {}", String::from_utf8_lossy(&out.stdout).trim());
            python
        }
        other => {
            let reason = match other {
                Ok(out) => String::from_utf8_lossy(&out.stderr).into_owned(),
                Err(e) => e.to_string(),
            };
            let log = std::env::var("HPRT_MITSUBA_INSTALL_LOG")
                .ok()
                .and_then(|p| std::fs::read_to_string(p).ok())
                .unwrap_or_default();
            panic!(
                "Mitsuba 3 is not available to {python}: {reason}\n\
                 tests/run.sh installs it into target/mitsuba-venv (pip install mitsuba); \
                 or set HPRT_MITSUBA_PYTHON to an interpreter that has it.\n{log}"
            );
        }
    }
}

/// Mean and variance of the mean of each block, from two independent renders `a` and `b`:
/// the estimate is their average; each pixel's variance of that average is `(a − b)² / 4`.
fn block_statistics(
    a: &RgbImageF32,
    b: &RgbImageF32,
    channel: usize,
    mask: &[bool],
) -> Vec<(f32, f32, usize)> {
    let (bw, bh) = (WIDTH / BLOCKS, HEIGHT / BLOCKS);
    let mut blocks = vec![(0.0f64, 0.0f64, 0usize); BLOCKS * BLOCKS];
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let i = y * WIDTH + x;
            if !mask[i] {
                continue;
            }
            let (la, lb) = (a.pixels[i][channel], b.pixels[i][channel]);
            let block = &mut blocks[(y / bh) * BLOCKS + x / bw];
            block.0 += f64::from(0.5 * (la + lb));
            block.1 += f64::from((la - lb) * (la - lb) / 4.0);
            block.2 += 1;
        }
    }
    blocks
        .into_iter()
        .map(|(sum, var, n)| {
            let n_f = n.max(1) as f64;
            ((sum / n_f) as f32, (var / (n_f * n_f)) as f32, n)
        })
        .collect()
}

/// The mean luminance of the pixels in `mask`, from two renders, and the variance of that mean.
fn masked_statistics(a: &RgbImageF32, b: &RgbImageF32, mask: &[bool]) -> (f32, f32) {
    let (mut sum, mut var, mut n) = (0.0f64, 0.0f64, 0usize);
    for ((pa, pb), _) in a
        .pixels
        .iter()
        .zip(&b.pixels)
        .zip(mask)
        .filter(|(_, m)| **m)
    {
        {
            let la = foundation::luminance(*pa);
            let lb = foundation::luminance(*pb);
            sum += f64::from(0.5 * (la + lb));
            var += f64::from((la - lb) * (la - lb) / 4.0);
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    ((sum / n) as f32, (var / (n * n)) as f32)
}

/// hprt's reference (seeds 0 and 1, the first with its auxiliary images in `aux/`) and
/// Mitsuba's render of `hprt export`'s files (seeds 0 and 1) of `scene`, each read back.
fn render_both(d: &Path, python: &str, scene: &Path) -> [RgbImageF32; 4] {
    let s = scene.to_str().unwrap();
    let spp = SPP.to_string();
    let common = ["--spp", spp.as_str(), "--bounces", "2"];
    let mut export = vec!["export", s, "-o", "mts"];
    export.extend(common);
    let out = hprt(d, &export);
    assert!(out.status.success(), "{}", stderr(&out));
    for seed in ["0", "1"] {
        let file = format!("hprt-{seed}.exr");
        let mut args = vec!["reference", s, "--seed", seed, "-o", &file];
        args.extend(common);
        if seed == "0" {
            args.extend(["--aux", "aux"]);
        }
        let out = hprt(d, &args);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let script = r#"
import sys
import mitsuba as mi
mi.set_variant("scalar_rgb")
sys.path.insert(0, "mts")
import thinsheet
import phong
import metallic_roughness
import normal_map
scene = mi.load_file("mts/scene.xml", surface="thinsheet")
for seed in (0, 1):
    mi.util.write_bitmap(f"mitsuba-{seed}.exr", mi.render(scene, seed=seed))
"#;
    let out = Command::new(python)
        .args(["-c", script])
        .current_dir(d)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "Mitsuba failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |name: &str| read_exr(&d.join(name)).unwrap();
    let images = ["hprt-0.exr", "hprt-1.exr", "mitsuba-0.exr", "mitsuba-1.exr"].map(read);
    assert_eq!((images[2].width, images[2].height), (WIDTH, HEIGHT));
    images
}

/// Each colour channel of each block of an 8 × 8 grid, hprt's two renders against Mitsuba's:
/// the blocks further apart than [`BIAS`] plus [`SIGMAS`] standard errors.
fn differing_blocks(images: &[RgbImageF32; 4]) -> Vec<String> {
    let [h0, h1, m0, m1] = images;
    let everything = vec![true; WIDTH * HEIGHT];
    let mut failures = Vec::new();
    let (mut worst, mut largest) = (0.0f32, 0.0f32);
    for channel in 0..3 {
        let ours = block_statistics(h0, h1, channel, &everything);
        let theirs = block_statistics(m0, m1, channel, &everything);
        for (i, ((h, hv, _), (m, mv, _))) in ours.iter().zip(&theirs).enumerate() {
            let tolerance = BIAS * m + SIGMAS * (hv + mv).sqrt();
            let off = (h - m).abs();
            largest = largest.max(off / m);
            worst = worst.max(off / tolerance);
            if off > tolerance {
                failures.push(format!(
                    "block ({}, {}), {}: hprt {h:.4} Mitsuba {m:.4}, tolerance {tolerance:.4}",
                    i % BLOCKS,
                    i / BLOCKS,
                    ["red", "green", "blue"][channel]
                ));
            }
        }
    }
    println!(
        "largest difference {:.2}% of a block's mean; worst block at {worst:.2} of its tolerance",
        100.0 * largest
    );
    failures
}

#[test]
fn mitsuba_agrees_with_the_reference_block_by_block() {
    let python = mitsuba_python();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(&d.join("sky.exr"));
    write_poster(d);
    let scene = write_scene_file(d);
    let images = render_both(d, &python, &scene);
    let failures = differing_blocks(&images);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let [h0, h1, m0, m1] = &images;
    let read = |name: &str| read_exr(&d.join(name)).unwrap();
    let visibility = read("aux/visibility.exr");
    let coverage = read("aux/coverage.exr");

    // The shadow: the pixels hprt finds in shadow (direct visibility below 0.5) are as dark in
    // Mitsuba's image, and there are enough of them to matter.
    let shadow: Vec<bool> = (0..WIDTH * HEIGHT)
        .map(|i| coverage.pixels[i].x > 0.5 && visibility.pixels[i].x < 0.5)
        .collect();
    let lit: Vec<bool> = (0..WIDTH * HEIGHT)
        .map(|i| coverage.pixels[i].x > 0.5 && visibility.pixels[i].x > 0.9)
        .collect();
    let shadow_pixels = shadow.iter().filter(|s| **s).count();
    assert!(shadow_pixels > 500, "only {shadow_pixels} shadow pixels");
    let (h, hv) = masked_statistics(h0, h1, &shadow);
    let (m, mv) = masked_statistics(m0, m1, &shadow);
    let tolerance = BIAS * m + SIGMAS * (hv + mv).sqrt();
    println!("shadow ({shadow_pixels} pixels): hprt {h:.4} Mitsuba {m:.4} ± {tolerance:.4}");
    assert!((h - m).abs() < tolerance, "shadow: hprt {h} Mitsuba {m}");
    let (lit_mean, _) = masked_statistics(m0, m1, &lit);
    assert!(
        m < 0.5 * lit_mean,
        "Mitsuba's image is not dark in hprt's shadow: {m} vs lit {lit_mean}"
    );
}

/// A textured PBR model we did not make, with its normal map: Khronos' NormalTangentMirrorTest
/// (base colour texture, metallic-roughness layer, tangents supplied, mirrored texture
/// coordinates) standing on a floor in the low sun, rendered by hprt and by Mitsuba through the
/// export's `hprtnormalmap` plugin (hprt's tangents, Mitsuba's texture lookup and frames): the
/// mean luminance over the model agrees within 3% (measured: 0.02%; the map itself brightens
/// the model by 7% in both renderers, so a map left out fails), and over the whole frame too. Not block by block: on this model hprt's
/// path tracer leaves single-pixel fireflies (tens of times the block's median) that Mitsuba's
/// does not, with the normal map or without it, which the block means cannot absorb.
#[test]
fn mitsuba_agrees_on_a_normal_mapped_model() {
    let python = mitsuba_python();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(&d.join("sky.exr"));
    std::fs::copy(
        repo().join("scenes/models/NormalTangentMirrorTest.glb"),
        d.join("panel.glb"),
    )
    .unwrap();
    let scene = d.join("panel.toml");
    std::fs::write(
        &scene,
        format!(
            r#"[camera]
position = [0.6, 0.4, 3.4]
target = [0, -0.1, 0]
fov_y_deg = 45
width = {WIDTH}
height = {HEIGHT}

[environment]
map = "sky.exr"
rotation_deg = 200

[[object]]
name = "floor"
box = {{ min = [-4, -1.3, -4], max = [4, -1.25, 4], skip_faces = ["-y"] }}
albedo = [0.6, 0.6, 0.6]

[[object]]
name = "panel"
mesh = "panel.glb"
"#
        ),
    )
    .unwrap();
    let [h0, h1, m0, m1] = &render_both(d, &python, &scene);
    // The middle half of the image in each direction lies on the panel (2.8 m × 2.25 m seen
    // from 3.4 m: it fills three quarters of the frame).
    let model: Vec<bool> = (0..WIDTH * HEIGHT)
        .map(|i| {
            let (x, y) = (i % WIDTH, i / WIDTH);
            (WIDTH / 4..3 * WIDTH / 4).contains(&x) && (HEIGHT / 4..3 * HEIGHT / 4).contains(&y)
        })
        .collect();
    let (h, _) = masked_statistics(h0, h1, &model);
    let (m, _) = masked_statistics(m0, m1, &model);
    println!("mean luminance over the model: hprt {h:.4}, Mitsuba {m:.4}");
    assert!(
        (h / m - 1.0).abs() < 0.03,
        "over the model: hprt {h} Mitsuba {m}"
    );
    let everything = vec![true; WIDTH * HEIGHT];
    let (h, _) = masked_statistics(h0, h1, &everything);
    let (m, _) = masked_statistics(m0, m1, &everything);
    println!("mean luminance over the frame: hprt {h:.4}, Mitsuba {m:.4}");
    assert!(
        (h / m - 1.0).abs() < 0.03,
        "over the frame: hprt {h} Mitsuba {m}"
    );
}
