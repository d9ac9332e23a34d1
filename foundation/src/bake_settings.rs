//! What a bake computes: SH order, rays per vertex, bounces, seed. Its own module because the
//! scene file carries the defaults and the bake consumes them.

use crate::settings::{InvalidSettings, SettingsProblem};
use crate::sh;

/// Settings of a bake; a scene file's `[bake]` table gives the defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BakeSettings {
    /// SH order (bands `0..order`).
    pub order: usize,
    /// Hemisphere samples (rays) per vertex.
    pub samples: u32,
    /// Indirect bounces of the Neumann series (0 = shadowed direct lighting only).
    pub bounces: u32,
    /// Seed of the per-vertex sample rotations.
    pub seed: u64,
}

impl Default for BakeSettings {
    fn default() -> Self {
        Self {
            order: 5,
            samples: 1024,
            bounces: 3,
            seed: 0,
        }
    }
}

/// Most rays per vertex a bake accepts.
pub const MAX_SAMPLES: u32 = 1 << 20;
/// Most bounces a bake accepts.
pub const MAX_BOUNCES: u32 = 256;

impl BakeSettings {
    pub fn validate(&self) -> Result<(), InvalidSettings> {
        let invalid = |problem| InvalidSettings::new("bake settings", problem);
        sh::check_order(self.order).map_err(|e| invalid(e.into()))?;
        if self.samples == 0 || self.samples > MAX_SAMPLES {
            return Err(invalid(SettingsProblem::Samples {
                samples: self.samples,
                max: MAX_SAMPLES,
            }));
        }
        if self.bounces > MAX_BOUNCES {
            return Err(invalid(SettingsProblem::Bounces {
                bounces: self.bounces,
                max: MAX_BOUNCES,
            }));
        }
        Ok(())
    }
}
