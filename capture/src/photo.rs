//! A photograph as the assembly reads it: 8-bit levels, its exposure time, and its view.

use crate::ball::MirrorBall;
use crate::camera::ShotCamera;
use glam::Vec3;
use std::path::PathBuf;

/// How far levels may vary around a calibration sample (sensor noise is a level or two).
pub(crate) const FLAT_LEVELS: u8 = 6;

/// Where a photograph's pixels look.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum View {
    Shot(ShotCamera),
    Ball(MirrorBall),
}

impl View {
    /// The pixel that sees direction `d` and its weight (feathering toward the frame's edges,
    /// or the ball's grazing angle), if the photograph shows `d`.
    pub fn locate(&self, d: Vec3) -> Option<(f32, f32, f32)> {
        match self {
            View::Shot(camera) => {
                let (x, y) = camera.pixel_of(d)?;
                Some((x, y, camera.feather(x, y)))
            }
            View::Ball(ball) => ball.locate(d),
        }
    }

    /// The factor between the radiance a pixel records and the environment's (the ball's
    /// reflectance; 1 for a direct shot).
    pub fn reflectance(&self, channel: usize) -> f32 {
        match self {
            View::Shot(_) => 1.0,
            View::Ball(ball) => ball.reflectance[channel],
        }
    }
}

/// One photograph: `width × height` RGB levels (0-255, row by row from the top), exposed for
/// `time` seconds, seen through `view`.
#[derive(Debug, Clone)]
pub struct Photo {
    pub path: PathBuf,
    pub width: usize,
    pub height: usize,
    pub levels: Vec<[u8; 3]>,
    pub time: f32,
    pub view: View,
}

impl Photo {
    /// The levels at the pixel containing continuous coordinates `(x, y)`.
    pub fn nearest(&self, x: f32, y: f32) -> [u8; 3] {
        let i = (x as usize).min(self.width - 1);
        let j = (y as usize).min(self.height - 1);
        self.levels[j * self.width + i]
    }

    /// Whether the 3 × 3 pixels around `(x, y)` differ by at most [`FLAT_LEVELS`] in every
    /// channel (and all lie inside the picture).
    pub fn is_flat_at(&self, x: f32, y: f32) -> bool {
        let (i, j) = (x as usize, y as usize);
        if i == 0 || j == 0 || i + 1 >= self.width || j + 1 >= self.height {
            return false;
        }
        (0..3).all(|c| {
            let (mut lo, mut hi) = (u8::MAX, 0);
            for (di, dj) in (0..3).flat_map(|a| (0..3).map(move |b| (a, b))) {
                let v = self.levels[(j + dj - 1) * self.width + i + di - 1][c];
                (lo, hi) = (lo.min(v), hi.max(v));
            }
            hi - lo <= FLAT_LEVELS
        })
    }

    /// The four pixels around `(x, y)` (centres at `i + ½`) and their bilinear shares.
    pub fn bilinear(&self, x: f32, y: f32) -> [([u8; 3], f32); 4] {
        let (fx, fy) = ((x - 0.5).max(0.0), (y - 0.5).max(0.0));
        let (i0, j0) = (
            (fx as usize).min(self.width - 1),
            (fy as usize).min(self.height - 1),
        );
        let (i1, j1) = ((i0 + 1).min(self.width - 1), (j0 + 1).min(self.height - 1));
        let (tx, ty) = (fx - i0 as f32, fy - j0 as f32);
        let at = |i: usize, j: usize| self.levels[j * self.width + i];
        [
            (at(i0, j0), (1.0 - tx) * (1.0 - ty)),
            (at(i1, j0), tx * (1.0 - ty)),
            (at(i0, j1), (1.0 - tx) * ty),
            (at(i1, j1), tx * ty),
        ]
    }
}
