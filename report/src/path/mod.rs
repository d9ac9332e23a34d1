//! Reports on a model carried along a room's `[path]` (`hprt report SCENE --path`): at each
//! position, the room path-traced with the model there (the truth), and the hybrid lit by
//! one probe, the nearest probe, the local map fused from every probe, the true probe at the
//! model's centre, and median cut on the fused map; each composited into the empty room's
//! truth the same way (the model drawn, the room changed by its shadows: `crate::room`).
//! Errors over the model and over the region it changes, per position and along the path;
//! temporal error, popping positions, an animated GIF, and where the model passes through a
//! proxy.

mod output;
mod results;

pub use output::summary_lines;
pub use results::PathReport;

use crate::error::{ReportError, Result};
use crate::gpu_composite::PrimaryHits;
use crate::maps::default_exposure;
use crate::methods::{PathMap, PathMethod, TRACKED, path_methods};
use crate::observer::Observer;
use crate::room::{PosedModel, RoomModel};
use crate::sequence::output::side_by_side;
use crate::sequence::temporal::{temporal, tonemapped_luminance};
use crate::stats::error_image;
use crate::{ReferenceImages, ReferenceRequest, ReportSettings, reference_images};
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::{RgbImageF32, check_finite};
use foundation::probe::Probe;
use foundation::scene::{ObjectRole, Pose, Scene, SceneMesh, mesh_crosses};
use glam::Vec3;
use reference::composite::{PixelKind, composite, pixel_kinds};
use results::{PathPosition, PositionResult, summarise};
use runtime::render::{FrameLighting, GpuContext, Renderer, ShadowCasters, ShadowSettings};
use runtime::{DecomposeMode, DecomposeSettings, EnvironmentLighting};
use std::path::Path;

/// What a path report measures besides the report's own settings.
pub struct PathOptions {
    /// Positions of the path reported (evenly spaced, first and last included); all its
    /// frames when it has fewer.
    pub positions: usize,
    /// Paths per texel of the true probes.
    pub probe_spp: u32,
}

/// Writes the report on `scene`'s `[path]` into `out`: `map` is the scene's sky, turned by
/// `rotation_deg`.
pub fn write_path_report(
    scene: &Scene,
    (map, rotation_deg): (&EnvMap, f32),
    camera: Camera,
    settings: &ReportSettings,
    options: &PathOptions,
    out: &Path,
    observer: &dyn Observer,
) -> Result<PathReport> {
    let sky = map.rotated(rotation_deg);
    let decompose = DecomposeSettings::for_mode(DecomposeMode::Consistent, scene.bake.order);
    let model = RoomModel::open(scene, sky, decompose.clone(), observer)?;
    let Some(path) = model.path.clone() else {
        return Err(ReportError::NoPath(scene.path.clone()));
    };
    let gpu = GpuContext::headless(settings.backend)?;
    observer.line(&format!("adapter: {}", gpu.description()));
    let sky = (map, rotation_deg);
    let setup = (&gpu, settings, observer);
    let mut run = PathRun::new(scene, (model, decompose), sky, &camera, setup)?;
    let poses = path.poses();
    let frames = pick_frames(poses.len(), options.positions);
    let (mut per_position, mut gif) = (Vec::new(), Vec::new());
    for (n, &frame) in frames.iter().enumerate() {
        let (position, images) = run.position(frame, poses[frame], options.probe_spp, observer)?;
        observer.line(&format!(
            "position {n}/{} (frame {frame}): {}",
            frames.len() - 1,
            position_line(&position)
        ));
        if position.intersects_room {
            log::warn!(
                "{}: at frame {frame} the model ({}) passes through the room's proxies",
                scene.path.display(),
                poses[frame].centre
            );
        }
        gif.push(side_by_side(
            &images.iter().collect::<Vec<_>>(),
            run.exposure,
        ));
        per_position.push(position);
    }
    let report = summarise(
        scene.path.display().to_string(),
        settings,
        (&path_methods(), options.probe_spp),
        per_position,
    );
    let gif_size = (camera.width * 4, camera.height);
    output::write_outputs(&report, &gif, gif_size, out)?;
    Ok(report)
}

/// `count` frames of `frames`, evenly spaced with the first and the last (all of them when
/// there are fewer).
fn pick_frames(frames: usize, count: usize) -> Vec<usize> {
    if count >= frames || frames < 2 {
        return (0..frames).collect();
    }
    let count = count.max(2);
    (0..count)
        .map(|k| (k * (frames - 1) + (count - 1) / 2) / (count - 1))
        .collect()
}

