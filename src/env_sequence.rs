//! Environment sequences (`--env-sequence`): maps that change from frame to frame. The format
//! is described in `scenes/README.md`, "Environment sequences": a folder of maps (frames in
//! file-name order), or a TOML file naming the frames, a folder, a cross-fade between two maps
//! or a sun moving over a base map.

use crate::maps::load_map;
use anyhow::Context;
use foundation::envmap::EnvMap;
use foundation::envmap::animated::{SunArc, SunDisc, crossfade, direction_of};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Most frames a sequence may have.
pub const MAX_FRAMES: usize = 10_000;

/// The sequence file (TOML): exactly one of its fields.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SequenceFile {
    frames: Option<Vec<PathBuf>>,
    folder: Option<PathBuf>,
    crossfade: Option<CrossFadeSpec>,
    sun: Option<SunSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CrossFadeSpec {
    from: PathBuf,
    to: PathBuf,
    frames: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SunSpec {
    base: PathBuf,
    frames: usize,
    /// `[azimuth, elevation]` in degrees at the first frame.
    from: [f32; 2],
    /// ... and at the last.
    to: [f32; 2],
    angular_radius_deg: toml::Spanned<f32>,
    /// `∫ L dω` of the disc above the base map, RGB.
    power: toml::Spanned<[f32; 3]>,
}

/// Smallest angular radius of a sequence's sun: below it the disc falls between the texels of
/// any map (a texel of an 8192-wide map spans 0.044°) and its radiance overflows.
const MIN_SUN_RADIUS_DEG: f32 = 0.01;
/// Largest power per channel of a sequence's sun: the real sun's is about 1e5 in the units of
/// a map whose sky is near 1; a thousand times more still leaves room in single precision.
const MAX_SUN_POWER: f32 = 1e8;

/// Where a sequence's frames come from.
pub enum Sequence {
    Files(Vec<PathBuf>),
    CrossFade {
        from: EnvMap,
        to: EnvMap,
        frames: usize,
    },
    Sun {
        base: EnvMap,
        arc: SunArc,
        frames: usize,
    },
}

impl Sequence {
    /// A folder of maps, or a sequence file.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let sequence = if path.is_dir() {
            Self::Files(maps_in(path)?)
        } else {
            Self::from_file(path)?
        };
        if let Self::Files(paths) = &sequence {
            check_frames(paths)?;
        }
        anyhow::ensure!(
            (1..=MAX_FRAMES).contains(&sequence.len()),
            "{}: a sequence has 1 to {MAX_FRAMES} frames, this one {}",
            path.display(),
            sequence.len()
        );
        Ok(sequence)
    }

    fn from_file(path: &Path) -> anyhow::Result<Self> {
        let text = foundation::infra::limits::read_text_file(path)
            .with_context(|| format!("cannot read the sequence {}", path.display()))?;
        let spec: SequenceFile = toml::from_str(&text)
            .with_context(|| format!("{}: not a valid sequence file", path.display()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let resolve = |p: &Path| dir.join(p);
        let given = [
            spec.frames.is_some(),
            spec.folder.is_some(),
            spec.crossfade.is_some(),
            spec.sun.is_some(),
        ];
        anyhow::ensure!(
            given.iter().filter(|g| **g).count() == 1,
            "{}: give exactly one of `frames`, `folder`, [crossfade] or [sun]",
            path.display()
        );
        if let Some(frames) = spec.frames {
            return Ok(Self::Files(frames.iter().map(|p| resolve(p)).collect()));
        }
        if let Some(folder) = spec.folder {
            return Ok(Self::Files(maps_in(&resolve(&folder))?));
        }
        if let Some(c) = spec.crossfade {
            return Ok(Self::CrossFade {
                from: load_map(&resolve(&c.from), None)?.map,
                to: load_map(&resolve(&c.to), None)?.map,
                frames: c.frames,
            });
        }
        let s = spec.sun.expect("one of the four is given");
        check_sun(path, &text, &s)?;
        Ok(Self::Sun {
            base: load_map(&resolve(&s.base), None)?.map,
            arc: SunArc {
                from: direction_of(s.from[0], s.from[1]),
                to: direction_of(s.to[0], s.to[1]),
                angular_radius: s.angular_radius_deg.get_ref().to_radians(),
                power: glam::Vec3::from_array(*s.power.get_ref()),
            },
            frames: s.frames,
        })
    }

    pub fn len(&self) -> usize {
        match self {
            Self::Files(paths) => paths.len(),
            Self::CrossFade { frames, .. } | Self::Sun { frames, .. } => *frames,
        }
    }

    /// Where frame `k` lies in `[0, 1]`.
    fn time(&self, k: usize) -> f32 {
        k as f32 / (self.len().max(2) - 1) as f32
    }

    /// The map of frame `k`.
    pub fn frame(&self, k: usize) -> anyhow::Result<EnvMap> {
        anyhow::ensure!(
            k < self.len(),
            "frame {k} is past the sequence's last frame ({})",
            self.len() - 1
        );
        Ok(match self {
            Self::Files(paths) => load_map(&paths[k], None)?.map,
            Self::CrossFade { from, to, .. } => crossfade(from, to, self.time(k)),
            Self::Sun { base, arc, .. } => arc.at(self.time(k)).over(base),
        })
    }

    /// The map the sun moves over, for a sun sequence.
    pub fn sun_base(&self) -> Option<&EnvMap> {
        match self {
            Self::Sun { base, .. } => Some(base),
            _ => None,
        }
    }

    /// The sun of frame `k`, for a sun sequence (the truth its light is measured against).
    pub fn sun(&self, k: usize) -> Option<SunDisc> {
        match self {
            Self::Sun { arc, .. } => Some(arc.at(self.time(k))),
            _ => None,
        }
    }
}

/// The lighting of `sequence` at frame `last`, its lights tracked from the first frame (the
/// state of a viewer or a report that played the sequence up to there).
pub fn lighting_at_frame(
    sequence: &Sequence,
    settings: runtime::DecomposeSettings,
    rotation_deg: f32,
    last: usize,
) -> anyhow::Result<runtime::EnvironmentLighting> {
    anyhow::ensure!(
        last < sequence.len(),
        "--frame {last}: the sequence has frames 0 to {}",
        sequence.len() - 1
    );
    let mut lighting = runtime::EnvironmentLighting::new(&sequence.frame(0)?, settings)?;
    lighting.enable_tracking(Some(runtime::TrackingSettings::default()))?;
    lighting.set_rotation(rotation_deg);
    for k in 0..=last {
        if k > 0 {
            lighting.set_map(sequence.frame(k)?);
        }
        lighting.decompose();
    }
    Ok(lighting)
}

/// The `.exr` and `.hdr` files of `folder`, sorted by name.
/// Refuses a sun whose radius or power is out of range, naming the file and line.
fn check_sun(path: &Path, text: &str, s: &SunSpec) -> anyhow::Result<()> {
    let line =
        |span: std::ops::Range<usize>| text[..span.start.min(text.len())].lines().count().max(1);
    let radius = *s.angular_radius_deg.get_ref();
    anyhow::ensure!(
        (MIN_SUN_RADIUS_DEG..=45.0).contains(&radius),
        "{}: line {}: angular_radius_deg must be in [{MIN_SUN_RADIUS_DEG}, 45], got {radius}",
        path.display(),
        line(s.angular_radius_deg.span())
    );
    let power = *s.power.get_ref();
    anyhow::ensure!(
        power
            .iter()
            .all(|p| p.is_finite() && (0.0..=MAX_SUN_POWER).contains(p)),
        "{}: line {}: the sun's power {power:?} must be finite, not negative and at most \
         {MAX_SUN_POWER:e} per channel",
        path.display(),
        line(s.power.span())
    );
    anyhow::ensure!(
        s.from.iter().chain(&s.to).all(|a| a.is_finite()),
        "{}: the sun's from and to angles must be finite",
        path.display()
    );
    Ok(())
}

/// Checks that every frame file is there and readable as a map header, before any frame is
/// rendered (a missing last frame must not cost the whole sequence's work first).
fn check_frames(paths: &[PathBuf]) -> anyhow::Result<()> {
    for (k, path) in paths.iter().enumerate() {
        foundation::envmap::read_size(path)
            .map_err(|e| anyhow::anyhow!("frame {k} of the sequence cannot be read: {e}"))?;
    }
    Ok(())
}

fn maps_in(folder: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut maps: Vec<PathBuf> = std::fs::read_dir(folder)
        .with_context(|| format!("cannot read the folder {}", folder.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "exr" || x == "hdr"))
        .collect();
    maps.sort();
    anyhow::ensure!(
        !maps.is_empty(),
        "{}: no .exr or .hdr maps in the folder",
        folder.display()
    );
    Ok(maps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sequence_files_name_exactly_one_source() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/env/sunrise.exr");
        let sun = write(
            "sun.toml",
            &format!(
                "[sun]\nbase = {:?}\nframes = 5\nfrom = [0, 10]\nto = [40, 30]\n\
                 angular_radius_deg = 1.0\npower = [2, 2, 2]\n",
                base
            ),
        );
        let s = Sequence::load(&sun).unwrap();
        assert_eq!(s.len(), 5);
        let last = s.sun(4).unwrap().direction;
        assert!(last.dot(direction_of(40.0, 30.0)) > 0.9999);
        assert!(s.frame(5).is_err());
        let both = write(
            "both.toml",
            &format!("frames = [{base:?}]\nfolder = \".\"\n"),
        );
        let message = format!("{:#}", Sequence::load(&both).err().unwrap());
        assert!(message.contains("exactly one"), "{message}");
        let typo = write("typo.toml", "frame = []\n");
        assert!(Sequence::load(&typo).is_err());
        let empty = tempfile::tempdir().unwrap();
        let message = format!("{:#}", Sequence::load(empty.path()).err().unwrap());
        assert!(message.contains("no .exr or .hdr"), "{message}");
    }
}
