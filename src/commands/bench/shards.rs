//! `hprt bench shards`: what sharding a bake costs. For each shard count N, every shard and
//! then the merge run one after another as separate `hprt` processes (as a batch system runs
//! them), each one's wall time and peak memory (its maximum resident set, from `wait4`)
//! against the one-machine bake's; `--instances K` bakes a synthetic scene of K copies of
//! the scene's objects side by side instead (generated, not shipped: K = 45 of the res2
//! dragon is about 9 million triangles).

use super::process::{Run, run_hprt};
use anyhow::Context;
use clap::Args;
use std::path::{Path, PathBuf};

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

/// A scene file of `instances` copies of `scene`'s objects, each moved along +X by the
/// scene's width and a gap.
fn synthetic_scene(scene: &Path, instances: u32, dir: &Path) -> anyhow::Result<PathBuf> {
    let loaded = crate::support::load_scene(scene)?;
    let (lo, hi) = loaded
        .geometry
        .mesh
        .bounds()
        .context("the scene is empty")?;
    let step = (hi.x - lo.x) * 1.1;
    let text = std::fs::read_to_string(scene)
        .with_context(|| format!("cannot read {}", scene.display()))?;
    let table: toml::Table = toml::from_str(&text).with_context(|| scene.display().to_string())?;
    let base = scene.parent().unwrap_or(Path::new("."));
    let objects = table
        .get("object")
        .and_then(|o| o.as_array())
        .context("the scene has no [[object]]")?;
    let mut copies = Vec::new();
    for k in 0..instances {
        for object in objects {
            let mut object = object
                .as_table()
                .cloned()
                .context("an [[object]] is not a table")?;
            if let Some(mesh) = object.get("mesh").and_then(|m| m.as_str()) {
                let path = std::path::absolute(base.join(mesh))?;
                object.insert("mesh".into(), path.display().to_string().into());
            }
            object.insert("name".into(), format!("copy {k} {}", copies.len()).into());
            let shift = toml::Value::Array(vec![(step * k as f32).into(), 0.0.into(), 0.0.into()]);
            // Copies are moved after the object's own transform (which they keep).
            let mut transform = object
                .get("transform")
                .and_then(|t| t.as_table())
                .cloned()
                .unwrap_or_default();
            let own = transform
                .get("translate")
                .and_then(|t| t.as_array())
                .cloned();
            let moved: Vec<toml::Value> = match own {
                Some(t) => t
                    .iter()
                    .zip(shift.as_array().into_iter().flatten())
                    .map(|(a, b)| {
                        (a.as_float().unwrap_or(0.0) + b.as_float().unwrap_or(0.0)).into()
                    })
                    .collect(),
                None => shift.as_array().cloned().unwrap_or_default(),
            };
            transform.insert("translate".into(), toml::Value::Array(moved));
            object.insert("transform".into(), toml::Value::Table(transform));
            copies.push(toml::Value::Table(object));
        }
    }
    let mut out = table.clone();
    out.remove("environment");
    out.insert("name".into(), format!("{instances} copies").into());
    out.insert("object".into(), toml::Value::Array(copies));
    let path = dir.join("synthetic.toml");
    std::fs::write(&path, toml::to_string(&out)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

pub(super) fn bench_shards(args: BenchShardsArgs) -> anyhow::Result<()> {
    let temporary = tempfile::tempdir().context("cannot make a temporary folder")?;
    let dir = args
        .work_dir
        .clone()
        .unwrap_or_else(|| temporary.path().to_owned());
    crate::support::create_folder(&dir)?;
    let scene = match args.instances {
        Some(k) => synthetic_scene(&args.scene, k, &dir)?,
        None => args.scene.clone(),
    };
    let triangles = crate::support::load_scene(&scene)?
        .geometry
        .mesh
        .triangle_count();
    let mut common = vec![scene.display().to_string()];
    for (flag, value) in [("--samples", args.samples), ("--bounces", args.bounces)] {
        if let Some(v) = value {
            common.extend([flag.to_owned(), v.to_string()]);
        }
    }
    let bake = |extra: &[String]| -> Vec<String> {
        [vec!["bake".to_owned()], common.clone(), extra.to_vec()].concat()
    };
    let path = |name: &str| dir.join(name).display().to_string();
    println!(
        "{}: {triangles} triangles; each process run alone, one after another",
        scene.display()
    );
    let whole = run_hprt(&bake(&["-o".into(), path("whole.bake")]))?;
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
    for &count in &args.counts {
        shard_row(count, &bake, &path, &whole)?;
    }
    println!(
        "every merge equals the one-machine bake byte for byte; shard times include each \
         process's scene load, BVH build and cost estimate"
    );
    Ok(())
}

/// Bakes `count` shards one after another and merges them, checks the merge against the
/// one-machine bake, and prints the row of their times and memory against `whole`'s.
fn shard_row(
    count: u32,
    bake: &impl Fn(&[String]) -> Vec<String>,
    path: &impl Fn(&str) -> String,
    whole: &Run,
) -> anyhow::Result<()> {
    let shards = path(&format!("shards-{count}"));
    let mut runs = Vec::new();
    for i in 0..count {
        let shard = format!("{i}/{count}");
        runs.push(run_hprt(&bake(&[
            "--shard".into(),
            shard,
            "-o".into(),
            shards.clone(),
        ]))?);
    }
    let merged = path(&format!("merged-{count}.bake"));
    let merge = run_hprt(&[
        "bake".into(),
        "merge".into(),
        shards.clone(),
        "-o".into(),
        merged.clone(),
    ])?;
    anyhow::ensure!(
        std::fs::read(&merged)? == std::fs::read(path("whole.bake"))?,
        "the merge of {count} shards differs from the one-machine bake"
    );
    let range = |f: fn(&Run) -> f64| {
        let values: Vec<f64> = runs.iter().map(f).collect();
        let lo = values.iter().cloned().fold(f64::MAX, f64::min);
        let hi = values.iter().cloned().fold(0.0, f64::max);
        (lo, hi, values.iter().sum::<f64>())
    };
    let (t_lo, t_hi, t_sum) = range(|r| r.seconds);
    let (m_lo, m_hi, _) = range(|r| r.peak_mib);
    println!(
        "{count:>3} {:>22} {:>22} {:>16} {:>14.3} {:>13.3}",
        format!("{t_lo:.2}-{t_hi:.2}"),
        format!("{m_lo:.0}-{m_hi:.0}"),
        format!("{:.2} / {:.0}", merge.seconds, merge.peak_mib),
        t_sum / whole.seconds,
        m_hi / whole.peak_mib
    );
    std::fs::remove_dir_all(&shards).ok();
    std::fs::remove_file(&merged).ok();
    Ok(())
}
