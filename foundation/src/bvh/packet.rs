//! Eight rays that leave one point, tested together against a node's four boxes and against
//! one triangle. Lane for lane the arithmetic is the single-ray tests' of [`super::wide`], so
//! a ray in a packet meets every box and triangle exactly as it does alone; what the rays
//! share is computed once: the origin's offsets to the box planes, and the triangle terms that
//! depend on the origin alone.

use super::wide::{Floors, Lanes, ROUNDING, WideRay, cross, dot};
use glam::{Vec3, Vec4};
use wide::{f32x8, i32x8};

/// Rays per packet.
pub(super) const LANES: usize = 8;

/// What a packet's box test finds for a node's four children.
pub(super) struct Entries {
    /// Each lane's entry distance.
    pub(super) near: [f32x8; 4],
    /// The lanes entering.
    pub(super) lanes: [u32; 4],
    /// The nearest entry of those lanes (+∞ for none).
    pub(super) nearest: [f32; 4],
}

const ROUNDING_X8: f32x8 = f32x8::splat(ROUNDING);

/// The lanes in bit mask `bits` as a vector mask.
#[inline(always)]
fn lane_mask(bits: u32) -> f32x8 {
    let lane_bits = i32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
    let set = (i32x8::splat(bits as i32) & lane_bits).simd_eq(lane_bits);
    wide::bytemuck::cast(set)
}

/// [`super::wide::safe_inverse`] of each lane, bit for bit.
#[inline(always)]
fn safe_inverses(d: f32x8) -> f32x8 {
    let tiny = f32x8::splat(1e-30);
    let signed_tiny = (d & f32x8::splat(-0.0)) | tiny;
    f32x8::ONE / d.abs().simd_lt(tiny).bitselect(signed_tiny, d)
}

/// The smallest lane (no NaN among them).
#[inline(always)]
fn smallest(v: f32x8) -> f32 {
    let a = v.to_array();
    let min = |x: f32, y: f32| if y < x { y } else { x };
    min(
        min(min(a[0], a[1]), min(a[2], a[3])),
        min(min(a[4], a[5]), min(a[6], a[7])),
    )
}

/// Up to eight rays from one origin, one per lane.
#[derive(Debug, Clone, Copy)]
pub(super) struct RayPacket {
    origin: [f32; 3],
    direction: [f32x8; 3],
    inv: [f32x8; 3],
    /// Nearest box entry (the single ray's rule, [`Floors`]).
    tmin: f32x8,
    /// Nearest hit on a triangle's front, on its back.
    front: f32x8,
    back: f32x8,
    /// Per axis, whether the direction is positive, when that is so of every lane or of none.
    octant: Option<[bool; 3]>,
    /// The lanes that hold a ray (a fan's last packet may be partial).
    pub(super) lanes: u32,
}

impl RayPacket {
    /// The rays from `origin` along `directions` (one to eight); lanes past them repeat the
    /// first ray and are left out of `lanes`.
    pub(super) fn new(origin: Vec3, directions: &[Vec3], tmin: f32) -> Self {
        debug_assert!((1..=LANES).contains(&directions.len()));
        let lane = |k: usize| directions.get(k).unwrap_or(&directions[0]);
        let direction = [0, 1, 2].map(|a| f32x8::new(std::array::from_fn(|k| lane(k)[a])));
        let inv = direction.map(safe_inverses);
        let signs = inv.map(|v| v.simd_ge(f32x8::ZERO).to_bitmask());
        let octant = signs
            .iter()
            .all(|&s| s == 0 || s == 0xff)
            .then(|| signs.map(|s| s == 0xff));
        let floors = Floors::new(tmin);
        Self {
            origin: origin.to_array(),
            direction,
            inv,
            octant,
            tmin: f32x8::splat(floors.boxes()),
            front: f32x8::splat(floors.front),
            back: f32x8::splat(floors.back),
            lanes: (1 << directions.len()) - 1,
        }
    }

    /// Lane `lane`'s ray alone.
    pub(super) fn lane(&self, lane: usize) -> WideRay {
        let get = |v: &[f32x8; 3]| v.map(|a| a.as_array()[lane]);
        let tmin = self.tmin.as_array()[0];
        WideRay::with_inverse(self.origin, get(&self.direction), get(&self.inv), tmin)
    }

