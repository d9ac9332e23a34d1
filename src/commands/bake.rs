//! `hprt bake`: the offline transfer bake.

use super::{load_scene, progress_bar, with_threads};
use anyhow::Context;
use clap::Args;
use precompute::atomic_file::AtomicOutput;
use precompute::bake::{self, BakeSettings, BakeStats};
use precompute::bakefile;
use precompute::bvh::SceneBvh;
use precompute::scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BakeArgs {
    /// Scene file (TOML); its [bake] table gives the defaults of the options below.
    pub scene: PathBuf,
    /// Output bake file (written atomically: an interrupted bake leaves no file).
    #[arg(short, long)]
    pub output: PathBuf,
    /// SH order n (n² coefficients per channel), 1..=20.
    #[arg(long)]
    pub order: Option<usize>,
    /// Cosine-distributed rays per vertex.
    #[arg(long)]
    pub samples: Option<u32>,
    /// Indirect bounces of the Neumann series (0 = shadowed direct only).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Seed of the per-vertex sample rotations.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// The scene's bake settings with command-line overrides.
pub fn settings_for(scene: &Scene, args: &BakeArgs) -> anyhow::Result<BakeSettings> {
    let settings = BakeSettings {
        order: args.order.unwrap_or(scene.bake.order),
        samples: args.samples.unwrap_or(scene.bake.samples),
        bounces: args.bounces.unwrap_or(scene.bake.bounces),
        seed: args.seed.unwrap_or(scene.bake.seed),
    };
    settings
        .validate()
        .map_err(|m| anyhow::anyhow!("invalid bake settings: {m}"))?;
    Ok(settings)
}

pub fn run(args: BakeArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let settings = settings_for(&scene, &args)?;
    // Fail on an unwritable destination before spending minutes baking.
    let output = AtomicOutput::create(&args.output)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let mesh = &scene.geometry.mesh;
    println!(
        "{}: {} vertices, {} triangles; order {}, {} samples, {} bounces",
        scene.name,
        mesh.vertex_count(),
        mesh.triangle_count(),
        settings.order,
        settings.samples,
        settings.bounces
    );
    let (transfer, stats) = with_threads(args.threads, || {
        let start = Instant::now();
        let bvh = SceneBvh::build(mesh);
        let bvh_seconds = start.elapsed().as_secs_f64();
        let progress = progress_bar(mesh.vertex_count() as u64, "baking");
        bake::bake(&scene.geometry, &bvh, &settings, &progress).map(|r| (r, bvh_seconds))
    })?
    .map_err(|m| anyhow::anyhow!(m))
    .map(|((t, s), bvh_seconds)| {
        println!("BVH built in {bvh_seconds:.2} s");
        (t, s)
    })?;
    let bytes = bakefile::encode(&transfer, &scene.geometry.content_hash());
    output
        .commit(&bytes)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    print_stats(&stats);
    println!(
        "wrote {} ({:.1} MB)",
        args.output.display(),
        bytes.len() as f64 / 1e6
    );
    Ok(())
}

pub fn print_stats(stats: &BakeStats) {
    println!(
        "traced {} rays in {:.2} s: {:.2} M rays/s",
        stats.rays,
        stats.direct_seconds,
        stats.rays_per_second() / 1e6
    );
    for (b, s) in stats.bounce_seconds.iter().enumerate() {
        println!(
            "bounce {}: {:.3} s ({:.1}% of the direct pass)",
            b + 1,
            s,
            100.0 * s / stats.direct_seconds.max(1e-9)
        );
    }
    println!(
        "bake time {:.2} s ({} operator entries)",
        stats.total_seconds, stats.operator_entries
    );
}
