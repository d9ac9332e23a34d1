//! What a decomposition is asked for: its mode, SH order, cube size, thresholds and caps.

use super::window::Window;
use foundation::settings::{InvalidSettings, SettingsProblem};

foundation::named_enum! {
    /// How light power and the SH part are formed from the peaks.
    #[derive(serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum DecomposeMode ("decomposition mode") {
        /// Exactly as the thesis: the SH part is the windowed projection of the whole map and a
        /// light's power is `2π(1 − cos R)(λ_i − P(Ξ_i))`.
        Thesis = "thesis",
        /// Energy-consistent: a light's power is the map's excess over the SH part inside its
        /// cap, and the SH part is fitted to the map with that excess removed, so the two
        /// integrate to the map's total.
        Consistent = "consistent",
    }
}

/// Settings the decomposer cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(transparent)]
pub struct DecomposeError(#[from] pub InvalidSettings);

/// Parameters of the decomposition.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DecomposeSettings {
    pub mode: DecomposeMode,
    /// SH order of the polynomial part.
    pub order: usize,
    /// Cube-map face resolution.
    pub face_size: usize,
    /// Subdivision level of the icosahedron (level 4: 2562 vertices, about 4° apart).
    pub ico_level: u32,
    /// Standard deviation of the smoothing Gaussian, in degrees.
    pub smoothing_deg: f32,
    /// Radius R of the SRBFs / light caps, in degrees (see [`DecomposeSettings::default_radius`]).
    pub radius_deg: f32,
    /// Weber fraction: a light is kept while it adds more than this share of the luminance of
    /// the lights before it.
    pub threshold: f32,
    /// Upper bound on the number of lights.
    pub max_lights: usize,
    /// A peak counts only if its residual exceeds this multiple of the map's mean luminance.
    pub min_contrast: f32,
    /// Window of the SH part; `None` uses the mode's default (Hanning for `thesis`, none for
    /// `consistent`, whose SH part no longer contains the sources that ring).
    pub window: Option<Window>,
}

/// Consistent mode at order 5: `DecomposeSettings::for_mode(DecomposeMode::Consistent, 5)`.
impl Default for DecomposeSettings {
    fn default() -> Self {
        Self::for_mode(DecomposeMode::Consistent, 5)
    }
}

/// Face size of the analysis (smoothing, peak search, projection). SH of order ≤ 20 and a
/// smoothing kernel of a few degrees lose nothing at this resolution; larger input maps are
/// box-filtered down to it (solid-angle weighted, so integrals are kept), while light caps are
/// still measured on the full-resolution map.
pub(crate) const ANALYSIS_FACE_SIZE: usize = 64;

/// Most peaks considered per frame (the brightest residual maxima).
pub(crate) const MAX_CANDIDATES: usize = 24;

impl DecomposeSettings {
    /// The defaults of `mode` at SH order `order`: every mode's rules start here.
    pub fn for_mode(mode: DecomposeMode, order: usize) -> Self {
        const SMOOTHING_DEG: f32 = 2.0;
        Self {
            mode,
            order,
            face_size: 64,
            ico_level: 4,
            smoothing_deg: SMOOTHING_DEG,
            radius_deg: Self::default_radius(mode, SMOOTHING_DEG),
            threshold: 0.05,
            max_lights: 8,
            min_contrast: 1.0,
            window: None,
        }
    }

    pub fn validate(&self) -> Result<(), DecomposeError> {
        let invalid = |problem| {
            Err(DecomposeError(InvalidSettings::new(
                "decomposition settings",
                problem,
            )))
        };
        if let Err(e) = foundation::sh::check_order(self.order) {
            return invalid(e.into());
        }
        if !(4..=1024).contains(&self.face_size) {
            return invalid(SettingsProblem::OutOfRange {
                quantity: "face size",
                value: self.face_size as u64,
                min: 4,
                max: 1024,
            });
        }
        if self.ico_level > 7 {
            return invalid(SettingsProblem::AboveMax {
                quantity: "icosahedron level",
                value: self.ico_level as u64,
                max: 7,
            });
        }
        if !(self.radius_deg > 0.0 && self.radius_deg <= 45.0) {
            return invalid(SettingsProblem::AngleOutOfRange {
                quantity: "radius",
                degrees: self.radius_deg,
                max: 45.0,
            });
        }
        if !(self.smoothing_deg > 0.0 && self.smoothing_deg <= 30.0) {
            return invalid(SettingsProblem::AngleOutOfRange {
                quantity: "smoothing",
                degrees: self.smoothing_deg,
                max: 30.0,
            });
        }
        if !(0.0..=1.0).contains(&self.threshold) {
            return invalid(SettingsProblem::NotAFraction {
                quantity: "threshold",
                value: self.threshold,
            });
        }
        if self.min_contrast.is_nan() || self.min_contrast < 0.0 {
            return invalid(SettingsProblem::Negative {
                quantity: "min contrast",
                value: self.min_contrast,
            });
        }
        if self.max_lights > MAX_CANDIDATES {
            return invalid(SettingsProblem::TooManyKeptLights {
                asked: self.max_lights,
                max: MAX_CANDIDATES,
            });
        }
        Ok(())
    }

    /// The default SRBF radius of a mode. `consistent`: a cap of 8°, wide enough for the
    /// bundled maps' suns and lamps. `thesis` leaves R open; its power `2π(1 − cos R) λ` with λ
    /// the Gaussian-smoothed peak gives a point source of power Φ the power `≈ (R²/2σ²) Φ`
    /// (σ: the smoothing), so `R = √2 σ` is the choice that keeps point sources' power. The
    /// smoothing runs on the analysis cube, whose texels (Δ = 90°/64 across) first spread a
    /// point over a box of variance Δ²/12, so σ² there is `σ² + Δ²/12` (4% more at 2°).
    pub fn default_radius(mode: DecomposeMode, smoothing_deg: f32) -> f32 {
        match mode {
            DecomposeMode::Consistent => 8.0,
            DecomposeMode::Thesis => {
                let texel_deg = 90.0 / ANALYSIS_FACE_SIZE as f32;
                (2.0 * (smoothing_deg * smoothing_deg + texel_deg * texel_deg / 12.0)).sqrt()
            }
        }
    }

    /// The window actually applied to the SH part.
    pub(crate) fn sh_window(&self) -> Window {
        self.window.unwrap_or(match self.mode {
            DecomposeMode::Thesis => Window::Hanning,
            DecomposeMode::Consistent => Window::None,
        })
    }
}
