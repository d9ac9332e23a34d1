//! Lights followed from frame to frame of a changing environment, so that no shadow appears or
//! vanishes in one frame:
//!
//! - **matching**: each tracked light takes the nearest light of the new frame's decomposition
//!   (within an angle), with its new direction and power: no lag;
//! - **hysteresis** on the Weber cut-off: a new light enters when it passes the threshold
//!   `t`; a tracked light stays while it passes `leave_fraction · t` (the decomposition is made
//!   at that lower threshold);
//! - **fades**: a light entering or leaving is faded over a few frames by moving its energy
//!   between the light and the SH part (as a delta function of the same power), so SH part plus
//!   lights integrate to the same total in every frame, and in consistent mode to the map.

use crate::decompose::weber::weber_elbow;
use crate::decompose::{DecomposeSettings, Decomposition, MAX_CANDIDATES};
use crate::light::DirectionalLight;
use foundation::Rgb;
use foundation::luminance;
use foundation::sh::ShCoeffs;

/// How lights are followed.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TrackingSettings {
    /// A tracked light leaves when it no longer passes this fraction of the Weber threshold.
    pub leave_fraction: f32,
    /// Frames over which a light fades in or out.
    pub fade_frames: u32,
    /// Largest angle between a light and its match in the next frame, degrees.
    pub match_deg: f32,
}

impl TrackingSettings {
    /// What the decomposer extracts under tracking: lights down to the leaving threshold,
    /// and up to twice as many, so that tracked lights stay found; the tracker decides which
    /// enter and keeps at most `max_lights`.
    pub(crate) fn decomposer_settings(&self, settings: &DecomposeSettings) -> DecomposeSettings {
        DecomposeSettings {
            threshold: settings.threshold * self.leave_fraction,
            max_lights: (2 * settings.max_lights).min(MAX_CANDIDATES),
            ..settings.clone()
        }
    }
}

impl Default for TrackingSettings {
    fn default() -> Self {
        Self {
            leave_fraction: 0.5,
            fade_frames: 6,
            match_deg: 15.0,
        }
    }
}

/// A light of a tracked frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TrackedLight {
    /// Stable across frames while the light is tracked.
    pub id: u32,
    /// Its full power (the light emits `weight` of it; the rest is in the SH part).
    pub light: DirectionalLight,
    /// Emitted share of the power: below 1 while fading in or out.
    pub weight: f32,
    pub fading_out: bool,
}

/// Follows the lights of successive decompositions.
#[derive(Debug, Clone, Default)]
pub struct LightTracker {
    settings: TrackingSettings,
    tracks: Vec<TrackedLight>,
    next_id: u32,
    started: bool,
}

impl LightTracker {
    pub fn new(settings: TrackingSettings) -> Self {
        Self {
            settings,
            ..Default::default()
        }
    }

    pub fn settings(&self) -> TrackingSettings {
        self.settings
    }

    /// The lights of the last frame, strongest first.
    pub fn lights(&self) -> &[TrackedLight] {
        &self.tracks
    }

    /// Forgets every light (the next frame starts afresh, without fades).
    pub fn reset(&mut self) {
        self.tracks.clear();
        self.started = false;
    }

    /// The next frame: `decomposition` was made at the Weber threshold
    /// `threshold · leave_fraction`; `threshold` is the one lights must pass to enter, and no
    /// light enters while `max_lights` are tracked. Returns the frame's lighting: the emitted
    /// (tracked, possibly fading) lights and the SH part holding the rest of the energy.
    pub fn update(
        &mut self,
        decomposition: &Decomposition,
        threshold: f32,
        max_lights: usize,
    ) -> Decomposition {
        let lights = &decomposition.lights;
        let luminances: Vec<f32> = lights.iter().map(|l| luminance(l.power)).collect();
        let entering = weber_elbow(&luminances, threshold);
        let step = 1.0 / self.settings.fade_frames.max(1) as f32;
        let mut matching = self.match_tracks(lights, step);
        self.admit(&mut matching, lights, entering, max_lights, step);
        self.started = true;
        let sh = sh_with_unemitted(decomposition, &matching);
        let mut tracks = matching.tracks;
        tracks.sort_by(|a, b| {
            luminance(b.light.power * b.weight).total_cmp(&luminance(a.light.power * a.weight))
        });
        self.tracks = tracks;
        self.emitted(decomposition, sh)
    }