/// The renderers, the truth's fixed parts and each method's lighting, from position to
/// position.
struct PathRun {
    scene: Scene,
    model: RoomModel,
    room_geometry: SceneMesh,
    camera: Camera,
    /// The model and the room, with separate bakes (`crate::room`); the room alone.
    whole: Renderer,
    room: Renderer,
    map: EnvMap,
    rotation_deg: f32,
    /// The empty room's truth: what is composited into, and the truth without the model.
    empty: ReferenceImages,
    request: ReferenceRequest,
    exposure: f32,
    lightings: MethodLightings,
    previous: Option<Previous>,
}

/// The last position's tone-mapped luminance, the truth's and each method's, and the pixels
/// the model covered or changed there.
struct Previous {
    truth: Vec<f32>,
    methods: Vec<(PathMethod, Vec<f32>)>,
    covered: Vec<bool>,
}

impl PathRun {
    /// `model` and the decomposition its methods' maps get.
    fn new(
        scene: &Scene,
        (model, decompose): (RoomModel, DecomposeSettings),
        (map, rotation_deg): (&EnvMap, f32),
        camera: &Camera,
        (gpu, settings, observer): (&GpuContext, &ReportSettings, &dyn Observer),
    ) -> Result<Self> {
        let shadow = ShadowSettings::default();
        let room_geometry = scene.geometry.of_role(ObjectRole::Proxy);
        let mut whole = Renderer::new(gpu, &model.geometry, &model.transfer, camera, shadow)?;
        let mut room = Renderer::new(gpu, &room_geometry, &model.room_transfer, camera, shadow)?;
        whole.set_environment(map, rotation_deg);
        room.set_environment(map, rotation_deg);
        // The room's own shadowing is in the local map already: only the model casts shadows.
        whole.set_shadow_casters(ShadowCasters::Objects);
        room.set_shadow_casters(ShadowCasters::Objects);
        let probes = model.lighting.probes();
        let room_centre = (room_geometry.mesh.bounds()).map_or(Vec3::ZERO, |(a, b)| 0.5 * (a + b));
        // The probe nearest the room's centre: method (a)'s.
        let one_probe = nearest(probes, room_centre);
        let lightings = MethodLightings::new(probes, one_probe, decompose.order)?;
        // The room's own light sets the exposure, as the map's does for a model in the open.
        let exposure = default_exposure(&probes[one_probe].radiance);
        let request = ReferenceRequest {
            target_noise: None,
            ..settings.reference_request(exposure)
        };
        let room_scene = scene
            .with_geometry(room_geometry.clone())
            .without_backplate();
        let no_limit = |_: &ReferenceImages| f64::INFINITY;
        let empty = reference_images(
            &room_scene,
            camera,
            map,
            rotation_deg,
            &request,
            &no_limit,
            observer,
        )
        .map_err(|e| ReportError::EmptyRoomTruth(Box::new(e)))?;
        Ok(Self {
            scene: scene.clone(),
            model,
            room_geometry,
            camera: *camera,
            whole,
            room,
            map: map.clone(),
            rotation_deg,
            empty,
            request,
            exposure,
            lightings,
            previous: None,
        })
    }

