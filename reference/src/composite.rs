//! The true composite (CONVENTIONS.md, "Compositing"): differential rendering in the ratio
//! form (Debevec 1998; the form of Blender's shadow catcher). The scene is path-traced with
//! and without its virtual objects, with the same seed; on proxy pixels the backplate is
//! multiplied by `L(with) / L(without)`, object pixels show the rendered objects, and every
//! other pixel keeps the backplate.

use crate::{EnvironmentLight, NO_HIT, ReferenceImage, ReferenceSettings, RenderError};
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::color::{Rgb, luminance};
use foundation::image_io::RgbImageF32;
use foundation::infra::progress::Progress;
use foundation::scene::{ObjectRole, SceneMesh};

pub use foundation::composite::{
    CHANGED_THRESHOLD, MAX_RATIO, PixelKind, RATIO_FLOOR, composite_pixel, shadow_ratio,
};

/// A composite and its layers, for a compositor to redo it.
#[derive(Debug, Clone)]
pub struct Composite {
    pub image: RgbImageF32,
    /// The rendered radiance on object pixels, zero elsewhere.
    pub objects: RgbImageF32,
    /// The shadow ratio on proxy pixels, one elsewhere.
    pub ratio: RgbImageF32,
    pub kinds: Vec<PixelKind>,
    /// Proxy pixels whose luminance ratio differs from 1 by more than [`CHANGED_THRESHOLD`].
    pub changed: Vec<bool>,
}

impl Composite {
    /// Whether the pixel is of `kind`, as 1 or 0 (a mask image).
    pub fn mask(&self, kind: PixelKind) -> Vec<f32> {
        self.kinds.iter().map(|k| f32::from(*k == kind)).collect()
    }

    pub fn changed_mask(&self) -> Vec<f32> {
        self.changed.iter().map(|c| f32::from(*c)).collect()
    }
}

/// The kind of each pixel, from the triangle of `geometry` its centre's ray hits first
/// (`primary`, [`NO_HIT`] for none: [`ReferenceImage::primary`]).
pub fn pixel_kinds(geometry: &SceneMesh, primary: &[u32]) -> Vec<PixelKind> {
    let roles = geometry.triangle_roles();
    primary
        .iter()
        .map(|&t| match t {
            NO_HIT => PixelKind::Background,
            t => match roles[t as usize] {
                ObjectRole::Object => PixelKind::Object,
                ObjectRole::Proxy => PixelKind::Proxy,
            },
        })
        .collect()
}

/// Composites `with` (the whole scene) into `backplate`, the proxies' change measured against
/// `without` (the proxies alone, same camera and seed).
pub fn composite(
    kinds: &[PixelKind],
    with: &RgbImageF32,
    without: &RgbImageF32,
    backplate: &RgbImageF32,
) -> Composite {
    let proxies: Vec<usize> = (0..kinds.len())
        .filter(|&i| kinds[i] == PixelKind::Proxy)
        .collect();
    let mean_without = proxies
        .iter()
        .map(|&i| f64::from(luminance(without.pixels[i])))
        .sum::<f64>()
        / proxies.len().max(1) as f64;
    let floor = RATIO_FLOOR * mean_without as f32;
    let ratio: Vec<Rgb> = (0..kinds.len())
        .map(|i| match kinds[i] {
            PixelKind::Proxy => shadow_ratio(with.pixels[i], without.pixels[i], floor),
            _ => Rgb::ONE,
        })
        .collect();
    composite_with_ratio(kinds, with, &ratio, backplate)
}

/// Composites `rendered` (its object pixels) into `backplate` with a given ratio per pixel
/// on the proxies (the ratio form's, or a peer's own account of the objects' effect on them,
/// such as ambient occlusion); other pixels' ratios are ignored.
pub fn composite_with_ratio(
    kinds: &[PixelKind],
    rendered: &RgbImageF32,
    ratio: &[Rgb],
    backplate: &RgbImageF32,
) -> Composite {
    let (w, h) = (rendered.width, rendered.height);
    let ratio: Vec<Rgb> = kinds
        .iter()
        .zip(ratio)
        .map(|(k, r)| if *k == PixelKind::Proxy { *r } else { Rgb::ONE })
        .collect();
    let image = (0..kinds.len())
        .map(|i| composite_pixel(kinds[i], backplate.pixels[i], rendered.pixels[i], ratio[i]))
        .collect();
    let objects = (0..kinds.len())
        .map(|i| match kinds[i] {
            PixelKind::Object => rendered.pixels[i],
            _ => Rgb::ZERO,
        })
        .collect();
    Composite {
        image: RgbImageF32::new(w, h, image),
        objects: RgbImageF32::new(w, h, objects),
        changed: ratio
            .iter()
            .map(|r| (luminance(*r) - 1.0).abs() > CHANGED_THRESHOLD)
            .collect(),
        ratio: RgbImageF32::new(w, h, ratio),
        kinds: kinds.to_vec(),
    }
}

