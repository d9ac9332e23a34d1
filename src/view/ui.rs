//! The viewer's control panel (egui).

use super::App;
use precompute::envmap::{direction_of_uv, rotate_y, uv_of_direction};
use precompute::image_io::{srgb_encode, tonemap};
use runtime::DecomposeMode;
use runtime::render::RenderMode;

const THUMBNAIL: [usize; 2] = [256, 128];

pub fn panel(app: &mut App, ui: &mut egui::Ui) {
    app.stats.panels.clear();
    let panel = egui::Panel::right("controls")
        .default_size(300.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                bake_section(app, ui);
                environment_section(app, ui);
                decomposition_section(app, ui);
                shadow_section(app, ui);
                display_section(app, ui);
                lights_section(app, ui);
                save_section(app, ui);
                if !app.stats.message.is_empty() {
                    ui.separator();
                    ui.label(&app.stats.message);
                }
            });
        });
    // The scene is drawn in the part of the window the panel leaves free.
    let pixels_per_point = ui.ctx().pixels_per_point();
    app.panel_px = (panel.response.rect.width() * pixels_per_point).round() as u32;
}

fn heading(app: &mut App, ui: &mut egui::Ui, name: &str) {
    ui.separator();
    ui.strong(name);
    app.stats.panels.push(name.to_owned());
}

fn bake_section(app: &mut App, ui: &mut egui::Ui) {
    if app.transfer.is_some() {
        return;
    }
    heading(app, ui, "Bake");
    match &app.bake_job {
        Some(job) => {
            let done = job.progress.fraction();
            ui.label("baking the scene's transfer…");
            ui.add(egui::ProgressBar::new(done).show_percentage());
        }
        None => {
            ui.label(format!(
                "No bake of this scene yet (looked for {}).",
                app.bake_path.display()
            ));
            let s = app.scene.bake;
            if ui
                .button(format!(
                    "Bake now (order {}, {} rays/vertex, {} bounces)",
                    s.order, s.samples, s.bounces
                ))
                .clicked()
            {
                app.start_bake();
            }
        }
    }
}

fn environment_section(app: &mut App, ui: &mut egui::Ui) {
    heading(app, ui, "Environment");
    let current = app
        .settings
        .env
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut chosen = None;
    egui::ComboBox::from_label("map")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for choice in &app.env_choices {
                let name = choice
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                if ui
                    .selectable_label(*choice == app.settings.env, name)
                    .clicked()
                {
                    chosen = Some(choice.clone());
                }
            }
        });
    ui.horizontal(|ui| {
        ui.text_edit_singleline(&mut app.env_path_text);
        if ui.button("Load").clicked() {
            chosen = Some(app.env_path_text.clone().into());
        }
    });
    if let Some(path) = chosen {
        app.settings.env = path;
        app.env_path_text = app.settings.env.display().to_string();
        app.load_environment();
    }
    ui.add(egui::Slider::new(&mut app.settings.rotation_deg, -180.0..=180.0).text("rotation °"));
    ui.horizontal(|ui| {
        ui.checkbox(&mut app.settings.animate, "animate");
        ui.add(egui::Slider::new(&mut app.settings.animate_speed, 1.0..=90.0).text("°/s"));
    });
    thumbnail(app, ui);
}

/// The map as the scene sees it (rotated), with the lights marked.
fn thumbnail(app: &mut App, ui: &mut egui::Ui) {
    let Some(env) = &app.environment else { return };
    let key = (
        app.settings.env.clone(),
        (app.settings.rotation_deg * 2.0).round() as i32,
    );
    if app.thumbnail_for.as_ref() != Some(&key) {
        let rotation = app.settings.rotation_deg.to_radians();
        let exposure = app.settings.exposure;
        let mut rgb = Vec::with_capacity(THUMBNAIL[0] * THUMBNAIL[1] * 3);
        for j in 0..THUMBNAIL[1] {
            for i in 0..THUMBNAIL[0] {
                let w = direction_of_uv(
                    (i as f32 + 0.5) / THUMBNAIL[0] as f32,
                    (j as f32 + 0.5) / THUMBNAIL[1] as f32,
                );
                let c = tonemap(env.map().radiance(rotate_y(w, -rotation)), exposure);
                rgb.extend(c.to_array().map(|x| (srgb_encode(x) * 255.0) as u8));
            }
        }
        let image = egui::ColorImage::from_rgb(THUMBNAIL, &rgb);
        match &mut app.thumbnail {
            Some(handle) => handle.set(image, egui::TextureOptions::NEAREST),
            None => {
                app.thumbnail = Some(ui.ctx().load_texture(
                    "environment",
                    image,
                    egui::TextureOptions::NEAREST,
                ))
            }
        }
        app.thumbnail_for = Some(key);
    }
    let Some(texture) = &app.thumbnail else {
        return;
    };
    let width = ui.available_width().min(280.0);
    let size = egui::vec2(width, width / 2.0);
    let response = ui.add(egui::Image::new((texture.id(), size)));
    let rect = response.rect;
    let painter = ui.painter_at(rect);
    if let Some(d) = &app.stats.decomposition {
        for (k, light) in d.lights.iter().enumerate() {
            let (u, v) = uv_of_direction(light.direction);
            let centre = rect.min + egui::vec2(u * rect.width(), v * rect.height());
            let radius = (light.cap_radius / std::f32::consts::PI * rect.height()).max(3.0);
            let colour = [
                egui::Color32::RED,
                egui::Color32::GREEN,
                egui::Color32::LIGHT_BLUE,
                egui::Color32::YELLOW,
            ][k % 4];
            painter.circle_stroke(centre, radius, egui::Stroke::new(1.5, colour));
        }
    }
}

