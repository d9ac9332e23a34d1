//! The true composite of a composite report: the scene path-traced with and without its
//! virtual objects in two independent halves, cached like the reports' references (so a
//! second report, or one after `hprt report --shard`, reads it instead of rendering it).

use crate::ReportSettings;
use crate::error::Result;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::{RgbImageF32, read_exr, write_exr};
use foundation::infra::cache::{CacheKey, Entry, EntryKind};
use foundation::infra::progress::NoProgress;
use foundation::scene::{Backplate, Scene, load_backplate_image};
use reference::composite::{PixelKind, composite, render_composite};
use reference::{EnvironmentLight, ReferenceSettings};
use std::path::PathBuf;

/// The regions' masks: object pixels, and the truth's changed region.
pub(crate) struct Regions {
    pub(crate) object: Vec<bool>,
    pub(crate) changed: Vec<bool>,
}

/// The true composite from two independent halves (each half the paths): the composite of
/// their mean renders, the regions, and the two halves' composites (for the noise).
pub(crate) struct Truth {
    pub(crate) image: RgbImageF32,
    pub(crate) regions: Regions,
    pub(crate) halves: [RgbImageF32; 2],
    /// Read from the cache, not rendered.
    pub(crate) cached: bool,
}

/// The path traces a truth is made of: per half, the scene and the proxies alone; and each
/// pixel's kind.
struct Renders {
    with: [RgbImageF32; 2],
    without: [RgbImageF32; 2],
    kinds: Vec<PixelKind>,
}

fn photograph(scene: &Scene, camera: &Camera) -> Result<Option<RgbImageF32>> {
    Ok(match &scene.backplate {
        Some(Backplate::Image(path)) => {
            Some(load_backplate_image(path, camera.width, camera.height)?)
        }
        _ => None,
    })
}

fn half_seeds(seed: u64) -> [u64; 2] {
    [seed, seed ^ 0x9e37_79b9_7f4a_7c15]
}

fn render(
    scene: &Scene,
    camera: &Camera,
    light: &EnvironmentLight,
    settings: &ReportSettings,
) -> Renders {
    let halves: Vec<_> = half_seeds(settings.seed)
        .into_iter()
        .map(|seed| {
            let reference = ReferenceSettings {
                sampler: settings.sampler,
                ..ReferenceSettings::new((settings.spp / 2).max(1), settings.bounces, seed)
            };
            render_composite(
                &scene.geometry,
                light,
                camera,
                &reference,
                None,
                &NoProgress,
            )
        })
        .collect();
    let kinds = halves[0].composite.kinds.clone();
    let [a, b]: [_; 2] = halves.try_into().ok().expect("two halves were rendered");
    Renders {
        with: [a.with_objects.radiance, b.with_objects.radiance],
        without: [a.without_objects.radiance, b.without_objects.radiance],
        kinds,
    }
}

/// The true composites' renders in the cache. Version 2: keys from the one key function
/// (`foundation::infra::cache`).
const COMPOSITES: EntryKind = EntryKind {
    folder: "composites",
    tag: "hprt composite truth v4 (near floor on backs only, no negative weight)",
};

/// The cache key: everything the renders depend on (the backplate is applied after).
fn key(
    scene: &Scene,
    camera: &Camera,
    map: &EnvMap,
    rotation_deg: f32,
    settings: &ReportSettings,
) -> Result<CacheKey> {
    CacheKey::try_new(COMPOSITES, |k| {
        super::truth::view_inputs(k, scene, camera, map, rotation_deg)?;
        k.u64(settings.bounces as u64)
            .u64(settings.seed)
            .u64(((settings.spp / 2).max(1)) as u64)
            .str(settings.sampler.name());
        Ok(())
    })
}

/// A cache entry's files: five images, and a marker written last that makes them an entry
/// (each written to a temporary name and renamed into place; their contents depend only on
/// the key, so concurrent writers on a shared cache write the same bytes).
struct EntryFiles {
    entry: Entry,
    images: [PathBuf; 5],
}

