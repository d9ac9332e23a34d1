//! The sequence report's files: `report.html`, `sequence.json`, `sequence.csv`, the plots and
//! the animated GIF; and its summary on the terminal.

use super::results::{FrameResult, SequenceReport};
use crate::error::{ReportError, Result};
use crate::figures;
use crate::methods::series_by_method;
use base64::Engine;
use foundation::image_io::{RgbImageF32, to_display_rgb8};
use foundation::infra::atomic_file::write_atomic;
use std::fmt::Write;
use std::path::Path;

/// The start of a report page of plots and tables, up to its body.
pub(crate) fn page_head(title: &str) -> String {
    format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>{title}</title>\
         <style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:3px 8px;\
         text-align:right}}</style></head><body>\n"
    )
}

/// Tone-mapped images next to each other, as 8-bit RGB rows.
pub(crate) fn side_by_side(images: &[&RgbImageF32], exposure: f32) -> Vec<u8> {
    let parts: Vec<Vec<u8>> = images
        .iter()
        .map(|image| to_display_rgb8(image, exposure))
        .collect();
    let (w, h) = (images[0].width, images[0].height);
    let mut rgb = Vec::with_capacity(w * h * 3 * images.len());
    for row in 0..h {
        for part in &parts {
            rgb.extend_from_slice(&part[row * w * 3..(row + 1) * w * 3]);
        }
    }
    rgb
}

pub(super) fn write_outputs(
    report: &SequenceReport,
    gif_frames: &[Vec<u8>],
    gif_width: u32,
    gif_height: u32,
    out: &Path,
) -> Result<()> {
    let series = |value: &dyn Fn(&FrameResult) -> Option<f64>| -> Vec<(String, Vec<f64>)> {
        let names = report.methods.iter().map(|m| m.method.as_str());
        let rows: Vec<&[FrameResult]> = (report.per_frame.iter())
            .map(|f| f.methods.as_slice())
            .collect();
        series_by_method(names, &rows, |r| &r.method, value)
    };
    let error_svg = figures::time_plot(
        "error against the reference",
        "mean error (covered pixels)",
        &series(&|r| Some(r.mean)),
    )?;
    let temporal_svg = figures::time_plot(
        "temporal error (frame differences against the reference's)",
        "mean temporal error",
        &series(&|r| r.temporal),
    )?;
    let gif = figures::animated_gif(gif_frames, gif_width, gif_height, 120)?;
    write_atomic(&out.join("error.svg"), error_svg.as_bytes())?;
    write_atomic(&out.join("temporal.svg"), temporal_svg.as_bytes())?;
    write_atomic(&out.join("sequence.gif"), &gif)?;
    write_atomic(
        &out.join("sequence.json"),
        serde_json::to_string_pretty(report)?.as_bytes(),
    )?;
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record([
        "frame",
        "method",
        "mean",
        "shadow_mean",
        "penumbra_mean",
        "temporal",
        "popping",
        "lights",
    ])?;
    for frame in &report.per_frame {
        for r in &frame.methods {
            let optional = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
            csv.write_record([
                frame.frame.to_string(),
                r.method.clone(),
                format!("{:.6}", r.mean),
                format!("{:.6}", r.shadow_mean),
                format!("{:.6}", r.penumbra_mean),
                optional(r.temporal),
                r.popping.to_string(),
                r.lights.to_string(),
            ])?;
        }
    }
    write_atomic(
        &out.join("sequence.csv"),
        &csv.into_inner()
            .map_err(|e| ReportError::Csv(e.to_string()))?,
    )?;
    let html = page(report, &gif, &error_svg, &temporal_svg)?;
    write_atomic(&out.join("report.html"), html.as_bytes())?;
    Ok(())
}

fn page(
    report: &SequenceReport,
    gif: &[u8],
    error_svg: &str,
    temporal_svg: &str,
) -> Result<String> {
    let mut html = page_head("hprt sequence report");
    writeln!(
        html,
        "<h1>Sequence report</h1><p>Scene <code>{}</code>, sequence <code>{}</code>, {} frames, \
         {}×{}, reference {} paths per pixel (seed {} in every frame).</p>",
        report.scene,
        report.sequence,
        report.frames,
        report.settings.width,
        report.settings.height,
        report.settings.spp,
        report.settings.seed
    )?;
    writeln!(
        html,
        "<table><tr><th>method</th><th>mean error</th><th>mean temporal error</th>\
         <th>popping frames</th><th>light-count changes</th></tr>"
    )?;
    for m in &report.methods {
        writeln!(
            html,
            "<tr><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td><td>{}</td></tr>",
            m.method, m.mean_error, m.mean_temporal_error, m.popping_frames, m.light_count_changes
        )?;
    }
    writeln!(html, "</table>")?;
    writeln!(
        html,
        "<p>Temporal error: the mean over covered pixels of |(M(t) − M(t−1)) − (R(t) − \
         R(t−1))| of tone-mapped luminance. A popping frame: its temporal error is more than {} \
         times the median of its neighbours' (3 frames on each side; at the first and last \
         frame, their trend if larger) and above {} (CONVENTIONS.md, \"Temporal \
         statistics\").</p>",
        report.pop_spike, report.pop_floor
    )?;
    if let Some(sun) = report.sun_worst {
        writeln!(
            html,
            "<p>The tracked hybrid's light against the true sun, worst frame: {:.3}° apart, \
             power off by {:.2}%.</p>",
            sun.angle_deg,
            100.0 * sun.power_error
        )?;
    }
    writeln!(
        html,
        "<h2>hybrid/tracked | prt | reference</h2><img src=\"data:image/gif;base64,{}\">",
        base64::engine::general_purpose::STANDARD.encode(gif)
    )?;
    writeln!(html, "<h2>Over time</h2>{error_svg}{temporal_svg}")?;
    writeln!(
        html,
        "<p>Per frame: <code>sequence.csv</code>, <code>sequence.json</code>.</p></body></html>"
    )?;
    Ok(html)
}

/// The sequence report's table, a line each.
pub fn summary_lines(report: &SequenceReport) -> Vec<String> {
    let mut lines = vec![String::new()];
    lines.push(format!(
        "{:<18} {:>10} {:>14} {:>9} {:>14}",
        "method", "mean", "temporal", "popping", "count changes"
    ));
    for m in &report.methods {
        lines.push(format!(
            "{:<18} {:>10.4} {:>14.4} {:>9} {:>14}",
            m.method, m.mean_error, m.mean_temporal_error, m.popping_frames, m.light_count_changes
        ));
    }
    if let Some(sun) = report.sun_worst {
        lines.push(format!(
            "sun: the tracked light is at most {:.3}° from the sun, its power at most {:.2}% off",
            sun.angle_deg,
            100.0 * sun.power_error
        ));
    }
    lines
}
