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
use crate::methods::{Method, TRACKED, Technique, sequence_methods};
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
use results::{FrameResult, SequenceFrame, SunAccuracy, summarise};
use runtime::DirectionalLight;
use runtime::render::Renderer;
use runtime::{DecomposeSettings, EnvironmentLighting};
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
    let methods = sequence_methods();
    let order = transfer.settings.order;
    let mut run = SequenceRun {
        renderer,
        methods: (methods.iter())
            .map(|method| MethodRun::new(*method, &first, order, rotation))
            .collect::<Result<_>>()?,
        base_lighting: base_lighting(sequence, order, rotation)?,
        rotation,
        exposure,
        previous_reference: None,
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
        let FrameMeasures {
            results,
            images,
            sun,
        } = run.frame(k, &map, &reference, sequence.sun(k))?;
        // hybrid/tracked | prt | reference
        let image = |technique| {
            (images.iter())
                .find(|(m, _)| m.technique == technique)
                .map_or(&reference.radiance, |(_, image)| image)
        };
        gif_frames.push(side_by_side(
            &[image(TRACKED), image(Technique::Prt), &reference.radiance],
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
    let light_changes: Vec<(Method, usize)> = (run.methods.iter())
        .map(|m| (m.method, m.light_changes))
        .collect();
    let counts = (methods.as_slice(), light_changes.as_slice());
    let report = summarise(scene, sequence_path, settings, counts, frames);
    write_outputs(&report, &gif_frames, camera.width * 3, camera.height, out)?;
    Ok(report)
}

/// The methods' state from frame to frame of a sequence report.
struct SequenceRun {
    renderer: Renderer,
    methods: Vec<MethodRun>,
    /// A sun sequence's base map, to measure its own level where the sun's light is.
    base_lighting: Option<EnvironmentLighting>,
    rotation: f32,
    exposure: f32,
    /// The last frame's tone-mapped luminance of the reference.
    previous_reference: Option<Vec<f32>>,
}

/// One method's state from frame to frame.
struct MethodRun {
    method: Method,
    lighting: EnvironmentLighting,
    /// The last frame's tone-mapped luminance.
    previous: Option<Vec<f32>>,
    previous_lights: Option<usize>,
    light_changes: usize,
}

impl MethodRun {
    fn new(method: Method, first: &EnvMap, order: usize, rotation: f32) -> Result<Self> {
        Ok(Self {
            method,
            lighting: method.technique.start(first, order, rotation)?,
            previous: None,
            previous_lights: None,
            light_changes: 0,
        })
    }
}

/// A frame's measures of every method: results and images by method, and how the tracked
/// hybrid follows a sun.
struct FrameMeasures {
    results: Vec<FrameResult>,
    images: Vec<(Method, RgbImageF32)>,
    sun: Option<SunAccuracy>,
}

/// A frame's measures of one method.
struct Measured {
    result: FrameResult,
    image: RgbImageF32,
    lights: Vec<DirectionalLight>,
}

impl SequenceRun {
    /// Renders frame `k` (`map`) with every method and measures it against `reference`: each
    /// method's result and image, and how the tracked hybrid follows `sun`, if any.
    fn frame(
        &mut self,
        k: usize,
        map: &EnvMap,
        reference: &ReferenceImages,
        sun: Option<SunDisc>,
    ) -> Result<FrameMeasures> {
        let reference_y = tonemapped_luminance(&reference.radiance, self.exposure);
        self.renderer.set_environment(map, self.rotation);
        let (mut results, mut images, mut accuracy) = (Vec::new(), Vec::new(), None);
        for m in 0..self.methods.len() {
            let measured = self.measure(k, m, map, reference, &reference_y)?;
            let method = self.methods[m].method;
            if method.technique == TRACKED
                && let Some(disc) = &sun
            {
                let base = self.base_lighting.as_mut();
                accuracy = sun_accuracy(&measured.lights, disc, self.rotation, base);
            }
            results.push(measured.result);
            images.push((method, measured.image));
        }
        self.previous_reference = Some(reference_y);
        Ok(FrameMeasures {
            results,
            images,
            sun: accuracy,
        })
    }

    /// Renders frame `k` (`map`) with method `m` and measures it against `reference`
    /// (`reference_y` its tone-mapped luminance).
    fn measure(
        &mut self,
        k: usize,
        m: usize,
        map: &EnvMap,
        reference: &ReferenceImages,
        reference_y: &[f32],
    ) -> Result<Measured> {
        let (exposure, masks) = (self.exposure, reference.masks());
        let run = &mut self.methods[m];
        if k > 0 {
            run.lighting.set_map(map.clone());
        }
        let (lighting, lights, _) = run.method.technique.frame(&mut run.lighting);
        self.renderer.set_lighting(&lighting)?;
        self.renderer.render()?;
        let image = self.renderer.read_back()?;
        // Statistics over NaN pixels would read as numbers: refuse the frame instead.
        check_finite(&image, "frame").map_err(|error| ReportError::Frame {
            frame: k,
            method: run.method.name,
            error,
        })?;
        let s = error_stats(&image, &reference.radiance, &masks, exposure);
        let y = tonemapped_luminance(&image, exposure);
        let temporal_error = (run.previous.as_ref().zip(self.previous_reference.as_ref())).map(
            |(before, reference_before)| {
                temporal(&y, before, reference_y, reference_before, &masks.covered)
            },
        );
        if run.previous_lights.is_some_and(|p| p != lights) {
            run.light_changes += 1;
        }
        run.previous_lights = Some(lights);
        run.previous = Some(y);
        let result = FrameResult {
            method: run.method.name.to_owned(),
            mean: s.mean,
            shadow_mean: s.shadow_mean,
            penumbra_mean: s.penumbra_mean,
            temporal: temporal_error,
            popping: false,
            lights,
        };
        Ok(Measured {
            result,
            image,
            lights: lighting.lights,
        })
    }
}

/// The lighting of a sun sequence's base map, which measures the map's own level where the
/// sun's light is.
fn base_lighting(
    sequence: &Sequence,
    order: usize,
    rotation: f32,
) -> Result<Option<EnvironmentLighting>> {
    let decompose = DecomposeSettings::for_mode(runtime::DecomposeMode::Consistent, order);
    let Some(base) = sequence.sun_base() else {
        return Ok(None);
    };
    let mut lighting = EnvironmentLighting::new(base, decompose)?;
    lighting.set_rotation(rotation);
    Ok(Some(lighting))
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
