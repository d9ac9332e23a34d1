//! A room's state in the viewer: the room and the model's place in it (see `room.rs`).

use anyhow::Context;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::scene::{ObjectRole, Pose, Scene};
use report::room::RoomModel;
use report::{ReferenceImages, ReferenceRequest, reference_images};
use runtime::{DecomposeSettings, ProbeFrame};

/// Paths per pixel of the empty room's picture (cached with the reports' references).
const PHOTOGRAPH_SPP: u32 = 16;

/// The room, the model's place in it and what its last update cost.
pub(super) struct RoomState {
    pub(super) model: RoomModel,
    /// The room alone, and its sky: its picture is path-traced for the view.
    room: Scene,
    map: EnvMap,
    rotation_deg: f32,
    /// Where the model is and how it is turned.
    pub(super) pose: Pose,
    /// The `[path]` frame shown (playing back, one per drawn frame).
    pub(super) path_frame: usize,
    /// The pose the renderer's lighting, vertices and bake were last set for.
    pub(super) drawn_at: Option<Pose>,
    pub(super) last: Option<ProbeFrame>,
    /// What the model's soft shadow on the room cost at the last update, in milliseconds.
    pub(super) shadow_ms: f64,
}

impl RoomState {
    /// The room of `scene` under `map` turned by `rotation_deg`: both parts baked (or taken
    /// from the cache, telling `observer`), the probes loaded.
    pub(super) fn open(
        scene: &Scene,
        map: &EnvMap,
        rotation_deg: f32,
        settings: DecomposeSettings,
        observer: &dyn report::Observer,
    ) -> anyhow::Result<Self> {
        let model = RoomModel::open(scene, map.rotated(rotation_deg), settings, observer)?;
        let room = scene.of_role(ObjectRole::Proxy).without_backplate();
        let pose = (model.path.as_ref())
            .and_then(|p| p.poses().first().copied())
            .unwrap_or(Pose::at(model.centre));
        Ok(Self {
            model,
            room,
            map: map.clone(),
            rotation_deg,
            pose,
            path_frame: 0,
            drawn_at: None,
            last: None,
            shadow_ms: 0.0,
        })
    }

    /// What the empty room's picture through `camera` needs, to be made on another thread.
    pub(super) fn photograph_request(&self, camera: Camera) -> PictureRequest {
        PictureRequest {
            room: self.room.clone(),
            map: self.map.clone(),
            rotation_deg: self.rotation_deg,
            camera,
        }
    }

    /// How far the model is turned from where the scene places it, in degrees (0 to 180),
    /// about whichever axis.
    pub(super) fn turn_deg(&self) -> f32 {
        let turn = self.pose.rotation.normalize();
        turn.angle_between(glam::Quat::IDENTITY).to_degrees()
    }

    /// Frames of the `[path]` (0 without one).
    pub(super) fn path_frames(&self) -> usize {
        self.model.path.as_ref().map_or(0, |p| p.positions().len())
    }

    /// The next frame of the `[path]`, looping; a jump back to its start forgets the
    /// followed lights.
    pub(super) fn advance_path(&mut self) {
        let Some(path) = &self.model.path else { return };
        let poses = path.poses();
        self.path_frame = (self.path_frame + 1) % poses.len();
        if self.path_frame == 0 {
            self.model.lighting.reset();
        }
        self.pose = poses[self.path_frame];
    }
}

/// The empty room path-traced through a camera (or taken from the reports' cache): the
/// picture the model is composited into, as a photograph of the room would be.
pub(super) struct PictureRequest {
    room: Scene,
    map: EnvMap,
    rotation_deg: f32,
    camera: Camera,
}

impl PictureRequest {
    pub(super) fn render(&self, observer: &dyn report::Observer) -> anyhow::Result<RgbImageF32> {
        let request = ReferenceRequest {
            spp: PHOTOGRAPH_SPP,
            bounces: self.room.bake.bounces,
            seed: 0,
            sampler: reference::SamplerKind::default(),
            target_noise: None,
            max_seconds: None,
            exposure: 1.0,
        };
        observer.line("path-tracing the empty room for the view (cached)");
        let no_limit = |_: &ReferenceImages| f64::INFINITY;
        let (map, rotation) = (&self.map, self.rotation_deg);
        Ok(reference_images(
            &self.room,
            &self.camera,
            map,
            rotation,
            &request,
            &no_limit,
            observer,
        )
        .context("cannot path-trace the empty room")?
        .radiance)
    }
}
