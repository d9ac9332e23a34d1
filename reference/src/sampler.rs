//! The reference's random numbers: where each light path gets its 2D samples.
//!
//! Two samplers, chosen by [`SamplerKind`]: independent numbers from each pixel's PCG stream,
//! and Owen-scrambled Sobol points (Burley 2020, the `sobol_burley` crate), scrambled per pixel
//! so that pixels' errors stay independent. Sobol points stratify each path's first
//! dimensions, which is where a direct-lighting-heavy reference spends its variance. Both are
//! deterministic functions of the seed, the pixel and the sample index: the image does not
//! depend on the number of threads, and samples `[a, b)` rendered later continue `[0, a)`.

use foundation::sampling::mix64;
use glam::Vec2;
use rand_core::Rng;
use rand_pcg::Pcg32;

foundation::named_enum! {
    /// Which numbers drive the reference's light paths.
    #[derive(Default, serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum SamplerKind ("sampler") {
        /// Owen-scrambled Sobol points, scrambled per pixel (the default).
        #[default]
        Sobol = "sobol",
        /// Independent uniform numbers from a PCG32 stream per pixel.
        Independent = "independent",
    }
}

/// The most samples per pixel a Sobol reference can take (`sobol_burley`'s sequence length).
pub const MAX_SOBOL_SAMPLES: u32 = 1 << 16;

/// A source of 2D sample points for one light path.
pub trait PathSampler {
    fn next_2d(&mut self) -> Vec2;
}

/// Independent numbers: any PCG stream (the bake-vs-reference checks use one per vertex).
impl PathSampler for Pcg32 {
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let scale = 1.0 / (1u32 << 24) as f32;
        Vec2::new(
            (self.next_u32() >> 8) as f32 * scale,
            (self.next_u32() >> 8) as f32 * scale,
        )
    }
}

/// Sample `index` of one pixel's Owen-scrambled Sobol sequence. Dimensions come in sets of
/// four (`sobol_burley::sample_4d`), each set scrambled with its own seed (Burley's padding),
/// so a path of any length has fresh, stratified dimensions.
pub struct SobolSampler {
    index: u32,
    pixel_seed: u64,
    set: u32,
    cached: [f32; 4],
    used: usize,
}

impl SobolSampler {
    pub fn new(pixel_seed: u64, index: u32) -> Self {
        Self {
            index,
            pixel_seed,
            set: 0,
            cached: [0.0; 4],
            used: 4,
        }
    }
}

impl PathSampler for SobolSampler {
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        if self.used == 4 {
            let seed =
                mix64(self.pixel_seed ^ u64::from(self.set).wrapping_mul(0x9e37_79b9)) as u32;
            self.cached = sobol_burley::sample_4d(self.index, 0, seed);
            self.set += 1;
            self.used = 0;
        }
        let v = Vec2::new(self.cached[self.used], self.cached[self.used + 1]);
        self.used += 2;
        v
    }
}

/// The sampler of sample `index` of pixel `pixel`, for a reference seeded with `seed`.
pub enum PixelSampler {
    Sobol(SobolSampler),
    Independent(Pcg32),
}

impl PixelSampler {
    /// The PCG variant is one stream per pixel and range of samples: `first` (the first sample
    /// of a rendering pass) picks the stream, so a pass that continues another draws new
    /// numbers.
    pub(crate) fn for_pass(kind: SamplerKind, seed: u64, pixel: u64, first: u32) -> Self {
        match kind {
            SamplerKind::Sobol => Self::Sobol(SobolSampler::new(mix64(seed ^ mix64(pixel)), first)),
            SamplerKind::Independent => {
                let stream_seed = if first == 0 {
                    seed
                } else {
                    mix64(seed ^ mix64(u64::from(first) << 32))
                };
                Self::Independent(super::stream(stream_seed, pixel))
            }
        }
    }

    /// Moves on to the next sample of the pixel.
    #[inline]
    pub(crate) fn next_sample(&mut self) {
        if let Self::Sobol(s) = self {
            *s = SobolSampler::new(s.pixel_seed, s.index + 1);
        }
    }
}

impl PathSampler for PixelSampler {
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        match self {
            Self::Sobol(s) => s.next_2d(),
            Self::Independent(r) => r.next_2d(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sobol points are stratified: 256 of them put exactly one point in each cell of a 16 × 16
    /// grid over their first two dimensions, and exactly 16 in each column of a 16-cell split
    /// of every later pair; independent numbers do not.
    #[test]
    fn sobol_points_stratify_every_pair_of_dimensions() {
        for pixel in [0u64, 7, 12345] {
            let mut cells = vec![vec![0u32; 256]; 4];
            for i in 0..256 {
                let mut s = SobolSampler::new(mix64(pixel), i);
                for pair in cells.iter_mut() {
                    let p = s.next_2d();
                    assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                    pair[(p.y * 16.0) as usize * 16 + (p.x * 16.0) as usize] += 1;
                }
            }
            assert!(
                cells[0].iter().all(|c| *c == 1),
                "pixel {pixel}: {:?}",
                cells[0]
            );
            for pair in &cells[1..] {
                for column in 0..16 {
                    let n: u32 = (0..16).map(|row| pair[row * 16 + column]).sum();
                    assert_eq!(n, 16);
                }
            }
        }
        let mut rng = super::super::stream(0, 0);
        let mut cells = vec![0u32; 256];
        for _ in 0..256 {
            let p = rng.next_2d();
            cells[(p.y * 16.0) as usize * 16 + (p.x * 16.0) as usize] += 1;
        }
        assert!(cells.iter().any(|c| *c != 1));
    }

    /// Each pixel gets its own scramble: two pixels' sequences differ everywhere.
    #[test]
    fn pixels_get_independent_scrambles() {
        let a: Vec<Vec2> = (0..16).map(|i| SobolSampler::new(1, i).next_2d()).collect();
        let b: Vec<Vec2> = (0..16).map(|i| SobolSampler::new(2, i).next_2d()).collect();
        assert!(a.iter().zip(&b).all(|(a, b)| a != b));
    }

    #[test]
    fn sampler_names_parse() {
        assert_eq!("sobol".parse::<SamplerKind>(), Ok(SamplerKind::Sobol));
        assert_eq!(SamplerKind::default(), SamplerKind::Sobol);
        assert!("halton".parse::<SamplerKind>().is_err());
    }
}
