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

pub mod composite;
pub mod export;
mod integrator;
pub mod job;
mod light;
mod sampler;
pub mod shard;

pub use integrator::{DirectVisibility, Integrator, PathEstimate, SurfacePoint};
pub use light::EnvironmentLight;
pub use sampler::{MAX_SOBOL_SAMPLES, PathSampler, PixelSampler, SamplerKind, SobolSampler};

use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::color::Rgb;
use foundation::envmap::{EnvMap, texel_centre_direction};
use foundation::image_io::RgbImageF32;
use foundation::infra::progress::Progress;
use foundation::probe::{DistanceMap, Probe};
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
    /// The triangle the pixel's centre sees, or [`NO_HIT`].
    pub primary: Vec<u32>,
    pub stats: RenderStats,
}

/// Marks a pixel that sees no geometry in [`ReferenceImage::primary`].
pub const NO_HIT: u32 = u32::MAX;

#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RenderStats {
    pub rays: u64,
    pub seconds: f64,
}

impl ReferenceImage {
    /// The `width` × `height` image whose rows `rows` each part holds (as [`render_rows`]
    /// rendered them), their statistics summed. `None` unless the parts fill every row once.
    pub fn assemble(
        width: usize,
        height: usize,
        parts: &[(Vec<usize>, ReferenceImage)],
    ) -> Option<ReferenceImage> {
        let mut source: Vec<Option<(usize, usize)>> = vec![None; height];
        for (p, (rows, image)) in parts.iter().enumerate() {
            if image.radiance.width != width || image.radiance.height != rows.len() {
                return None;
            }
            for (k, &j) in rows.iter().enumerate() {
                match source.get_mut(j) {
                    Some(slot @ None) => *slot = Some((p, k)),
                    _ => return None,
                }
            }
        }
        let source: Vec<(usize, usize)> = source.into_iter().collect::<Option<_>>()?;
        // Row j of the image is row k of part p.
        fn gather<T: Copy>(
            source: &[(usize, usize)],
            width: usize,
            parts: &[(Vec<usize>, ReferenceImage)],
            at: impl Fn(&ReferenceImage) -> &[T],
        ) -> Vec<T> {
            source
                .iter()
                .flat_map(|&(p, k)| at(&parts[p].1)[k * width..(k + 1) * width].iter().copied())
                .collect()
        }
        let rgb = |at: fn(&ReferenceImage) -> &[Rgb]| {
            RgbImageF32::new(width, height, gather(&source, width, parts, at))
        };
        Some(ReferenceImage {
            radiance: rgb(|i| &i.radiance.pixels),
            specular: rgb(|i| &i.specular.pixels),
            coverage: gather(&source, width, parts, |i| &i.coverage),
            visibility: gather(&source, width, parts, |i| &i.visibility),
            primary: gather(&source, width, parts, |i| &i.primary),
            stats: RenderStats {
                rays: parts.iter().map(|(_, i)| i.stats.rays).sum(),
                seconds: parts.iter().map(|(_, i)| i.stats.seconds).sum(),
            },
        })
    }
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

/// What one pixel's paths found.
#[derive(Clone, Copy)]
struct PixelResult {
    radiance: Rgb,
    coverage: f32,
    visibility: f32,
    specular: Rgb,
    primary: u32,
}

/// Why a path trace stopped without an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RenderError {
    /// Its [`Progress`] answered [`Progress::cancelled`] (asked before each image row).
    #[error("the path trace was cancelled")]
    Cancelled,
}

/// `progress` with its cancellation ignored: the work it reports on always finishes.
pub(crate) struct NeverCancelled<'a>(pub(crate) &'a dyn Progress);

impl Progress for NeverCancelled<'_> {
    fn start(&self, total: u64) {
        self.0.start(total);
    }
    fn advance(&self, steps: u64) {
        self.0.advance(steps);
    }
    fn status(&self, text: &str) {
        self.0.status(text);
    }
    fn finish(&self) {
        self.0.finish();
    }
}

/// Renders `camera`'s view of `geometry` lit by `light`. `progress` counts image rows; it
/// cannot cancel this form ([`try_render`] can).
pub fn render(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    progress: &dyn Progress,
) -> ReferenceImage {
    let progress = NeverCancelled(progress);
    try_render(geometry, bvh, light, camera, settings, &progress).expect("never cancelled")
}

/// [`render`], stopped with [`RenderError::Cancelled`] when `progress` answers
/// [`Progress::cancelled`] (asked before each row); the same image when it does not.
pub fn try_render(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    progress: &dyn Progress,
) -> Result<ReferenceImage, RenderError> {
    let rows: Vec<usize> = (0..camera.height as usize).collect();
    try_render_rows(geometry, bvh, light, camera, settings, &rows, progress)
}

/// Renders the image rows `rows` (in that order, one below the other) of [`render`]'s
/// image, each pixel exactly as the whole image has it (a pixel's samples depend only on its
/// index and the seed), so rows rendered apart and [assembled](ReferenceImage::assemble)
/// equal the whole image. `progress` cannot cancel this form ([`try_render_rows`] can).
pub fn render_rows(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    rows: &[usize],
    progress: &dyn Progress,
) -> ReferenceImage {
    let progress = NeverCancelled(progress);
    try_render_rows(geometry, bvh, light, camera, settings, rows, &progress)
        .expect("never cancelled")
}

