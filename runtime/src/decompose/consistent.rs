//! The energy-consistent mode's lights ([`super::DecomposeMode::Consistent`]): each light
//! carries the excess of the map over the SH part in its cap, and the SH part is refitted to
//! what the lights leave (a few fixed-point steps).

use super::{CONSISTENT_ITERATIONS, Decomposer};
use crate::cubemap::CubeMap;
use crate::light::DirectionalLight;
use foundation::sh::ShCoeffs;
use foundation::{Rgb, luminance};
use glam::Vec3;

impl Decomposer {
    /// What `map` holds around `centres` as the consistent mode measures a light: the excess
    /// of the map over the refitted SH part in each centre's cap (texels shared by caps go to
    /// the nearest centre). Measures a map's own "local level" where another map has a light.
    pub fn cap_excess(&mut self, map: &CubeMap, centres: &[Vec3]) -> Vec<Rgb> {
        assert_eq!(
            map.size(),
            self.settings.face_size,
            "cube map of the wrong size"
        );
        self.prepare_analysis(map);
        let full = self.project_analysis(map);
        self.caps_used = 0;
        self.cap_powers(map, &full, centres, CONSISTENT_ITERATIONS)
    }

    /// The power of the excess in each of `centres`' caps after `iterations` refits ([`Self::
    /// extract`]'s lights' powers, without their directions and sizes).
    fn cap_powers(
        &mut self,
        map: &CubeMap,
        full: &ShCoeffs<Rgb>,
        centres: &[Vec3],
        iterations: usize,
    ) -> Vec<Rgb> {
        let radius = self.settings.radius_deg.to_radians();
        let members = self.cap_members(centres, radius);
        let (_, excess) = self.refit(map, full, &members, iterations, (false, false));
        let mut power = vec![Rgb::ZERO; centres.len()];
        for (e, &t) in excess.iter().zip(&members) {
            let i = self.owner[t as usize].0 as usize;
            power[i] += *e * self.geometry.solid_angles()[t as usize];
        }
        for &t in &members {
            self.owner[t as usize] = (u16::MAX, 0.0);
        }
        power
    }

    /// Consistent: lights carry the map's excess over the SH part in their caps; the SH part is
    /// the projection of what remains.
    pub(super) fn consistent_lights(
        &mut self,
        map: &CubeMap,
        full: &ShCoeffs<Rgb>,
        centres: &[Vec3],
    ) -> (ShCoeffs<Rgb>, Vec<DirectionalLight>) {
        // One refit step is enough to rank the candidates.
        let trial: Vec<f32> = self
            .cap_powers(map, full, centres, 1)
            .iter()
            .map(|p| luminance(*p))
            .collect();
        let mut order: Vec<usize> = (0..trial.len()).filter(|&i| trial[i] > 0.0).collect();
        order.sort_by(|a, b| trial[*b].total_cmp(&trial[*a]));
        let luminances: Vec<f32> = order.iter().map(|&i| trial[i]).collect();
        let kept: Vec<Vec3> = order[..self.keep_count(&luminances)]
            .iter()
            .map(|&i| centres[i])
            .collect();
        let (mut sh, mut lights) = self.extract(map, full, &kept, CONSISTENT_ITERATIONS);
        sh.scale_bands(&self.sh_window);
        lights.retain(|l| luminance(l.power) > 0.0);
        lights.sort_by(|a, b| luminance(b.power).total_cmp(&luminance(a.power)));
        (sh, lights)
    }

    /// The texels within `radius` of any of `centres`, each once, in the order found; each
    /// texel's nearest centre is left in `owner` (the caller resets it).
    fn cap_members(&mut self, centres: &[Vec3], radius: f32) -> Vec<u32> {
        let mut members: Vec<u32> = Vec::new();
        for (i, c) in centres.iter().enumerate() {
            // The ranking and the extraction ask for the same caps: each is found once.
            let used = &self.caps[..self.caps_used];
            let k = match used.iter().position(|(d, r, _)| d == c && *r == radius) {
                Some(k) => k,
                None => {
                    if self.caps_used == self.caps.len() {
                        self.caps.push((*c, radius, Vec::new()));
                    }
                    let cap = &mut self.caps[self.caps_used];
                    (cap.0, cap.1) = (*c, radius);
                    self.geometry.texels_within(*c, radius, &mut cap.2);
                    self.caps_used += 1;
                    self.caps_used - 1
                }
            };
            let cap = &self.caps[k].2;
            for &t in cap {
                let cos = self.geometry.directions()[t as usize].dot(*c);
                let slot = &mut self.owner[t as usize];
                if slot.0 == u16::MAX {
                    members.push(t);
                    *slot = (i as u16, cos);
                } else if cos > slot.1 {
                    *slot = (i as u16, cos);
                }
            }
        }
        members
    }

