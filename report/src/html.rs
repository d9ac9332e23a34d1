//! `report.html`: one self-contained page (PNGs embedded as base64, plots as inline SVG), so
//! it can be mailed or archived on its own.

use super::{MapReport, MapStatus, MethodResult, Report};
use crate::error::{ReportError, Result};
use crate::methods::per_map_methods;
use base64::Engine;
use std::fmt::Write;
use std::path::Path;

const STYLE: &str = "
body { font-family: system-ui, sans-serif; margin: 2em; color: #222; max-width: 1700px; }
h1 { font-size: 1.5em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 1em 0; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: right; }
th { background: #f3f3f3; } td.name { text-align: left; }
td.best { font-weight: bold; background: #e8f5e9; }
.row { display: flex; flex-wrap: wrap; gap: 0.8em; align-items: flex-start; }
.grid { display: grid; grid-template-columns: repeat(4, minmax(0, 1fr)); gap: 0.8em; margin-bottom: 0.8em; }
.grid img { width: 100%; } svg { max-width: 100%; height: auto; }
figure { margin: 0; } figcaption { font-size: 0.9em; text-align: center; color: #555; }
img { image-rendering: pixelated; max-width: 100%; }
.failed { color: #b00020; } .warning { color: #8a4b00; background: #fff4e0; padding: 0.5em; } tr.noise td { color: #555; font-style: italic; } .note { color: #555; font-size: 0.9em; }
";

/// Escapes text for HTML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `mean ± std` with the digits the errors need; "–" for an empty region.
fn mean_std(mean: f64, std: f64) -> String {
    if mean.is_finite() {
        format!("{mean:.4} ± {std:.4}")
    } else {
        "–".into()
    }
}

fn embedded_png(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(ReportError::file("cannot read", path))?;
    Ok(format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    ))
}

fn figure(html: &mut String, src: &str, caption: &str) {
    let _ = write!(
        html,
        "<figure><img src=\"{src}\" alt=\"{caption}\"><figcaption>{caption}</figcaption></figure>"
    );
}

/// The per-map rows of the Table 5.1-style summary; the lowest error of each statistic bold.
/// Each method's place (1: lowest) by mean error among `methods`; ties share a place.
fn ranks_by_mean(methods: &[MethodResult]) -> Vec<usize> {
    methods
        .iter()
        .map(|m| {
            1 + methods
                .iter()
                .filter(|other| other.stats.mean < m.stats.mean)
                .count()
        })
        .collect()
}

fn summary_table(html: &mut String, maps: &[&MapReport]) {
    // Glossy scenes: the highlight region's column.
    let glossy = maps
        .iter()
        .any(|m| m.methods.iter().any(|x| x.stats.highlight_pixels > 0));
    html.push_str(
        "<table><tr><th>map</th><th>method</th><th>rank</th><th>mean ± std</th><th>shadow mean ± std</th>\
         <th>penumbra mean ± std</th><th>relative RMSE</th><th>relative RMSE, noise-corrected</th><th>lights</th><th>decomposition (ms): first frame / warm</th><th>frame (ms)</th>",
    );
    html.push_str(if glossy {
        "<th>highlight mean ± std</th></tr>"
    } else {
        "</tr>"
    });
    for map in maps {
        map_rows(html, map, glossy);
    }
    html.push_str("</table>");
}

/// A map's rows of the summary: each method's errors, the best of each column marked, then
/// the reference's noise floor.
fn map_rows(html: &mut String, map: &MapReport, glossy: bool) {
    let best = |key: fn(&MethodResult) -> f64| {
        map.methods
            .iter()
            .map(key)
            .filter(|v| v.is_finite())
            .fold(f64::INFINITY, f64::min)
    };
    let best_mean = best(|m| m.stats.mean);
    let best_shadow = best(|m| m.stats.shadow_mean);
    let best_penumbra = best(|m| m.stats.penumbra_mean);
    let best_rmse = best(|m| m.stats.relative_rmse);
    let best_highlight = best(|m| m.stats.highlight_mean);
    let cell = |value: f64, best: f64, text: String| {
        let class = if value == best { " class=\"best\"" } else { "" };
        format!("<td{class}>{text}</td>")
    };
    let ranks = ranks_by_mean(&map.methods);
    for (k, m) in map.methods.iter().enumerate() {
        let s = &m.stats;
        let name = if k == 0 {
            format!(
                "<td class=\"name\" rowspan=\"{}\">{}</td>",
                map.methods.len(),
                escape(&map.name)
            )
        } else {
            String::new()
        };
        let _ = write!(
            html,
            "<tr>{name}<td class=\"name\">{}</td><td>{}</td>{}{}{}{}<td>{:.4}</td><td>{}</td><td>{:.2} / {:.2}</td><td>{:.1}</td>{}</tr>",
            escape(&m.method),
            ranks[k],
            cell(s.mean, best_mean, mean_std(s.mean, s.std)),
            cell(
                s.shadow_mean,
                best_shadow,
                mean_std(s.shadow_mean, s.shadow_std)
            ),
            cell(
                s.penumbra_mean,
                best_penumbra,
                mean_std(s.penumbra_mean, s.penumbra_std)
            ),
            cell(
                s.relative_rmse,
                best_rmse,
                format!("{:.4}", s.relative_rmse)
            ),
            m.relative_rmse_corrected,
            m.lights,
            m.decomposition_ms,
            m.warm_decomposition_ms,
            m.frame_ms,
            if glossy {
                cell(
                    s.highlight_mean,
                    best_highlight,
                    mean_std(s.highlight_mean, s.highlight_std),
                )
            } else {
                String::new()
            },
        );
    }
    if !map.methods.is_empty() {
        noise_row(html, map);
    }
}

/// The row of the reference's noise floor under a map's methods.
fn noise_row(html: &mut String, map: &MapReport) {
    let n = &map.noise;
    let optional = |v: f64| {
        if v.is_finite() {
            format!("{v:.4}")
        } else {
            "–".into()
        }
    };
    let _ = write!(
        html,
        "<tr class=\"noise\"><td class=\"name\" colspan=\"2\">reference noise floor ({} spp)</td><td></td>\
         <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td colspan=\"4\"></td></tr>",
        map.reference_spp,
        optional(n.mean),
        optional(n.shadow_mean),
        optional(n.penumbra_mean),
        optional(n.relative_rmse),
    );
}

fn sweep_table(html: &mut String, map: &MapReport) {
    html.push_str(
        "<table><tr><th>mode</th><th>Weber threshold</th><th>lights</th><th>mean</th>\
         <th>shadow mean</th><th>penumbra mean</th></tr>",
    );
    for (label, points) in &map.sweep {
        for p in points {
            let optional = |v: f64| {
                if v.is_finite() {
                    format!("{v:.4}")
                } else {
                    "–".into()
                }
            };
            let (shadow, penumbra) = (optional(p.shadow_mean), optional(p.penumbra_mean));
            let _ = write!(
                html,
                "<tr><td class=\"name\">{}</td><td>{}</td><td>{}</td><td>{:.4}</td><td>{shadow}</td><td>{penumbra}</td></tr>",
                escape(label),
                p.threshold,
                p.lights,
                p.mean
            );
        }
    }
    html.push_str("</table>");
}

fn map_section(html: &mut String, map: &MapReport, out: &Path) -> Result<()> {
    let dir = out.join(&map.name);
    let _ = write!(
        html,
        "<h2 id=\"{0}\">{0}</h2><p class=\"note\">{1} · exposure {2:.4} · reference {3}</p>",
        escape(&map.name),
        escape(&map.path),
        map.exposure,
        if map.reference_cached {
            format!("{} spp, from the cache", map.reference_spp)
        } else {
            format!(
                "{} spp, rendered in {:.1} s",
                map.reference_spp, map.reference_seconds
            )
        }
    );
    if map.noise_warning {
        let best = map
            .methods
            .iter()
            .map(|m| m.stats.mean)
            .fold(f64::INFINITY, f64::min);
        let _ = write!(
            html,
            "<p class=\"warning\">Warning: the reference's own noise floor ({:.4}) is {:.0}% of \
             the best method's mean error ({best:.4}): on this map the statistics measure the \
             reference as much as the methods. Render it with more samples (<code>--spp</code>, \
             or <code>--target-noise</code>).</p>",
            map.noise.mean,
            100.0 * map.noise.mean / best
        );
    }
    html.push_str("<div class=\"grid\">");
    figure(
        html,
        &embedded_png(&dir.join("reference.png"))?,
        "reference (path traced)",
    );
    for method in per_map_methods() {
        let png = dir.join(format!("{}.png", method.file_stem));
        figure(html, &embedded_png(&png)?, method.name);
    }
    html.push_str(
        "</div><div class=\"grid\"><p class=\"note\">Below each method: its error against the \
         reference, |ΔY| after tone mapping. One scale per map (the 99th percentile of PRT's \
         errors; larger errors saturate); grey pixels see no geometry.</p>",
    );
    for method in per_map_methods() {
        let png = dir.join(format!("error-{}.png", method.file_stem));
        figure(
            html,
            &embedded_png(&png)?,
            &format!("|ΔY| after tone mapping, {}", method.name),
        );
    }
    html.push_str("</div>");
    summary_table(html, &[map]);
    let svg_path = dir.join("threshold.svg");
    let svg =
        std::fs::read_to_string(&svg_path).map_err(ReportError::file("cannot read", &svg_path))?;
    let _ = write!(
        html,
        "<div class=\"row\"><div style=\"flex: 0 1 600px\">{svg}</div><div>"
    );
    sweep_table(html, map);
    html.push_str("</div></div>");
    Ok(())
}

/// The page for `report`, whose images lie under `out`.
pub(crate) fn page(report: &Report, out: &Path) -> Result<String> {
    let mut html = String::new();
    let s = &report.settings;
    let _ = write!(
        html,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>hprt report: {scene}</title><style>{STYLE}</style></head><body>\
         <h1>hprt error report: {scene}</h1>\
         <p>Hybrid (SH polynomial + shadow-mapped directional lights) and plain PRT against a \
         path-traced reference, as in Table 5.1 of the thesis. Errors are \
         |Y(tonemap(test)) − Y(tonemap(reference))| over pixels covered by geometry, one exposure \
         per map; the shadow region is the covered pixels whose direct visibility of the \
         environment is below {threshold}, the penumbra region those whose visibility lies \
         strictly between {low} and {high} (partly lit: where filter widths and source sizes \
         show); in glossy scenes the highlight region is the covered pixels where the \
         reference's specular part (light the first surface's Phong lobe reflects) exceeds the \
         rest; relative RMSE is of linear luminance, relative to the \
         reference's mean. Bold: the lowest error per map.</p>\
         <p class=\"note\">{w}×{h} pixels · reference {spp} paths per pixel, {bounces} bounces, \
         seed {seed} · bake {bake} · adapter {adapter} · frame time: median of {frames} frames</p>",
        scene = escape(&report.scene),
        threshold = report.shadow_visibility_threshold,
        low = report.penumbra_visibility.0,
        high = report.penumbra_visibility.1,
        w = s.width,
        h = s.height,
        spp = s.spp,
        bounces = s.bounces,
        seed = s.seed,
        bake = escape(&report.bake),
        adapter = escape(&report.adapter),
        frames = s.frames,
    );
    if let Some(web) = &report.web {
        let _ = write!(
            html,
            "<p><a href=\"{web}\">The scene in your browser</a>: the hybrid, PRT and the peers \
             drawn live (WebGPU, or WebGL2), the map turned and decomposed in the page. Serve \
             this folder (<code>python3 -m http.server</code>) and open it there.</p>",
            web = escape(web)
        );
    }
    let ok: Vec<&MapReport> = report
        .maps
        .iter()
        .filter(|m| m.status == MapStatus::Ok)
        .collect();
    let failed: Vec<&MapReport> = report
        .maps
        .iter()
        .filter(|m| m.status == MapStatus::Failed)
        .collect();
    if !ok.is_empty() {
        html.push_str("<h2>Summary</h2>");
        summary_table(&mut html, &ok);
    }
    if !failed.is_empty() {
        html.push_str("<h2 class=\"failed\">Maps that failed</h2><ul>");
        for map in &failed {
            let _ = write!(
                html,
                "<li class=\"failed\"><b>{}</b> ({}): {}</li>",
                escape(&map.name),
                escape(&map.path),
                escape(map.error.as_deref().unwrap_or("unknown error"))
            );
        }
        html.push_str("</ul>");
    }
    for map in ok {
        map_section(&mut html, map, out)?;
    }
    html.push_str("</body></html>\n");
    Ok(html)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::ErrorStats;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("<a href=\"x\">&</a>"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&lt;/a&gt;"
        );
    }

    #[test]
    fn methods_rank_by_mean_error_with_ties_sharing_a_place() {
        let result = |mean| MethodResult {
            method: String::new(),
            stats: ErrorStats {
                mean,
                ..ErrorStats::default()
            },
            relative_rmse_corrected: 0.0,
            lights: 0,
            decomposition_ms: 0.0,
            warm_decomposition_ms: 0.0,
            frame_ms: 0.0,
        };
        let methods = [result(0.3), result(0.1), result(0.2), result(0.1)];
        assert_eq!(ranks_by_mean(&methods), [4, 1, 3, 1]);
    }

    #[test]
    fn empty_region_shows_a_dash() {
        assert_eq!(mean_std(f64::NAN, f64::NAN), "–");
        assert_eq!(mean_std(0.01, 0.002), "0.0100 ± 0.0020");
    }
}
