//! `hprt bench shards`: what sharding a bake costs. For each shard count N, every shard and
//! then the merge run one after another as separate `hprt` processes (as a batch system runs
//! them), each one's wall time and peak memory (its maximum resident set, from `wait4`)
//! against the one-machine bake's; `--instances K` bakes a synthetic scene of K copies of
//! the scene's objects side by side instead (generated, not shipped: K = 45 of the res2
//! dragon is about 9 million triangles).

use bench::shards::{SHARDS_NOTE, Shards, ShardsBench, shards_header};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchShardsArgs {
    /// Scene file.
    #[arg(default_value = "scenes/dragon.toml")]
    pub scene: PathBuf,
    /// Shard counts to run.
    #[arg(long, value_delimiter = ',', default_values_t = [1u32, 2, 4, 8])]
    pub counts: Vec<u32>,
    /// Rays per vertex (default: the scene's).
    #[arg(long)]
    pub samples: Option<u32>,
    /// Bounces (default: the scene's).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Bake a scene of this many copies of the scene's objects, side by side, instead.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub instances: Option<u32>,
    /// Folder for the shards, bakes and generated scene (default: a temporary one).
    #[arg(long)]
    pub work_dir: Option<PathBuf>,
}

pub(super) fn bench_shards(args: BenchShardsArgs) -> anyhow::Result<()> {
    let bench = ShardsBench {
        scene: args.scene,
        counts: args.counts,
        samples: args.samples,
        bounces: args.bounces,
        instances: args.instances,
        work_dir: args.work_dir,
        program: super::rows::this_program()?,
    };
    let shards = Shards::prepare(&bench)?;
    println!("{}", shards.title());
    let whole = shards.whole()?;
    println!("{}", shards_header(&whole));
    for &count in &bench.counts {
        println!("{}", shards.row(count, &whole)?.line());
    }
    println!("{SHARDS_NOTE}");
    Ok(())
}
