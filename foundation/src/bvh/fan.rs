//! Tracing a fan: rays that leave one point (the bake's rays of a vertex), eight at a time
//! down the tree together ([`RayPacket`]), each packet visiting a node's children nearest
//! first. A ray gets the answer it gets alone ([`SceneBvh::closest_hit`],
//! [`SceneBvh::occluded`]), bit for bit; what it saves is the box and triangle work its
//! neighbours share.
//!
//! What a ray hits does not depend on the tree, so neither does any bake (issue 57, 2026-12-07,
//! when bake answers were let change once): nothing nearer than `MIN_BOX_DISTANCE` counts,
//! triangles held to the boxes' floor (before, a hit that near counted only where its leaf's
//! box reached past the floor); of triangles hit at the same distance the lowest scene index
//! wins (before, the first a traversal met, so packets traced tied lanes again alone); every
//! box is padded by 2⁻²⁰ of the scene's largest coordinate (the builder's split boxes of a long
//! triangle can leave its edge by an ulp); and a waiting child is kept or left by the entry
//! test's slack. `every_tree_gives_the_same_hits` builds four trees and checks it, and fails
//! without the floor, the tie rule or the padding. The 871k-triangle dragon's bake (256
//! samples, 1 bounce) moved at 1,147 of 435,161 vertices' direct transfer (by up to 0.19, an
//! RMS of 0.0005 over all coefficients) and its white-furnace mean from 0.50772 to 0.50783:
//! rays that stopped on a neighbour within 1e-4 of their origin now pass it.
//!
//! Held to the floor on both sides, though, a surface lying on another lost it: the glTF
//! crate's sides, where they stand on the plinth, gathered the plinth's inside instead of its
//! lit top, and the crate report got worse (prt 0.0127 to 0.0143, hybrid 0.0076 to 0.0088).
//! So a front counts however near (down to the floor behind the origin, at `t = 0`), a back
//! from the floor on: the seam a ray leaves is behind it, the surface it lies on in front.
//! The crate's report (`hprt report scenes/models/crate.glb --envs scenes/env/city.exr`,
//! 512 spp) then gave prt 0.0108 and hybrid 0.0051, better than under either earlier rule.
//! Packed triangles wind counter-clockwise seen from their front, so the determinant's sign
//! tells the sides apart at the cost of one select per test. Boxes are now entered from the
//! floor behind the origin, so a fan enters the leaves around its vertex that it used to cull
//! (4% slower on the 871k dragon at 32 samples, one thread, best of three); a leaf's skipped
//! triangles (the vertex's own) are now passed over before their ray test, which won it back
//! (6.74 against 6.75 s before this change).
//!
//! Trees measured since (871k dragon, 256 samples, direct pass, 2 threads, Xeon, 2026-12-07):
//! obvhs's slow preset as before 5.43 M rays/s; more reinsertion (`0.5`, `1×` after collapse)
//! 5.17; the very slow preset's search with full reinsertion 4.99; four triangles a leaf
//! 4.84; a collapse cost of 2 instead of 3 5.16. The slow preset stays. On the same rays
//! Embree 4.4's single-ray closest hit traced 3.91 M rays/s. Tracing a packet's lanes alone
//! once two or three remain, rather than one, was no faster on the bundled dragon at 64
//! samples, where packets part most (2.05–2.34 against 2.20–2.46 M rays/s, measured beside
//! another job). Ordering a fan's rays coherently (by the Morton code of each ray's point on
//! the projected disk, its hits scattered back so the bake's bits stay the same) helped the
//! bundled dragon at 64 samples a little (3.62 to 3.66 and 3.38 to 3.58 M rays/s) and hurt
//! at 1024 samples (5.34 to 4.91) and on the 871k dragon at 64 (3.58 to 3.24): not kept.
//!
//! Earlier attempts, answers unchanged each time (2026-12-03, Zen 1): an eight-wide tree for
//! the fans, 5–10% slower than these packets, which test each child box for their eight
//! lanes, so a wider node costs them more than the levels it saves (`attempt/bvh8-fans`);
//! culling a node's children by the packet's frustum (`attempt/packet-frustum`), a vector
//! reduction for the children's nearest entries and a branch-free ranking of them
//! (`attempt/packet-ordering`), four-lane packets (`attempt/packet4`), sixteen-lane packets
//! (`attempt/packet16`) and laying a node's inner children side by side
//! (`attempt/node-layout`) gained nothing; packets of eight rays from different vertices,
//! a chunk's rays sorted by direction, were much slower (1.8 against 3.2 M rays/s,
//! `attempt/bundles`): lanes that start at different points part in the first leaves, where
//! a fan's lanes, sharing their origin, stay together. Tracing every fan twice in a row took
//! 1.74 times as long as once: cache misses are not where most of the time goes.
//!
//! Not built, and why. Embree's box test (one fused multiply-add a plane, the origin's term
//! folded in): a fan's packets already pay one multiply a plane and lane, the origin's offset
//! to a node's planes taken once for its eight rays, and the single-ray test would need FMA,
//! which the portable build (x86-64 without it) calls through libm. Compressed nodes
//! (quantised child boxes): they save memory traffic, and a fan traced twice in a row from a
//! warm cache costs three quarters of the first pass, so traffic is not where the time goes,
//! while dequantising adds work per box. An eight-wide single-ray path for the lanes a packet
//! leaves alone: it needs a second, eight-wide tree beside the four-wide one the packets
//! trace (eight-wide costs the packets 5–10%, above), and memory is not to grow.

