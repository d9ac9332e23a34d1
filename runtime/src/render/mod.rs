//! The hybrid renderer (thesis 4.4, Figure 4.6), with wgpu. A frame is four passes, one module
//! each, over resources of their own:
//!
//! 1. [`gpu_scene`]: a compute pass turns the baked transfer and the SH lighting into
//!    per-vertex radiance (`shaders/transfer.wgsl`), only when the lighting changed;
//! 2. [`shadow_maps`]: each directional light's shadow map (`shaders/shadow.wgsl`), re-rendered
//!    only when the light moves;
//! 3. [`prt_pass`]: the scene with that radiance, writing the G-buffer ([`targets`]);
//! 4. [`light_pass`]: one additive full-screen pass adds every light with percentage-closer
//!    filtering and shows the [`environment`] behind the scene (`shaders/lights.wgsl`).
//!
//! [`frame`] records them in this order, in one place.
//!
//! Glossy scenes add [`materials`] and the [`reflection_maps`] the PRT pass reflects,
//! prefiltered only when the reflected environment changes.
//!
//! [`uniforms`] holds what the passes share per frame, [`shaders`] loads the WGSL, [`gpu`]
//! opens the device, [`readback`] copies images back, [`pass_helpers`] builds the descriptors
//! every pass repeats.

mod bindings;
mod composite;
mod display_pass;
mod environment_texture;
mod error;
mod frame;
mod gpu;
mod gpu_scene;
mod light_pass;
mod materials;
mod pass_helpers;
mod prt_pass;
mod readback;
mod reflection_maps;
mod shaders;
mod shadow_fit;
mod shadow_maps;
mod targets;
mod transfer_pass;
mod transfer_texels;
mod uniforms;

use composite::{Compositor, CompositorSource};
pub use composite::{LiveBackplate, rows_of, with_objects_alone};
pub use display_pass::{DisplayPass, capture_target};
use environment_texture::EnvironmentTexture;
use error::checked;
pub use error::{BakeMismatch, ReadbackError, RenderError};
use foundation::Rgb;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::material::Material;
use foundation::scene::SceneMesh;
use foundation::settings::{InvalidSettings, SettingsProblem};
pub use gpu::{Backend, GpuContext, GpuError};
use gpu_scene::GpuScene;
use light_pass::LightPass;
use precompute::bake::Transfer;
use prt_pass::PrtPass;
pub use readback::TextureCopy;
#[cfg(not(target_arch = "wasm32"))]
pub use readback::read_texture;
use reflection_maps::ReflectionMaps;
pub use shaders::{MAX_GPU_ORDER, MAX_LIGHTS};
pub use shadow_fit::{BoundingSphere, ShadowFit, ShadowSettings};
use shadow_maps::ShadowMaps;
use targets::Targets;
use uniforms::FrameBuffers;

pub use crate::lighting::{FrameLighting, RenderMode};

/// Refuses an image larger than the adapter's textures can be (before the driver would).
fn check_image_size(device: &wgpu::Device, camera: &Camera) -> Result<(), RenderError> {
    let max = device.limits().max_texture_dimension_2d;
    if camera.width > max || camera.height > max {
        return Err(InvalidSettings::new(
            "image size",
            SettingsProblem::ImageOverAdapter {
                width: camera.width,
                height: camera.height,
                max_side: max,
            },
        )
        .into());
    }
    Ok(())
}

/// What a frame is drawn with and whether the vertex radiance is stale.
struct FrameState {
    camera: Camera,
    lighting: Option<FrameLighting>,
    radiance_dirty: bool,
    /// The reflection maps must be prefiltered again (glossy scenes only).
    reflections_dirty: bool,
    /// The light count the shadow-map layers were laid out for.
    shadow_layers: Option<usize>,
}

/// Face size of the reflection maps unless set otherwise.
pub const DEFAULT_REFLECTION_SIZE: usize = 128;

