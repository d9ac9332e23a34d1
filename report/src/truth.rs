//! The reports' reference: two independent halves, whose difference measures its own noise
//! (CONVENTIONS.md, "The reference's noise"), cached with their sample counts so that a later,
//! stricter request continues them instead of starting over. (The path tracer itself is the
//! `reference` crate; this module is the report's use of it.)

mod request;

pub(crate) use request::view_inputs;
pub use request::{NoiseTarget, ReferenceRequest};

use crate::error::{ReportError, Result};
use crate::observer::Observer;
use crate::stats::{Masks, NoiseFloor, noise_floor};
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::{RgbImageF32, read_exr, write_exr};
use foundation::infra::cache::{CacheKey, Entry};
use foundation::infra::progress::Progress;
use foundation::scene::Scene;
use reference::{
    self, EnvironmentLight, MAX_SOBOL_SAMPLES, ReferenceImage, ReferenceSettings, SamplerKind,
};
use request::reference_key;
use std::path::PathBuf;
use std::time::Instant;

/// The reference with its coverage, visibility and halves.
pub struct ReferenceImages {
    /// The mean of the two halves.
    pub radiance: RgbImageF32,
    pub halves: [RgbImageF32; 2],
    pub coverage: Vec<f32>,
    pub visibility: Vec<f32>,
    /// Glossy scenes: the part of `radiance` reflected by the first surface's specular lobe.
    pub specular: Option<RgbImageF32>,
    pub samples_per_half: u32,
    /// Nothing had to be rendered.
    pub cached: bool,
    /// Seconds spent rendering now.
    pub seconds: f64,
}

impl ReferenceImages {
    /// The noise floor of the statistics on this reference.
    pub fn noise(&self, exposure: f32) -> NoiseFloor {
        noise_floor(&self.halves[0], &self.halves[1], &self.masks(), exposure)
    }

    /// The statistics' regions on this reference (the highlight region where it has a
    /// specular part).
    pub fn masks(&self) -> Masks {
        let masks = Masks::new(&self.coverage, &self.visibility);
        match &self.specular {
            Some(specular) => masks.with_highlight(&self.radiance, specular),
            None => masks,
        }
    }
}

/// The seed of half `k` (0 or 1): independent streams and scrambles.
fn half_seed(seed: u64, k: usize) -> u64 {
    if k == 0 {
        seed
    } else {
        seed ^ 0x9e37_79b9_7f4a_7c15
    }
}

#[derive(serde::Serialize, serde::Deserialize)]
struct CacheMeta {
    samples_per_half: u32,
}

/// A cache entry: a marker naming the sample count, and images named by it. Every file is
/// written to a temporary name and renamed into place, and the images of one sample count are
/// the same whoever renders them (the samples are deterministic), so processes on many
/// machines sharing the cache (report shards on NFS) never see a mixed entry: the marker,
/// renamed last, names images that are complete.
struct CachePaths {
    entry: Entry,
}

/// The images of one cache entry.
struct EntryFiles {
    halves: [PathBuf; 2],
    coverage: PathBuf,
    visibility: PathBuf,
    specular: PathBuf,
}

impl CachePaths {
    fn new(key: &CacheKey) -> Self {
        Self { entry: key.entry() }
    }

    fn files(&self, samples_per_half: u32) -> EntryFiles {
        let file = |kind: &str| self.entry.file(&format!("{samples_per_half}spp.{kind}"));
        EntryFiles {
            halves: [file("half0.exr"), file("half1.exr")],
            coverage: file("coverage.exr"),
            visibility: file("visibility.exr"),
            specular: file("specular.exr"),
        }
    }

    /// `glossy`: the entry must have its specular part.
    fn load(&self, glossy: bool) -> Result<ReferenceImages> {
        let meta: CacheMeta = serde_json::from_slice(&std::fs::read(self.entry.marker())?)?;
        let files = self.files(meta.samples_per_half);
        let halves = [read_exr(&files.halves[0])?, read_exr(&files.halves[1])?];
        let grey = |path: &PathBuf| -> Result<Vec<f32>> {
            Ok(read_exr(path)?.pixels.iter().map(|p| p.x).collect())
        };
        Ok(ReferenceImages {
            radiance: weighted_image(&halves[0], 1, &halves[1], 1),
            halves,
            coverage: grey(&files.coverage)?,
            visibility: grey(&files.visibility)?,
            specular: if glossy {
                Some(read_exr(&files.specular)?)
            } else {
                None
            },
            samples_per_half: meta.samples_per_half,
            cached: true,
            seconds: 0.0,
        })
    }

