//! The per-frame half of hprt: the environment map becomes an SH polynomial plus directional
//! lights ([`decompose`]); [`lighting`] is the one path from a map to a frame's lighting, which
//! the [`render`]er draws through the baked transfer and shadow maps.

// Every public item is reachable from the crate root: the API is what lib.rs exports.
#![deny(unreachable_pub)]

pub mod bundle;
mod cubemap;
mod decompose;
mod light;
mod lighting;
mod peers;
mod probes;
mod reflection;
pub mod render;
mod tracking;
pub mod viewer;

pub use cubemap::{CubeGeometry, CubeMap, CubeResampler, CubeSource};
pub use decompose::{
    DecomposeError, DecomposeMode, DecomposeSettings, Decomposer, Decomposition, Window,
    decomposition_picture, describe,
};
pub use light::DirectionalLight;
pub use lighting::{
    EnvironmentLighting, FrameCost, FrameLighting, LitFrame, RenderMode, ShTransfer,
    lights_indirect_default, map_rotation,
};
pub use peers::median_cut::{MedianCutError, analysis_map, median_cut};
pub use probes::{
    FusionSettings, FusionStats, ProbeFrame, ProbeFusion, ProbeLighting, ROOM_SHADOW_RAYS,
    RoomShadow, model_radiance,
};
pub use reflection::{ReflectedEnvironment, SharedCube, convolve_exact};
pub use tracking::{LightTracker, TrackedLight, TrackingSettings};
