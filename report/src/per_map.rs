//! The report per map (thesis chapter 5, Table 5.1 and Figures 5.7–5.11): for each
//! environment map, the path-traced reference, the plain PRT image and the hybrid in both
//! decomposition modes, their error images and statistics, and the error against the Weber
//! threshold.

use crate::error::{Result, error_chain};
use crate::figures::{self, Curve};
use crate::maps::{default_exposure, load_map, median, scene_rotation};
use crate::method_lighting::{LightingCost, first_frame_lighting, method_lighting};
use crate::methods::{Method, per_map_methods};
use crate::observer::Observer;
use crate::results::{MapReport, MapStatus, MethodResult, Report, SweepPoint};
use crate::settings::ReportSettings;
use crate::stats::{self, Masks, NoiseFloor, error_stats};
use crate::truth::{ReferenceImages, reference_images};
use crate::{csv, html};
use foundation::camera::Camera;
use foundation::image_io::{RgbImageF32, write_exr, write_png};
use foundation::infra::atomic_file::write_atomic;
use foundation::scene::Scene;
use precompute::bake::Transfer;
use runtime::render::{FrameLighting, GpuContext, Renderer, ShadowSettings};
use runtime::{DecomposeSettings, EnvironmentLighting};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Renders with `lighting` and times `frames` frames (static lighting, median).
fn render_timed(
    renderer: &mut Renderer,
    lighting: &FrameLighting,
    frames: usize,
) -> Result<(RgbImageF32, f64)> {
    renderer.set_lighting(lighting)?;
    renderer.render()?;
    let image = renderer.read_back()?;
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        renderer.render()?;
        renderer.wait();
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok((image, median(times)))
}

/// Each map's name in the report (and its folder's): the file stem, with `-2`, `-3`... added to
/// later maps of the same stem, so that no map's images overwrite another's.
pub(crate) fn unique_map_names(envs: &[PathBuf]) -> Vec<String> {
    let mut names: Vec<String> = Vec::with_capacity(envs.len());
    for env in envs {
        let stem = map_name(env);
        let mut name = stem.clone();
        let mut k = 2;
        while names.contains(&name) {
            name = format!("{stem}-{k}");
            k += 1;
        }
        names.push(name);
    }
    names
}

fn map_name(path: &Path) -> String {
    // A folder of the report: one plain name whatever the file is called (`...exr` has the
    // stem `..`).
    path.file_stem()
        .map(|s| foundation::infra::names::as_file_name(&s.to_string_lossy()))
        .unwrap_or_else(|| "map".into())
}

struct MapJob<'a> {
    scene: &'a Scene,
    camera: Camera,
    settings: &'a ReportSettings,
    renderer: &'a mut Renderer,
    out: &'a Path,
    observer: &'a dyn Observer,
}

/// The reference's images, written into the map's folder.
fn write_reference(dir: &Path, reference: &ReferenceImages, exposure: f32) -> Result<()> {
    let (w, h) = (reference.radiance.width, reference.radiance.height);
    write_exr(&dir.join("reference.exr"), &reference.radiance)?;
    write_png(&dir.join("reference.png"), &reference.radiance, exposure)?;
    // The two independent halves it averages: their difference is its noise floor.
    for (k, half) in reference.halves.iter().enumerate() {
        write_exr(&dir.join(format!("reference-half{k}.exr")), half)?;
    }
    write_exr(
        &dir.join("reference-coverage.exr"),
        &RgbImageF32::from_grey(w, h, &reference.coverage),
    )?;
    write_exr(
        &dir.join("reference-visibility.exr"),
        &RgbImageF32::from_grey(w, h, &reference.visibility),
    )?;
    Ok(())
}

