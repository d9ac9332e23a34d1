//! `hprt bench`: benchmarks anyone can rerun; they print medians over repeats.

use super::{load_scene, with_threads};
use clap::{Args, Subcommand};
use indicatif::ProgressBar;
use precompute::bake::{self, BakeSettings};
use precompute::bvh::SceneBvh;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Bake throughput: rays per second, bake time and the cost of each bounce.
    Bake(BenchBakeArgs),
    /// Reference renderer speed: seconds, rays per second, seconds per megapixel per sample.
    Reference(BenchReferenceArgs),
}

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
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

#[derive(Args)]
pub struct BenchBakeArgs {
    /// Scene files (default: the bundled teapot and dragon scenes).
    #[arg(default_values = ["scenes/teapot.toml", "scenes/dragon.toml"])]
    pub scenes: Vec<PathBuf>,
    #[arg(long, default_value_t = 5)]
    pub order: usize,
    #[arg(long, default_value_t = 1024)]
    pub samples: u32,
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Bakes per scene; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn run(command: BenchCommand) -> anyhow::Result<()> {
    match command {
        BenchCommand::Bake(args) => bench_bake(args),
        BenchCommand::Reference(args) => bench_reference(args),
    }
}

/// Median of a non-empty sample.
pub fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

fn bench_bake(args: BenchBakeArgs) -> anyhow::Result<()> {
    let settings = BakeSettings {
        order: args.order,
        samples: args.samples,
        bounces: args.bounces,
        seed: 0,
    };
    settings
        .validate()
        .map_err(|m| anyhow::anyhow!("invalid bake settings: {m}"))?;
    println!(
        "bake benchmark: order {}, {} samples, {} bounces, {} threads, median of {}",
        args.order,
        args.samples,
        args.bounces,
        args.threads.unwrap_or_else(rayon::current_num_threads),
        args.repeat
    );
    println!(
        "{:<10} {:>9} {:>11} {:>9} {:>10} {:>12} {:>16}",
        "scene", "vertices", "rays", "bake s", "direct s", "M rays/s", "max bounce/direct"
    );
    for path in &args.scenes {
        let scene = load_scene(path)?;
        let runs = with_threads(args.threads, || {
            let bvh = SceneBvh::build(&scene.geometry.mesh);
            (0..args.repeat.max(1))
                .map(|_| bake::bake(&scene.geometry, &bvh, &settings, &ProgressBar::hidden()))
                .collect::<Result<Vec<_>, _>>()
        })?
        .map_err(|m| anyhow::anyhow!(m))?;
        let stats: Vec<_> = runs.into_iter().map(|(_, s)| s).collect();
        let bounce_ratio = median(
            stats
                .iter()
                .map(|s| s.bounce_seconds.iter().copied().fold(0.0, f64::max) / s.direct_seconds)
                .collect(),
        );
        println!(
            "{:<10} {:>9} {:>11} {:>9.2} {:>10.2} {:>12.2} {:>15.1}%",
            scene.name,
            stats[0].vertices,
            stats[0].rays,
            median(stats.iter().map(|s| s.total_seconds).collect()),
            median(stats.iter().map(|s| s.direct_seconds).collect()),
            median(stats.iter().map(|s| s.rays_per_second()).collect()) / 1e6,
            100.0 * bounce_ratio
        );
    }
    Ok(())
}

/// Mitsuba 3's `path` integrator, `scalar_rgb` variant, on this machine class (2 cores): about
/// 1.0 s per megapixel per sample at max depth 5 (the figure the reference is held to).
const MITSUBA_SCALAR_SECONDS_PER_MEGAPIXEL_SAMPLE: f64 = 1.0;

fn bench_reference(args: BenchReferenceArgs) -> anyhow::Result<()> {
    use precompute::reference::{self, EnvironmentLight, ReferenceSettings};
    let scene = load_scene(&args.scene)?;
    let env = super::choose_environment(&scene, None, None, None)?;
    let camera = scene.camera.with_size(args.width, args.height);
    camera
        .validate()
        .map_err(|m| anyhow::anyhow!("invalid image size: {m}"))?;
    let settings = ReferenceSettings {
        spp: args.spp,
        bounces: args.bounces,
        seed: 0,
    };
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
                    &ProgressBar::hidden(),
                )
                .stats
            })
            .collect::<Vec<_>>()
    })?;
    let seconds = median(runs.iter().map(|r| r.seconds).collect());
    let rays_per_second = median(runs.iter().map(|r| r.rays_per_second()).collect());
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
        "time {seconds:.2} s, {:.2} M rays/s, {per:.3} s per megapixel per sample \
         ({:.2}x the speed of Mitsuba 3 scalar_rgb's ~{MITSUBA_SCALAR_SECONDS_PER_MEGAPIXEL_SAMPLE} s)",
        rays_per_second / 1e6,
        MITSUBA_SCALAR_SECONDS_PER_MEGAPIXEL_SAMPLE / per
    );
    Ok(())
}
