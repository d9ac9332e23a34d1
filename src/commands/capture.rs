//! `hprt capture`: an HDR environment map from ordinary photographs (oriented shots or a
//! mirror ball at several exposures), with its confidence and a preview.

use crate::outputs::{check_outputs, open_outputs, write_outputs};
use anyhow::Context;
use capture::{Assembled, AssemblySettings, InverseResponse};
use clap::Args;
use foundation::image_io::{RgbImageF32, exr_bytes, png_bytes};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CaptureArgs {
    /// Capture description (TOML): [[shot]] entries (image, exposure, yaw, pitch, roll, fov,
    /// k1, k2) or [[ball]] entries (image, exposure, centre, radius, fov, yaw, pitch,
    /// reflectance); paths relative to it. Exposure times are read from each image's EXIF
    /// when it records one; a ball without centre and radius is found. See README.
    pub description: PathBuf,
    /// The linear equirectangular map (EXR), relative radiance (the middle level of the
    /// recovered response is 1).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Width of the map (its height is half).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(64..=8192))]
    pub width: u32,
    /// Use this inverse response (CSV: level,r,g,b; 256 rows) instead of recovering one.
    #[arg(long)]
    pub response: Option<PathBuf>,
    /// Write the inverse response used (CSV, as --response reads it), with its spread on a
    /// `# spread` line.
    #[arg(long)]
    pub save_response: Option<PathBuf>,
    /// Confidence image (PNG): grey from 0 (filled hole) to 1; red where every exposure clipped;
    /// yellow where the exposures disagree by more than 10% through the response.
    #[arg(long)]
    pub coverage: Option<PathBuf>,
    /// Tone-mapped preview (PNG) with filled holes tinted blue and clipped texels red.
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// Multiply the radiance by this (an absolute scale: from a white card or a measured
    /// illuminance).
    #[arg(long, default_value_t = 1.0, value_parser = crate::cli::parse_finite)]
    pub scale: f32,
}

pub fn run(args: CaptureArgs) -> anyhow::Result<()> {
    let outputs = [
        ("-o", Some(args.output.as_path())),
        ("--save-response", args.save_response.as_deref()),
        ("--coverage", args.coverage.as_deref()),
        ("--preview", args.preview.as_deref()),
    ];
    let mut inputs: Vec<&Path> = vec![args.description.as_path()];
    inputs.extend(args.response.as_deref());
    check_outputs(&inputs, &outputs)?;
    if args.scale <= 0.0 {
        anyhow::bail!("--scale {} must be positive", args.scale);
    }
    let files = open_outputs(&outputs)?;
    let loaded = capture::load_capture(&args.description)?;
    for note in &loaded.notes {
        log::warn!("{note}");
    }
    let photos = loaded.photos;
    // The photographs are inputs too: no output may be written over one.
    inputs.extend(photos.iter().map(|p| p.path.as_path()));
    check_outputs(&inputs, &outputs)?;
    let width = args.width as usize;
    let settings = AssemblySettings {
        width,
        height: width / 2,
        ..Default::default()
    };
    let response = match &args.response {
        Some(path) => capture::read_response(path)?,
        None => {
            warn_of_equal_steps(&args.description, &photos);
            capture::calibrate(&photos, &settings).with_context(|| {
                format!(
                    "{}: cannot recover the response",
                    args.description.display()
                )
            })?
        }
    };
    let mut captured = capture::assemble(&photos, &response, &settings);
    captured.scale(args.scale);
    check_radiance(&args, &captured, &photos, &response)?;
    report(&args.description, &captured, photos.len());
    let spread = captured.response_spread();
    report_spread(&args.description, spread, args.response.as_deref());
    let image = RgbImageF32::new(width, width / 2, captured.map.texels().to_vec());
    let mut bytes = vec![exr_bytes(&image)?];
    if args.save_response.is_some() {
        bytes.push(capture::response_csv(&response, spread).into_bytes());
    }
    if args.coverage.is_some() {
        bytes.push(png_bytes(&captured.coverage_rgb(), width, width / 2)?);
    }
    if args.preview.is_some() {
        bytes.push(png_bytes(&captured.preview_rgb(&image), width, width / 2)?);
    }
    write_outputs(files, bytes)
}

