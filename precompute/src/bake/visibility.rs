//! The tracing pass of the bake: every (vertex, sample) ray is cast exactly once.

use super::bounce::OperatorBlock;
use super::{BakeSettings, InterreflectionOperator, RAY_OFFSET_FRACTION, TransferVectors};
use foundation::bvh::{Hit, SceneBvh, Skip};
use foundation::color::Rgb;
use foundation::infra::progress::Progress;
use foundation::sampling::{
    Frame, cosine_hemisphere, cranley_patterson, hammersley, hash_to_unit2, mix64,
};
use foundation::scene::SceneMesh;
use foundation::sh::{ShBasis, num_coeffs};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use wide::f32x8;

/// What the tracing pass found for a run of vertices (all of them, or a shard's).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TracedVertices {
    pub(crate) order: usize,
    /// Per vertex, `(1/N) Σ_{escaping rays} Y_k(ω)`: the scalar direct transfer before albedo.
    pub(crate) visibility: Vec<f32>,
    /// Where the other rays landed, as interpolation weights over vertices (one row per
    /// traced vertex; columns index the whole scene).
    pub(crate) operator: InterreflectionOperator,
    /// Vertices inside a solid: most of their rays reach the back of a surface.
    pub(crate) inside: Vec<bool>,
}

/// A vertex counts as inside a solid when more than this fraction of its rays reach back
/// faces (lightmappers call it the back-face tolerance).
pub const INSIDE_BACKFACE_FRACTION: f32 = 0.5;

impl TracedVertices {
    /// `T_direct,c(v) = ρ_c(v) · visibility(v)`.
    pub(crate) fn direct_transfer(&self, albedo: &[Rgb], order: usize) -> TransferVectors {
        debug_assert_eq!(order, self.order);
        let n = num_coeffs(order);
        let mut out = TransferVectors::zeros(order, albedo.len());
        let stride = out.stride();
        out.as_mut_slice()
            .par_chunks_mut(stride)
            .zip(self.visibility.par_chunks(n))
            .zip(albedo.par_iter())
            .for_each(|((dst, vis), rho)| {
                for c in 0..3 {
                    for (d, y) in dst[c * n..(c + 1) * n].iter_mut().zip(vis) {
                        *d = rho[c] * y;
                    }
                }
            });
        out
    }
}

/// The base sample set: cosine-weighted Hammersley points, sorted along a Morton curve of the
/// unit square so consecutive rays of a vertex are spatially coherent.
fn base_samples(count: u32) -> Vec<Vec2> {
    let mut points: Vec<Vec2> = (0..count).map(|i| hammersley(i, count)).collect();
    let morton = |p: &Vec2| {
        let spread = |x: f32| {
            let mut v = ((x.clamp(0.0, 1.0) * 65535.0) as u64) & 0xffff;
            v = (v | (v << 8)) & 0x00ff_00ff;
            v = (v | (v << 4)) & 0x0f0f_0f0f;
            v = (v | (v << 2)) & 0x3333_3333;
            (v | (v << 1)) & 0x5555_5555
        };
        spread(p.x) | (spread(p.y) << 1)
    };
    points.sort_by_key(morton);
    points
}

/// Per-thread buffers reused across vertices.
struct Scratch {
    /// The SH basis at up to eight escaping directions; a fan's escaping directions.
    basis: Vec<f32x8>,
    escaped: Vec<Vec3>,
    /// A fan's directions and what each ray hit.
    directions: Vec<Vec3>,
    found: Vec<Option<Hit>>,
    hits: Vec<(u32, f32)>,
}

/// Results for a contiguous run of vertices, in vertex order.
struct Chunk {
    visibility: Vec<f32>,
    operator: OperatorBlock,
    inside: Vec<bool>,
}

/// Vertices per parallel work item (and per block of the interreflection operator).
pub(crate) const CHUNK: usize = 32;

