//! Ray casting against the scene: obvhs builds the tree, [`wide`] lays it out four-wide for
//! the CPU, and the traversals here visit it, one ray at a time or, for rays sharing an origin,
//! eight at a time ([`fan`]).

use crate::infra::huge_pages::HugePageTable;
use crate::mesh::TriangleMesh;
pub use cache::{BvhFileError, bvh_key};
use glam::{Vec3, Vec3A};
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::triangle::Triangle;
use stack::{Stack, insert_farthest_first};
use wide::{Bvh4, ChildRef, NO_TRIANGLE, ROUNDING, TrianglePacket, WideRay, moller_trumbore};

mod cache;
mod fan;
mod packet;
mod stack;
#[cfg(test)]
mod testing;
mod wide;

/// Where the ray-epsilon scale of a scene comes from: a fraction of its bounding-box diagonal.
/// The bake and the reference offset every ray by it, so both see the same geometry.
pub const RAY_OFFSET_FRACTION: f32 = 1e-5;

/// How obvhs builds the tree: its slow preset (pre-split triangles, a wider PLOC search), 0.3 s
/// more to build the 202k-triangle dragon than its medium one, for a tree that traces faster.
const TREE: obvhs::BvhBuildParams = obvhs::BvhBuildParams::slow_build();

/// The closest intersection of a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Index of the triangle in the scene mesh.
    pub triangle: u32,
    pub t: f32,
    /// Barycentric weights of the triangle's second and third vertex.
    pub b1: f32,
    pub b2: f32,
}

impl Hit {
    /// Weights of the three vertices, each at least 0: on the edge opposite the first vertex
    /// `1 - b1 - b2` can round to just below 0 (`-2⁻²⁴`), which no point of the triangle has.
    #[inline]
    pub fn barycentrics(&self) -> [f32; 3] {
        [(1.0 - self.b1 - self.b2).max(0.0), self.b1, self.b2]
    }
}

/// A BVH over a triangle mesh, with triangles stored in leaf order, four to a packet.
pub struct SceneBvh {
    tree: Bvh4,
    /// The leaves' triangles, four to a packet, slot `4k + lane` in packet `k`.
    packets: HugePageTable<TrianglePacket>,
    /// Scene triangle index of each leaf slot ([`NO_TRIANGLE`] for padding), with
    /// [`FLIPPED`] set where the packet holds the triangle's corners as `[a, c, b]`.
    ids: HugePageTable<u32>,
    /// Vertex indices of each leaf slot's triangle (the bake skips a vertex's own triangles).
    corners: HugePageTable<[u32; 3]>,
}

/// Set in a slot's id when its packet holds the triangle's corners as `[a, c, b]`: packed, every
/// triangle winds counter-clockwise seen from its front (the side its vertex normals face,
/// [`TriangleMesh::front_normal`]), so the sign of a hit's determinant says which side it meets.
const FLIPPED: u32 = 1 << 31;

/// Triangle `t`'s corners as packed (front counter-clockwise), and whether they were swapped.
pub(super) fn packed_corners(mesh: &TriangleMesh, t: usize) -> ([Vec3; 3], bool) {
    let [a, b, c] = mesh.corners(t);
    if (b - a).cross(c - a).dot(mesh.front_normal(t)) < 0.0 {
        ([a, c, b], true)
    } else {
        ([a, b, c], false)
    }
}

/// A ray: where it starts, where it goes, and how far it is searched (`tmax` shrinks to the
/// closest hit found so far).
#[derive(Debug, Clone, Copy)]
struct SegmentRay {
    origin: Vec3A,
    direction: Vec3A,
    tmax: f32,
}

impl SceneBvh {
    pub fn build(mesh: &TriangleMesh) -> Self {
        Self::build_with(mesh, TREE)
    }

