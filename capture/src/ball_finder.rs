//! Finding a chrome ball's outline in a photograph when the description does not give it.
//!
//! A ball of reflectance ρ < 1 shows, just inside its rim, what lies just outside it (a grazing
//! reflection sees past the ball), dimmed by ρ: its outline is an edge of the log brightness
//! all round. Hence, as OpenCV's `HoughCircles` with its gradient method: on a reduced image
//! of the exposures fused, every strong edge votes for centres along its gradient line, and
//! each best centre takes the radii its edges lie at. Each candidate is refined at full
//! resolution from the edge found along rays from its centre (sub-pixel), fitted by least
//! squares with outliers dropped, then as the cone of rays grazing the ball; the ball is the
//! largest candidate whose edges lie on that cone and whose disc is busier than its
//! surroundings.

use crate::camera::ShotCamera;
use glam::{Vec2, Vec3};
use hough::vote;

mod hough;

pub use hough::Circle;

/// The long side of the reduced image the votes are cast in.
const VOTING_SIDE: usize = 320;
/// Rays cast from the coarse centre to refine the outline.
const RAYS: usize = 360;
/// The least radius of a ball, as a share of the picture's shorter side: smaller circles are
/// as often a texture's.
const MIN_RADIUS: f32 = 0.1;
/// How much busier a ball's disc must be than its surroundings ([`detail_ratio`]).
const MIN_DETAIL_RATIO: f32 = 1.8;
/// How near the grazing cone an edge must be to support a found ball (pixels): a ball's
/// outline is found to a fraction of a pixel all round; a texture's edges only scatter near a
/// circle.
const SUPPORT_MARGIN: f32 = 1.0;
/// Least support for an outline to count as found.
const MIN_SUPPORT: f32 = 0.6;

/// A ball found in a photograph.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoundBall {
    /// Its outline's best circle, in the description's pixels (spanning `[i, i + 1)`).
    pub outline: Circle,
    /// The cone of rays that graze it: its axis (toward the ball's centre) and half-angle.
    pub axis: Vec3,
    pub half_angle: f32,
}

/// The ball in the photographs of one view (`w × h` levels row by row, each with its exposure
/// time) taken through `camera`, if its outline is clear enough.
pub fn find_ball(
    exposures: &[(&[[u8; 3]], f32)],
    (w, h): (usize, usize),
    camera: &ShotCamera,
) -> Option<FoundBall> {
    let brightness = log_brightness(exposures, w * h);
    let scale = w.max(h).div_ceil(VOTING_SIDE).max(1);
    let small = reduce(&brightness, w, h, scale);
    let s = scale as f32;
    let min_radius = (MIN_RADIUS * w.min(h) as f32).max(4.0);
    // The ball is the largest well-supported outline: a highlight reflected in it is a circle
    // too, a smaller one inside.
    let mut best: Option<FoundBall> = None;
    let small_min = ((min_radius / s).floor() as usize).max(4);
    for coarse in vote(&small.0, small.1, small.2, small_min) {
        let mut circle = Circle {
            centre: (coarse.centre + 0.5) * s - 0.5 * Vec2::ONE,
            radius: coarse.radius * s,
            support: 0.0,
        };
        // Two refinements: the second starts from a centre within a pixel.
        let mut points = Vec::new();
        let refined = (0..2).try_for_each(|_| {
            (circle, points) = refine(&brightness, w, h, circle, 2.0 * s + 2.0)?;
            Some(())
        });
        if refined.is_none()
            || circle.support < MIN_SUPPORT
            || circle.radius < min_radius
            || best.is_some_and(|b| circle.radius <= b.outline.radius)
        {
            continue;
        }
        let found = grazing_cone(camera, circle, &points)
            .filter(|_| detail_ratio(&brightness, (w, h), circle) >= MIN_DETAIL_RATIO);
        if found.is_some() {
            best = found;
        }
    }
    best
}

/// How much busier the picture is inside `circle` than around it: the mean log-brightness
/// gradient over the disc's inner part against that over a ring outside (within the picture).
/// A ball squeezes the whole room into its disc; a circle that happens to follow a texture's
/// edges has the same texture on both sides.
fn detail_ratio(values: &[f32], (w, h): (usize, usize), circle: Circle) -> f32 {
    let (mut inside, mut outside) = ((0.0f32, 0u32), (0.0f32, 0u32));
    let r = circle.radius;
    let (x0, x1) = (
        (circle.centre.x - 1.6 * r).max(1.0),
        (circle.centre.x + 1.6 * r).min((w - 2) as f32),
    );
    let (y0, y1) = (
        (circle.centre.y - 1.6 * r).max(1.0),
        (circle.centre.y + 1.6 * r).min((h - 2) as f32),
    );
    if !(x0 < x1 && y0 < y1) {
        return 0.0;
    }
    for y in y0 as usize..=y1 as usize {
        for x in x0 as usize..=x1 as usize {
            let d = Vec2::new(x as f32, y as f32).distance(circle.centre) / r;
            let gx = values[y * w + x + 1] - values[y * w + x - 1];
            let gy = values[(y + 1) * w + x] - values[(y - 1) * w + x];
            let g = (gx * gx + gy * gy).sqrt();
            if (0.2..0.85).contains(&d) {
                inside = (inside.0 + g, inside.1 + 1);
            } else if (1.15..1.6).contains(&d) {
                outside = (outside.0 + g, outside.1 + 1);
            }
        }
    }
    let mean = |(sum, n): (f32, u32)| sum / n.max(1) as f32;
    mean(inside) / mean(outside).max(1e-6)
}

