//! Reports on an environment sequence (`hprt report SCENE --env-sequence S`): for every frame
//! the path-traced reference (same seed in every frame), plain PRT, the hybrid with its lights
//! tracked from frame to frame and the hybrid decomposed afresh each frame; their error per
//! frame, their temporal error, popping frames and, for a moving sun, how well its light
//! follows the sun. Writes `report.html` (plots and an animated GIF of hybrid | prt |
//! reference), `sequence.json`, `sequence.csv`, the plots as SVG and the GIF.

pub(crate) mod output;
mod results;
pub(crate) mod temporal;

pub use output::summary_lines;
pub use results::SequenceReport;

use crate::env_sequence::Sequence;
use crate::error::{ReportError, Result};
use crate::maps::{default_exposure, scene_rotation};
use crate::observer::Observer;
use crate::per_map::report_renderer;
use crate::stats::error_stats;
use crate::{ReferenceImages, ReferenceRequest, ReportSettings, reference_images};
use foundation::envmap::EnvMap;
use foundation::envmap::animated::SunDisc;
use foundation::image_io::{RgbImageF32, check_finite};
use foundation::luminance;
use foundation::scene::Scene;
use output::{side_by_side, write_outputs};
use precompute::bake::Transfer;
use results::{FrameResult, SequenceFrame, SequenceMethod, SunAccuracy, summarise};
use runtime::DirectionalLight;
use runtime::render::Renderer;
use runtime::{DecomposeSettings, EnvironmentLighting, TrackingSettings};
use std::path::Path;
use temporal::{temporal, tonemapped_luminance};

/// Writes the report on `sequence` (read from `sequence_path`) into `out`.
pub fn write_sequence_report(
    scene: &Scene,
    (sequence_path, sequence): (&Path, &Sequence),
    transfer: &Transfer,
    settings: &ReportSettings,
    out: &Path,
    observer: &dyn Observer,
) -> Result<SequenceReport> {
    crate::maps::create_folder(out)?;
    let (_gpu, camera, renderer) = report_renderer(scene, transfer, settings, observer)?;
    let rotation = scene_rotation(scene, None);
    let first = sequence.frame(0)?;
    let exposure = default_exposure(&first);
    let (lightings, base_lighting) =
        method_lightings(sequence, &first, transfer.settings.order, rotation)?;
    let mut run = SequenceRun {
        renderer,
        lightings,
        base_lighting,
        rotation,
        exposure,
        previous: None,
        previous_lights: vec![None; SequenceMethod::ALL.len()],
        light_changes: vec![0; SequenceMethod::ALL.len()],
    };
    let request = ReferenceRequest {
        target_noise: None,
        ..settings.reference_request(exposure)
    };
    let mut frames = Vec::new();
    let mut gif_frames = Vec::new();
    for k in 0..sequence.len() {
        let map = if k == 0 {
            first.clone()
        } else {
            sequence.frame(k)?
        };
        let no_limit = |_: &ReferenceImages| f64::INFINITY;
        let reference = reference_images(
            scene, &camera, &map, rotation, &request, &no_limit, observer,
        )?;
        let (results, images, sun) = run.frame(k, &map, &reference, sequence.sun(k))?;
        // hybrid/tracked | prt | reference
        gif_frames.push(side_by_side(
            &[&images[1], &images[0], &reference.radiance],
            exposure,
        ));
        observer.line(&format!(
            "frame {k}/{}: {}",
            sequence.len() - 1,
            frame_line(&results)
        ));
        frames.push(SequenceFrame {
            frame: k,
            methods: results,
            sun,
            reference_cached: reference.cached,
        });
    }
    let report = summarise(scene, sequence_path, settings, frames, &run.light_changes);
    write_outputs(&report, &gif_frames, camera.width * 3, camera.height, out)?;
    Ok(report)
}

/// The methods' state from frame to frame of a sequence report.
struct SequenceRun {
    renderer: Renderer,
    /// Per method, its lighting.
    lightings: Vec<EnvironmentLighting>,
    /// A sun sequence's base map, to measure its own level where the sun's light is.
    base_lighting: Option<EnvironmentLighting>,
    rotation: f32,
    exposure: f32,
    /// The last frame's tone-mapped luminance: the reference's and each method's.
    previous: Option<(Vec<f32>, Vec<Vec<f32>>)>,
    previous_lights: Vec<Option<usize>>,
    light_changes: Vec<usize>,
}

