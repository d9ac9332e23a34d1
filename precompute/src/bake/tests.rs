//! Furnace tests and properties of the bake.

use super::*;
use foundation::color::Rgb;
use foundation::mesh::{TriangleMesh, box_mesh, sphere_mesh};
use foundation::sh::ShCoeffs;
use glam::Vec3;

/// SH coefficients of a uniform environment of radiance `value`.
pub(crate) fn uniform_light(order: usize, value: Rgb) -> ShCoeffs<Rgb> {
    let mut l = ShCoeffs::zeros(order);
    l.as_mut_slice()[0] = value * (4.0 * std::f32::consts::PI).sqrt();
    l
}

fn scene_of(mesh: &TriangleMesh, albedo: Rgb) -> SceneMesh {
    let mut s = SceneMesh::default();
    s.push_object("test".into(), mesh, albedo);
    s
}

fn run(geometry: &SceneMesh, settings: BakeSettings) -> (Transfer, BakeStats) {
    let bvh = SceneBvh::build(&geometry.mesh);
    bake(
        geometry,
        &bvh,
        &settings,
        &foundation::infra::progress::NoProgress,
    )
    .unwrap()
}

/// An open box (five inward-facing walls, no lid): a concave mesh where every vertex is
/// partly occluded.
fn open_box() -> TriangleMesh {
    let outer = box_mesh(
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 1.0, 1.0),
        [8, 4, 8],
        [false; 6],
    );
    let mut mesh = TriangleMesh::default();
    for t in 0..outer.triangle_count() {
        let [a, b, c] = outer.corners(t);
        // Drop the top face, flip the others to face inwards.
        if a.y == 1.0 && b.y == 1.0 && c.y == 1.0 {
            continue;
        }
        let base = mesh.positions.len() as u32;
        let n = -outer.normals[outer.triangles[t][0] as usize];
        mesh.positions.extend([a, c, b]);
        mesh.normals.extend([n; 3]);
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    mesh
}

#[test]
fn furnace_unoccluded_vertices_reflect_their_albedo() {
    let albedo = Rgb::new(0.8, 0.5, 0.2);
    let geometry = scene_of(&sphere_mesh(Vec3::ZERO, 1.0, 2), albedo);
    let settings = BakeSettings {
        order: 3,
        samples: 64,
        bounces: 2,
        seed: 1,
    };
    let (transfer, _) = run(&geometry, settings);
    let light = uniform_light(3, Rgb::ONE);
    for v in 0..geometry.mesh.vertex_count() {
        let l = transfer.full().radiance(v, &light);
        assert!(
            (l - albedo).abs().max_element() < 0.01 * albedo.max_element(),
            "vertex {v}: {l}"
        );
        // A convex mesh has no interreflection.
        assert_eq!(transfer.indirect.radiance(v, &light), Rgb::ZERO);
    }
}

fn white_furnace_deficits(
    geometry: &SceneMesh,
    bounce_counts: &[u32],
    samples: u32,
) -> Vec<Vec<f32>> {
    let light = uniform_light(1, Rgb::ONE);
    bounce_counts
        .iter()
        .map(|&bounces| {
            let (transfer, _) = run(
                geometry,
                BakeSettings {
                    order: 1,
                    samples,
                    bounces,
                    seed: 3,
                },
            );
            let full = transfer.full();
            (0..geometry.mesh.vertex_count())
                .map(|v| 1.0 - full.radiance(v, &light).x)
                .collect()
        })
        .collect()
}

fn mean(v: &[f32]) -> f32 {
    v.iter().sum::<f32>() / v.len() as f32
}

