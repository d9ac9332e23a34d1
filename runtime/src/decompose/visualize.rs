//! A picture of a decomposition: the map, the SH part, the residual and the lights, as four
//! equirectangular panels.

use super::Decomposition;
use foundation::envmap::{EnvMap, direction_of_uv, uv_of_direction};
use foundation::image_io::{srgb_encode, tonemap};
use foundation::sh::ShBasis;
use foundation::{Rgb, luminance};
use glam::Vec3;

/// An 8-bit RGB picture.
pub struct Picture {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Picture {
    fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            rgb: vec![0; width * height * 3],
        }
    }

    fn set(&mut self, x: usize, y: usize, c: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = (y * self.width + x) * 3;
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }
}

fn display(c: Rgb, exposure: f32) -> [u8; 3] {
    tonemap(c, exposure)
        .to_array()
        .map(|x| (srgb_encode(x) * 255.0 + 0.5) as u8)
}

/// Tone-mapping exposure that puts the map's mean luminance at mid-grey.
pub(crate) fn auto_exposure(map: &EnvMap) -> f32 {
    std::f32::consts::LN_2 / map.mean_luminance().max(1e-6)
}

/// Four `panel_width × panel_width/2` panels: top left the map (tone-mapped) with the lights
/// marked (a circle of the cap radius and a cross at the direction), top right the SH part,
/// bottom left the positive residual (map − SH part), bottom right the negative residual.
/// `rotation` (radians) is the map's rotation about +Y.
pub fn decomposition_picture(
    map: &EnvMap,
    rotation: f32,
    decomposition: &Decomposition,
    panel_width: usize,
) -> Picture {
    let (w, h) = (panel_width, panel_width / 2);
    let exposure = auto_exposure(map);
    let basis = ShBasis::<f32>::new(decomposition.sh.order()).expect("supported order");
    let mut y = vec![0.0; basis.num_coeffs()];
    let mut picture = Picture::new(2 * w, 2 * h);
    for j in 0..h {
        for i in 0..w {
            let dir = direction_of_uv((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            // Box-filter the source map over this panel pixel's footprint.
            let source = map_average(map, rotation, i, j, w, h);
            basis.eval(dir, &mut y);
            let sh = decomposition.sh.dot_basis(&y);
            let residual = source - sh;
            picture.set(i, j, display(source, exposure));
            picture.set(w + i, j, display(sh.max(Rgb::ZERO), exposure));
            picture.set(i, h + j, display(residual.max(Rgb::ZERO), exposure));
            picture.set(w + i, h + j, display((-residual).max(Rgb::ZERO), exposure));
        }
    }
    for (k, light) in decomposition.lights.iter().enumerate() {
        let colour = MARKER_COLOURS[k % MARKER_COLOURS.len()];
        mark_light(
            &mut picture,
            w,
            h,
            light.direction,
            light.cap_radius,
            colour,
        );
    }
    picture
}

const MARKER_COLOURS: [[u8; 3]; 4] = [[255, 40, 40], [40, 255, 40], [60, 140, 255], [255, 0, 255]];

fn map_average(map: &EnvMap, rotation: f32, i: usize, j: usize, w: usize, h: usize) -> Rgb {
    let (sx, sy) = ((map.width() / w).max(1), (map.height() / h).max(1));
    let mut sum = Rgb::ZERO;
    for a in 0..sy {
        for b in 0..sx {
            let u = (i as f32 + (b as f32 + 0.5) / sx as f32) / w as f32;
            let v = (j as f32 + (a as f32 + 0.5) / sy as f32) / h as f32;
            let dir = direction_of_uv(u, v);
            sum += map.radiance(foundation::envmap::rotate_y(dir, -rotation));
        }
    }
    sum / (sx * sy) as f32
}

/// Draws a cross at `direction` and the outline of the cap around it on the top-left panel.
fn mark_light(
    picture: &mut Picture,
    w: usize,
    h: usize,
    direction: Vec3,
    radius: f32,
    colour: [u8; 3],
) {
    let to_pixel = |d: Vec3| {
        let (u, v) = uv_of_direction(d);
        ((u * w as f32) as usize, (v * h as f32) as usize)
    };
    let (cx, cy) = to_pixel(direction);
    for d in -6i32..=6 {
        picture.set((cx as i32 + d).rem_euclid(w as i32) as usize, cy, colour);
        picture.set(cx, (cy as i32 + d).clamp(0, h as i32 - 1) as usize, colour);
    }
    let (t1, t2) = direction.any_orthonormal_pair();
    for k in 0..360 {
        let a = (k as f32).to_radians();
        let p = direction * radius.cos() + (t1 * a.cos() + t2 * a.sin()) * radius.sin();
        let (x, y) = to_pixel(p);
        picture.set(x, y, colour);
    }
}

/// Luminance share of each light as text, for logs.
pub fn describe(decomposition: &Decomposition) -> String {
    let total = luminance(decomposition.total_power);
    decomposition
        .lights
        .iter()
        .map(|l| format!("{:.1}%", 100.0 * luminance(l.power) / total))
        .collect::<Vec<_>>()
        .join(", ")
}