/// Error heat maps on one scale per map, the baseline's (PRT's) 99th percentile over covered
/// pixels; larger errors saturate.
fn write_heat_maps(
    dir: &Path,
    images: &[RgbImageF32],
    reference: &RgbImageF32,
    masks: &Masks,
    exposure: f32,
) -> Result<()> {
    let errors: Vec<Vec<f32>> = images
        .iter()
        .map(|image| stats::error_image(image, reference, exposure))
        .collect();
    let scale = stats::covered_percentile(&errors[0], &masks.covered, 0.99).max(1e-3);
    for (method, errors) in per_map_methods().iter().zip(&errors) {
        let (w, h) = (reference.width as u32, reference.height as u32);
        let png = figures::heat_map(errors, &masks.covered, w, h, scale, method.name)?;
        write_atomic(&dir.join(format!("error-{}.png", method.file_stem)), &png)?;
    }
    Ok(())
}

/// One map's section; an error is reported as a failed map by the caller.
fn report_map(job: &mut MapJob, env: &Path, name: &str) -> Result<MapReport> {
    let name = name.to_owned();
    let map = load_map(env, None)?.map;
    let rotation = scene_rotation(job.scene, None);
    let exposure = default_exposure(&map);
    let dir = job.out.join(&name);
    crate::maps::create_folder(&dir)?;

    // The methods first: a reference rendered to a share of the best method's error needs
    // their images.
    job.renderer.set_environment(&map, rotation);
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default())?;
    lighting.set_rotation(rotation);
    if job.scene.geometry.is_glossy() {
        lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
    }
    let (rendered, images) = render_methods(job, &mut lighting, &dir, exposure)?;
    job.renderer.release_shadow_maps(); // not needed while the reference renders on the CPU

    let request = job.settings.reference_request(exposure);
    let best_error = |reference: &ReferenceImages| {
        let masks = reference.masks();
        images
            .iter()
            .map(|image| error_stats(image, &reference.radiance, &masks, exposure).mean)
            .fold(f64::INFINITY, f64::min)
    };
    let reference = reference_images(
        job.scene,
        &job.camera,
        &map,
        rotation,
        &request,
        &best_error,
        job.observer,
    )?;
    let noise = reference.noise(exposure);
    announce_reference(job.observer, &name, &reference, &noise, &job.camera);
    write_reference(&dir, &reference, exposure)?;
    let masks = reference.masks();
    let methods: Vec<MethodResult> = rendered
        .iter()
        .zip(&images)
        .map(|(rendered, image)| {
            let stats = error_stats(image, &reference.radiance, &masks, exposure);
            MethodResult {
                method: rendered.method.name.to_owned(),
                relative_rmse_corrected: stats::corrected_relative_rmse(
                    stats.relative_rmse,
                    &noise,
                ),
                stats,
                lights: rendered.lights,
                decomposition_ms: rendered.cost.first_ms,
                warm_decomposition_ms: rendered.cost.warm_ms,
                frame_ms: rendered.frame_ms,
            }
        })
        .collect();
    write_heat_maps(&dir, &images, &reference.radiance, &masks, exposure)?;
    let (sweep, curves) = threshold_sweep(job, &mut lighting, &reference, &masks, exposure)?;
    let noise_warning = warn_if_noisy(job.observer, &name, &noise, &methods);
    let svg = figures::threshold_plot(&name, &curves, methods[0].stats.mean)?;
    write_atomic(&dir.join("threshold.svg"), svg.as_bytes())?;
    Ok(MapReport {
        name,
        path: env.display().to_string(),
        status: MapStatus::Ok,
        error: None,
        exposure,
        reference_cached: reference.cached,
        reference_seconds: reference.seconds,
        reference_spp: 2 * reference.samples_per_half,
        noise,
        noise_warning,
        methods,
        sweep,
    })
}

/// One method's points of the threshold sweep, by its name.
type MethodSweep = (String, Vec<SweepPoint>);

/// One method's frame: its lights, what its lighting cost and its frame time.
struct RenderedMethod {
    method: Method,
    lights: usize,
    cost: LightingCost,
    frame_ms: f64,
}

