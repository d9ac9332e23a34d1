//! A model carried through a room lit by its probes (a scene with `[[probe]]` entries): the
//! model moves live (its `[path]` played back, the arrow keys, the panel, `move` and `place`
//! in a script), turns (Q and E, the panel, `turn` in a script), and each new position fuses the local map at its centre, decomposes it and
//! follows its lights (`crate::room`); the model and its shadows are composited into the
//! empty room's path-traced picture, seen through the scene's camera.

use super::App;
use super::jobs::{Job, JobObserver};
use super::room_state::RoomState;
use foundation::envmap::EnvMap;
use glam::{Quat, Vec3};
use std::sync::Arc;

impl App {
    /// Opens the scene's room when it has probes, in the background (its parts may need
    /// baking); the viewer then draws the room's bakes.
    pub(super) fn open_room(&mut self, map: &EnvMap) {
        if self.scene.probes.is_empty() || self.room.is_some() || self.jobs.room.is_some() {
            return;
        }
        let (scene, map) = (self.scene.clone(), map.clone());
        let rotation = self.settings.rotation_deg;
        let settings = self.settings.decompose_settings();
        self.jobs.room = Some(Job::start("opening the room", move |progress| {
            RoomState::open(&scene, &map, rotation, settings, &JobObserver(progress))
        }));
    }

    /// Takes in the room once it is open.
    pub(super) fn poll_room(&mut self) {
        let Some(done) = self.jobs.room.as_ref().and_then(|j| j.poll()) else {
            return;
        };
        self.jobs.room = None;
        match done {
            Ok(room) => {
                self.bake.transfer = Some(Arc::new(room.model.transfer.clone()));
                self.bake.proxies = Some(Arc::new(room.model.room_transfer.clone()));
                self.bake.job = None;
                self.window.renderer = None;
                self.room = Some(room);
            }
            Err(e) => self.stats.message = format!("cannot open the room: {e:#}"),
        }
    }

    /// Moves the model by `offset`, live.
    pub(super) fn move_model(&mut self, offset: Vec3) {
        if let Some(room) = self.room.as_mut() {
            room.pose.centre += offset;
        }
    }

    /// Puts the model's centre at `centre`, live.
    pub(super) fn place_model(&mut self, centre: Vec3) {
        if let Some(room) = self.room.as_mut() {
            room.pose.centre = centre;
        }
    }

    /// Turns the model by `degrees` about the vertical through its centre, live.
    pub(super) fn turn_model(&mut self, degrees: f32) {
        if let Some(room) = self.room.as_mut() {
            let turn = Quat::from_rotation_y(degrees.to_radians());
            room.pose.rotation = (turn * room.pose.rotation).normalize();
        }
    }

    /// The room's lighting for this frame: the path played on, and where the model moved,
    /// the local map fused, decomposed and its lights followed; the model's vertices moved.
    pub(super) fn update_room(&mut self) -> anyhow::Result<()> {
        let (Some(room), Some(renderer)) = (self.room.as_mut(), self.window.renderer.as_mut())
        else {
            return Ok(());
        };
        renderer.set_shadow_settings(self.settings.shadow)?;
        if self.settings.play_path {
            room.advance_path();
        }
        if room.drawn_at == Some(room.pose) && room.model.soft_shadow == self.settings.soft_shadow {
            return Ok(());
        }
        room.model.soft_shadow = self.settings.soft_shadow;
        let (lighting, frame) = room.model.update(room.pose.centre);
        let posed = room.model.posed(room.pose)?;
        room.shadow_ms = room.model.draw(renderer, &posed, &lighting)?;
        self.lighting.decomposition_ms = frame.decompose_ms;
        self.lighting.decomposition = Some(frame.lighting.clone());
        room.last = Some(frame);
        room.drawn_at = Some(room.pose);
        Ok(())
    }

    /// The room's part of the scripted state.
    pub(super) fn room_json(&self) -> serde_json::Value {
        let Some(room) = &self.room else {
            return serde_json::Value::Null;
        };
        let last = room.last.as_ref();
        serde_json::json!({
            "probes": room.model.lighting.probes().len(),
            "centre": room.pose.centre.to_array(),
            "turn_deg": room.turn_deg(),
            "path_frame": room.path_frame,
            "path_frames": room.path_frames(),
            "fuse_ms": last.map_or(0.0, |f| f.fuse_ms),
            "decompose_ms": last.map_or(0.0, |f| f.decompose_ms),
            "soft_shadow": room.model.soft_shadow,
            "soft_shadow_ms": room.shadow_ms,
            "lights": last.map_or(0, |f| f.lighting.lights.len()),
        })
    }
}
