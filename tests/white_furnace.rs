//! White furnace with interreflection on the bundled teapot scene: with albedo 1 under a
//! uniform environment of radiance 1, the full transfer's outgoing radiance approaches 1 at
//! every vertex, occluded ones included.

mod common;

use common::bake_quietly;
use foundation::bvh::SceneBvh;
use foundation::color::Rgb;
use foundation::scene::Scene;
use foundation::sh::ShCoeffs;
use precompute::bake::BakeSettings;

#[test]
fn teapot_scene_deficit_shrinks_with_every_bounce() {
    let mut scene = Scene::load(&common::scene("teapot.toml")).unwrap();
    scene.geometry.albedo.iter_mut().for_each(|a| *a = Rgb::ONE);
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let mut white = ShCoeffs::zeros(1);
    white.as_mut_slice()[0] = Rgb::splat((4.0 * std::f32::consts::PI).sqrt());

    let mut means = Vec::new();
    let mut worst = 0.0f32;
    for bounces in [0, 1, 2, 4, 8, 16] {
        let settings = BakeSettings {
            order: 1,
            samples: 128,
            bounces,
            seed: 0,
        };
        let transfer = bake_quietly(&scene.geometry, &bvh, &settings);
        let full = transfer.full();
        let n = full.vertex_count();
        let deficits: Vec<f32> = (0..n).map(|v| 1.0 - full.radiance(v, &white).y).collect();
        means.push(deficits.iter().sum::<f32>() / n as f32);
        worst = deficits.iter().copied().fold(0.0, f32::max);
    }
    for w in means.windows(2) {
        assert!(
            w[1] < w[0],
            "the deficit must shrink with every bounce: {means:?}"
        );
    }
    assert!(means[0] > 0.05, "the scene has occlusion: {means:?}");
    assert!(
        *means.last().unwrap() < 0.02,
        "mean deficit after 16 bounces: {means:?}"
    );
    // Every vertex, occluded ones included, approaches 1.
    assert!(
        worst < 0.05,
        "worst vertex deficit after 16 bounces: {worst}"
    );
}