/// The renderer of one baked scene.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    scene: GpuScene,
    bounds: BoundingSphere,
    buffers: FrameBuffers,
    targets: Targets,
    shadow_maps: ShadowMaps,
    environment: EnvironmentTexture,
    prt_pass: PrtPass,
    light_pass: LightPass,
    reflections: ReflectionMaps,
    frame: FrameState,
    /// The live composite into a backplate, when enabled ([`Self::enable_composite`]).
    composite: Option<Compositor>,
    /// Show the environment map where no geometry is.
    pub background: bool,
    casters: ShadowCasters,
}

/// What casts the lights' shadows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ShadowCasters {
    /// Every object and proxy.
    #[default]
    All,
    /// The virtual objects alone: the proxies are a room whose own shadowing is already in
    /// the light (a local map fused from probes at the model holds the room as it sees it),
    /// so they take the objects' shadows but cast none.
    Objects,
}

impl Renderer {
    /// Uploads the scene and its bake and builds the pipelines, for `camera`'s image size.
    pub fn new(
        gpu: &GpuContext,
        geometry: &SceneMesh,
        transfer: &Transfer,
        camera: &Camera,
        shadow: ShadowSettings,
    ) -> Result<Self, RenderError> {
        checked(&gpu.device, || {
            Self::create(gpu, geometry, transfer, camera, shadow)
        })
    }

    fn create(
        gpu: &GpuContext,
        geometry: &SceneMesh,
        transfer: &Transfer,
        camera: &Camera,
        shadow: ShadowSettings,
    ) -> Result<Self, RenderError> {
        camera.validate()?;
        check_image_size(&gpu.device, camera)?;
        let device = gpu.device.clone();
        let scene = GpuScene::new(&device, &gpu.queue, geometry, transfer)?;
        let buffers = FrameBuffers::new(&device);
        Ok(Self {
            bounds: BoundingSphere::of_box(scene.bounds.0, scene.bounds.1),
            prt_pass: PrtPass::new(&device, &scene.texture_layout),
            reflections: ReflectionMaps::new(&device, &gpu.queue, DEFAULT_REFLECTION_SIZE),
            light_pass: LightPass::new(&device),
            shadow_maps: ShadowMaps::new(&device, shadow)?,
            targets: Targets::new(&device, camera.width, camera.height),
            environment: EnvironmentTexture::new(
                &device,
                &gpu.queue,
                &EnvMap::uniform(2, 1, Rgb::ZERO),
                0.0,
            ),
            buffers,
            scene,
            frame: FrameState {
                camera: *camera,
                lighting: None,
                radiance_dirty: true,
                reflections_dirty: true,
                shadow_layers: None,
            },
            composite: None,
            background: true,
            casters: ShadowCasters::All,
            queue: gpu.queue.clone(),
            device,
        })
    }

    /// The SH order of the bake this renderer draws.
    pub fn order(&self) -> usize {
        self.scene.order
    }

    pub fn shadow_settings(&self) -> ShadowSettings {
        self.shadow_maps.settings()
    }

    /// Changes the shadow settings (maps are re-rendered if their resolution changes).
    pub fn set_shadow_settings(&mut self, shadow: ShadowSettings) -> Result<(), RenderError> {
        if self.shadow_maps.set_settings(&self.device, shadow)? {
            self.light_pass.inputs_changed();
        }
        Ok(())
    }

    /// Composites every frame into `backplate` from now on (CONVENTIONS.md, "Compositing"):
    /// `geometry` is the scene this renderer draws, `proxies` the bake of its proxies alone
    /// (`SceneMesh::subset`, the same SH order). The images shown and read back become the
    /// composite.
    pub fn enable_composite(
        &mut self,
        geometry: &SceneMesh,
        proxies: &Transfer,
        backplate: &LiveBackplate,
    ) -> Result<(), RenderError> {
        let device = self.device.clone();
        let compositor = checked(&device, || {
            Compositor::new(
                &self.device,
                &self.queue,
                &CompositorSource {
                    scene: &self.scene,
                    geometry,
                    proxies_transfer: proxies,
                    backplate,
                    size: (self.targets.width, self.targets.height),
                },
            )
        })?;
        self.composite = Some(compositor);
        // The shadow-map array gains the proxies' own maps, and the proxies' radiance is
        // made from the lighting already set (a composite turned on after the first frame).
        self.shadow_maps.invalidate();
        self.frame.radiance_dirty = true;
        Ok(())
    }

