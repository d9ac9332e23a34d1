//! What a reference render is of (a [`JobSpec`]: the inputs as given), that job loaded and
//! checked (a [`ReferenceJob`]), and the files it writes: shared by one run, a shard and the
//! merge.

use crate::cli::{EnvironmentArgs, ImageSizeArgs};
use crate::maps::default_exposure;
use crate::outputs::{check_outputs, open_outputs, scene_inputs, write_outputs};
use crate::support::{TerminalProgress, load_scene, with_threads};
use anyhow::Context;
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::envmap::Layout;
use foundation::image_io::{RgbImageF32, exr_bytes, png_bytes, to_display_rgb8};
use foundation::infra::atomic_file::AtomicOutput;
use foundation::scene::{Backplate, load_backplate_image};
use reference::composite::{Composite, PixelKind};
use reference::{self, EnvironmentLight, ReferenceImage, ReferenceSettings, SamplerKind};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// What a reference render is of: every input as given, paths made absolute (the merge
/// reloads them, perhaps from another folder).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobSpec {
    pub scene: PathBuf,
    pub env: Option<PathBuf>,
    pub layout: Option<Layout>,
    pub rotate: Option<f32>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: u32,
    pub bounces: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
}

/// The files a reference writes (one run, or the merge of a sharded one).
#[derive(Args)]
pub struct OutputFiles {
    /// Tone-mapping exposure of the PNG (default: 0.5 / the map's mean luminance).
    #[arg(long, value_parser = crate::cli::parse_positive)]
    pub exposure: Option<f32>,
    /// Output linear OpenEXR; with --shard, the folder the band goes into.
    #[arg(short, long, required = true)]
    pub output: Option<PathBuf>,
    /// Also write a tone-mapped PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Also write coverage and direct-visibility images (EXR and PNG) into this folder; for a
    /// scene with a [backplate], also the masks of the objects, the proxies and the changed
    /// region, and the layers a compositor redoes the composite from (the objects, the shadow
    /// ratio).
    #[arg(long)]
    pub aux: Option<PathBuf>,
}

