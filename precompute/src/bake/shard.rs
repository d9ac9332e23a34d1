//! The bake split across machines: each shard traces the rays of one range of vertices (the
//! direct transfer and the interreflection operator's rows), and the merge concatenates the
//! ranges and sums the bounces. A vertex's rays depend only on the vertex and the seed, so
//! the merged bake equals a one-machine bake byte for byte, whatever the shard count.
//!
//! The ranges are balanced by cost, not by count: every vertex traces the same number of
//! rays, but a ray through a dense dragon visits many more BVH nodes than one leaving a floor.
//! The cost is estimated by tracing a few probe rays from a subset of vertices and counting
//! the nodes they visit, which depends only on the scene, so every shard finds the same split.

use super::bounce::InterreflectionOperator;
use super::visibility::{self, TracedVertices};
use super::{BakeError, BakeSettings, BakeStats, TracedScene, Transfer};
use foundation::bvh::SceneBvh;
use foundation::infra::progress::Progress;
use foundation::infra::shard::{IncompleteShards, ShardSpec, check_indices, split_by_cost};
use foundation::scene::SceneMesh;
use std::ops::Range;
use std::time::Instant;

/// One shard's share of the tracing pass, with what the merge checks it against.
#[derive(Debug, Clone, PartialEq)]
pub struct BakeShard {
    pub spec: ShardSpec,
    pub settings: BakeSettings,
    /// Vertices of the whole scene.
    pub vertex_count: u64,
    /// The vertices this shard traced.
    pub vertices: Range<usize>,
    /// The scene mesh's hash ([`SceneMesh::content_hash`]).
    pub mesh_hash: [u8; 32],
    /// Hash of every shard's range: shards of one job agree on it.
    pub partition_hash: [u8; 32],
    /// The scene file the shard was baked from (the merge reloads it to sum the bounces).
    pub scene_path: String,
    /// BLAKE3 hash of that file's bytes: the merge reads the file only when it still holds
    /// them, so a path rewritten in a shard cannot make hprt read (and quote) another file.
    pub scene_hash: [u8; 32],
    /// Seconds the tracing took.
    pub seconds: f64,
    pub(crate) traced: TracedVertices,
}

/// Why shards do not merge.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MergeError {
    #[error(transparent)]
    Incomplete(#[from] IncompleteShards),
    #[error("the shards are of different jobs: {what} differ (shard {a} and shard {b})")]
    Mismatch {
        what: &'static str,
        a: String,
        b: String,
    },
    #[error(
        "the shards were baked from another scene: its geometry, normals or albedos differ \
         from this scene's; bake the shards again"
    )]
    SceneChanged,
    #[error("the shards' vertex ranges do not cover the scene's vertices exactly")]
    Gaps,
    #[error(transparent)]
    Bake(#[from] BakeError),
}

/// Probe rays traced from each probed vertex to estimate its cost.
const PROBE_RAYS: u32 = 8;
/// One vertex in this many, at least, is probed; its neighbours in index order share its
/// estimate.
const PROBE_STRIDE: usize = 4;
/// Probed vertices enough to balance any shard count: a large scene's stride widens so that
/// about this many are probed (on 45 dragons, 5M vertices, probing one in four cost each shard
/// 6 s, more than a quarter of an eighth's tracing).
const PROBED_VERTICES: usize = 1 << 16;

/// The stride of the probed vertices of a scene of `vertices`.
fn probe_stride(vertices: usize) -> usize {
    (vertices / PROBED_VERTICES).max(PROBE_STRIDE)
}

/// Every shard's vertex range, balanced by the estimated tracing cost.
pub fn partition(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    settings: &BakeSettings,
    count: u32,
) -> Vec<Range<usize>> {
    let stride = probe_stride(geometry.mesh.vertex_count());
    let costs = visibility::vertex_costs(geometry, bvh, settings, PROBE_RAYS, stride);
    split_by_cost(&costs, count)
}

/// The hash shards of one job share: every range's bounds.
pub fn partition_hash(ranges: &[Range<usize>]) -> [u8; 32] {
    let mut hasher = blake3::Hasher::new();
    for r in ranges {
        hasher.update(&(r.start as u64).to_le_bytes());
        hasher.update(&(r.end as u64).to_le_bytes());
    }
    *hasher.finalize().as_bytes()
}

