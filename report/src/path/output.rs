//! The path report's files: `report.html`, `path.json`, `path.csv`, the plots along the path
//! and the animated GIF; and its summary on the terminal.

use super::results::{PathReport, PositionResult};
use crate::error::{ReportError, Result};
use crate::figures;
use crate::methods::series_by_method;
use base64::Engine;
use foundation::infra::atomic_file::write_atomic;
use std::fmt::Write;
use std::path::Path;

/// What the GIF shows, left to right.
pub(super) const GIF_PANELS: &str = "one probe | nearest probe | fused | path-traced truth";

pub(super) fn write_outputs(
    report: &PathReport,
    gif_frames: &[Vec<u8>],
    (gif_width, gif_height): (u32, u32),
    out: &Path,
) -> Result<()> {
    let series = |value: &dyn Fn(&PositionResult) -> Option<f64>| -> Vec<(String, Vec<f64>)> {
        let names = report.methods.iter().map(|m| m.method.as_str());
        let rows: Vec<&[PositionResult]> = (report.per_position.iter())
            .map(|p| p.methods.as_slice())
            .collect();
        series_by_method(names, &rows, |r| &r.method, value)
    };
    let plots = [
        (
            "model_error.svg",
            figures::time_plot(
                "error over the model, along the path",
                "mean error (model pixels)",
                &series(&|r| Some(r.model)),
            )?,
        ),
        (
            "changed_error.svg",
            figures::time_plot(
                "error over the changed region (the model's shadows), along the path",
                "mean error (changed pixels)",
                &series(&|r| Some(r.changed)),
            )?,
        ),
        (
            "temporal.svg",
            figures::time_plot(
                "temporal error (changes between positions against the truth's)",
                "mean temporal error",
                &series(&|r| r.temporal),
            )?,
        ),
    ];
    let gif = figures::animated_gif(gif_frames, gif_width, gif_height, 120)?;
    for (name, svg) in &plots {
        write_atomic(&out.join(name), svg.as_bytes())?;
    }
    write_atomic(&out.join("path.gif"), &gif)?;
    write_atomic(
        &out.join("path.json"),
        serde_json::to_string_pretty(report)?.as_bytes(),
    )?;
    write_atomic(&out.join("path.csv"), &csv_bytes(report)?)?;
    let svgs: Vec<&str> = plots.iter().map(|(_, svg)| svg.as_str()).collect();
    write_atomic(
        &out.join("report.html"),
        page(report, &gif, &svgs)?.as_bytes(),
    )?;
    Ok(())
}

fn csv_bytes(report: &PathReport) -> Result<Vec<u8>> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record([
        "frame",
        "x",
        "y",
        "z",
        "intersects_room",
        "method",
        "model",
        "changed",
        "temporal",
        "popping",
        "lights",
    ])?;
    for p in &report.per_position {
        for r in &p.methods {
            let optional = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
            csv.write_record([
                p.frame.to_string(),
                p.centre[0].to_string(),
                p.centre[1].to_string(),
                p.centre[2].to_string(),
                p.intersects_room.to_string(),
                r.method.clone(),
                format!("{:.6}", r.model),
                format!("{:.6}", r.changed),
                optional(r.temporal),
                r.popping.to_string(),
                r.lights.to_string(),
            ])?;
        }
    }
    csv.into_inner()
        .map_err(|e| ReportError::Csv(e.to_string()))
}

fn page(report: &PathReport, gif: &[u8], svgs: &[&str]) -> Result<String> {
    let mut html = super::super::sequence::output::page_head("hprt path report");
    writeln!(
        html,
        "<h1>A model carried through a room</h1><p>Scene <code>{}</code>, {} positions of its \
         <code>[path]</code>, {}×{}; the truth path-traced with the model at each position \
         ({} paths per pixel, seed {}), the true probes at {} paths per texel. Each method's \
         lighting drives the same hybrid (SH part and shadow-mapped lights, the lights followed \
         from position to position) and the same composite into the empty room's truth \
         (CONVENTIONS.md, \"Light probes\").</p>",
        report.scene,
        report.frames,
        report.settings.width,
        report.settings.height,
        report.settings.spp,
        report.settings.seed,
        report.probe_spp
    )?;
    writeln!(
        html,
        "<table><tr><th>method</th><th>model error</th><th>changed-region error</th>\
         <th>temporal error</th><th>popping positions</th></tr>"
    )?;
    for m in &report.methods {
        writeln!(
            html,
            "<tr><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td></tr>",
            m.method,
            m.mean_model_error,
            m.mean_changed_error,
            m.mean_temporal_error,
            m.popping_frames
        )?;
    }
    writeln!(
        html,
        "</table><p>The fused map beats one probe and the nearest probe on the model at {} of \
         {} positions; its mean model error is {:.2}× the true probe's.</p>",
        report.fused_beats_probes, report.frames, report.fused_over_true
    )?;
    let through: Vec<String> = (report.per_position.iter())
        .filter(|p| p.intersects_room)
        .map(|p| p.frame.to_string())
        .collect();
    if !through.is_empty() {
        writeln!(
            html,
            "<p><b>Warning:</b> the model passes through the room's proxies at frames {}.</p>",
            through.join(", ")
        )?;
    }
    writeln!(
        html,
        "<h2>{GIF_PANELS}</h2><img src=\"data:image/gif;base64,{}\">",
        base64::engine::general_purpose::STANDARD.encode(gif)
    )?;
    writeln!(html, "<h2>Along the path</h2>{}", svgs.join(""))?;
    writeln!(
        html,
        "<p>Errors: mean absolute difference of tone-mapped luminance. Temporal error and \
         popping as in the sequence reports: a popping position's temporal error is more than \
         {} times its neighbours' median (at the ends, their trend if larger) and above {}. \
         Per position: <code>path.csv</code>, \
         <code>path.json</code>.</p></body></html>",
        report.pop_spike, report.pop_floor
    )?;
    Ok(html)
}

/// The path report's table and verdict, a line each.
pub fn summary_lines(report: &PathReport) -> Vec<String> {
    let mut lines = vec![String::new()];
    lines.push(format!(
        "{:<20} {:>10} {:>10} {:>10} {:>9}",
        "method", "model", "changed", "temporal", "popping"
    ));
    for m in &report.methods {
        lines.push(format!(
            "{:<20} {:>10.4} {:>10.4} {:>10.4} {:>9}",
            m.method,
            m.mean_model_error,
            m.mean_changed_error,
            m.mean_temporal_error,
            m.popping_frames
        ));
    }
    lines.push(format!(
        "the fused map beats one probe and the nearest probe on the model at {} of {} positions; \
         its model error is {:.2}x the true probe's",
        report.fused_beats_probes, report.frames, report.fused_over_true
    ));
    lines
}
