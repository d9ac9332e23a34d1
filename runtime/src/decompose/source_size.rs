//! The angular size of the source behind each light, measured on the full-resolution map.
//!
//! The decomposition works on a coarse cube (texels of about 1.4°) and smooths it, so the
//! spread of a light's excess measures the glow around the source and the cube's texels as
//! much as the source: a sun of 0.27° came out near 2°, and its shadows' penumbrae several
//! times too wide. Here the source is the region around the light's peak brighter than half
//! way from the local background to the peak (its half-maximum region: for a disc of uniform
//! radiance, the disc itself, whatever the glow below half its level), and the light's radius
//! is that of the disc of the same solid angle. Where lights share a source (a large area
//! light split into several), each measures the part of it nearer to itself than to the
//! others, so together they span the source. Below a texel the region is one texel; the
//! estimate is then the radius of a texel's solid angle, within a texel of the truth.
//!
//! Many real sources are a bright core in a wide halo (a lamp and its shade, the sun through
//! haze or leaves): the light carries the halo's power too, and a halo casts a wider penumbra
//! than its core. So the measurement also gives the fraction of the light's excess in the core
//! and the radius of a disc standing for the rest (the disc with the halo's mean angular
//! distance from the light, `E[θ] = 2ρ/3` for a uniform disc); the shadow filter spreads its
//! samples over both discs in proportion (CONVENTIONS.md, "Shadows and background on the GPU").

use glam::Vec3;
use precompute::envmap::EnvMap;
use precompute::luminance;
use std::f32::consts::PI;

/// Texels within this angle of a light give its local background (their median luminance);
/// wide enough that sources of up to about 15° cover less than half of it.
const BACKGROUND_RADIUS: f32 = 30.0 * PI / 180.0;
/// The region of a source is searched this far from its light at most.
const MAX_SOURCE_RADIUS: f32 = 45.0 * PI / 180.0;

/// Equirectangular texels `(i, j)` within `radius` of `centre` (rows by polar angle, then the
/// columns of each row whose azimuth can be that close).
fn texels_within(map: &EnvMap, centre: Vec3, radius: f32) -> Vec<(usize, usize)> {
    let (w, h) = (map.width(), map.height());
    let theta = centre.y.clamp(-1.0, 1.0).acos();
    let row_angle = PI / h as f32;
    let first = (((theta - radius) / row_angle).floor().max(0.0)) as usize;
    let last = ((((theta + radius) / row_angle).ceil()) as usize).min(h);
    let cos_radius = radius.cos();
    let centre_u = precompute::envmap::uv_of_direction(centre).0 * w as f32;
    let mut out = Vec::new();
    for j in first..last {
        // Columns to test: all of them near a pole, else an azimuth window around the centre's.
        let sin_row = ((j as f32 + 0.5) * row_angle).sin();
        let half_width = if sin_row * PI <= radius * 2.0 || theta < radius || PI - theta < radius {
            w as f32
        } else {
            (radius / sin_row) / (2.0 * PI) * w as f32 * 1.5 + 2.0
        };
        let span = (2.0 * half_width).min(w as f32) as usize;
        let start = (centre_u - half_width.min(w as f32 / 2.0)).floor() as isize;
        for k in 0..span.max(1) {
            let i = (start + k as isize).rem_euclid(w as isize) as usize;
            if map.texel_direction(i, j).dot(centre) >= cos_radius {
                out.push((i, j));
            }
        }
    }
    out
}

/// The median of `values` (0 when empty).
fn median(mut values: Vec<f32>) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The angular radius of the disc of solid angle `omega`.
pub fn disc_radius(omega: f32) -> f32 {
    (1.0 - omega / (2.0 * PI)).clamp(-1.0, 1.0).acos()
}

/// What the map shows of the source behind one light: a core disc in a halo disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceShape {
    /// Angular radius of the core (the half-maximum region's disc), radians.
    pub radius: f32,
    /// Angular radius of the disc standing for the halo, radians (at least `radius`).
    pub halo_radius: f32,
    /// Fraction of the excess over the local background in the core, in (0, 1].
    pub core_fraction: f32,
}