/// The ball outlined by `points` (edges found along rays from `circle`'s centre), seen
/// through `camera`: the cone of rays grazing it, if most of the points lie on it.
fn grazing_cone(camera: &ShotCamera, circle: Circle, points: &[Vec2]) -> Option<FoundBall> {
    // Pixel centres were at integers; the description's pixels span [i, i + 1).
    let rays: Vec<Vec3> = points
        .iter()
        .map(|p| camera.direction_of(p.x + 0.5, p.y + 0.5))
        .collect();
    let pixel_angle = 2.0 * camera.tan_half_fov / camera.height as f32;
    // A ball off the camera's axis outlines an ellipse: its ends may stray from the best
    // circle by more than a pixel, not from the cone.
    let near: Vec<Vec3> = rays
        .iter()
        .zip(points)
        .filter(|(_, p)| (p.distance(circle.centre) - circle.radius).abs() <= 3.0)
        .map(|(v, _)| *v)
        .collect();
    let (axis, half_angle) = fit_grazing_cone(near, 1.5 * pixel_angle)?;
    let on_cone = rays
        .iter()
        .filter(|v| (v.angle_between(axis) - half_angle).abs() <= SUPPORT_MARGIN * pixel_angle)
        .count();
    let support = on_cone as f32 / RAYS as f32;
    (support >= MIN_SUPPORT).then_some(FoundBall {
        outline: Circle {
            centre: circle.centre + Vec2::splat(0.5),
            support,
            ..circle
        },
        axis,
        half_angle,
    })
}

/// The cone `a · v = cos α` through `rays` (least squares in `b = a / cos α`, which makes it
/// linear: `b · v = 1`), refitted without rays more than `margin` radians off it.
fn fit_grazing_cone(mut rays: Vec<Vec3>, margin: f32) -> Option<(Vec3, f32)> {
    let fit = |rays: &[Vec3]| {
        if rays.len() < 8 {
            return None;
        }
        let (mut a, mut b) = ([[0.0f64; 3]; 3], [0.0f64; 3]);
        for v in rays {
            let v = v.as_dvec3().to_array();
            for i in 0..3 {
                for j in 0..3 {
                    a[i][j] += v[i] * v[j];
                }
                b[i] += v[i];
            }
        }
        let b = glam::DVec3::from_array(solve3(a, b)?);
        let length = b.length();
        (length > 1.0).then(|| ((b / length).as_vec3(), (1.0 / length).acos() as f32))
    };
    let mut cone = fit(&rays)?;
    for _ in 0..3 {
        rays.retain(|v| (v.angle_between(cone.0) - cone.1).abs() <= margin);
        cone = fit(&rays)?;
    }
    Some(cone)
}

/// Per pixel, `ln((1 + level) / time)` of its mean level averaged over the exposures with a
/// hat weight (the response is not known yet: a rough log radiance, but one in which the rim's
/// step by the ball's reflectance shows in the dark and the bright parts of the room alike).
fn log_brightness(exposures: &[(&[[u8; 3]], f32)], pixels: usize) -> Vec<f32> {
    (0..pixels)
        .map(|i| {
            let (mut sum, mut total, mut fallback) = (0.0f32, 0.0f32, (f32::MAX, 0.0f32));
            for (levels, time) in exposures {
                let p = levels[i];
                let z = (p[0] as f32 + 2.0 * p[1] as f32 + p[2] as f32) / 4.0;
                let value = ((1.0 + z) / time.max(f32::MIN_POSITIVE)).ln();
                let weight = z.min(255.0 - z).max(0.0);
                sum += weight * value;
                total += weight;
                // Where every exposure is black or clipped: the one nearest mid-grey.
                let distance = (z - 128.0).abs();
                if distance < fallback.0 {
                    fallback = (distance, value);
                }
            }
            if total > 0.0 { sum / total } else { fallback.1 }
        })
        .collect()
}

