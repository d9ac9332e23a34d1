//! SH projection and evaluation folded into one octant of the cube.
//!
//! The cube's texel centres are symmetric under each reflection x → −x, y → −y, z → −z, and
//! every real SH basis function is even or odd under each of them (a monomial-like polynomial:
//! `Y_2,−2 ∝ xy` is odd in x and y, even in z). So a texel with x, y, z > 0 and its seven
//! images share their basis values up to sign, and a coefficient of parity class `p` (the
//! axes it is odd under) is `Σ_o Y_k(o) · Σ_s (−1)^|p ∧ s| L_s(o) Δω`, the inner sum a
//! Walsh–Hadamard transform of the octet's eight radiances: an eighth of the basis values to
//! read (a table that stays in cache) and an eighth of the multiply-adds. An octet's texels
//! also share their solid angle (the octant texel's stands for all eight: the geometry's
//! values for them differ only by the rounding of their computation, about 1e-4). The
//! symmetries are checked when it is set up; a geometry without them is projected texel by
//! texel.

use super::lanes::load;
use crate::cubemap::{CubeGeometry, CubeMap};
use foundation::Rgb;
use foundation::sh::{ShBasis, ShCoeffs, num_coeffs};
use glam::{Vec3, Vec3A};
use wide::f32x8;

/// A texel with x, y, z > 0 and its images ([`OctantBasis`]).
type Octet = [u32; 8];
/// A texel's octant texel and reflection ([`OctantBasis`]).
type Slot = (u32, u8);

/// Basis rows are padded to a multiple of this many values (one 8-wide vector).
const LANES: usize = 8;
/// Octets transformed at a time by the projection (a multiple of four).
const PROJECTION_TILE: usize = 128;

/// The basis of one order tabulated on one octant of a cube, with each texel's octant texel
/// and reflection.
#[derive(Debug, Clone)]
pub(crate) struct OctantBasis {
    order: usize,
    /// For each texel with x, y, z > 0, its eight images, indexed by the reflected axes
    /// (bit 0: x, bit 1: y, bit 2: z); image 0 is the texel itself.
    octets: Vec<Octet>,
    /// For each texel, its octant texel and its reflection (bits as above).
    slots: Vec<Slot>,
    /// For each coefficient, the axes its basis function is odd under.
    parity: Vec<u8>,
    /// `rows[o · stride + k]`: `Y_k` at octant texel `o`, padded with zeros to `stride`.
    rows: Vec<f32>,
    stride: usize,
    /// `columns[k · count + o]`: the same values by coefficient, times the solid angle of
    /// octant texel `o`.
    columns: Vec<f32>,
}

impl OctantBasis {
    /// `None` when the geometry's texels or the basis lack the symmetry (an odd face size
    /// puts texel centres on the planes).
    pub(crate) fn new(geometry: &CubeGeometry, order: usize) -> Option<Self> {
        let basis = ShBasis::<f32>::new(order).ok()?;
        let n = num_coeffs(order);
        let (octets, slots) = octets(geometry)?;
        let directions = geometry.directions();
        let mut values = vec![0.0f32; n];
        let mut image = vec![0.0f32; n];
        let mut parity = vec![0u8; n];
        let mut determined = vec![0u8; n];
        let stride = n.next_multiple_of(LANES);
        let mut rows = vec![0.0f32; octets.len() * stride];
        for (octet, row) in octets.iter().zip(rows.chunks_exact_mut(stride)) {
            basis.eval(directions[octet[0] as usize], &mut values);
            row[..n].copy_from_slice(&values);
            for axis in 0..3u8 {
                basis.eval(directions[octet[1 << axis] as usize], &mut image);
                for k in 0..n {
                    let odd = classify(values[k], image[k])?;
                    let bit = 1u8 << axis;
                    // Too small to tell here: decided at another texel.
                    let Some(odd) = odd else { continue };
                    if determined[k] & bit != 0 && (parity[k] & bit != 0) != odd {
                        return None;
                    }
                    determined[k] |= bit;
                    parity[k] = if odd {
                        parity[k] | bit
                    } else {
                        parity[k] & !bit
                    };
                }
            }
        }
        if determined.iter().any(|&d| d != 0b111) {
            return None;
        }
        let count = octets.len();
        let solid_angles = geometry.solid_angles();
        let mut columns = vec![0.0f32; n * count];
        for (o, (row, octet)) in rows.chunks_exact(stride).zip(&octets).enumerate() {
            let d_omega = solid_angles[octet[0] as usize];
            let same = |t: &u32| (solid_angles[*t as usize] - d_omega).abs() <= 1e-3 * d_omega;
            if !octet.iter().all(same) {
                return None;
            }
            for k in 0..n {
                columns[k * count + o] = row[k] * d_omega;
            }
        }
        Some(Self {
            order,
            octets,
            slots,
            parity,
            rows,
            stride,
            columns,
        })
    }