use super::packet::{LANES, RayPacket};
use super::stack::{Stack, insert_farthest_first};
use super::wide::{ChildRef, ROUNDING};
use super::{Hit, NoTally, SceneBvh, SegmentRay, Skip};
use glam::Vec3;
use wide::f32x8;

/// Lanes few enough to be traced alone from where they are: a single ray tests a node's four
/// boxes, and a leaf's triangles four at a time, in one vector operation where a packet takes
/// one per box and per triangle.
const ALONE: u32 = 1;

/// A child a packet has still to visit: the lanes that entered it, and where each did.
#[derive(Clone, Copy)]
struct Pending {
    child: ChildRef,
    lanes: u32,
    near: f32x8,
}

/// A packet's closest hits so far: per lane, its distance (the search's far end) and slot.
struct Closest {
    tmax: f32x8,
    slot: [Option<usize>; LANES],
}

impl SceneBvh {
    /// The closest hit of each ray from `origin` along `directions`, `t` in `[tmin, tmax]`,
    /// ignoring `skip`: into `hits`, one per direction, in order.
    pub fn closest_hits(
        &self,
        origin: Vec3,
        directions: &[Vec3],
        (tmin, tmax): (f32, f32),
        skip: Skip,
        hits: &mut Vec<Option<Hit>>,
    ) {
        hits.clear();
        for chunk in directions.chunks(LANES) {
            let packet = RayPacket::new(origin, chunk, tmin);
            let closest = self.packet_closest(&packet, tmax, skip);
            let distances = closest.tmax.to_array();
            for (lane, direction) in chunk.iter().enumerate() {
                let ray = SegmentRay {
                    origin: origin.into(),
                    direction: (*direction).into(),
                    tmax: distances[lane],
                };
                hits.push(closest.slot[lane].map(|slot| self.finish(&ray, slot)));
            }
        }
    }

    /// Whether anything but `skip` blocks each ray from `origin` along `directions`, `t` in
    /// `[tmin, tmax]`: into `blocked`, one per direction, in order.
    pub fn occluded_fan(
        &self,
        origin: Vec3,
        directions: &[Vec3],
        (tmin, tmax): (f32, f32),
        skip: Skip,
        blocked: &mut Vec<bool>,
    ) {
        blocked.clear();
        for chunk in directions.chunks(LANES) {
            let packet = RayPacket::new(origin, chunk, tmin);
            let mask = self.packet_occluded(&packet, tmax, skip);
            blocked.extend((0..chunk.len()).map(|lane| mask & (1 << lane) != 0));
        }
    }

    fn packet_closest(&self, packet: &RayPacket, tmax: f32, skip: Skip) -> Closest {
        let mut closest = Closest {
            tmax: f32x8::splat(tmax),
            slot: [None; LANES],
        };
        let Some(mut current) = self.tree.root() else {
            return closest;
        };
        let mut lanes = packet.lanes;
        let mut stack = Stack::<Pending>::new();
        loop {
            if lanes.count_ones() <= ALONE {
                self.lanes_alone(current, lanes, packet, skip, &mut closest);
            } else if current.is_inner() {
                if let Some(next) = self.descend(current, lanes, packet, closest.tmax, &mut stack) {
                    (current, lanes) = next;
                    continue;
                }
            } else {
                self.leaf_closest(current, lanes, packet, skip, &mut closest);
            }
            // The next child some lane still has to visit: one whose box it enters before
            // its closest hit so far.
            loop {
                let Some(pending) = stack.pop() else {
                    return closest;
                };
                // The entry test's slack, as a single ray's (`SceneBvh::closest_below`).
                let far = closest.tmax * f32x8::splat(ROUNDING);
                let open = pending.lanes & pending.near.simd_le(far).to_bitmask();
                if open != 0 {
                    (current, lanes) = (pending.child, open);
                    break;
                }
            }
        }
    }

