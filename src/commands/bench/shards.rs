//! `hprt bench shards`: what sharding a bake costs. For each shard count N, every shard and
//! then the merge run one after another as separate `hprt` processes (as a batch system runs
//! them), each one's wall time and peak memory (its maximum resident set, from `wait4`)
//! against the one-machine bake's; `--instances K` bakes a synthetic scene of K copies of
//! the scene's objects side by side instead (generated, not shipped: K = 45 of the res2
//! dragon is about 9 million triangles).

use bench::shards::{ShardRow, Shards, ShardsBench};
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
        program: super::this_program()?,
    };
    let shards = Shards::prepare(&bench)?;
    println!(
        "{}: {} triangles; each process run alone, one after another",
        shards.scene.display(),
        shards.triangles
    );
    let whole = shards.whole()?;
    println!(
        "one machine: {:.2} s, peak {:.0} MiB",
        whole.seconds, whole.peak_mib
    );
    println!(
        "{:>3} {:>22} {:>22} {:>16} {:>14} {:>13}",
        "N",
        "shard s (min-max)",
        "shard MiB (min-max)",
        "merge s / MiB",
        "sum / one",
        "max MiB / one"
    );
    for &count in &bench.counts {
        print_row(&shards.row(count, &whole)?);
    }
    println!(
        "every merge equals the one-machine bake byte for byte; shard times include each \
         process's scene load, BVH build and cost estimate"
    );
    Ok(())
}

fn print_row(row: &ShardRow) {
    let (t, m) = (row.seconds, row.peak_mib);
    println!(
        "{:>3} {:>22} {:>22} {:>16} {:>14.3} {:>13.3}",
        row.count,
        format!("{:.2}-{:.2}", t.min, t.max),
        format!("{:.0}-{:.0}", m.min, m.max),
        format!("{:.2} / {:.0}", row.merge.seconds, row.merge.peak_mib),
        row.time_over_one,
        row.memory_over_one
    );
}
