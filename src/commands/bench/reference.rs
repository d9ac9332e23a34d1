//! `hprt bench reference`: the reference renderer's speed.

use crate::maps::{self};
use crate::support::{load_scene, median, with_threads};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchReferenceArgs {
    /// Scene file (default: the bundled teapot scene).
    #[arg(default_value = "scenes/teapot.toml")]
    pub scene: PathBuf,
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Renders; the median is reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Skip the comparison with Mitsuba 3 (run when its Python package is found).
    #[arg(long)]
    pub no_mitsuba: bool,
}

pub(super) fn bench_reference(args: BenchReferenceArgs) -> anyhow::Result<()> {
    use reference::{self, EnvironmentLight, ReferenceSettings};
    let scene = load_scene(&args.scene)?;
    let env = maps::choose(&scene, None, None, None)?;
    let camera = scene.camera.with_size(args.width, args.height);
    camera.validate()?;
    let settings = ReferenceSettings::new(args.spp, args.bounces, 0);
    settings.validate()?;
    let runs = with_threads(args.threads, || {
        let bvh = SceneBvh::build(&scene.geometry.mesh);
        let light = EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
        (0..args.repeat.max(1))
            .map(|_| {
                reference::render(
                    &scene.geometry,
                    &bvh,
                    &light,
                    &camera,
                    &settings,
                    &NoProgress,
                )
            })
            .collect::<Vec<_>>()
    })?;
    let seconds = median(runs.iter().map(|r| r.stats.seconds).collect());
    let rays_per_second = median(runs.iter().map(|r| r.stats.rays_per_second()).collect());
    let megapixel_samples = args.width as f64 * args.height as f64 * args.spp as f64 / 1e6;
    let per = seconds / megapixel_samples;
    println!(
        "reference benchmark: {} {}x{}, {} spp, {} bounces, {} threads, median of {}",
        scene.name,
        args.width,
        args.height,
        args.spp,
        args.bounces,
        args.threads.unwrap_or_else(rayon::current_num_threads),
        args.repeat
    );
    println!(
        "hprt: {seconds:.2} s, {:.2} M rays/s, {per:.3} s per megapixel per sample",
        rays_per_second / 1e6,
    );
    if args.no_mitsuba {
        return Ok(());
    }
    let last = runs.last().expect("at least one run");
    compare_with_mitsuba(&args, &scene, &env, camera, seconds, last)
}

/// Renders the same image with Mitsuba 3, when it is found, and prints its time and mean
/// radiance beside hprt's (`seconds`, `last`).
fn compare_with_mitsuba(
    args: &BenchReferenceArgs,
    scene: &foundation::scene::Scene,
    env: &maps::ChosenEnvironment,
    camera: foundation::camera::Camera,
    seconds: f64,
    last: &reference::ReferenceImage,
) -> anyhow::Result<()> {
    let Some(mitsuba) = crate::commands::mitsuba::Mitsuba::find() else {
        println!(
            "Mitsuba 3 not found (pip install mitsuba, or set HPRT_MITSUBA_PYTHON): no comparison"
        );
        return Ok(());
    };
    let dir = tempfile::tempdir()?;
    let export = reference::export::ExportSettings {
        camera,
        rotation_deg: env.rotation_deg,
        spp: args.spp,
        bounces: args.bounces,
    };
    let (times, image) = mitsuba.render(
        dir.path(),
        &scene.geometry,
        &env.loaded.map,
        &export,
        args.repeat.max(1) + 1,
    )?;
    anyhow::ensure!(times.len() >= 2, "Mitsuba reported no timings");
    // The first render compiles the LLVM variant's kernels; the rest are steady state.
    let steady = median(times[1..].to_vec());
    let difference =
        crate::commands::mitsuba::covered_mean_difference(&last.radiance, &image, &last.coverage);
    println!(
        "Mitsuba {} {}: {steady:.2} s (median of {}; the first, with kernel compilation, \
         {:.2} s); hprt takes {:.2}x Mitsuba's time; mean radiance of covered pixels: hprt \
         {:+.2}% from Mitsuba",
        mitsuba.version,
        mitsuba.variant,
        times.len() - 1,
        times[0],
        seconds / steady,
        100.0 * difference
    );
    Ok(())
}
