//! `hprt bake`: the offline transfer bake.

use crate::bake_cache::print_bake_stats;
use crate::outputs::{check_outputs, scene_inputs};
use crate::support::{TerminalProgress, load_scene, with_threads};
use anyhow::Context;
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::infra::atomic_file::AtomicOutput;
use foundation::scene::Scene;
use precompute::bake::{self, BakeSettings};
use precompute::bakefile;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BakeArgs {
    /// Scene file (TOML), whose [bake] table gives the defaults of the options below; or a
    /// model (glTF, OBJ, PLY, BPT) placed in a default scene.
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
    settings.validate()?;
    Ok(settings)
}

pub fn run(args: BakeArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let settings = settings_for(&scene, &args)?;
    check_outputs(&scene_inputs(&scene, &[]), &[("-o", Some(&args.output))])?;
    // Fail on an unwritable destination before spending minutes baking.
    let output = AtomicOutput::create(&args.output)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    if settings.order > runtime::render::MAX_GPU_ORDER {
        log::warn!(
            "SH order {} is above the GPU renderer's maximum ({}): this bake can be used by the \
             CPU code (the reference comparisons, the numpy reader) but not by `hprt render`, \
             `hprt view` or `hprt report`",
            settings.order,
            runtime::render::MAX_GPU_ORDER
        );
    }
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
    let baked = with_threads(args.threads, || {
        let start = Instant::now();
        let bvh = SceneBvh::build(mesh);
        let bvh_seconds = start.elapsed().as_secs_f64();
        let progress = TerminalProgress::new("baking");
        bake::bake(&scene.geometry, &bvh, &settings, &progress).map(|r| (r, bvh_seconds))
    })??;
    let ((transfer, stats), bvh_seconds) = baked;
    println!("BVH built in {bvh_seconds:.2} s");
    let bytes = bakefile::encode(&transfer, &scene.geometry.content_hash());
    output
        .commit(&bytes)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    print_bake_stats(&stats);
    println!(
        "wrote {} ({:.1} MB)",
        args.output.display(),
        bytes.len() as f64 / 1e6
    );
    Ok(())
}