impl SequenceRun {
    /// Renders frame `k` (`map`) with every method and measures it against `reference`: each
    /// method's result, its image, and how the tracked hybrid follows `sun`, if any.
    fn frame(
        &mut self,
        k: usize,
        map: &EnvMap,
        reference: &ReferenceImages,
        sun: Option<SunDisc>,
    ) -> Result<(Vec<FrameResult>, Vec<RgbImageF32>, Option<SunAccuracy>)> {
        let exposure = self.exposure;
        let masks = reference.masks();
        let reference_y = tonemapped_luminance(&reference.radiance, exposure);
        self.renderer.set_environment(map, self.rotation);
        let mut results = Vec::new();
        let mut ys = Vec::new();
        let mut images = Vec::new();
        let mut accuracy = None;
        for (m, method) in SequenceMethod::ALL.iter().enumerate() {
            let lighting = &mut self.lightings[m];
            if k > 0 {
                lighting.set_map(map.clone());
            }
            let frame = lighting.frame(method.render_mode(), None);
            self.renderer.set_lighting(&frame.lighting)?;
            self.renderer.render()?;
            let image = self.renderer.read_back()?;
            // Statistics over NaN pixels would read as numbers: refuse the frame instead.
            check_finite(&image, "frame").map_err(|error| ReportError::Frame {
                frame: k,
                method: method.name(),
                error,
            })?;
            let s = error_stats(&image, &reference.radiance, &masks, exposure);
            let y = tonemapped_luminance(&image, exposure);
            let temporal_error = self.previous.as_ref().map(|(reference_before, before)| {
                temporal(
                    &y,
                    &before[m],
                    &reference_y,
                    reference_before,
                    &masks.covered,
                )
            });
            let lights = frame.lighting.lights.len();
            if self.previous_lights[m].is_some_and(|p| p != lights) {
                self.light_changes[m] += 1;
            }
            self.previous_lights[m] = Some(lights);
            if *method == SequenceMethod::HybridTracked
                && let Some(disc) = &sun
            {
                accuracy = sun_accuracy(
                    &frame.lighting.lights,
                    disc,
                    self.rotation,
                    self.base_lighting.as_mut(),
                );
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
        self.previous = Some((reference_y, ys));
        Ok((results, images, accuracy))
    }
}

/// The lighting of each method (tracking for the tracked hybrid), and of the base map of a sun
/// sequence, which measures the map's own level where the sun's light is.
fn method_lightings(
    sequence: &Sequence,
    first: &EnvMap,
    order: usize,
    rotation: f32,
) -> Result<(Vec<EnvironmentLighting>, Option<EnvironmentLighting>)> {
    let decompose = DecomposeSettings::for_mode(runtime::DecomposeMode::Consistent, order);
    let mut lightings = Vec::new();
    for method in SequenceMethod::ALL {
        let mut lighting = EnvironmentLighting::new(first, decompose.clone())?;
        if method == SequenceMethod::HybridTracked {
            lighting.enable_tracking(Some(TrackingSettings::default()))?;
        }
        lighting.set_rotation(rotation);
        lightings.push(lighting);
    }
    let base = match sequence.sun_base() {
        Some(base) => {
            let mut lighting = EnvironmentLighting::new(base, decompose)?;
            lighting.set_rotation(rotation);
            Some(lighting)
        }
        None => None,
    };
    Ok((lightings, base))
}

/// How the light nearest the true sun `disc` follows it: its angle, and its power beyond the
/// base map's own excess in the same cap (its local level there) against the disc's.
fn sun_accuracy(
    lights: &[DirectionalLight],
    disc: &SunDisc,
    rotation: f32,
    base_lighting: Option<&mut EnvironmentLighting>,
) -> Option<SunAccuracy> {
    let truth = glam::Quat::from_rotation_y(rotation.to_radians()) * disc.direction;
    let nearest = (0..lights.len()).max_by(|a, b| {
        let cos = |i: &usize| lights[*i].direction.dot(truth);
        cos(a).total_cmp(&cos(b))
    })?;
    let directions: Vec<glam::Vec3> = lights.iter().map(|l| l.direction).collect();
    let base_excess = base_lighting
        .map(|b| b.cap_excess(&directions))
        .unwrap_or_default();
    let light = &lights[nearest];
    let own = base_excess
        .get(nearest)
        .map_or(0.0, |p| luminance(*p) as f64);
    let want = luminance(disc.power()) as f64;
    Some(SunAccuracy {
        angle_deg: light
            .direction
            .dot(truth)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees() as f64,
        power_error: (luminance(light.power) as f64 - own - want).abs() / want,
    })
}

/// One frame's errors, for the terminal.
fn frame_line(results: &[FrameResult]) -> String {
    results
        .iter()
        .map(|r| {
            format!(
                "{} {:.4}{}",
                r.method,
                r.mean,
                r.temporal
                    .map_or(String::new(), |t| format!(" (temporal {t:.4})"))
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}