/// Renders every method (writing its EXR and PNG into `dir`) and times it.
fn render_methods(
    job: &mut MapJob,
    lighting: &mut EnvironmentLighting,
    dir: &Path,
    exposure: f32,
) -> Result<(Vec<RenderedMethod>, Vec<RgbImageF32>)> {
    let order = job.renderer.order();
    let default_threshold = DecomposeSettings::default().threshold;
    let mut rendered = Vec::new();
    let mut images = Vec::new();
    for method in per_map_methods() {
        let (frame, lights, cost) = method_lighting(lighting, order, method, default_threshold)?;
        let (image, frame_ms) = render_timed(job.renderer, &frame, job.settings.frames)?;
        write_exr(&dir.join(format!("{}.exr", method.file_stem)), &image)?;
        write_png(
            &dir.join(format!("{}.png", method.file_stem)),
            &image,
            exposure,
        )?;
        rendered.push(RenderedMethod {
            method,
            lights,
            cost,
            frame_ms,
        });
        images.push(image);
    }
    Ok((rendered, images))
}

/// Says where the map's reference came from and how noisy it is.
fn announce_reference(
    observer: &dyn Observer,
    name: &str,
    reference: &ReferenceImages,
    noise: &NoiseFloor,
    camera: &Camera,
) {
    let spp = 2 * reference.samples_per_half;
    if reference.cached {
        observer.line(&format!("{name}: reference from the cache ({spp} spp)"));
    } else {
        observer.line(&format!(
            "{name}: reference ({}x{}, {spp} spp) rendered in {:.1} s",
            camera.width, camera.height, reference.seconds
        ));
    }
    observer.line(&format!(
        "{name}: reference noise floor {:.5} (mean), {:.5} (shadow region)",
        noise.mean, noise.shadow_mean
    ));
}

/// Error against the Weber threshold, for both hybrid modes: the sweep's points and the
/// plot's curves.
fn threshold_sweep(
    job: &mut MapJob,
    lighting: &mut EnvironmentLighting,
    reference: &ReferenceImages,
    masks: &Masks,
    exposure: f32,
) -> Result<(Vec<MethodSweep>, Vec<Curve>)> {
    let order = job.renderer.order();
    let mut sweep = Vec::new();
    let mut curves = Vec::new();
    for method in per_map_methods().iter().filter(|m| m.is_hybrid()) {
        let mut points = Vec::new();
        for &threshold in &job.settings.thresholds {
            let (frame, lights, _) = first_frame_lighting(lighting, order, *method, threshold)?;
            job.renderer.set_lighting(&frame)?;
            job.renderer.render()?;
            let image = job.renderer.read_back()?;
            let s = error_stats(&image, &reference.radiance, masks, exposure);
            points.push(SweepPoint {
                threshold,
                lights,
                mean: s.mean,
                shadow_mean: s.shadow_mean,
                penumbra_mean: s.penumbra_mean,
            });
        }
        curves.push(Curve {
            label: method.name.to_owned(),
            points: points
                .iter()
                .map(|p| (p.threshold, p.mean, p.lights))
                .collect(),
        });
        sweep.push((method.name.to_owned(), points));
    }
    Ok((sweep, curves))
}

/// Warns when the reference's noise is a large share of the best method's error; returns
/// whether it did.
fn warn_if_noisy(
    observer: &dyn Observer,
    name: &str,
    noise: &NoiseFloor,
    methods: &[MethodResult],
) -> bool {
    let best = methods
        .iter()
        .map(|m| m.stats.mean)
        .fold(f64::INFINITY, f64::min);
    let noisy = stats::noise_dominates(noise, best);
    if noisy {
        observer.line(&format!(
            "warning: {name}: the reference's noise floor {:.5} is {:.0}% of the best method's \
             mean error {best:.5}; the statistics measure the reference as much as the methods \
             (raise --spp or pass --target-noise {:.5})",
            noise.mean,
            100.0 * noise.mean / best,
            stats::NOISE_WARNING * best
        ));
    }
    noisy
}

