//! Turning a map's lighting: the SH part rotated band by band ([`ShRotation`]) and the lights'
//! directions turned, so a turning map keeps exactly the same lights.

use crate::decompose::Decomposition;
use crate::light::DirectionalLight;
use foundation::Rgb;
use foundation::sh::ShCoeffs;
use foundation::sh::rotation::ShRotation;
use glam::{Mat3, Quat};

/// `sh` of a function turned by `orientation`.
pub(crate) fn rotate_sh(sh: &ShCoeffs<Rgb>, orientation: Quat) -> ShCoeffs<Rgb> {
    if orientation == Quat::IDENTITY {
        return sh.clone();
    }
    ShRotation::new(Mat3::from_quat(orientation), sh.order())
        .expect("an ShCoeffs always has a supported order")
        .rotate(sh)
}

/// A decomposition of a map turned by `orientation`: the same lights, turned, and the SH part
/// rotated.
pub(crate) fn rotate_decomposition(base: &Decomposition, orientation: Quat) -> Decomposition {
    Decomposition {
        sh: rotate_sh(&base.sh, orientation),
        lights: base
            .lights
            .iter()
            .map(|l| DirectionalLight {
                direction: (orientation * l.direction).normalize(),
                ..*l
            })
            .collect(),
        total_power: base.total_power,
        candidates: base.candidates,
    }
}
