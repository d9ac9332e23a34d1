//! A scene's composite drawn by the GPU methods, in its first, read-back form: the renderer
//! draws the whole scene and the proxies alone (each with its own bake: the proxies' transfer
//! and shadow maps with and without the objects), and the ratio form of the reference
//! (`reference::composite`, CONVENTIONS.md "Compositing") is applied to the two read-back
//! images on the CPU, pixels classified by their centre's ray as the reference classifies
//! them. The same formula as the truth, so a method's composite is measured against the
//! truth's on equal terms; the viewer's live composite needs the ratio in a GPU pass.

use crate::bake::cached_bake;
use crate::error::{ReportError, Result};
use crate::observer::Observer;
use foundation::Rgb;
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::scene::{Backplate, ObjectRole, Scene, load_backplate_image};
use glam::Vec3;
use precompute::bake::Transfer;
use reference::NO_HIT;
use reference::composite::{
    Composite, PixelKind, composite, composite_with_ratio, environment_backplate, pixel_kinds,
};
use runtime::FrameLighting;
use runtime::render::{GpuContext, LiveBackplate, Renderer, ShadowSettings};

/// How the objects' effect on the proxies is composited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum CompositeForm {
    /// The ratio of the proxies with and without the objects (every light's shadow, the
    /// light the objects bounce onto them): the truth's form.
    #[default]
    Differential,
    /// The mobile-AR paper's simpler peer: the backplate times the proxies' ambient occlusion
    /// by the objects (no lights' shadows).
    Occlusion,
    /// The viewer's composite: the differential form drawn in the frame on the GPU (the
    /// proxies' radiance and shadow maps without the objects, the ratio in a GPU pass), pixels
    /// classified by depth.
    Live,
}

/// What the composite of one frame needs besides the whole scene's renderer.
pub struct CompositeInputs<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    /// The map and its rotation, for the environment backplate and the proxies' renderer.
    pub map: &'a EnvMap,
    pub rotation_deg: f32,
    pub shadow: ShadowSettings,
    pub form: CompositeForm,
}

/// The proxies alone as a scene of their own, with the whole scene's bake settings (their
/// bake is cached like any scene's).
fn proxies_scene(scene: &Scene, whole: &Transfer) -> Scene {
    Scene {
        bake: whole.settings,
        ..scene.of_role(ObjectRole::Proxy).renamed("proxies")
    }
}

/// The bake of the proxies alone (cached like any scene's), with the whole scene's settings.
pub fn proxies_bake(scene: &Scene, whole: &Transfer, observer: &dyn Observer) -> Result<Transfer> {
    let proxies = proxies_scene(scene, whole);
    let (_, transfer) = cached_bake(&proxies, observer).map_err(|e| ReportError::Bake {
        what: "the proxies alone",
        source: Box::new(e),
    })?;
    Ok(transfer)
}

/// The backplate of the live composite: the environment, or the scene's photograph at its
/// camera's size.
pub fn live_backplate(scene: &Scene) -> Result<LiveBackplate> {
    Ok(match &scene.backplate {
        Some(Backplate::Image(path)) => LiveBackplate::Photograph(load_backplate_image(
            path,
            scene.camera.width,
            scene.camera.height,
        )?),
        _ => LiveBackplate::Environment,
    })
}

/// The live composite of one frame ([`CompositeForm::Live`]), read back.
pub fn live_composite_frame(
    whole: &mut Renderer,
    transfer: &Transfer,
    lighting: &FrameLighting,
    inputs: &CompositeInputs,
    observer: &dyn Observer,
) -> Result<RgbImageF32> {
    let proxies_transfer = proxies_bake(inputs.scene, transfer, observer)?;
    whole.enable_composite(
        &inputs.scene.geometry,
        &proxies_transfer,
        &live_backplate(inputs.scene)?,
    )?;
    whole.set_environment(inputs.map, inputs.rotation_deg);
    whole.set_lighting(lighting)?;
    // The ratio's floor comes from the frame before (CONVENTIONS.md, "Compositing"): the
    // first frame finds it for the second.
    whole.render()?;
    whole.render()?;
    Ok(whole.read_back()?)
}

/// The picture composited into, at the camera's size.
fn backplate_image(inputs: &CompositeInputs) -> Result<RgbImageF32> {
    match &inputs.scene.backplate {
        Some(Backplate::Image(path)) => Ok(load_backplate_image(
            path,
            inputs.camera.width,
            inputs.camera.height,
        )?),
        _ => {
            let light = reference::EnvironmentLight::new(inputs.map, inputs.rotation_deg);
            Ok(environment_backplate(&light, inputs.camera))
        }
    }
}