impl EntryFiles {
    fn new(key: &CacheKey) -> Self {
        let entry = key.entry();
        Self {
            images: ["with0", "with1", "without0", "without1", "kinds"]
                .map(|kind| entry.file(&format!("{kind}.exr"))),
            entry,
        }
    }

    fn load(&self) -> Result<Renders> {
        let [w0, w1, o0, o1, kinds] = self.images.clone().map(|p| read_exr(&p));
        let kinds = kinds?
            .pixels
            .iter()
            .map(|p| match p.x as u8 {
                1 => PixelKind::Object,
                2 => PixelKind::Proxy,
                _ => PixelKind::Background,
            })
            .collect();
        Ok(Renders {
            with: [w0?, w1?],
            without: [o0?, o1?],
            kinds,
        })
    }

    fn store(&self, renders: &Renders) -> Result<()> {
        self.entry.create_folder()?;
        let (w, h) = (renders.with[0].width, renders.with[0].height);
        let kinds: Vec<f32> = renders
            .kinds
            .iter()
            .map(|k| match k {
                PixelKind::Background => 0.0,
                PixelKind::Object => 1.0,
                PixelKind::Proxy => 2.0,
            })
            .collect();
        let kinds = RgbImageF32::from_grey(w, h, &kinds);
        let images = [
            &renders.with[0],
            &renders.with[1],
            &renders.without[0],
            &renders.without[1],
            &kinds,
        ];
        for (path, image) in self.images.iter().zip(images) {
            write_exr(path, image)?;
        }
        self.entry.commit(b"{\"complete\": true}")?;
        Ok(())
    }
}

/// The renders of the truth: cached, or rendered and cached.
fn renders(
    scene: &Scene,
    camera: &Camera,
    map: &EnvMap,
    rotation_deg: f32,
    settings: &ReportSettings,
) -> Result<(Renders, bool)> {
    let entry = EntryFiles::new(&key(scene, camera, map, rotation_deg, settings)?);
    if entry.entry.marker().exists() {
        match entry.load() {
            Ok(renders) => return Ok((renders, true)),
            Err(e) => {
                log::warn!("a cached composite truth is unreadable ({e:#}); rendering it again")
            }
        }
    }
    let light = EnvironmentLight::new(map, rotation_deg);
    let renders = render(scene, camera, &light, settings);
    entry.store(&renders)?;
    Ok((renders, false))
}

/// The true composite of `scene` under `map` turned by `rotation_deg`, at `settings`' samples.
pub(crate) fn true_composite(
    scene: &Scene,
    camera: &Camera,
    map: &EnvMap,
    rotation_deg: f32,
    settings: &ReportSettings,
) -> Result<Truth> {
    let backplate = match photograph(scene, camera)? {
        Some(image) => image,
        None => {
            let light = EnvironmentLight::new(map, rotation_deg);
            reference::composite::environment_backplate(&light, camera)
        }
    };
    let (r, cached) = renders(scene, camera, map, rotation_deg, settings)?;
    let mean = |a: &RgbImageF32, b: &RgbImageF32| {
        let pixels = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x + *y) * 0.5);
        RgbImageF32::new(a.width, a.height, pixels.collect())
    };
    let with = mean(&r.with[0], &r.with[1]);
    let without = mean(&r.without[0], &r.without[1]);
    let truth = composite(&r.kinds, &with, &without, &backplate);
    let regions = Regions {
        object: r.kinds.iter().map(|k| *k == PixelKind::Object).collect(),
        changed: truth.changed.clone(),
    };
    let halves = [0, 1].map(|k| composite(&r.kinds, &r.with[k], &r.without[k], &backplate).image);
    Ok(Truth {
        image: truth.image,
        regions,
        halves,
        cached,
    })
}
