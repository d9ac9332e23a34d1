//! The viewer's bake, environment, lighting and renderer: made, reloaded and remade as the
//! settings change.

use super::App;
use super::jobs::{Job, JobObserver};
use crate::bake_cache;
use crate::maps::default_exposure;
use precompute::bake::Transfer;
use runtime::EnvironmentLighting;
use runtime::render::{LiveBackplate, Renderer};
use std::sync::Arc;

impl App {
    pub(super) fn load_environment(&mut self) {
        // The map, and how many of its texels were invalid and set to 0.
        let loaded = match &self.lighting.sequence {
            Some((sequence, _)) => {
                (sequence.frame(0).map(|map| (map, 0))).map_err(anyhow::Error::from)
            }
            None => crate::maps::load_map(&self.settings.env, None)
                .map(|loaded| (loaded.map, loaded.sanitized)),
        };
        let (map, sanitized) = match loaded {
            Ok(loaded) => loaded,
            Err(e) => {
                self.stats.message = format!("cannot load the map: {e:#}");
                return;
            }
        };
        let mut lighting = match EnvironmentLighting::new(&map, self.settings.decompose_settings())
        {
            Ok(lighting) => lighting,
            Err(e) => {
                self.stats.message = format!("cannot light the scene with the map: {e}");
                return;
            }
        };
        if self.settings.exposure == 1.0 && self.lighting.environment.is_none() {
            self.settings.exposure = default_exposure(&map);
        }
        self.lighting.lit_for = None;
        self.panel.environment_changed();
        self.stats.message = if sanitized > 0 {
            format!("{sanitized} texels with negative or invalid radiance set to 0")
        } else {
            String::new()
        };
        if self.lighting.sequence.is_some()
            && let Err(e) = lighting.enable_tracking(Some(runtime::TrackingSettings::default()))
        {
            self.stats.message = format!("cannot track the lights: {e}");
        }
        if let Some(r) = self.window.renderer.as_mut() {
            r.set_environment(lighting.map(), self.settings.rotation_deg);
            if let Some(gpu) = self.window.gpu.as_mut() {
                gpu.renderer_changed();
            }
        }
        self.lighting.environment = Some(lighting);
    }

    /// Moves the virtual objects (not the proxies) by `offset` and re-bakes in the background;
    /// the frame shown keeps the old placement until the new bake lands.
    pub(super) fn move_objects(&mut self, offset: glam::Vec3) {
        self.scene.geometry.move_objects(offset);
        self.settings.object_offset += offset;
        self.bake.path = crate::bake_cache::bake_path(&self.scene, &self.scene.bake);
        self.stats.message = format!("moved the objects by {offset}: baking again");
        self.start_bake();
    }

    pub(super) fn start_bake(&mut self) {
        let scene = self.scene.clone();
        self.bake.job = Some(Job::start("baking the scene's transfer", move |progress| {
            let (_, transfer, _) = bake_cache::bake_into_cache(&scene, &scene.bake, progress)?;
            Ok(transfer)
        }));
    }

    /// Takes in what the background work finished since the last frame.
    pub(super) fn poll_jobs(&mut self) {
        self.poll_bake();
        self.poll_room();
        if let Some(done) = self.jobs.proxies.as_ref().and_then(|j| j.poll()) {
            self.jobs.proxies = None;
            match done {
                Ok(proxies) => self.bake.proxies = Some(Arc::new(proxies)),
                Err(e) => self.composite_failed(&e),
            }
        }
    }

    fn poll_bake(&mut self) {
        let Some(done) = self.bake.job.as_ref().and_then(|j| j.poll()) else {
            return;
        };
        self.bake.job = None;
        match done {
            Ok(transfer) => {
                // Drawn again from the new bake (the objects may have moved).
                self.window.renderer = None;
                self.settings.order = transfer.settings.order;
                self.bake.transfer = Some(Arc::new(transfer));
                self.stats.message = format!("baked into {}", self.bake.path.display());
            }
            Err(e) => self.stats.message = format!("the bake failed: {e:#}"),
        }
    }

