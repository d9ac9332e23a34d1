//! The settings: what is refused, and each mode's defaults.

use super::*;

#[test]
fn rejects_bad_settings() {
    for s in [
        DecomposeSettings {
            order: 0,
            ..Default::default()
        },
        DecomposeSettings {
            face_size: 2,
            ..Default::default()
        },
        DecomposeSettings {
            radius_deg: 0.0,
            ..Default::default()
        },
        DecomposeSettings {
            threshold: 1.5,
            ..Default::default()
        },
    ] {
        assert!(Decomposer::new(s).is_err());
    }
}

/// Each mode's defaults come from one place: thesis mode's radius keeps a point source's power
/// (`R = √2 σ`, σ widened by the analysis texel), consistent mode's cap is 8°; `Default` is consistent mode at order 5.
#[test]
fn each_mode_gets_its_own_defaults() {
    let thesis = DecomposeSettings::for_mode(DecomposeMode::Thesis, 3);
    assert_eq!(thesis.order, 3);
    let texel = 90.0 / ANALYSIS_FACE_SIZE as f32;
    let sigma_squared = thesis.smoothing_deg.powi(2) + texel * texel / 12.0;
    assert!((thesis.radius_deg - (2.0 * sigma_squared).sqrt()).abs() < 1e-6);
    assert_eq!(thesis.sh_window(), Window::Hanning);
    let consistent = DecomposeSettings::for_mode(DecomposeMode::Consistent, 5);
    assert_eq!(consistent.radius_deg, 8.0);
    assert_eq!(consistent.sh_window(), Window::None);
    assert_eq!(consistent, DecomposeSettings::default());
}

#[test]
fn more_lights_than_peaks_considered_is_an_error() {
    let settings = DecomposeSettings {
        max_lights: MAX_CANDIDATES + 1,
        ..Default::default()
    };
    let message = Decomposer::new(settings).err().unwrap().to_string();
    assert!(message.contains("at most 24 lights"), "{message}");
}
