//! The panel's room and composite sections: the model in its room, and the objects composited
//! into the backplate.

use super::{MODEL_TURN_DEG, Panel, PanelAction};

impl Panel<'_> {
    /// The room: where the model is, the path, and what each update of its lighting costs.
    pub(super) fn room_section(&mut self, ui: &mut egui::Ui) {
        let Some(room) = &self.info.room else { return };
        self.heading(ui, "Room");
        let c = room.centre;
        ui.label(format!(
            "{} probes; the model at ({:.2}, {:.2}, {:.2}), turned {:.0}°",
            room.probes, c.x, c.y, c.z, room.turn_deg
        ));
        let soft = format!(
            "its soft shadow and bounce on the room ({:.2} ms)",
            room.shadow_ms
        );
        ui.checkbox(&mut self.settings.soft_shadow, soft)
            .on_hover_text(
                "The model's occlusion of the room's SH light and the light it bounces onto \
                 the room, traced from the room's vertices at each position (the lights' \
                 shadows come from their shadow maps)",
            );
        ui.horizontal(|ui| {
            ui.label("turn the model");
            for degrees in [-MODEL_TURN_DEG, MODEL_TURN_DEG] {
                if (ui.button(format!("{degrees:+.0}°")))
                    .on_hover_text("About the vertical through its centre; its bake turns with it")
                    .clicked()
                {
                    self.actions.push(PanelAction::TurnModel(degrees));
                }
            }
        });
        if let Some((frame, frames)) = room.path {
            ui.checkbox(&mut self.settings.play_path, "play the path")
                .on_hover_text("The scene's [path], one frame per drawn frame, looping");
            ui.label(format!("path frame {frame} of {frames}"));
        }
        if let Some(last) = room.last {
            ui.label(format!(
                "local map {:.2} ms + decomposition {:.2} ms = {:.2} ms per update",
                last.fuse_ms,
                last.decompose_ms,
                last.fuse_ms + last.decompose_ms
            ))
            .on_hover_text(
                "The local map fused from the probes at the model's centre, then decomposed \
                 with its lights followed (CONVENTIONS.md, \"Light probes\")",
            );
            ui.label(format!(
                "{} lights; {:.1}% of texels seen by no probe",
                last.lighting.lights.len(),
                100.0 * last.stats.unseen as f64 / room.texels.max(1) as f64
            ));
        }
        ui.label("arrow keys move the model (Page Up/Down: up and down), Q and E turn it");
        ui.label(
            "the empty room's picture is path-traced for the view as the composite turns on: \
             turn it off and on after moving the camera",
        );
    }

    pub(super) fn composite_section(&mut self, ui: &mut egui::Ui) {
        self.heading(ui, "Composite");
        ui.checkbox(&mut self.settings.composite, "into the backplate")
            .on_hover_text(
                "The objects, and the change they make to the proxies, over the backplate \
                 (off: the whole scene, proxies drawn)",
            );
        ui.add_enabled(
            self.settings.composite,
            egui::Checkbox::new(&mut self.settings.wireframe, "proxy wireframe"),
        )
        .on_hover_text("The proxies' edges, to line them up with the picture");
        ui.horizontal(|ui| {
            ui.label("move the objects");
            let step = 0.25;
            for (label, offset) in [
                ("-x", glam::Vec3::new(-step, 0.0, 0.0)),
                ("+x", glam::Vec3::new(step, 0.0, 0.0)),
                ("-z", glam::Vec3::new(0.0, 0.0, -step)),
                ("+z", glam::Vec3::new(0.0, 0.0, step)),
            ] {
                if ui
                    .button(label)
                    .on_hover_text("Moves the virtual objects over the proxies; re-bakes")
                    .clicked()
                {
                    self.actions.push(PanelAction::MoveObjects(offset));
                }
            }
        });
    }
}
