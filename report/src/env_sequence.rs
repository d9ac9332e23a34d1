//! Environment sequences (`--env-sequence`): maps that change from frame to frame. The format
//! is described in `scenes/README.md`, "Environment sequences": a folder of maps (frames in
//! file-name order), or a TOML file naming the frames, a folder, a cross-fade between two maps
//! or a sun moving over a base map.

use foundation::envmap::EnvMap;
use foundation::envmap::animated::{SunArc, SunDisc, crossfade, direction_of};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use thiserror::Error;

type Result<T, E = SequenceError> = std::result::Result<T, E>;

/// What is wrong with a sequence, naming its file.
#[derive(Debug, Error)]
pub enum SequenceError {
    #[error("cannot read the sequence {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: foundation::infra::limits::ReadError,
    },
    #[error("{}: not a valid sequence file", path.display())]
    Parse {
        path: PathBuf,
        #[source]
        source: toml::de::Error,
    },
    #[error("{}: give exactly one of `frames`, `folder`, [crossfade] or [sun]", .0.display())]
    NotOneSource(PathBuf),
    #[error("{}: a sequence has 1 to {MAX_FRAMES} frames, this one {count}", path.display())]
    FrameCount { path: PathBuf, count: usize },
    #[error("frame {frame} is past the sequence's last frame ({last})")]
    PastLastFrame { frame: usize, last: usize },
    #[error("--frame {frame}: the sequence has frames 0 to {last}")]
    FrameOption { frame: usize, last: usize },
    #[error(
        "{}: line {line}: angular_radius_deg must be in [{MIN_SUN_RADIUS_DEG}, 45], got {radius}",
        path.display()
    )]
    SunRadius {
        path: PathBuf,
        line: usize,
        radius: f32,
    },
    #[error(
        "{}: line {line}: the sun's power {power:?} must be finite, not negative and at most \
         {MAX_SUN_POWER:e} per channel",
        path.display()
    )]
    SunPower {
        path: PathBuf,
        line: usize,
        power: [f32; 3],
    },
    #[error("{}: the sun's from and to angles must be finite", .0.display())]
    SunAngles(PathBuf),
    /// (The map's error in the message, as the header reader words it.)
    #[error("frame {frame} of the sequence cannot be read: {error}")]
    UnreadableFrame {
        frame: usize,
        error: foundation::envmap::EnvMapError,
    },
    #[error("cannot read the folder {}", path.display())]
    Folder {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: no .exr or .hdr maps in the folder", .0.display())]
    NoMaps(PathBuf),
    /// A frame's map, or a map a sequence file names, that cannot be loaded.
    #[error("cannot load the environment map")]
    Map(#[from] foundation::envmap::EnvMapError),
    #[error(transparent)]
    Decompose(#[from] runtime::DecomposeError),
}

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
    pub fn load(path: &Path) -> Result<Self> {
        let sequence = if path.is_dir() {
            Self::Files(maps_in(path)?)
        } else {
            Self::from_file(path)?
        };
        if let Self::Files(paths) = &sequence {
            check_frames(paths)?;
        }
        if !(1..=MAX_FRAMES).contains(&sequence.len()) {
            return Err(SequenceError::FrameCount {
                path: path.to_owned(),
                count: sequence.len(),
            });
        }
        Ok(sequence)
    }

    fn from_file(path: &Path) -> Result<Self> {
        let text = foundation::infra::limits::read_text_file(path).map_err(|source| {
            SequenceError::Read {
                path: path.to_owned(),
                source,
            }
        })?;
        let spec: SequenceFile = toml::from_str(&text).map_err(|source| SequenceError::Parse {
            path: path.to_owned(),
            source,
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let resolve = |p: &Path| dir.join(p);
        let given = [
            spec.frames.is_some(),
            spec.folder.is_some(),
            spec.crossfade.is_some(),
            spec.sun.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(SequenceError::NotOneSource(path.to_owned()));
        }
        if let Some(frames) = spec.frames {
            return Ok(Self::Files(frames.iter().map(|p| resolve(p)).collect()));
        }
        if let Some(folder) = spec.folder {
            return Ok(Self::Files(maps_in(&resolve(&folder))?));
        }
        if let Some(c) = spec.crossfade {
            return Ok(Self::CrossFade {
                from: foundation::envmap::load(&resolve(&c.from), None)?.map,
                to: foundation::envmap::load(&resolve(&c.to), None)?.map,
                frames: c.frames,
            });
        }
        let s = spec.sun.expect("one of the four is given");
        check_sun(path, &text, &s)?;
        Ok(Self::Sun {
            base: foundation::envmap::load(&resolve(&s.base), None)?.map,
            arc: SunArc {
                from: direction_of(s.from[0], s.from[1]),
                to: direction_of(s.to[0], s.to[1]),
                angular_radius: s.angular_radius_deg.get_ref().to_radians(),
                power: glam::Vec3::from_array(*s.power.get_ref()),
            },
            frames: s.frames,
        })
    }

    // A sequence has at least one frame (`load` refuses none), so no `is_empty`.
    #[allow(clippy::len_without_is_empty)]
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
    pub fn frame(&self, k: usize) -> Result<EnvMap> {
        if k >= self.len() {
            let last = self.len().saturating_sub(1);
            return Err(SequenceError::PastLastFrame { frame: k, last });
        }
        Ok(match self {
            Self::Files(paths) => foundation::envmap::load(&paths[k], None)?.map,
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
) -> Result<runtime::EnvironmentLighting> {
    if last >= sequence.len() {
        let frame = last;
        let last = sequence.len().saturating_sub(1);
        return Err(SequenceError::FrameOption { frame, last });
    }
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
fn check_sun(path: &Path, text: &str, s: &SunSpec) -> Result<(), SequenceError> {
    let line =
        |span: std::ops::Range<usize>| text[..span.start.min(text.len())].lines().count().max(1);
    let radius = *s.angular_radius_deg.get_ref();
    if !(MIN_SUN_RADIUS_DEG..=45.0).contains(&radius) {
        return Err(SequenceError::SunRadius {
            path: path.to_owned(),
            line: line(s.angular_radius_deg.span()),
            radius,
        });
    }
    let power = *s.power.get_ref();
    if !(power.iter()).all(|p| p.is_finite() && (0.0..=MAX_SUN_POWER).contains(p)) {
        return Err(SequenceError::SunPower {
            path: path.to_owned(),
            line: line(s.power.span()),
            power,
        });
    }
    if !s.from.iter().chain(&s.to).all(|a| a.is_finite()) {
        return Err(SequenceError::SunAngles(path.to_owned()));
    }
    Ok(())
}

/// Checks that every frame file is there and readable as a map header, before any frame is
/// rendered (a missing last frame must not cost the whole sequence's work first).
fn check_frames(paths: &[PathBuf]) -> Result<(), SequenceError> {
    for (frame, path) in paths.iter().enumerate() {
        foundation::envmap::read_size(path)
            .map_err(|error| SequenceError::UnreadableFrame { frame, error })?;
    }
    Ok(())
}

fn maps_in(folder: &Path) -> Result<Vec<PathBuf>, SequenceError> {
    let mut maps: Vec<PathBuf> = std::fs::read_dir(folder)
        .map_err(|source| SequenceError::Folder {
            path: folder.to_owned(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "exr" || x == "hdr"))
        .collect();
    maps.sort();
    if maps.is_empty() {
        return Err(SequenceError::NoMaps(folder.to_owned()));
    }
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
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/env/sunrise.exr");
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
