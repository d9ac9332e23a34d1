//! The source measurement against brute force and closed forms.

use super::median::{median_of_keys, order_key};
use super::texels::texels_within;
use super::*;
use foundation::Rgb;
use foundation::luminance;

/// [`SourceMeter::shapes`] once.
fn source_shapes(map: &EnvMap, directions: &[Vec3], cap_radius: f32) -> Vec<Option<SourceShape>> {
    SourceMeter::new().shapes(map, directions, cap_radius)
}

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
                let angle = foundation::envmap::direction_of_uv(u, v)
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
fn the_median_is_the_middle_element_in_total_order() {
    let mut state = 12345u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    for len in [1usize, 2, 3, 10, 1000, 30_001] {
        // Wide exponents, many ties, zeros of both signs and a few negatives.
        let values: Vec<f32> = (0..len)
            .map(|_| match next() % 5 {
                0 => 0.0,
                1 => -0.0,
                2 => (next() % 7) as f32,
                3 => -((next() % 1000) as f32) * 1e-3,
                _ => f32::from_bits(next() % 0x7f00_0000),
            })
            .collect();
        let mut sorted = values.clone();
        sorted.sort_by(f32::total_cmp);
        let keys: Vec<u32> = values.iter().map(|v| order_key(*v)).collect();
        assert_eq!(
            median_of_keys(&mut keys.clone()).to_bits(),
            sorted[len / 2].to_bits(),
            "{len} values"
        );
    }
    assert_eq!(median_of_keys(&mut []), 0.0);
    // Flat maps: all keys equal, or equal but for a few on either side.
    for (len, odd) in [(1001usize, 0usize), (1001, 3), (4000, 499)] {
        let mut values = vec![1.5f32; len];
        for k in 0..odd {
            values[k] = 1.5 + (k as f32 + 1.0) * 1e-6;
            values[len - 1 - k] = 1.5 - (k as f32 + 1.0) * 1e-6;
        }
        let mut sorted = values.clone();
        sorted.sort_by(f32::total_cmp);
        let mut keys: Vec<u32> = values.iter().map(|v| order_key(*v)).collect();
        assert_eq!(
            median_of_keys(&mut keys).to_bits(),
            sorted[len / 2].to_bits()
        );
    }
}

/// The measurement as first written, by brute force: every texel tested with its own
/// direction, the median by sorting, the half-maximum region by a flood fill over a hash
/// set, the nearest light among all of them.
fn brute_force_shapes(map: &EnvMap, directions: &[Vec3], cap: f32) -> Vec<Option<SourceShape>> {
    let (w, h) = (map.width(), map.height());
    let texels: Vec<(usize, usize)> = (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).collect();
    let lum = |(i, j): (usize, usize)| luminance(map.texel(i, j));
    let dir = |(i, j): (usize, usize)| map.texel_direction(i, j);
    let nearest = |v: Vec3| {
        (0..directions.len())
            .max_by(|a, b| v.dot(directions[*a]).total_cmp(&v.dot(directions[*b])))
            .unwrap()
    };
    let within = |c: Vec3, r: f32| -> Vec<(usize, usize)> {
        texels
            .iter()
            .copied()
            .filter(|t| dir(*t).dot(c) >= r.cos())
            .collect()
    };
    (0..directions.len())
        .map(|k| {
            let d = directions[k];
            let step = super::background::lattice_step(w, h, BACKGROUND_RADIUS);
            let on_lattice = |n: usize| n % step == step / 2;
            let mut background: Vec<f32> = within(d, BACKGROUND_RADIUS)
                .into_iter()
                .filter(|&(i, j)| on_lattice(i) && on_lattice(j))
                .map(lum)
                .collect();
            background.sort_by(f32::total_cmp);
            let background = background[background.len() / 2];
            let cell: Vec<(usize, usize)> = within(d, cap)
                .into_iter()
                .filter(|t| nearest(dir(*t)) == k)
                .collect();
            let (peak_texel, peak) = cell
                .iter()
                .map(|&t| (t, lum(t)))
                .max_by(|a, b| a.1.total_cmp(&b.1))?;
            if peak <= background {
                return None;
            }
            let half = 0.5 * (background + peak);
            let mut core = std::collections::HashSet::from([peak_texel]);
            let mut stack = vec![peak_texel];
            while let Some((i, j)) = stack.pop() {
                let mut next = vec![((i + 1) % w, j), ((i + w - 1) % w, j)];
                if j > 0 {
                    next.push((i, j - 1));
                }
                if j + 1 < h {
                    next.push((i, j + 1));
                }
                for n in next {
                    if !core.contains(&n)
                        && lum(n) > half
                        && dir(n).dot(d) >= MAX_SOURCE_RADIUS.cos()
                        && nearest(dir(n)) == k
                    {
                        core.insert(n);
                        stack.push(n);
                    }
                }
            }
            let omega: f64 = core
                .iter()
                .map(|t| f64::from(map.texel_solid_angle(t.1)))
                .sum();
            let excess = |t: (usize, usize)| {
                f64::from((lum(t) - background).max(0.0) * map.texel_solid_angle(t.1))
            };
            let core_excess: f64 = core.iter().map(|t| excess(*t)).sum();
            let (mut halo, mut moment) = (0.0, 0.0);
            for t in cell.iter().filter(|t| !core.contains(t)) {
                halo += excess(*t);
                moment += excess(*t) * f64::from(dir(*t).angle_between(d));
            }
            let radius = disc_radius(omega as f32);
            Some(SourceShape {
                radius,
                halo_radius: if halo > 0.0 {
                    ((1.5 * moment / halo) as f32).clamp(radius, cap.max(radius))
                } else {
                    radius
                },
                core_fraction: (core_excess / (core_excess + halo)) as f32,
            })
        })
        .collect()
}