    /// Tests inner node `node`'s children for the packet's `lanes`; of those entered, leaves
    /// all but the nearest on the stack (farthest deepest) and returns the nearest with its
    /// lanes. A child's distance is its nearest lane's entry.
    #[inline(always)]
    fn descend(
        &self,
        node: ChildRef,
        lanes: u32,
        packet: &RayPacket,
        tmax: f32x8,
        stack: &mut Stack<Pending>,
    ) -> Option<(ChildRef, u32)> {
        let children = (self.tree.occupied(node.index), lanes);
        let entries = packet.enter(self.tree.planes(node.index), children, tmax);
        let mut order = [(0.0f32, (0usize, 0u32)); 4];
        let mut n = 0;
        for k in 0..4 {
            let entered = entries.lanes[k];
            if entered == 0 {
                continue;
            }
            insert_farthest_first(&mut order, &mut n, (entries.nearest[k], (k, entered)));
        }
        let (_, (nearest, nearest_lanes)) = *order[..n].last()?;
        for &(_, (k, entered)) in &order[..n - 1] {
            let child = self.tree.child(node.index, k);
            self.prefetch(child);
            stack.push(Pending {
                child,
                lanes: entered,
                near: entries.near[k],
            });
        }
        Some((self.tree.child(node.index, nearest), nearest_lanes))
    }