/// A single-channel image as grey EXR and PNG files' bytes.
fn grey_files(width: usize, height: usize, values: &[f32]) -> anyhow::Result<[Vec<u8>; 2]> {
    let image = RgbImageF32::from_grey(width, height, values);
    // Linear 0..1 shown directly (exposure chosen so that tonemap(1) is near white).
    let rgb: Vec<u8> = values
        .iter()
        .flat_map(|v| [(v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8; 3])
        .collect();
    Ok([exr_bytes(&image)?, png_bytes(&rgb, width, height)?])
}

/// The file names `--aux DIR` adds: coverage and direct visibility, and for a composite its
/// masks (object, proxy, changed region) and layers (the objects, the shadow ratio).
fn aux_files(dir: &std::path::Path, composite: bool) -> Vec<PathBuf> {
    let mut names = vec!["coverage", "visibility"];
    if composite {
        names.extend(["object_mask", "proxy_mask", "changed_mask"]);
    }
    let mut files: Vec<PathBuf> = names
        .into_iter()
        .flat_map(|name| ["exr", "png"].map(|ext| dir.join(format!("{name}.{ext}"))))
        .collect();
    if composite {
        files.extend(["objects.exr", "ratio.exr"].map(|name| dir.join(name)));
    }
    files
}

/// Everything a reference render depends on, loaded and checked.
pub struct ReferenceJob {
    pub(super) scene: foundation::scene::Scene,
    pub(super) env: crate::maps::ChosenEnvironment,
    pub(super) camera: foundation::camera::Camera,
    pub(super) settings: ReferenceSettings,
    /// A [backplate] image (`None` for "environment", or without a [backplate]).
    pub(super) backplate: Option<RgbImageF32>,
}

impl ReferenceJob {
    pub fn prepare(spec: &JobSpec) -> anyhow::Result<Self> {
        let scene = load_scene(&spec.scene)?;
        let environment = EnvironmentArgs {
            env: spec.env.clone(),
            layout: spec.layout,
            rotate: spec.rotate,
        };
        let env = environment.choose(&scene)?;
        let size = ImageSizeArgs {
            width: spec.width,
            height: spec.height,
        };
        let camera = size.camera(&scene)?;
        let settings = ReferenceSettings {
            sampler: spec.sampler,
            ..ReferenceSettings::new(spec.spp, spec.bounces, spec.seed)
        };
        settings.validate()?;
        let backplate = match &scene.backplate {
            Some(Backplate::Image(path)) => Some(
                load_backplate_image(path, camera.width, camera.height)
                    .with_context(|| format!("scene {}", scene.path.display()))?,
            ),
            _ => None,
        };
        if scene.backplate.is_some() && !scene.geometry.has_proxies() {
            eprintln!(
                "warning: {}: [backplate] but no proxy (role = \"proxy\"): the objects are \
                 composited without shadows on the picture",
                scene.path.display()
            );
        }
        Ok(Self {
            scene,
            env,
            camera,
            settings,
            backplate,
        })
    }

    pub(super) fn composite(&self) -> bool {
        self.scene.backplate.is_some()
    }

    /// Checks and opens the outputs before any work.
    pub(super) fn open_outputs(
        &self,
        files: &OutputFiles,
        output: &std::path::Path,
        more_inputs: &[&std::path::Path],
    ) -> anyhow::Result<Vec<AtomicOutput>> {
        let mut inputs = scene_inputs(&self.scene, &[Some(&self.env.path)]);
        inputs.extend_from_slice(more_inputs);
        let aux = files
            .aux
            .as_deref()
            .map(|dir| aux_files(dir, self.composite()))
            .unwrap_or_default();
        let mut outputs = vec![("-o", Some(output)), ("--png", files.png.as_deref())];
        outputs.extend(aux.iter().map(|p| ("--aux", Some(p.as_path()))));
        check_outputs(&inputs, &outputs)?;
        if let Some(dir) = &files.aux {
            crate::support::create_folder(dir)?;
        }
        open_outputs(&outputs)
    }

    pub(super) fn announce(&self) {
        println!(
            "{}: {}x{}, {} spp, {} bounces, lit by {} rotated {}°{}",
            self.scene.name,
            self.camera.width,
            self.camera.height,
            self.settings.spp,
            self.settings.bounces,
            self.env.path.display(),
            self.env.rotation_deg,
            if self.composite() {
                ", composited (with and without the objects)"
            } else {
                ""
            }
        );
    }

    /// Path-traces rows `rows`: the whole scene, and for a composite the proxies alone.
    pub(super) fn render_rows(
        &self,
        rows: &[usize],
        threads: Option<usize>,
    ) -> anyhow::Result<(ReferenceImage, Option<ReferenceImage>)> {
        with_threads(threads, || {
            let light = EnvironmentLight::new(&self.env.loaded.map, self.env.rotation_deg);
            let progress = TerminalProgress::new("rendering rows");
            let (geometry, camera, settings) = (&self.scene.geometry, &self.camera, &self.settings);
            if self.composite() {
                let [with, without] = reference::composite::render_composite_rows(
                    geometry, &light, camera, settings, rows, &progress,
                );
                (with, Some(without))
            } else {
                let bvh = SceneBvh::build(&geometry.mesh);
                let image = reference::render_rows(
                    geometry, &bvh, &light, camera, settings, rows, &progress,
                );
                (image, None)
            }
        })
    }

    pub(super) fn render_whole(
        &self,
        threads: Option<usize>,
    ) -> anyhow::Result<(ReferenceImage, Option<Composite>)> {
        let rows: Vec<usize> = (0..self.camera.height as usize).collect();
        let (with, without) = self.render_rows(&rows, threads)?;
        Ok(self.finish(with, without))
    }

    /// The image and, for a composite, the composite of the two whole traces, warning when
    /// the objects change none of the proxies.
    pub(super) fn finish(
        &self,
        with: ReferenceImage,
        without: Option<ReferenceImage>,
    ) -> (ReferenceImage, Option<Composite>) {
        let Some(without) = without else {
            return (with, None);
        };
        let light = EnvironmentLight::new(&self.env.loaded.map, self.env.rotation_deg);
        let out = reference::composite::composite_renders(
            &self.scene.geometry,
            &light,
            &self.camera,
            with,
            without,
            self.backplate.as_ref(),
        );
        let c = &out.composite;
        if self.scene.geometry.has_proxies() && !c.changed.iter().any(|c| *c) {
            eprintln!(
                "warning: {}: the objects change no proxy pixel by more than {}% (is anything \
                 above the proxies, and in view?)",
                self.scene.path.display(),
                100.0 * reference::composite::CHANGED_THRESHOLD
            );
        }
        (out.with_objects, Some(out.composite))
    }

    /// Writes the image (and --png, --aux) into the opened `files`.
    pub(super) fn write(
        &self,
        options: &OutputFiles,
        output: &std::path::Path,
        files: Vec<AtomicOutput>,
        image: &ReferenceImage,
        composite: Option<&Composite>,
    ) -> anyhow::Result<()> {
        let exposure = options
            .exposure
            .unwrap_or_else(|| default_exposure(&self.env.loaded.map));
        let bytes = output_bytes(options, image, composite, exposure)?;
        write_outputs(files, bytes)?;
        let camera = &self.camera;
        let megapixel_samples =
            camera.width as f64 * camera.height as f64 * self.settings.spp as f64 / 1e6;
        println!(
            "rendered in {:.2} s: {:.2} M rays/s, {:.3} s per megapixel per sample; wrote {}",
            image.stats.seconds,
            image.stats.rays_per_second() / 1e6,
            image.stats.seconds / megapixel_samples,
            output.display()
        );
        Ok(())
    }
}

/// The bytes of every output, in the order of [`aux_files`] after `-o` and `--png`.
fn output_bytes(
    args: &OutputFiles,
    image: &ReferenceImage,
    composite: Option<&Composite>,
    exposure: f32,
) -> anyhow::Result<Vec<Vec<u8>>> {
    let shown = composite.map_or(&image.radiance, |c| &c.image);
    let mut bytes = vec![exr_bytes(shown).context("the render failed")?];
    let (w, h) = (shown.width, shown.height);
    if args.png.is_some() {
        bytes.push(png_bytes(&to_display_rgb8(shown, exposure), w, h)?);
    }
    if args.aux.is_some() {
        bytes.extend(grey_files(w, h, &image.coverage)?);
        bytes.extend(grey_files(w, h, &image.visibility)?);
        if let Some(c) = composite {
            bytes.extend(grey_files(w, h, &c.mask(PixelKind::Object))?);
            bytes.extend(grey_files(w, h, &c.mask(PixelKind::Proxy))?);
            bytes.extend(grey_files(w, h, &c.changed_mask())?);
            bytes.push(exr_bytes(&c.objects)?);
            bytes.push(exr_bytes(&c.ratio)?);
        }
    }
    Ok(bytes)
}