/// The report's adapter, camera and renderer of `scene`'s bake, at the report's image size.
pub(crate) fn report_renderer(
    scene: &Scene,
    transfer: &Transfer,
    settings: &ReportSettings,
    observer: &dyn Observer,
) -> Result<(GpuContext, Camera, Renderer)> {
    let camera = scene.camera.with_size(settings.width, settings.height);
    camera.validate()?;
    let gpu = GpuContext::headless(settings.backend)?;
    observer.line(&format!("adapter: {}", gpu.description()));
    let renderer = Renderer::new(
        &gpu,
        &scene.geometry,
        transfer,
        &camera,
        ShadowSettings::default(),
    )?;
    Ok((gpu, camera, renderer))
}

/// Writes the whole report into `out`; maps that fail are reported as failed.
pub fn run_report(
    scene: &Scene,
    transfer: &Transfer,
    bake: &Path,
    envs: &[PathBuf],
    settings: &ReportSettings,
    out: &Path,
    observer: &dyn Observer,
) -> Result<Report> {
    crate::maps::create_folder(out)?;
    let (gpu, camera, mut renderer) = report_renderer(scene, transfer, settings, observer)?;
    let mut maps = Vec::new();
    for (env, name) in envs.iter().zip(unique_map_names(envs)) {
        let mut cx = MapJob {
            scene,
            camera,
            settings,
            renderer: &mut renderer,
            out,
            observer,
        };
        let report = report_map(&mut cx, env, &name).unwrap_or_else(|e| {
            let error = error_chain(&e);
            observer.line(&format!("{}: failed: {error}", env.display()));
            MapReport {
                name: name.clone(),
                path: env.display().to_string(),
                status: MapStatus::Failed,
                error: Some(error),
                exposure: 0.0,
                reference_cached: false,
                reference_seconds: 0.0,
                reference_spp: 0,
                noise: NoiseFloor::default(),
                noise_warning: false,
                methods: Vec::new(),
                sweep: Vec::new(),
            }
        });
        maps.push(report);
    }
    let web = match settings.web {
        true => Some(crate::web_viewer::write(
            scene, transfer, camera, envs, &maps, out, observer,
        )?),
        false => None,
    };
    let report = Report {
        web,
        scene: scene.path.display().to_string(),
        adapter: gpu.description().to_string(),
        bake: bake.display().to_string(),
        settings: settings.clone(),
        shadow_visibility_threshold: stats::SHADOW_VISIBILITY,
        penumbra_visibility: stats::PENUMBRA_VISIBILITY,
        maps,
    };
    write_atomic(
        &out.join("stats.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    write_atomic(&out.join("stats.csv"), &csv::csv_bytes(&report)?)?;
    write_atomic(
        &out.join("report.html"),
        html::page(&report, out)?.as_bytes(),
    )?;
    Ok(report)
}

/// The report's table, a line each: every map's methods and their errors.
pub fn summary_lines(report: &Report, glossy: bool) -> Vec<String> {
    let mut lines = vec![String::new()];
    // Glossy scenes add the highlight region's mean error.
    lines.push(format!(
        "{:<12} {:<18} {:>8} {:>8} {:>8} {:>8} {:>6}{}",
        "map",
        "method",
        "mean",
        "shadow",
        "penumbra",
        "rel.rmse",
        "lights",
        if glossy { "  highlight" } else { "" }
    ));
    for map in &report.maps {
        if map.methods.is_empty() {
            lines.push(format!("{:<12} failed", map.name));
        }
        for m in &map.methods {
            let highlight = if glossy {
                format!(" {:>10.4}", m.stats.highlight_mean)
            } else {
                String::new()
            };
            lines.push(format!(
                "{:<12} {:<18} {:>8.4} {:>8.4} {:>8.4} {:>8.4} {:>6}{highlight}",
                map.name,
                m.method,
                m.stats.mean,
                m.stats.shadow_mean,
                m.stats.penumbra_mean,
                m.stats.relative_rmse,
                m.lights
            ));
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_of_the_same_name_get_their_own_folders() {
        let envs: Vec<PathBuf> = ["a/sky.exr", "b/sky.exr", "c/sky.hdr", "sun.exr"]
            .iter()
            .map(PathBuf::from)
            .collect();
        assert_eq!(unique_map_names(&envs), ["sky", "sky-2", "sky-3", "sun"]);
    }
}
