//! A four-wide BVH laid out for CPU traversal: each node holds its four children's boxes as
//! full-precision planes side by side, tested together with one set of SIMD operations, and
//! children are visited nearest first. The tree itself is obvhs's (PLOC with pre-splitting,
//! reinsertion and leaf collapse): only its binary nodes are regrouped by fours.
//!
//! obvhs's own compressed wide BVH is designed for GPUs: on a CPU its quantised boxes must be
//! decoded at every node, and its children come in a fixed order per ray octant.

use crate::infra::huge_pages::HugePageTable;
use glam::{Vec3A, Vec4};
use obvhs::bvh2::Bvh2;

/// Four children: their boxes as planes (`min x, min y, min z, max x, max y, max z`, each
/// for the four), and what each is.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(super) struct Node4 {
    planes: [Vec4; 6],
    /// Inner child: its node's index. Leaf child: its first triangle slot.
    child: [u32; 4],
    /// Leaf child: its number of triangles; inner child: [`INNER`]; empty slot: 0 (with a
    /// box no ray enters).
    count: [u32; 4],
}

const INNER: u32 = u32::MAX;

/// One child reference: an inner node or a run of triangle slots.
#[derive(Debug, Clone, Copy)]
pub(super) struct ChildRef {
    pub index: u32,
    pub count: u32,
}

impl ChildRef {
    #[inline(always)]
    pub(super) fn is_inner(&self) -> bool {
        self.count == INNER
    }
}

/// A padding slot of a leaf's last packet.
pub(super) const NO_TRIANGLE: u32 = u32::MAX;

/// The regrouped tree: nodes in depth-first order (the root first).
#[derive(Debug)]
pub(super) struct Bvh4 {
    nodes: HugePageTable<Node4>,
    /// What a ray starts from: the root node, or the single leaf of a tiny mesh.
    root: Option<ChildRef>,
}

/// What regrouping builds up: the nodes, and for each triangle slot the index of the obvhs
/// primitive it holds (leaves start on a multiple of four: their triangles are tested by
/// packets of four).
struct Builder<'a> {
    bvh2: &'a Bvh2,
    /// Added to every box on every side ([`BOX_PADDING`]).
    padding: f32,
    nodes: Vec<Node4>,
    slots: Vec<u32>,
}

impl Bvh4 {
    /// Regroups `bvh2`'s binary nodes by fours: a node takes its two children and keeps
    /// opening its largest inner child (by surface area) until it has four. Returns the tree
    /// and, per triangle slot, the obvhs primitive it holds ([`NO_TRIANGLE`] for padding).
    pub(super) fn from_bvh2(bvh2: &Bvh2) -> (Self, Vec<u32>) {
        let magnitude = bvh2.nodes.first().map_or(0.0, |root| {
            let aabb = root.aabb();
            aabb.min.abs().max(aabb.max.abs()).max_element()
        });
        let mut builder = Builder {
            bvh2,
            padding: magnitude * BOX_PADDING,
            nodes: Vec::new(),
            slots: Vec::new(),
        };
        let root = bvh2.nodes.first().map(|root| {
            if root.prim_count > 0 {
                builder.leaf(0)
            } else {
                ChildRef {
                    index: builder.node(0),
                    count: INNER,
                }
            }
        });
        let tree = Self {
            nodes: HugePageTable::new(builder.nodes.into_iter()),
            root,
        };
        (tree, builder.slots)
    }
}