#[test]
fn white_furnace_open_box_converges_to_one() {
    let geometry = scene_of(&open_box(), Rgb::ONE);
    let counts = [0, 1, 2, 4, 8, 16];
    let deficits = white_furnace_deficits(&geometry, &counts, 256);
    let means: Vec<f32> = deficits.iter().map(|d| mean(d)).collect();
    for w in means.windows(2) {
        assert!(
            w[1] < w[0],
            "deficit must shrink with every bounce: {means:?}"
        );
    }
    // Every vertex's deficit shrinks too (no bounce subtracts light).
    for pair in deficits.windows(2) {
        for (a, b) in pair[0].iter().zip(&pair[1]) {
            assert!(b <= &(a + 1e-5));
        }
    }
    // Occluded vertices really were dark without interreflection.
    assert!(means[0] > 0.3, "{means:?}");
    assert!(*means.last().unwrap() < 0.02, "{means:?}");
}

#[test]
fn same_result_whatever_the_thread_count() {
    let geometry = scene_of(&open_box(), Rgb::splat(0.7));
    let settings = BakeSettings {
        order: 4,
        samples: 128,
        bounces: 2,
        seed: 9,
    };
    let in_pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&geometry, settings).0)
    };
    assert_eq!(in_pool(1), in_pool(3));
}

/// At the centre of the open box's floor, the sky is seen through the 2 × 2 opening 1 above:
/// the unoccluded cosine-weighted solid angle is π F, with F the form factor of a square of
/// half-side a at height h, `4 · (1/2π) · 2 · X/√(1+X²) · atan(X/√(1+X²))` for X = a/h = 1
/// (0.5541). So the direct transfer's first coefficient is `ρ F Y₀`, whether the bake traces
/// occlusion rays only (bounces = 0) or records hits for the bounces (bounces = 1).
#[test]
fn direct_transfer_under_an_opening_is_its_form_factor() {
    let albedo = 0.6;
    let geometry = scene_of(&open_box(), Rgb::splat(albedo));
    let x: f64 = 1.0;
    let root = (1.0 + x * x).sqrt();
    let form_factor = 4.0 / std::f64::consts::PI * (x / root) * (x / root).atan();
    let expected = albedo as f64 * form_factor / (4.0 * std::f64::consts::PI).sqrt();
    // Every vertex at the floor's centre (the mesh does not share vertices between faces).
    let centre: Vec<usize> = (0..geometry.mesh.vertex_count())
        .filter(|&v| geometry.mesh.positions[v].length() < 1e-6)
        .collect();
    assert!(!centre.is_empty());
    for bounces in [0, 1] {
        let settings = BakeSettings {
            order: 3,
            samples: 4096,
            bounces,
            seed: 5,
        };
        let (transfer, _) = run(&geometry, settings);
        let mean = centre
            .iter()
            .map(|&v| f64::from(transfer.direct.vector(v, 0)[0]))
            .sum::<f64>()
            / centre.len() as f64;
        assert!(
            (mean - expected).abs() < 0.005 * expected,
            "bounces {bounces}: t₀ = {mean}, form factor gives {expected}"
        );
        if bounces == 0 {
            assert!(transfer.indirect.as_slice().iter().all(|x| *x == 0.0));
        }
        // The bent normal of the floor's centre is straight up; near a wall it leans away
        // from it.
        let bent = transfer
            .direct
            .bent_normals(&geometry.albedo, &geometry.mesh.normals);
        for &v in &centre {
            assert!(bent[v].dot(Vec3::Y) > 0.999, "{}", bent[v]);
        }
        let near_wall: Vec<usize> = (0..geometry.mesh.vertex_count())
            .filter(|&v| {
                let p = geometry.mesh.positions[v];
                p.y.abs() < 1e-6 && (p.x - 0.75).abs() < 1e-6 && p.z.abs() < 1e-6
            })
            .collect();
        assert!(!near_wall.is_empty());
        for &v in &near_wall {
            assert!(bent[v].x < -0.1 && bent[v].y > 0.7, "{}", bent[v]);
        }
        // The specular occlusion read back from it is the form factor itself.
        let fraction = transfer.direct.unoccluded_fraction(&geometry.albedo);
        let mean =
            centre.iter().map(|&v| f64::from(fraction[v])).sum::<f64>() / centre.len() as f64;
        assert!(
            (mean - form_factor).abs() < 0.005 * form_factor,
            "unoccluded fraction {mean}, form factor {form_factor}"
        );
    }
}

