//! `hprt bake`: the offline transfer bake, on one machine or as shards (`--shard I/N`) that
//! `hprt bake merge` joins.

use crate::bake_cache::print_bake_stats;
use crate::outputs::{check_outputs, scene_inputs};
use crate::support::{TerminalProgress, create_folder, load_scene, with_threads};
use anyhow::Context;
use clap::{Args, Subcommand};
use foundation::bvh::SceneBvh;
use foundation::infra::atomic_file::AtomicOutput;
use foundation::infra::recorded::{RecordedFile, check_scene_path, file_hash};
use foundation::infra::shard::{ProcessEnvironment, ShardSpec, files_with_extension};
use foundation::scene::Scene;
use precompute::bake::{self, BakeSettings, BakeStats, Transfer};
use precompute::{bakefile, shardfile};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct BakeArgs {
    /// Scene file (TOML), whose [bake] table gives the defaults of the options below; or a
    /// model (glTF, OBJ, PLY, BPT) placed in a default scene.
    #[arg(required = true)]
    pub scene: Option<PathBuf>,
    /// Output bake file (written atomically: an interrupted bake leaves no file); with
    /// --shard, the folder the shard file goes into.
    #[arg(short, long, required = true)]
    pub output: Option<PathBuf>,
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
    /// Trace only the I-th of N shares of the vertices (balanced by cost) into
    /// `-o DIR/bake-I-of-N.hprtshard`; `hprt bake merge DIR` joins them. I and N may be
    /// `auto`: from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT, or Kubernetes'
    /// JOB_COMPLETION_INDEX (write auto/N).
    #[arg(long)]
    pub shard: Option<String>,
    #[command(subcommand)]
    pub merge: Option<BakeCommand>,
}

#[derive(Subcommand)]
pub enum BakeCommand {
    /// Join the shards of `hprt bake --shard` and sum the bounces: the same file, byte for
    /// byte, as one `hprt bake`.
    Merge(MergeArgs),
}

#[derive(Args)]
pub struct MergeArgs {
    /// The folder of the shards (`*.hprtshard`).
    pub shards: PathBuf,
    /// Output bake file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The scene (default: the one the shards name; it must be the same scene).
    #[arg(long)]
    pub scene: Option<PathBuf>,
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
    if let Some(BakeCommand::Merge(merge)) = args.merge {
        return run_merge(merge);
    }
    let (Some(scene_path), Some(output)) = (&args.scene, &args.output) else {
        anyhow::bail!("hprt bake needs a scene and -o");
    };
    let scene = load_scene(scene_path)?;
    let settings = settings_for(&scene, &args)?;
    if let Some(shard) = &args.shard {
        let spec = ShardSpec::parse(shard, &ProcessEnvironment)?;
        return run_shard(&scene, &settings, spec, output, args.threads);
    }
    check_outputs(&scene_inputs(&scene, &[]), &[("-o", Some(output))])?;
    // Fail on an unwritable destination before spending minutes baking.
    let file = AtomicOutput::create(output)
        .with_context(|| format!("cannot write {}", output.display()))?;
    warn_above_gpu_order(&settings);
    announce(&scene, &settings, "");
    let baked = with_threads(args.threads, || {
        let start = Instant::now();
        let bvh = SceneBvh::cached(&scene.geometry.mesh);
        let bvh_seconds = start.elapsed().as_secs_f64();
        let progress = TerminalProgress::new("baking");
        bake::bake(&scene.geometry, &bvh, &settings, &progress).map(|r| (r, bvh_seconds))
    })??;
    let ((transfer, stats), bvh_seconds) = baked;
    println!("BVH built in {bvh_seconds:.2} s");
    write_bake(file, output, &scene, &transfer, &stats)
}

fn warn_above_gpu_order(settings: &BakeSettings) {
    if settings.order > runtime::render::MAX_GPU_ORDER {
        log::warn!(
            "SH order {} is above the GPU renderer's maximum ({}): this bake can be used by the \
             CPU code (the reference comparisons, the numpy reader) but not by `hprt render`, \
             `hprt view` or `hprt report`",
            settings.order,
            runtime::render::MAX_GPU_ORDER
        );
    }
}

fn announce(scene: &Scene, settings: &BakeSettings, what: &str) {
    let mesh = &scene.geometry.mesh;
    println!(
        "{}: {} vertices, {} triangles; order {}, {} samples, {} bounces{what}",
        scene.name,
        mesh.vertex_count(),
        mesh.triangle_count(),
        settings.order,
        settings.samples,
        settings.bounces
    );
}

