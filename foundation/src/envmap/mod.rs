//! Distant environment lighting `L_env(ω)`, stored as an equirectangular radiance map in the
//! shared convention (CONVENTIONS.md, "Environment maps"). Every input layout (cube crosses,
//! six faces, light probes) is resampled into this one form when loaded.

pub mod animated;
mod column;
mod error;
pub mod faces;
mod files;
mod layouts;
mod load;
mod mapping;
pub mod sampling;

pub use error::EnvMapError;
pub use files::read_size;
pub use layouts::Layout;
pub use load::{LoadedEnvMap, MIN_MAP_WIDTH, load};
use mapping::v_of_direction;
pub use mapping::{YRotation, direction_of_uv, rotate_y, uv_of_direction};

use crate::color::{Rgb, luminance};
use crate::sh::{ShBasis, ShCoeffs};
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Equirectangular radiance: texel `(i, j)` covers `u ∈ [i/W, (i+1)/W)`,
/// `v ∈ [j/H, (j+1)/H)` and is constant over that area.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<Rgb>,
}

/// Direction through the centre of texel `(i, j)` of a `width × height` map (for a map of
/// that size not yet made: a probe's distances, a rendered probe).
pub fn texel_centre_direction(width: usize, height: usize, i: usize, j: usize) -> Vec3 {
    direction_of_uv(
        (i as f32 + 0.5) / width as f32,
        (j as f32 + 0.5) / height as f32,
    )
}

impl EnvMap {
    pub fn new(width: usize, height: usize, texels: Vec<Rgb>) -> Self {
        assert_eq!(texels.len(), width * height);
        assert!(width > 0 && height > 0);
        Self {
            width,
            height,
            texels,
        }
    }

    /// A constant environment.
    pub fn uniform(width: usize, height: usize, radiance: Rgb) -> Self {
        Self::new(width, height, vec![radiance; width * height])
    }

