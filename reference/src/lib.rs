//! The CPU path-traced reference: the ground truth every image-quality claim is measured
//! against. It shares the scene, the BVH and the conventions with the bake, but not its light
//! transport code.
//!
//! One primary ray through each pixel centre (no anti-aliasing, so images compare pixel for
//! pixel with the rasterizer), then `spp` independent light paths from the point it hits.
//! Each pixel has its own random stream, seeded by the seed and the pixel index, so the image
//! does not depend on the number of threads.

// Every public item is reachable from the crate root: the API is what lib.rs exports.
#![deny(unreachable_pub)]

pub mod export;
mod integrator;
mod light;
mod sampler;

pub use integrator::{DirectVisibility, Integrator, PathEstimate, SurfacePoint};
pub use light::EnvironmentLight;
pub use sampler::{MAX_SOBOL_SAMPLES, PathSampler, PixelSampler, SamplerKind, SobolSampler};

use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::color::Rgb;
use foundation::image_io::RgbImageF32;
use foundation::infra::progress::Progress;
use foundation::sampling::mix64;
use foundation::scene::SceneMesh;
use rand_pcg::Pcg32;
use rayon::prelude::*;
use std::time::Instant;

/// What to render.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ReferenceSettings {
    /// Light paths per pixel.
    pub spp: u32,
    /// Indirect bounces, as in the bake (0: shadowed direct lighting).
    pub bounces: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    /// Index of the first sample: a pass with `first_sample = n` continues one of `n` samples
    /// (same seed and sampler), so the two can be averaged weighted by their counts.
    pub first_sample: u32,
}

impl ReferenceSettings {
    /// `spp` samples from the start of the sequence with the default sampler.
    pub fn new(spp: u32, bounces: u32, seed: u64) -> Self {
        Self {
            spp,
            bounces,
            seed,
            sampler: SamplerKind::default(),
            first_sample: 0,
        }
    }

    /// Sobol sequences are 2^16 points long.
    pub fn validate(&self) -> Result<(), TooManySamples> {
        let asked = u64::from(self.first_sample) + u64::from(self.spp);
        if self.sampler == SamplerKind::Sobol && asked > u64::from(MAX_SOBOL_SAMPLES) {
            return Err(TooManySamples { asked });
        }
        Ok(())
    }
}

/// More samples per pixel than the Sobol sequences hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "the sobol sampler takes at most {max} samples per pixel, {asked} asked",
    max = MAX_SOBOL_SAMPLES
)]
pub struct TooManySamples {
    pub asked: u64,
}

/// The rendered images.
pub struct ReferenceImage {
    /// Linear radiance; pixels that see no geometry show the environment.
    pub radiance: RgbImageF32,
    /// 1 where the pixel's centre sees geometry, else 0.
    pub coverage: Vec<f32>,
    /// For covered pixels, the fraction of the (luminance of the) unoccluded direct
    /// irradiance from the environment that is actually visible; 1 elsewhere.
    pub visibility: Vec<f32>,
    /// The part of `radiance` reflected by the first surface's specular lobe (zero for
    /// diffuse surfaces and uncovered pixels).
    pub specular: RgbImageF32,
    pub stats: RenderStats,
}

#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RenderStats {
    pub rays: u64,
    pub seconds: f64,
}

impl RenderStats {
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds.max(1e-9)
    }
}

/// The random stream of pixel (or vertex) `index`.
pub(crate) fn stream(seed: u64, index: u64) -> Pcg32 {
    Pcg32::new(mix64(seed ^ mix64(index)), index)
}

/// One image row: radiance, coverage, direct visibility, the rays it took, and the specular
/// part of the radiance.
type RowResult = (Vec<Rgb>, Vec<f32>, Vec<f32>, u64, Vec<Rgb>);

