//! The reference renderer's speed, and Mitsuba 3's on the same image when it is installed.

use crate::error::{BenchError, Result};
use crate::inputs::{ChosenMap, EnvironmentChoice, load_scene, with_threads};
use crate::mitsuba::{Mitsuba, covered_mean_difference};
use crate::stats::median;
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::infra::progress::NoProgress;
use foundation::scene::Scene;
use reference::{EnvironmentLight, ReferenceImage, ReferenceSettings};
use serde::Serialize;
use std::path::PathBuf;

/// What `bench_reference` measures.
#[derive(Debug, Clone)]
pub struct ReferenceBench {
    pub scene: PathBuf,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub bounces: u32,
    /// Renders; medians are reported.
    pub repeat: usize,
    /// Worker threads (all cores when `None`).
    pub threads: Option<usize>,
}

/// hprt's medians.
#[derive(Debug, Clone, Serialize)]
pub struct ReferenceResult {
    pub scene: String,
    pub seconds: f64,
    pub rays_per_second: f64,
    pub seconds_per_megapixel_sample: f64,
}

/// Mitsuba's time on the same image, beside hprt's.
#[derive(Debug, Clone, Serialize)]
pub struct MitsubaComparison {
    pub version: String,
    pub variant: &'static str,
    /// The median of the renders after the first.
    pub seconds: f64,
    /// Renders in that median.
    pub renders: usize,
    /// The first render's time, kernel compilation included.
    pub first_seconds: f64,
    /// hprt's median time over Mitsuba's.
    pub time_ratio: f64,
    /// The relative difference of hprt's mean radiance over covered pixels from Mitsuba's.
    pub mean_difference: f64,
}

/// The renders `bench_reference` made: their medians, and what Mitsuba needs to draw the same.
pub struct ReferenceRun {
    pub result: ReferenceResult,
    scene: Scene,
    env: ChosenMap,
    camera: Camera,
    settings: ReferenceSettings,
    last: ReferenceImage,
}

/// Renders the scene's reference `repeat` times.
pub fn bench_reference(bench: &ReferenceBench) -> Result<ReferenceRun> {
    let scene = load_scene(&bench.scene)?;
    let env = EnvironmentChoice::default().choose(&scene)?;
    let camera = scene.camera.with_size(bench.width, bench.height);
    camera.validate()?;
    let settings = ReferenceSettings::new(bench.spp, bench.bounces, 0);
    settings.validate()?;
    let mut runs = with_threads(bench.threads, || {
        let bvh = SceneBvh::build(&scene.geometry.mesh);
        let light = EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
        (0..bench.repeat.max(1))
            .map(|_| {
                reference::render(
                    &scene.geometry,
                    &bvh,
                    &light,
                    &camera,
                    &settings,
                    &NoProgress,
                )
            })
            .collect::<Vec<_>>()
    })?;
    let seconds = median(runs.iter().map(|r| r.stats.seconds).collect());
    let rays_per_second = median(runs.iter().map(|r| r.stats.rays_per_second()).collect());
    let megapixel_samples = bench.width as f64 * bench.height as f64 * bench.spp as f64 / 1e6;
    let last = runs.pop().expect("at least one render");
    Ok(ReferenceRun {
        result: ReferenceResult {
            scene: scene.name.clone(),
            seconds,
            rays_per_second,
            seconds_per_megapixel_sample: seconds / megapixel_samples,
        },
        scene,
        env,
        camera,
        settings,
        last,
    })
}

impl ReferenceRun {
    /// Renders the same image with Mitsuba 3, when it is found (`None` otherwise): `repeat`
    /// timed renders after the first.
    pub fn compare_with_mitsuba(&self, repeat: usize) -> Result<Option<MitsubaComparison>> {
        let Some(mitsuba) = Mitsuba::find() else {
            return Ok(None);
        };
        let dir = tempfile::tempdir()
            .map_err(BenchError::file("cannot make a temporary folder", "/tmp"))?;
        let export = reference::export::ExportSettings {
            camera: self.camera,
            rotation_deg: self.env.rotation_deg,
            spp: self.settings.spp,
            bounces: self.settings.bounces,
        };
        let geometry = &self.scene.geometry;
        let map = &self.env.loaded.map;
        let (times, image) = mitsuba.render(dir.path(), geometry, map, &export, repeat + 1)?;
        if times.len() < 2 {
            return Err(BenchError::NoMitsubaTimings);
        }
        // The first render compiles the LLVM variant's kernels; the rest are steady state.
        let steady = median(times[1..].to_vec());
        let last = &self.last;
        Ok(Some(MitsubaComparison {
            version: mitsuba.version.clone(),
            variant: mitsuba.variant,
            seconds: steady,
            renders: times.len() - 1,
            first_seconds: times[0],
            time_ratio: self.result.seconds / steady,
            mean_difference: covered_mean_difference(&last.radiance, &image, &last.coverage),
        }))
    }
}

impl ReferenceRun {
    /// The benchmark's settings and hprt's figures, as `hprt bench reference` prints them.
    pub fn lines(&self, bench: &ReferenceBench) -> String {
        let r = &self.result;
        format!(
            "reference benchmark: {} {}x{}, {} spp, {} bounces, {} threads, median of {}\n\
             hprt: {:.2} s, {:.2} M rays/s, {:.3} s per megapixel per sample",
            r.scene,
            bench.width,
            bench.height,
            bench.spp,
            bench.bounces,
            bench.threads.unwrap_or_else(rayon::current_num_threads),
            bench.repeat,
            r.seconds,
            r.rays_per_second / 1e6,
            r.seconds_per_megapixel_sample
        )
    }
}

/// Said when no Python with Mitsuba 3 is found.
pub const NO_MITSUBA: &str =
    "Mitsuba 3 not found (pip install mitsuba, or set HPRT_MITSUBA_PYTHON): no comparison";

impl MitsubaComparison {
    /// Mitsuba's figures beside hprt's.
    pub fn line(&self) -> String {
        format!(
            "Mitsuba {} {}: {:.2} s (median of {}; the first, with kernel compilation, {:.2} s); \
             hprt takes {:.2}x Mitsuba's time; mean radiance of covered pixels: hprt {:+.2}% \
             from Mitsuba",
            self.version,
            self.variant,
            self.seconds,
            self.renders,
            self.first_seconds,
            self.time_ratio,
            100.0 * self.mean_difference
        )
    }
}
