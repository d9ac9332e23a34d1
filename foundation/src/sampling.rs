//! Sample points and warps shared by the bake and the reference renderer.

use glam::{Vec2, Vec3};

/// Van der Corput radical inverse in base 2.
#[inline]
pub(crate) fn radical_inverse_base2(i: u32) -> f32 {
    // 0x1p-32: maps the bit-reversed integer into [0, 1).
    (i.reverse_bits() as f64 * (1.0 / 4_294_967_296.0)) as f32
}

/// Point `i` of the `n`-point Hammersley set in `[0,1)²`.
#[inline]
pub fn hammersley(i: u32, n: u32) -> Vec2 {
    Vec2::new((i as f32 + 0.5) / n as f32, radical_inverse_base2(i))
}

/// Toroidal shift of a point set (Cranley–Patterson rotation): decorrelates neighbouring
/// vertices that reuse one Hammersley set, without losing its stratification.
#[inline]
pub fn cranley_patterson(u: Vec2, offset: Vec2) -> Vec2 {
    let s = u + offset;
    s - s.floor()
}

/// Shirley–Chiu concentric map from the unit square to the unit disk (area preserving,
/// low distortion, so stratification survives).
#[inline]
pub(crate) fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, std::f32::consts::FRAC_PI_4 * (o.y / o.x))
    } else {
        (
            o.y,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (o.x / o.y),
        )
    };
    let (s, c) = theta.sin_cos();
    Vec2::new(r * c, r * s)
}

/// Cosine-weighted direction on the local hemisphere around +Z; pdf `cos θ / π`.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// The pdf per solid angle of [`cosine_hemisphere`]'s directions at cosine `cos` to the
/// normal (zero below the surface).
#[inline]
pub fn cosine_hemisphere_pdf(cos: f32) -> f32 {
    cos.max(0.0) * std::f32::consts::FRAC_1_PI
}

/// The power heuristic (β = 2) weight of a sample drawn with pdf `pdf_a` when another strategy
/// would draw it with `pdf_b` (Veach 1997); the two weights of a direction add up to one.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 { a / (a + b) } else { 0.0 }
}

/// Orthonormal frame around a unit normal.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    pub tangent: Vec3,
    pub bitangent: Vec3,
    pub normal: Vec3,
}

impl Frame {
    pub fn from_normal(normal: Vec3) -> Self {
        let (tangent, bitangent) = normal.any_orthonormal_pair();
        Self {
            tangent,
            bitangent,
            normal,
        }
    }

    /// Local (+Z = normal) to world.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.tangent * v.x + self.bitangent * v.y + self.normal * v.z
    }

    /// World to local (+Z = normal).
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(
            v.dot(self.tangent),
            v.dot(self.bitangent),
            v.dot(self.normal),
        )
    }
}

/// SplitMix64 finaliser: a well-mixed 64-bit hash of `x` (seeds per vertex or per pixel).
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Two uniform numbers in `[0,1)` derived from a hash (a per-vertex Cranley–Patterson offset).
#[inline]
pub fn hash_to_unit2(h: u64) -> Vec2 {
    Vec2::new(
        (h >> 40) as f32 / (1u64 << 24) as f32,
        ((h >> 8) & 0xff_ffff) as f32 / (1u64 << 24) as f32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        let (a, b) = (0.3, 2.0);
        assert!((power_heuristic(a, b) + power_heuristic(b, a) - 1.0).abs() < 1e-6);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }

    /// The cosine warp's samples follow its pdf: the share of them within angle θ of the
    /// normal is ∫ pdf over that cap, 1 − cos²θ.
    #[test]
    fn cosine_samples_follow_their_pdf() {
        let n = 128 * 128;
        let samples: Vec<Vec3> = (0..n)
            .map(|i| cosine_hemisphere(hammersley(i, n)))
            .collect();
        for c in [0.2f32, 0.5, 0.8, 0.95] {
            let share = samples.iter().filter(|w| w.z > c).count() as f32 / n as f32;
            assert!((share - (1.0 - c * c)).abs() < 2e-3, "cos {c}: {share}");
            // The same cap by integrating the pdf (in cos θ, times 2π).
            let steps = 1000;
            let integral: f32 = (0..steps)
                .map(|k| {
                    let mu = c + (1.0 - c) * (k as f32 + 0.5) / steps as f32;
                    cosine_hemisphere_pdf(mu) * std::f32::consts::TAU * (1.0 - c) / steps as f32
                })
                .sum();
            assert!(
                (integral - (1.0 - c * c)).abs() < 1e-4,
                "cos {c}: {integral}"
            );
        }
        assert_eq!(cosine_hemisphere_pdf(-0.5), 0.0);
    }

    #[test]
    fn hammersley_is_stratified_in_both_axes() {
        let n = 64;
        let mut xs: Vec<f32> = (0..n).map(|i| hammersley(i, n).x).collect();
        let mut ys: Vec<f32> = (0..n).map(|i| hammersley(i, n).y).collect();
        xs.sort_by(f32::total_cmp);
        ys.sort_by(f32::total_cmp);
        for (k, (x, y)) in xs.iter().zip(&ys).enumerate() {
            assert!((*x * n as f32 - k as f32 - 0.5).abs() < 1e-4);
            assert!((*y * n as f32 - k as f32).abs() < 1e-4);
        }
    }

    #[test]
    fn cosine_hemisphere_integrates_cos_over_pdf_to_pi() {
        // E[cos θ / pdf] = E[π] trivially; the real check: E[cos θ] = 2/3 for pdf cos/π.
        let n = 4096;
        let mean_cos: f32 = (0..n)
            .map(|i| cosine_hemisphere(hammersley(i, n)).z)
            .sum::<f32>()
            / n as f32;
        assert!((mean_cos - 2.0 / 3.0).abs() < 1e-3, "{mean_cos}");
        for i in 0..n {
            let d = cosine_hemisphere(hammersley(i, n));
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
        }
    }

    #[test]
    fn frame_is_orthonormal() {
        for n in [Vec3::Y, -Vec3::Y, Vec3::new(0.3, -0.2, 0.9).normalize()] {
            let f = Frame::from_normal(n);
            assert!(f.tangent.dot(f.bitangent).abs() < 1e-6);
            assert!(f.tangent.dot(n).abs() < 1e-6);
            assert!((f.to_world(Vec3::Z) - n).length() < 1e-6);
            assert!((f.tangent.cross(f.bitangent) - n).length() < 1e-5);
        }
    }
}