/// Renders `camera`'s view of `geometry` lit by `light`. `progress` counts image rows.
pub fn render(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    progress: &dyn Progress,
) -> ReferenceImage {
    let start = Instant::now();
    let (width, height) = (camera.width as usize, camera.height as usize);
    let basis = camera.basis();
    let integrator = Integrator::new(geometry, bvh, light, settings.bounces);
    progress.start(height as u64);
    let rows: Vec<RowResult> = (0..height)
        .into_par_iter()
        .map(|j| {
            let mut row = (
                Vec::with_capacity(width),
                Vec::with_capacity(width),
                Vec::with_capacity(width),
                0u64,
                Vec::with_capacity(width),
            );
            for i in 0..width {
                let direction = camera.pixel_direction(&basis, i as u32, j as u32);
                row.3 += 1;
                let Some(hit) = bvh.intersect(camera.position, direction, 0.0, f32::INFINITY)
                else {
                    row.0.push(light.radiance(direction));
                    row.1.push(0.0);
                    row.2.push(1.0);
                    row.4.push(Rgb::ZERO);
                    continue;
                };
                let point = integrator.surface(&hit);
                let mut sampler = PixelSampler::for_pass(
                    settings.sampler,
                    settings.seed,
                    (j * width + i) as u64,
                    settings.first_sample,
                );
                let (mut sum, mut specular) = (Rgb::ZERO, Rgb::ZERO);
                let mut direct = DirectVisibility::default();
                for _ in 0..settings.spp {
                    let e = integrator.radiance(&point, -direction, &mut sampler, &mut row.3);
                    sampler.next_sample();
                    sum += e.radiance;
                    specular += e.specular;
                    direct.visible += e.direct.visible;
                    direct.unoccluded += e.direct.unoccluded;
                }
                row.0.push(sum / settings.spp.max(1) as f32);
                row.4.push(specular / settings.spp.max(1) as f32);
                row.1.push(1.0);
                row.2.push(if direct.unoccluded > 0.0 {
                    direct.visible / direct.unoccluded
                } else {
                    1.0
                });
            }
            progress.advance(1);
            row
        })
        .collect();
    progress.finish();
    let mut pixels = Vec::with_capacity(width * height);
    let mut image = ReferenceImage {
        radiance: RgbImageF32::filled(0, 0, Rgb::ZERO),
        coverage: Vec::with_capacity(width * height),
        visibility: Vec::with_capacity(width * height),
        specular: RgbImageF32::filled(0, 0, Rgb::ZERO),
        stats: RenderStats::default(),
    };
    let mut specular = Vec::with_capacity(width * height);
    for (radiance, coverage, visibility, rays, row_specular) in rows {
        pixels.extend(radiance);
        specular.extend(row_specular);
        image.coverage.extend(coverage);
        image.visibility.extend(visibility);
        image.stats.rays += rays;
    }
    image.radiance = RgbImageF32::new(width, height, pixels);
    image.specular = RgbImageF32::new(width, height, specular);
    image.stats.seconds = start.elapsed().as_secs_f64();
    image
}

/// Mean and standard error of `samples` estimates of the radiance leaving vertex `v` (the
/// quantity the bake's `dot(t, l)` predicts).
pub fn estimate_vertex(integrator: &Integrator, v: u32, samples: u32, seed: u64) -> (Rgb, Rgb) {
    let point = integrator.vertex(v);
    let mut rng = stream(seed, v as u64);
    let (mut sum, mut sum_sq) = (Rgb::ZERO, Rgb::ZERO);
    let mut rays = 0;
    for _ in 0..samples {
        let l = integrator
            .radiance(&point, point.shading_normal, &mut rng, &mut rays)
            .radiance;
        sum += l;
        sum_sq += l * l;
    }
    let n = samples as f32;
    let mean = sum / n;
    let variance = (sum_sq / n - mean * mean).max(Rgb::ZERO) * (n / (n - 1.0).max(1.0));
    (mean, (variance / n).powf(0.5))
}

#[cfg(test)]
mod tests;