    /// Strongest tracks choose first: the nearest unclaimed light within the match angle.
    /// A matched track fades in further, an unmatched one fades out (and ends at weight 0).
    fn match_tracks(&mut self, lights: &[DirectionalLight], step: f32) -> Matching {
        let cos_match = self.settings.match_deg.to_radians().cos();
        self.tracks
            .sort_by(|a, b| luminance(b.light.power).total_cmp(&luminance(a.light.power)));
        let mut claimed = vec![false; lights.len()];
        let mut tracks = Vec::with_capacity(self.tracks.len() + lights.len());
        let mut owner: Vec<Option<usize>> = vec![None; lights.len()];
        for track in &self.tracks {
            let best = lights
                .iter()
                .enumerate()
                .filter(|(i, l)| {
                    !claimed[*i] && l.direction.dot(track.light.direction) >= cos_match
                })
                .max_by(|(_, a), (_, b)| {
                    a.direction
                        .dot(track.light.direction)
                        .total_cmp(&b.direction.dot(track.light.direction))
                });
            let mut next = *track;
            match best {
                Some((i, light)) => {
                    claimed[i] = true;
                    owner[i] = Some(tracks.len());
                    next.light = *light;
                    next.fading_out = false;
                    next.weight = (next.weight + step).min(1.0);
                }
                None => {
                    next.fading_out = true;
                    next.weight -= step;
                }
            }
            if next.weight > 0.0 {
                tracks.push(next);
            }
        }
        Matching {
            tracks,
            claimed,
            owner,
        }
    }

    /// New tracks for the unclaimed lights among the first `entering` (those passing the
    /// entering threshold), while fewer than `max_lights` stay.
    fn admit(
        &mut self,
        matching: &mut Matching,
        lights: &[DirectionalLight],
        entering: usize,
        max_lights: usize,
        step: f32,
    ) {
        for (i, light) in lights.iter().enumerate() {
            let staying = matching.tracks.iter().filter(|t| !t.fading_out).count();
            if matching.claimed[i] || i >= entering || staying >= max_lights {
                continue;
            }
            matching.owner[i] = Some(matching.tracks.len());
            matching.tracks.push(TrackedLight {
                id: self.next_id,
                light: *light,
                // The first frame shows its lights at once.
                weight: if self.started { step } else { 1.0 },
                fading_out: false,
            });
            self.next_id += 1;
        }
    }

    /// The frame's lighting: the tracks' emitted lights, each with its share of the total.
    fn emitted(&self, decomposition: &Decomposition, sh: ShCoeffs<Rgb>) -> Decomposition {
        let total = luminance(decomposition.total_power).max(f32::MIN_POSITIVE);
        Decomposition {
            sh,
            lights: self
                .tracks
                .iter()
                .map(|t| {
                    let power = t.light.power * t.weight;
                    DirectionalLight {
                        power,
                        share: luminance(power) / total,
                        ..t.light
                    }
                })
                .collect(),
            total_power: decomposition.total_power,
            candidates: decomposition.candidates,
        }
    }
}

/// A frame's tracks while they are matched to its lights.
struct Matching {
    tracks: Vec<TrackedLight>,
    /// Per light of the frame, whether a track matched it.
    claimed: Vec<bool>,
    /// Per light of the frame, the index in `tracks` of the track that emits it.
    owner: Vec<Option<usize>>,
}

