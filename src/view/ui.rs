//! The viewer's control panel (egui). It edits the [`ViewSettings`], keeps its own widgets'
//! state in a [`PanelState`], reads the rest of the viewer through a [`PanelInfo`], and
//! returns what the user asked for as [`PanelAction`]s.

mod environment;
mod placement;

use foundation::envmap::EnvMap;
use precompute::bake::BakeSettings;
use runtime::render::RenderMode;
use runtime::viewer::ViewSettings;
use runtime::{DecomposeMode, Decomposition, TrackedLight};
use std::path::{Path, PathBuf};

/// Degrees a press of Q or E, or of the panel's buttons, turns a room's model.
pub const MODEL_TURN_DEG: f32 = 15.0;

/// Where the scene's bake stands.
pub enum BakeStatus<'a> {
    /// Loaded, of this SH order.
    Ready { order: usize },
    /// Baking in the background; the share done.
    Baking(f32),
    /// None yet: where it was looked for and what "Bake now" would make.
    Missing {
        path: &'a Path,
        settings: BakeSettings,
    },
}

/// What the panel shows of the viewer.
pub struct PanelInfo<'a> {
    pub bake: BakeStatus<'a>,
    /// Background work running besides the bake: what it does and its share done.
    pub working: Option<(&'static str, f32)>,
    /// The scene composites into a backplate.
    pub has_backplate: bool,
    pub environment: Option<&'a EnvMap>,
    pub env_choices: &'a [PathBuf],
    pub decomposition: Option<&'a Decomposition>,
    /// The tracked lights, when a sequence plays.
    pub tracked: &'a [TrackedLight],
    /// `(frame, frames)` of the sequence being played.
    pub sequence_frame: Option<(usize, usize)>,
    /// Median frame time, once frames have been timed.
    pub frame_ms: Option<f64>,
    pub decomposition_ms: f64,
    pub adapter: &'a str,
    pub message: &'a str,
    /// The `hprt render` command line of the current view.
    pub command_line: String,
    /// Each object's name and diffuse albedo (the bound on its specular).
    pub objects: Vec<(&'a str, foundation::Rgb)>,
    /// The room the model moves through, when the scene has probes.
    pub room: Option<RoomInfo<'a>>,
}

/// What the panel shows of a room the model moves through.
pub struct RoomInfo<'a> {
    pub probes: usize,
    /// Where the centre of the model is.
    pub centre: glam::Vec3,
    /// How far it is turned from where the scene places it.
    pub turn_deg: f32,
    /// What its soft shadow on the room cost at the last update, in milliseconds.
    pub shadow_ms: f64,
    /// `(frame, frames)` of the `[path]`.
    pub path: Option<(usize, usize)>,
    /// The last update: its costs and how many texels no probe saw.
    pub last: Option<&'a runtime::ProbeFrame>,
    /// Texels of the local map.
    pub texels: usize,
}

/// What the user asked for in the panel.
#[derive(Debug, Clone, PartialEq)]
pub enum PanelAction {
    LoadEnvironment(PathBuf),
    StartBake,
    ResetView,
    SaveScreenshot,
    /// Move the virtual objects by this offset (then re-bake).
    MoveObjects(glam::Vec3),
    /// Turn a room's model by this many degrees about the vertical.
    TurnModel(f32),
}

/// The panel's own state between frames.
#[derive(Default)]
pub struct PanelState {
    /// The map path being typed.
    pub env_path_text: String,
    thumbnail: Option<egui::TextureHandle>,
    /// Map and half-degree rotation the thumbnail shows.
    thumbnail_for: Option<(PathBuf, i32)>,
    /// Headings drawn in the last frame (the scripted state reports them).
    pub headings: Vec<String>,
    /// Width of the panel in pixels (the scene fills the rest of the window).
    pub width_px: u32,
    /// The object whose material the panel edits.
    material_object: usize,
}

impl PanelState {
    pub fn new(env: &Path) -> Self {
        Self {
            env_path_text: env.display().to_string(),
            ..Default::default()
        }
    }

    /// The map was replaced: redraw the thumbnail.
    pub fn environment_changed(&mut self) {
        self.thumbnail_for = None;
    }
}

