//! The GPU renderer end to end: the hybrid against the reference, bad inputs and adapters,
//! the background and textures.

mod common;

use common::*;
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::infra::progress::NoProgress;
use foundation::scene::{Scene, SceneMesh};
use foundation::sh::ShCoeffs;
use foundation::{Rgb, luminance};
use glam::Vec3;
use reference::{self, EnvironmentLight, ReferenceSettings};
use runtime::ShTransfer;
use runtime::render::{FrameLighting, RenderMode, Renderer, ShadowSettings};
use runtime::{CubeSource, DecomposeMode, DecomposeSettings, Decomposer, DirectionalLight};

/// Mean |Y(tonemap(a)) - Y(tonemap(b))| over the masked pixels.
#[test]
fn hybrid_beats_prt_in_the_shadows_against_the_reference() {
    let teapot = Scene::load(&scene("teapot.toml")).unwrap();
    let map = foundation::envmap::load(&scene("env/sunrise.exr"), None)
        .unwrap()
        .map;
    let rotation = teapot.environment.as_ref().unwrap().rotation_deg;
    let cam = teapot.camera.with_size(160, 120);
    let transfer = bake_of(&teapot.geometry, 5, 256, 2);

    // The reference at test time: small and noisy, but unbiased.
    let bvh = SceneBvh::build(&teapot.geometry.mesh);
    let light = EnvironmentLight::new(&map, rotation);
    let settings = ReferenceSettings::new(96, 2, 1);
    let truth = reference::render(&teapot.geometry, &bvh, &light, &cam, &settings, &NoProgress);

    let decompose = DecomposeSettings::default();
    let cube = CubeSource::new(&map, decompose.face_size).cube(rotation.to_radians());
    let mut decomposer = Decomposer::new(decompose).unwrap();
    let decomposition = decomposer.decompose(&cube);
    let projection = decomposer.project(&cube);
    for gpu in gpus() {
        let mut images = Vec::new();
        for mode in [RenderMode::Hybrid, RenderMode::Prt] {
            let lighting = FrameLighting::for_mode(mode, &projection, &decomposition, true);
            images.push(render(&gpu, &teapot.geometry, &transfer, &cam, &lighting));
        }
        let exposure = 0.5 / map.mean_luminance();
        let covered: Vec<bool> = truth.coverage.iter().map(|c| *c > 0.0).collect();
        let shadow: Vec<bool> = truth
            .coverage
            .iter()
            .zip(&truth.visibility)
            .map(|(c, v)| *c > 0.0 && *v < 0.5)
            .collect();
        assert!(
            shadow.iter().filter(|s| **s).count() > 500,
            "the teapot casts a shadow"
        );
        let hybrid = tone_mapped_error(&images[0], &truth.radiance, &covered, exposure);
        let prt = tone_mapped_error(&images[1], &truth.radiance, &covered, exposure);
        let hybrid_shadow = tone_mapped_error(&images[0], &truth.radiance, &shadow, exposure);
        let prt_shadow = tone_mapped_error(&images[1], &truth.radiance, &shadow, exposure);
        println!(
            "mean error: hybrid {hybrid:.4} prt {prt:.4}; shadow region: hybrid {hybrid_shadow:.4} prt {prt_shadow:.4}"
        );
        // Bound: the thesis' PRT on its teapot scenes ranged 0.0065-0.0271 (Table 5.1); 0.02 allows
        // for this test's 96-spp reference noise (about 0.005 per pixel) on top of approximation
        // error, and is still below what plain PRT reaches in the shadows here.
        assert!(hybrid < 0.02, "hybrid mean error {hybrid}");
        assert!(
            hybrid_shadow < prt_shadow,
            "shadow region: hybrid {hybrid_shadow} vs prt {prt_shadow}"
        );

        // hybrid/thesis, the thesis' own method at its own default radius. Its SH part keeps the
        // whole map and its lights add the sources again: by design it double counts them. On the
        // table's lit pixels (reference visibility above 0.97, normal +Y) its lights alone must
        // add their Lambert term `ρ/π Σ Φ_i max(0, d_i·y)` on top of what the SH part gives, so
        // it is brighter than the truth by at least `Σ Φ_i max(0, d_i·y) / E(y)`.
        let thesis_settings = DecomposeSettings::for_mode(DecomposeMode::Thesis, 5);
        let thesis = Decomposer::new(thesis_settings).unwrap().decompose(&cube);
        assert!(!thesis.lights.is_empty());
        let thesis_images: Vec<RgbImageF32> = [RenderMode::Hybrid, RenderMode::Lights]
            .into_iter()
            .map(|mode| {
                let lighting = FrameLighting::for_mode(mode, &projection, &thesis, false);
                render(&gpu, &teapot.geometry, &transfer, &cam, &lighting)
            })
            .collect();
        let table_albedo = Rgb::new(0.6, 0.48, 0.36);
        let lambert: Rgb = thesis
            .lights
            .iter()
            .map(|l| l.power * (l.direction.y.max(0.0) / std::f32::consts::PI))
            .sum::<Rgb>()
            * table_albedo;
        let basis = cam.basis();
        let mut lit_table = vec![false; truth.radiance.pixels.len()];
        for (i, lit) in lit_table.iter_mut().enumerate() {
            let (x, y) = (
                (i % cam.width as usize) as u32,
                (i / cam.width as usize) as u32,
            );
            let ray = cam.pixel_direction(&basis, x, y);
            *lit = truth.visibility[i] > 0.97
                && bvh
                    .intersect(cam.position, ray, 0.0, f32::MAX)
                    .is_some_and(|h| (cam.position + ray * h.t).y.abs() < 1e-3);
        }
        let lit_pixels = lit_table.iter().filter(|l| **l).count();
        assert!(lit_pixels > 1000, "{lit_pixels} lit table pixels");
        let mean_in = |image: &RgbImageF32| {
            let sum: f32 = (0..lit_table.len())
                .filter(|&i| lit_table[i])
                .map(|i| luminance(image.pixels[i]))
                .sum();
            sum / lit_pixels as f32
        };
        let lights_alone = mean_in(&thesis_images[1]) / luminance(lambert);
        let excess = mean_in(&thesis_images[0]) / mean_in(&truth.radiance);
        let predicted = 1.0
            + luminance(lambert)
                / luminance(table_albedo * (map.irradiance(Vec3::Y) / std::f32::consts::PI));
        println!(
            "hybrid/thesis on the lit table: lights {lights_alone:.4} of their Lambert term; \
         {excess:.3} × the reference (double count alone: {predicted:.3})"
        );
        assert!((lights_alone - 1.0).abs() < 0.02, "{lights_alone}");
        assert!(excess > predicted - 0.05, "{excess} vs {predicted}");
    }
}