fn write_bake(
    file: AtomicOutput,
    output: &Path,
    scene: &Scene,
    transfer: &Transfer,
    stats: &BakeStats,
) -> anyhow::Result<()> {
    let bytes = bakefile::encode(transfer, &scene.geometry.content_hash());
    file.commit(&bytes)
        .with_context(|| format!("cannot write {}", output.display()))?;
    print_bake_stats(stats);
    println!(
        "wrote {} ({:.1} MB)",
        output.display(),
        bytes.len() as f64 / 1e6
    );
    Ok(())
}

/// `hprt bake SCENE --shard I/N -o DIR`: one shard's tracing pass.
fn run_shard(
    scene: &Scene,
    settings: &BakeSettings,
    spec: ShardSpec,
    dir: &Path,
    threads: Option<usize>,
) -> anyhow::Result<()> {
    let path = dir.join(shardfile::file_name(spec));
    check_outputs(&scene_inputs(scene, &[]), &[("-o", Some(&path))])?;
    create_folder(dir)?;
    let file =
        AtomicOutput::create(&path).with_context(|| format!("cannot write {}", path.display()))?;
    announce(scene, settings, &format!("; shard {spec}"));
    // The merge reloads the scene by this path, perhaps from another folder.
    let scene_path = std::path::absolute(&scene.path)
        .with_context(|| format!("cannot resolve {}", scene.path.display()))?;
    let scene_hash =
        file_hash(&scene_path).with_context(|| format!("cannot read {}", scene_path.display()))?;
    let shard = with_threads(threads, || {
        let bvh = SceneBvh::cached(&scene.geometry.mesh);
        let progress = TerminalProgress::new("tracing");
        let name = scene_path.to_string_lossy();
        let scene_file = (name.as_ref(), scene_hash);
        bake::shard::trace_shard(&scene.geometry, &bvh, settings, spec, scene_file, &progress)
    })??;
    let bytes = file
        .commit_streamed(|out| shardfile::write(&shard, out))
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!(
        "traced vertices {}..{} of {} in {:.2} s; wrote {} ({:.1} MB)",
        shard.vertices.start,
        shard.vertices.end,
        shard.vertex_count,
        shard.seconds,
        path.display(),
        bytes as f64 / 1e6
    );
    Ok(())
}

/// `hprt bake merge DIR -o FILE`.
fn run_merge(args: MergeArgs) -> anyhow::Result<()> {
    let dir = &args.shards;
    let files = files_with_extension(dir, shardfile::EXTENSION, "bake shards", "hprt bake SCENE")?;
    let shards = files
        .iter()
        .map(|f| shardfile::read(f))
        .collect::<Result<Vec<_>, _>>()
        .context("cannot merge the shards")?;
    let scene_path = match &args.scene {
        Some(path) => path.clone(),
        None => {
            // A path read from a shard: the file must still be the one it was baked from
            // before any of it is read.
            let recorded = RecordedFile {
                path: PathBuf::from(&shards[0].scene_path),
                blake3: blake3::Hash::from_bytes(shards[0].scene_hash)
                    .to_hex()
                    .to_string(),
            };
            check_scene_path(&files[0], &recorded.path)?;
            recorded.check(&files[0]).context(
                "cannot merge the shards (give the scene with --scene if it moved or changed)",
            )?;
            recorded.path
        }
    };
    let scene = load_scene(&scene_path)?;
    let mut inputs = scene_inputs(&scene, &[]);
    inputs.extend(files.iter().map(PathBuf::as_path));
    check_outputs(&inputs, &[("-o", Some(&args.output))])?;
    let file = AtomicOutput::create(&args.output)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let settings = shards[0].settings;
    announce(
        &scene,
        &settings,
        &format!("; merging {} shards", files.len()),
    );
    let (transfer, stats) = with_threads(args.threads, || {
        let progress = TerminalProgress::new("merging");
        bake::shard::merge(&scene.geometry, shards, &progress)
    })?
    .with_context(|| format!("cannot merge the shards in {}", args.shards.display()))?;
    println!(
        "tracing took {:.2} s summed over the shards",
        stats.direct_seconds
    );
    write_bake(file, &args.output, &scene, &transfer, &stats)
}
