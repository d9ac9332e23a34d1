//! Each method's lighting of a map (hybrid in either mode, plain PRT, the peers), and what
//! making it cost on a first frame and on a later frame of a changing map.

use crate::error::Result;
use crate::methods::Method;
use runtime::EnvironmentLighting;
use runtime::render::FrameLighting;

/// What making a method's lighting cost, in milliseconds.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LightingCost {
    /// On the map's first frame.
    pub(crate) first_ms: f64,
    /// On a later frame of a changing map.
    pub(crate) warm_ms: f64,
}

/// The lighting of `method` at Weber `threshold` (each mode's own defaults otherwise), its
/// number of lights and what the decomposition (or projection) cost: on the first frame, and
/// done again as for the next frame of a changing map.
pub(crate) fn method_lighting(
    lighting: &mut EnvironmentLighting,
    order: usize,
    method: Method,
    threshold: f32,
) -> Result<(FrameLighting, usize, LightingCost)> {
    let (frame, lights, first_ms) = first_frame_lighting(lighting, order, method, threshold)?;
    lighting.forget_derived();
    let (_, _, warm_ms) = first_frame_lighting(lighting, order, method, threshold)?;
    Ok((frame, lights, LightingCost { first_ms, warm_ms }))
}

/// [`method_lighting`]'s lighting and the cost of making it from what `lighting` holds.
pub(crate) fn first_frame_lighting(
    lighting: &mut EnvironmentLighting,
    order: usize,
    method: Method,
    threshold: f32,
) -> Result<(FrameLighting, usize, f64)> {
    method.technique.configure(lighting, order, threshold)?;
    Ok(method.technique.frame(lighting))
}
