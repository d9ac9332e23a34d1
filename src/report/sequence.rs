//! Reports on an environment sequence (`hprt report SCENE --env-sequence S`): for every frame
//! the path-traced reference (same seed in every frame), plain PRT, the hybrid with its lights
//! tracked from frame to frame and the hybrid decomposed afresh each frame; their error per
//! frame, their temporal error, popping frames and, for a moving sun, how well its light
//! follows the sun. Writes `report.html` (plots and an animated GIF of hybrid | prt |
//! reference), `sequence.json`, `sequence.csv`, the plots as SVG and the GIF.

use super::figures;
use super::stats::error_stats;
use super::{ReferenceRequest, ReportSettings, reference_images};
use crate::bake_cache;
use crate::cli::ReportOptions;
use crate::environment::{default_exposure, scene_rotation};
use crate::sequence::Sequence;
use base64::Engine;
use foundation::image_io::{RgbImageF32, to_display_rgb8, tonemap};
use foundation::infra::atomic_file::write_atomic;
use foundation::luminance;
use foundation::scene::Scene;
use runtime::render::{GpuContext, RenderMode, Renderer, ShadowSettings};
use runtime::{DecomposeSettings, EnvironmentLighting, TrackingSettings};
use std::fmt::Write;
use std::path::Path;

/// A frame pops when its temporal error is more than this multiple of its neighbours' (a
/// spike: a light or shadow appearing or vanishing at once, not the steady change of a moving
/// map)...
pub const POP_SPIKE: f64 = 2.0;
/// ... and above this (tone-mapped luminance), so that a near-static sequence's noise does not
/// count.
pub const POP_FLOOR: f64 = 0.002;

/// The methods of a sequence report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SequenceMethod {
    Prt,
    /// Lights tracked from frame to frame (hysteresis, fades).
    HybridTracked,
    /// Decomposed afresh every frame, as the thesis does.
    HybridUntracked,
}

impl SequenceMethod {
    const ALL: [SequenceMethod; 3] = [
        SequenceMethod::Prt,
        SequenceMethod::HybridTracked,
        SequenceMethod::HybridUntracked,
    ];

    fn name(self) -> &'static str {
        match self {
            SequenceMethod::Prt => "prt",
            SequenceMethod::HybridTracked => "hybrid/tracked",
            SequenceMethod::HybridUntracked => "hybrid/untracked",
        }
    }

    fn render_mode(self) -> RenderMode {
        match self {
            SequenceMethod::Prt => RenderMode::Prt,
            _ => RenderMode::Hybrid,
        }
    }
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct FrameResult {
    pub method: String,
    pub mean: f64,
    pub shadow_mean: f64,
    pub penumbra_mean: f64,
    /// Mean over covered pixels of `|(M(t) − M(t−1)) − (R(t) − R(t−1))|` (none in frame 0).
    pub temporal: Option<f64>,
    /// Whether the frame pops (see `POP_SPIKE`).
    pub popping: bool,
    pub lights: usize,
}

