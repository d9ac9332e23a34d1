//! The coarse search of `find_ball`: circles voted for by a reduced image's strong edges, as
//! OpenCV's `HoughCircles` with its gradient method.

use glam::Vec2;

/// A circle in pixels: centre and radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    pub centre: Vec2,
    pub radius: f32,
    /// The share of rays from the centre whose edge lies on the outline: within 1.5 pixels of
    /// the circle while searching; within `SUPPORT_MARGIN` of the grazing cone once found.
    pub support: f32,
}

/// Coarse circles refined in search of the ball.
const CANDIDATES: usize = 16;

/// The best-voted circles of a reduced image of at least `r_min` pixels' radius (centre and
/// radius in its pixels, votes per unit of circumference as support), at most [`CANDIDATES`],
/// no two alike. As OpenCV's gradient method: every strong edge votes for the centres along
/// its gradient line (both ways: the ball may be darker or brighter than the room), the votes
/// blurred (a gradient's direction is off by a few degrees: the lines of a large circle cross
/// over some pixels); then each of the best centres takes the radii its edges lie at.
pub(super) fn vote(values: &[f32], w: usize, h: usize, r_min: usize) -> Vec<Circle> {
    let r_max = w.min(h) / 2;
    if r_max <= r_min || w < 3 || h < 3 {
        return Vec::new();
    }
    let edges = strong_edges(values, w, h);
    let mut votes = vec![0.0f32; w * h];
    for (p, g) in &edges {
        let direction = *g / g.length();
        for sign in [-1.0f32, 1.0] {
            for r in r_min..=r_max {
                let c = *p + direction * (sign * r as f32);
                let (cx, cy) = (c.x.round(), c.y.round());
                if cx >= 0.0 && cy >= 0.0 && (cx as usize) < w && (cy as usize) < h {
                    votes[cy as usize * w + cx as usize] += 1.0;
                }
            }
        }
    }
    let votes = box_blur(&box_blur(&votes, w, h, 2), w, h, 2);
    let mut candidates = Vec::new();
    for centre in best_centres(&votes, w, h, CANDIDATES) {
        candidates.extend(best_radii(&edges, centre, r_min, r_max));
    }
    candidates.sort_by(|a, b| b.support.total_cmp(&a.support));
    candidates.truncate(CANDIDATES);
    candidates
}

/// The image's pixels whose Sobel gradient is among the strongest quarter, with the gradient.
fn strong_edges(values: &[f32], w: usize, h: usize) -> Vec<(Vec2, Vec2)> {
    let mut edges = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let at = |dx: isize, dy: isize| {
                values[(y as isize + dy) as usize * w + (x as isize + dx) as usize]
            };
            let gx =
                at(1, -1) + 2.0 * at(1, 0) + at(1, 1) - at(-1, -1) - 2.0 * at(-1, 0) - at(-1, 1);
            let gy =
                at(-1, 1) + 2.0 * at(0, 1) + at(1, 1) - at(-1, -1) - 2.0 * at(0, -1) - at(1, -1);
            let g = Vec2::new(gx, gy);
            if g.length_squared() > 1e-6 {
                edges.push((Vec2::new(x as f32, y as f32), g));
            }
        }
    }
    if edges.is_empty() {
        return edges;
    }
    let mut magnitudes: Vec<f32> = edges.iter().map(|(_, g)| g.length()).collect();
    let cut = magnitudes.len() * 3 / 4;
    let threshold = *magnitudes.select_nth_unstable_by(cut, f32::total_cmp).1;
    edges.retain(|(_, g)| g.length() >= threshold);
    edges
}

/// The mean over `(2k + 1)²` pixels around each pixel (clamped at the edges).
fn box_blur(values: &[f32], w: usize, h: usize, k: usize) -> Vec<f32> {
    let mut out = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let (y0, y1) = (y.saturating_sub(k), (y + k).min(h - 1));
            let (x0, x1) = (x.saturating_sub(k), (x + k).min(w - 1));
            let mut sum = 0.0;
            for yy in y0..=y1 {
                sum += values[yy * w + x0..=yy * w + x1].iter().sum::<f32>();
            }
            out[y * w + x] = sum / ((y1 - y0 + 1) * (x1 - x0 + 1)) as f32;
        }
    }
    out
}

/// The `count` best local maxima of `votes`, at least 3 pixels apart.
fn best_centres(votes: &[f32], w: usize, h: usize, count: usize) -> Vec<Vec2> {
    let mut order: Vec<usize> = (0..w * h).filter(|&i| votes[i] > 0.0).collect();
    order.sort_by(|a, b| votes[*b].total_cmp(&votes[*a]));
    let mut chosen: Vec<Vec2> = Vec::new();
    for i in order {
        let c = Vec2::new((i % w) as f32, (i / w) as f32);
        if chosen.iter().all(|o| o.distance(c) >= 3.0) {
            chosen.push(c);
            if chosen.len() == count {
                break;
            }
        }
    }
    chosen
}

/// The two radii (from `r_min` to `r_max`) at which most of `edges` whose gradient points
/// along the radius lie around `centre`, as circles with their count per unit circumference.
fn best_radii(edges: &[(Vec2, Vec2)], centre: Vec2, r_min: usize, r_max: usize) -> Vec<Circle> {
    let mut histogram = vec![0.0f32; r_max + 2];
    for (p, g) in edges {
        let offset = *p - centre;
        let r = offset.length();
        if r < 1.0 || (r.round() as usize) > r_max {
            continue;
        }
        // Only edges across the circle, not along it.
        if (offset.dot(*g) / (r * g.length())).abs() > 0.9 {
            histogram[r.round() as usize] += 1.0;
        }
    }
    let score = |r: usize| {
        let near = histogram[r - 1] + histogram[r] + histogram[r + 1];
        near / (std::f32::consts::TAU * r as f32)
    };
    let mut radii: Vec<(usize, f32)> = (r_min.max(1)..=r_max).map(|r| (r, score(r))).collect();
    radii.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut out: Vec<Circle> = Vec::new();
    for (r, s) in radii {
        if out.iter().all(|c| (c.radius - r as f32).abs() >= 3.0) {
            out.push(Circle {
                centre,
                radius: r as f32,
                support: s,
            });
            if out.len() == 2 {
                break;
            }
        }
    }
    out
}
