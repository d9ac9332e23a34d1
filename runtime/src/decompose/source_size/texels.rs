//! A map's texels tabulated by row and column, and the texels of a cap, visited in order.

use super::median::order_key;
use foundation::envmap::EnvMap;
use foundation::luminance;
use glam::Vec3;
use std::f32::consts::PI;

/// The texel directions of an equirectangular map size, tabulated by row and column (the same
/// floats as [`EnvMap::texel_direction`], without two sines per texel), and each row's texel
/// solid angle: the measurement visits tens of thousands of texels per light every frame.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct EquirectTexels {
    /// `(sin φ, cos φ)` of each column's centre.
    pub(super) columns: Vec<(f32, f32)>,
    /// `(sin θ, cos θ)` of each row's centre.
    pub(super) rows: Vec<(f32, f32)>,
    pub(super) solid_angles: Vec<f32>,
}

impl EquirectTexels {
    pub(super) fn new(width: usize, height: usize) -> Self {
        let columns = (0..width)
            .map(|i| (std::f32::consts::TAU * ((i as f32 + 0.5) / width as f32)).sin_cos())
            .collect();
        let rows = (0..height)
            .map(|j| (PI * ((j as f32 + 0.5) / height as f32)).sin_cos())
            .collect();
        let shape = EnvMap::uniform(width, height, foundation::Rgb::ZERO);
        Self {
            columns,
            rows,
            solid_angles: (0..height).map(|j| shape.texel_solid_angle(j)).collect(),
        }
    }
}

/// A map seen through its tabulated texels.
pub(super) struct TexelTable<'a> {
    pub(super) map: &'a EnvMap,
    pub(super) texels: &'a EquirectTexels,
}

impl TexelTable<'_> {
    pub(super) fn width(&self) -> usize {
        self.map.width()
    }

    pub(super) fn height(&self) -> usize {
        self.map.height()
    }

    #[inline]
    pub(super) fn direction(&self, (i, j): (usize, usize)) -> Vec3 {
        let ((sin_phi, cos_phi), (sin_theta, cos_theta)) =
            (self.texels.columns[i], self.texels.rows[j]);
        Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
    }

    #[inline]
    pub(super) fn luminance(&self, (i, j): (usize, usize)) -> f32 {
        luminance(self.map.texel(i, j))
    }

    #[inline]
    pub(super) fn solid_angle(&self, (_, j): (usize, usize)) -> f32 {
        self.texels.solid_angles[j]
    }

    /// Calls `visit` for each texel `(i, j)` within `radius` of `centre`, with its direction:
    /// rows by polar angle, then in each row the columns of an azimuth window around the centre's, in increasing
    /// azimuth from the window's start (wrapping). Only the part of the window that can be
    /// that close (with two texels' margin) is tested.
    pub(super) fn for_each_within(
        &self,
        centre: Vec3,
        radius: f32,
        mut visit: impl FnMut((usize, usize), Vec3),
    ) {
        let w = self.width();
        let (theta, rows) = self.cap_rows(centre, radius);
        let row_angle = PI / self.height() as f32;
        let cos_radius = radius.cos();
        let centre_u = foundation::envmap::uv_of_direction(centre).0 * w as f32;
        let column_angle = std::f64::consts::TAU / w as f64;
        for j in rows {
            // Columns to test: all of them near a pole, else a window around the centre's.
            let sin_row = ((j as f32 + 0.5) * row_angle).sin();
            let half_width =
                if sin_row * PI <= radius * 2.0 || theta < radius || PI - theta < radius {
                    w as f32
                } else {
                    (radius / sin_row) / (2.0 * PI) * w as f32 * 1.5 + 2.0
                };
            let span = (2.0 * half_width).min(w as f32) as usize;
            let start = (centre_u - half_width.min(w as f32 / 2.0)).floor() as isize;
            // The columns whose azimuth is within Δφ of the centre's, where
            // cos Δφ = (cos R − cos θ cos θ_c) / (sin θ sin θ_c), lie within `reach` columns
            // of the centre's position in the window (exact in f64, then widened).
            let reach = if half_width >= w as f32 {
                w as f64
            } else {
                // Away from the poles: sin θ and sin θ_c are both well above zero here. The
                // f32 test can pass a texel up to ~1e-6 below cos R (rounding in the tables
                // and the dot product): widen the bound by that, then by two columns.
                let (sin_theta, cos_theta) = self.texels.rows[j];
                let (sin_c, cos_c) = (f64::from(theta).sin(), f64::from(theta).cos());
                let across = f64::from(sin_theta) * sin_c;
                let q = (f64::from(cos_radius) - f64::from(cos_theta) * cos_c - 1e-6) / across;
                q.clamp(-1.0, 1.0).acos() / column_angle + 2.0
            };
            let centre_k = f64::from(centre_u) - start as f64;
            let k_first = (centre_k - reach).floor().max(0.0) as usize;
            let k_last = ((centre_k + reach).ceil().max(0.0) as usize).min(span.max(1));
            let mut i = (start + k_first as isize).rem_euclid(w as isize) as usize;
            for _ in k_first..k_last {
                let direction = self.direction((i, j));
                if direction.dot(centre) >= cos_radius {
                    visit((i, j), direction);
                }
                i = if i + 1 == w { 0 } else { i + 1 };
            }
        }
    }
}