    /// Builds a map by box-filtering `f` over `supersample²` points per texel.
    pub fn from_fn(
        width: usize,
        height: usize,
        supersample: usize,
        f: impl Fn(Vec3) -> Rgb + Sync,
    ) -> Self {
        use rayon::prelude::*;
        let s = supersample.max(1);
        let texels = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % width, k / width);
                let mut sum = Rgb::ZERO;
                for a in 0..s {
                    for b in 0..s {
                        let u = (i as f32 + (a as f32 + 0.5) / s as f32) / width as f32;
                        let v = (j as f32 + (b as f32 + 0.5) / s as f32) / height as f32;
                        sum += f(direction_of_uv(u, v));
                    }
                }
                sum / (s * s) as f32
            })
            .collect();
        Self::new(width, height, texels)
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn texels(&self) -> &[Rgb] {
        &self.texels
    }

    #[inline]
    pub fn texel(&self, i: usize, j: usize) -> Rgb {
        self.texels[j * self.width + i]
    }

    /// Direction through the centre of texel `(i, j)`.
    pub fn texel_direction(&self, i: usize, j: usize) -> Vec3 {
        texel_centre_direction(self.width, self.height, i, j)
    }

    /// Solid angle of a texel of row `j`: `(2π/W)(π/H) sin θ` at the row centre.
    #[inline]
    pub fn texel_solid_angle(&self, j: usize) -> f32 {
        let theta = PI * (j as f32 + 0.5) / self.height as f32;
        TAU / self.width as f32 * PI / self.height as f32 * theta.sin()
    }

    /// Texel containing direction `w`.
    #[inline]
    pub fn texel_of(&self, w: Vec3) -> (usize, usize) {
        // As `uv_of_direction`, whose `u` takes an arctangent: `column_of` mostly does not.
        let v = v_of_direction(w);
        (
            column::column_of(w, self.width),
            ((v * self.height as f32) as usize).min(self.height - 1),
        )
    }

    /// Radiance arriving from `w` (piecewise constant per texel).
    #[inline]
    pub fn radiance(&self, w: Vec3) -> Rgb {
        let (i, j) = self.texel_of(w);
        self.texel(i, j)
    }

    /// `∫ L(ω) dω` per channel.
    pub fn total_power(&self) -> Rgb {
        (0..self.height)
            .map(|j| {
                let row: Rgb = self.texels[j * self.width..(j + 1) * self.width]
                    .iter()
                    .sum();
                row * self.texel_solid_angle(j)
            })
            .sum()
    }

    /// Mean luminance over the sphere.
    pub fn mean_luminance(&self) -> f32 {
        luminance(self.total_power()) / (4.0 * PI)
    }

    /// The map averaged over `factor × factor` blocks of texels, weighted by solid angle, so
    /// its integral is unchanged up to the midpoint rule of the texel solid angle
    /// `(2π/W)(π/H) sin θ` (a relative 1e-3 for a 128-row result). `factor` must divide both
    /// dimensions.
    pub fn downsampled(&self, factor: usize) -> EnvMap {
        assert!(
            factor > 0 && self.width.is_multiple_of(factor) && self.height.is_multiple_of(factor)
        );
        let (w, h) = (self.width / factor, self.height / factor);
        let mut texels = Vec::with_capacity(w * h);
        for j in 0..h {
            let rows = j * factor..(j + 1) * factor;
            let d_omegas: Vec<f32> = rows.clone().map(|r| self.texel_solid_angle(r)).collect();
            let weight: f32 = d_omegas.iter().sum::<f32>() * factor as f32;
            for i in 0..w {
                let mut sum = Rgb::ZERO;
                for (r, &d_omega) in rows.clone().zip(&d_omegas) {
                    let start = r * self.width + i * factor;
                    sum += self.texels[start..start + factor].iter().sum::<Rgb>() * d_omega;
                }
                texels.push(sum / weight);
            }
        }
        EnvMap::new(w, h, texels)
    }

    /// The map turned about +Y by `angle_deg` (CONVENTIONS.md), resampled exactly when the
    /// angle is a whole number of texel columns, else with linear interpolation along rows.
    pub fn rotated(&self, angle_deg: f32) -> EnvMap {
        let shift = angle_deg / 360.0 * self.width as f32;
        let mut texels = Vec::with_capacity(self.texels.len());
        for j in 0..self.height {
            let row = &self.texels[j * self.width..(j + 1) * self.width];
            for i in 0..self.width {
                // L'(u) = L(u + angle/360°).
                let x = i as f32 + shift;
                let x0 = x.floor();
                let t = x - x0;
                let a = row[(x0 as i64).rem_euclid(self.width as i64) as usize];
                let b = row[(x0 as i64 + 1).rem_euclid(self.width as i64) as usize];
                texels.push(a * (1.0 - t) + b * t);
            }
        }
        EnvMap::new(self.width, self.height, texels)
    }

    /// SH projection by texel quadrature (texel centres, solid-angle weights).
    pub fn sh_projection(&self, order: usize) -> ShCoeffs<Rgb> {
        let basis = ShBasis::<f32>::new(order).expect("a supported SH order");
        let mut coeffs = ShCoeffs::<Rgb>::zeros(order);
        let mut y = vec![0.0; basis.num_coeffs()];
        for j in 0..self.height {
            let d_omega = self.texel_solid_angle(j);
            for i in 0..self.width {
                basis.eval(self.texel_direction(i, j), &mut y);
                let l = self.texel(i, j) * d_omega;
                for (c, yk) in coeffs.as_mut_slice().iter_mut().zip(&y) {
                    *c += l * *yk;
                }
            }
        }
        coeffs
    }

    /// Lambertian irradiance `∫ L(ω) max(0, n·ω) dω` for unit normal `n`, by brute force.
    pub fn irradiance(&self, n: Vec3) -> Rgb {
        let mut sum = Rgb::ZERO;
        for j in 0..self.height {
            let d_omega = self.texel_solid_angle(j);
            for i in 0..self.width {
                let cos = n.dot(self.texel_direction(i, j));
                if cos > 0.0 {
                    sum += self.texel(i, j) * (cos * d_omega);
                }
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapping_matches_the_convention() {
        // Top row looks up, u = 0 toward -Z, u = 1/4 toward +X.
        assert!((direction_of_uv(0.3, 0.0) - Vec3::Y).length() < 1e-6);
        assert!((direction_of_uv(0.0, 0.5) - Vec3::NEG_Z).length() < 1e-6);
        assert!((direction_of_uv(0.25, 0.5) - Vec3::X).length() < 1e-6);
        for (u, v) in [(0.1, 0.2), (0.6, 0.7), (0.99, 0.5), (0.0, 0.3)] {
            let (u2, v2) = uv_of_direction(direction_of_uv(u, v));
            assert!(
                (u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5,
                "{u},{v} -> {u2},{v2}"
            );
        }
    }

    #[test]
    fn solid_angles_sum_to_four_pi_and_uniform_power() {
        let map = EnvMap::uniform(64, 32, Rgb::ONE);
        let total = map.total_power();
        assert!((total.x - 4.0 * PI).abs() < 1e-3 * 4.0 * PI, "{total}");
        // Uniform radiance 1: irradiance π for any normal; SH has only the constant term.
        let e = map.irradiance(Vec3::new(0.3, 0.5, -0.2).normalize());
        assert!((e.y - PI).abs() < 0.01 * PI, "{e}");
        let sh = EnvMap::uniform(256, 128, Rgb::ONE).sh_projection(3);
        assert!((sh.as_slice()[0].x - (4.0 * PI).sqrt()).abs() < 2e-3);
        assert!(
            sh.as_slice()[1..]
                .iter()
                .all(|c| c.abs().max_element() < 2e-3)
        );
    }

    #[test]
    fn downsampling_keeps_the_integral() {
        let map = EnvMap::from_fn(128, 64, 1, |w| {
            Rgb::new(1.0 + w.x, 2.0 + w.y * w.y, (5.0 * w.z).exp())
        });
        let small = map.downsampled(4);
        assert_eq!((small.width(), small.height()), (32, 16));
        let (a, b) = (small.total_power(), map.total_power());
        assert!(
            (a - b).abs().max_element() < 2e-3 * b.max_element(),
            "{a} vs {b}"
        );
        assert_eq!(
            EnvMap::uniform(64, 32, Rgb::ONE).downsampled(2),
            EnvMap::uniform(32, 16, Rgb::ONE)
        );
    }

    #[test]
    fn rotation_moves_features_counter_clockwise_seen_from_above() {
        // A bright texel toward -Z; rotating by +90° moves it to R_y(90°)(-Z) = -X.
        let mut map = EnvMap::uniform(360, 180, Rgb::ZERO);
        let (i, j) = map.texel_of(Vec3::NEG_Z);
        map.texels[j * 360 + i] = Rgb::ONE;
        let rotated = map.rotated(90.0);
        let expected = rotate_y(Vec3::NEG_Z, 90f32.to_radians());
        assert!((expected - Vec3::NEG_X).length() < 1e-6);
        assert_eq!(rotated.radiance(expected), Rgb::ONE);
        assert_eq!(rotated.radiance(Vec3::NEG_Z), Rgb::ZERO);
    }
}