impl Builder<'_> {
    /// Appends a leaf's triangles, padded to whole packets of four with [`NO_TRIANGLE`].
    fn leaf(&mut self, node: usize) -> ChildRef {
        let n = &self.bvh2.nodes[node];
        let first = self.slots.len() as u32;
        let start = n.first_index as usize;
        self.slots
            .extend_from_slice(&self.bvh2.primitive_indices[start..start + n.prim_count as usize]);
        while !self.slots.len().is_multiple_of(4) {
            self.slots.push(NO_TRIANGLE);
        }
        ChildRef {
            index: first,
            count: n.prim_count,
        }
    }

    /// Appends the four-wide node for binary inner node `node`, then its subtrees; returns
    /// its index.
    fn node(&mut self, node: usize) -> u32 {
        let bvh2 = self.bvh2;
        let first = bvh2.nodes[node].first_index as usize;
        let mut group = vec![first, first + 1];
        while group.len() < 4 {
            let widest = group
                .iter()
                .enumerate()
                .filter(|(_, c)| bvh2.nodes[**c].prim_count == 0)
                .max_by(|(_, a), (_, b)| {
                    let area = |c: usize| bvh2.nodes[c].aabb().half_area();
                    area(**a).total_cmp(&area(**b))
                })
                .map(|(k, _)| k);
            let Some(k) = widest else { break };
            let opened = group.swap_remove(k);
            let children = bvh2.nodes[opened].first_index as usize;
            group.extend([children, children + 1]);
        }
        let index = self.nodes.len();
        self.nodes.push(Node4 {
            planes: [
                Vec4::splat(f32::INFINITY),
                Vec4::splat(f32::INFINITY),
                Vec4::splat(f32::INFINITY),
                Vec4::splat(f32::NEG_INFINITY),
                Vec4::splat(f32::NEG_INFINITY),
                Vec4::splat(f32::NEG_INFINITY),
            ],
            child: [0; 4],
            count: [0; 4],
        });
        for (k, &c) in group.iter().enumerate() {
            let aabb = *bvh2.nodes[c].aabb();
            let reference = if bvh2.nodes[c].prim_count > 0 {
                self.leaf(c)
            } else {
                ChildRef {
                    index: self.node(c),
                    count: INNER,
                }
            };
            let n = &mut self.nodes[index];
            for axis in 0..3 {
                n.planes[axis][k] = aabb.min[axis] - self.padding;
                n.planes[3 + axis][k] = aabb.max[axis] + self.padding;
            }
            n.child[k] = reference.index;
            n.count[k] = reference.count;
        }
        index as u32
    }
}

/// Words of a [`Node4`] in a file: 24 plane values (as bits), 4 children, 4 counts.
pub(super) const NODE_WORDS: usize = 32;

impl Node4 {
    pub(super) fn to_words(self) -> [u32; NODE_WORDS] {
        let mut words = [0u32; NODE_WORDS];
        let planes = self
            .planes
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits));
        let rest = self.child.into_iter().chain(self.count);
        for (word, value) in words.iter_mut().zip(planes.chain(rest)) {
            *word = value;
        }
        words
    }

    /// The node of `words` ([`NODE_WORDS`] of them).
    pub(super) fn from_words(words: &[u32]) -> Self {
        let plane =
            |k: usize| Vec4::from_array(std::array::from_fn(|i| f32::from_bits(words[4 * k + i])));
        Self {
            planes: std::array::from_fn(plane),
            child: std::array::from_fn(|i| words[24 + i]),
            count: std::array::from_fn(|i| words[28 + i]),
        }
    }

    /// Its children as references (empty slots left out).
    pub(super) fn children(&self) -> impl Iterator<Item = ChildRef> + '_ {
        (0..4).filter(|k| self.count[*k] != 0).map(|k| ChildRef {
            index: self.child[k],
            count: self.count[k],
        })
    }
}

impl Bvh4 {
    /// The nodes, root first, and what a ray starts from.
    pub(super) fn parts(&self) -> (&[Node4], Option<ChildRef>) {
        (&self.nodes, self.root)
    }

    /// The tree of `nodes` and `root` (checked by the caller).
    pub(super) fn from_parts(nodes: Vec<Node4>, root: Option<ChildRef>) -> Self {
        Self {
            nodes: HugePageTable::new(nodes.into_iter()),
            root,
        }
    }

    #[inline(always)]
    pub(super) fn prefetch(&self, node: u32) {
        crate::infra::prefetch::prefetch(self.nodes.as_ptr().wrapping_add(node as usize));
    }

    pub(super) fn root(&self) -> Option<ChildRef> {
        self.root
    }

    #[inline(always)]
    pub(super) fn child(&self, node: u32, k: usize) -> ChildRef {
        let n = &self.nodes[node as usize];
        ChildRef {
            index: n.child[k],
            count: n.count[k],
        }
    }

    /// `node`'s four children's boxes as planes (see [`Node4`]).
    #[inline(always)]
    pub(super) fn planes(&self, node: u32) -> &[Vec4; 6] {
        &self.nodes[node as usize].planes
    }

    /// The mask of `node`'s slots that hold a child (an empty slot's box is inside out).
    #[inline(always)]
    pub(super) fn occupied(&self, node: u32) -> u32 {
        let count = &self.nodes[node as usize].count;
        (0..4).fold(0, |mask, k| mask | (u32::from(count[k] != 0) << k))
    }