/// Several lights close enough to compete for texels, over a textured sky with discs and
/// a haloed lamp, one light near the pole: the fast measurement finds what brute force
/// does (the sums in another order: within 1e-5 relative).
#[test]
fn the_measurement_agrees_with_brute_force() {
    let lights = [
        Vec3::new(0.3, 0.5, -0.6).normalize(),
        Vec3::new(0.38, 0.5, -0.6).normalize(),
        Vec3::new(-0.7, 0.2, 0.4).normalize(),
        Vec3::new(0.05, 0.99, 0.05).normalize(),
        Vec3::new(0.2, -0.3, 0.9).normalize(),
    ];
    let map = map_around(256, Vec3::Y, |_| 0.0);
    let texels = (0..128)
        .flat_map(|j| (0..256).map(move |i| (i, j)))
        .map(|(i, j)| {
            let w = map.texel_direction(i, j);
            let sky = 1.0 + 0.5 * (7.0 * w.x).sin() * (5.0 * w.z).cos() + 0.3 * w.y;
            let glow: f32 = lights
                .iter()
                .enumerate()
                .map(|(k, l)| {
                    let a = w.angle_between(*l).to_degrees();
                    let size = 1.0 + k as f32;
                    if a < size {
                        80.0 / size
                    } else {
                        6.0 * (-(a - size) / 3.0).exp()
                    }
                })
                .sum();
            Rgb::new(sky + glow, 0.9 * sky + glow, 0.8 * sky + 1.1 * glow)
        })
        .collect();
    let map = EnvMap::new(256, 128, texels);
    let cap = 8f32.to_radians();
    let fast = source_shapes(&map, &lights, cap);
    let brute = brute_force_shapes(&map, &lights, cap);
    for (k, (f, b)) in fast.iter().zip(&brute).enumerate() {
        let (f, b) = (f.expect("a source"), b.expect("a source"));
        for (name, x, y) in [
            ("radius", f.radius, b.radius),
            ("halo", f.halo_radius, b.halo_radius),
            ("core fraction", f.core_fraction, b.core_fraction),
        ] {
            assert!(
                (x - y).abs() <= 1e-5 * y.abs(),
                "light {k} {name}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn a_map_without_a_peak_has_no_source() {
    let map = EnvMap::uniform(128, 64, Rgb::splat(2.0));
    assert_eq!(source_shapes(&map, &[Vec3::Y], 0.1), [None]);
}

#[test]
fn texels_within_a_cap_across_the_seam_and_the_pole() {
    // Centres at the seam, the poles, next to a pole and at random; radii from under a
    // texel to the background's 30°: exactly the texels a brute-force scan finds.
    let mut centres = vec![
        Vec3::new(0.0, 0.2, 1.0).normalize(),
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::NEG_Z,
        Vec3::new(0.01, 0.9999, 0.0).normalize(),
    ];
    let mut state = 7u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    for _ in 0..12 {
        centres.push(Vec3::new(next(), next(), next()).normalize());
    }
    for (width, height) in [(256, 128), (96, 48)] {
        let map = EnvMap::uniform(width, height, Rgb::ONE);
        let indexed = EnvMap::new(
            width,
            height,
            (0..width * height).map(|n| Rgb::splat(n as f32)).collect(),
        );
        for &centre in &centres {
            for radius_deg in [0.3f32, 2.0, 12.0, 30.0] {
                let radius = radius_deg.to_radians();
                let mut found = texels_within(&map, centre, radius);
                found.sort_unstable();
                let mut brute: Vec<(usize, usize)> = (0..height)
                    .flat_map(|j| (0..width).map(move |i| (i, j)))
                    .filter(|&(i, j)| map.texel_direction(i, j).dot(centre) >= radius.cos())
                    .collect();
                brute.sort_unstable();
                assert_eq!(found, brute, "{centre} {radius_deg}° on {width}x{height}");
                // The bulk reading finds the same texels, or those of them on a lattice
                // (each map texel's luminance is its index here, so the values name the
                // texels).
                for step in [1, 2, 3] {
                    let mut values = Vec::new();
                    let texels = EquirectTexels::new(width, height);
                    TexelTable {
                        map: &indexed,
                        texels: &texels,
                    }
                    .luminances_within(centre, radius, step, &mut values);
                    values.sort_unstable();
                    let on_lattice = |n: usize| n % step == step / 2;
                    let mut expected: Vec<u32> = brute
                        .iter()
                        .filter(|&&(i, j)| on_lattice(i) && on_lattice(j))
                        .map(|&(i, j)| order_key(luminance(indexed.texel(i, j))))
                        .collect();
                    expected.sort_unstable();
                    assert_eq!(
                        values, expected,
                        "{centre} {radius_deg}° on {width}x{height}, step {step}"
                    );
                }
            }
        }
    }
}
