//! Per-frame decomposition cost (one thread): `cargo bench -p runtime --bench decompose`.
//! Targets: 6×64×64 under 0.5 ms (a changing map's whole frame, resampling and the sources'
//! sizes included, under 2 ms: `hprt bench turn`), 6×256×256 under 15 ms; turning a decomposed
//! map (SH rotation of the SH part and the lights) well under 0.05 ms at order 5; median cut (a
//! peer) at 32 lights under 1 ms on a 256 × 128 map. This machine's speed drifts by a third
//! within minutes: compare two builds with interleaved runs.

use criterion::{Criterion, criterion_group, criterion_main};
use runtime::{CubeSource, DecomposeMode, DecomposeSettings, Decomposer, EnvironmentLighting};
use runtime::{analysis_map, median_cut};
use std::path::Path;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("decompose");
    // sunrise: one dominant sun; hall: many ceiling lights (the most candidates to rank).
    for (name, face) in [
        ("sunrise", 64),
        ("sunrise", 256),
        ("hall", 64),
        ("hall", 256),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/env/{name}.exr"));
        let map = foundation::envmap::load(&path, None)
            .expect("the bundled map")
            .map;
        for mode in [DecomposeMode::Consistent, DecomposeMode::Thesis] {
            let settings = DecomposeSettings {
                face_size: face,
                mode,
                ..Default::default()
            };
            let cube = CubeSource::new(&map, face).cube(0.0);
            let mut decomposer = Decomposer::new(settings).expect("valid settings");
            group.bench_function(format!("{name}/{face}/{}", mode.name()), |b| {
                b.iter(|| decomposer.decompose(&cube))
            });
        }
        let source = CubeSource::new(&map, face);
        let mut cube = source.cube(0.0);
        group.bench_function(format!("{name}/{face}/resample-rotated"), |b| {
            b.iter(|| source.cube_into(0.3, &mut cube))
        });
        let mut lighting =
            EnvironmentLighting::new(&map, DecomposeSettings::default()).expect("valid settings");
        lighting.decompose();
        let mut angle = 0.0f32;
        group.bench_function(format!("{name}/{face}/rotate-decomposition"), |b| {
            b.iter(|| {
                angle += 1.0;
                lighting.set_rotation(angle);
                lighting.decompose()
            })
        });
    }
    for name in ["sunrise", "hall"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/env/{name}.exr"));
        let map = analysis_map(
            &foundation::envmap::load(&path, None)
                .expect("the bundled map")
                .map,
        );
        for lights in [8, 32] {
            group.bench_function(
                format!(
                    "{name}/{}x{}/median-cut-{lights}",
                    map.width(),
                    map.height()
                ),
                |b| b.iter(|| median_cut(&map, lights).expect("a power of two")),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