/// Traces shard `spec`'s vertices. `scene_file` is the scene file's path and the hash of its
/// bytes, recorded for the merge. `progress` counts vertices.
pub fn trace_shard(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    settings: &BakeSettings,
    spec: ShardSpec,
    (scene_path, scene_hash): (&str, [u8; 32]),
    progress: &dyn Progress,
) -> Result<BakeShard, BakeError> {
    settings.validate()?;
    let start = Instant::now();
    let ranges = partition(geometry, bvh, settings, spec.count);
    let vertices = ranges[spec.index as usize].clone();
    progress.start(vertices.len() as u64);
    let traced = visibility::trace_vertices(geometry, bvh, settings, vertices.clone(), progress)
        .ok_or(BakeError::Cancelled)?;
    progress.finish();
    Ok(BakeShard {
        spec,
        settings: *settings,
        vertex_count: geometry.mesh.vertex_count() as u64,
        vertices,
        mesh_hash: geometry.content_hash(),
        partition_hash: partition_hash(&ranges),
        scene_path: scene_path.to_owned(),
        scene_hash,
        seconds: start.elapsed().as_secs_f64(),
        traced,
    })
}

/// Checks that `shards` are all of one job, every index once, then sorts them by index.
pub fn check_complete(shards: &mut [BakeShard]) -> Result<(), MergeError> {
    let first = shards.first().ok_or(IncompleteShards::Empty)?;
    let count = first.spec.count;
    for s in shards.iter() {
        let differ = |what: &'static str| MergeError::Mismatch {
            what,
            a: first.spec.to_string(),
            b: s.spec.to_string(),
        };
        if s.spec.count != count {
            return Err(differ("shard counts"));
        }
        if s.settings != first.settings {
            return Err(differ("bake settings"));
        }
        if s.mesh_hash != first.mesh_hash || s.vertex_count != first.vertex_count {
            return Err(differ("scenes"));
        }
        if s.partition_hash != first.partition_hash {
            return Err(differ("vertex partitions"));
        }
    }
    shards.sort_by_key(|s| s.spec.index);
    check_indices(&shards.iter().map(|s| s.spec).collect::<Vec<_>>())?;
    let tiles = shards.first().is_some_and(|s| s.vertices.start == 0)
        && shards
            .windows(2)
            .all(|w| w[0].vertices.end == w[1].vertices.start)
        && shards
            .last()
            .is_some_and(|s| s.vertices.end as u64 == s.vertex_count);
    if !tiles {
        return Err(MergeError::Gaps);
    }
    Ok(())
}