    /// Whether background work runs, or is about to start for what the settings ask (the
    /// composite's bake or picture): what a script's `wait-bake` waits for.
    pub(super) fn busy(&self) -> bool {
        let jobs = &self.jobs;
        let running = self.bake.job.is_some()
            || jobs.proxies.is_some()
            || jobs.room.is_some()
            || jobs.room_picture.is_some();
        let compositing = (self.window.renderer.as_ref()).is_some_and(|r| r.is_compositing());
        let composite_pending =
            self.composite_wanted() && self.bake.transfer.is_some() && !compositing;
        running || composite_pending
    }

    /// Whether the settings ask for a composite the scene can make (a backplate or a room).
    fn composite_wanted(&self) -> bool {
        self.settings.composite && (self.scene.backplate.is_some() || self.room.is_some())
    }

    fn composite_failed(&mut self, e: &anyhow::Error) {
        self.settings.composite = false;
        self.stats.message = format!("cannot composite: {e:#}");
    }

    /// Shows the next frame of the sequence being played.
    pub(super) fn advance_sequence(&mut self) -> anyhow::Result<()> {
        let (Some((sequence, frame)), Some(env)) = (
            self.lighting.sequence.as_mut(),
            self.lighting.environment.as_mut(),
        ) else {
            return Ok(());
        };
        *frame = (*frame + 1) % sequence.len();
        if *frame == 0 {
            // Looping: start the tracking afresh, as on the first frame.
            env.enable_tracking(Some(runtime::TrackingSettings::default()))?;
        }
        env.set_map(sequence.frame(*frame)?);
        if let Some(renderer) = self.window.renderer.as_mut() {
            renderer.set_environment(env.map(), self.settings.rotation_deg);
            if let Some(gpu) = self.window.gpu.as_mut() {
                gpu.renderer_changed();
            }
        }
        self.lighting.lit_for = None;
        self.panel.environment_changed();
        Ok(())
    }

    /// The decomposition (and the renderer's lighting) when anything it depends on changed.
    pub(super) fn update_lighting(&mut self) -> anyhow::Result<()> {
        if self.room.is_some() {
            return self.update_room();
        }
        let (Some(env), Some(renderer)) = (
            self.lighting.environment.as_mut(),
            self.window.renderer.as_mut(),
        ) else {
            return Ok(());
        };
        renderer.set_shadow_settings(self.settings.shadow)?;
        let materials_changed = self
            .lighting
            .lit_for
            .as_ref()
            .is_none_or(|previous| previous.materials != self.settings.materials);
        if materials_changed {
            // Kept within energy conservation: k_s at most 1 − k_d per channel.
            for (m, o) in self
                .settings
                .materials
                .iter_mut()
                .zip(&self.scene.geometry.objects)
            {
                m.specular = m
                    .specular
                    .min(foundation::Rgb::ONE - o.albedo)
                    .max(foundation::Rgb::ZERO);
            }
            renderer.set_materials(&self.settings.materials)?;
            if renderer.is_glossy() {
                env.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
            }
        }
        let needs = match &self.lighting.lit_for {
            Some(previous) => {
                materials_changed
                    || previous.rotation_deg != self.settings.rotation_deg
                    || previous.decompose_settings() != self.settings.decompose_settings()
                    || previous.mode != self.settings.mode
                    || previous.lights_indirect != self.settings.lights_indirect
                    || previous.median_cut_lights != self.settings.median_cut_lights
                    || previous.env != self.settings.env
            }
            None => true,
        };
        if !needs {
            return Ok(());
        }
        env.set_settings(self.settings.decompose_settings())?;
        env.set_rotation(self.settings.rotation_deg);
        env.set_median_cut_lights(self.settings.median_cut_lights)?;
        let frame = env.frame(self.settings.mode, Some(self.settings.lights_indirect));
        // The panel shows the lights in every mode, plain PRT included.
        let decomposition = match frame.decomposition {
            Some(d) => d,
            None => env.decompose(),
        };
        renderer.set_lighting(&frame.lighting)?;
        renderer.set_environment_rotation(self.settings.rotation_deg);
        self.lighting.decomposition = Some(decomposition);
        self.lighting.decomposition_ms = frame.ms;
        self.lighting.lit_for = Some(self.settings.clone());
        Ok(())
    }