/// How the hybrid's light follows the true sun of a sun sequence.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SunAccuracy {
    /// Angle between the nearest light and the sun, degrees.
    pub angle_deg: f64,
    /// `|P_light − P_base − P_sun| / P_sun` in luminance: `P_base` is the base map's own excess
    /// in the light's cap (its local level there), `P_sun` the disc's power.
    pub power_error: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SequenceFrame {
    pub frame: usize,
    pub methods: Vec<FrameResult>,
    pub sun: Option<SunAccuracy>,
    pub reference_cached: bool,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct MethodSummary {
    pub method: String,
    pub mean_error: f64,
    pub mean_temporal_error: f64,
    pub popping_frames: usize,
    pub light_count_changes: usize,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SequenceReport {
    pub scene: String,
    pub sequence: String,
    pub frames: usize,
    pub settings: ReportSettings,
    pub pop_spike: f64,
    pub pop_floor: f64,
    pub methods: Vec<MethodSummary>,
    /// Worst over the frames, for a sun sequence.
    pub sun_worst: Option<SunAccuracy>,
    pub per_frame: Vec<SequenceFrame>,
}

/// Tone-mapped luminance of every pixel.
fn tonemapped_luminance(image: &RgbImageF32, exposure: f32) -> Vec<f32> {
    image
        .pixels
        .iter()
        .map(|p| luminance(tonemap(*p, exposure)))
        .collect()
}

/// Temporal error of a method's frame: the mean over covered pixels of how much its change
/// differs from the reference's.
fn temporal(
    now: &[f32],
    before: &[f32],
    reference_now: &[f32],
    reference_before: &[f32],
    covered: &[bool],
) -> f64 {
    let (mut sum, mut count) = (0.0f64, 0usize);
    for i in 0..now.len() {
        if covered[i] {
            let change = now[i] - before[i];
            let reference_change = reference_now[i] - reference_before[i];
            sum += (change - reference_change).abs() as f64;
            count += 1;
        }
    }
    sum / count.max(1) as f64
}

/// Frames on each side whose temporal errors a frame is compared with.
const POP_WINDOW: usize = 3;

/// Marks the popping frames of one method's temporal errors (frame 0 has none): a frame pops
/// when its temporal error is a spike against its neighbours' (the median of up to
/// `POP_WINDOW` frames on each side), so that a sequence whose motion speeds up or slows down
/// pops nowhere, while a light appearing at once does.
fn mark_popping(temporal: &[Option<f64>]) -> Vec<bool> {
    (0..temporal.len())
        .map(|t| {
            let Some(value) = temporal[t] else {
                return false;
            };
            let neighbours: Vec<f64> = (t.saturating_sub(POP_WINDOW)..=t + POP_WINDOW)
                .filter(|&u| u != t)
                .filter_map(|u| temporal.get(u).copied().flatten())
                .collect();
            if neighbours.is_empty() {
                return false;
            }
            let local = crate::support::median(neighbours);
            value > POP_SPIKE * local && value > POP_FLOOR
        })
        .collect()
}

/// Bakes (or reuses) the transfer and writes the sequence report into `out`.
pub fn write_sequence_report(
    scene: &Scene,
    sequence_path: &Path,
    options: &ReportOptions,
    out: &Path,
) -> anyhow::Result<()> {
    let sequence = Sequence::load(sequence_path)?;
    let (_, transfer) = bake_cache::bake_for(scene, options.bake.as_deref())?;
    let camera = options.size.camera(scene)?;
    let settings = ReportSettings {
        thresholds: Vec::new(),
        ..ReportSettings::new(options, &camera, &transfer)
    };
    crate::support::create_folder(out)?;
    let gpu = GpuContext::headless(options.backend)?;
    println!("adapter: {}", gpu.description());
    let mut renderer = Renderer::new(
        &gpu,
        &scene.geometry,
        &transfer,
        &camera,
        ShadowSettings::default(),
    )?;
    let rotation = scene_rotation(scene, None);
    let first = sequence.frame(0)?;
    let exposure = default_exposure(&first);
    let decompose =
        DecomposeSettings::for_mode(runtime::DecomposeMode::Consistent, transfer.settings.order);
    let mut lightings = Vec::new();
    for method in SequenceMethod::ALL {
        let mut lighting = EnvironmentLighting::new(&first, decompose.clone())?;
        if method == SequenceMethod::HybridTracked {
            lighting.enable_tracking(Some(TrackingSettings::default()))?;
        }
        lighting.set_rotation(rotation);
        lightings.push(lighting);
    }
    // The base map of a sun sequence, to measure its own level where the sun's light is.
    let mut base_lighting = match sequence.sun_base() {
        Some(base) => {
            let mut lighting = EnvironmentLighting::new(base, decompose.clone())?;
            lighting.set_rotation(rotation);
            Some(lighting)
        }
        None => None,
    };
    let request = ReferenceRequest {
        target_noise: None,
        ..settings.reference_request(exposure)
    };
    let mut frames = Vec::new();
    let mut previous: Option<(Vec<f32>, Vec<Vec<f32>>)> = None;
    let mut previous_lights = vec![None; SequenceMethod::ALL.len()];
    let mut light_changes = vec![0usize; SequenceMethod::ALL.len()];
    let mut gif_frames = Vec::new();
    for k in 0..sequence.len() {
        let map = if k == 0 {
            first.clone()
        } else {
            sequence.frame(k)?
        };
        let reference =
            reference_images(scene, &camera, &map, rotation, &request, &|_| f64::INFINITY)?;
        let masks = reference.masks();
        let reference_y = tonemapped_luminance(&reference.radiance, exposure);
        renderer.set_environment(&map, rotation);
        let mut results = Vec::new();
        let mut ys = Vec::new();
        let mut images = Vec::new();
        let mut sun = None;
        for (m, method) in SequenceMethod::ALL.iter().enumerate() {
            let lighting = &mut lightings[m];
            if k > 0 {
                lighting.set_map(map.clone());
            }
            let frame = lighting.frame(method.render_mode(), None);
            renderer.set_lighting(&frame.lighting)?;
            renderer.render()?;
            let image = renderer.read_back()?;
            let s = error_stats(&image, &reference.radiance, &masks, exposure);
            let y = tonemapped_luminance(&image, exposure);
            let temporal_error = previous.as_ref().map(|(reference_before, before)| {
                temporal(
                    &y,
                    &before[m],
                    &reference_y,
                    reference_before,
                    &masks.covered,
                )
            });
            let lights = frame.lighting.lights.len();
            if previous_lights[m].is_some_and(|p| p != lights) {
                light_changes[m] += 1;
            }
            previous_lights[m] = Some(lights);
            if *method == SequenceMethod::HybridTracked
                && let Some(disc) = sequence.sun(k)
            {
                let truth = glam::Quat::from_rotation_y(rotation.to_radians()) * disc.direction;
                let lights = &frame.lighting.lights;
                let nearest = (0..lights.len()).max_by(|a, b| {
                    let cos = |i: &usize| lights[*i].direction.dot(truth);
                    cos(a).total_cmp(&cos(b))
                });
                // The base map's own excess in the same caps: its local level there.
                let directions: Vec<glam::Vec3> = lights.iter().map(|l| l.direction).collect();
                let base_excess = base_lighting
                    .as_mut()
                    .map(|b| b.cap_excess(&directions))
                    .unwrap_or_default();
                sun = nearest.map(|i| {
                    let light = &lights[i];
                    let own = base_excess.get(i).map_or(0.0, |p| luminance(*p) as f64);
                    let want = luminance(disc.power()) as f64;
                    SunAccuracy {
                        angle_deg: light
                            .direction
                            .dot(truth)
                            .clamp(-1.0, 1.0)
                            .acos()
                            .to_degrees() as f64,
                        power_error: (luminance(light.power) as f64 - own - want).abs() / want,
                    }
                });
            }
            results.push(FrameResult {
                method: method.name().to_owned(),
                mean: s.mean,
                shadow_mean: s.shadow_mean,
                penumbra_mean: s.penumbra_mean,
                temporal: temporal_error,
                popping: false,
                lights,
            });
            ys.push(y);
            images.push(image);
        }
        // hybrid/tracked | prt | reference
        gif_frames.push(side_by_side(
            &[&images[1], &images[0], &reference.radiance],
            exposure,
        ));
        println!(
            "frame {k}/{}: {}",
            sequence.len() - 1,
            results
                .iter()
                .map(|r| format!(
                    "{} {:.4}{}",
                    r.method,
                    r.mean,
                    r.temporal
                        .map_or(String::new(), |t| format!(" (temporal {t:.4})"))
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
        frames.push(SequenceFrame {
            frame: k,
            methods: results,
            sun,
            reference_cached: reference.cached,
        });
        previous = Some((reference_y, ys));
    }
    let report = summarise(scene, sequence_path, &settings, frames, &light_changes);
    write_outputs(&report, &gif_frames, camera.width * 3, camera.height, out)?;
    print_summary(&report);
    println!("\nwrote {}", out.join("report.html").display());
    Ok(())
}

/// Tone-mapped images next to each other, as 8-bit RGB rows.
fn side_by_side(images: &[&RgbImageF32], exposure: f32) -> Vec<u8> {
    let parts: Vec<Vec<u8>> = images
        .iter()
        .map(|image| to_display_rgb8(image, exposure))
        .collect();
    let (w, h) = (images[0].width, images[0].height);
    let mut rgb = Vec::with_capacity(w * h * 3 * images.len());
    for row in 0..h {
        for part in &parts {
            rgb.extend_from_slice(&part[row * w * 3..(row + 1) * w * 3]);
        }
    }
    rgb
}

fn summarise(
    scene: &Scene,
    sequence: &Path,
    settings: &ReportSettings,
    mut per_frame: Vec<SequenceFrame>,
    light_changes: &[usize],
) -> SequenceReport {
    for m in 0..SequenceMethod::ALL.len() {
        let temporal: Vec<Option<f64>> = per_frame.iter().map(|f| f.methods[m].temporal).collect();
        for (frame, popping) in per_frame.iter_mut().zip(mark_popping(&temporal)) {
            frame.methods[m].popping = popping;
        }
    }
    let methods = SequenceMethod::ALL
        .iter()
        .enumerate()
        .map(|(m, method)| {
            let results: Vec<&FrameResult> = per_frame.iter().map(|f| &f.methods[m]).collect();
            let temporal: Vec<f64> = results.iter().filter_map(|r| r.temporal).collect();
            MethodSummary {
                method: method.name().to_owned(),
                mean_error: results.iter().map(|r| r.mean).sum::<f64>() / results.len() as f64,
                mean_temporal_error: if temporal.is_empty() {
                    0.0
                } else {
                    temporal.iter().sum::<f64>() / temporal.len() as f64
                },
                popping_frames: results.iter().filter(|r| r.popping).count(),
                light_count_changes: light_changes[m],
            }
        })
        .collect();
    let suns: Vec<SunAccuracy> = per_frame.iter().filter_map(|f| f.sun).collect();
    let sun_worst = (!suns.is_empty()).then(|| SunAccuracy {
        angle_deg: suns.iter().map(|s| s.angle_deg).fold(0.0, f64::max),
        power_error: suns.iter().map(|s| s.power_error).fold(0.0, f64::max),
    });
    SequenceReport {
        scene: scene.path.display().to_string(),
        sequence: sequence.display().to_string(),
        frames: per_frame.len(),
        settings: settings.clone(),
        pop_spike: POP_SPIKE,
        pop_floor: POP_FLOOR,
        methods,
        sun_worst,
        per_frame,
    }
}

fn write_outputs(
    report: &SequenceReport,
    gif_frames: &[Vec<u8>],
    gif_width: u32,
    gif_height: u32,
    out: &Path,
) -> anyhow::Result<()> {
    let series = |value: &dyn Fn(&FrameResult) -> Option<f64>| -> Vec<(String, Vec<f64>)> {
        SequenceMethod::ALL
            .iter()
            .enumerate()
            .map(|(m, method)| {
                let values = report
                    .per_frame
                    .iter()
                    .map(|f| value(&f.methods[m]).unwrap_or(f64::NAN))
                    .collect();
                (method.name().to_owned(), values)
            })
            .collect()
    };
    let error_svg = figures::time_plot(
        "error against the reference",
        "mean error (covered pixels)",
        &series(&|r| Some(r.mean)),
    )?;
    let temporal_svg = figures::time_plot(
        "temporal error (frame differences against the reference's)",
        "mean temporal error",
        &series(&|r| r.temporal),
    )?;
    let gif = figures::animated_gif(gif_frames, gif_width, gif_height, 120)?;
    write_atomic(&out.join("error.svg"), error_svg.as_bytes())?;
    write_atomic(&out.join("temporal.svg"), temporal_svg.as_bytes())?;
    write_atomic(&out.join("sequence.gif"), &gif)?;
    write_atomic(
        &out.join("sequence.json"),
        serde_json::to_string_pretty(report)?.as_bytes(),
    )?;
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record([
        "frame",
        "method",
        "mean",
        "shadow_mean",
        "penumbra_mean",
        "temporal",
        "popping",
        "lights",
    ])?;
    for frame in &report.per_frame {
        for r in &frame.methods {
            let optional = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
            csv.write_record([
                frame.frame.to_string(),
                r.method.clone(),
                format!("{:.6}", r.mean),
                format!("{:.6}", r.shadow_mean),
                format!("{:.6}", r.penumbra_mean),
                optional(r.temporal),
                r.popping.to_string(),
                r.lights.to_string(),
            ])?;
        }
    }
    write_atomic(
        &out.join("sequence.csv"),
        &csv.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?,
    )?;
    let html = page(report, &gif, &error_svg, &temporal_svg)?;
    write_atomic(&out.join("report.html"), html.as_bytes())?;
    Ok(())
}

fn page(
    report: &SequenceReport,
    gif: &[u8],
    error_svg: &str,
    temporal_svg: &str,
) -> anyhow::Result<String> {
    let mut html = String::new();
    writeln!(
        html,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>hprt sequence report</title>\
         <style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:3px 8px;\
         text-align:right}}</style></head><body>"
    )?;
    writeln!(
        html,
        "<h1>Sequence report</h1><p>Scene <code>{}</code>, sequence <code>{}</code>, {} frames, \
         {}×{}, reference {} paths per pixel (seed {} in every frame).</p>",
        report.scene,
        report.sequence,
        report.frames,
        report.settings.width,
        report.settings.height,
        report.settings.spp,
        report.settings.seed
    )?;
    writeln!(
        html,
        "<table><tr><th>method</th><th>mean error</th><th>mean temporal error</th>\
         <th>popping frames</th><th>light-count changes</th></tr>"
    )?;
    for m in &report.methods {
        writeln!(
            html,
            "<tr><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td><td>{}</td></tr>",
            m.method, m.mean_error, m.mean_temporal_error, m.popping_frames, m.light_count_changes
        )?;
    }
    writeln!(html, "</table>")?;
    writeln!(
        html,
        "<p>Temporal error: the mean over covered pixels of |(M(t) − M(t−1)) − (R(t) − \
         R(t−1))| of tone-mapped luminance. A popping frame: its temporal error is more than {} \
         times the median of its neighbours' (3 frames on each side) and above {} (CONVENTIONS.md, \
         \"Temporal statistics\").</p>",
        report.pop_spike, report.pop_floor
    )?;
    if let Some(sun) = report.sun_worst {
        writeln!(
            html,
            "<p>The tracked hybrid's light against the true sun, worst frame: {:.3}° apart, \
             power off by {:.2}%.</p>",
            sun.angle_deg,
            100.0 * sun.power_error
        )?;
    }
    writeln!(
        html,
        "<h2>hybrid/tracked | prt | reference</h2><img src=\"data:image/gif;base64,{}\">",
        base64::engine::general_purpose::STANDARD.encode(gif)
    )?;
    writeln!(html, "<h2>Over time</h2>{error_svg}{temporal_svg}")?;
    writeln!(
        html,
        "<p>Per frame: <code>sequence.csv</code>, <code>sequence.json</code>.</p></body></html>"
    )?;
    Ok(html)
}

fn print_summary(report: &SequenceReport) {
    println!();
    println!(
        "{:<18} {:>10} {:>14} {:>9} {:>14}",
        "method", "mean", "temporal", "popping", "count changes"
    );
    for m in &report.methods {
        println!(
            "{:<18} {:>10.4} {:>14.4} {:>9} {:>14}",
            m.method, m.mean_error, m.mean_temporal_error, m.popping_frames, m.light_count_changes
        );
    }
    if let Some(sun) = report.sun_worst {
        println!(
            "sun: the tracked light is at most {:.3}° from the sun, its power at most {:.2}% off",
            sun.angle_deg,
            100.0 * sun.power_error
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporal_error_measures_changes_beyond_the_reference() {
        let covered = [true, true, false];
        // The reference brightens pixel 0 by 0.1, the method by 0.3; pixel 1 is unchanged; the
        // uncovered pixel 2 does not count.
        let t = temporal(
            &[0.6, 0.2, 9.0],
            &[0.3, 0.2, 0.0],
            &[0.5, 0.2, 0.0],
            &[0.4, 0.2, 0.0],
            &covered,
        );
        assert!((t - 0.1).abs() < 1e-6, "{t}");
    }

    #[test]
    fn popping_frames_are_spikes_of_the_temporal_error() {
        let steady = [None, Some(0.01), Some(0.012), Some(0.011), Some(0.009)];
        assert!(mark_popping(&steady).iter().all(|p| !p));
        let pop = [None, Some(0.01), Some(0.05), Some(0.011), Some(0.009)];
        assert_eq!(mark_popping(&pop), [false, false, true, false, false]);
        // A motion that speeds up and slows down again does not pop.
        let ramp: Vec<Option<f64>> = std::iter::once(None)
            .chain((1..30).map(|t| Some(0.004 + 0.006 * (t as f64 / 5.0).sin().abs())))
            .collect();
        assert!(mark_popping(&ramp).iter().all(|p| !p));
        // Tiny errors never pop.
        let still = [None, Some(1e-5), Some(1e-3), Some(1e-5)];
        assert!(mark_popping(&still).iter().all(|p| !p));
    }
}