/// Traces the rays of `vertices` (a vertex's results do not depend on which others are traced
/// with it, so shards of the range concatenate to the whole). `None` when `progress` asks to
/// stop: it is asked before each chunk of [`CHUNK`] vertices.
pub(crate) fn trace_vertices(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    settings: &BakeSettings,
    vertices: std::ops::Range<usize>,
    progress: &dyn Progress,
) -> Option<TracedVertices> {
    let order = settings.order;
    let n = num_coeffs(order);
    let tracer = VertexTracer::new(geometry, bvh, settings);
    let first = vertices.start;
    let vertex_count = vertices.len();

    let chunks: Vec<Chunk> = (0..vertex_count.div_ceil(CHUNK))
        .into_par_iter()
        .map_init(
            || Scratch {
                basis: vec![f32x8::ZERO; n],
                escaped: Vec::with_capacity(tracer.fans.len()),
                directions: Vec::with_capacity(tracer.fans.len()),
                found: Vec::with_capacity(tracer.fans.len()),
                hits: Vec::with_capacity(3 * tracer.fans.len()),
            },
            |scratch, chunk_index| {
                if progress.cancelled() {
                    return None;
                }
                let vertices = first + chunk_index * CHUNK
                    ..first + ((chunk_index + 1) * CHUNK).min(vertex_count);
                let mut chunk = Chunk {
                    visibility: vec![0.0; vertices.len() * n],
                    operator: OperatorBlock::new(),
                    inside: Vec::with_capacity(vertices.len()),
                };
                for (local, v) in vertices.clone().enumerate() {
                    let visibility = &mut chunk.visibility[local * n..(local + 1) * n];
                    let inside = tracer.trace(v, scratch, visibility);
                    chunk.inside.push(inside);
                    // Merge the hits into one sparse row of the interreflection operator.
                    scratch.hits.sort_unstable_by_key(|(i, _)| *i);
                    chunk.operator.push_sorted_row(&scratch.hits);
                }
                chunk.operator.shrink_to_fit();
                progress.advance(vertices.len() as u64);
                Some(chunk)
            },
        )
        .collect::<Option<_>>()?;

    let mut visibility = Vec::with_capacity(vertex_count * n);
    let mut blocks = Vec::with_capacity(chunks.len());
    let mut inside = Vec::with_capacity(vertex_count);
    for chunk in chunks {
        visibility.extend_from_slice(&chunk.visibility);
        blocks.push(chunk.operator);
        inside.extend(chunk.inside);
    }
    Some(TracedVertices {
        order,
        visibility,
        operator: InterreflectionOperator::from_blocks(blocks),
        inside,
    })
}

/// Each vertex's estimated tracing cost: the BVH nodes visited by `probe_rays` rays from one
/// vertex in `stride` (cosine-distributed, rotated per vertex like the bake's), which the
/// vertices after it share. Depends only on the scene and the settings.
pub(crate) fn vertex_costs(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    settings: &BakeSettings,
    probe_rays: u32,
    stride: usize,
) -> Vec<f64> {
    let tracer = VertexTracer::new(geometry, bvh, settings);
    let vertex_count = geometry.mesh.vertex_count();
    let probes: Vec<f64> = (0..vertex_count.div_ceil(stride))
        .into_par_iter()
        .map(|k| tracer.probe_work(k * stride, probe_rays) as f64)
        .collect();
    (0..vertex_count).map(|v| probes[v / stride]).collect()
}

/// How the bake's rays leave the vertices: a fan per vertex, every ray of it from one origin
/// (the vertex moved off its surface along its normal), in directions cosine-distributed about
/// the normal, rotated per vertex, in the order the bake traces them.
pub struct RayFans {
    samples: Vec<Vec2>,
    offset: f32,
    seed: u64,
}

impl RayFans {
    pub fn new(geometry: &SceneMesh, settings: &BakeSettings) -> Self {
        Self {
            samples: base_samples(settings.samples),
            offset: RAY_OFFSET_FRACTION * geometry.diagonal(),
            seed: settings.seed,
        }
    }