/// Draws the panel on the right of the window.
pub fn panel(
    ui: &mut egui::Ui,
    settings: &mut ViewSettings,
    state: &mut PanelState,
    info: &PanelInfo,
) -> Vec<PanelAction> {
    state.headings.clear();
    let mut actions = Vec::new();
    let mut panel = Panel {
        settings,
        state,
        info,
        actions: &mut actions,
    };
    let response = egui::Panel::right("controls")
        .default_size(300.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                panel.bake_section(ui);
                if info.room.is_some() {
                    panel.room_section(ui);
                }
                panel.environment_section(ui);
                panel.decomposition_section(ui);
                panel.shadow_section(ui);
                panel.material_section(ui);
                panel.display_section(ui);
                if info.has_backplate {
                    panel.composite_section(ui);
                }
                panel.lights_section(ui);
                panel.save_section(ui);
                if !info.message.is_empty() {
                    ui.separator();
                    ui.label(info.message);
                }
            });
        });
    let pixels_per_point = ui.ctx().pixels_per_point();
    panel.state.width_px = (response.response.rect.width() * pixels_per_point).round() as u32;
    actions
}

struct Panel<'a> {
    settings: &'a mut ViewSettings,
    state: &'a mut PanelState,
    info: &'a PanelInfo<'a>,
    actions: &'a mut Vec<PanelAction>,
}