    /// Searches the subtree at `start` for each of the packet's `lanes` alone (as
    /// [`SceneBvh::closest_hit`] does), from its closest hit so far.
    #[inline(always)]
    fn lanes_alone(
        &self,
        start: ChildRef,
        mut lanes: u32,
        packet: &RayPacket,
        skip: Skip,
        closest: &mut Closest,
    ) {
        let mut tmax = closest.tmax.to_array();
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let ray = packet.lane(lane);
            let slot = &mut closest.slot[lane];
            self.closest_below(start, (&ray, skip), &mut tmax[lane], slot, &mut NoTally);
        }
        closest.tmax = f32x8::new(tmax);
    }

    /// Tests a leaf's triangles for the packet's `lanes`, keeping each lane's closest hit.
    #[inline(always)]
    fn leaf_closest(
        &self,
        leaf: ChildRef,
        lanes: u32,
        packet: &RayPacket,
        skip: Skip,
        closest: &mut Closest,
    ) {
        let first = leaf.index as usize;
        for slot in first..first + leaf.count as usize {
            // Skipped first: a vertex's own triangles, in the leaves every ray of its fan
            // leaves through, cost a comparison instead of eight ray tests.
            if self.skipped(slot, skip) {
                continue;
            }
            let triangle = self.packets[slot / 4].lane(slot % 4);
            let (t, hits) = packet.intersect(triangle, closest.tmax);
            let mut hits = hits & lanes;
            if hits == 0 {
                continue;
            }
            let t = t.to_array();
            let mut tmax = closest.tmax.to_array();
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                self.keep_closer(t[lane], slot, &mut tmax[lane], &mut closest.slot[lane]);
            }
            closest.tmax = f32x8::new(tmax);
        }
    }

    /// The mask of the packet's lanes that something but `skip` blocks; a lane stops at its
    /// first blocker, the packet when every lane has.
    fn packet_occluded(&self, packet: &RayPacket, tmax: f32, skip: Skip) -> u32 {
        let far = f32x8::splat(tmax);
        let mut blocked = 0;
        let Some(mut current) = self.tree.root() else {
            return blocked;
        };
        let mut lanes = packet.lanes;
        let mut stack = Stack::<(ChildRef, u32)>::new();
        loop {
            if current.is_inner() {
                let children = (self.tree.occupied(current.index), lanes);
                let entries = packet.enter(self.tree.planes(current.index), children, far);
                for (k, &entered) in entries.lanes.iter().enumerate() {
                    if entered != 0 {
                        let child = self.tree.child(current.index, k);
                        self.prefetch(child);
                        stack.push((child, entered));
                    }
                }
            } else {
                let first = current.index as usize;
                for slot in first..first + current.count as usize {
                    let triangle = self.packets[slot / 4].lane(slot % 4);
                    let (_, hits) = packet.intersect(triangle, far);
                    let hits = hits & lanes & !blocked;
                    if hits != 0 && !self.skipped(slot, skip) {
                        blocked |= hits;
                        if packet.lanes & !blocked == 0 {
                            return blocked;
                        }
                    }
                }
            }
            loop {
                let Some((child, waiting)) = stack.pop() else {
                    return blocked;
                };
                if waiting & !blocked != 0 {
                    (current, lanes) = (child, waiting & !blocked);
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::Soup;
    use super::*;
    use crate::mesh::TriangleMesh;

    /// Fans from inside and outside a triangle soup, of sizes that leave partial packets:
    /// every ray's hit, bit for bit, and its occlusion are those it gets alone, and those of
    /// testing every triangle.
    #[test]
    fn fans_agree_with_single_rays_and_with_testing_every_triangle() {
        let mut soup = Soup::new(11);
        let bvh = SceneBvh::build(&soup.mesh);
        let (mut hits, mut rays) = (0, 0);
        let (mut found, mut blocked) = (Vec::new(), Vec::new());
        for fan in 0..120u32 {
            let origin = soup.point(if fan % 2 == 0 { 3.0 } else { 9.0 });
            let count = [1, 7, 8, 9, 37, 64][fan as usize % 6];
            let directions: Vec<Vec3> = (0..count).map(|k| soup.direction(fan + k)).collect();
            let tmax = if fan % 3 == 0 { 2.0 } else { f32::INFINITY };
            let skip = Skip::Triangle(fan * 17 % 3000);
            bvh.closest_hits(origin, &directions, (0.0, tmax), skip, &mut found);
            bvh.occluded_fan(origin, &directions, (0.0, tmax), skip, &mut blocked);
            assert_eq!(
                (found.len(), blocked.len()),
                (directions.len(), directions.len())
            );
            for (k, &direction) in directions.iter().enumerate() {
                let alone = bvh.closest_hit(origin, direction, 0.0, tmax, skip);
                assert_eq!(found[k], alone, "fan {fan}, ray {k}");
                let expected = soup.closest(origin, direction, tmax, skip);
                assert_eq!(found[k].map(|h| (h.t, h.triangle)), expected);
                assert_eq!(blocked[k], expected.is_some(), "fan {fan}, ray {k}");
                hits += usize::from(expected.is_some());
                rays += 1;
            }
        }
        assert!(
            hits > rays / 4 && hits < rays * 3 / 4,
            "{hits} hits of {rays}"
        );
    }

    /// Two tessellations of one square, cells of 1 and of 2, split along opposite diagonals:
    /// every ray meets two triangles at exactly the same distance (all the arithmetic is
    /// exact up to powers of two), often in different leaves. Fans and lone rays keep the
    /// same one, the first tessellation's (the lower index).
    #[test]
    fn fans_settle_ties_as_single_rays_do() {
        let mut mesh = TriangleMesh::default();
        for (cell, flip) in [(1.0, false), (2.0, true)] {
            let n = (8.0 / cell) as usize;
            for (i, j) in (0..n).flat_map(|i| (0..n).map(move |j| (i, j))) {
                let corner = |di: usize, dj: usize| {
                    Vec3::new((i + di) as f32 * cell, (j + dj) as f32 * cell, 0.0)
                };
                let [a, b, c, d] = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                let halves = if flip {
                    [[a, b, d], [b, c, d]]
                } else {
                    [[a, b, c], [a, c, d]]
                };
                for triangle in halves {
                    let first = mesh.positions.len() as u32;
                    mesh.positions.extend(triangle);
                    mesh.normals.extend([Vec3::Z; 3]);
                    mesh.triangles.push([first, first + 1, first + 2]);
                }
            }
        }
        let bvh = SceneBvh::build(&mesh);
        let mut soup = Soup::new(3);
        let mut found = Vec::new();
        let mut hits = 0;
        for fan in 0..200 {
            let origin = Vec3::new(4.0, 4.0, 3.0) + soup.point(3.0) * Vec3::new(1.0, 1.0, 0.0);
            let directions: Vec<Vec3> = (0..32)
                .map(|_| (soup.point(1.0) * Vec3::new(1.0, 1.0, 0.0) - Vec3::Z).normalize())
                .collect();
            bvh.closest_hits(
                origin,
                &directions,
                (0.0, f32::INFINITY),
                Skip::Nothing,
                &mut found,
            );
            for (k, &direction) in directions.iter().enumerate() {
                let alone = bvh.closest_hit(origin, direction, 0.0, f32::INFINITY, Skip::Nothing);
                assert_eq!(found[k], alone, "fan {fan}, ray {k}");
                assert!(alone.is_none_or(|h| h.triangle < 128), "fan {fan}, ray {k}");
                hits += usize::from(alone.is_some());
            }
        }
        assert!(hits > 3000, "{hits} of 6400 rays reach the square");
    }
}