/// Merges a complete set of shards of `geometry`'s bake and sums the bounces: the same
/// transfer as [`super::bake`] on one machine.
pub fn merge(
    geometry: &SceneMesh,
    mut shards: Vec<BakeShard>,
    progress: &dyn Progress,
) -> Result<(Transfer, BakeStats), MergeError> {
    check_complete(&mut shards)?;
    let first = &shards[0];
    if first.mesh_hash != geometry.content_hash() {
        return Err(MergeError::SceneChanged);
    }
    let settings = first.settings;
    let seconds = shards.iter().map(|s| s.seconds).sum();
    let order = settings.order;
    // Sized once: growing would hold the old and the new array at the same time.
    let rows: usize = shards.iter().map(|s| s.vertices.len()).sum();
    let mut visibility = Vec::with_capacity(shards.iter().map(|s| s.traced.visibility.len()).sum());
    let mut inside = Vec::with_capacity(rows);
    let mut blocks = Vec::with_capacity(
        shards
            .iter()
            .map(|s| s.traced.operator.blocks().len())
            .sum(),
    );
    for shard in shards {
        visibility.extend(shard.traced.visibility);
        inside.extend(shard.traced.inside);
        blocks.extend(shard.traced.operator.into_blocks());
    }
    let traced = TracedVertices {
        order,
        visibility,
        operator: InterreflectionOperator::from_blocks(blocks),
        inside,
    };
    let traced = TracedScene::new(geometry, &settings, traced, seconds);
    Ok(super::sum_bounces(geometry, &settings, traced, progress)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{bakefile, shardfile};
    use foundation::color::Rgb;
    use foundation::infra::progress::NoProgress;
    use foundation::mesh::{box_mesh, sphere_mesh};
    use glam::Vec3;

    /// A dense sphere over a sparse floor slab: its vertices' rays do very different work.
    fn dense_over_sparse() -> SceneMesh {
        let mut s = SceneMesh::default();
        let floor = box_mesh(
            Vec3::new(-3.0, -0.2, -3.0),
            Vec3::new(3.0, 0.0, 3.0),
            [24, 1, 24],
            [false; 6],
        );
        s.push_object("floor".into(), &floor, Rgb::splat(0.6));
        s.push_object(
            "ball".into(),
            &sphere_mesh(Vec3::new(0.0, 0.6, 0.0), 0.55, 4),
            Rgb::new(0.8, 0.4, 0.2),
        );
        s
    }

    fn settings() -> BakeSettings {
        BakeSettings {
            order: 3,
            samples: 48,
            bounces: 2,
            seed: 7,
        }
    }

    #[test]
    fn merged_shards_equal_the_whole_bake_byte_for_byte() {
        let scene = dense_over_sparse();
        let bvh = SceneBvh::build(&scene.mesh);
        let s = settings();
        let (whole, _) = super::super::bake(&scene, &bvh, &s, &NoProgress).unwrap();
        let hash = scene.content_hash();
        let expected = bakefile::encode(&whole, &hash);
        for count in [1u32, 2, 3, 7] {
            // Shard in reverse order, through the file format, as separate machines would.
            let shards: Vec<BakeShard> = (0..count)
                .rev()
                .map(|i| {
                    let spec = ShardSpec::new(i, count).unwrap();
                    let shard =
                        trace_shard(&scene, &bvh, &s, spec, ("scene.toml", [0; 32]), &NoProgress)
                            .unwrap();
                    let path = std::path::Path::new("shard");
                    let decoded = shardfile::decode(path, &shardfile::encode(&shard)).unwrap();
                    assert_eq!(decoded.vertices, shard.vertices);
                    decoded
                })
                .collect();
            let (merged, _) = merge(&scene, shards, &NoProgress).unwrap();
            assert!(
                bakefile::encode(&merged, &hash) == expected,
                "{count} shards differ from the whole bake"
            );
        }
    }

    #[test]
    fn large_scenes_probe_about_the_same_number_of_vertices() {
        assert_eq!(super::probe_stride(110_604), super::PROBE_STRIDE);
        let stride = super::probe_stride(4_977_180);
        assert_eq!(stride, 75);
        let probed = 4_977_180usize.div_ceil(stride);
        assert!((super::PROBED_VERTICES..super::PROBED_VERTICES * 2).contains(&probed));
    }

    #[test]
    fn shards_are_balanced_by_work_not_by_count() {
        let scene = dense_over_sparse();
        let bvh = SceneBvh::build(&scene.mesh);
        let s = settings();
        // The work the bake's rays really do per vertex: many rays from every vertex.
        let work = visibility::vertex_costs(&scene, &bvh, &s, 64, 1);
        let spread = |ranges: &[Range<usize>]| {
            let sums: Vec<f64> = ranges
                .iter()
                .map(|r| work[r.clone()].iter().sum())
                .collect();
            let max = sums.iter().cloned().fold(0.0, f64::max);
            let min = sums.iter().cloned().fold(f64::MAX, f64::min);
            max / min
        };
        let count = 4;
        let by_cost = partition(&scene, &bvh, &s, count);
        let by_count: Vec<_> = (0..count)
            .map(|i| ShardSpec::new(i, count).unwrap().even_range(work.len()))
            .collect();
        assert!(
            spread(&by_count) > 1.3,
            "the scene is not uneven: {}",
            spread(&by_count)
        );
        assert!(
            spread(&by_cost) < 1.12,
            "by cost: {} max/min",
            spread(&by_cost)
        );
    }

    #[test]
    fn incomplete_or_mixed_shards_do_not_merge() {
        let scene = dense_over_sparse();
        let bvh = SceneBvh::build(&scene.mesh);
        let s = settings();
        let shard = |i, n, s: &BakeSettings| {
            trace_shard(
                &scene,
                &bvh,
                s,
                ShardSpec::new(i, n).unwrap(),
                ("x", [0; 32]),
                &NoProgress,
            )
            .unwrap()
        };
        let missing = merge(&scene, vec![shard(0, 3, &s), shard(2, 3, &s)], &NoProgress);
        assert!(matches!(
            missing,
            Err(MergeError::Incomplete(IncompleteShards::Missing {
                index: 1,
                ..
            }))
        ));
        let twice = merge(
            &scene,
            vec![shard(0, 2, &s), shard(1, 2, &s), shard(1, 2, &s)],
            &NoProgress,
        );
        assert_eq!(
            twice.err(),
            Some(MergeError::Incomplete(IncompleteShards::Duplicate {
                index: 1,
                count: 2
            }))
        );
        let other_seed = BakeSettings { seed: 8, ..s };
        let mixed = merge(
            &scene,
            vec![shard(0, 2, &s), shard(1, 2, &other_seed)],
            &NoProgress,
        );
        assert!(matches!(mixed, Err(MergeError::Mismatch { .. })));
        let mut changed = dense_over_sparse();
        changed.albedo[0] = Rgb::splat(0.5);
        let other_scene = merge(&changed, vec![shard(0, 1, &s)], &NoProgress);
        assert_eq!(other_scene.err(), Some(MergeError::SceneChanged));
    }
}
