//! The lighting of a model moving through a room: at each position, the local map fused
//! from the room's probes, decomposed, its lights followed from the previous position.

use super::fusion::{FusionSettings, FusionStats, ProbeFusion};
use crate::cubemap::CubeGeometry;
use crate::decompose::{DecomposeError, DecomposeSettings, Decomposer, Decomposition};
use crate::tracking::{LightTracker, TrackingSettings};
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::probe::Probe;
use glam::Vec3;
use web_time::Instant;

/// A room's probes, proxies and sky, and the decomposition that follows a moving point.
pub struct ProbeLighting {
    probes: Vec<Probe>,
    proxies: SceneBvh,
    sky: EnvMap,
    fusion: FusionSettings,
    geometry: CubeGeometry,
    settings: DecomposeSettings,
    decomposer: Decomposer,
    tracker: LightTracker,
}

/// One update's lighting and what it took.
#[derive(Debug, Clone)]
pub struct ProbeFrame {
    /// The SH part and the tracked lights (fading in and out, so that moving never pops).
    pub lighting: Decomposition,
    pub stats: FusionStats,
    /// Milliseconds fusing the local map, and decomposing it.
    pub fuse_ms: f64,
    pub decompose_ms: f64,
}

impl ProbeLighting {
    /// The local map is fused at `settings.face_size`, and decomposed with `settings`.
    pub fn new(
        probes: Vec<Probe>,
        proxies: SceneBvh,
        sky: EnvMap,
        settings: DecomposeSettings,
        tracking: TrackingSettings,
    ) -> Result<Self, DecomposeError> {
        let decomposer = Decomposer::new(tracking.decomposer_settings(&settings))?;
        Ok(Self {
            geometry: CubeGeometry::new(settings.face_size),
            probes,
            proxies,
            sky,
            fusion: FusionSettings::default(),
            settings,
            decomposer,
            tracker: LightTracker::new(tracking),
        })
    }

    /// The decomposition's settings.
    pub fn settings(&self) -> &DecomposeSettings {
        &self.settings
    }

    pub fn probes(&self) -> &[Probe] {
        &self.probes
    }

    /// The room's surfaces.
    pub fn proxies(&self) -> &SceneBvh {
        &self.proxies
    }

    /// The cube map the decomposition works on: its face size and directions.
    pub fn geometry(&self) -> &CubeGeometry {
        &self.geometry
    }

    /// The local map at `p`, undecomposed.
    pub fn local_map(&self, p: Vec3) -> (crate::cubemap::CubeMap, FusionStats) {
        let fusion = ProbeFusion::new(&self.probes, &self.proxies, &self.sky, self.fusion);
        fusion.local_map(&self.geometry, p)
    }

    /// The lighting at `p`, its lights followed from the previous update's.
    pub fn update(&mut self, p: Vec3) -> ProbeFrame {
        let start = Instant::now();
        let (map, stats) = self.local_map(p);
        let fused = Instant::now();
        let decomposition = self.decomposer.decompose(&map);
        let (threshold, max_lights) = (self.settings.threshold, self.settings.max_lights);
        let lighting = self.tracker.update(&decomposition, threshold, max_lights);
        ProbeFrame {
            lighting,
            stats,
            fuse_ms: (fused - start).as_secs_f64() * 1e3,
            decompose_ms: fused.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// Forgets the followed lights: the next update starts afresh (a jump, not a move).
    pub fn reset(&mut self) {
        self.tracker.reset();
    }
}