    /// Entry distance of the ray into each of `node`'s four children, and the mask of those
    /// it enters within `[tmin, tmax]`.
    #[inline(always)]
    pub(super) fn enter(&self, node: u32, ray: &WideRay, tmax: f32) -> (Vec4, u32) {
        let n = &self.nodes[node as usize];
        let slab = |plane: usize, axis: usize| (n.planes[plane] - ray.origin[axis]) * ray.inv[axis];
        let t_near = slab(ray.near[0], 0)
            .max(slab(ray.near[1], 1))
            .max(slab(ray.near[2], 2).max(Vec4::splat(ray.floors.boxes())));
        let t_far = slab(ray.far[0], 0)
            .min(slab(ray.far[1], 1))
            .min(slab(ray.far[2], 2).min(Vec4::splat(tmax)))
            * ROUNDING;
        (t_near, t_near.cmple(t_far).bitmask())
    }
}

/// Slack on the far distance so that rounding never loses a box the ray grazes (Ize 2013:
/// `1 + 2γ₃`); a child waiting on the stack is kept or left by the same slack.
pub(super) const ROUNDING: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Padding of every box, relative to the scene's largest coordinate (2⁻²⁰): the builder's
/// split boxes of a long triangle (pre-splits) meet its edges at rounded points, so a box
/// can leave the triangle's true edge by an ulp of the coordinates; padded, it holds it.
const BOX_PADDING: f32 = 1.0 / (1u32 << 20) as f32;

/// A ray prepared for box and packet tests: each component splatted across four lanes.
#[derive(Debug, Clone, Copy)]
pub(super) struct WideRay {
    pub origin: [Vec4; 3],
    pub direction: [Vec4; 3],
    inv: [Vec4; 3],
    /// Per axis, which plane the ray meets first: min (`axis`) for a positive direction,
    /// max (`axis + 3`) for a negative one; `far` is the other.
    near: [usize; 3],
    far: [usize; 3],
    /// Where a hit on a triangle's front and on its back starts counting (and boxes,
    /// [`Floors::boxes`]).
    floors: Floors,
}

impl WideRay {
    pub(super) fn new(origin: Vec3A, direction: Vec3A, tmin: f32) -> Self {
        let inv = [
            safe_inverse(direction.x),
            safe_inverse(direction.y),
            safe_inverse(direction.z),
        ];
        Self::with_inverse(origin.to_array(), direction.to_array(), inv, tmin)
    }

    /// The ray with its direction's inverse already worked out (by [`safe_inverse`]).
    pub(super) fn with_inverse(
        origin: [f32; 3],
        direction: [f32; 3],
        inv: [f32; 3],
        tmin: f32,
    ) -> Self {
        let near = |k: usize| if inv[k] >= 0.0 { k } else { k + 3 };
        let far = |k: usize| if inv[k] >= 0.0 { k + 3 } else { k };
        Self {
            origin: origin.map(Vec4::splat),
            direction: direction.map(Vec4::splat),
            inv: inv.map(Vec4::splat),
            near: [near(0), near(1), near(2)],
            far: [far(0), far(1), far(2)],
            floors: Floors::new(tmin),
        }
    }
}

/// `1 / d` for a slab test. A zero component would give 0 · ∞ = NaN; a tiny one keeps the
/// arithmetic finite and the answer the same.
#[inline(always)]
pub(super) fn safe_inverse(d: f32) -> f32 {
    1.0 / if d.abs() < 1e-30 {
        1e-30f32.copysign(d)
    } else {
        d
    }
}

/// How near a hit on the back of a triangle may be and still count: `t >= MIN_BOX_DISTANCE`
/// (obvhs's `EPSILON` for boxes). So a ray leaving a seam of an unwelded mesh does not stop
/// on the neighbour touching its origin, whose back it leaves through (the bake's furnace
/// tests rest on it). The front of a triangle counts however near, down to this distance
/// behind the origin, as `t = 0` ([`Floors`]): a surface lying on another (a crate standing
/// on a plinth) sees it, as it would from a hair above it. Boxes are entered from the same
/// distance behind, so what a ray hits is the same in every tree: no near hit counts only
/// where its leaf's box happens to reach far enough.
pub(super) const MIN_BOX_DISTANCE: f32 = 1e-4;

/// Where hits start counting for a ray searched from `tmin`: on a triangle's front, on its
/// back, and (the lower) for boxes. A `tmin` past [`MIN_BOX_DISTANCE`] is every floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Floors {
    pub front: f32,
    pub back: f32,
}