/// The clamped cosine's zonal coefficients `Â_l = 2π ∫₀¹ P_l(x) x dx`, by hand (Ramamoorthi and
/// Hanrahan 2001): π, 2π/3, π/4, 0, −π/24.
const CLAMPED_COSINE: [f32; 5] = [
    std::f32::consts::PI,
    2.0 * std::f32::consts::PI / 3.0,
    std::f32::consts::PI / 4.0,
    0.0,
    -std::f32::consts::PI / 24.0,
];

/// A square of side 2 around the origin, facing `normal`, alone in the scene.
fn plane_facing(normal: Vec3) -> TriangleMesh {
    let normal = normal.normalize();
    let (u, v) = normal.any_orthonormal_pair();
    let corners = [-u - v, u - v, u + v, -u + v];
    TriangleMesh {
        positions: corners.to_vec(),
        normals: vec![normal; 4],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: Vec::new(),
        tangents: Vec::new(),
    }
}

/// Lit by a single SH basis function `Y_lm`, an unoccluded Lambertian point of normal n
/// reflects `ρ/π Â_l Y_lm(n)` (Funk–Hecke). Checked for all 25 functions of order 5 on every
/// vertex of a sphere (every normal) and of a tilted plane: a dropped cosine changes `Â_l`, a
/// band or coefficient out of place lights the wrong function, and band 3 must vanish. The
/// tolerance, 1.5e-3, is three times the Hammersley set's error at 4096 samples (it falls as
/// 1/N: 2.2e-3 at 1024, 5.5e-4 at 4096); the smallest term checked, band 4's, reaches 0.03.
#[test]
fn each_sh_basis_function_lights_open_surfaces_by_funk_hecke() {
    let albedo = Rgb::new(0.9, 0.6, 0.3);
    let basis = foundation::sh::ShBasis::new(5).unwrap();
    for (name, mesh) in [
        ("sphere", sphere_mesh(Vec3::ZERO, 1.0, 2)),
        ("plane", plane_facing(Vec3::new(0.4, 0.8, -0.45))),
    ] {
        let geometry = scene_of(&mesh, albedo);
        let settings = BakeSettings {
            order: 5,
            samples: 4096,
            bounces: 1,
            seed: 2,
        };
        let (transfer, _) = run(&geometry, settings);
        let full = transfer.full();
        let mut worst = 0.0f32;
        for (l, clamped_cosine) in CLAMPED_COSINE.iter().enumerate() {
            for m in -(l as isize)..=l as isize {
                let k = foundation::sh::index(l, m);
                let mut light = ShCoeffs::zeros(5);
                light.as_mut_slice()[k] = Rgb::ONE;
                for v in 0..geometry.mesh.vertex_count() {
                    let n = geometry.mesh.normals[v];
                    let y = basis.eval_vec(n)[k];
                    let want = albedo * (clamped_cosine / std::f32::consts::PI * y);
                    let got = full.radiance(v, &light);
                    let error = (got - want).abs().max_element();
                    worst = worst.max(error);
                    assert!(
                        error < 1.5e-3,
                        "{name}, Y({l},{m}), vertex {v} (n = {n}): {got} vs {want}"
                    );
                }
            }
        }
        println!("{name}: largest error {worst:.2e}");
    }
}

#[test]
fn rejects_bad_settings() {
    let geometry = scene_of(&sphere_mesh(Vec3::ZERO, 1.0, 0), Rgb::ONE);
    let bvh = SceneBvh::build(&geometry.mesh);
    for settings in [
        BakeSettings {
            samples: 0,
            ..Default::default()
        },
        BakeSettings {
            order: foundation::sh::MAX_ORDER + 1,
            ..Default::default()
        },
    ] {
        assert!(
            bake(
                &geometry,
                &bvh,
                &settings,
                &foundation::infra::progress::NoProgress
            )
            .is_err()
        );
    }
}

