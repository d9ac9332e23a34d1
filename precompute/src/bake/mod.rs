//! The offline bake (thesis Figure 4.2): per-vertex SH transfer with shadowing and
//! interreflections.
//!
//! One pass traces `samples` cosine-distributed rays per vertex. A ray that escapes adds the SH
//! basis in its direction to the vertex's direct (shadowed) transfer; a ray that hits the front
//! of a triangle records the hit's barycentric weights. Those weights form a sparse
//! interreflection operator `W` (vertex × vertex), so each Neumann-series bounce
//! `T_b = diag(ρ) W T_{b-1}` reuses every hit without tracing again.

pub(crate) mod bounce;
mod inside;
pub mod shard;
mod transfer;
pub(crate) mod visibility;

pub use bounce::InterreflectionOperator;
pub use inside::VertexNeighbours;
pub(crate) use inside::fill_inside;
pub use transfer::TransferVectors;
pub use visibility::{INSIDE_BACKFACE_FRACTION, RayFans};

pub use foundation::bake_settings::{BakeSettings, MAX_BOUNCES, MAX_SAMPLES};
use foundation::bvh::SceneBvh;
use foundation::infra::progress::Progress;
use foundation::scene::SceneMesh;
use foundation::settings::InvalidSettings;
use std::time::Instant;

/// Why a bake stopped without a result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Settings(#[from] InvalidSettings),
    /// Its [`Progress`] answered [`Progress::cancelled`] (asked per chunk of vertices and per
    /// bounce).
    #[error("the bake was cancelled")]
    Cancelled,
}

/// Direct and interreflected transfer of every vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct Transfer {
    pub settings: BakeSettings,
    pub direct: TransferVectors,
    pub indirect: TransferVectors,
    /// Vertices of textured objects: their transfer is per unit texel value, to be multiplied
    /// by the texture where drawn (CONVENTIONS.md, "Textured albedo").
    pub textured_vertices: u64,
}

impl Transfer {
    /// Direct plus indirect.
    pub fn full(&self) -> TransferVectors {
        self.direct.sum(&self.indirect)
    }
}

/// Timings and counts of one bake.
#[derive(Debug, Clone, Default)]
pub struct BakeStats {
    pub vertices: usize,
    pub rays: u64,
    pub direct_seconds: f64,
    /// Time of each bounce.
    pub bounce_seconds: Vec<f64>,
    pub total_seconds: f64,
    /// Non-zero entries of the interreflection operator.
    pub operator_entries: usize,
}

impl BakeStats {
    /// Rays traced per second of the direct pass (the only pass that traces).
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.direct_seconds.max(1e-9)
    }
}

pub use foundation::bvh::RAY_OFFSET_FRACTION;

/// The result of the tracing pass: the direct transfer and the interreflection operator, from
/// which any number of bounces follows without tracing again.
pub struct TracedScene {
    /// The direct transfer as stored: with each vertex's albedo (on a textured object, its
    /// texture's factor: the transfer is per unit texel value).
    pub direct: TransferVectors,
    pub operator: InterreflectionOperator,
    /// The albedo each vertex reflects toward the others ([`SceneMesh::reflected_albedo`]).
    reflected_albedo: Vec<foundation::color::Rgb>,
    /// For a textured scene: the direct transfer with the reflected albedo (what the next
    /// bounce sees) and the stored vertices' albedo; `None` where the two albedos agree.
    textured: Option<(TransferVectors, Vec<foundation::color::Rgb>)>,
    /// Vertices inside solids (see [`fill_inside`]); their transfer is their neighbours'.
    pub inside: Vec<bool>,
    neighbours: VertexNeighbours,
    /// Seconds the tracing took.
    pub seconds: f64,
}

impl TracedScene {
    /// The indirect transfer after each of `bounces` Neumann-series steps: item `b` is
    /// `Σ_{k=1..b+1} diag(a) W (diag(ρ) W)^(k-1) T_direct(ρ)`, with `ρ` the reflected and `a`
    /// the vertex albedo (the same unless the scene is textured).
    pub fn cumulative_indirect(&self, bounces: u32) -> impl Iterator<Item = TransferVectors> + '_ {
        let mut series = NeumannSeries::new(self, bounces);
        (0..bounces).map(move |_| series.step().clone())
    }
}

/// The Neumann series summed one bounce at a time. Every large vector is written before it
/// is read: adding into fresh zeros would first map the shared zero page and then fault
/// again on the write, each fault flushing every thread's TLB.
struct NeumannSeries<'a> {
    scene: &'a TracedScene,
    /// What the next bounce gathers from (`None`: the direct transfer, not yet copied).
    previous: Option<TransferVectors>,
    /// The indirect transfer so far (`None` before the first bounce).
    sum: Option<TransferVectors>,
    /// Bounces still to add.
    remaining: u32,
    /// A textured scene gathers once and scales twice (reflected, stored).
    ones: Option<Vec<foundation::color::Rgb>>,
}

impl<'a> NeumannSeries<'a> {
    fn new(scene: &'a TracedScene, bounces: u32) -> Self {
        let ones = scene
            .textured
            .as_ref()
            .map(|_| vec![foundation::color::Rgb::ONE; scene.direct.vertex_count()]);
        Self {
            scene,
            previous: None,
            sum: None,
            remaining: bounces,
            ones,
        }
    }