/// Box-filters `values` by `k × k` blocks (partial blocks at the edges averaged as they are).
fn reduce(values: &[f32], w: usize, h: usize, k: usize) -> (Vec<f32>, usize, usize) {
    let (sw, sh) = (w.div_ceil(k), h.div_ceil(k));
    let mut sums = vec![0.0f32; sw * sh];
    let mut counts = vec![0u32; sw * sh];
    for y in 0..h {
        for x in 0..w {
            let i = (y / k) * sw + x / k;
            sums[i] += values[y * w + x];
            counts[i] += 1;
        }
    }
    for (s, c) in sums.iter_mut().zip(&counts) {
        *s /= (*c).max(1) as f32;
    }
    (sums, sw, sh)
}

/// The outline near `circle` (within `reach` pixels of it), found along rays from its centre
/// at full resolution and fitted.
fn refine(
    values: &[f32],
    w: usize,
    h: usize,
    circle: Circle,
    reach: f32,
) -> Option<(Circle, Vec<Vec2>)> {
    let sample = |p: Vec2| bilinear(values, w, h, p);
    let mut points = Vec::with_capacity(RAYS);
    for k in 0..RAYS {
        let angle = std::f32::consts::TAU * k as f32 / RAYS as f32;
        let dir = Vec2::new(angle.cos(), angle.sin());
        // The derivative over one pixel every quarter pixel across the reach; the edge at its
        // largest magnitude, placed between samples by a parabola through its neighbours.
        let start = (circle.radius - reach).max(1.0);
        let count = (2.0 * reach / 0.25) as usize;
        let mut derivative = Vec::with_capacity(count);
        for i in 0..count {
            let t = start + 0.25 * i as f32;
            derivative.push(
                sample(circle.centre + dir * (t + 0.5))? - sample(circle.centre + dir * (t - 0.5))?,
            );
        }
        // The outermost strong edge: outside the ball lies the room, smooth at this scale;
        // just inside, grazing reflections sweep across the whole room (a bright or dark ring,
        // inner edges) within a pixel or two.
        let largest = derivative.iter().fold(0.0f32, |m, d| m.max(d.abs()));
        let strong = |i: usize| {
            let d = derivative[i].abs();
            d >= 0.5 * largest
                && (i == 0 || d >= derivative[i - 1].abs())
                && (i + 1 == count || d >= derivative[i + 1].abs())
        };
        let Some(i) = (0..count).rev().find(|&i| largest > 0.0 && strong(i)) else {
            continue;
        };
        let offset = if i > 0 && i + 1 < count {
            let (a, b, c) = (
                derivative[i - 1].abs(),
                derivative[i].abs(),
                derivative[i + 1].abs(),
            );
            let curvature = a - 2.0 * b + c;
            if curvature < 0.0 {
                0.5 * (a - c) / curvature
            } else {
                0.0
            }
        } else {
            0.0
        };
        points.push(circle.centre + dir * (start + 0.25 * (i as f32 + offset)));
    }
    let mut kept = points.clone();
    let mut fitted = fit_circle(&kept)?;
    for _ in 0..3 {
        kept.retain(|p| (p.distance(fitted.0) - fitted.1).abs() <= 1.5);
        fitted = fit_circle(&kept)?;
    }
    let support = points
        .iter()
        .filter(|p| (p.distance(fitted.0) - fitted.1).abs() <= 1.5)
        .count() as f32
        / RAYS as f32;
    let circle = Circle {
        centre: fitted.0,
        radius: fitted.1,
        support,
    };
    Some((circle, points))
}

/// The value at continuous pixel coordinates `p` (pixel centres at integers), if inside.
fn bilinear(values: &[f32], w: usize, h: usize, p: Vec2) -> Option<f32> {
    if !(p.x >= 0.0 && p.y >= 0.0 && p.x <= (w - 1) as f32 && p.y <= (h - 1) as f32) {
        return None;
    }
    let (x0, y0) = (p.x.floor() as usize, p.y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (p.x - x0 as f32, p.y - y0 as f32);
    let row = |y: usize| values[y * w + x0] * (1.0 - fx) + values[y * w + x1] * fx;
    Some(row(y0) * (1.0 - fy) + row(y1) * fy)
}

/// The least-squares circle through `points` (Kåsa's algebraic fit: `x² + y² + D x + E y + F
/// = 0`, linear in D, E, F), centred on the points' mean for conditioning.
fn fit_circle(points: &[Vec2]) -> Option<(Vec2, f32)> {
    if points.len() < 8 {
        return None;
    }
    let mean = points.iter().copied().sum::<Vec2>() / points.len() as f32;
    let (mut a, mut b) = ([[0.0f64; 3]; 3], [0.0f64; 3]);
    for p in points {
        let q = (*p - mean).as_dvec2();
        let row = [q.x, q.y, 1.0];
        let rhs = -(q.x * q.x + q.y * q.y);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            b[i] += row[i] * rhs;
        }
    }
    let [d, e, f] = solve3(a, b)?;
    let centre = glam::DVec2::new(-d / 2.0, -e / 2.0);
    let r2 = centre.length_squared() - f;
    (r2 > 0.0).then(|| (centre.as_vec2() + mean, r2.sqrt() as f32))
}