    /// Writes the images, then the sample count that makes them the entry, then removes the
    /// images of the count it replaced.
    fn store(&self, images: &ReferenceImages, replaced: Option<u32>) -> Result<()> {
        self.entry.create_folder()?;
        let (w, h) = (images.radiance.width, images.radiance.height);
        let files = self.files(images.samples_per_half);
        write_exr(&files.halves[0], &images.halves[0])?;
        write_exr(&files.halves[1], &images.halves[1])?;
        write_exr(
            &files.coverage,
            &RgbImageF32::from_grey(w, h, &images.coverage),
        )?;
        write_exr(
            &files.visibility,
            &RgbImageF32::from_grey(w, h, &images.visibility),
        )?;
        if let Some(specular) = &images.specular {
            write_exr(&files.specular, specular)?;
        }
        let meta = CacheMeta {
            samples_per_half: images.samples_per_half,
        };
        self.entry.commit(&serde_json::to_vec(&meta)?)?;
        if let Some(old) = replaced.filter(|&n| n != images.samples_per_half) {
            let old = self.files(old);
            for path in old
                .halves
                .iter()
                .chain([&old.coverage, &old.visibility, &old.specular])
            {
                let _ = std::fs::remove_file(path);
            }
        }
        Ok(())
    }
}

/// `(a n + b k) / (n + k)` element by element: the mean of `n` samples' estimate `a` and
/// `k` samples' estimate `b`.
fn weighted<T>(a: &[T], n: u32, b: &[T], k: u32) -> Vec<T>
where
    T: Copy
        + std::ops::Mul<f32, Output = T>
        + std::ops::Add<Output = T>
        + std::ops::Div<f32, Output = T>,
{
    let (n, k) = (n as f32, k as f32);
    a.iter()
        .zip(b)
        .map(|(a, b)| (*a * n + *b * k) / (n + k))
        .collect()
}

fn weighted_image(a: &RgbImageF32, n: u32, b: &RgbImageF32, k: u32) -> RgbImageF32 {
    RgbImageF32::new(a.width, a.height, weighted(&a.pixels, n, &b.pixels, k))
}

/// What a reference traces: the scene's BVH, seen through the camera, lit by the turned map.
/// Built once per reference, on its first pass.
struct View<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    bvh: SceneBvh,
    light: EnvironmentLight<'a>,
}

/// Renders samples `[first, first + count)` of both halves and merges them into `current`.
fn render_pass(
    view: &View,
    request: &ReferenceRequest,
    current: Option<ReferenceImages>,
    count: u32,
    progress: &dyn Progress,
) -> Result<ReferenceImages, reference::RenderError> {
    let first = current.as_ref().map_or(0, |c| c.samples_per_half);
    let passes: Vec<ReferenceImage> = (0..2)
        .map(|k| {
            let settings = ReferenceSettings {
                sampler: request.sampler,
                first_sample: first,
                ..ReferenceSettings::new(count, request.bounces, half_seed(request.seed, k))
            };
            // Stopped when `progress` asks (Ctrl-C from Python); the same image otherwise.
            reference::try_render(
                &view.scene.geometry,
                &view.bvh,
                &view.light,
                view.camera,
                &settings,
                progress,
            )
        })
        .collect::<Result<_, _>>()?;
    let [a, b]: [ReferenceImage; 2] = passes.try_into().ok().expect("two halves");
    let visibility = weighted(&a.visibility, 1, &b.visibility, 1);
    let specular = view
        .scene
        .geometry
        .is_glossy()
        .then(|| weighted_image(&a.specular, 1, &b.specular, 1));
    let specular = match (specular, current.as_ref().and_then(|c| c.specular.as_ref())) {
        (Some(new), Some(old)) => Some(weighted_image(old, first, &new, count)),
        (new, _) => new,
    };
    let (halves, visibility) = match current {
        None => ([a.radiance, b.radiance], visibility),
        Some(c) => (
            [
                weighted_image(&c.halves[0], first, &a.radiance, count),
                weighted_image(&c.halves[1], first, &b.radiance, count),
            ],
            weighted(&c.visibility, first, &visibility, count),
        ),
    };
    Ok(ReferenceImages {
        radiance: weighted_image(&halves[0], 1, &halves[1], 1),
        halves,
        coverage: a.coverage,
        visibility,
        specular,
        samples_per_half: first + count,
        cached: false,
        seconds: 0.0,
    })
}

/// The cached reference at `paths`, if there is a readable one.
fn cached(paths: &CachePaths, key: &str, glossy: bool) -> Option<ReferenceImages> {
    if !paths.entry.marker().exists() {
        return None;
    }
    match paths.load(glossy) {
        Ok(images) => Some(images),
        Err(e) => {
            log::warn!("the cached reference {key} is unreadable ({e:#}); rendering it again");
            None
        }
    }
}

/// The most samples per half a reference takes with `sampler`.
fn sample_limit(sampler: SamplerKind) -> u32 {
    match sampler {
        SamplerKind::Sobol => MAX_SOBOL_SAMPLES,
        SamplerKind::Independent => u32::MAX / 2,
    }
}