    /// `SH(L)_k = Σ_t L_t Y_k(ω_t) Δω_t`, folded.
    pub(crate) fn project(&self, map: &CubeMap) -> ShCoeffs<Rgb> {
        let texels = map.texels();
        let count = self.octets.len();
        // Eight partial sums per coefficient and channel (octet o into lane o mod 8).
        let mut sums = vec![[f32x8::ZERO; 3]; num_coeffs(self.order)];
        // The transforms of a tile of octets by class and channel: the tile stays in the
        // first-level cache while every coefficient passes over it.
        let mut combos = [[[0.0f32; PROJECTION_TILE]; 3]; 8];
        for first in (0..count).step_by(PROJECTION_TILE) {
            let len = PROJECTION_TILE.min(count - first);
            for (i, octet) in self.octets[first..first + len].iter().enumerate() {
                let mut v: [Vec3A; 8] =
                    std::array::from_fn(|s| Vec3A::from(texels[octet[s] as usize]));
                walsh_hadamard(&mut v);
                for (class, value) in v.into_iter().enumerate() {
                    for (channel, value) in combos[class].iter_mut().zip(value.to_array()) {
                        channel[i] = value;
                    }
                }
            }
            for (k, sums) in sums.iter_mut().enumerate() {
                let column = &self.columns[k * count + first..][..len];
                add_weighted(sums, &combos[self.parity[k] as usize], column);
            }
        }
        let coeffs = sums
            .iter()
            .map(|s| {
                let [r, g, b] = s.map(f32x8::reduce_add);
                Rgb::new(r, g, b)
            })
            .collect();
        ShCoeffs::from_vec(coeffs).expect("n² coefficients")
    }

    /// `coeffs` (of this order) at the texels `members`, into `out`.
    pub(crate) fn eval_at(&self, coeffs: &ShCoeffs<Rgb>, members: &[u32], out: &mut Vec<Rgb>) {
        let signed = self.signed_coeffs(coeffs);
        let octs = self.stride / LANES;
        out.clear();
        out.extend(members.iter().map(|&t| {
            let (o, s) = self.slots[t as usize];
            let row = &self.rows[o as usize * self.stride..][..self.stride];
            let coeffs = &signed[s as usize * octs..][..octs];
            let mut sums = [f32x8::ZERO; 3];
            for (y, c) in row.chunks_exact(LANES).zip(coeffs) {
                let y = load(y);
                for (sum, c) in sums.iter_mut().zip(c) {
                    *sum = y.mul_add(*c, *sum);
                }
            }
            let [r, g, b] = sums.map(f32x8::reduce_add);
            Rgb::new(r, g, b)
        }));
    }

    /// `coeffs` less `Σ_i w_i Y(ω_{members_i})`: the projection of `weighted` (radiance times
    /// solid angle) at the members taken away.
    pub(crate) fn subtract(
        &self,
        coeffs: &ShCoeffs<Rgb>,
        members: &[u32],
        weighted: &[Rgb],
    ) -> ShCoeffs<Rgb> {
        // Sums by reflection, each over the octant texels' rows, then folded back by parity.
        // `sums[s · octs + q][channel]`: coefficients `LANES · q..` of reflection `s`.
        let octs = self.stride / LANES;
        let mut sums = vec![[f32x8::ZERO; 3]; 8 * octs];
        for (&t, w) in members.iter().zip(weighted) {
            let (o, s) = self.slots[t as usize];
            let row = &self.rows[o as usize * self.stride..][..self.stride];
            let w = w.to_array().map(f32x8::splat);
            for (y, sums) in row.chunks_exact(LANES).zip(&mut sums[s as usize * octs..]) {
                let y = load(y);
                for (sum, w) in sums.iter_mut().zip(w) {
                    *sum = y.mul_add(w, *sum);
                }
            }
        }
        let sums: Vec<[[f32; LANES]; 3]> = sums.iter().map(|s| s.map(f32x8::to_array)).collect();
        let out = coeffs
            .as_slice()
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let mut total = Rgb::ZERO;
                for s in 0..8 {
                    let sums = &sums[s * octs + k / LANES];
                    let v = Rgb::new(sums[0][k % LANES], sums[1][k % LANES], sums[2][k % LANES]);
                    total += if self.odd(k, s) { -v } else { v };
                }
                *c - total
            })
            .collect();
        ShCoeffs::from_vec(out).expect("n² coefficients")
    }

    /// Whether reflection `s` flips the sign of basis function `k`.
    fn odd(&self, k: usize, s: usize) -> bool {
        (self.parity[k] as usize & s).count_ones() % 2 == 1
    }

    /// For each reflection `s`, the coefficients with the signs it gives their basis functions,
    /// padded with zeros to the row stride, [`LANES`] at a time for each channel: entry
    /// `s · stride / LANES + q` holds coefficients `LANES · q..LANES · (q + 1)`.
    fn signed_coeffs(&self, coeffs: &ShCoeffs<Rgb>) -> Vec<[f32x8; 3]> {
        let octs = self.stride / LANES;
        let mut signed = vec![[[0.0f32; LANES]; 3]; 8 * octs];
        for (s, octs) in signed.chunks_exact_mut(octs).enumerate() {
            for (k, c) in coeffs.as_slice().iter().enumerate().take(self.parity.len()) {
                let c = if self.odd(k, s) { -*c } else { *c };
                for (channel, value) in octs[k / LANES].iter_mut().zip(c.to_array()) {
                    channel[k % LANES] = value;
                }
            }
        }
        signed
            .into_iter()
            .map(|channels| channels.map(f32x8::new))
            .collect()
    }
}

