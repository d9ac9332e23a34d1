//! The report's figures, drawn with plotters: error heat maps with a scale bar (PNG) and the
//! error-against-threshold plots (SVG).

use crate::error::{ReportError, Result};
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::sync::Once;

/// Registers the font plotters draws text with (egui's bundled Ubuntu Light), once.
fn font() -> &'static str {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // The bytes are a valid font shipped with egui; failure would be a packaging bug.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
    "sans-serif"
}

/// Width of the scale bar area to the right of a heat map.
const BAR_AREA: u32 = 120;

/// The error image as a colour-mapped PNG (viridis, 0 at dark blue, `max` and above at
/// yellow), pixels without geometry grey, and a labelled scale bar. Returns the PNG bytes.
pub fn heat_map(
    errors: &[f32],
    covered: &[bool],
    width: u32,
    height: u32,
    max: f32,
    title: &str,
) -> Result<Vec<u8>> {
    let (w, h) = (width + BAR_AREA, height.max(120));
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) as usize;
            let colour = if covered[i] {
                let c = ViridisRGB::get_color_normalized(errors[i].min(max), 0.0, max);
                [c.0, c.1, c.2]
            } else {
                [128, 128, 128]
            };
            let o = ((y * w + x) * 3) as usize;
            rgb[o..o + 3].copy_from_slice(&colour);
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let bar = root.margin(8, 8, width as i32 + 10, 0);
        let (bar_w, bar_h) = (14i32, h as i32 - 40);
        let top = 30;
        for k in 0..bar_h {
            let value = max * (1.0 - k as f32 / bar_h as f32);
            let c = ViridisRGB::get_color_normalized(value, 0.0, max);
            bar.draw(&Rectangle::new(
                [(0, top + k), (bar_w, top + k + 1)],
                c.filled(),
            ))?;
        }
        let style = (font(), 12).into_font().color(&BLACK);
        for tick in 0..=4 {
            let value = max * tick as f32 / 4.0;
            let y = top + bar_h - (bar_h as f32 * tick as f32 / 4.0) as i32;
            let label = if tick == 4 {
                format!("≥{value:.3}")
            } else {
                format!("{value:.3}")
            };
            bar.draw(&Text::new(label, (bar_w + 4, y - 6), style.clone()))?;
        }
        bar.draw(&Text::new(title.to_owned(), (0, 4), style))?;
        root.present()?;
    }
    Ok(foundation::image_io::png_bytes(
        &rgb, w as usize, h as usize,
    )?)
}

/// Tick values 1, 2, 5 × 10^k inside `[low, high]`: a log axis shows only whole decades
/// otherwise, and the errors often span less than one.
fn log_ticks(low: f64, high: f64) -> Vec<f64> {
    let mut ticks = Vec::new();
    let mut decade = 10f64.powf(low.log10().floor());
    while decade <= high {
        for m in [1.0, 2.0, 5.0] {
            let t = m * decade;
            if t >= low && t <= high {
                ticks.push(t);
            }
        }
        decade *= 10.0;
    }
    ticks
}

/// One curve of the threshold plot.
pub struct Curve {
    pub label: String,
    /// `(Weber threshold, mean error, number of lights)`.
    pub points: Vec<(f32, f64, usize)>,
}

/// Mean error against the Weber threshold, each point labelled with its number of lights, and
/// the PRT error as a horizontal line. Returns SVG text.
pub fn threshold_plot(title: &str, curves: &[Curve], prt_error: f64) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (600, 300)).into_drawing_area();
        root.fill(&WHITE)?;
        let (low, high) = error_range(curves, prt_error);
        let thresholds = curves.iter().flat_map(|c| c.points.iter().map(|p| p.0));
        let last = thresholds.fold(0.0f32, f32::max).max(0.05);
        // Room on the right for the legend, clear of the curves.
        let right = last * 1.6;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (font(), 16))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(
                0f32..right,
                (low..high)
                    .log_scale()
                    .with_key_points(log_ticks(low, high)),
            )?;
        chart
            .configure_mesh()
            .x_desc("Weber threshold")
            .y_desc("mean error (covered pixels)")
            .y_label_formatter(&|v| format!("{v:.3}"))
            .label_style((font(), 12))
            .axis_desc_style((font(), 12))
            .draw()?;
        let palette = [
            RGBColor(200, 60, 40),
            RGBColor(40, 110, 200),
            RGBColor(40, 160, 90),
        ];
        for (k, curve) in curves.iter().enumerate() {
            let colour = palette[k % palette.len()];
            chart
                .draw_series(LineSeries::new(
                    curve.points.iter().map(|p| (p.0, p.1)),
                    colour.stroke_width(2),
                ))?
                .label(curve.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart.draw_series(curve.points.iter().map(|p| {
                EmptyElement::at((p.0, p.1))
                    + Circle::new((0, 0), 3, colour.filled())
                    + Text::new(
                        format!("{}", p.2),
                        (4, -14),
                        (font(), 11).into_font().color(&colour),
                    )
            }))?;
        }
        chart
            .draw_series(LineSeries::new(
                [(0.0, prt_error), (last, prt_error)],
                BLACK.stroke_width(1),
            ))?
            .label("prt")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((font(), 12))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
    }
    Ok(svg)
}