    /// Turns the live composite on or off as the settings ask (a scene with a backplate only),
    /// baking the proxies alone the first time.
    pub(super) fn apply_composite(&mut self) -> anyhow::Result<()> {
        let compositing = (self.window.renderer.as_ref()).is_some_and(|r| r.is_compositing());
        // A room's picture is made for the view: wait for the panel's first frame, which
        // sets the view's width.
        if self.room.is_some() && self.settings.composite && !compositing && self.stats.frames == 0
        {
            return Ok(());
        }
        let wanted = self.composite_wanted();
        if self.window.renderer.is_none() || self.bake.transfer.is_none() {
            return Ok(());
        }
        if wanted && !compositing {
            // The proxies' bake and the room's picture come from background work: composite
            // once both are there.
            let (Some(proxies), Some(backplate)) = (self.ready_proxies(), self.ready_backplate()?)
            else {
                return Ok(());
            };
            let Some(renderer) = self.window.renderer.as_mut() else {
                return Ok(());
            };
            if let Err(e) = renderer.enable_composite(&self.scene.geometry, &proxies, &backplate) {
                self.composite_failed(&e.into());
            }
            self.renderer_changed();
        } else if !wanted && compositing {
            if let Some(renderer) = self.window.renderer.as_mut() {
                renderer.disable_composite();
            }
            self.renderer_changed();
        }
        if let Some(renderer) = self.window.renderer.as_mut() {
            renderer.set_wireframe(self.settings.wireframe);
        }
        Ok(())
    }

    fn renderer_changed(&mut self) {
        if let Some(gpu) = self.window.gpu.as_mut() {
            gpu.renderer_changed();
        }
    }

    /// The proxies' bake, or `None` while it is made in the background (started here).
    fn ready_proxies(&mut self) -> Option<Arc<Transfer>> {
        if let Some(proxies) = &self.bake.proxies {
            return Some(Arc::clone(proxies));
        }
        if self.jobs.proxies.is_none()
            && let Some(transfer) = self.bake.transfer.clone()
        {
            let scene = self.scene.clone();
            self.jobs.proxies = Some(Job::start("baking the proxies alone", move |progress| {
                let observer = JobObserver(progress);
                Ok(report::gpu_composite::proxies_bake(
                    &scene, &transfer, &observer,
                )?)
            }));
        }
        None
    }

    /// The composite's backplate: the scene's, or the room's picture for the view (`None`
    /// while it is path-traced in the background, started here).
    fn ready_backplate(&mut self) -> anyhow::Result<Option<LiveBackplate>> {
        if self.room.is_none() {
            return Ok(Some(report::gpu_composite::live_backplate(&self.scene)?));
        }
        if let Some(done) = self.jobs.room_picture.as_ref().and_then(|j| j.poll()) {
            self.jobs.room_picture = None;
            match done {
                Ok(picture) => return Ok(Some(LiveBackplate::Photograph(picture))),
                Err(e) => self.composite_failed(&e),
            }
            return Ok(None);
        }
        if self.jobs.room_picture.is_none() {
            let camera = self.current_camera();
            if let Some(room) = &self.room {
                let request = room.photograph_request(camera);
                self.jobs.room_picture = Some(Job::start(
                    "path-tracing the empty room for the view",
                    move |progress| request.render(&JobObserver(progress)),
                ));
            }
        }
        Ok(None)
    }

    pub(super) fn ensure_renderer(&mut self) -> anyhow::Result<()> {
        if self.window.renderer.is_some() {
            return Ok(());
        }
        let (Some(gpu), Some(transfer)) = (self.window.gpu.as_mut(), self.bake.transfer.as_ref())
        else {
            return Ok(());
        };
        let camera = self.input.orbit.camera(gpu.config.width, gpu.config.height);
        let mut renderer = Renderer::new(
            &gpu.gpu,
            &self.scene.geometry,
            transfer,
            &camera,
            self.settings.shadow,
        )?;
        if let Some(env) = &self.lighting.environment {
            renderer.set_environment(env.map(), self.settings.rotation_deg);
        }
        gpu.renderer_changed();
        self.window.renderer = Some(renderer);
        self.lighting.lit_for = None;
        if let Some(room) = self.room.as_mut() {
            room.drawn_at = None;
            // The room's own shadowing is in the local map already: only the model casts.
            if let Some(renderer) = self.window.renderer.as_mut() {
                renderer.set_shadow_casters(runtime::render::ShadowCasters::Objects);
            }
        }
        Ok(())
    }
}
