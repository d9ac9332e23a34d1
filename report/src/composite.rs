//! A composite's report (issue 31): for each map, the true composite (the scene path-traced
//! with and without its virtual objects, in two independent halves) and every GPU method's
//! composite (`crate::gpu_composite`, the truth's ratio form), with their errors over the
//! objects, over the changed region (proxy pixels the objects change by more than 2%) and over
//! the whole frame, beside the truth's own noise there.

use crate::ReportSettings;
use crate::composite_truth::{Regions, Truth, true_composite};
use crate::error::{ReportError, Result};
use crate::gpu_composite::{CompositeForm, CompositeInputs, composite_frame};
use crate::maps::{default_exposure, load_map, scene_rotation};
use crate::method_lighting::method_lighting;
use crate::methods::{Method, Technique, per_map_methods};
use crate::observer::Observer;
use crate::per_map::{report_renderer, unique_map_names};
use foundation::Rgb;
use foundation::color::luminance;
use foundation::image_io::{RgbImageF32, write_exr, write_png};
use foundation::infra::atomic_file::write_atomic;
use foundation::scene::Scene;
use precompute::bake::Transfer;
use runtime::render::{GpuContext, Renderer, ShadowSettings};
use runtime::{DecomposeMode, DecomposeSettings, EnvironmentLighting};
use std::path::{Path, PathBuf};

/// Relative luminance RMS errors of a composite over the report's three regions:
/// `√mean((Y − Y_truth)²) / mean(Y_truth)` over each.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RegionErrors {
    pub object: f64,
    pub changed: f64,
    pub frame: f64,
}