/// [`render_rows`], stopped with [`RenderError::Cancelled`] when `progress` answers
/// [`Progress::cancelled`] (asked before each row).
pub fn try_render_rows(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    rows: &[usize],
    progress: &dyn Progress,
) -> Result<ReferenceImage, RenderError> {
    let start = Instant::now();
    let (width, height) = (camera.width as usize, rows.len());
    let basis = camera.basis();
    let integrator = Integrator::new(geometry, bvh, light, settings.bounces);
    progress.start(height as u64);
    let rows: Vec<(Vec<PixelResult>, u64)> = rows
        .par_iter()
        .map(|&j| {
            if progress.cancelled() {
                return None;
            }
            let mut rays = 0u64;
            let row = (0..width)
                .map(|i| {
                    let direction = camera.pixel_direction(&basis, i as u32, j as u32);
                    let index = (j * width + i) as u64;
                    render_pixel(
                        &integrator,
                        camera.position,
                        direction,
                        index,
                        settings,
                        &mut rays,
                    )
                })
                .collect();
            progress.advance(1);
            Some((row, rays))
        })
        .collect::<Option<_>>()
        .ok_or(RenderError::Cancelled)?;
    progress.finish();
    let pixels: Vec<PixelResult> = rows
        .iter()
        .flat_map(|(row, _)| row.iter().copied())
        .collect();
    let image = |f: fn(&PixelResult) -> Rgb| {
        RgbImageF32::new(width, height, pixels.iter().map(f).collect())
    };
    Ok(ReferenceImage {
        radiance: image(|p| p.radiance),
        specular: image(|p| p.specular),
        coverage: pixels.iter().map(|p| p.coverage).collect(),
        visibility: pixels.iter().map(|p| p.visibility).collect(),
        primary: pixels.iter().map(|p| p.primary).collect(),
        stats: RenderStats {
            rays: rows.iter().map(|(_, rays)| rays).sum(),
            seconds: start.elapsed().as_secs_f64(),
        },
    })
}

/// A synthetic light probe: the radiance arriving at `position` through the centre of each
/// texel of a `width × height` equirectangular map, each texel's paths as a pixel's (its
/// random stream from the seed and the texel index), and the distance to `geometry` through
/// each texel. `progress` counts rows.
pub fn render_probe(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    light: &EnvironmentLight,
    position: glam::Vec3,
    (width, height): (usize, usize),
    settings: &ReferenceSettings,
    progress: &dyn Progress,
) -> (Probe, RenderStats) {
    let start = Instant::now();
    let integrator = Integrator::new(geometry, bvh, light, settings.bounces);
    progress.start(height as u64);
    let rows: Vec<(Vec<Rgb>, u64)> = (0..height)
        .into_par_iter()
        .map(|j| {
            let mut rays = 0u64;
            let row = (0..width)
                .map(|i| {
                    let direction = texel_centre_direction(width, height, i, j);
                    let index = (j * width + i) as u64;
                    render_pixel(&integrator, position, direction, index, settings, &mut rays)
                        .radiance
                })
                .collect();
            progress.advance(1);
            (row, rays)
        })
        .collect();
    progress.finish();
    let texels = rows
        .iter()
        .flat_map(|(row, _)| row.iter().copied())
        .collect();
    let radiance = EnvMap::new(width, height, texels);
    let distances = DistanceMap::trace(bvh, position, width, height);
    let probe = Probe::new(position, radiance, distances).expect("maps of one size");
    let stats = RenderStats {
        rays: rows.iter().map(|(_, rays)| rays).sum::<u64>() + (width * height) as u64,
        seconds: start.elapsed().as_secs_f64(),
    };
    (probe, stats)
}

/// The paths of pixel `index`, whose centre's ray leaves `origin` in `direction`.
fn render_pixel(
    integrator: &Integrator,
    origin: glam::Vec3,
    direction: glam::Vec3,
    index: u64,
    settings: &ReferenceSettings,
    rays: &mut u64,
) -> PixelResult {
    *rays += 1;
    let Some(hit) = integrator
        .bvh
        .intersect(origin, direction, 0.0, f32::INFINITY)
    else {
        return PixelResult {
            radiance: integrator.light.radiance(direction),
            coverage: 0.0,
            visibility: 1.0,
            specular: Rgb::ZERO,
            primary: NO_HIT,
        };
    };
    let point = integrator.surface(&hit);
    let mut sampler = PixelSampler::for_pass(
        settings.sampler,
        settings.seed,
        index,
        settings.first_sample,
    );
    let (mut sum, mut specular) = (Rgb::ZERO, Rgb::ZERO);
    let mut direct = DirectVisibility::default();
    for _ in 0..settings.spp {
        let e = integrator.radiance(&point, -direction, &mut sampler, rays);
        sampler.next_sample();
        sum += e.radiance;
        specular += e.specular;
        direct.visible += e.direct.visible;
        direct.unoccluded += e.direct.unoccluded;
    }
    let samples = settings.spp.max(1) as f32;
    PixelResult {
        radiance: sum / samples,
        coverage: 1.0,
        visibility: if direct.unoccluded > 0.0 {
            direct.visible / direct.unoccluded
        } else {
            1.0
        },
        specular: specular / samples,
        primary: hit.triangle,
    }
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
