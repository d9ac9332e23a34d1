//! Light that changes across a room (the light-probe fusion thesis, chapter 5): probes
//! captured at a few points ([`foundation::probe`]), each with its distance to the room, are
//! blended on a proxy of the room into the environment map at any other point
//! ([`ProbeFusion::local_map`]).

mod fusion;
mod lighting;
mod room_shadow;
#[cfg(test)]
mod tests;

pub use fusion::{FusionSettings, FusionStats, ProbeFusion};
pub use lighting::{ProbeFrame, ProbeLighting};
pub use room_shadow::{ROOM_SHADOW_RAYS, RoomShadow, model_radiance};