fn decomposition_section(app: &mut App, ui: &mut egui::Ui) {
    heading(app, ui, "Decomposition");
    egui::ComboBox::from_label("mode")
        .selected_text(app.settings.decompose_mode.name())
        .show_ui(ui, |ui| {
            for mode in [DecomposeMode::Consistent, DecomposeMode::Thesis] {
                ui.selectable_value(&mut app.settings.decompose_mode, mode, mode.name());
            }
        });
    ui.add(egui::Slider::new(&mut app.settings.threshold, 0.0..=0.5).text("Weber threshold"));
    let max_order = app
        .transfer
        .as_ref()
        .map_or(app.settings.order, |t| t.settings.order);
    ui.add(
        egui::Slider::new(&mut app.settings.order, 1..=max_order).text("SH order of the lighting"),
    );
    ui.checkbox(
        &mut app.settings.lights_indirect,
        "lights' bounce light through the bake",
    );
}

fn shadow_section(app: &mut App, ui: &mut egui::Ui) {
    heading(app, ui, "Shadows");
    egui::ComboBox::from_label("shadow map")
        .selected_text(format!("{0}×{0}", app.settings.shadow.resolution))
        .show_ui(ui, |ui| {
            for r in [512, 1024, 2048, 4096] {
                ui.selectable_value(&mut app.settings.shadow.resolution, r, format!("{r}×{r}"));
            }
        });
    ui.add(
        egui::Slider::new(&mut app.settings.shadow.pcf_taps, 1..=9)
            .step_by(2.0)
            .text("PCF taps"),
    );
    ui.checkbox(
        &mut app.settings.shadow.from_angular_radius,
        "penumbra from the light's size",
    );
}

fn display_section(app: &mut App, ui: &mut egui::Ui) {
    heading(app, ui, "Display");
    ui.horizontal(|ui| {
        for mode in RenderMode::ALL {
            ui.radio_value(&mut app.settings.mode, mode, mode.name());
        }
    });
    ui.add(
        egui::Slider::new(&mut app.settings.exposure, 0.01..=100.0)
            .logarithmic(true)
            .text("exposure"),
    );
    if ui.button("Reset view (R)").clicked() {
        app.orbit = app.initial_orbit;
    }
}

fn lights_section(app: &mut App, ui: &mut egui::Ui) {
    heading(app, ui, "Lights");
    let frame_ms: Vec<f64> = app.stats.frame_ms.iter().copied().collect();
    if !frame_ms.is_empty() {
        let ms = crate::support::median(frame_ms);
        ui.label(format!("frame {ms:.1} ms ({:.1} fps)", 1000.0 / ms));
    }
    ui.label(format!(
        "decomposition {:.2} ms",
        app.stats.decomposition_ms
    ));
    ui.label(format!("adapter: {}", app.stats.adapter));
    if let Some(d) = &app.stats.decomposition {
        ui.label(format!("{} light(s)", d.lights.len()));
        for (k, light) in d.lights.iter().enumerate() {
            ui.add(
                egui::ProgressBar::new(light.share.clamp(0.0, 1.0)).text(format!(
                    "light {}: {:.1}%",
                    k + 1,
                    100.0 * light.share
                )),
            );
        }
    }
}

fn save_section(app: &mut App, ui: &mut egui::Ui) {
    heading(app, ui, "Save");
    if ui.button("Save screenshot").clicked() {
        let path = std::path::PathBuf::from(format!("hprt-{}-{}.png", app.scene.name, app.frames));
        if let Err(e) = app.save_screenshot(&path) {
            app.stats.message = format!("screenshot failed: {e:#}");
        }
    }
    let mut line = app.command_line(std::path::Path::new("render.png"));
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