impl Panel<'_> {
    fn heading(&mut self, ui: &mut egui::Ui, name: &str) {
        ui.separator();
        ui.strong(name);
        self.state.headings.push(name.to_owned());
    }

    fn bake_section(&mut self, ui: &mut egui::Ui) {
        match self.info.bake {
            BakeStatus::Ready { .. } => {}
            BakeStatus::Baking(done) => {
                self.heading(ui, "Bake");
                ui.label("baking the scene's transfer…");
                ui.add(egui::ProgressBar::new(done).show_percentage());
            }
            BakeStatus::Missing { path, settings: s } => {
                self.heading(ui, "Bake");
                ui.label(format!(
                    "No bake of this scene yet (looked for {}).",
                    path.display()
                ));
                let label = format!(
                    "Bake now (order {}, {} rays/vertex, {} bounces)",
                    s.order, s.samples, s.bounces
                );
                if ui.button(label).clicked() {
                    self.actions.push(PanelAction::StartBake);
                }
            }
        }
        if let Some((what, done)) = self.info.working {
            self.heading(ui, "Working");
            ui.label(format!("{what}…"));
            ui.add(egui::ProgressBar::new(done).show_percentage());
        }
    }

    fn decomposition_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Decomposition");
        let mut mode = self.settings.decompose_mode;
        egui::ComboBox::from_label("mode")
            .selected_text(mode.name())
            .show_ui(ui, |ui| {
                for choice in [DecomposeMode::Consistent, DecomposeMode::Thesis] {
                    ui.selectable_value(&mut mode, choice, choice.name());
                }
            });
        self.settings.set_decompose_mode(mode);
        ui.add(egui::Slider::new(&mut self.settings.threshold, 0.0..=0.5).text("Weber threshold"));
        let max_order = match self.info.bake {
            BakeStatus::Ready { order } => order,
            _ => self.settings.order,
        };
        ui.add(
            egui::Slider::new(&mut self.settings.order, 1..=max_order)
                .text("SH order of the lighting"),
        );
        ui.checkbox(
            &mut self.settings.lights_indirect,
            "lights' bounce light through the bake",
        );
    }

    fn shadow_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Shadows");
        let shadow = &mut self.settings.shadow;
        egui::ComboBox::from_label("shadow map")
            .selected_text(format!("{0}×{0}", shadow.resolution))
            .show_ui(ui, |ui| {
                for r in [512, 1024, 2048, 4096] {
                    ui.selectable_value(&mut shadow.resolution, r, format!("{r}×{r}"));
                }
            });
        ui.add(
            egui::Slider::new(&mut shadow.pcf_taps, 1..=9)
                .step_by(2.0)
                .text("PCF taps"),
        );
        ui.checkbox(
            &mut shadow.from_angular_radius,
            "penumbra from the light's size",
        );
    }

    /// Per object: its specular reflectance (each channel at most 1 − its albedo) and
    /// shininess, applied live (the scene file is not changed).
    fn material_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Material");
        let objects = &self.info.objects;
        if objects.is_empty() || self.settings.materials.len() != objects.len() {
            return;
        }
        let index = self.state.material_object.min(objects.len() - 1);
        egui::ComboBox::from_label("object")
            .selected_text(objects[index].0)
            .show_ui(ui, |ui| {
                for (i, (name, _)) in objects.iter().enumerate() {
                    ui.selectable_value(&mut self.state.material_object, i, *name);
                }
            });
        let albedo = objects[index].1;
        let material = &mut self.settings.materials[index];
        if let Some(layer) = &mut material.layer {
            ui.add(egui::Slider::new(&mut layer.metallic, 0.0..=1.0).text("metallic"));
            ui.add(egui::Slider::new(&mut layer.roughness, 0.0..=1.0).text("roughness"));
            ui.label(format!(
                "base colour {:.2} {:.2} {:.2}",
                albedo.x, albedo.y, albedo.z
            ));
            return;
        }
        for (c, label) in ["specular R", "specular G", "specular B"]
            .iter()
            .enumerate()
        {
            let bound = (1.0 - albedo[c]).max(0.0);
            ui.add(egui::Slider::new(&mut material.specular[c], 0.0..=bound).text(*label));
        }
        if material.shininess <= 0.0 {
            material.shininess = 60.0;
        }
        ui.add(
            egui::Slider::new(
                &mut material.shininess,
                1.0..=foundation::material::MAX_SHININESS,
            )
            .logarithmic(true)
            .text("shininess"),
        );
        ui.label(format!(
            "albedo {:.2} {:.2} {:.2} (k_d)",
            albedo.x, albedo.y, albedo.z
        ));
    }

    fn display_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Display");
        ui.horizontal(|ui| {
            for mode in RenderMode::ALL {
                ui.radio_value(&mut self.settings.mode, mode, mode.name());
            }
        });
        if self.settings.mode == RenderMode::MedianCut {
            egui::ComboBox::from_label("median-cut lights")
                .selected_text(self.settings.median_cut_lights.to_string())
                .show_ui(ui, |ui| {
                    for n in [1, 2, 4, 8, 16, 32] {
                        ui.selectable_value(&mut self.settings.median_cut_lights, n, n.to_string());
                    }
                });
        }
        ui.add(
            egui::Slider::new(&mut self.settings.exposure, 0.01..=100.0)
                .logarithmic(true)
                .text("exposure"),
        );
        if ui.button("Reset view (R)").clicked() {
            self.actions.push(PanelAction::ResetView);
        }
    }

    fn lights_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Lights");
        if let Some(ms) = self.info.frame_ms {
            ui.label(format!("frame {ms:.1} ms ({:.1} fps)", 1000.0 / ms));
        }
        ui.label(format!(
            "decomposition {:.2} ms",
            self.info.decomposition_ms
        ));
        ui.label(format!("adapter: {}", self.info.adapter));
        if let Some((frame, frames)) = self.info.sequence_frame {
            ui.label(format!("sequence frame {} of {frames}", frame + 1));
        }
        if !self.info.tracked.is_empty() {
            ui.label(format!("{} tracked light(s)", self.info.tracked.len()));
            for t in self.info.tracked {
                let state = if t.fading_out {
                    "fading out"
                } else if t.weight < 1.0 {
                    "fading in"
                } else {
                    "steady"
                };
                ui.label(format!(
                    "#{}: {:.1}% of the map, {state} ({:.0}%)",
                    t.id,
                    100.0 * t.light.share,
                    100.0 * t.weight
                ));
            }
            return;
        }
        let Some(decomposition) = self.info.decomposition else {
            return;
        };
        ui.label(format!("{} light(s)", decomposition.lights.len()));
        for (k, light) in decomposition.lights.iter().enumerate() {
            ui.add(
                egui::ProgressBar::new(light.share.clamp(0.0, 1.0)).text(format!(
                    "light {}: {:.1}%",
                    k + 1,
                    100.0 * light.share
                )),
            );
        }
    }

    fn save_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Save");
        if ui.button("Save screenshot").clicked() {
            self.actions.push(PanelAction::SaveScreenshot);
        }
        let mut line = self.info.command_line.clone();
        ui.label("the same image from the command line:");
        ui.add(
            egui::TextEdit::multiline(&mut line)
                .desired_rows(3)
                .code_editor(),
        );
        if ui.button("Copy command").clicked() {
            ui.ctx().copy_text(line.clone());
            println!("{line}");
        }
    }
}