#[test]
fn bad_inputs_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = write_scene(
        d,
        "a.toml",
        "box = { min = [-1, 0, -1], max = [1, 1, 1] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let b = write_scene(
        d,
        "b.toml",
        "box = { min = [-1, 0, -1], max = [1, 2, 1] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let env = scene("env/city.exr");
    assert!(
        hprt(d, &["bake", a.to_str().unwrap(), "-o", "a.bake"])
            .status
            .success()
    );
    let base = |s: &std::path::Path| {
        vec![
            "render".to_owned(),
            s.to_str().unwrap().to_owned(),
            "--bake".into(),
            "a.bake".into(),
            "--env".into(),
            env.to_str().unwrap().to_owned(),
        ]
    };
    let run = |mut args: Vec<String>, extra: &[&str]| {
        args.extend(extra.iter().map(|s| s.to_string()));
        hprt(d, &args.iter().map(String::as_str).collect::<Vec<_>>())
    };
    assert_clean_failure(
        &run(base(&b), &["-o", "x.png"]),
        &["a.bake", "made for another scene"],
    );
    assert_clean_failure(
        &run(base(&a), &["--order", "6", "-o", "x.png"]),
        &["order 2", "order 6", "re-bake"],
    );
    let mut missing = base(&a);
    missing[5] = "nowhere.exr".into();
    assert_clean_failure(&run(missing, &["-o", "x.png"]), &["nowhere.exr"]);
    assert!(!d.join("x.png").exists());
    // A working render, for contrast, reports its adapter.
    let out = run(
        base(&a),
        &[
            "--width", "32", "--height", "24", "-o", "ok.png", "--exr", "ok.exr",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("adapter:"));
    assert!(d.join("ok.png").exists() && d.join("ok.exr").exists());
}

#[test]
fn no_adapter_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = write_scene(
        d,
        "a.toml",
        "box = { min = [-1, 0, -1], max = [1, 1, 1] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    assert!(
        hprt(d, &["bake", a.to_str().unwrap(), "-o", "a.bake"])
            .status
            .success()
    );
    // Hide every Vulkan driver from the loader.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hprt"))
        .args([
            "render",
            a.to_str().unwrap(),
            "--bake",
            "a.bake",
            "--env",
            scene("env/city.exr").to_str().unwrap(),
        ])
        .args(["--backend", "vulkan", "-o", "x.png"])
        .current_dir(d)
        .env("VK_ICD_FILENAMES", "/nonexistent.json")
        .env("VK_DRIVER_FILES", "/nonexistent.json")
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    assert_clean_failure(&out, &["no Vulkan graphics adapter", "mesa-vulkan-drivers"]);
    assert!(!d.join("x.png").exists());
}