/// Whether a basis value's image under a reflection says the function is odd (`Some(true)`:
/// `image = −value`) or even (`Some(false)`), `Some(None)` when both are too small to tell,
/// and `None` when it is neither.
fn classify(value: f32, image: f32) -> Option<Option<bool>> {
    let tolerance = 1e-4 * value.abs().max(1e-3);
    let (even, odd) = (
        (value - image).abs() <= tolerance,
        (value + image).abs() <= tolerance,
    );
    match (even, odd) {
        (true, true) => Some(None),
        (true, false) => Some(Some(false)),
        (false, true) => Some(Some(true)),
        (false, false) => None,
    }
}

/// Each texel with x, y, z > 0 with its eight images, and every texel's octant texel and
/// reflection; `None` unless every texel has exact images and none lies on a plane.
fn octets(geometry: &CubeGeometry) -> Option<(Vec<Octet>, Vec<Slot>)> {
    let directions = geometry.directions();
    if directions.iter().any(|d| d.abs().min_element() < 1e-6) {
        return None;
    }
    let mut octets = Vec::with_capacity(directions.len() / 8);
    let mut slots = vec![(u32::MAX, 0u8); directions.len()];
    for d in directions {
        if d.min_element() < 0.0 {
            continue;
        }
        let o = octets.len() as u32;
        let mut octet = [0u32; 8];
        for (s, image_texel) in octet.iter_mut().enumerate() {
            let sign = |bit: usize| if s & bit != 0 { -1.0 } else { 1.0 };
            let image = *d * Vec3::new(sign(1), sign(2), sign(4));
            let m = geometry.texel_of(image);
            if directions[m].distance(image) > 1e-5 || slots[m].0 != u32::MAX {
                return None;
            }
            slots[m] = (o, s as u8);
            *image_texel = m as u32;
        }
        octets.push(octet);
    }
    (8 * octets.len() == directions.len()).then_some((octets, slots))
}

/// In place, `v[c] ← Σ_s (−1)^|c ∧ s| v[s]`: three butterfly stages, written out so that
/// the values stay in registers.
fn walsh_hadamard(v: &mut [Vec3A; 8]) {
    let [x0, x1, x2, x3, x4, x5, x6, x7] = *v;
    let (a0, a1, a2, a3) = (x0 + x1, x0 - x1, x2 + x3, x2 - x3);
    let (a4, a5, a6, a7) = (x4 + x5, x4 - x5, x6 + x7, x6 - x7);
    let (b0, b1, b2, b3) = (a0 + a2, a1 + a3, a0 - a2, a1 - a3);
    let (b4, b5, b6, b7) = (a4 + a6, a5 + a7, a4 - a6, a5 - a7);
    *v = [
        b0 + b4,
        b1 + b5,
        b2 + b6,
        b3 + b7,
        b0 - b4,
        b1 - b5,
        b2 - b6,
        b3 - b7,
    ];
}