/// The measured shape of the source behind each light `directions[k]` (unit, in the map's
/// frame), searched from its peak within `cap_radius`; `None` where the map has no peak above
/// its background there.
pub fn source_shapes(
    map: &EnvMap,
    directions: &[Vec3],
    cap_radius: f32,
) -> Vec<Option<SourceShape>> {
    let nearest_light = |w: Vec3| {
        directions
            .iter()
            .enumerate()
            .max_by(|a, b| w.dot(*a.1).total_cmp(&w.dot(*b.1)))
            .map_or(0, |(k, _)| k)
    };
    let lum = |(i, j): (usize, usize)| luminance(map.texel(i, j));
    directions
        .iter()
        .enumerate()
        .map(|(k, &d)| {
            let background = median(
                texels_within(map, d, BACKGROUND_RADIUS)
                    .into_iter()
                    .map(lum)
                    .collect(),
            );
            let cell: Vec<(usize, usize)> = texels_within(map, d, cap_radius)
                .into_iter()
                .filter(|t| nearest_light(map.texel_direction(t.0, t.1)) == k)
                .collect();
            let (peak_texel, peak) = cell
                .iter()
                .map(|&t| (t, lum(t)))
                .max_by(|a, b| a.1.total_cmp(&b.1))?;
            if peak.partial_cmp(&background) != Some(std::cmp::Ordering::Greater) {
                return None;
            }
            let half = 0.5 * (background + peak);
            let core = half_maximum_region(map, peak_texel, d, half, |t| {
                nearest_light(map.texel_direction(t.0, t.1)) == k
            });
            let omega: f32 = core.iter().map(|t| map.texel_solid_angle(t.1)).sum();
            let radius = disc_radius(omega);
            // The excess in the core, and the excess and its angular moment in the halo.
            let excess =
                |t: (usize, usize)| (lum(t) - background).max(0.0) * map.texel_solid_angle(t.1);
            let core_excess: f32 = core.iter().map(|&t| excess(t)).sum();
            let (mut halo_excess, mut halo_moment) = (0.0f32, 0.0f32);
            for &t in cell.iter().filter(|t| !core.contains(t)) {
                let e = excess(t);
                halo_excess += e;
                halo_moment += e * map.texel_direction(t.0, t.1).angle_between(d);
            }
            let halo_radius = if halo_excess > 0.0 {
                (1.5 * halo_moment / halo_excess).clamp(radius, cap_radius.max(radius))
            } else {
                radius
            };
            Some(SourceShape {
                radius,
                halo_radius,
                core_fraction: core_excess / (core_excess + halo_excess),
            })
        })
        .collect()
}

/// Sets each light's angular radius, halo and core fraction (its directions in the map's
/// frame) to the measured shape of its source, where the map has one; the others keep the
/// decomposition's estimate.
pub fn measure_sources(map: &EnvMap, lights: &mut [crate::light::DirectionalLight]) {
    let Some(cap_radius) = lights.iter().map(|l| l.cap_radius).reduce(f32::max) else {
        return;
    };
    let directions: Vec<Vec3> = lights.iter().map(|l| l.direction).collect();
    for (light, shape) in lights
        .iter_mut()
        .zip(source_shapes(map, &directions, cap_radius))
    {
        if let Some(shape) = shape {
            light.angular_radius = shape.radius;
            light.halo_radius = shape.halo_radius;
            light.core_fraction = shape.core_fraction;
        }
    }
}

/// The texels `owned` connected to `seed` (4-neighbours, wrapping in azimuth) brighter than
/// `level`, within [`MAX_SOURCE_RADIUS`] of `centre`. A convex source cut by the
/// convex cells of the lights nearest to its parts stays connected within each cell.
fn half_maximum_region(
    map: &EnvMap,
    seed: (usize, usize),
    centre: Vec3,
    level: f32,
    owned: impl Fn((usize, usize)) -> bool,
) -> std::collections::HashSet<(usize, usize)> {
    let (w, h) = (map.width(), map.height());
    let cos_max = MAX_SOURCE_RADIUS.cos();
    let mut seen = std::collections::HashSet::new();
    let mut stack = vec![seed];
    seen.insert(seed);
    while let Some((i, j)) = stack.pop() {
        let mut neighbours = vec![((i + 1) % w, j), ((i + w - 1) % w, j)];
        if j > 0 {
            neighbours.push((i, j - 1));
        }
        if j + 1 < h {
            neighbours.push((i, j + 1));
        }
        for n in neighbours {
            if !seen.contains(&n)
                && luminance(map.texel(n.0, n.1)) > level
                && map.texel_direction(n.0, n.1).dot(centre) >= cos_max
                && owned(n)
            {
                seen.insert(n);
                stack.push(n);
            }
        }
    }
    seen
}

#[cfg(test)]
mod tests {
    use super::*;
    use precompute::Rgb;

    /// A map of `width × width/2` with a uniform disc of angular radius `radius` and radiance
    /// 100 at `centre` over a sky of 1, plus a glow of 5 falling off over 3 radii around it.
    fn disc_map(width: usize, centre: Vec3, radius: f32) -> EnvMap {
        map_around(width, centre, |angle| {
            if angle <= radius {
                100.0
            } else {
                1.0 + 5.0 * (-(angle - radius) / (3.0 * radius)).exp()
            }
        })
    }

    /// A map of `width × width/2` whose radiance is `radiance(angle from centre)`, each texel
    /// the average of 4 × 4 samples, as a camera integrates a pixel.
    fn map_around(width: usize, centre: Vec3, radiance: impl Fn(f32) -> f32) -> EnvMap {
        let height = width / 2;
        let n = 4;
        let mut texels = Vec::with_capacity(width * height);
        for j in 0..height {
            for i in 0..width {
                let mut sum = 0.0;
                for s in 0..n * n {
                    let u = (i as f32 + ((s % n) as f32 + 0.5) / n as f32) / width as f32;
                    let v = (j as f32 + ((s / n) as f32 + 0.5) / n as f32) / height as f32;
                    let angle = precompute::envmap::direction_of_uv(u, v)
                        .dot(centre)
                        .clamp(-1.0, 1.0)
                        .acos();
                    sum += radiance(angle);
                }
                texels.push(Rgb::splat(sum / (n * n) as f32));
            }
        }
        EnvMap::new(width, height, texels)
    }