    /// Draws the same scene with `geometry`'s vertex positions: its objects moved rigidly (a
    /// model carried through a room keeps its bake when it is a translation: its transfer
    /// does not depend on where it is, see `with_objects_alone`). The shadow maps are drawn
    /// again; the triangles and the bake stay.
    pub fn move_vertices(&mut self, geometry: &SceneMesh) -> Result<(), RenderError> {
        let moved = geometry.mesh.vertex_count() as u32;
        if moved != self.scene.vertex_count {
            return Err(InvalidSettings::new(
                "geometry",
                SettingsProblem::VertexCount {
                    moved,
                    drawn: self.scene.vertex_count,
                },
            )
            .into());
        }
        self.scene.write_vertices(&self.queue, geometry);
        self.bounds = BoundingSphere::of_box(self.scene.bounds.0, self.scene.bounds.1);
        self.shadow_maps.invalidate();
        Ok(())
    }

    /// Draws the same scene with a new bake of it, `geometry` as the bake's (a turned model
    /// keeps its bake turned: `precompute::bake::TransferVectors::rotate_vertices`; move its
    /// vertices with [`Self::move_vertices`]).
    pub fn set_transfer(
        &mut self,
        geometry: &SceneMesh,
        transfer: &Transfer,
    ) -> Result<(), RenderError> {
        self.scene.write_transfer(&self.queue, geometry, transfer)?;
        self.frame.radiance_dirty = true;
        Ok(())
    }

    /// Frees the shadow maps beyond the fewest kept (32 lights' maps of 2048² take 1 GiB),
    /// before other work that needs the memory; the next frame with lights draws them again,
    /// the same.
    pub fn release_shadow_maps(&mut self) {
        if self.shadow_maps.release(&self.device) {
            self.light_pass.inputs_changed();
        }
    }

    /// Which geometry casts the lights' shadows (all of it unless set).
    pub fn set_shadow_casters(&mut self, casters: ShadowCasters) {
        if casters != self.casters {
            self.casters = casters;
            self.shadow_maps.invalidate();
            self.light_pass.inputs_changed();
        }
    }

    /// Back to drawing the whole scene.
    pub fn disable_composite(&mut self) {
        self.composite = None;
        self.shadow_maps.invalidate();
        self.light_pass.inputs_changed();
    }

    pub fn is_compositing(&self) -> bool {
        self.composite.is_some()
    }

    /// Draws the proxies' edges over the composite (to line them up with a photograph).
    pub fn set_wireframe(&mut self, on: bool) {
        if let Some(composite) = &mut self.composite {
            composite.wireframe = on;
        }
    }

    /// The environment shown behind the scene (not its lighting: see [`Self::set_lighting`]).
    pub fn set_environment(&mut self, map: &EnvMap, rotation_deg: f32) {
        self.environment =
            EnvironmentTexture::new(&self.device, &self.queue, map, rotation_deg.to_radians());
        self.light_pass.inputs_changed();
    }

    /// Only rotates the background environment.
    pub fn set_environment_rotation(&mut self, rotation_deg: f32) {
        self.environment.rotation = rotation_deg.to_radians();
    }

