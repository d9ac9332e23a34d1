//! The viewer's state, one struct per concern.

use super::jobs::Job;
use super::room_state::RoomState;
use super::window::WindowGpu;
use crate::support::median;
use foundation::image_io::RgbImageF32;
use precompute::bake::Transfer;
use report::env_sequence::Sequence;
use runtime::render::{Backend, Renderer};
use runtime::viewer::Orbit;
use runtime::viewer::ViewSettings;
use runtime::viewer::script;
use runtime::{Decomposition, EnvironmentLighting};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use winit::event::MouseButton;
use winit::window::Window;
/// The scene's bake: loaded, being made in the background, or missing.
pub(super) struct BakeState {
    pub(super) path: PathBuf,
    pub(super) transfer: Option<Arc<Transfer>>,
    pub(super) job: Option<Job<Transfer>>,
    /// The bake of the proxies alone, for the live composite (made when first needed).
    pub(super) proxies: Option<Arc<Transfer>>,
}

/// The viewer's other background work, besides the scene's bake.
#[derive(Default)]
pub(super) struct Jobs {
    /// The proxies' bake, when the live composite first needs it.
    pub(super) proxies: Option<Job<Transfer>>,
    /// The room: both parts baked, the probes loaded.
    pub(super) room: Option<Job<RoomState>>,
    /// The empty room's picture for the view, when the composite first needs it.
    pub(super) room_picture: Option<Job<RgbImageF32>>,
}

impl Jobs {
    /// The first job running, for the panel: what it does and its share done.
    pub(super) fn running(&self) -> Option<(&'static str, f32)> {
        let proxies = self
            .proxies
            .as_ref()
            .map(|j| (j.what, j.progress.fraction()));
        let room = self.room.as_ref().map(|j| (j.what, j.progress.fraction()));
        let picture = (self.room_picture.as_ref()).map(|j| (j.what, j.progress.fraction()));
        proxies.or(room).or(picture)
    }
}

/// The environment map as lighting, and the settings it was last turned into lighting for.
#[derive(Default)]
pub(super) struct LightingState {
    pub(super) environment: Option<EnvironmentLighting>,
    pub(super) lit_for: Option<ViewSettings>,
    pub(super) decomposition: Option<Decomposition>,
    pub(super) decomposition_ms: f64,
    /// A sequence being played, and the frame shown.
    pub(super) sequence: Option<(Sequence, usize)>,
}

/// The window, its GPU and what is drawn in it.
pub(super) struct WindowState {
    pub(super) backend: Backend,
    /// Requested, then current, window size in pixels.
    pub(super) size: (u32, u32),
    pub(super) window: Option<Arc<Window>>,
    pub(super) gpu: Option<WindowGpu>,
    pub(super) renderer: Option<Renderer>,
    pub(super) egui_ctx: egui::Context,
    pub(super) egui_state: Option<egui_winit::State>,
}

/// The camera and the mouse.
pub(super) struct InputState {
    pub(super) orbit: Orbit,
    pub(super) initial_orbit: Orbit,
    pub(super) drag: Option<(MouseButton, (f64, f64))>,
    pub(super) cursor: (f64, f64),
}

/// Commands of `--script` still to run.
#[derive(Default)]
pub(super) struct ScriptState {
    pub(super) commands: VecDeque<script::Command>,
    /// Frames to wait before the next command.
    pub(super) wait: u32,
}

/// Timings and messages the panel and the scripted state report.
#[derive(Default)]
pub(super) struct Stats {
    pub(super) frame_ms: VecDeque<f64>,
    pub(super) adapter: String,
    pub(super) message: String,
    pub(super) frames: u64,
    pub(super) last_frame: Option<Instant>,
}

impl Stats {
    pub(super) fn median_frame_ms(&self) -> Option<f64> {
        (!self.frame_ms.is_empty()).then(|| median(self.frame_ms.iter().copied().collect()))
    }
}