    #[test]
    fn measures_discs_of_known_radius_at_several_resolutions() {
        let centre = Vec3::new(0.3, 0.5, -0.6).normalize();
        for width in [256usize, 512, 1024] {
            let texel = 2.0 * PI / width as f32;
            for radius_deg in [0.25f32, 0.5, 1.0, 2.0, 5.0, 10.0] {
                let radius = radius_deg.to_radians();
                let map = disc_map(width, centre, radius);
                let measured = source_shapes(&map, &[centre], 8f32.to_radians())[0]
                    .expect("a disc above its sky")
                    .radius;
                let error = (measured - radius).abs();
                assert!(
                    error <= (0.2 * radius).max(texel),
                    "{width} wide, {radius_deg}°: measured {}°",
                    measured.to_degrees()
                );
            }
        }
    }

    /// A 1° disc of 100 in a uniform ring out to 3° of 6, over a sky of 1: the excess is
    /// 99·πr² in the core and 5·8πr² in the ring, so the core holds 99/139 of it; the ring's
    /// mean angle from the centre is (2/3)(27 − 1)/(9 − 1) r, a disc of 1.5 times that.
    #[test]
    fn measures_the_core_and_halo_of_a_lamp() {
        let centre = Vec3::new(-0.2, 0.3, 0.8).normalize();
        let r = 1f32.to_radians();
        let map = map_around(1024, centre, |angle| {
            if angle <= r {
                100.0
            } else if angle <= 3.0 * r {
                6.0
            } else {
                1.0
            }
        });
        let shape = source_shapes(&map, &[centre], 8f32.to_radians())[0].expect("a lamp");
        let halo = 1.5 * (2.0 / 3.0) * (26.0 / 8.0) * r;
        assert!(
            (shape.radius - r).abs() < 0.1 * r,
            "core {}°",
            shape.radius.to_degrees()
        );
        assert!(
            (shape.core_fraction - 99.0 / 139.0).abs() < 0.03,
            "core fraction {}",
            shape.core_fraction
        );
        assert!(
            (shape.halo_radius - halo).abs() < 0.1 * halo,
            "halo {}° (expected {}°)",
            shape.halo_radius.to_degrees(),
            halo.to_degrees()
        );
        // A disc with no halo holds nearly all of its excess: only the texels straddling its
        // rim below half its level (a ring a texel wide, about a tenth of a 1° disc's excess
        // at 0.35° texels) count as halo.
        let plain = map_around(1024, centre, |angle| if angle <= r { 100.0 } else { 1.0 });
        let shape = source_shapes(&plain, &[centre], 8f32.to_radians())[0].expect("a disc");
        assert!(
            shape.core_fraction > 0.9,
            "core fraction {}",
            shape.core_fraction
        );
        // That ring lies at the rim, so the disc standing for it is about 1.5 r.
        assert!(
            shape.halo_radius < 2.0 * r,
            "halo {}°",
            shape.halo_radius.to_degrees()
        );
    }

    #[test]
    fn lights_sharing_a_source_split_it() {
        // A 10° disc seen by two lights on either side of its centre: each measures about half
        // of it, so the two radii are 10°/√2, not the whole disc's.
        let centre = Vec3::new(0.0, 0.4, -1.0).normalize();
        let map = disc_map(512, centre, 10f32.to_radians());
        let side = Vec3::new(0.09, 0.0, 0.0);
        let lights = [(centre + side).normalize(), (centre - side).normalize()];
        let radii = source_shapes(&map, &lights, 8f32.to_radians());
        for r in radii {
            let r = r.expect("a source").radius.to_degrees();
            assert!((r - 10.0 / 2f32.sqrt()).abs() < 0.6, "{r}°");
        }
    }

    #[test]
    fn a_map_without_a_peak_has_no_source() {
        let map = EnvMap::uniform(128, 64, Rgb::splat(2.0));
        assert_eq!(source_shapes(&map, &[Vec3::Y], 0.1), [None]);
    }

    #[test]
    fn texels_within_a_cap_across_the_seam_and_the_pole() {
        let map = EnvMap::uniform(256, 128, Rgb::ONE);
        for centre in [Vec3::new(0.0, 0.2, 1.0).normalize(), Vec3::Y, Vec3::NEG_Z] {
            let radius = 12f32.to_radians();
            let mut found = texels_within(&map, centre, radius);
            found.sort_unstable();
            let brute: Vec<(usize, usize)> = (0..128)
                .flat_map(|j| (0..256).map(move |i| (i, j)))
                .filter(|&(i, j)| map.texel_direction(i, j).dot(centre) >= radius.cos())
                .collect();
            let mut brute = brute;
            brute.sort_unstable();
            assert_eq!(found, brute, "{centre}");
        }
    }
}