/// Adds `values_i weights_i` for each channel to its eight partial sums (element `i` into
/// lane `i mod 8`, a length not a multiple of eight padded with zeros).
fn add_weighted(sums: &mut [f32x8; 3], channels: &[[f32; PROJECTION_TILE]; 3], weights: &[f32]) {
    for (sum, values) in sums.iter_mut().zip(channels) {
        let values = &values[..weights.len()];
        let (v_chunks, w_chunks) = (values.chunks_exact(LANES), weights.chunks_exact(LANES));
        if !v_chunks.remainder().is_empty() {
            *sum += f32x8::from(v_chunks.remainder()) * f32x8::from(w_chunks.remainder());
        }
        for (v, w) in v_chunks.zip(w_chunks) {
            *sum = load(v).mul_add(load(w), *sum);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The eight-point transform is the sum with the signs of each class.
    #[test]
    fn the_transform_signs_each_reflection_by_its_parity() {
        let inputs: [Vec3A; 8] =
            std::array::from_fn(|s| Vec3A::new(s as f32 + 1.0, (s * s) as f32, 0.5 - s as f32));
        let mut v = inputs;
        walsh_hadamard(&mut v);
        for (class, got) in v.iter().enumerate() {
            let mut expected = Vec3A::ZERO;
            for (s, x) in inputs.iter().enumerate() {
                let odd = (class & s).count_ones() % 2 == 1;
                expected += if odd { -*x } else { *x };
            }
            assert_eq!(got.to_array(), expected.to_array(), "class {class}");
        }
    }

    /// Every texel's octant texel and reflection lead back to it, and the parity found for
    /// each coefficient is the one its polynomial has (`Y_1,1 ∝ x`, `Y_2,−2 ∝ xy`, ...).
    #[test]
    fn slots_and_parities_are_those_of_the_geometry_and_the_basis() {
        let geometry = CubeGeometry::new(8);
        let basis = OctantBasis::new(&geometry, 5).expect("an even face size is symmetric");
        for (t, &(o, s)) in basis.slots.iter().enumerate() {
            assert_eq!(basis.octets[o as usize][s as usize] as usize, t);
        }
        let mut values = vec![0.0f32; 25];
        let d = Vec3::new(0.3, 0.5, 0.8).normalize();
        ShBasis::<f32>::new(5).unwrap().eval(d, &mut values);
        for (k, &p) in basis.parity.iter().enumerate() {
            let mut image = vec![0.0f32; 25];
            for axis in 0..3 {
                let mut m = d;
                m[axis] = -m[axis];
                ShBasis::<f32>::new(5).unwrap().eval(m, &mut image);
                let odd = p & (1 << axis) != 0;
                let expected = if odd { -values[k] } else { values[k] };
                assert!((image[k] - expected).abs() < 1e-5, "k {k} axis {axis}");
            }
        }
        assert!(OctantBasis::new(&CubeGeometry::new(9), 3).is_none());
    }

    /// Evaluating at texels and subtracting a projection agree with the plain sums over the
    /// texels' own basis values (to rounding), at texels of every octant.
    #[test]
    fn evaluation_and_subtraction_match_the_texels_own_basis() {
        let geometry = CubeGeometry::new(16);
        let order = 5;
        let basis = OctantBasis::new(&geometry, order).unwrap();
        let plain = ShBasis::<f32>::new(order).unwrap();
        let mut sh = ShCoeffs::zeros(order);
        for (k, c) in sh.as_mut_slice().iter_mut().enumerate() {
            *c = Rgb::new(1.0 / (1.0 + k as f32), (k as f32).sin(), 0.1 * k as f32);
        }
        let members: Vec<u32> = (0..geometry.texel_count() as u32).step_by(7).collect();
        let mut values = Vec::new();
        basis.eval_at(&sh, &members, &mut values);
        let mut row = vec![0.0f32; 25];
        let mut expected_sh = sh.clone();
        let weighted: Vec<Rgb> = members
            .iter()
            .map(|&t| Rgb::new(0.01 * (t % 13) as f32, 0.02, 0.003 * (t % 5) as f32))
            .collect();
        for ((&t, got), w) in members.iter().zip(&values).zip(&weighted) {
            plain.eval(geometry.directions()[t as usize], &mut row);
            let expected = sh.dot_basis(&row);
            assert!((*got - expected).abs().max_element() < 1e-5, "texel {t}");
            for (c, y) in expected_sh.as_mut_slice().iter_mut().zip(&row) {
                *c -= *w * *y;
            }
        }
        let got = basis.subtract(&sh, &members, &weighted);
        for (a, b) in got.as_slice().iter().zip(expected_sh.as_slice()) {
            assert!((*a - *b).abs().max_element() < 1e-5, "{a} vs {b}");
        }
    }
}
