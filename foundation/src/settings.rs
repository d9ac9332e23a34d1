//! The error of settings that cannot be used (a camera, a bake, a decomposition, shadows).

use crate::sh::UnsupportedOrder;
use glam::Vec3;

/// Settings that cannot be used, and why: `what` names the settings, `problem` the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid {what}: {problem}")]
pub struct InvalidSettings {
    pub what: &'static str,
    pub problem: SettingsProblem,
}

impl InvalidSettings {
    pub fn new(what: &'static str, problem: SettingsProblem) -> Self {
        Self { what, problem }
    }
}

/// What is wrong with settings, with the numbers a caller needs to correct them (the
/// messages are those users and tests read).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsProblem {
    #[error(transparent)]
    Order(#[from] UnsupportedOrder),
    /// An integer setting outside its inclusive range.
    #[error("{quantity} {value} outside {min}..={max}")]
    OutOfRange {
        quantity: &'static str,
        value: u64,
        min: u64,
        max: u64,
    },
    /// An integer setting above its maximum.
    #[error("{quantity} {value} above {max}")]
    AboveMax {
        quantity: &'static str,
        value: u64,
        max: u64,
    },
    /// An angle outside `(0, max]` degrees.
    #[error("{quantity} {degrees}° outside (0, {max}]")]
    AngleOutOfRange {
        quantity: &'static str,
        degrees: f32,
        max: f32,
    },
    /// A fraction outside `[0, 1]`.
    #[error("{quantity} {value} outside [0, 1]")]
    NotAFraction { quantity: &'static str, value: f32 },
    /// A quantity that must not be negative (NaN included).
    #[error("{quantity} {value} is negative")]
    Negative { quantity: &'static str, value: f32 },
    /// More lights kept than peaks considered per frame.
    #[error("at most {max} lights can be kept (the peaks considered per frame), {asked} asked")]
    TooManyKeptLights { asked: usize, max: usize },
    #[error("samples must be between 1 and {max}, got {samples}")]
    Samples { samples: u32, max: u32 },
    #[error("bounces must be at most {max}, got {bounces}")]
    Bounces { bounces: u32, max: u32 },
    #[error("PCF taps {taps} must be odd, 1..=15")]
    PcfTaps { taps: u32 },
    #[error("image size {width}x{height} is empty")]
    EmptyImage { width: u32, height: u32 },
    #[error(
        "image size {width}x{height} is over the limit ({max_side} per side, {max_pixels} \
         pixels)"
    )]
    ImageOverLimit {
        width: u32,
        height: u32,
        max_side: u32,
        max_pixels: u64,
    },
    /// An image larger than the graphics adapter's textures.
    #[error("{width}x{height} is larger than the graphics adapter allows ({max_side} per side)")]
    ImageOverAdapter {
        width: u32,
        height: u32,
        max_side: u32,
    },
    #[error("fov_y_deg {fov_y_deg} is outside (0, 179)")]
    FieldOfView { fov_y_deg: f32 },
    /// A camera's `position`, `target` or `up` (`field`) with a NaN or infinite component.
    #[error("camera {field} {value} is not finite")]
    CameraNotFinite { field: &'static str, value: Vec3 },
    #[error("camera up vector is zero")]
    ZeroUp,
    #[error("camera position and target coincide")]
    TargetAtPosition,
    #[error("camera up vector is parallel to the viewing direction")]
    UpAlongView,
    /// Moved geometry whose vertex count differs from the drawn scene's.
    #[error("the moved scene has {moved} vertices, the drawn one {drawn}")]
    VertexCount { moved: u32, drawn: u32 },
    #[error("{lights} lights, at most {max} are drawn")]
    TooManyLights { lights: usize, max: usize },
    #[error("no lighting set")]
    NoLighting,
    /// Materials given not one per object.
    #[error("{materials} materials for {objects} objects")]
    MaterialCount { materials: usize, objects: usize },
    #[error("{count} distinct glossy materials, the renderer draws at most {max}")]
    TooManyGlossyMaterials { count: usize, max: usize },
    #[error("the scene has no proxies")]
    NoProxies,
    #[error(
        "proxy `{proxy}` is glossy; the live composite draws diffuse proxies (`hprt render` \
         composites glossy ones)"
    )]
    GlossyProxy { proxy: String },
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake_settings::BakeSettings;
    use crate::camera::Camera;

    #[test]
    fn a_caller_reads_the_numbers_of_the_problem() {
        let bake = BakeSettings {
            samples: 0,
            ..BakeSettings::default()
        };
        let error = bake.validate().unwrap_err();
        assert_eq!(error.what, "bake settings");
        assert!(matches!(
            error.problem,
            SettingsProblem::Samples { samples: 0, max } if max == crate::bake_settings::MAX_SAMPLES
        ));
        let order = BakeSettings {
            order: 0,
            ..BakeSettings::default()
        };
        assert!(matches!(
            order.validate().unwrap_err().problem,
            SettingsProblem::Order(UnsupportedOrder(0))
        ));
    }

    #[test]
    fn the_messages_are_unchanged() {
        let camera = Camera {
            position: Vec3::Z,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 180.0,
            width: 4,
            height: 4,
        };
        let error = camera.validate().unwrap_err();
        assert!(matches!(
            error.problem,
            SettingsProblem::FieldOfView { fov_y_deg } if fov_y_deg == 180.0
        ));
        assert_eq!(
            error.to_string(),
            "invalid camera: fov_y_deg 180 is outside (0, 179)"
        );
        let range = SettingsProblem::OutOfRange {
            quantity: "face size",
            value: 2,
            min: 4,
            max: 1024,
        };
        assert_eq!(range.to_string(), "face size 2 outside 4..=1024");
        let angle = SettingsProblem::AngleOutOfRange {
            quantity: "radius",
            degrees: 50.5,
            max: 45.0,
        };
        assert_eq!(angle.to_string(), "radius 50.5° outside (0, 45]");
    }
}