/// Refuses a map whose radiance overflowed, naming what multiplied to it: the exposures, the
/// response, the reflectance and `--scale` (each is bounded where it enters, but not their
/// product).
fn check_radiance(
    args: &CaptureArgs,
    captured: &Assembled,
    photos: &[capture::Photo],
    response: &InverseResponse,
) -> anyhow::Result<()> {
    let bad = captured.overflowed_texels();
    if bad == 0 {
        return Ok(());
    }
    let times = photos.iter().map(|p| p.time);
    let (shortest, longest) = times.fold((f32::MAX, 0.0f32), |(a, b), t| (a.min(t), b.max(t)));
    let top = response
        .curves
        .iter()
        .flatten()
        .fold(0.0f32, |m, v| m.max(*v));
    anyhow::bail!(
        "{}: {bad} texels of the map overflowed: the exposures ({shortest} to {longest} s), the \
         response (up to {top}{}), the balls' reflectance and --scale {} divide or multiply to \
         more than a float holds; check them",
        args.description.display(),
        args.response
            .as_ref()
            .map(|p| format!(", from {}", p.display()))
            .unwrap_or_default(),
        args.scale
    )
}

/// What the capture resolved, and a warning for what no exposure did.
fn report(description: &Path, captured: &Assembled, photos: usize) {
    let (clipped_sr, clipped_share) = captured.saturation();
    println!(
        "{}: {photos} photographs; {:.1}% of the sphere resolved, {:.1}% filled from its \
         surroundings",
        description.display(),
        100.0 * captured.covered_fraction(),
        100.0 * captured.filled_fraction(),
    );
    if clipped_sr > 0.0 {
        log::warn!(
            "{}: {clipped_sr:.4} sr were clipped in every exposure (marked red in --coverage); \
             at their least possible radiance they carry {:.1}% of the map's power, and their \
             true power may be far larger: add shorter exposures (an unclipped sun needs about \
             1/10000 of the exposure of the sky)",
            description.display(),
            100.0 * clipped_share
        );
    }
}

/// A warning where the exposures step by one ratio: the response recovered from them is the
/// priors' guess within one step, and no figure printed here can show it wrong.
fn warn_of_equal_steps(description: &Path, photos: &[capture::Photo]) {
    let times: Vec<f32> = photos.iter().map(|p| p.time).collect();
    if let Some(warning) = capture::equal_steps_warning(&times) {
        log::warn!("{}: {warning} with --response", description.display());
    }
}

/// The response's spread beside the map, and a warning where it shows the response is poor.
fn report_spread(description: &Path, spread: Option<f32>, given: Option<&Path>) {
    let Some(spread) = spread else {
        println!(
            "{}: no texel was read by two exposures above the darkest levels (at or above level \
             32): the response's spread is unknown (exposures too far apart to check it)",
            description.display()
        );
        return;
    };
    let source = given.map_or("recovered".to_owned(), |p| format!("from {}", p.display()));
    println!(
        "{}: response ({source}) spread {:.1}%: the median texel's exposures, through it, \
         disagree by that much (RMS of the log)",
        description.display(),
        100.0 * spread
    );
    if spread > capture::SPREAD_WARNING {
        log::warn!(
            "{}: the response's ({source}) spread is {:.1}%, above {:.0}%: the response does not \
             fit these photographs (a camera that changed its tone curve, white balance or ISO \
             between exposures, misregistered shots, or a wrong --response); texels that \
             disagree most are yellow in --coverage",
            description.display(),
            100.0 * spread,
            100.0 * capture::SPREAD_WARNING
        );
    }
}
