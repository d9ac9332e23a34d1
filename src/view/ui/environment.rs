//! The panel's environment section: choosing the map, turning it, and its thumbnail with the
//! lights marked.

use super::{Panel, PanelAction};
use foundation::envmap::{EnvMap, direction_of_uv, rotate_y, uv_of_direction};
use foundation::image_io::{srgb_encode, tonemap};
use std::path::Path;

const THUMBNAIL: [usize; 2] = [256, 128];

impl Panel<'_> {
    pub(super) fn environment_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Environment");
        let file_name = |p: &Path| {
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        let mut chosen = None;
        egui::ComboBox::from_label("map")
            .selected_text(file_name(&self.settings.env))
            .show_ui(ui, |ui| {
                for choice in self.info.env_choices {
                    if ui
                        .selectable_label(*choice == self.settings.env, file_name(choice))
                        .clicked()
                    {
                        chosen = Some(choice.clone());
                    }
                }
            });
        ui.horizontal(|ui| {
            ui.text_edit_singleline(&mut self.state.env_path_text);
            if ui.button("Load").clicked() {
                chosen = Some(self.state.env_path_text.clone().into());
            }
        });
        if let Some(path) = chosen {
            self.state.env_path_text = path.display().to_string();
            self.actions.push(PanelAction::LoadEnvironment(path));
        }
        ui.add(
            egui::Slider::new(&mut self.settings.rotation_deg, -180.0..=180.0).text("rotation °"),
        );
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.settings.animate, "animate");
            ui.add(egui::Slider::new(&mut self.settings.animate_speed, 1.0..=90.0).text("°/s"));
        });
        self.thumbnail(ui);
    }

    /// The map as the scene sees it (rotated), with the lights marked.
    fn thumbnail(&mut self, ui: &mut egui::Ui) {
        let Some(map) = self.info.environment else {
            return;
        };
        let key = (
            self.settings.env.clone(),
            (self.settings.rotation_deg * 2.0).round() as i32,
        );
        if self.state.thumbnail_for.as_ref() != Some(&key) {
            let image = thumbnail_image(
                map,
                self.settings.rotation_deg.to_radians(),
                self.settings.exposure,
            );
            match &mut self.state.thumbnail {
                Some(handle) => handle.set(image, egui::TextureOptions::NEAREST),
                None => {
                    self.state.thumbnail = Some(ui.ctx().load_texture(
                        "environment",
                        image,
                        egui::TextureOptions::NEAREST,
                    ))
                }
            }
            self.state.thumbnail_for = Some(key);
        }
        let Some(texture) = &self.state.thumbnail else {
            return;
        };
        let width = ui.available_width().min(280.0);
        let size = egui::vec2(width, width / 2.0);
        let rect = ui.add(egui::Image::new((texture.id(), size))).rect;
        let painter = ui.painter_at(rect);
        let Some(decomposition) = self.info.decomposition else {
            return;
        };
        let colours = [
            egui::Color32::RED,
            egui::Color32::GREEN,
            egui::Color32::LIGHT_BLUE,
            egui::Color32::YELLOW,
        ];
        for (k, light) in decomposition.lights.iter().enumerate() {
            let (u, v) = uv_of_direction(light.direction);
            let centre = rect.min + egui::vec2(u * rect.width(), v * rect.height());
            let radius = (light.cap_radius / std::f32::consts::PI * rect.height()).max(3.0);
            painter.circle_stroke(centre, radius, egui::Stroke::new(1.5, colours[k % 4]));
        }
    }
}

/// The map as the scene sees it, turned by `rotation` radians and tone-mapped.
fn thumbnail_image(map: &EnvMap, rotation: f32, exposure: f32) -> egui::ColorImage {
    let mut rgb = Vec::with_capacity(THUMBNAIL[0] * THUMBNAIL[1] * 3);
    for j in 0..THUMBNAIL[1] {
        for i in 0..THUMBNAIL[0] {
            let w = direction_of_uv(
                (i as f32 + 0.5) / THUMBNAIL[0] as f32,
                (j as f32 + 0.5) / THUMBNAIL[1] as f32,
            );
            let c = tonemap(map.radiance(rotate_y(w, -rotation)), exposure);
            rgb.extend(c.to_array().map(|x| (srgb_encode(x) * 255.0) as u8));
        }
    }
    egui::ColorImage::from_rgb(THUMBNAIL, &rgb)
}
