//! What sharding a bake costs. For each shard count N, every shard and then the merge run one
//! after another as separate `hprt` processes (as a batch system runs them), each one's wall
//! time and peak memory (its maximum resident set, from `wait4`) against the one-machine
//! bake's; `instances` bakes a synthetic scene of K copies of the scene's objects side by side
//! instead (generated, not shipped: K = 45 of the res2 dragon is about 9 million triangles).

mod synthetic;

use crate::Reporter;
use crate::error::{BenchError, Result};
use crate::inputs::{load_scene, work_folder};
use crate::process::{Run, run_hprt};
use crate::stats::Spread;
use serde::Serialize;
use std::path::PathBuf;

/// What `bench_shards` measures.
#[derive(Debug, Clone)]
pub struct ShardsBench {
    pub scene: PathBuf,
    /// Shard counts to run.
    pub counts: Vec<u32>,
    /// Rays per vertex (the scene's when `None`).
    pub samples: Option<u32>,
    /// Bounces (the scene's when `None`).
    pub bounces: Option<u32>,
    /// Bake a scene of this many copies of the scene's objects, side by side, instead.
    pub instances: Option<u32>,
    /// Folder for the shards, bakes and generated scene (a temporary one when `None`).
    pub work_dir: Option<PathBuf>,
    /// The hprt program the bakes run as.
    pub program: PathBuf,
}

/// One shard count's costs against the one-machine bake's.
#[derive(Debug, Clone, Serialize)]
pub struct ShardRow {
    pub count: u32,
    /// The shards' wall times, seconds.
    pub seconds: Spread,
    /// The shards' peak memory, MiB.
    pub peak_mib: Spread,
    pub merge: Run,
    /// The shards' summed time over the one-machine bake's.
    pub time_over_one: f64,
    /// The largest shard's peak memory over the one-machine bake's.
    pub memory_over_one: f64,
}

/// The whole benchmark's figures.
#[derive(Debug, Clone, Serialize)]
pub struct ShardsResult {
    pub scene: PathBuf,
    pub triangles: usize,
    pub whole: Run,
    pub rows: Vec<ShardRow>,
}

/// The benchmark under way: its scene (generated when asked) and folder.
pub struct Shards {
    /// The scene file baked.
    pub scene: PathBuf,
    pub triangles: usize,
    dir: PathBuf,
    common: Vec<String>,
    program: PathBuf,
    _temporary: Option<tempfile::TempDir>,
}

/// Runs the whole benchmark, reporting each shard count's row as it is measured.
pub fn bench_shards(
    bench: &ShardsBench,
    reporter: &dyn Reporter<ShardRow>,
) -> Result<ShardsResult> {
    let shards = Shards::prepare(bench)?;
    let whole = shards.whole()?;
    let mut rows = Vec::new();
    for &count in &bench.counts {
        let row = shards.row(count, &whole)?;
        reporter.row(&row);
        rows.push(row);
    }
    Ok(ShardsResult {
        scene: shards.scene.clone(),
        triangles: shards.triangles,
        whole,
        rows,
    })
}

impl Shards {
    /// Makes the folder and the synthetic scene (when asked), and counts the triangles.
    pub fn prepare(bench: &ShardsBench) -> Result<Self> {
        let (dir, temporary) = work_folder(bench.work_dir.as_deref())?;
        let scene = match bench.instances {
            Some(k) => synthetic::synthetic_scene(&bench.scene, k, &dir)?,
            None => bench.scene.clone(),
        };
        let triangles = load_scene(&scene)?.geometry.mesh.triangle_count();
        let mut common = vec![scene.display().to_string()];
        for (flag, value) in [("--samples", bench.samples), ("--bounces", bench.bounces)] {
            if let Some(v) = value {
                common.extend([flag.to_owned(), v.to_string()]);
            }
        }
        Ok(Self {
            scene,
            triangles,
            dir,
            common,
            program: bench.program.clone(),
            _temporary: temporary,
        })
    }

    fn bake(&self, extra: &[String]) -> Result<Run> {
        let args = [vec!["bake".to_owned()], self.common.clone(), extra.to_vec()].concat();
        run_hprt(&self.program, &args)
    }

    fn path(&self, name: &str) -> String {
        self.dir.join(name).display().to_string()
    }

    /// The one-machine bake.
    pub fn whole(&self) -> Result<Run> {
        self.bake(&["-o".into(), self.path("whole.bake")])
    }

    /// Bakes `count` shards one after another and merges them, checks the merge against the
    /// one-machine bake, and measures their times and memory against `whole`'s.
    pub fn row(&self, count: u32, whole: &Run) -> Result<ShardRow> {
        let shards = self.path(&format!("shards-{count}"));
        let mut runs = Vec::new();
        for i in 0..count {
            let shard = format!("{i}/{count}");
            runs.push(self.bake(&["--shard".into(), shard, "-o".into(), shards.clone()])?);
        }
        let merged = self.path(&format!("merged-{count}.bake"));
        let merge_args = ["bake", "merge", &shards, "-o", &merged].map(str::to_owned);
        let merge = run_hprt(&self.program, &merge_args)?;
        let read = |path: &str| std::fs::read(path).map_err(BenchError::file("cannot read", path));
        if read(&merged)? != read(&self.path("whole.bake"))? {
            return Err(BenchError::MergeDiffers(count));
        }
        let seconds = Spread::of(runs.iter().map(|r| r.seconds));
        let peak_mib = Spread::of(runs.iter().map(|r| r.peak_mib));
        std::fs::remove_dir_all(&shards).ok();
        std::fs::remove_file(&merged).ok();
        Ok(ShardRow {
            count,
            seconds,
            peak_mib,
            merge,
            time_over_one: seconds.sum / whole.seconds,
            memory_over_one: peak_mib.max / whole.peak_mib,
        })
    }
}

impl Shards {
    /// The line before the one-machine bake.
    pub fn title(&self) -> String {
        format!(
            "{}: {} triangles; each process run alone, one after another",
            self.scene.display(),
            self.triangles
        )
    }
}

/// The one-machine bake's cost, and the table's column names.
pub fn shards_header(whole: &Run) -> String {
    format!(
        "one machine: {:.2} s, peak {:.0} MiB\n{:>3} {:>22} {:>22} {:>16} {:>14} {:>13}",
        whole.seconds,
        whole.peak_mib,
        "N",
        "shard s (min-max)",
        "shard MiB (min-max)",
        "merge s / MiB",
        "sum / one",
        "max MiB / one"
    )
}

/// What every row was checked for, and what its times hold.
pub const SHARDS_NOTE: &str = "every merge equals the one-machine bake byte for byte; shard \
    times include each process's scene load, its BVH (built by the first process, read from \
    the cache by the others) and the cost estimate";

impl ShardRow {
    /// The row as the table shows it.
    pub fn line(&self) -> String {
        let (t, m) = (self.seconds, self.peak_mib);
        format!(
            "{:>3} {:>22} {:>22} {:>16} {:>14.3} {:>13.3}",
            self.count,
            format!("{:.2}-{:.2}", t.min, t.max),
            format!("{:.0}-{:.0}", m.min, m.max),
            format!("{:.2} / {:.0}", self.merge.seconds, self.merge.peak_mib),
            self.time_over_one,
            self.memory_over_one
        )
    }
}