#[test]
fn vulkan_and_opengl_software_adapters_draw_the_same_image() {
    let geometry = sphere_on_plane();
    let transfer = bake_of(&geometry, 3, 32, 1);
    let light = DirectionalLight {
        direction: Vec3::new(0.3, 0.8, 0.5).normalize(),
        power: Rgb::splat(4.0),
        cap_radius: 0.1,
        angular_radius: 0.02,
        halo_radius: 0.02,
        core_fraction: 1.0,
        share: 0.5,
    };
    let lighting = FrameLighting {
        sh: uniform_sh(3, 0.5),
        lights: vec![light],
        lights_indirect: true,
        shadows: true,
        sh_transfer: ShTransfer::Baked,
        reflections: Default::default(),
    };
    let cam = camera(Vec3::new(3.0, 4.0, 6.0), Vec3::new(0.0, 0.5, 0.0), 96, 72);
    let images: Vec<RgbImageF32> = gpus()
        .iter()
        .map(|gpu| render(gpu, &geometry, &transfer, &cam, &lighting))
        .collect();
    let worst = images[0]
        .pixels
        .iter()
        .zip(&images[1].pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-2, "largest pixel difference {worst}");
}

/// The background: the map along each pixel's ray, bilinear where magnified, averaged over the
/// pixel where minified (a one-texel checkerboard shows its mean, not either square).
#[test]
fn background_shows_the_map_filtered() {
    let geometry = floor_with(1.0, &[]);
    let transfer = bake_of(&geometry, 2, 16, 0);
    // Looking up and away from the floor: every pixel sees the sky.
    let cam = camera(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.3, 2.0, -1.0), 64, 48);
    for gpu in gpus() {
        let mut renderer =
            Renderer::new(&gpu, &geometry, &transfer, &cam, ShadowSettings::default()).unwrap();
        renderer
            .set_lighting(&FrameLighting {
                sh: ShCoeffs::zeros(2),
                lights: Vec::new(),
                lights_indirect: false,
                shadows: false,
                sh_transfer: ShTransfer::Baked,
                reflections: Default::default(),
            })
            .unwrap();
        renderer.background = true;
        let basis = cam.basis();
        let smooth = EnvMap::from_fn(256, 128, 1, |w| {
            Rgb::new(1.0 + w.x, 1.0 + w.y, 1.0 + 0.5 * w.z)
        });
        let checker_texels = (0..1024)
            .flat_map(|j| (0..2048).map(move |i| Rgb::splat(((i + j) % 2) as f32 * 2.0)))
            .collect();
        let checker = EnvMap::new(2048, 1024, checker_texels);
        for (map, name) in [(&smooth, "smooth"), (&checker, "checker")] {
            renderer.set_environment(map, 30.0);
            renderer.render().unwrap();
            let image = renderer.read_back().unwrap();
            for j in 0..cam.height {
                for i in 0..cam.width {
                    let ray = cam.pixel_direction(&basis, i, j);
                    // The map is turned 30° about +Y: look up R_y(−30°) ray.
                    let expected = if name == "smooth" {
                        map.radiance(foundation::envmap::rotate_y(ray, -30f32.to_radians()))
                    } else {
                        Rgb::ONE
                    };
                    let got = image.get(i as usize, j as usize);
                    assert!(
                        ((got - expected) / expected).abs().max_element() < 0.03,
                        "{name} map, pixel ({i}, {j}): {got} for {expected}"
                    );
                }
            }
        }
    }
}