    /// The tree `params` build. Which tree it is changes the work a ray costs, never what it
    /// hits (the tests build others to show it).
    fn build_with(mesh: &TriangleMesh, params: obvhs::BvhBuildParams) -> Self {
        let (tris, flipped): (Vec<Triangle>, Vec<bool>) = (0..mesh.triangle_count())
            .map(|t| {
                let ([a, b, c], flipped) = packed_corners(mesh, t);
                let triangle = Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                };
                (triangle, flipped)
            })
            .unzip();
        let bvh2 = build_bvh2_from_tris(&tris, params, &mut std::time::Duration::default());
        let (tree, ids) = Bvh4::from_bvh2(&bvh2);
        let packets = TrianglePacket::pack(&ids, |i| {
            let t = &tris[i as usize];
            [t.v0, t.v1, t.v2]
        });
        let corners = HugePageTable::new(ids.iter().map(|&i| {
            mesh.triangles
                .get(i as usize)
                .copied()
                .unwrap_or([NO_TRIANGLE; 3])
        }));
        let flag = |i: u32| match flipped.get(i as usize) {
            Some(true) => i | FLIPPED,
            _ => i,
        };
        Self {
            tree,
            packets,
            ids: HugePageTable::new(ids.into_iter().map(flag)),
            corners,
        }
    }

    /// Closest hit along `origin + t·direction`, `t` in `[tmin, tmax]`, ignoring `skip`.
    pub fn closest_hit(
        &self,
        origin: Vec3,
        direction: Vec3,
        tmin: f32,
        tmax: f32,
        skip: Skip,
    ) -> Option<Hit> {
        self.closest_hit_tallied(origin, direction, tmin, tmax, skip, &mut NoTally)
    }

    /// The work [`Self::closest_hit`] does for this ray: the nodes it visits, inner nodes and
    /// leaves. Deterministic (a property of the tree and the ray, not of the
    /// machine), so shards can split a job by it.
    pub fn closest_hit_work(&self, origin: Vec3, direction: Vec3, skip: Skip) -> u32 {
        let mut work = 0;
        self.closest_hit_tallied(origin, direction, 0.0, f32::INFINITY, skip, &mut work);
        work
    }

    #[inline(always)]
    fn closest_hit_tallied(
        &self,
        origin: Vec3,
        direction: Vec3,
        tmin: f32,
        tmax: f32,
        skip: Skip,
        tally: &mut impl Tally,
    ) -> Option<Hit> {
        let mut ray = SegmentRay {
            origin: origin.into(),
            direction: direction.into(),
            tmax,
        };
        let wide = WideRay::new(ray.origin, ray.direction, tmin);
        let mut closest = None;
        let search = (&wide, skip);
        self.closest_below(
            self.tree.root()?,
            search,
            &mut ray.tmax,
            &mut closest,
            tally,
        );
        closest.map(|slot| self.finish(&ray, slot))
    }

    /// Searches the subtree at `start` for a hit nearer than `tmax` (the closest so far, in
    /// slot `closest`), updating both; children are visited nearest first, and of equidistant
    /// triangles the lowest scene index is kept ([`Self::keep_closer`]).
    #[inline(always)]
    fn closest_below(
        &self,
        start: ChildRef,
        (wide, skip): (&WideRay, Skip),
        tmax: &mut f32,
        closest: &mut Option<usize>,
        tally: &mut impl Tally,
    ) {
        let mut stack = Stack::new();
        let mut current = start;
        loop {
            tally.add(1);
            if current.is_inner() {
                let (t_near, mut entered) = self.tree.enter(current.index, wide, *tmax);
                if entered != 0 {
                    // Nearest first: the others wait on the stack, the nearest is next.
                    let mut order = [(0.0f32, current); 4];
                    let mut n = 0;
                    while entered != 0 {
                        let k = entered.trailing_zeros() as usize;
                        entered &= entered - 1;
                        let child = self.tree.child(current.index, k);
                        insert_farthest_first(&mut order, &mut n, (t_near[k], child));
                    }
                    for &(t, child) in &order[..n - 1] {
                        self.prefetch(child);
                        stack.push((child, t));
                    }
                    current = order[n - 1].1;
                    continue;
                }
            } else {
                for packet in Self::packets_of(current) {
                    let (t, mut hits) = self.packets[packet].intersect(wide, *tmax);
                    while hits != 0 {
                        let lane = hits.trailing_zeros() as usize;
                        hits &= hits - 1;
                        let slot = 4 * packet + lane;
                        if !self.skipped(slot, skip) {
                            self.keep_closer(t[lane], slot, tmax, closest);
                        }
                    }
                }
            }
            loop {
                let Some((child, t)) = stack.pop() else {
                    return;
                };
                // The entry test's own slack ([`wide::ROUNDING`]), so that a child is kept or
                // left by the same rule whenever its turn comes.
                if t <= *tmax * ROUNDING {
                    current = child;
                    break;
                }
            }
        }
    }

    /// Keeps a hit at `t` on the triangle in `slot` if it is nearer than the closest so far
    /// (at `tmax`, in slot `closest`) or as near on a triangle of lower scene index: the
    /// answer is then the same whatever order a tree visits its leaves in.
    #[inline(always)]
    fn keep_closer(&self, t: f32, slot: usize, tmax: &mut f32, closest: &mut Option<usize>) {
        let nearer =
            t < *tmax || (t == *tmax && closest.is_some_and(|c| self.id(slot) < self.id(c)));
        if nearer {
            *tmax = t;
            *closest = Some(slot);
        }
    }

    /// Whether anything but `skip` blocks `origin + t·direction`, `t` in `[tmin, tmax]`.
    pub fn occluded(
        &self,
        origin: Vec3,
        direction: Vec3,
        tmin: f32,
        tmax: f32,
        skip: Skip,
    ) -> bool {
        let wide = WideRay::new(origin.into(), direction.into(), tmin);
        let mut stack = Stack::new();
        let Some(mut current) = self.tree.root() else {
            return false;
        };
        loop {
            if current.is_inner() {
                let (_, mut entered) = self.tree.enter(current.index, &wide, tmax);
                while entered != 0 {
                    let k = entered.trailing_zeros() as usize;
                    entered &= entered - 1;
                    let child = self.tree.child(current.index, k);
                    self.prefetch(child);
                    stack.push(child);
                }
            } else {
                for packet in Self::packets_of(current) {
                    let (_, mut hits) = self.packets[packet].intersect(&wide, tmax);
                    while hits != 0 {
                        let lane = hits.trailing_zeros() as usize;
                        hits &= hits - 1;
                        if !self.skipped(4 * packet + lane, skip) {
                            return true;
                        }
                    }
                }
            }
            match stack.pop() {
                Some(child) => current = child,
                None => return false,
            }
        }
    }

    fn finish(&self, ray: &SegmentRay, slot: usize) -> Hit {
        let [v0, e1, e2] = self.packets[slot / 4].lane(slot % 4);
        let (u, v, _, _) =
            moller_trumbore(ray.origin.to_array(), ray.direction.to_array(), v0, e1, e2);
        let (b1, b2) = if self.ids[slot] & FLIPPED != 0 {
            (v, u)
        } else {
            (u, v)
        };
        Hit {
            triangle: self.id(slot),
            t: ray.tmax,
            b1,
            b2,
        }
    }

    /// Asks the cache for a child the traversal will visit later, so that the misses of
    /// all the children a ray enters overlap.
    #[inline(always)]
    fn prefetch(&self, child: ChildRef) {
        if child.is_inner() {
            self.tree.prefetch(child.index);
        } else {
            let packets = Self::packets_of(child);
            crate::infra::prefetch::prefetch_range(
                self.packets.as_ptr().wrapping_add(packets.start),
                packets.len(),
            );
        }
    }

    /// The packets holding a leaf's triangles.
    #[inline(always)]
    fn packets_of(leaf: ChildRef) -> std::ops::Range<usize> {
        let first = leaf.index as usize / 4;
        first..first + (leaf.count as usize).div_ceil(4)
    }

    /// Closest hit along `origin + t·direction`, `t` in `[tmin, tmax]`.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        self.closest_hit(origin, direction, tmin, tmax, Skip::Nothing)
    }

    /// The scene index of the triangle in `slot`.
    #[inline(always)]
    fn id(&self, slot: usize) -> u32 {
        self.ids[slot] & !FLIPPED
    }

    /// Whether a ray leaving with `skip` ignores the triangle in `slot`.
    #[inline(always)]
    fn skipped(&self, slot: usize, skip: Skip) -> bool {
        match skip {
            Skip::Nothing => false,
            Skip::Triangle(t) => self.id(slot) == t,
            Skip::VertexTriangles(v) => self.corners[slot].contains(&v),
        }
    }
}

/// Triangles a ray ignores: those at its origin, which it would otherwise hit at `t ≈ 0`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Skip {
    Nothing,
    /// One scene triangle (the one a ray leaves from).
    Triangle(u32),
    /// Every triangle sharing a vertex (a vertex never shadows itself).
    VertexTriangles(u32),
}

/// Counts the work of a traversal (or, as [`NoTally`], nothing at no cost).
trait Tally {
    fn add(&mut self, n: u32);
}

struct NoTally;

impl Tally for NoTally {
    #[inline(always)]
    fn add(&mut self, _: u32) {}
}

impl Tally for u32 {
    #[inline(always)]
    fn add(&mut self, n: u32) {
        *self += n;
    }
}

#[cfg(test)]
mod tests;