    /// Measures every method with the model at `pose` (the path's `frame`); returns the
    /// results and the images of the GIF.
    fn position(
        &mut self,
        frame: usize,
        pose: Pose,
        probe_spp: u32,
        observer: &dyn Observer,
    ) -> Result<(PathPosition, [RgbImageF32; 4])> {
        let centre = pose.centre;
        let posed = self.model.posed(pose)?;
        let geometry = &posed.geometry;
        self.whole.release_shadow_maps(); // not needed while the truth renders on the CPU
        let truth = self.truth_at(geometry, observer)?;
        let kinds = pixel_kinds(
            geometry,
            &PrimaryHits::trace(&self.scene_with(geometry), &self.camera).triangles,
        );
        let empty = &self.empty.radiance;
        let changed = composite(&kinds, &truth.radiance, empty, empty).changed;
        let on_model: Vec<bool> = kinds.iter().map(|k| *k == PixelKind::Object).collect();
        let true_probe = self.true_probe(centre, probe_spp);
        let lightings = (self.lightings).at(&mut self.model, centre, &true_probe)?;
        let mut covered: Vec<bool> = (on_model.iter().zip(&changed))
            .map(|(a, b)| *a || *b)
            .collect();
        if let Some(before) = &self.previous {
            (covered.iter_mut().zip(&before.covered)).for_each(|(c, b)| *c |= *b);
        }
        let truth_y = tonemapped_luminance(&truth.radiance, self.exposure);
        let (mut results, mut ys, mut images) = (Vec::new(), Vec::new(), Vec::new());
        for (method, lighting) in &lightings {
            let name = method.method.name;
            let image = self.composite_with(&kinds, &posed, lighting)?;
            check_finite(&image, "frame").map_err(|error| ReportError::Frame {
                frame,
                method: name,
                error,
            })?;
            let errors = error_image(&image, &truth.radiance, self.exposure);
            let y = tonemapped_luminance(&image, self.exposure);
            let temporal = (self.previous.as_ref()).and_then(|before| {
                let (_, y_before) = before.methods.iter().find(|(m, _)| m == method)?;
                Some(temporal(&y, y_before, &truth_y, &before.truth, &covered))
            });
            results.push(PositionResult {
                method: name.to_owned(),
                model: masked_mean(&errors, &on_model),
                changed: masked_mean(&errors, &changed),
                temporal,
                popping: false,
                lights: lighting.lights.len(),
            });
            ys.push((*method, y));
            images.push((*method, image));
        }
        let model_mesh = geometry.of_role(ObjectRole::Object).mesh;
        let position = PathPosition {
            frame,
            centre: centre.to_array(),
            intersects_room: mesh_crosses(&model_mesh, self.model.lighting.proxies()),
            model_pixels: on_model.iter().filter(|c| **c).count(),
            changed_pixels: changed.iter().filter(|c| **c).count(),
            methods: results,
        };
        let covered = (on_model.iter().zip(&changed)).map(|(a, b)| *a || *b);
        self.previous = Some(Previous {
            truth: truth_y,
            methods: ys,
            covered: covered.collect(),
        });
        // The GIF: the tracked hybrid on one probe, on the nearest probe, on the fused map.
        let hybrid_on = |map: PathMap| {
            (images.iter())
                .find(|(m, _)| m.map == map && m.method.technique == TRACKED)
                .map_or_else(|| truth.radiance.clone(), |(_, image)| image.clone())
        };
        let gif = [PathMap::OneProbe, PathMap::NearestProbe, PathMap::Fused].map(hybrid_on);
        let [one, nearest, fused] = gif;
        Ok((position, [one, nearest, fused, truth.radiance.clone()]))
    }

    fn scene_with(&self, geometry: &SceneMesh) -> Scene {
        self.scene
            .with_geometry(geometry.clone())
            .without_backplate()
    }

    /// The room path-traced with the model placed as in `geometry`.
    fn truth_at(&self, geometry: &SceneMesh, observer: &dyn Observer) -> Result<ReferenceImages> {
        let scene = self.scene_with(geometry);
        let no_limit = |_: &ReferenceImages| f64::INFINITY;
        let (map, rotation) = (&self.map, self.rotation_deg);
        reference_images(
            &scene,
            &self.camera,
            map,
            rotation,
            &self.request,
            &no_limit,
            observer,
        )
    }

    /// The probe path-traced at `centre` in the empty room, at the scene's probes' size.
    fn true_probe(&self, centre: Vec3, spp: u32) -> Probe {
        let probes = self.model.lighting.probes();
        let size = (probes[0].radiance.width(), probes[0].radiance.height());
        let light = reference::EnvironmentLight::new(&self.map, self.rotation_deg);
        let settings = reference::ReferenceSettings::new(spp, self.request.bounces, 0);
        let proxies = self.model.lighting.proxies();
        let no_progress = &foundation::infra::progress::NoProgress;
        let room = &self.room_geometry;
        reference::render_probe(room, proxies, &light, centre, size, &settings, no_progress).0
    }

    /// The model at `posed` and the room drawn with `lighting`, the room alone too,
    /// composited into the empty room's truth.
    fn composite_with(
        &mut self,
        kinds: &[PixelKind],
        posed: &PosedModel,
        lighting: &FrameLighting,
    ) -> Result<RgbImageF32> {
        self.model.draw(&mut self.whole, posed, lighting)?;
        self.whole.render()?;
        let with = self.whole.read_back()?;
        self.room.set_lighting(lighting)?;
        self.room.render()?;
        let without = self.room.read_back()?;
        Ok(composite(kinds, &with, &without, &self.empty.radiance).image)
    }
}

