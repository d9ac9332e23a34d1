//! The per-frame half of hprt: the environment map becomes an SH polynomial plus directional
//! lights ([`decompose`]), which the renderer draws through the baked transfer and shadow maps.

pub mod cubemap;
pub mod decompose;
pub mod light;

pub use cubemap::{CubeGeometry, CubeMap, CubeResampler, CubeSource};
pub use decompose::{DecomposeMode, DecomposeSettings, Decomposer, Decomposition, Window};
pub use light::DirectionalLight;
pub mod render;