/// The environment map as `camera` sees it: the backplate of the HDRI workflow.
pub fn environment_backplate(light: &EnvironmentLight, camera: &Camera) -> RgbImageF32 {
    let basis = camera.basis();
    let pixels = (0..camera.height)
        .flat_map(|j| (0..camera.width).map(move |i| (i, j)))
        .map(|(i, j)| light.radiance(camera.pixel_direction(&basis, i, j)))
        .collect();
    RgbImageF32::new(camera.width as usize, camera.height as usize, pixels)
}

/// The two path traces of a composite and the composite itself.
pub struct CompositeRender {
    pub composite: Composite,
    /// The whole scene: virtual objects and proxies.
    pub with_objects: ReferenceImage,
    /// The proxies alone, with the same seed.
    pub without_objects: ReferenceImage,
}

/// Path-traces `geometry` with and without its virtual objects (same settings and seed) and
/// composites the objects into `backplate` (`None`: the environment map as the camera sees
/// it). `progress` counts the rows of both renders; it cannot cancel this form
/// ([`try_render_composite`] can).
pub fn render_composite(
    geometry: &SceneMesh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    backplate: Option<&RgbImageF32>,
    progress: &dyn Progress,
) -> CompositeRender {
    let progress = crate::NeverCancelled(progress);
    try_render_composite(geometry, light, camera, settings, backplate, &progress)
        .expect("never cancelled")
}

/// [`render_composite`], stopped with [`RenderError::Cancelled`] when `progress` answers
/// [`Progress::cancelled`] (asked before each row of either render).
pub fn try_render_composite(
    geometry: &SceneMesh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    backplate: Option<&RgbImageF32>,
    progress: &dyn Progress,
) -> Result<CompositeRender, RenderError> {
    let rows: Vec<usize> = (0..camera.height as usize).collect();
    let [with_objects, without_objects] =
        try_render_composite_rows(geometry, light, camera, settings, &rows, progress)?;
    Ok(composite_renders(
        geometry,
        light,
        camera,
        with_objects,
        without_objects,
        backplate,
    ))
}

/// The rows `rows` of both path traces of [`render_composite`]: the whole scene, and the
/// proxies alone. `progress` cannot cancel this form ([`try_render_composite_rows`] can).
pub fn render_composite_rows(
    geometry: &SceneMesh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    rows: &[usize],
    progress: &dyn Progress,
) -> [ReferenceImage; 2] {
    let progress = crate::NeverCancelled(progress);
    try_render_composite_rows(geometry, light, camera, settings, rows, &progress)
        .expect("never cancelled")
}

/// [`render_composite_rows`], stopped with [`RenderError::Cancelled`] when `progress` answers
/// [`Progress::cancelled`].
pub fn try_render_composite_rows(
    geometry: &SceneMesh,
    light: &EnvironmentLight,
    camera: &Camera,
    settings: &ReferenceSettings,
    rows: &[usize],
    progress: &dyn Progress,
) -> Result<[ReferenceImage; 2], RenderError> {
    let proxies = geometry.of_role(ObjectRole::Proxy);
    let trace = |scene: &SceneMesh| {
        let bvh = SceneBvh::build(&scene.mesh);
        crate::try_render_rows(scene, &bvh, light, camera, settings, rows, progress)
    };
    Ok([trace(geometry)?, trace(&proxies)?])
}

/// The composite of the two whole path traces of [`render_composite`] into `backplate`
/// (`None`: the environment map as the camera sees it).
pub fn composite_renders(
    geometry: &SceneMesh,
    light: &EnvironmentLight,
    camera: &Camera,
    with_objects: ReferenceImage,
    without_objects: ReferenceImage,
    backplate: Option<&RgbImageF32>,
) -> CompositeRender {
    let environment;
    let backplate = match backplate {
        Some(image) => image,
        None => {
            environment = environment_backplate(light, camera);
            &environment
        }
    };
    let kinds = pixel_kinds(geometry, &with_objects.primary);
    let composite = composite(
        &kinds,
        &with_objects.radiance,
        &without_objects.radiance,
        backplate,
    );
    CompositeRender {
        composite,
        with_objects,
        without_objects,
    }
}

#[cfg(test)]
mod tests;