    /// Rays per fan.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Vertex `v`'s fan: its origin and its rays' directions.
    pub fn fan<'s>(
        &'s self,
        geometry: &SceneMesh,
        v: usize,
    ) -> (Vec3, impl Iterator<Item = Vec3> + 's) {
        let mesh = &geometry.mesh;
        let normal = mesh.normals[v];
        let frame = Frame::from_normal(normal);
        let origin = mesh.positions[v] + normal * self.offset;
        let rotation = hash_to_unit2(mix64(self.seed ^ mix64(v as u64)));
        let directions = self
            .samples
            .iter()
            .map(move |u| frame.to_world(cosine_hemisphere(cranley_patterson(*u, rotation))));
        (origin, directions)
    }
}

/// What tracing one vertex's rays needs, shared by every vertex.
struct VertexTracer<'a> {
    geometry: &'a SceneMesh,
    bvh: &'a SceneBvh,
    basis: ShBasis<f32>,
    fans: RayFans,
    inv_samples: f32,
    /// Whether hits are recorded (for the interreflection operator).
    record_hits: bool,
    front_normals: Vec<Vec3>,
    seed: u64,
}

impl<'a> VertexTracer<'a> {
    fn new(geometry: &'a SceneMesh, bvh: &'a SceneBvh, settings: &BakeSettings) -> Self {
        let mesh = &geometry.mesh;
        Self {
            geometry,
            bvh,
            basis: ShBasis::<f32>::new(settings.order).expect("validated settings"),
            fans: RayFans::new(geometry, settings),
            inv_samples: 1.0 / settings.samples as f32,
            record_hits: settings.bounces > 0,
            front_normals: (0..mesh.triangle_count())
                .map(|t| mesh.front_normal(t))
                .collect(),
            seed: settings.seed,
        }
    }

    /// Traces vertex `v`'s rays: adds `(1/N) Σ Y_k(ω)` over the escaping ones to `visibility`,
    /// leaves the hits' interpolation weights in `scratch.hits`, and says whether the vertex
    /// is inside a solid.
    #[inline]
    fn trace(&self, v: usize, scratch: &mut Scratch, visibility: &mut [f32]) -> bool {
        let mesh = &self.geometry.mesh;
        let (origin, directions) = self.fans.fan(self.geometry, v);
        scratch.directions.clear();
        scratch.directions.extend(directions);
        // The fan's rays share their origin: traced together, eight at a time.
        let skip = Skip::VertexTriangles(v as u32);
        let range = (0.0, f32::INFINITY);
        let (directions, found) = (&scratch.directions, &mut scratch.found);
        self.bvh
            .closest_hits(origin, directions, range, skip, found);
        scratch.hits.clear();
        scratch.escaped.clear();
        let mut back_faces = 0u32;
        for (&direction, hit) in scratch.directions.iter().zip(&scratch.found) {
            match hit {
                None => scratch.escaped.push(direction),
                Some(hit) => {
                    if direction.dot(self.front_normals[hit.triangle as usize]) > 0.0 {
                        back_faces += 1;
                    }
                    if self.record_hits {
                        // Either side of a triangle shows its front's radiance
                        // (CONVENTIONS.md, "Surfaces").
                        let corners = mesh.triangles[hit.triangle as usize];
                        for (i, w) in corners.iter().zip(hit.barycentrics()) {
                            scratch.hits.push((*i, w * self.inv_samples));
                        }
                    }
                }
            }
        }
        // The escaping rays' basis values, eight at a time, summed in ray order.
        for directions in scratch.escaped.chunks(8) {
            accumulate_basis(&self.basis, directions, &mut scratch.basis, visibility);
        }
        for y in visibility.iter_mut() {
            *y *= self.inv_samples;
        }
        back_faces as f32 > INSIDE_BACKFACE_FRACTION * self.fans.len() as f32
    }

