//! A frame's lighting: what it is ([`frame`], the contract the renderer takes) apart from the
//! service that makes it from an environment map ([`EnvironmentLighting`]).

mod environment;
mod frame;
mod rotation;
#[cfg(test)]
mod tests;

pub use environment::EnvironmentLighting;
pub use frame::{
    FrameLighting, LitFrame, RenderMode, ShTransfer, lights_indirect_default, map_rotation,
};
pub use rotation::{rotate_decomposition, rotate_sh};
