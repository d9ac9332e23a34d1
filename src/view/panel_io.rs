//! The viewer's side of its panel: what the panel is shown, what its actions do, and one frame
//! of it run and handed to the GPU.

use super::App;
use super::ui::{self, BakeStatus, PanelAction, PanelInfo};
use std::path::Path;
use winit::window::Window;

impl App {
    /// What the panel shows.
    pub(super) fn panel_info(&self, command_line: String) -> PanelInfo<'_> {
        let bake = match (&self.bake.transfer, &self.bake.job) {
            (Some(t), _) => BakeStatus::Ready {
                order: t.settings.order,
            },
            (None, Some(job)) => BakeStatus::Baking(job.progress.fraction()),
            (None, None) => BakeStatus::Missing {
                path: &self.bake.path,
                settings: self.scene.bake,
            },
        };
        PanelInfo {
            bake,
            working: self.jobs.running(),
            has_backplate: self.scene.backplate.is_some() || self.room.is_some(),
            room: self.room.as_ref().map(|r| ui::RoomInfo {
                probes: r.model.lighting.probes().len(),
                centre: r.pose.centre,
                turn_deg: r.turn_deg(),
                shadow_ms: r.shadow_ms,
                path: (r.path_frames() > 0).then(|| (r.path_frame, r.path_frames())),
                last: r.last.as_ref(),
                texels: r.model.lighting.geometry().directions().len(),
            }),
            environment: self.lighting.environment.as_ref().map(|e| e.map()),
            env_choices: &self.env_choices,
            decomposition: self.lighting.decomposition.as_ref(),
            tracked: self
                .lighting
                .environment
                .as_ref()
                .map_or(&[], |e| e.tracked_lights()),
            sequence_frame: self
                .lighting
                .sequence
                .as_ref()
                .map(|(s, frame)| (*frame, s.len())),
            frame_ms: self.stats.median_frame_ms(),
            decomposition_ms: self.lighting.decomposition_ms,
            adapter: &self.stats.adapter,
            message: &self.stats.message,
            command_line,
            objects: self
                .scene
                .geometry
                .objects
                .iter()
                .map(|o| (o.name.as_str(), o.albedo))
                .collect(),
        }
    }

    pub(super) fn apply(&mut self, action: PanelAction) {
        match action {
            PanelAction::LoadEnvironment(path) => {
                self.settings.env = path;
                self.load_environment();
            }
            PanelAction::StartBake => self.start_bake(),
            PanelAction::MoveObjects(offset) if self.room.is_some() => self.move_model(offset),
            PanelAction::MoveObjects(offset) => self.move_objects(offset),
            PanelAction::TurnModel(degrees) => self.turn_model(degrees),
            PanelAction::ResetView => self.reset_view(),
            PanelAction::SaveScreenshot => {
                let name = format!("hprt-{}-{}.png", self.scene.name, self.stats.frames);
                if let Err(e) = self.save_screenshot(Path::new(&name)) {
                    self.stats.message = format!("screenshot failed: {e:#}");
                }
            }
        }
    }

    pub(super) fn run_ui(
        &mut self,
        window: &Window,
    ) -> (Vec<egui::ClippedPrimitive>, egui_wgpu::ScreenDescriptor) {
        let state = self
            .window
            .egui_state
            .as_mut()
            .expect("egui is set up with the window");
        let input = state.take_egui_input(window);
        let ctx = self.window.egui_ctx.clone();
        // The panel edits copies of the settings and its own state while it reads the rest.
        let command_line = self.command_line(Path::new("render.png"));
        let mut settings = self.settings.clone();
        let mut panel = std::mem::take(&mut self.panel);
        let info = self.panel_info(command_line);
        let mut actions = Vec::new();
        let mut output = ctx.run_ui(input, |ui| {
            actions = ui::panel(ui, &mut settings, &mut panel, &info);
        });
        drop(info);
        self.settings = settings;
        self.panel = panel;
        for action in actions {
            self.apply(action);
        }
        let state = self
            .window
            .egui_state
            .as_mut()
            .expect("egui is set up with the window");
        state.handle_platform_output(window, output.platform_output);
        let gpu = self.window.gpu.as_mut().expect("a window has its GPU");
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                gpu.egui
                    .update_texture(&gpu.gpu.device, &gpu.gpu.queue, *id, delta);
            }
        }
        for id in &output.textures_delta.free {
            gpu.egui.free_texture(id);
        }
        // Applied above: tell epaint they were handled.
        output.textures_delta.clear();
        let paint = ctx.tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [gpu.config.width, gpu.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        (paint, screen)
    }
}