/// The next pass towards the noise target `wanted`: how many samples per half it ends at and
/// its label, or none when the target is met or missed for good (warned).
fn next_pass(
    images: &ReferenceImages,
    wanted: NoiseTarget,
    request: &ReferenceRequest,
    limit: u32,
    start: Instant,
    seconds_per_sample: Option<f64>,
    best_error: &dyn Fn(&ReferenceImages) -> f64,
) -> Option<(u32, String)> {
    let target = match wanted {
        NoiseTarget::Absolute(t) => t,
        NoiseTarget::ShareOfBest(share) => share * best_error(images),
    };
    let floor = images.noise(request.exposure).mean;
    let n = images.samples_per_half;
    if floor <= target {
        return None;
    }
    if n >= limit {
        log::warn!(
            "reference: the target noise {target:.5} was missed: the noise floor is \
             {floor:.5} at 2 × {n} spp, the most samples the reference takes"
        );
        return None;
    }
    // Noise falls at least as 1/√n: the samples that should reach the target, at most
    // the sampler's limit (a target far below the noise would predict ages).
    let needed = (f64::from(n) * (floor / target).powi(2))
        .ceil()
        .min(f64::from(limit));
    let next = (2 * n).min(limit);
    if let (Some(max), Some(per_sample)) = (request.max_seconds, seconds_per_sample) {
        let elapsed = start.elapsed().as_secs_f64();
        if elapsed + per_sample * f64::from(next - n) > max {
            log::warn!(
                "reference: the target noise {target:.5} was missed: the noise floor is \
                 {floor:.5} at 2 × {n} spp, and the next pass would end after the \
                 {max} s limit"
            );
            return None;
        }
    }
    let left = seconds_per_sample
        .map(|s| format!(", about {:.0} s left", s * (needed - f64::from(n)).max(0.0)))
        .unwrap_or_default();
    let label =
        format!("2 × {n} → 2 × {next} spp (noise floor {floor:.5}, target {target:.5}{left})");
    Some((next, label))
}

/// The reference `request` asks for: from the cache, continued from it, or rendered (then
/// cached). `best_error` gives the best method's mean error against a reference, for a
/// target relative to it.
pub fn reference_images(
    scene: &Scene,
    camera: &Camera,
    map: &EnvMap,
    rotation_deg: f32,
    request: &ReferenceRequest,
    best_error: &dyn Fn(&ReferenceImages) -> f64,
    observer: &dyn Observer,
) -> Result<ReferenceImages> {
    let key = reference_key(scene, camera, map, rotation_deg, request)?;
    let paths = CachePaths::new(&key);
    let mut current = cached(&paths, key.hex(), scene.geometry.is_glossy());
    let limit = sample_limit(request.sampler);
    let start = Instant::now();
    let mut seconds_per_sample = None;
    let view = std::cell::OnceCell::new();
    // One pass of `count` more samples per half, and the seconds each took.
    let pass = |current: Option<ReferenceImages>, count: u32, label: String| {
        observer.line(&format!("reference: {label}"));
        let progress = observer.progress("reference rows");
        progress.status(&label);
        let pass_start = Instant::now();
        let view = view.get_or_init(|| View {
            scene,
            camera,
            bvh: SceneBvh::cached(&scene.geometry.mesh),
            light: EnvironmentLight::new(map, rotation_deg),
        });
        let images = render_pass(view, request, current, count, progress.as_ref())?;
        Ok::<_, ReportError>((
            images,
            pass_start.elapsed().as_secs_f64() / f64::from(count),
        ))
    };
    let wanted = request.spp.div_ceil(2).max(1);
    let have = current.as_ref().map_or(0, |c| c.samples_per_half);
    if have < wanted {
        let label = format!("2 × {have} → 2 × {wanted} spp");
        let (images, per_sample) = pass(current, wanted - have, label)?;
        current = Some(images);
        seconds_per_sample = Some(per_sample);
    }
    let mut images = current.expect("rendered or cached");
    if let Some(wanted) = request.target_noise {
        while let Some((next, label)) = next_pass(
            &images,
            wanted,
            request,
            limit,
            start,
            seconds_per_sample,
            best_error,
        ) {
            let n = images.samples_per_half;
            let (more, per_sample) = pass(Some(images), next - n, label)?;
            images = more;
            seconds_per_sample = Some(per_sample);
        }
    }
    let rendered = images.samples_per_half > have;
    if rendered {
        paths.store(&images, (have > 0).then_some(have))?;
    }
    images.cached = !rendered;
    images.seconds = start.elapsed().as_secs_f64();
    Ok(images)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_have_different_seeds_and_half_zero_keeps_the_seed() {
        assert_eq!(half_seed(7, 0), 7);
        assert_ne!(half_seed(7, 1), 7);
        assert_ne!(half_seed(0, 1), half_seed(1, 1));
    }

    #[test]
    fn noise_targets_parse() {
        assert_eq!("0.001".parse(), Ok(NoiseTarget::Absolute(0.001)));
        assert_eq!("20%".parse(), Ok(NoiseTarget::ShareOfBest(0.2)));
        for bad in ["0", "-1%", "abc", "nan", "%"] {
            assert!(bad.parse::<NoiseTarget>().is_err(), "{bad}");
        }
    }

    #[test]
    fn weighted_merge_is_the_mean_of_all_samples() {
        assert_eq!(weighted(&[1.0, 4.0], 1, &[4.0, 1.0], 2), vec![3.0, 2.0]);
    }
}
