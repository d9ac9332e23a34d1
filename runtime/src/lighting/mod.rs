//! A frame's lighting: what it is ([`frame`], the contract the renderer takes) apart from the
//! service that makes it from an environment map ([`EnvironmentLighting`]).

mod service;
mod frame;
mod rotation;
#[cfg(test)]
mod tests;

pub use service::EnvironmentLighting;
pub use frame::{
    FrameLighting, LitFrame, RenderMode, ShTransfer, lights_indirect_default, map_rotation,
};