/// A textured quad under a uniform sky of radiance 1 reflects exactly its texel's albedo
/// (`E/π = 1`, nothing to shadow or interreflect): a checkerboard's two colours, pixel by
/// pixel on the GPU and in the path-traced reference (256 samples: its noise is below 0.7%
/// here), within 1% in the linear readback. Pixels within a texel of a cell edge (where
/// bilinear filtering blends) are left out.
#[test]
fn a_textured_quad_shows_its_texture_per_pixel_on_the_gpu_and_in_the_reference() {
    use foundation::image_io::srgb_decode;
    use foundation::texture::AlbedoTexture;
    use std::sync::Arc;
    const SIDE: usize = 16;
    const CELL: usize = 4;
    let colours = [[200u8, 60, 30], [40, 180, 220]]
        .map(|c| Rgb::from_array(c.map(|b| srgb_decode(f32::from(b) / 255.0))));
    let cell_of = |x: usize, y: usize| (x / CELL + y / CELL) % 2;
    let texture = Arc::new(AlbedoTexture {
        width: SIDE,
        height: SIDE,
        texels: (0..SIDE * SIDE)
            .map(|i| colours[cell_of(i % SIDE, i / SIDE)])
            .collect(),
    });
    let mut quad = plane_facing(Vec3::ZERO, Vec3::Y);
    let (u, v) = Vec3::Y.any_orthonormal_pair();
    quad.uvs = quad
        .positions
        .iter()
        .map(|p| glam::Vec2::new(0.5 + 0.5 * p.dot(u), 0.5 + 0.5 * p.dot(v)))
        .collect();
    let mut geometry = SceneMesh::default();
    geometry.push_textured_object("checker".into(), &quad, Rgb::ONE, texture);
    let cam = camera(Vec3::new(0.3, 2.6, 1.2), Vec3::ZERO, 96, 96);
    let transfer = bake_of(&geometry, 3, 256, 1);
    let reference = reference::render(
        &geometry,
        &SceneBvh::build(&geometry.mesh),
        &EnvironmentLight::new(&EnvMap::uniform(64, 32, Rgb::ONE), 0.0),
        &cam,
        &ReferenceSettings::new(256, 1, 0),
        &NoProgress,
    );

    // Which colour each pixel's centre sees, where it sees one cell clearly.
    let bvh = SceneBvh::build(&geometry.mesh);
    let basis = cam.basis();
    for gpu in gpus() {
        let image = render(
            &gpu,
            &geometry,
            &transfer,
            &cam,
            &FrameLighting::prt(uniform_sh(3, 1.0)),
        );
        let mut checked = [0usize; 2];
        for j in 0..96 {
            for i in 0..96 {
                let d = cam.pixel_direction(&basis, i, j);
                let Some(hit) = bvh.intersect(cam.position, d, 0.0, f32::INFINITY) else {
                    continue;
                };
                let p = cam.position + d * hit.t;
                let texel =
                    glam::Vec2::new(0.5 + 0.5 * p.dot(u), 0.5 + 0.5 * p.dot(v)) * SIDE as f32;
                let edge = |t: f32| {
                    let r = t.rem_euclid(CELL as f32);
                    r.min(CELL as f32 - r)
                };
                if edge(texel.x) < 1.0 || edge(texel.y) < 1.0 {
                    continue;
                }
                let colour = cell_of(texel.x as usize, texel.y as usize);
                let want = colours[colour];
                let gpu_pixel = image.pixels[(j * 96 + i) as usize];
                assert!(
                    ((gpu_pixel - want) / want).abs().max_element() < 0.01,
                    "GPU pixel ({i}, {j}): {gpu_pixel} vs {want}"
                );
                let traced = reference.radiance.pixels[(j * 96 + i) as usize];
                assert!(
                    ((traced - want) / want).abs().max_element() < 0.01,
                    "reference pixel ({i}, {j}): {traced} vs {want}"
                );
                checked[colour] += 1;
            }
        }
        assert!(
            checked.iter().all(|&n| n > 500),
            "pixels inside cells of each colour: {checked:?}"
        );
    }
}
