//! `hprt report --shard I/N`: the references (or a composite scene's true composites) of a
//! share of the report's (map, frame) pairs, rendered into the cache, where the unsharded `hprt report` afterwards finds them all.
//! Shard I takes pairs I, I+N, I+2N, … The cache's files are written to a temporary file and
//! renamed into place, which stays atomic on a shared file system (NFS renames within a
//! folder atomically), so shards on many machines may share one cache folder.

use crate::composite_truth::true_composite;
use crate::env_sequence::Sequence;
use crate::error::{ReportError, Result};
use crate::maps::{default_exposure, load_map, scene_rotation};
use crate::observer::Observer;
use crate::{ReferenceImages, ReportSettings, reference_images};
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::infra::shard::ShardSpec;
use foundation::scene::Scene;
use std::path::PathBuf;

/// The maps a report's references are of.
pub enum ReportMaps<'a> {
    /// One reference per map.
    Maps(&'a [PathBuf]),
    /// One reference per frame of an environment sequence.
    Sequence(&'a Sequence),
}

impl ReportMaps<'_> {
    fn len(&self) -> usize {
        match self {
            Self::Maps(maps) => maps.len(),
            Self::Sequence(sequence) => sequence.len(),
        }
    }

    /// Pair `k`'s map and the exposure its reference's noise is measured at (a sequence's
    /// first frame's, as its report does).
    fn map(&self, k: usize) -> Result<(EnvMap, f32)> {
        Ok(match self {
            Self::Maps(maps) => {
                let map = load_map(&maps[k], None)?.map;
                let exposure = default_exposure(&map);
                (map, exposure)
            }
            Self::Sequence(sequence) => {
                let exposure = default_exposure(&sequence.frame(0)?);
                (sequence.frame(k)?, exposure)
            }
        })
    }

    fn name(&self, k: usize) -> String {
        match self {
            Self::Maps(maps) => maps[k].display().to_string(),
            Self::Sequence(_) => format!("frame {k}"),
        }
    }
}

/// The pairs shard `spec` renders.
pub fn share(spec: ShardSpec, pairs: usize) -> Vec<usize> {
    (spec.index as usize..pairs)
        .step_by(spec.count as usize)
        .collect()
}

/// Renders (or finds cached) the references of shard `spec`'s pairs.
pub fn render_share(
    scene: &Scene,
    maps: &ReportMaps,
    camera: &Camera,
    settings: &ReportSettings,
    spec: ShardSpec,
    observer: &dyn Observer,
) -> Result<()> {
    let rotation = scene_rotation(scene, None);
    let pairs = share(spec, maps.len());
    observer.line(&format!(
        "shard {spec}: {} of the report's {} references",
        pairs.len(),
        maps.len()
    ));
    let composite = scene.backplate.is_some();
    if composite && settings.target_noise.is_some() {
        return Err(ReportError::TargetNoiseInComposite);
    }
    for k in pairs {
        let (map, exposure) = maps.map(k)?;
        if composite {
            let truth = true_composite(scene, camera, &map, rotation, settings)?;
            observer.line(&format!(
                "{}: the true composite {}",
                maps.name(k),
                if truth.cached {
                    "was cached"
                } else {
                    "rendered"
                }
            ));
            continue;
        }
        let mut request = settings.reference_request(exposure);
        if let ReportMaps::Sequence(_) = maps {
            // As the sequence report asks (its frames have no noise target).
            request.target_noise = None;
        }
        let no_limit = |_: &ReferenceImages| f64::INFINITY;
        let reference =
            reference_images(scene, camera, &map, rotation, &request, &no_limit, observer)?;
        observer.line(&format!(
            "{}: reference of 2 × {} spp {}",
            maps.name(k),
            reference.samples_per_half,
            if reference.cached {
                "was cached".to_owned()
            } else {
                format!("rendered in {:.1} s", reference.seconds)
            }
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_interleave_and_cover_every_pair_once() {
        let mut all: Vec<usize> = (0..3)
            .flat_map(|i| share(ShardSpec::new(i, 3).unwrap(), 8))
            .collect();
        assert_eq!(share(ShardSpec::new(1, 3).unwrap(), 8), vec![1, 4, 7]);
        all.sort();
        assert_eq!(all, (0..8).collect::<Vec<_>>());
        assert!(share(ShardSpec::new(5, 6).unwrap(), 3).is_empty());
    }
}
