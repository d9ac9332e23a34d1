//! Furnace tests, convergence and determinism of the reference renderer; glossy surfaces in
//! `glossy`.

use super::*;
use foundation::envmap::EnvMap;
use foundation::mesh::{TriangleMesh, box_mesh, sphere_mesh};
use glam::Vec3;

mod glossy;
mod metallic_roughness;

fn scene_of(objects: &[(&TriangleMesh, Rgb)]) -> SceneMesh {
    let mut s = SceneMesh::default();
    for (i, (mesh, albedo)) in objects.iter().enumerate() {
        s.push_object(format!("o{i}"), mesh, *albedo);
    }
    s
}

fn camera(position: Vec3, target: Vec3, size: u32) -> Camera {
    Camera {
        position,
        target,
        up: Vec3::Y,
        fov_y_deg: 40.0,
        width: size,
        height: size,
    }
}

fn render_simple(
    geometry: &SceneMesh,
    map: &EnvMap,
    cam: &Camera,
    spp: u32,
    bounces: u32,
    seed: u64,
) -> ReferenceImage {
    let settings = ReferenceSettings::new(spp, bounces, seed);
    render_with(geometry, map, cam, &settings)
}

fn render_with(
    geometry: &SceneMesh,
    map: &EnvMap,
    cam: &Camera,
    settings: &ReferenceSettings,
) -> ReferenceImage {
    let bvh = SceneBvh::build(&geometry.mesh);
    let light = EnvironmentLight::new(map, 0.0);
    render(
        geometry,
        &bvh,
        &light,
        cam,
        settings,
        &foundation::infra::progress::NoProgress,
    )
}

fn covered_mean(image: &ReferenceImage) -> Rgb {
    let (sum, n) = image
        .radiance
        .pixels
        .iter()
        .zip(&image.coverage)
        .filter(|(_, c)| **c > 0.0)
        .fold((Rgb::ZERO, 0), |(s, n), (p, _)| (s + *p, n + 1));
    sum / n as f32
}

#[test]
fn furnace_sphere_reflects_its_albedo() {
    let albedo = Rgb::new(0.8, 0.5, 0.3);
    let geometry = scene_of(&[(&sphere_mesh(Vec3::ZERO, 1.0, 4), albedo)]);
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let cam = camera(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, 48);
    let image = render_simple(&geometry, &map, &cam, 16, 3, 1);
    let mean = covered_mean(&image);
    assert!(
        ((mean - albedo) / albedo).abs().max_element() < 0.005,
        "{mean}"
    );
    // Uncovered pixels show the environment; a convex sphere sees its whole sky, except for
    // the few directions below a facet that its smooth normal still counts as above.
    assert!(image.coverage.contains(&0.0));
    let covered: Vec<f32> = image
        .visibility
        .iter()
        .zip(&image.coverage)
        .filter(|(_, c)| **c > 0.0)
        .map(|(v, _)| *v)
        .collect();
    let mean_visibility = covered.iter().sum::<f32>() / covered.len() as f32;
    assert!(mean_visibility > 0.995, "{mean_visibility}");
}

/// An open box seen from above through its missing top.
fn open_box() -> TriangleMesh {
    let outer = box_mesh(
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 1.5, 1.0),
        [4, 4, 4],
        [false, false, true, false, false, false],
    );
    // Turn it inside out so the walls face the interior.
    TriangleMesh {
        positions: outer.positions.clone(),
        normals: outer.normals.iter().map(|n| -*n).collect(),
        triangles: outer.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
        uvs: Vec::new(),
        tangents: Vec::new(),
    }
}

#[test]
fn white_furnace_concave_scene_renders_one() {
    let geometry = scene_of(&[(&open_box(), Rgb::ONE)]);
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let cam = camera(Vec3::new(0.0, 4.0, 0.01), Vec3::ZERO, 32);
    let image = render_simple(&geometry, &map, &cam, 32, 64, 2);
    let mean = covered_mean(&image).y;
    assert!((mean - 1.0).abs() < 0.01, "{mean}");
    // The floor of the box really is occluded.
    let centre = (16 * 32 + 16) as usize;
    assert!(
        image.coverage[centre] == 1.0 && image.visibility[centre] < 0.6,
        "{}",
        image.visibility[centre]
    );
}

fn sphere_on_plane() -> SceneMesh {
    let plane = box_mesh(
        Vec3::new(-3.0, -0.2, -3.0),
        Vec3::new(3.0, 0.0, 3.0),
        [1, 1, 1],
        [false; 6],
    );
    scene_of(&[
        (
            &sphere_mesh(Vec3::new(0.0, 1.0, 0.0), 1.0, 3),
            Rgb::splat(0.7),
        ),
        (&plane, Rgb::new(0.6, 0.5, 0.4)),
    ])
}