/// What each pixel's centre ray sees first in the whole scene: the point and the face normal
/// turned toward the camera, with the triangle (as the reference's primary rays find them).
pub(crate) struct PrimaryHits {
    pub(crate) triangles: Vec<u32>,
    points: Vec<Option<(Vec3, Vec3)>>,
}

impl PrimaryHits {
    pub(crate) fn trace(scene: &Scene, camera: &Camera) -> Self {
        let bvh = SceneBvh::build(&scene.geometry.mesh);
        let basis = camera.basis();
        let (triangles, points) = (0..camera.height)
            .flat_map(|j| (0..camera.width).map(move |i| (i, j)))
            .map(|(i, j)| {
                let direction = camera.pixel_direction(&basis, i, j);
                let Some(hit) = bvh.intersect(camera.position, direction, 0.0, f32::INFINITY)
                else {
                    return (NO_HIT, None);
                };
                let [a, b, c] = scene.geometry.mesh.corners(hit.triangle as usize);
                let normal = (b - a).cross(c - a).normalize_or_zero();
                let facing = if normal.dot(direction) > 0.0 {
                    -normal
                } else {
                    normal
                };
                let point = camera.position + direction * hit.t;
                (hit.triangle, Some((point, facing)))
            })
            .unzip();
        Self { triangles, points }
    }
}

/// Draws `lighting` with `whole` (the whole scene's renderer, drawing `transfer`) and, for
/// the differential form, a renderer of the proxies alone with their own bake, and composites
/// the result into the backplate.
pub fn composite_frame(
    gpu: &GpuContext,
    whole: &mut Renderer,
    transfer: &Transfer,
    lighting: &FrameLighting,
    inputs: &CompositeInputs,
    observer: &dyn Observer,
) -> Result<Composite> {
    let draw = |renderer: &mut Renderer| -> Result<RgbImageF32> {
        renderer.set_environment(inputs.map, inputs.rotation_deg);
        renderer.set_lighting(lighting)?;
        renderer.render()?;
        Ok(renderer.read_back()?)
    };
    let with_objects = draw(whole)?;
    let hits = PrimaryHits::trace(inputs.scene, inputs.camera);
    let kinds = pixel_kinds(&inputs.scene.geometry, &hits.triangles);
    let backplate = backplate_image(inputs)?;
    if inputs.form == CompositeForm::Occlusion {
        let occlusion = ambient_occlusion(inputs.scene, &hits, &kinds);
        return Ok(composite_with_ratio(
            &kinds,
            &with_objects,
            &occlusion,
            &backplate,
        ));
    }
    // The proxies' renderer makes shadow maps of its own: the whole scene's are not needed.
    whole.release_shadow_maps();
    let proxies = proxies_scene(inputs.scene, transfer);
    let proxies_transfer = proxies_bake(inputs.scene, transfer, observer)?;
    let mut without = Renderer::new(
        gpu,
        &proxies.geometry,
        &proxies_transfer,
        inputs.camera,
        inputs.shadow,
    )?;
    let without_objects = draw(&mut without)?;
    Ok(composite(
        &kinds,
        &with_objects,
        &without_objects,
        &backplate,
    ))
}

/// Rays per proxy pixel of [`ambient_occlusion`].
pub const OCCLUSION_RAYS: u32 = 64;

/// The mobile-AR paper's simpler account of the objects on a proxy (a peer): at the point
/// each proxy pixel's centre sees, the cosine-weighted fraction of its hemisphere the virtual
/// objects leave open (no lights' shadows, no bounced light). One per pixel, 1 off the
/// proxies; Hammersley directions rotated per pixel, so the same every run.
fn ambient_occlusion(scene: &Scene, hits: &PrimaryHits, kinds: &[PixelKind]) -> Vec<Rgb> {
    use foundation::sampling::{
        Frame, cosine_hemisphere, cranley_patterson, hammersley, hash_to_unit2, mix64,
    };
    let objects_geometry = scene.geometry.of_role(ObjectRole::Object);
    let objects = SceneBvh::build(&objects_geometry.mesh);
    let offset = 1e-4 * scene.geometry.diagonal();
    (0..kinds.len())
        .map(|index| {
            let (Some((point, normal)), PixelKind::Proxy) = (hits.points[index], kinds[index])
            else {
                return Rgb::ONE;
            };
            let origin = point + normal * offset;
            let frame = Frame::from_normal(normal);
            let shift = hash_to_unit2(mix64(index as u64));
            let open = (0..OCCLUSION_RAYS)
                .filter(|k| {
                    let u = cranley_patterson(hammersley(*k, OCCLUSION_RAYS), shift);
                    let w = frame.to_world(cosine_hemisphere(u));
                    objects.intersect(origin, w, 0.0, f32::INFINITY).is_none()
                })
                .count();
            Rgb::splat(open as f32 / OCCLUSION_RAYS as f32)
        })
        .collect()
}
