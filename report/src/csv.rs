//! `stats.csv`: one row per map and method.

use super::results::Report;
use crate::error::{ReportError, Result};

/// The columns of `stats.csv`.
const CSV_COLUMNS: [&str; 26] = [
    "map",
    "status",
    "method",
    "mean",
    "std",
    "shadow_mean",
    "shadow_std",
    "penumbra_mean",
    "penumbra_std",
    "relative_rmse",
    "lights",
    "decomposition_ms",
    "frame_ms",
    "covered_pixels",
    "shadow_pixels",
    "penumbra_pixels",
    "relative_rmse_corrected",
    "reference_spp",
    "noise_floor_mean",
    "noise_floor_shadow_mean",
    "noise_floor_relative_rmse",
    "noise_warning",
    "highlight_mean",
    "highlight_std",
    "highlight_pixels",
    "warm_decomposition_ms",
];

pub(super) fn csv_bytes(report: &Report) -> Result<Vec<u8>> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(CSV_COLUMNS)?;
    for map in &report.maps {
        if map.methods.is_empty() {
            // A failed map: its name and status, the other columns empty.
            let mut record = vec![map.name.as_str(), map.status.name()];
            record.resize(CSV_COLUMNS.len(), "");
            writer.write_record(record)?;
        }
        for m in &map.methods {
            let s = &m.stats;
            writer.write_record([
                map.name.clone(),
                map.status.name().to_owned(),
                m.method.clone(),
                format!("{:.6}", s.mean),
                format!("{:.6}", s.std),
                format!("{:.6}", s.shadow_mean),
                format!("{:.6}", s.shadow_std),
                format!("{:.6}", s.penumbra_mean),
                format!("{:.6}", s.penumbra_std),
                format!("{:.6}", s.relative_rmse),
                m.lights.to_string(),
                format!("{:.3}", m.decomposition_ms),
                format!("{:.3}", m.frame_ms),
                s.covered_pixels.to_string(),
                s.shadow_pixels.to_string(),
                s.penumbra_pixels.to_string(),
                format!("{:.6}", m.relative_rmse_corrected),
                map.reference_spp.to_string(),
                format!("{:.6}", map.noise.mean),
                format!("{:.6}", map.noise.shadow_mean),
                format!("{:.6}", map.noise.relative_rmse),
                map.noise_warning.to_string(),
                format!("{:.6}", s.highlight_mean),
                format!("{:.6}", s.highlight_std),
                s.highlight_pixels.to_string(),
                format!("{:.3}", m.warm_decomposition_ms),
            ])?;
        }
    }
    writer
        .into_inner()
        .map_err(|e| ReportError::Csv(e.to_string()))
}