/// `a x = b` by Cramer's rule, `None` when `a` is singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    if d.abs() < 1e-12 {
        return None;
    }
    Some(std::array::from_fn(|k| {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        det(m) / d
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::{CameraResponse, photograph};
    use crate::{MirrorBall, ShotCamera, View};
    use foundation::Rgb;
    use foundation::envmap::EnvMap;
    use glam::Vec3;
    use rand_pcg::Pcg32;

    /// A sky over a darker ground with a sun and a bright window: outlines of every contrast.
    fn room() -> EnvMap {
        let sun = Vec3::new(0.3, 0.8, -0.5).normalize();
        let window = Vec3::new(-0.9, 0.1, 0.3).normalize();
        EnvMap::from_fn(256, 128, 2, |d| {
            let sky = if d.y > 0.0 {
                Rgb::new(0.5, 0.6, 0.9) * (0.5 + d.y)
            } else {
                Rgb::new(0.3, 0.25, 0.2) * (1.0 + 0.5 * (8.0 * d.x).sin())
            };
            let spots = if d.dot(sun) > 0.995 { 50.0 } else { 0.0 }
                + if d.dot(window) > 0.95 { 4.0 } else { 0.0 };
            sky + Rgb::splat(spots)
        })
    }

    /// Balls at several places and sizes, photographed with noise, are found within a pixel
    /// (the cone of rays grazing them: its axis and half-angle), from the darker step of their
    /// reflectance. (Just inside the rim the reflection sweeps fast across the room; its edges
    /// pull a large ball's outline in by most of a pixel.)
    #[test]
    fn a_ball_is_found_where_it_was_photographed() {
        let map = room();
        let response = CameraResponse::knee([1.0; 3], 2.0, f32::INFINITY, 0.6);
        let mut rng = Pcg32::new(7, 9);
        for (size, centre, radius, yaw) in [
            ((160, 120), (80.0, 60.0), 45.0, 0.0),
            ((200, 150), (117.3, 70.6), 38.5, 40.0),
            ((640, 480), (300.0, 260.0), 150.0, -100.0),
            ((400, 300), (90.0, 210.0), 60.0, 200.0),
        ] {
            let camera = ShotCamera::new((yaw, 10.0, 0.0), 30.0, size, (0.0, 0.0));
            let ball = MirrorBall::new(camera, centre, radius, [0.6; 3]);
            let photo = photograph(&map, View::Ball(ball), size, 0.5, &response, &mut rng);
            let found = find_ball(&[(&photo.levels, photo.time)], size, &camera).expect("a ball");
            let (axis, half_angle) = ball.grazing_cone();
            let pixel = 2.0 * camera.tan_half_fov / size.1 as f32;
            let (axis_error, angle_error) = (
                found.axis.angle_between(axis) / pixel,
                (found.half_angle - half_angle).abs() / pixel,
            );
            assert!(
                axis_error < 1.0 && angle_error < 1.0,
                "{size:?}: {found:?} against {centre:?}, {radius}: off by {axis_error} and \
                 {angle_error} pixels"
            );
        }
    }

    /// A picture with no ball in it (a plain shot of the room) gives none.
    #[test]
    fn no_ball_no_circle() {
        let map = room();
        let response = CameraResponse::knee([1.0; 3], 2.0, f32::INFINITY, 0.6);
        let camera = ShotCamera::new((30.0, 5.0, 0.0), 60.0, (160, 120), (0.0, 0.0));
        let photo = photograph(
            &map,
            View::Shot(camera),
            (160, 120),
            0.5,
            &response,
            &mut Pcg32::new(1, 1),
        );
        let found = find_ball(&[(&photo.levels, photo.time)], (160, 120), &camera);
        assert_eq!(found, None);
    }

    #[test]
    fn the_fit_recovers_a_circle_from_its_points() {
        let points: Vec<Vec2> = (0..40)
            .map(|k| {
                let a = k as f32 * 0.157;
                Vec2::new(120.5, 80.25) + 33.0 * Vec2::new(a.cos(), a.sin())
            })
            .collect();
        let (c, r) = fit_circle(&points).unwrap();
        assert!(c.distance(Vec2::new(120.5, 80.25)) < 1e-3 && (r - 33.0).abs() < 1e-3);
        assert!(fit_circle(&points[..5]).is_none());
    }
}