/// The index of the probe nearest `p`.
fn nearest(probes: &[Probe], p: Vec3) -> usize {
    (0..probes.len())
        .min_by(|a, b| {
            let d = |i: &usize| probes[*i].position.distance(p);
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0)
}

/// The mean of `values` where `mask` holds (0 where it never does).
fn masked_mean(values: &[f32], mask: &[bool]) -> f64 {
    let (sum, count) = (values.iter().zip(mask))
        .filter(|(_, m)| **m)
        .fold((0.0f64, 0usize), |(s, c), (v, _)| (s + *v as f64, c + 1));
    sum / count.max(1) as f64
}

/// Each path method's lighting, from position to position: the tracked hybrid on the fused
/// map is the room model's own; every other method keeps its lighting and the probe it holds.
struct MethodLightings {
    methods: Vec<(PathMethod, Option<MethodLighting>)>,
    /// The probe nearest the room's centre.
    one: usize,
}

/// A path method's own lighting, and the probe whose map it holds (none: a map of its own
/// position, the fused or the true probe's).
struct MethodLighting {
    lighting: EnvironmentLighting,
    probe: Option<usize>,
}

impl MethodLightings {
    fn new(probes: &[Probe], one: usize, order: usize) -> Result<Self> {
        let methods = (path_methods().into_iter())
            .map(|method| {
                if is_room_model(method) {
                    return Ok((method, None));
                }
                let technique = method.method.technique;
                let lighting = technique.start(&probes[one].radiance, order, 0.0)?;
                Ok((
                    method,
                    Some(MethodLighting {
                        lighting,
                        probe: Some(one),
                    }),
                ))
            })
            .collect::<Result<_>>()?;
        Ok(Self { methods, one })
    }

    /// Every method's lighting at `centre`, in [`path_methods`]' order.
    fn at(
        &mut self,
        model: &mut RoomModel,
        centre: Vec3,
        true_probe: &Probe,
    ) -> Result<Vec<(PathMethod, FrameLighting)>> {
        let probes = model.lighting.probes();
        let near = nearest(probes, centre);
        let (cube, _) = model.lighting.local_map(centre);
        let geometry = model.lighting.geometry();
        let (w, h) = (true_probe.radiance.width(), true_probe.radiance.height());
        let fused_map = EnvMap::from_fn(w, h, 1, |d| cube.texels()[geometry.texel_of(d)]);
        let mut lightings = Vec::new();
        for (method, own) in &mut self.methods {
            let Some(own) = own else {
                lightings.push((*method, model.update(centre).0));
                continue;
            };
            let probes = model.lighting.probes();
            let probe = match method.map {
                PathMap::OneProbe => Some(self.one),
                PathMap::NearestProbe => Some(near),
                PathMap::Fused | PathMap::TrueProbe => None,
            };
            if probe.is_none() || probe != own.probe {
                own.lighting.set_map(match (method.map, probe) {
                    (_, Some(k)) => probes[k].radiance.clone(),
                    (PathMap::TrueProbe, None) => true_probe.radiance.clone(),
                    _ => fused_map.clone(),
                });
                own.probe = probe;
            }
            lightings.push((*method, method.method.technique.frame(&mut own.lighting).0));
        }
        Ok(lightings)
    }
}

/// Whether `method` is the room model's own: the tracked hybrid on the fused map.
fn is_room_model(method: PathMethod) -> bool {
    method.map == PathMap::Fused && method.method.technique == TRACKED
}

/// One position's model errors, for the terminal.
fn position_line(position: &PathPosition) -> String {
    (position.methods.iter())
        .map(|r| format!("{} {:.4}", r.method, r.model))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_picked_evenly_with_both_ends() {
        assert_eq!(pick_frames(120, 5), [0, 30, 60, 89, 119]);
        assert_eq!(pick_frames(4, 10), [0, 1, 2, 3]);
        assert_eq!(pick_frames(120, 2), [0, 119]);
        assert_eq!(pick_frames(120, 1), [0, 119]);
    }

    #[test]
    fn masked_means_count_only_the_mask() {
        assert_eq!(masked_mean(&[1.0, 3.0, 100.0], &[true, true, false]), 2.0);
        assert_eq!(masked_mean(&[1.0], &[false]), 0.0);
    }
}