    /// The excess at each of `members` after `iterations` refits of the SH part, and that part
    /// refitted to the last excess when `keep_sh` (else `full`). The first step evaluates `full`
    /// at the members, or, when `full_known`, reads it from the last refit's (which covered
    /// these texels, of the same map).
    fn refit(
        &mut self,
        map: &CubeMap,
        full: &ShCoeffs<Rgb>,
        members: &[u32],
        iterations: usize,
        (keep_sh, full_known): (bool, bool),
    ) -> (ShCoeffs<Rgb>, Vec<Rgb>) {
        let texels = map.texels();
        // At the analysis resolution the projector has the basis at every texel already (folded
        // into one octant); otherwise it is evaluated at the members.
        let octant = if self.downsample.is_empty() {
            self.projector.octant()
        } else {
            None
        };
        if octant.is_none() {
            self.member_basis
                .set(members, &self.basis, self.geometry.directions());
        }
        let mut sh = full.clone();
        let mut excess: Vec<Rgb> = vec![Rgb::ZERO; members.len()];
        let (mut expansion, mut projected) = (Vec::new(), Vec::new());
        for step in 0..iterations {
            // P = SH(map) − SH(excess), P refitted to the map less the excess.
            if step == 0 && full_known {
                expansion.clear();
                expansion.extend(members.iter().map(|&t| self.full_at[t as usize]));
            } else {
                match octant {
                    Some(octant) => octant.eval_at(&sh, members, &mut expansion),
                    None => self.member_basis.eval_all(&sh, &mut expansion),
                }
                if step == 0 {
                    for (&t, p) in members.iter().zip(&expansion) {
                        self.full_at[t as usize] = *p;
                    }
                }
            }
            for ((e, &t), p) in excess.iter_mut().zip(members).zip(&expansion) {
                *e = (texels[t as usize] - *p).max(Rgb::ZERO);
            }
            if step + 1 == iterations && !keep_sh {
                break;
            }
            projected.clear();
            projected.extend(
                excess
                    .iter()
                    .zip(members)
                    .map(|(e, &t)| *e * self.geometry.solid_angles()[t as usize]),
            );
            sh = match octant {
                Some(octant) => octant.subtract(full, members, &projected),
                None => self.member_basis.subtract(full, &projected),
            };
        }
        (sh, excess)
    }

    /// For caps of radius R around `centres`: the excess `max(0, L − P)` of the map over the SH
    /// part `P`, where `P` is refitted to the map minus that excess (a few fixed-point steps).
    /// Texels in several caps belong to the nearest centre. Returns the final `P` and one light
    /// per centre.
    fn extract(
        &mut self,
        map: &CubeMap,
        full: &ShCoeffs<Rgb>,
        centres: &[Vec3],
        iterations: usize,
    ) -> (ShCoeffs<Rgb>, Vec<DirectionalLight>) {
        let radius = self.settings.radius_deg.to_radians();
        let members = self.cap_members(centres, radius);
        // The ranking before it refitted a superset of these caps.
        let (sh, excess) = self.refit(map, full, &members, iterations, (true, true));
        // Each light: power, luminance-weighted centroid and spread of its excess.
        let mut power = vec![Rgb::ZERO; centres.len()];
        let mut moment = vec![Vec3::ZERO; centres.len()];
        for (e, &t) in excess.iter().zip(&members) {
            let i = self.owner[t as usize].0 as usize;
            let d_omega = self.geometry.solid_angles()[t as usize];
            power[i] += *e * d_omega;
            moment[i] += self.geometry.directions()[t as usize] * (luminance(*e) * d_omega);
        }
        let directions: Vec<Vec3> = moment
            .iter()
            .zip(centres)
            .map(|(m, c)| m.try_normalize().unwrap_or(*c))
            .collect();
        let mut spread = vec![0.0f32; centres.len()];
        for (e, &t) in excess.iter().zip(&members) {
            let i = self.owner[t as usize].0 as usize;
            let theta = self.geometry.directions()[t as usize].angle_between(directions[i]);
            spread[i] += theta * theta * luminance(*e) * self.geometry.solid_angles()[t as usize];
        }
        for &t in &members {
            self.owner[t as usize] = (u16::MAX, 0.0);
        }
        let lights = (0..centres.len())
            .map(|i| {
                let lum = luminance(power[i]);
                // A uniform disc of radius ρ has E[θ²] = ρ²/2.
                let rho = if lum > 0.0 {
                    (2.0 * spread[i] / lum).sqrt()
                } else {
                    0.0
                }
                .clamp(0.25f32.to_radians(), radius);
                DirectionalLight {
                    direction: directions[i],
                    power: power[i],
                    cap_radius: radius,
                    angular_radius: rho,
                    halo_radius: rho,
                    core_fraction: 1.0,
                    share: 0.0,
                }
            })
            .collect();
        (sh, lights)
    }
}
