//! Environments that change over time, made from maps: a cross-fade between two maps, and a
//! sun (a disc of given angular radius and power) moving along an arc over a base map. They
//! are the moving test cases of the temporal measurements; a sequence of map files needs
//! nothing of this module.

use super::EnvMap;
use crate::color::Rgb;
use glam::Vec3;
use std::f32::consts::PI;

/// Texel samples per side when a sequence frame is made (antialiases the sun's edge).
const SUPERSAMPLE: usize = 3;

/// `(1 − t) a + t b`, at `a`'s resolution (`b` is looked up per texel where the sizes differ).
pub fn crossfade(a: &EnvMap, b: &EnvMap, t: f32) -> EnvMap {
    let t = t.clamp(0.0, 1.0);
    if (a.width(), a.height()) == (b.width(), b.height()) {
        let texels = a
            .texels()
            .iter()
            .zip(b.texels())
            .map(|(x, y)| *x * (1.0 - t) + *y * t)
            .collect();
        return EnvMap::new(a.width(), a.height(), texels);
    }
    EnvMap::from_fn(a.width(), a.height(), SUPERSAMPLE, |w| {
        a.radiance(w) * (1.0 - t) + b.radiance(w) * t
    })
}

/// A uniform disc of radiance in the sky.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunDisc {
    /// Unit direction of the disc's centre.
    pub direction: Vec3,
    /// Angular radius, radians.
    pub angular_radius: f32,
    /// Radiance inside the disc (added to the base map's).
    pub radiance: Rgb,
}

impl SunDisc {
    /// A disc whose integral `∫ L dω` is `power`.
    pub(crate) fn with_power(direction: Vec3, angular_radius: f32, power: Rgb) -> Self {
        Self {
            direction: direction.normalize(),
            angular_radius,
            radiance: power / Self::solid_angle_of(angular_radius),
        }
    }

    fn solid_angle_of(angular_radius: f32) -> f32 {
        2.0 * PI * (1.0 - angular_radius.cos())
    }

    /// `∫ L dω` of the disc (above the base map).
    pub fn power(&self) -> Rgb {
        self.radiance * Self::solid_angle_of(self.angular_radius)
    }

    /// `base` with the disc added, at `base`'s resolution: each texel gets the disc's radiance
    /// times the share of the texel it covers (sampled on a fine grid), scaled so that the map
    /// holds exactly the disc's power however the disc falls on the texels (a moving sun does
    /// not flicker).
    pub fn over(&self, base: &EnvMap) -> EnvMap {
        const GRID: usize = 8;
        let (w, h) = (base.width(), base.height());
        // Texels whose centre lies within the disc's radius plus two texel diagonals.
        let texel_angle = 2.0 * PI / w as f32;
        let reach = (self.angular_radius + 3.0 * texel_angle).min(PI).cos();
        let mut covered: Vec<(usize, f32)> = Vec::new();
        for j in 0..h {
            for i in 0..w {
                if base.texel_direction(i, j).dot(self.direction) < reach {
                    continue;
                }
                let mut inside = 0;
                for a in 0..GRID {
                    for b in 0..GRID {
                        let u = (i as f32 + (a as f32 + 0.5) / GRID as f32) / w as f32;
                        let v = (j as f32 + (b as f32 + 0.5) / GRID as f32) / h as f32;
                        let d = crate::envmap::direction_of_uv(u, v);
                        inside += usize::from(d.dot(self.direction) >= self.angular_radius.cos());
                    }
                }
                if inside > 0 {
                    covered.push((j * w + i, inside as f32 / (GRID * GRID) as f32));
                }
            }
        }
        let held: f32 = covered
            .iter()
            .map(|(t, share)| share * base.texel_solid_angle(t / w))
            .sum();
        let mut texels = base.texels().to_vec();
        if held > 0.0 {
            for (t, share) in covered {
                // Radiance × share × Ω summed over the texels is exactly the disc's power.
                texels[t] += self.power() * (share / held);
            }
        } else {
            // A disc smaller than the sampling grid: all its power in the texel at its centre.
            let (i, j) = base.texel_of(self.direction);
            texels[j * w + i] += self.power() / base.texel_solid_angle(j);
        }
        EnvMap::new(w, h, texels)
    }
}

/// The direction of azimuth `azimuth_deg` (from +Z toward +X, as the equirectangular `u`) and
/// elevation `elevation_deg` above the horizon.
pub fn direction_of(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
}

/// A sun moving at constant angular speed along the great-circle arc from `from` to `to`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunArc {
    pub from: Vec3,
    pub to: Vec3,
    pub angular_radius: f32,
    pub power: Rgb,
}

impl SunArc {
    /// The sun at `t` in `[0, 1]` along the arc.
    pub fn at(&self, t: f32) -> SunDisc {
        let (a, b) = (self.from.normalize(), self.to.normalize());
        let angle = a.dot(b).clamp(-1.0, 1.0).acos();
        let direction = if angle < 1e-6 {
            a
        } else {
            (a * ((1.0 - t) * angle).sin() + b * (t * angle).sin()) / angle.sin()
        };
        SunDisc::with_power(direction, self.angular_radius, self.power)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::luminance;

    #[test]
    fn a_sun_disc_over_a_map_adds_its_power() {
        let base = EnvMap::uniform(1024, 512, Rgb::splat(0.5));
        let sun = SunDisc::with_power(direction_of(40.0, 30.0), 1.5f32.to_radians(), Rgb::ONE);
        let map = sun.over(&base);
        let added = luminance(map.total_power() - base.total_power());
        assert!((added - 1.0).abs() < 1e-3, "{added}");
        // Exactly its power wherever it falls, also when it is smaller than a texel.
        let coarse = EnvMap::uniform(128, 64, Rgb::splat(0.5));
        for k in 0..20 {
            let small = SunDisc::with_power(
                direction_of(3.7 * k as f32, 10.0 + k as f32),
                0.4f32.to_radians(),
                Rgb::ONE,
            );
            let added = luminance(small.over(&coarse).total_power() - coarse.total_power());
            assert!((added - 1.0).abs() < 1e-3, "{k}: {added}");
        }
        assert!(luminance(sun.power() - Rgb::ONE).abs() < 1e-5);
        // The brightest texel is at the sun.
        let (i, j) = map.texel_of(sun.direction);
        assert!(map.texel(i, j).x > 100.0);
    }

    #[test]
    fn the_arc_moves_at_constant_speed_between_its_ends() {
        let arc = SunArc {
            from: direction_of(0.0, 10.0),
            to: direction_of(90.0, 10.0),
            angular_radius: 0.01,
            power: Rgb::ONE,
        };
        assert!(arc.at(0.0).direction.dot(arc.from) > 1.0 - 1e-6);
        assert!(arc.at(1.0).direction.dot(arc.to.normalize()) > 1.0 - 1e-6);
        let step = |t0: f32, t1: f32| arc.at(t0).direction.dot(arc.at(t1).direction).acos();
        assert!((step(0.0, 0.25) - step(0.5, 0.75)).abs() < 1e-4);
        assert!((arc.at(0.4).direction.length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn crossfade_blends_linearly_at_any_resolution() {
        let a = EnvMap::uniform(64, 32, Rgb::splat(1.0));
        let b = EnvMap::uniform(64, 32, Rgb::splat(3.0));
        assert_eq!(crossfade(&a, &b, 0.25).texel(5, 5), Rgb::splat(1.5));
        let c = EnvMap::uniform(32, 16, Rgb::splat(3.0));
        assert!((crossfade(&a, &c, 0.5).texel(7, 3) - Rgb::splat(2.0)).length() < 1e-5);
    }
}
