//! The per-frame half of hprt: the environment map becomes an SH polynomial plus directional
//! lights ([`decompose`]); [`lighting`] is the one path from a map to a frame's lighting, which
//! the [`render`]er draws through the baked transfer and shadow maps.

pub mod cubemap;
pub mod decompose;
pub mod light;
pub mod lighting;
pub mod peers;
pub mod reflection;
pub mod render;
pub mod sequence;
pub mod tracking;

pub use cubemap::{CubeGeometry, CubeMap, CubeResampler, CubeSource};
pub use decompose::{
    DecomposeError, DecomposeMode, DecomposeSettings, Decomposer, Decomposition, Window,
};
pub use light::DirectionalLight;
pub use lighting::{EnvironmentLighting, FrameLighting, LitFrame, RenderMode, ShTransfer};
pub use tracking::{LightTracker, TrackedLight, TrackingSettings};
