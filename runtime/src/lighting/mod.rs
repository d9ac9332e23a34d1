//! A frame's lighting: what it is ([`frame`], the contract the renderer takes) apart from the
//! service that makes it from an environment map ([`EnvironmentLighting`]).

mod frame;
mod rotation;
mod service;
#[cfg(test)]
mod tests;

pub use frame::{
    FrameLighting, LitFrame, RenderMode, ShTransfer, lights_indirect_default, map_rotation,
};
pub use service::{EnvironmentLighting, FrameCost};