    /// Adds the next bounce; returns the indirect transfer so far.
    fn step(&mut self) -> &TransferVectors {
        let scene = self.scene;
        let input = match (&self.previous, &scene.textured) {
            (Some(previous), _) => previous,
            (None, Some((reflected_direct, _))) => reflected_direct,
            (None, None) => &scene.direct,
        };
        self.remaining = self.remaining.saturating_sub(1);
        let fill = |mut t: TransferVectors| {
            fill_inside(&mut t, &scene.inside, &scene.neighbours);
            t
        };
        let (next, stored) = match (&scene.textured, &self.ones) {
            (Some((_, albedo)), Some(ones)) => {
                let gathered = scene.operator.apply(input, ones);
                let next = fill(gathered.scaled_per_vertex(&scene.reflected_albedo));
                (next, Some(fill(gathered.scaled_per_vertex(albedo))))
            }
            _ => (
                fill(scene.operator.apply(input, &scene.reflected_albedo)),
                None,
            ),
        };
        match (&mut self.sum, stored) {
            (Some(sum), stored) => sum.add(stored.as_ref().unwrap_or(&next)),
            (None, Some(stored)) => self.sum = Some(stored.plus_zero()),
            // The last bounce of an untextured scene: nothing gathers from it again.
            (None, None) if self.remaining == 0 => {
                self.sum = Some(next.plus_zero());
                return self.sum.as_ref().expect("just set");
            }
            (None, None) => self.sum = Some(next.clone().plus_zero()),
        }
        self.previous = Some(next);
        self.sum.as_ref().expect("set above")
    }

    /// The indirect transfer of every bounce added (`None` if none was).
    fn into_sum(self) -> Option<TransferVectors> {
        self.sum
    }
}

/// Traces every (vertex, sample) ray once: the direct transfer and the interreflection
/// operator. `progress` counts vertices, and may cancel.
pub fn trace(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    settings: &BakeSettings,
    progress: &dyn Progress,
) -> Result<TracedScene, BakeError> {
    settings.validate()?;
    let start = Instant::now();
    let vertex_count = geometry.mesh.vertex_count();
    progress.start(vertex_count as u64);
    let traced = visibility::trace_vertices(geometry, bvh, settings, 0..vertex_count, progress)
        .ok_or(BakeError::Cancelled)?;
    Ok(TracedScene::new(
        geometry,
        settings,
        traced,
        start.elapsed().as_secs_f64(),
    ))
}

impl TracedScene {
    /// The scene's tracing results (every vertex's), their direct transfer with albedo, and
    /// the inside vertices filled from their neighbours.
    fn new(
        geometry: &SceneMesh,
        settings: &BakeSettings,
        traced: visibility::TracedVertices,
        seconds: f64,
    ) -> Self {
        let neighbours = VertexNeighbours::new(&geometry.mesh);
        let reflected_albedo = geometry.reflected_albedo();
        let mut reflected_direct = traced.direct_transfer(&reflected_albedo, settings.order);
        fill_inside(&mut reflected_direct, &traced.inside, &neighbours);
        // Textured, glossy and layered scenes reflect toward other surfaces another albedo than
        // the one their vertices' transfer is stored with.
        let (direct, textured) = if geometry.is_textured() || geometry.is_glossy() {
            let albedo = geometry.albedo.clone();
            let mut direct = traced.direct_transfer(&albedo, settings.order);
            fill_inside(&mut direct, &traced.inside, &neighbours);
            (direct, Some((reflected_direct, albedo)))
        } else {
            (reflected_direct, None)
        };
        TracedScene {
            direct,
            operator: traced.operator,
            reflected_albedo,
            textured,
            inside: traced.inside,
            neighbours,
            seconds,
        }
    }
}

/// Bakes the transfer of every vertex of `geometry`. `progress` counts vertices of the
/// tracing pass (pass [`foundation::infra::progress::NoProgress`] for none); when it answers
/// [`Progress::cancelled`] the bake stops with [`BakeError::Cancelled`].
pub fn bake(
    geometry: &SceneMesh,
    bvh: &SceneBvh,
    settings: &BakeSettings,
    progress: &dyn Progress,
) -> Result<(Transfer, BakeStats), BakeError> {
    let start = Instant::now();
    let traced = trace(geometry, bvh, settings, progress)?;
    let (transfer, mut stats) = sum_bounces(geometry, settings, traced, progress)?;
    foundation::infra::memory::release_freed_memory();
    stats.total_seconds = start.elapsed().as_secs_f64();
    Ok((transfer, stats))
}

/// The Neumann series over a traced scene: the finished bake (cancelled between bounces when
/// `progress` asks).
fn sum_bounces(
    geometry: &SceneMesh,
    settings: &BakeSettings,
    traced: TracedScene,
    progress: &dyn Progress,
) -> Result<(Transfer, BakeStats), BakeError> {
    let start = Instant::now();
    let vertex_count = geometry.mesh.vertex_count();
    let mut stats = BakeStats {
        vertices: vertex_count,
        rays: vertex_count as u64 * settings.samples as u64,
        direct_seconds: traced.seconds,
        operator_entries: traced.operator.entries(),
        ..Default::default()
    };
    let mut series = NeumannSeries::new(&traced, settings.bounces);
    for bounce in 0..settings.bounces {
        if progress.cancelled() {
            return Err(BakeError::Cancelled);
        }
        let bounce_start = Instant::now();
        series.step();
        stats
            .bounce_seconds
            .push(bounce_start.elapsed().as_secs_f64());
        progress.status(&format!("bounce {}/{}", bounce + 1, settings.bounces));
    }
    let indirect = series
        .into_sum()
        .unwrap_or_else(|| TransferVectors::zeros(settings.order, vertex_count));
    stats.total_seconds = traced.seconds + start.elapsed().as_secs_f64();
    progress.finish();
    Ok((
        Transfer {
            settings: *settings,
            direct: traced.direct,
            indirect,
            textured_vertices: geometry
                .objects
                .iter()
                .filter(|o| o.texture.is_some())
                .map(|o| u64::from(o.vertices.end - o.vertices.start))
                .sum(),
        },
        stats,
    ))
}

#[cfg(test)]
mod tests;