impl Floors {
    #[inline(always)]
    pub(super) fn new(tmin: f32) -> Self {
        if tmin > MIN_BOX_DISTANCE {
            Self {
                front: tmin,
                back: tmin,
            }
        } else {
            Self {
                front: -MIN_BOX_DISTANCE,
                back: MIN_BOX_DISTANCE,
            }
        }
    }

    /// Where boxes start counting: the front's floor, never past the back's (a box holds
    /// every hit that counts).
    #[inline(always)]
    pub(super) fn boxes(self) -> f32 {
        self.front
    }
}

/// Arithmetic on one value or on four side by side: what the triangle test is written over.
pub(super) trait Lanes:
    Copy
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    const ONE: Self;
}

impl Lanes for f32 {
    const ONE: Self = 1.0;
}

impl Lanes for Vec4 {
    const ONE: Self = Vec4::ONE;
}

impl Lanes for wide::f32x8 {
    const ONE: Self = wide::f32x8::ONE;
}

#[inline(always)]
pub(super) fn cross<T: Lanes>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
pub(super) fn dot<T: Lanes>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Möller–Trumbore, for one triangle (`f32`) or four (`Vec4`): the same operations in the
/// same order, so a packet's lane gives its triangle's answer bit for bit. Returns `(u, v,
/// t, 1/det)`: the barycentric weights of the second and third vertex, the distance (all NaN
/// for a ray in the triangle's plane, which then fails every comparison), and the inverse
/// determinant, positive when the ray meets the front (counter-clockwise) side.
#[inline(always)]
pub(super) fn moller_trumbore<T: Lanes>(
    origin: [T; 3],
    direction: [T; 3],
    v0: [T; 3],
    e1: [T; 3],
    e2: [T; 3],
) -> (T, T, T, T) {
    let p = cross(direction, e2);
    let inv_det = T::ONE / dot(e1, p);
    let s = [origin[0] - v0[0], origin[1] - v0[1], origin[2] - v0[2]];
    let q = cross(s, e1);
    (
        dot(s, p) * inv_det,
        dot(direction, q) * inv_det,
        dot(e2, q) * inv_det,
        inv_det,
    )
}

/// Four triangles side by side: first vertices and edges, per axis.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(16))]
pub(super) struct TrianglePacket {
    pub v0: [Vec4; 3],
    pub e1: [Vec4; 3],
    pub e2: [Vec4; 3],
}

impl TrianglePacket {
    /// Packs `corners(slot)` for each slot; a padding slot gets a triangle no ray hits.
    pub(super) fn pack(slots: &[u32], corners: impl Fn(u32) -> [Vec3A; 3]) -> HugePageTable<Self> {
        HugePageTable::new(slots.chunks(4).map(|chunk| {
            let mut packet = Self {
                v0: [Vec4::ZERO; 3],
                e1: [Vec4::ZERO; 3],
                e2: [Vec4::ZERO; 3],
            };
            for (lane, &slot) in chunk.iter().enumerate() {
                if slot == NO_TRIANGLE {
                    continue;
                }
                let [a, b, c] = corners(slot);
                for axis in 0..3 {
                    packet.v0[axis][lane] = a[axis];
                    packet.e1[axis][lane] = b[axis] - a[axis];
                    packet.e2[axis][lane] = c[axis] - a[axis];
                }
            }
            packet
        }))
    }

    /// Distances to the four triangles (a front hit behind the origin at 0), and the mask of
    /// those hit within the ray's floors ([`Floors`]) and `tmax`.
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &WideRay, tmax: f32) -> (Vec4, u32) {
        let (u, v, t, inv_det) =
            moller_trumbore(ray.origin, ray.direction, self.v0, self.e1, self.e2);
        let floor = Vec4::select(
            inv_det.cmpgt(Vec4::ZERO),
            Vec4::splat(ray.floors.front),
            Vec4::splat(ray.floors.back),
        );
        let distance = t.max(Vec4::ZERO);
        let hit = u.cmpge(Vec4::ZERO)
            & v.cmpge(Vec4::ZERO)
            & (u + v).cmple(Vec4::ONE)
            & t.cmpge(floor)
            & distance.cmple(Vec4::splat(tmax));
        (distance, hit.bitmask())
    }

    /// One lane's triangle: first vertex and edges.
    pub(super) fn lane(&self, lane: usize) -> [[f32; 3]; 3] {
        let get = |v: &[Vec4; 3]| [v[0][lane], v[1][lane], v[2][lane]];
        [get(&self.v0), get(&self.e1), get(&self.e2)]
    }
}
