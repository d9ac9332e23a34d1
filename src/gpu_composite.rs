//! A scene's composite drawn by the GPU methods, in its first, read-back form: the renderer
//! draws the whole scene and the proxies alone (each with its own bake: the proxies' transfer
//! and shadow maps with and without the objects), and the ratio form of the reference
//! (`reference::composite`, CONVENTIONS.md "Compositing") is applied to the two read-back
//! images on the CPU, pixels classified by their centre's ray as the reference classifies
//! them. The same formula as the truth, so a method's composite is measured against the
//! truth's on equal terms; the viewer's live composite needs the ratio in a GPU pass.

use crate::bake_cache::bake_for;
use anyhow::Context;
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::scene::{Backplate, ObjectRole, Scene, load_backplate_image};
use precompute::bake::Transfer;
use reference::composite::{Composite, PixelKind, composite, environment_backplate};
use runtime::FrameLighting;
use runtime::render::{GpuContext, Renderer, ShadowSettings};

/// What the composite of one frame needs besides the whole scene's renderer.
pub struct CompositeInputs<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    /// The map and its rotation, for the environment backplate and the proxies' renderer.
    pub map: &'a EnvMap,
    pub rotation_deg: f32,
    pub shadow: ShadowSettings,
}

/// The proxies alone as a scene of their own (their bake is cached like any scene's).
pub fn proxies_scene(scene: &Scene) -> Scene {
    Scene {
        name: format!("{}-proxies", scene.name),
        geometry: scene.geometry.subset(|o| o.role == ObjectRole::Proxy),
        ..scene.clone()
    }
}

/// The bake of the proxies alone, at the whole scene's bake settings.
pub fn proxies_transfer(scene: &Scene, whole: &Transfer) -> anyhow::Result<Transfer> {
    let mut proxies = proxies_scene(scene);
    proxies.bake = whole.settings;
    let (_, transfer) = bake_for(&proxies, None).context("cannot bake the proxies alone")?;
    Ok(transfer)
}

/// The picture composited into, at the camera's size.
pub fn backplate_image(inputs: &CompositeInputs) -> anyhow::Result<RgbImageF32> {
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

/// Each pixel's kind, by its centre's ray through the whole scene.
pub fn pixel_kinds(scene: &Scene, camera: &Camera) -> Vec<PixelKind> {
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let basis = camera.basis();
    let roles = scene.geometry.triangle_roles();
    (0..camera.height)
        .flat_map(|j| (0..camera.width).map(move |i| (i, j)))
        .map(|(i, j)| {
            let direction = camera.pixel_direction(&basis, i, j);
            match bvh.intersect(camera.position, direction, 0.0, f32::INFINITY) {
                None => PixelKind::Background,
                Some(hit) => match roles[hit.triangle as usize] {
                    ObjectRole::Object => PixelKind::Object,
                    ObjectRole::Proxy => PixelKind::Proxy,
                },
            }
        })
        .collect()
}

/// Draws `lighting` with `whole` (the whole scene's renderer) and a renderer of the proxies
/// alone, and composites the two into the backplate.
pub fn composite_frame(
    gpu: &GpuContext,
    whole: &mut Renderer,
    proxies: &Transfer,
    lighting: &FrameLighting,
    inputs: &CompositeInputs,
) -> anyhow::Result<Composite> {
    let geometry = inputs
        .scene
        .geometry
        .subset(|o| o.role == ObjectRole::Proxy);
    let mut without = Renderer::new(gpu, &geometry, proxies, inputs.camera, inputs.shadow)?;
    let draw = |renderer: &mut Renderer| -> anyhow::Result<RgbImageF32> {
        renderer.set_environment(inputs.map, inputs.rotation_deg);
        renderer.set_lighting(lighting)?;
        renderer.render()?;
        Ok(renderer.read_back()?)
    };
    let with_objects = draw(whole)?;
    let without_objects = draw(&mut without)?;
    let kinds = pixel_kinds(inputs.scene, inputs.camera);
    let backplate = backplate_image(inputs)?;
    Ok(composite(
        &kinds,
        &with_objects,
        &without_objects,
        &backplate,
    ))
}