fn sunny_map() -> EnvMap {
    EnvMap::from_fn(128, 64, 2, |w| {
        let sun = if w.dot(Vec3::new(0.4, 0.8, 0.45).normalize()) > 0.995 {
            300.0
        } else {
            0.0
        };
        Rgb::new(0.3, 0.4, 0.6) * (0.5 + w.y.max(0.0)) + Rgb::splat(sun)
    })
}

#[test]
fn same_image_whatever_the_thread_count() {
    let geometry = sphere_on_plane();
    let map = sunny_map();
    let cam = camera(Vec3::new(2.0, 3.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 24);
    let in_pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_simple(&geometry, &map, &cam, 8, 2, 7))
    };
    let (a, b) = (in_pool(1), in_pool(3));
    assert_eq!(a.radiance, b.radiance);
    assert_eq!(a.visibility, b.visibility);
    assert_ne!(
        render_simple(&geometry, &map, &cam, 8, 2, 8).radiance,
        a.radiance
    );
}

/// Independent samples: the error falls as 1/√spp. Sobol points: faster, and below the
/// independent sampler's at every count.
#[test]
fn error_falls_as_one_over_root_spp_and_faster_with_sobol() {
    let geometry = sphere_on_plane();
    let map = sunny_map();
    let cam = camera(Vec3::new(2.0, 3.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 20);
    let truth = render_simple(&geometry, &map, &cam, 4096, 2, 100);
    let rmse = |spp: u32, sampler: SamplerKind| {
        // Average the squared error over several seeds to tame its own noise.
        let mut total = 0.0f64;
        for seed in 0..4 {
            let settings = ReferenceSettings {
                sampler,
                ..ReferenceSettings::new(spp, 2, seed)
            };
            let image = render_with(&geometry, &map, &cam, &settings);
            total += image
                .radiance
                .pixels
                .iter()
                .zip(&truth.radiance.pixels)
                .map(|(a, b)| (*a - *b).length_squared() as f64)
                .sum::<f64>();
        }
        total.sqrt()
    };
    let counts = [4, 16, 64];
    let errors: Vec<f64> = counts
        .iter()
        .map(|&spp| rmse(spp, SamplerKind::Independent))
        .collect();
    for pair in errors.windows(2) {
        // 4x the samples: the error should halve (allow 1.6-2.5, the truth has noise too).
        let ratio = pair[0] / pair[1];
        assert!((1.6..2.5).contains(&ratio), "errors {errors:?}");
    }
    let sobol: Vec<f64> = counts
        .iter()
        .map(|&spp| rmse(spp, SamplerKind::Sobol))
        .collect();
    println!("independent {errors:?}, sobol {sobol:?}");
    for (s, e) in sobol.iter().zip(&errors) {
        assert!(s < e, "sobol {sobol:?} vs independent {errors:?}");
    }
    assert!(sobol[0] / sobol[2] > 4.5, "sobol {sobol:?}");
}

/// A pass that continues another (`first_sample`) averages with it into the same image as
/// one pass of all the samples, for both samplers.
#[test]
fn passes_continue_each_other() {
    let geometry = sphere_on_plane();
    let map = sunny_map();
    let cam = camera(Vec3::new(2.0, 3.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 12);
    for sampler in [SamplerKind::Sobol, SamplerKind::Independent] {
        let whole = ReferenceSettings {
            sampler,
            ..ReferenceSettings::new(12, 1, 3)
        };
        let first = ReferenceSettings { spp: 4, ..whole };
        let rest = ReferenceSettings {
            spp: 8,
            first_sample: 4,
            ..whole
        };
        let [whole, first, rest] =
            [whole, first, rest].map(|s| render_with(&geometry, &map, &cam, &s));
        // Sobol samples are indexed: samples 0-3 and 4-11 are samples 0-11. Independent
        // passes draw from other streams, so only the statistics agree.
        if sampler == SamplerKind::Sobol {
            for ((w, a), b) in whole
                .radiance
                .pixels
                .iter()
                .zip(&first.radiance.pixels)
                .zip(&rest.radiance.pixels)
            {
                let merged = (*a * 4.0 + *b * 8.0) / 12.0;
                let tolerance = 1e-5 * w.max_element().max(1.0);
                assert!(
                    (merged - *w).abs().max_element() < tolerance,
                    "{merged} vs {w}"
                );
            }
        }
        // The continuation draws new numbers: it is not the first pass again.
        assert_ne!(first.radiance, rest.radiance);
    }
}

#[test]
fn shadows_show_in_the_visibility_image() {
    let geometry = sphere_on_plane();
    let map = sunny_map();
    // Look straight down on the plane: the sphere's shadow falls opposite the sun.
    let cam = camera(Vec3::new(0.0, 8.0, 0.01), Vec3::ZERO, 40);
    let image = render_simple(&geometry, &map, &cam, 32, 0, 3);
    let min = image.visibility.iter().cloned().fold(1.0f32, f32::min);
    assert!(min < 0.3, "a hard sun shadow: {min}");
}

/// A probe inside the white furnace's open box sees 1 everywhere (the walls' radiance and
/// the sky through the top), and its distances are the box's; a probe under a sunny sky sees
/// the map itself, bit for bit, wherever it sees out.
#[test]
fn probes_see_the_furnace_and_the_sky() {
    let no_progress = &foundation::infra::progress::NoProgress;
    let geometry = scene_of(&[(&open_box(), Rgb::ONE)]);
    let bvh = SceneBvh::build(&geometry.mesh);
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let light = EnvironmentLight::new(&map, 0.0);
    let settings = ReferenceSettings::new(16, 64, 3);
    let at = Vec3::new(0.2, 0.7, -0.1);
    let (probe, stats) = render_probe(
        &geometry,
        &bvh,
        &light,
        at,
        (64, 32),
        &settings,
        no_progress,
    );
    assert!(stats.rays > 64 * 32 * 16);
    let texels = probe.radiance.texels();
    let mean = texels.iter().map(|t| t.y).sum::<f32>() / texels.len() as f32;
    assert!((mean - 1.0).abs() < 0.01, "furnace probe mean {mean}");
    assert!(probe.distances.distance(Vec3::Y).is_infinite());
    assert!((probe.distances.distance(-Vec3::Y) - 0.7).abs() < 0.05);

    let geometry = sphere_on_plane();
    let bvh = SceneBvh::build(&geometry.mesh);
    let map = sunny_map();
    let light = EnvironmentLight::new(&map, 0.0);
    let at = Vec3::new(1.5, 0.5, 1.0);
    let (probe, _) = render_probe(
        &geometry,
        &bvh,
        &light,
        at,
        (128, 64),
        &settings,
        no_progress,
    );
    let mut outside = 0;
    for j in 0..64 {
        for i in 0..128 {
            let w = probe.radiance.texel_direction(i, j);
            if probe.distances.distance(w).is_infinite() {
                assert_eq!(
                    probe.radiance.texel(i, j),
                    light.radiance(w),
                    "texel ({i}, {j})"
                );
                outside += 1;
            }
        }
    }
    assert!(outside > 128 * 20, "{outside} texels see the sky");
}

/// Progress that asks to stop once `limit` rows are rendered.
struct CancelAfter {
    limit: u64,
    done: std::sync::atomic::AtomicU64,
}

impl Progress for CancelAfter {
    fn advance(&self, steps: u64) {
        self.done
            .fetch_add(steps, std::sync::atomic::Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.done.load(std::sync::atomic::Ordering::Relaxed) >= self.limit
    }
}

/// A progress that answers cancelled stops the path trace within a row per thread with
/// `Cancelled`; one that never does changes no bit; the infallible form never asks.
#[test]
fn a_cancelled_render_stops_early_and_an_uncancelled_one_is_unchanged() {
    let geometry = scene_of(&[(&sphere_mesh(Vec3::ZERO, 1.0, 3), Rgb::splat(0.5))]);
    let map = EnvMap::uniform(32, 16, Rgb::ONE);
    let cam = camera(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, 200);
    let settings = ReferenceSettings::new(2, 1, 3);
    let bvh = SceneBvh::build(&geometry.mesh);
    let light = EnvironmentLight::new(&map, 0.0);
    let progress = |limit| CancelAfter {
        limit,
        done: Default::default(),
    };

    let early = progress(1);
    let result = try_render(&geometry, &bvh, &light, &cam, &settings, &early);
    assert_eq!(result.err(), Some(RenderError::Cancelled));
    let rows = early.done.into_inner();
    assert!(
        rows <= rayon::current_num_threads() as u64,
        "rendered {rows} of 200 rows after the cancel"
    );

    let bits = |image: &ReferenceImage| -> Vec<u32> {
        let values = image.radiance.pixels.iter().flat_map(|p| p.to_array());
        values.map(f32::to_bits).collect()
    };
    let plain = render_with(&geometry, &map, &cam, &settings);
    let asked = try_render(
        &geometry,
        &bvh,
        &light,
        &cam,
        &settings,
        &progress(u64::MAX),
    );
    assert_eq!(bits(&asked.unwrap()), bits(&plain));
    // The infallible form renders every row even when asked to stop.
    let ignored = render(&geometry, &bvh, &light, &cam, &settings, &progress(1));
    assert_eq!(bits(&ignored), bits(&plain));
}