/// The bake's indirect transfer is the Neumann series summed term by term, `Σ_k T_k` with
/// `T_k = diag(ρ) W T_{k-1}` from `T_0` the direct transfer, bit for bit: with one bounce
/// (its term becomes the sum) and with three (each term is kept for the next).
#[test]
fn bounces_sum_the_series_term_by_term() {
    let albedo = Rgb::new(0.8, 0.6, 0.4);
    let geometry = scene_of(&open_box(), albedo);
    let bvh = SceneBvh::build(&geometry.mesh);
    let no_progress = &foundation::infra::progress::NoProgress;
    for bounces in [1, 3] {
        let settings = BakeSettings {
            order: 3,
            samples: 64,
            bounces,
            seed: 4,
        };
        let traced = trace(&geometry, &bvh, &settings, no_progress).unwrap();
        let albedos = vec![albedo; geometry.mesh.vertex_count()];
        let mut term = traced.direct.clone();
        let mut sum = TransferVectors::zeros(settings.order, albedos.len());
        for _ in 0..bounces {
            term = traced.operator.apply(&term, &albedos);
            fill_inside(&mut term, &traced.inside, &traced.neighbours);
            for (s, t) in sum.as_mut_slice().iter_mut().zip(term.as_slice()) {
                *s += t;
            }
        }
        let partial_sums: Vec<TransferVectors> = traced.cumulative_indirect(bounces).collect();
        let (transfer, _) = sum_bounces(&geometry, &settings, traced, no_progress).unwrap();
        let bits =
            |t: &TransferVectors| t.as_slice().iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(sum.as_slice().iter().any(|&x| x > 0.01), "no light bounced");
        assert_eq!(bits(&transfer.indirect), bits(&sum), "{bounces} bounces");
        assert_eq!(partial_sums.len(), bounces as usize);
        assert_eq!(bits(partial_sums.last().unwrap()), bits(&sum));
    }
}

/// Progress that asks to stop once `limit` vertices are traced.
struct CancelAfter {
    limit: u64,
    done: std::sync::atomic::AtomicU64,
}

impl CancelAfter {
    fn new(limit: u64) -> Self {
        Self {
            limit,
            done: Default::default(),
        }
    }
    fn done(&self) -> u64 {
        self.done.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Progress for CancelAfter {
    fn advance(&self, steps: u64) {
        self.done
            .fetch_add(steps, std::sync::atomic::Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.done() >= self.limit
    }
}

/// A progress that answers cancelled stops the tracing within a few chunks, or the bounces
/// after the tracing, with `Cancelled`; one that never does changes no bit of the bake.
#[test]
fn a_cancelled_bake_stops_early_and_an_uncancelled_one_is_unchanged() {
    let geometry = scene_of(&sphere_mesh(Vec3::ZERO, 1.0, 5), Rgb::splat(0.5));
    let bvh = SceneBvh::build(&geometry.mesh);
    let vertices = geometry.mesh.vertex_count() as u64;
    assert!(
        vertices > 100 * visibility::CHUNK as u64,
        "{vertices} vertices"
    );
    let settings = BakeSettings {
        order: 2,
        samples: 16,
        bounces: 1,
        seed: 1,
    };

    let early = CancelAfter::new(1);
    let result = bake(&geometry, &bvh, &settings, &early);
    assert_eq!(result.err(), Some(BakeError::Cancelled));
    // Each worker thread finishes the chunk it started, and starts no other.
    let threads = rayon::current_num_threads() as u64;
    assert!(
        early.done() <= threads * visibility::CHUNK as u64,
        "traced {} of {vertices} vertices after the cancel",
        early.done()
    );

    // Tracing done, cancelled before the first bounce.
    let late = CancelAfter::new(vertices);
    let result = bake(&geometry, &bvh, &settings, &late);
    assert_eq!(result.err(), Some(BakeError::Cancelled));
    assert_eq!(late.done(), vertices);

    let never = CancelAfter::new(u64::MAX);
    let (asked, _) = bake(&geometry, &bvh, &settings, &never).unwrap();
    let (plain, _) = run(&geometry, settings);
    assert_eq!(asked, plain);
}