/// The SH part with the energy no light emits: what a light does not emit goes to it (or, for
/// a light fading out of a frame that no longer holds it, comes from it).
fn sh_with_unemitted(decomposition: &Decomposition, matching: &Matching) -> ShCoeffs<Rgb> {
    let mut sh = decomposition.sh.clone();
    for (i, light) in decomposition.lights.iter().enumerate() {
        let emitted = matching.owner[i].map_or(0.0, |t| matching.tracks[t].weight);
        sh.add_delta(light.direction, light.power * (1.0 - emitted));
    }
    for track in matching.tracks.iter().filter(|t| t.fading_out) {
        sh.add_delta(track.light.direction, track.light.power * -track.weight);
    }
    sh
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::Rgb;
    use foundation::sh::ShCoeffs;
    use glam::Vec3;
    use std::f32::consts::PI;

    fn light(direction: Vec3, power: f32) -> DirectionalLight {
        DirectionalLight {
            direction: direction.normalize(),
            power: Rgb::splat(power),
            cap_radius: 0.14,
            angular_radius: 0.01,
            halo_radius: 0.01,
            core_fraction: 1.0,
            share: 0.0,
        }
    }

    /// A consistent decomposition of a total of 10: the SH part holds what the lights do not.
    fn frame(lights: Vec<DirectionalLight>) -> Decomposition {
        let mut sh = ShCoeffs::zeros(3);
        let rest = 10.0 - luminance(lights_power(&lights));
        sh.as_mut_slice()[0] = Rgb::splat(rest / (4.0 * PI).sqrt());
        Decomposition {
            sh,
            lights,
            total_power: Rgb::splat(10.0),
            candidates: 0,
        }
    }

    fn lights_power(lights: &[DirectionalLight]) -> Rgb {
        lights.iter().map(|l| l.power).sum()
    }

    fn total(d: &Decomposition) -> f32 {
        luminance(d.total())
    }

    #[test]
    fn a_light_appearing_fades_in_and_energy_is_kept_in_every_frame() {
        let mut tracker = LightTracker::new(TrackingSettings::default());
        let sun = light(Vec3::Y, 4.0);
        let first = tracker.update(&frame(vec![sun]), 0.05, 8);
        assert_eq!(first.lights.len(), 1);
        assert_eq!(
            first.lights[0].power, sun.power,
            "the first frame shows its lights at once"
        );
        let lamp = light(Vec3::X, 2.0);
        let mut emitted = Vec::new();
        for _ in 0..8 {
            let d = tracker.update(&frame(vec![sun, lamp]), 0.05, 8);
            assert!((total(&d) - 10.0).abs() < 1e-4, "{}", total(&d));
            emitted.push(d.lights.iter().map(|l| luminance(l.power)).sum::<f32>());
        }
        // 4 + 2/6, 4 + 4/6, ... then 6: no jump of the lamp's full power in one frame.
        for pair in emitted.windows(2) {
            assert!(pair[1] - pair[0] <= 2.0 / 6.0 + 1e-4, "{emitted:?}");
        }
        assert!((emitted[7] - 6.0).abs() < 1e-4);
        assert_eq!(tracker.lights().len(), 2);
    }

    #[test]
    fn a_light_vanishing_fades_out_keeping_the_total() {
        let mut tracker = LightTracker::new(TrackingSettings::default());
        let sun = light(Vec3::Y, 4.0);
        let lamp = light(Vec3::X, 2.0);
        tracker.update(&frame(vec![sun, lamp]), 0.05, 8);
        let mut emitted = Vec::new();
        for _ in 0..7 {
            let d = tracker.update(&frame(vec![sun]), 0.05, 8);
            assert!((total(&d) - 10.0).abs() < 1e-4);
            emitted.push(d.lights.iter().map(|l| luminance(l.power)).sum::<f32>());
        }
        assert!(
            (emitted[0] - (4.0 + 2.0 * 5.0 / 6.0)).abs() < 1e-4,
            "{emitted:?}"
        );
        assert!((emitted[6] - 4.0).abs() < 1e-4);
        assert_eq!(tracker.lights().len(), 1);
    }

    /// A light whose Weber share flickers around the threshold stays once it is in.
    #[test]
    fn hysteresis_keeps_a_light_near_the_threshold() {
        let mut tracker = LightTracker::new(TrackingSettings::default());
        let sun = light(Vec3::Y, 10.0);
        // 0.7 / 10.7 = 6.5% passes 5%; 0.4 / 10.4 = 3.8% does not, but passes 2.5%.
        let strong = light(Vec3::Z, 0.7);
        let weak = light(Vec3::Z, 0.4);
        tracker.update(&frame(vec![sun, strong]), 0.05, 8);
        for k in 0..20 {
            let other = if k % 2 == 0 { weak } else { strong };
            let d = tracker.update(&frame(vec![sun, other]), 0.05, 8);
            assert_eq!(d.lights.len(), 2, "frame {k}");
            assert_eq!(d.lights[1].power, other.power);
        }
        // A new light as weak as that does not enter.
        let d = tracker.update(&frame(vec![sun, strong, light(Vec3::NEG_X, 0.4)]), 0.05, 8);
        assert_eq!(d.lights.len(), 2);
        assert!((total(&d) - 10.0).abs() < 1e-4);
    }

    /// A moving light keeps its identity and follows the map without lag.
    #[test]
    fn a_moving_light_is_followed_at_once() {
        let mut tracker = LightTracker::new(TrackingSettings::default());
        let mut id = None;
        for k in 0..30 {
            let angle = (k as f32 * 3.0).to_radians();
            let sun = light(Vec3::new(angle.sin(), 0.5, angle.cos()), 5.0);
            let d = tracker.update(&frame(vec![sun]), 0.05, 8);
            assert_eq!(d.lights[0].direction, sun.direction);
            assert_eq!(d.lights[0].power, sun.power);
            let this = tracker.lights()[0].id;
            assert_eq!(*id.get_or_insert(this), this);
        }
    }
}