/// The error axis of [`threshold_plot`], on a log scale (the thesis mode's errors can be ten
/// times the others'): every finite positive error inside, with room above for the labels.
fn error_range(curves: &[Curve], prt_error: f64) -> (f64, f64) {
    let errors: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.1))
        .chain([prt_error])
        .filter(|e| e.is_finite() && *e > 0.0)
        .collect();
    let high = errors.iter().copied().fold(1e-6, f64::max) * 1.6;
    let low = errors.iter().copied().fold(high, f64::min) / 1.3;
    (low, high)
}

/// Values over the frames of a sequence, one line per method. Returns SVG text.
pub fn time_plot(title: &str, y_label: &str, series: &[(String, Vec<f64>)]) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (600, 300)).into_drawing_area();
        root.fill(&WHITE)?;
        let frames = series
            .iter()
            .map(|(_, v)| v.len())
            .max()
            .unwrap_or(1)
            .max(2);
        let high = series
            .iter()
            .flat_map(|(_, v)| v.iter().copied())
            .filter(|v| v.is_finite())
            .fold(1e-6, f64::max)
            * 1.15;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (font(), 16))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(0usize..frames - 1, 0.0..high)?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc(y_label)
            .y_label_formatter(&|v| format!("{v:.3}"))
            .label_style((font(), 12))
            .axis_desc_style((font(), 12))
            .draw()?;
        let palette = [
            RGBColor(0, 0, 0),
            RGBColor(200, 60, 40),
            RGBColor(40, 110, 200),
            RGBColor(40, 160, 90),
        ];
        for (k, (label, values)) in series.iter().enumerate() {
            let colour = palette[k % palette.len()];
            chart
                .draw_series(LineSeries::new(
                    values
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.is_finite())
                        .map(|(i, v)| (i, *v)),
                    colour.stroke_width(2),
                ))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((font(), 12))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
    }
    Ok(svg)
}

/// An animated GIF of `frames` (8-bit RGB, `width × height` each), `delay_ms` per frame,
/// looping.
pub fn animated_gif(frames: &[Vec<u8>], width: u32, height: u32, delay_ms: u32) -> Result<Vec<u8>> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let mut bytes = Vec::new();
    {
        let mut encoder = GifEncoder::new_with_speed(&mut bytes, 10);
        encoder.set_repeat(Repeat::Infinite)?;
        for rgb in frames {
            let rgba: Vec<u8> = rgb
                .chunks_exact(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect();
            let buffer = image::RgbaImage::from_raw(width, height, rgba)
                .ok_or_else(|| ReportError::Figure("a GIF frame of the wrong size".into()))?;
            encoder.encode_frame(image::Frame::from_parts(
                buffer,
                0,
                0,
                image::Delay::from_numer_denom_ms(delay_ms, 1),
            ))?;
        }
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_map_has_the_image_and_the_bar() {
        let errors = vec![0.0, 0.05, 0.1, 0.2];
        let png = heat_map(&errors, &[true, true, true, false], 2, 2, 0.1, "prt").unwrap();
        let image = image::load_from_memory(&png).unwrap().into_rgb8();
        assert_eq!(image.width(), 2 + BAR_AREA);
        // Uncovered pixels are grey; a zero error is viridis' dark purple.
        assert_eq!(image.get_pixel(1, 1).0, [128, 128, 128]);
        assert!(image.get_pixel(0, 0).0[0] < 100);
    }

    #[test]
    fn log_ticks_follow_the_1_2_5_sequence() {
        let ticks = log_ticks(0.004, 0.07);
        let expected = [0.005, 0.01, 0.02, 0.05];
        assert_eq!(ticks.len(), expected.len());
        for (t, e) in ticks.iter().zip(expected) {
            assert!((t - e).abs() < 1e-12, "{ticks:?}");
        }
    }

    #[test]
    fn threshold_plot_is_svg_with_the_labels() {
        let curve = Curve {
            label: "hybrid/consistent".into(),
            points: vec![(0.0, 0.01, 8), (0.1, 0.012, 2), (0.5, 0.02, 1)],
        };
        let svg = threshold_plot("sunrise", &[curve], 0.03).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("hybrid/consistent") && svg.contains("prt")
        );
    }
}