    /// BVH nodes visited by `rays` probe rays from vertex `v`, plus one per ray for the work
    /// outside the traversal.
    fn probe_work(&self, v: usize, rays: u32) -> u64 {
        let mesh = &self.geometry.mesh;
        let normal = mesh.normals[v];
        let frame = Frame::from_normal(normal);
        let origin = mesh.positions[v] + normal * self.fans.offset;
        let rotation = hash_to_unit2(mix64(self.seed ^ mix64(v as u64)));
        (0..rays)
            .map(|i| {
                let u = cranley_patterson(hammersley(i, rays), rotation);
                let direction = frame.to_world(cosine_hemisphere(u));
                let skip = Skip::VertexTriangles(v as u32);
                1 + u64::from(self.bvh.closest_hit_work(origin, direction, skip))
            })
            .sum()
    }
}

/// Adds the basis at each of `directions` (one to eight) to `sum`, one direction after the
/// other: the sum a direction at a time gives, bit for bit.
#[inline]
fn accumulate_basis(
    basis: &ShBasis<f32>,
    directions: &[Vec3],
    values: &mut [f32x8],
    sum: &mut [f32],
) {
    let lane = |i: usize| directions[i.min(directions.len() - 1)];
    let w = [0, 1, 2].map(|a| f32x8::new(std::array::from_fn(|i| lane(i)[a])));
    basis.eval_lanes(w, values);
    for i in 0..directions.len() {
        for (s, y) in sum.iter_mut().zip(values.iter()) {
            *s += y.as_array()[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base_samples_are_a_permutation_of_hammersley() {
        let mut a: Vec<(f32, f32)> = base_samples(256).iter().map(|p| (p.x, p.y)).collect();
        let mut b: Vec<(f32, f32)> = (0..256)
            .map(|i| hammersley(i, 256))
            .map(|p| (p.x, p.y))
            .collect();
        a.sort_by(|x, y| x.partial_cmp(y).unwrap());
        b.sort_by(|x, y| x.partial_cmp(y).unwrap());
        assert_eq!(a, b);
        // Coherent: consecutive points are close on average.
        let s = base_samples(1024);
        let mean_step: f32 = s.windows(2).map(|w| w[0].distance(w[1])).sum::<f32>() / 1023.0;
        assert!(mean_step < 0.1, "{mean_step}");
    }

    /// On the dragon, whose scan has overlapping triangles that rays meet at exactly the same
    /// distance, the bake's fans give every ray its lone answer, ties included.
    #[test]
    fn fans_on_the_dragon_give_each_ray_its_own_hit() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/dragon.toml");
        let scene = foundation::scene::Scene::open(std::path::Path::new(path)).unwrap();
        let settings = BakeSettings {
            order: 2,
            samples: 256,
            bounces: 0,
            seed: 0,
        };
        let geometry = &scene.geometry;
        let bvh = SceneBvh::build(&geometry.mesh);
        let fans = RayFans::new(geometry, &settings);
        let (mut found, mut ties) = (Vec::new(), 0);
        for v in 0..600 {
            let (origin, directions) = fans.fan(geometry, v);
            let directions: Vec<Vec3> = directions.collect();
            let skip = Skip::VertexTriangles(v as u32);
            bvh.closest_hits(origin, &directions, (0.0, f32::INFINITY), skip, &mut found);
            for (&d, hit) in directions.iter().zip(&found) {
                let alone = bvh.closest_hit(origin, d, 0.0, f32::INFINITY, skip);
                assert_eq!(*hit, alone, "vertex {v}, direction {d}");
                // Another triangle at the very same distance?
                if let Some(hit) = hit {
                    let just_past = f32::from_bits(hit.t.to_bits() + 1);
                    let other = Skip::Triangle(hit.triangle);
                    let second = bvh.closest_hit(origin, d, 0.0, just_past, other);
                    ties += usize::from(second.is_some_and(|s| s.t == hit.t));
                }
            }
        }
        assert!(
            ties > 0,
            "no ties among these vertices' rays: the test misses its point"
        );
    }
}
