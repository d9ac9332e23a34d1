//! `hprt bench composite`: what the live composite adds to a frame (issue 31's target: at
//! most 20% over the same scene drawn whole).

use super::render::time_frames;
use crate::support::{load_scene, median};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use foundation::scene::{ObjectRole, Scene};
use precompute::bake::{self, BakeSettings, Transfer};
use report::gpu_composite::live_backplate;
use runtime::render::{GpuContext, RenderMode, Renderer, ShadowSettings};
use runtime::{DecomposeSettings, EnvironmentLighting};
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchCompositeArgs {
    /// Scenes with a [backplate] (default: the bundled composite example).
    #[arg(default_values = ["scenes/teapot_composite.toml"])]
    pub scenes: Vec<PathBuf>,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Frames timed per configuration (after one warm-up frame); medians are reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 20)]
    pub frames: usize,
    /// Repeats of each configuration, alternated; the median of their medians is reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 5)]
    pub repeats: usize,
    /// Rays per vertex of the bakes made for the benchmark (their quality does not matter).
    #[arg(long, default_value_t = 32)]
    pub bake_samples: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

pub(super) fn bench_composite(args: BenchCompositeArgs) -> anyhow::Result<()> {
    let gpu = GpuContext::headless(args.backend)?;
    println!(
        "live composite benchmark on {}: {}x{}, hybrid, median of {} frames x {} repeats",
        gpu.description(),
        args.width,
        args.height,
        args.frames,
        args.repeats
    );
    println!(
        "{:<20} {:>10} {:>13} {:>8} {:>11} {:>14} {:>8}",
        "scene", "whole ms", "composite ms", "ratio", "whole dyn", "composite dyn", "ratio"
    );
    for path in &args.scenes {
        let scene = load_scene(path)?;
        anyhow::ensure!(
            scene.backplate.is_some(),
            "{}: no [backplate] to composite into",
            path.display()
        );
        let runs = bench_scene(&args, &gpu, &scene)?;
        // Ratios of back-to-back runs: the machine's drift cancels in each.
        let ratio = |a: usize, b: usize| {
            median(
                runs[a]
                    .iter()
                    .zip(&runs[b])
                    .map(|(whole, composite)| composite / whole)
                    .collect(),
            )
        };
        let t = runs.clone().map(median);
        println!(
            "{:<20} {:>10.2} {:>13.2} {:>8.3} {:>11.2} {:>14.2} {:>8.3}",
            scene.name,
            t[0],
            t[1],
            ratio(0, 1),
            t[2],
            t[3],
            ratio(2, 3)
        );
    }
    println!(
        "whole: the same scene drawn with its proxies as ordinary objects; dyn: the map turning a \
         degree a frame (vertex radiance and shadow maps redone every frame); ratio: the median of \
         each repeat's composite / whole."
    );
    Ok(())
}

/// The scene's bake and its proxies' bake alone, at the benchmark's settings.
fn bakes(scene: &Scene, samples: u32) -> anyhow::Result<(Transfer, Transfer)> {
    let settings = BakeSettings {
        order: 5,
        samples,
        bounces: 1,
        seed: 0,
    };
    let bake_of = |geometry: &foundation::scene::SceneMesh| {
        let bvh = SceneBvh::build(&geometry.mesh);
        bake::bake(geometry, &bvh, &settings, &NoProgress).map(|(t, _)| t)
    };
    let proxies = scene.geometry.of_role(ObjectRole::Proxy);
    Ok((bake_of(&scene.geometry)?, bake_of(&proxies)?))
}

/// Each repeat's median frame times: whole static, composite static, whole dynamic, composite
/// dynamic.
fn bench_scene(
    args: &BenchCompositeArgs,
    gpu: &GpuContext,
    scene: &Scene,
) -> anyhow::Result<[Vec<f64>; 4]> {
    let (whole, proxies) = bakes(scene, args.bake_samples)?;
    let env = scene
        .environment
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("{}: no [environment]", scene.path.display()))?;
    let map = crate::maps::load_map(&env.map, None)?.map;
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default())?;
    let camera = scene.camera.with_size(args.width, args.height);
    let mut renderer = Renderer::new(
        gpu,
        &scene.geometry,
        &whole,
        &camera,
        ShadowSettings::default(),
    )?;
    renderer.set_environment(&map, env.rotation_deg);
    let backplate = live_backplate(scene)?;
    let mut runs: [Vec<f64>; 4] = Default::default();
    for _ in 0..args.repeats.max(1) {
        for (k, composite) in [false, true].into_iter().enumerate() {
            match composite {
                true => renderer.enable_composite(&scene.geometry, &proxies, &backplate)?,
                false => renderer.disable_composite(),
            }
            lighting.set_rotation(env.rotation_deg);
            renderer.set_environment_rotation(env.rotation_deg);
            renderer.set_lighting(&lighting.frame(RenderMode::Hybrid, None).lighting)?;
            runs[k].push(time_frames(args.frames, || {
                renderer.render()?;
                renderer.wait();
                Ok(())
            })?);
            let mut angle = env.rotation_deg;
            runs[2 + k].push(time_frames(args.frames, || {
                angle += 1.0;
                lighting.set_rotation(angle);
                renderer.set_environment_rotation(angle);
                renderer.set_lighting(&lighting.frame(RenderMode::Hybrid, None).lighting)?;
                renderer.render()?;
                renderer.wait();
                Ok(())
            })?);
        }
    }
    Ok(runs)
}