impl TexelTable<'_> {
    /// The polar angle of `centre` and the rows a cap of `radius` around it reaches.
    pub(super) fn cap_rows(&self, centre: Vec3, radius: f32) -> (f32, std::ops::Range<usize>) {
        let h = self.height();
        let theta = centre.y.clamp(-1.0, 1.0).acos();
        let row_angle = PI / h as f32;
        let first = (((theta - radius) / row_angle).floor().max(0.0)) as usize;
        let last = ((((theta + radius) / row_angle).ceil()) as usize).min(h);
        (theta, first..last)
    }

    /// Appends the luminance ([`order_key`]) of every texel of the lattice of step `step`
    /// (rows and columns `n` with `n mod step = step / 2`; every texel for 1) within `radius`
    /// of `centre` to `out` (of [`Self::for_each_within`]'s texels, in no particular order).
    /// In each row, the columns certainly inside (by more than the test's rounding) are read
    /// in bulk, and only those near the cap's rim are tested.
    pub(super) fn luminances_within(
        &self,
        centre: Vec3,
        radius: f32,
        step: usize,
        out: &mut Vec<u32>,
    ) {
        // The first lattice column at or after `a`.
        let on_lattice_from = |a: usize| a + (step / 2 + step - a % step) % step;
        let w = self.width();
        let (theta, rows) = self.cap_rows(centre, radius);
        let cos_radius = radius.cos();
        let centre_u = f64::from(foundation::envmap::uv_of_direction(centre).0) * w as f64;
        let column_angle = std::f64::consts::TAU / w as f64;
        let (sin_c, cos_c) = (f64::from(theta).sin(), f64::from(theta).cos());
        let texels = self.map.texels();
        for j in rows.filter(|j| j % step == step / 2) {
            let (sin_theta, cos_theta) = self.texels.rows[j];
            let across = f64::from(sin_theta) * sin_c;
            let level = f64::from(cos_radius) - f64::from(cos_theta) * cos_c;
            // cos Δφ ≥ level / across inside the cap; with the rounding allowance either way.
            let half_columns = |slack: f64| -> f64 {
                if across < 1e-9 {
                    return if slack > 0.0 { -1.0 } else { w as f64 };
                }
                let q = (level + slack) / across;
                if q > 1.0 {
                    -1.0
                } else {
                    q.max(-1.0).acos() / column_angle
                }
            };
            let inner = half_columns(4e-6) - 1.0;
            let outer = half_columns(-4e-6) + 1.0;
            let row = &texels[j * w..(j + 1) * w];
            let (inside, near) = (
                column_range(centre_u, inner, w),
                column_range(centre_u, outer, w),
            );
            for (a, b) in inside.segments(w) {
                let a = on_lattice_from(a).min(b);
                let lattice = row[a..b].iter().step_by(step);
                out.extend(lattice.map(|c| order_key(luminance(*c))));
            }
            for band in near.minus(inside, w) {
                for (a, b) in band.segments(w) {
                    for i in (on_lattice_from(a)..b).step_by(step) {
                        if self.direction((i, j)).dot(centre) >= cos_radius {
                            out.push(order_key(luminance(row[i])));
                        }
                    }
                }
            }
        }
    }
}

/// Columns `first, first + 1, …` (`count` of them, wrapping at the map's width).
#[derive(Debug, Clone, Copy)]
pub(super) struct ColumnRange {
    pub(super) first: usize,
    pub(super) count: usize,
}

/// The columns whose centres lie within `half` columns of position `centre` (in columns,
/// from the map's left edge).
pub(super) fn column_range(centre: f64, half: f64, width: usize) -> ColumnRange {
    if half < 0.0 {
        return ColumnRange { first: 0, count: 0 };
    }
    // Column i's centre is at i + 0.5.
    let first = (centre - 0.5 - half).ceil();
    let last = (centre - 0.5 + half).floor();
    let count = (last - first + 1.0).max(0.0);
    if count >= width as f64 {
        return ColumnRange {
            first: 0,
            count: width,
        };
    }
    ColumnRange {
        first: first.rem_euclid(width as f64) as usize % width,
        count: count as usize,
    }
}

impl ColumnRange {
    /// The range as at most two index ranges of a row.
    pub(super) fn segments(self, width: usize) -> impl Iterator<Item = (usize, usize)> {
        let end = self.first + self.count;
        let head = (self.first, end.min(width));
        let tail = (0, end.saturating_sub(width));
        [head, tail].into_iter().filter(|(a, b)| a < b)
    }

    /// The columns of `self` outside `inner` (which lies within it, centred alike): a band on
    /// each side.
    pub(super) fn minus(self, inner: ColumnRange, width: usize) -> [ColumnRange; 2] {
        let none = ColumnRange { first: 0, count: 0 };
        if inner.count == 0 {
            return [self, none];
        }
        if self.count == width {
            // The whole row (which starts anywhere): the rest of it after `inner`.
            let rest = ColumnRange {
                first: (inner.first + inner.count) % width,
                count: width - inner.count,
            };
            return [rest, none];
        }
        let left = (inner.first + width - self.first) % width;
        let left = left.min(self.count - inner.count);
        [
            ColumnRange {
                first: self.first,
                count: left,
            },
            ColumnRange {
                first: (inner.first + inner.count) % width,
                count: self.count - inner.count - left,
            },
        ]
    }
}

/// Equirectangular texels `(i, j)` within `radius` of `centre` (rows by polar angle, then the
/// columns of each row whose azimuth can be that close).
#[cfg(test)]
pub(super) fn texels_within(map: &EnvMap, centre: Vec3, radius: f32) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let texels = EquirectTexels::new(map.width(), map.height());
    TexelTable {
        map,
        texels: &texels,
    }
    .for_each_within(centre, radius, |t, _| out.push(t));
    out
}