/// The pixels of each region.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct RegionPixels {
    pub object: usize,
    pub changed: usize,
    pub frame: usize,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct CompositeMethodResult {
    pub method: String,
    /// Its images' file name, without the extension.
    pub file_stem: String,
    pub errors: RegionErrors,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct CompositeMapReport {
    pub name: String,
    pub path: String,
    pub exposure: f32,
    pub reference_spp: u32,
    pub pixels: RegionPixels,
    /// The truth's noise: its two halves' difference, halved (the noise of their mean).
    pub noise: RegionErrors,
    pub methods: Vec<CompositeMethodResult>,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct CompositeReport {
    pub scene: String,
    pub adapter: String,
    pub settings: ReportSettings,
    pub maps: Vec<CompositeMapReport>,
}

/// `√mean((Y(image) − Y(truth))²) / mean(Y(truth))` over the pixels `mask` keeps (0 when it
/// keeps none).
fn relative_rmse(image: &[Rgb], truth: &[Rgb], mask: impl Fn(usize) -> bool) -> f64 {
    let (mut squared, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for i in (0..truth.len()).filter(|&i| mask(i)) {
        let t = f64::from(luminance(truth[i]));
        squared += (f64::from(luminance(image[i])) - t).powi(2);
        sum += t;
        n += 1;
    }
    if n == 0 || sum <= 0.0 {
        return 0.0;
    }
    (squared / n as f64).sqrt() / (sum / n as f64)
}

fn region_errors(image: &[Rgb], truth: &[Rgb], regions: &Regions) -> RegionErrors {
    RegionErrors {
        object: relative_rmse(image, truth, |i| regions.object[i]),
        changed: relative_rmse(image, truth, |i| regions.changed[i]),
        frame: relative_rmse(image, truth, |_| true),
    }
}

/// The picture composited into, at the camera's size (`None`: the environment).
/// The methods composited, with their images' file stems: every report method in the
/// differential form, and the mobile-AR paper's occlusion peer lit by the hybrid.
fn methods() -> Vec<(&'static str, &'static str, Method, CompositeForm)> {
    let mut all: Vec<_> = per_map_methods()
        .into_iter()
        .map(|m| (m.name, m.file_stem, m, CompositeForm::Differential))
        .collect();
    let consistent = |m: &Method| {
        m.technique
            == Technique::Hybrid {
                mode: DecomposeMode::Consistent,
                tracked: false,
            }
    };
    if let Some(hybrid) = per_map_methods().into_iter().find(consistent) {
        all.push((
            "occlusion (mobile AR)",
            "occlusion",
            hybrid,
            CompositeForm::Occlusion,
        ));
    }
    all
}

/// What every map's section of a composite's report shares.
struct CompositeJob<'a> {
    scene: &'a Scene,
    gpu: &'a GpuContext,
    renderer: &'a mut Renderer,
    transfer: &'a Transfer,
    settings: &'a ReportSettings,
    observer: &'a dyn Observer,
}

/// One map's section, its images written into `dir`.
fn report_map(
    job: &mut CompositeJob,
    (env, name): (&Path, &str),
    dir: &Path,
) -> Result<CompositeMapReport> {
    let (scene, settings) = (job.scene, job.settings);
    crate::maps::create_folder(dir)?;
    let map = load_map(env, None)?.map;
    let rotation = scene_rotation(scene, None);
    let exposure = default_exposure(&map);
    let camera = scene.camera.with_size(settings.width, settings.height);
    job.observer.line(&format!(
        "{name}: the true composite ({}x{}, {} spp)",
        camera.width, camera.height, settings.spp
    ));
    // The last map's shadow maps are not needed while the truth renders on the CPU.
    job.renderer.release_shadow_maps();
    let truth = true_composite(scene, &camera, &map, rotation, settings)?;
    if truth.cached {
        job.observer
            .line(&format!("{name}: the true composite from the cache"));
    }
    write_exr(&dir.join("truth.exr"), &truth.image)?;
    write_png(&dir.join("truth.png"), &truth.image, exposure)?;
    write_masks(dir, &truth)?;
    let noise = truth_noise(&truth);
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default())?;
    lighting.set_rotation(rotation);
    let mut results = Vec::new();
    for (label, stem, method, form) in methods() {
        let threshold = DecomposeSettings::default().threshold;
        let order = job.renderer.order();
        let (frame, _, _) = method_lighting(&mut lighting, order, method, threshold)?;
        let inputs = CompositeInputs {
            scene,
            camera: &camera,
            map: &map,
            rotation_deg: rotation,
            shadow: ShadowSettings::default(),
            form,
        };
        let image = composite_frame(
            job.gpu,
            job.renderer,
            job.transfer,
            &frame,
            &inputs,
            job.observer,
        )?
        .image;
        write_exr(&dir.join(format!("{stem}.exr")), &image)?;
        write_png(&dir.join(format!("{stem}.png")), &image, exposure)?;
        results.push(CompositeMethodResult {
            method: label.to_owned(),
            file_stem: stem.to_owned(),
            errors: region_errors(&image.pixels, &truth.image.pixels, &truth.regions),
        });
    }
    Ok(CompositeMapReport {
        name: name.to_owned(),
        path: env.display().to_string(),
        exposure,
        reference_spp: 2 * (settings.spp / 2).max(1),
        pixels: RegionPixels {
            object: truth.regions.object.iter().filter(|b| **b).count(),
            changed: truth.regions.changed.iter().filter(|b| **b).count(),
            frame: truth.image.width * truth.image.height,
        },
        noise,
        methods: results,
    })
}

/// The truth's masks beside it: where the objects are, and where they change the backplate.
fn write_masks(dir: &Path, truth: &Truth) -> Result<()> {
    let (w, h) = (truth.image.width, truth.image.height);
    let mask = |m: &[bool]| {
        RgbImageF32::from_grey(
            w,
            h,
            &m.iter()
                .map(|b| f32::from(u8::from(*b)))
                .collect::<Vec<_>>(),
        )
    };
    write_exr(&dir.join("object_mask.exr"), &mask(&truth.regions.object))?;
    write_exr(&dir.join("changed_mask.exr"), &mask(&truth.regions.changed))?;
    Ok(())
}

/// The truth's own noise in each region, from its two independent halves (their error against
/// each other, halved).
fn truth_noise(truth: &Truth) -> RegionErrors {
    let noise = region_errors(
        &truth.halves[0].pixels,
        &truth.halves[1].pixels,
        &truth.regions,
    );
    RegionErrors {
        object: noise.object / 2.0,
        changed: noise.changed / 2.0,
        frame: noise.frame / 2.0,
    }
}

/// Writes the composite report of `scene` under each of `envs` into `out`.
pub fn run_composite_report(
    scene: &Scene,
    transfer: &Transfer,
    envs: &[PathBuf],
    settings: &ReportSettings,
    out: &Path,
    observer: &dyn Observer,
) -> Result<CompositeReport> {
    if settings.target_noise.is_some() {
        return Err(ReportError::TargetNoiseInComposite);
    }
    crate::maps::create_folder(out)?;
    let (gpu, _, mut renderer) = report_renderer(scene, transfer, settings, observer)?;
    let mut job = CompositeJob {
        scene,
        gpu: &gpu,
        renderer: &mut renderer,
        transfer,
        settings,
        observer,
    };
    let mut maps = Vec::new();
    for (env, name) in envs.iter().zip(unique_map_names(envs)) {
        let dir = out.join(&name);
        maps.push(report_map(&mut job, (env, &name), &dir)?);
    }
    let report = CompositeReport {
        scene: scene.path.display().to_string(),
        adapter: gpu.description().to_string(),
        settings: settings.clone(),
        maps,
    };
    write_atomic(
        &out.join("stats.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
    )?;
    write_atomic(&out.join("report.html"), html(&report).as_bytes())?;
    Ok(report)
}

/// Every map's table, a line each: each method's errors over the three regions, the truth's
/// noise first.
pub fn composite_summary_lines(report: &CompositeReport) -> Vec<String> {
    let mut lines = Vec::new();
    for map in &report.maps {
        lines.push(format!(
            "\n{} ({} spp; {} object, {} changed, {} pixels): relative luminance RMSE",
            map.name, map.reference_spp, map.pixels.object, map.pixels.changed, map.pixels.frame
        ));
        lines.push(format!(
            "{:<24} {:>8} {:>8} {:>8}",
            "method", "object", "changed", "frame"
        ));
        let row = |name: &str, e: &RegionErrors| {
            format!(
                "{name:<24} {:>8.4} {:>8.4} {:>8.4}",
                e.object, e.changed, e.frame
            )
        };
        lines.push(row("(truth's noise)", &map.noise));
        for m in &map.methods {
            lines.push(row(&m.method, &m.errors));
        }
    }
    lines
}

/// A page of tables and images.
fn html(report: &CompositeReport) -> String {
    let mut page = format!(
        "<!doctype html><meta charset=utf-8><title>hprt composite report</title>\
         <h1>Composite report: {}</h1><p>adapter: {}. Errors: relative luminance RMSE against \
         the path-traced composite, over the objects, over the changed region (proxy pixels \
         the objects change by more than 2% in the truth) and over the frame; the truth's \
         noise first.</p>",
        report.scene, report.adapter
    );
    for map in &report.maps {
        page += &format!(
            "<h2>{}</h2><p>{} ({} spp)</p><table border=1 cellpadding=4>\
             <tr><th>method</th><th>object</th><th>changed</th><th>frame</th></tr>",
            map.name, map.path, map.reference_spp
        );
        let row = |name: &str, e: &RegionErrors| {
            format!(
                "<tr><td>{name}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td></tr>",
                e.object, e.changed, e.frame
            )
        };
        page += &row("(truth's noise)", &map.noise);
        for m in &map.methods {
            page += &row(&m.method, &m.errors);
        }
        page += "</table><p>";
        let images = std::iter::once("truth".to_owned())
            .chain(map.methods.iter().map(|m| m.file_stem.clone()));
        for stem in images {
            page += &format!(
                "<figure style=\"display:inline-block\"><img src=\"{}/{stem}.png\">\
                 <figcaption>{stem}</figcaption></figure>",
                map.name
            );
        }
        page += "</p>";
    }
    page
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_rmse_is_the_rms_luminance_error_over_the_mean() {
        let truth = vec![Rgb::splat(2.0), Rgb::splat(2.0), Rgb::splat(100.0)];
        let image = vec![Rgb::splat(1.0), Rgb::splat(3.0), Rgb::ZERO];
        // Over the first two: errors ±1, mean 2.
        let e = relative_rmse(&image, &truth, |i| i < 2);
        assert!((e - 0.5).abs() < 1e-9, "{e}");
        assert_eq!(relative_rmse(&image, &truth, |_| false), 0.0);
        assert_eq!(relative_rmse(&truth, &truth, |_| true), 0.0);
    }
}