    /// Each lane's entry distance into each of a node's four children (their boxes as
    /// `planes`: min x, y, z, max x, y, z, each for the four), and per child the mask of the
    /// `lanes` entering it within `[tmin, tmax]` and the nearest of their entries (+∞ for
    /// none); only the `children` slots are tested.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // `k` picks a lane of six planes and three outputs
    pub(super) fn enter(
        &self,
        planes: &[Vec4; 6],
        (children, lanes): (u32, u32),
        tmax: f32x8,
    ) -> Entries {
        // The origin's offset to every plane, shared by the eight rays.
        let offsets: [[f32; 4]; 6] =
            std::array::from_fn(|p| (planes[p] - Vec4::splat(self.origin[p % 3])).to_array());
        let lanes = lane_mask(lanes);
        let mut entries = Entries {
            near: [f32x8::ZERO; 4],
            lanes: [0; 4],
            nearest: [f32::INFINITY; 4],
        };
        for k in 0..4 {
            if children & (1 << k) == 0 {
                continue;
            }
            let slab = |axis: usize| {
                let a = f32x8::splat(offsets[axis][k]) * self.inv[axis];
                let b = f32x8::splat(offsets[axis + 3][k]) * self.inv[axis];
                match self.octant {
                    // Every lane meets the min plane first (positive direction) or every
                    // lane the max plane: the single ray's choice.
                    Some(positive) if positive[axis] => (a, b),
                    Some(_) => (b, a),
                    // Otherwise the nearer of the two planes is the one each lane's sign
                    // picks.
                    None => (a.fast_min(b), a.fast_max(b)),
                }
            };
            let (near_x, far_x) = slab(0);
            let (near_y, far_y) = slab(1);
            let (near_z, far_z) = slab(2);
            let t_near = near_x.fast_max(near_y).fast_max(near_z.fast_max(self.tmin));
            let t_far = far_x.fast_min(far_y).fast_min(far_z.fast_min(tmax)) * ROUNDING_X8;
            let entered = t_near.simd_le(t_far) & lanes;
            entries.near[k] = t_near;
            entries.lanes[k] = entered.to_bitmask();
            entries.nearest[k] = smallest(entered.bitselect(t_near, f32x8::splat(f32::INFINITY)));
        }
        entries
    }

    /// Möller–Trumbore for the eight rays against one triangle (its first vertex and edges):
    /// the distances (a front hit behind the origin at 0), and the mask of the lanes hitting
    /// it within the floors ([`Floors`]) and `tmax`.
    #[inline(always)]
    pub(super) fn intersect(&self, [v0, e1, e2]: [[f32; 3]; 3], tmax: f32x8) -> (f32x8, u32) {
        // `moller_trumbore`'s operations in its order, the origin's terms once for all lanes.
        let s = [
            self.origin[0] - v0[0],
            self.origin[1] - v0[1],
            self.origin[2] - v0[2],
        ];
        let q = cross(s, e1);
        let splat = |v: [f32; 3]| v.map(f32x8::splat);
        let p = cross(self.direction, splat(e2));
        let inv_det = f32x8::ONE / dot(splat(e1), p);
        let u = dot(splat(s), p) * inv_det;
        let v = dot(self.direction, splat(q)) * inv_det;
        let t = f32x8::splat(dot(e2, q)) * inv_det;
        let floor = inv_det
            .simd_gt(f32x8::ZERO)
            .bitselect(self.front, self.back);
        let distance = t.fast_max(f32x8::ZERO);
        let hit = u.simd_ge(f32x8::ZERO)
            & v.simd_ge(f32x8::ZERO)
            & (u + v).simd_le(<f32x8 as Lanes>::ONE)
            & t.simd_ge(floor)
            & distance.simd_le(tmax);
        (distance, hit.to_bitmask())
    }
}

#[cfg(test)]
mod tests {
    use super::super::wide::safe_inverse;
    use super::*;

    #[test]
    fn inverses_are_the_single_rays() {
        let values = [
            1.0,
            -2.5,
            0.0,
            -0.0,
            1e-31,
            -1e-31,
            1e-30,
            -3e-29,
            7.5e8,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            0.3,
            -0.7,
            1e-12,
            -1e-12,
            2.0,
        ];
        for chunk in values.chunks(LANES) {
            let lanes = safe_inverses(f32x8::new(chunk.try_into().unwrap())).to_array();
            for (d, inv) in chunk.iter().zip(lanes) {
                assert_eq!(inv.to_bits(), safe_inverse(*d).to_bits(), "1/{d}");
            }
        }
    }

    #[test]
    fn lane_masks_and_smallest_lanes() {
        let v = f32x8::new([5.0, 3.0, 8.0, 1.0, 9.0, 2.0, 7.0, 4.0]);
        assert_eq!(lane_mask(0b1010_0101).to_bitmask(), 0b1010_0101);
        assert_eq!(smallest(v), 1.0);
        let picked = lane_mask(0b0100_0101).bitselect(v, f32x8::splat(f32::INFINITY));
        assert_eq!(smallest(picked), 5.0);
    }
}