    /// The camera, and the image size with it. Returns whether the image (see
    /// [`Self::color_view`]) was re-created for a new size.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<bool, RenderError> {
        camera.validate()?;
        check_image_size(&self.device, camera)?;
        let resized = (camera.width, camera.height) != (self.targets.width, self.targets.height);
        if resized {
            self.targets = Targets::new(&self.device, camera.width, camera.height);
            self.light_pass.inputs_changed();
            if let Some(composite) = &mut self.composite {
                composite.resize(&self.device, camera.width, camera.height);
            }
        }
        self.frame.camera = *camera;
        Ok(resized)
    }

    pub fn set_lighting(&mut self, lighting: &FrameLighting) -> Result<(), RenderError> {
        if lighting.lights.len() > MAX_LIGHTS {
            return Err(InvalidSettings::new(
                "lighting",
                SettingsProblem::TooManyLights {
                    lights: lighting.lights.len(),
                    max: MAX_LIGHTS,
                },
            )
            .into());
        }
        if self.frame.lighting.as_ref() != Some(lighting) {
            if self.frame.lighting.as_ref().map(|l| &l.reflections) != Some(&lighting.reflections) {
                self.frame.reflections_dirty = true;
            }
            self.frame.lighting = Some(lighting.clone());
            self.frame.radiance_dirty = true;
        }
        Ok(())
    }

    /// Whether any object is glossy (reflection maps are made only then).
    pub fn is_glossy(&self) -> bool {
        !self.scene.materials.table.glossy.is_empty()
    }

    /// Gives the objects new materials (one per object of the scene, in order), live.
    pub fn set_materials(&mut self, materials: &[Material]) -> Result<(), RenderError> {
        if materials.len() != self.scene.materials.table.object_entries.len() {
            return Err(InvalidSettings::new(
                "materials",
                SettingsProblem::MaterialCount {
                    materials: materials.len(),
                    objects: self.scene.materials.table.object_entries.len(),
                },
            )
            .into());
        }
        let was_glossy = self.is_glossy();
        if self.scene.materials.set(&self.queue, materials)? || !was_glossy {
            self.frame.reflections_dirty = true;
        }
        Ok(())
    }

    /// Face size of the reflection maps (prefiltered again at the next frame).
    pub fn set_reflection_size(&mut self, face_size: usize) -> Result<(), RenderError> {
        if !(4..=2048).contains(&face_size) {
            return Err(InvalidSettings::new(
                "reflection maps",
                SettingsProblem::OutOfRange {
                    quantity: "face size",
                    value: face_size as u64,
                    min: 4,
                    max: 2048,
                },
            )
            .into());
        }
        if face_size != self.reflections.face_size() {
            self.reflections = ReflectionMaps::new(&self.device, &self.queue, face_size);
            self.prt_pass.inputs_changed();
            self.frame.reflections_dirty = true;
        }
        Ok(())
    }

    /// The linear HDR image of the last [`Self::render`] (Rgba16Float): the composite when
    /// compositing.
    pub(crate) fn color_view(&self) -> &wgpu::TextureView {
        match &self.composite {
            Some(composite) => composite.image().1,
            None => &self.targets.color_view,
        }
    }

    fn color_texture(&self) -> &wgpu::Texture {
        match &self.composite {
            Some(composite) => composite.image().0,
            None => &self.targets.color,
        }
    }

    /// Waits for the last frame and copies it to the CPU as linear radiance.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn read_back(&self) -> Result<RgbImageF32, RenderError> {
        checked(&self.device, || {
            let bytes = readback::read_texture(&self.device, &self.queue, self.color_texture(), 8)?;
            Ok(self.radiance(&bytes))
        })
    }

    /// Starts copying the last frame back, for a caller that waits for the mapping itself
    /// (a page): [`Self::finish_read_back`] once [`TextureCopy::buffer`] is mapped.
    pub fn start_read_back(&self) -> TextureCopy {
        TextureCopy::submit(&self.device, &self.queue, self.color_texture(), 8)
    }

    /// The linear radiance of a copy [`Self::start_read_back`] began, once mapped.
    pub fn finish_read_back(&self, copy: TextureCopy) -> Result<RgbImageF32, RenderError> {
        Ok(self.radiance(&copy.texels()?))
    }

    /// The color target's Rgba16Float texels as linear RGB.
    fn radiance(&self, bytes: &[u8]) -> RgbImageF32 {
        let halves: &[half::f16] = bytemuck::cast_slice(bytes);
        let pixels = halves
            .chunks_exact(4)
            .map(|p| Rgb::new(p[0].to_f32(), p[1].to_f32(), p[2].to_f32()))
            .collect();
        RgbImageF32::new(
            self.targets.width as usize,
            self.targets.height as usize,
            pixels,
        )
    }

    /// Blocks until submitted work is done.
    pub fn wait(&self) {
        // Only fails if the device is lost, which the next call reports anyway.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }

    /// The world-space bounding sphere the shadow maps cover.
    pub fn bounds(&self) -> BoundingSphere {
        self.bounds
    }
}
