//! One frame, in order: reflections, vertex radiance, the frame's uniforms, shadow maps, the
//! PRT pass, the light pass, the composite. The order lives here alone (docs/STYLE.md,
//! "Order in one place").

use super::error::checked;
use super::light_pass::LightPassInputs;
use super::prt_pass::PrtPassInputs;
use super::uniforms::{self, FrameParameters, FrameUniform, LightUniform};
use super::{FrameLighting, RenderError, Renderer, ShadowCasters, ShadowFit};
use crate::lighting::ShTransfer;
use foundation::settings::{InvalidSettings, SettingsProblem};

impl Renderer {
    /// Records and submits one frame; returns without waiting for the GPU.
    pub fn render(&mut self) -> Result<(), RenderError> {
        let device = self.device.clone();
        checked(&device, || self.record_frame())
    }

    fn record_frame(&mut self) -> Result<(), RenderError> {
        let lighting = self
            .frame
            .lighting
            .clone()
            .ok_or_else(|| InvalidSettings::new("lighting", SettingsProblem::NoLighting))?;
        let shadows = lighting.shadows && !lighting.lights.is_empty() && self.casts_shadows();
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.record_reflections(&mut encoder, &lighting);
        self.record_radiance(&mut encoder, &lighting);
        let light_data = self.write_uniforms(&lighting);
        if shadows {
            let matrices: Vec<_> = light_data.iter().map(|l| l.shadow_matrix()).collect();
            self.record_shadow_maps(&mut encoder, &matrices);
        }
        self.record_passes(&mut encoder, shadows);
        self.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The vertex radiance (the scene's, and the proxies' when compositing), only when the
    /// lighting or the bake changed.
    fn record_radiance(&mut self, encoder: &mut wgpu::CommandEncoder, lighting: &FrameLighting) {
        if !self.frame.radiance_dirty {
            return;
        }
        self.scene.update_radiance(&self.queue, encoder, lighting);
        if let Some(composite) = &self.composite {
            let (order, vertices) = (self.scene.order, self.scene.vertex_count);
            composite.update_radiance(&self.queue, encoder, lighting, order, vertices);
        }
        self.frame.radiance_dirty = false;
    }

    /// Writes the frame's and the lights' uniforms; returns the lights' (their shadow
    /// matrices place the shadow maps).
    fn write_uniforms(&mut self, lighting: &FrameLighting) -> Vec<LightUniform> {
        let shadow = self.shadow_maps.settings();
        let view_proj = uniforms::camera_view_proj(&self.frame.camera, &self.bounds);
        let frame = self.frame_uniform(lighting, view_proj);
        let fits: Vec<ShadowFit> = lighting
            .lights
            .iter()
            .map(|l| {
                ShadowFit::to_view(l.direction, self.scene.bounds, view_proj, shadow.resolution)
            })
            .collect();
        let light_data = uniforms::light_uniforms(&lighting.lights, &fits);
        self.buffers.write(&self.queue, &frame, &light_data);
        light_data
    }

    fn frame_uniform(&self, lighting: &FrameLighting, view_proj: glam::Mat4) -> FrameUniform {
        let lights = &lighting.lights;
        FrameUniform::new(&FrameParameters {
            camera: &self.frame.camera,
            view_proj,
            environment_rotation: self.environment.rotation,
            light_count: lights.len(),
            // The composite draws its own backplate.
            background: self.background && self.composite.is_none(),
            pcf_taps: self.shadow_maps.settings().pcf_taps,
            // 0: no maps of the proxies alone (they cannot shadow themselves).
            proxy_layers: match self.proxy_layers() {
                true => lights.len() as u32,
                false => 0,
            },
            sh: &lighting.sh,
            sh_per_pixel: lighting.sh_transfer.per_pixel(),
            unoccluded_reflections: lighting.sh_transfer == ShTransfer::Unbaked,
            reflection_to_map: match &lighting.reflections {
                crate::reflection::ReflectedEnvironment::Remainder { orientation, .. } => {
                    glam::Mat4::from_quat(orientation.inverse())
                }
                _ => glam::Mat4::IDENTITY,
            },
        })
    }

    /// The PRT pass, the light pass and, compositing, the composite.
    fn record_passes(&mut self, encoder: &mut wgpu::CommandEncoder, shadows: bool) {
        self.prt_pass.record(
            &self.device,
            encoder,
            &self.targets,
            &self.scene,
            &PrtPassInputs {
                frame: &self.buffers.frame,
                materials: &self.scene.materials.uniform,
                reflections: &self.reflections,
                composite: self.composite.as_ref().map(|c| c.prt_pass_inputs()),
            },
        );
        if self.composite.is_some() {
            // The proxies' maps and the composite's images are bound afresh each frame.
            self.light_pass.inputs_changed();
        }
        let inputs = LightPassInputs {
            buffers: &self.buffers,
            targets: &self.targets,
            shadow_maps: &self.shadow_maps,
            environment: &self.environment,
            materials: &self.scene.materials.uniform,
            composite: self.composite.as_ref().map(|c| c.light_pass_inputs()),
        };
        self.light_pass
            .record(&self.device, encoder, &inputs, shadows);
        if let Some(composite) = &self.composite {
            composite.record(&self.device, encoder, &self.scene, &self.buffers);
        }
    }

    /// Whether anything casts shadows: with no casters every map would be empty (every light
    /// wholly visible), so none is drawn or kept, which is what the shadowless pass computes.
    fn casts_shadows(&self) -> bool {
        match self.casters {
            ShadowCasters::All => true,
            ShadowCasters::Objects => !self.scene.objects.is_empty() || self.proxy_layers(),
        }
    }

    /// Whether the shadow maps hold each light's map of the proxies alone too (compositing
    /// proxies that can shadow themselves, and do).
    fn proxy_layers(&self) -> bool {
        self.casters == ShadowCasters::All
            && self.composite.as_ref().is_some_and(|c| c.self_shadowing)
    }

    /// Each light's shadow map where its matrix changed; compositing, then each light's map
    /// of the proxies alone, in the layers after the scene's.
    fn record_shadow_maps(&mut self, encoder: &mut wgpu::CommandEncoder, matrices: &[glam::Mat4]) {
        let lights = matrices.len();
        let layers: Vec<glam::Mat4> = match self.proxy_layers() {
            true => matrices.iter().chain(matrices).copied().collect(),
            false => matrices.to_vec(),
        };
        if self.shadow_maps.reserve(&self.device, layers.len()) {
            self.light_pass.inputs_changed();
        }
        if self.frame.shadow_layers != Some(lights) {
            // The proxies' layers moved with the light count.
            self.shadow_maps.invalidate();
            self.frame.shadow_layers = Some(lights);
        }
        let (scene, composite, casters) = (&self.scene, &self.composite, self.casters);
        self.shadow_maps.render_stale(
            &self.queue,
            encoder,
            |pass, layer| match (composite, casters) {
                (Some(c), _) if layer >= lights => c.draw_proxies_depth_only(scene, pass),
                (_, ShadowCasters::All) => scene.draw_depth_only(pass),
                (_, ShadowCasters::Objects) => scene.draw_parts_depth_only(pass, &scene.objects),
            },
            &layers,
        );
    }

    /// Prefilters the reflection maps now, if the lighting or the materials changed them
    /// (a frame does it otherwise); with [`Self::wait`], what a lighting change costs.
    pub fn update_reflections(&mut self) -> Result<(), RenderError> {
        let Some(lighting) = self.frame.lighting.clone() else {
            return Ok(());
        };
        let device = self.device.clone();
        checked(&device, || {
            let mut encoder = self.device.create_command_encoder(&Default::default());
            self.record_reflections(&mut encoder, &lighting);
            self.queue.submit([encoder.finish()]);
            Ok(())
        })
    }

    fn record_reflections(&mut self, encoder: &mut wgpu::CommandEncoder, lighting: &FrameLighting) {
        if !(self.frame.reflections_dirty && self.is_glossy()) {
            return;
        }
        let recreated = self.reflections.update(
            &self.device,
            &self.queue,
            encoder,
            &lighting.reflections,
            &self.scene.materials.table.shininess,
        );
        if recreated {
            self.prt_pass.inputs_changed();
        }
        self.frame.reflections_dirty = false;
    }
}
