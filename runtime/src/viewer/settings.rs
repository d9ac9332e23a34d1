//! What a viewer's panel controls, how a script's `set NAME VALUE` changes it, and the
//! `hprt render` command line that reproduces what it shows.

use crate::render::{MAX_LIGHTS, RenderMode, ShadowSettings};
use crate::{DecomposeMode, DecomposeSettings, lights_indirect_default};
use foundation::Rgb;
use foundation::camera::Camera;
use foundation::infra::named_enum::UnknownName;
use foundation::material::{MAX_SHININESS, Material};
use std::path::{Path, PathBuf};

/// Why a `set NAME VALUE` was refused.
#[derive(Debug, thiserror::Error)]
pub enum SettingError {
    #[error("unknown setting {0:?}")]
    Unknown(String),
    #[error("{name}: `{value}` is not a finite number")]
    NotANumber { name: String, value: String },
    #[error("{name}: expected on or off, got {value:?}")]
    NotASwitch { name: String, value: String },
    #[error("{name}: {source}")]
    UnknownName { name: String, source: UnknownName },
    #[error("{name}: median cut makes a power of two of lights, 1 to {MAX_LIGHTS}; got {value:?}")]
    MedianCutLights { name: String, value: String },
    #[error("{name}: expected an object index after ':'")]
    NoIndex { name: String },
    #[error("{name}: no object {index} (the scene has {count})")]
    NoObject {
        name: String,
        index: usize,
        count: usize,
    },
    #[error("{name}: expected r,g,b or one value, got {value:?}")]
    NotAColour { name: String, value: String },
    #[error("{name}: specular {value} outside [0, 1]")]
    SpecularOutOfRange { name: String, value: String },
    #[error("{name}: shininess {value} outside (0, {MAX_SHININESS}]")]
    ShininessOutOfRange { name: String, value: f32 },
    #[error("{name}: {value} outside [0, 1]")]
    FactorOutOfRange { name: String, value: f32 },
}

/// `value` as a finite number.
fn finite(name: &str, value: &str) -> Result<f32, SettingError> {
    (value.trim().parse::<f32>().ok())
        .filter(|v| v.is_finite())
        .ok_or_else(|| SettingError::NotANumber {
            name: name.to_owned(),
            value: value.to_owned(),
        })
}

#[derive(Debug, Clone, PartialEq)]
pub struct ViewSettings {
    pub env: PathBuf,
    pub rotation_deg: f32,
    pub animate: bool,
    /// Degrees per second while animating.
    pub animate_speed: f32,
    pub mode: RenderMode,
    pub decompose_mode: DecomposeMode,
    pub threshold: f32,
    /// SH order of the lighting (at most the bake's).
    pub order: usize,
    pub shadow: ShadowSettings,
    pub lights_indirect: bool,
    /// Lights of the median-cut peer (a power of two).
    pub median_cut_lights: usize,
    pub exposure: f32,
    /// Per object of the scene, its specular lobe (edited live; the scene file keeps its
    /// own).
    pub materials: Vec<Material>,
    /// Composite into the scene's backplate (only a scene with one).
    pub composite: bool,
    /// Play a room's `[path]` back, one frame per drawn frame.
    pub play_path: bool,
    /// A room takes the model's soft shadow and bounce on its SH light (the lights' shadows
    /// it always takes).
    pub soft_shadow: bool,
    /// Show the proxies' edges over the composite.
    pub wireframe: bool,
    /// The `--backplate` a model was opened with (repeated in the render command line).
    pub backplate: Option<PathBuf>,
    /// How far the virtual objects were moved (repeated in the render command line).
    pub object_offset: glam::Vec3,
}

/// `r,g,b` or one value, each in [0, 1].
fn parse_specular(name: &str, value: &str) -> Result<Rgb, SettingError> {
    let values: Vec<f32> = (value.split(','))
        .map(|v| finite(name, v))
        .collect::<Result<_, _>>()?;
    let rgb = match values[..] {
        [v] => Rgb::splat(v),
        [r, g, b] => Rgb::new(r, g, b),
        _ => {
            return Err(SettingError::NotAColour {
                name: name.to_owned(),
                value: value.to_owned(),
            });
        }
    };
    if rgb.min_element() < 0.0 || rgb.max_element() > 1.0 {
        return Err(SettingError::SpecularOutOfRange {
            name: name.to_owned(),
            value: value.to_owned(),
        });
    }
    Ok(rgb)
}

/// `on`/`true` or `off`/`false`.
fn switch(name: &str, value: &str) -> Result<bool, SettingError> {
    match value {
        "on" | "true" => Ok(true),
        "off" | "false" => Ok(false),
        _ => Err(SettingError::NotASwitch {
            name: name.to_owned(),
            value: value.to_owned(),
        }),
    }
}

/// A named value (`mode`, `decompose`).
fn named<T: std::str::FromStr<Err = UnknownName>>(
    name: &str,
    value: &str,
) -> Result<T, SettingError> {
    value.parse().map_err(|source| SettingError::UnknownName {
        name: name.to_owned(),
        source,
    })
}

/// A median-cut light count: a power of two, at most [`MAX_LIGHTS`].
fn median_cut_lights(name: &str, value: &str) -> Result<usize, SettingError> {
    (value.parse::<usize>().ok())
        .filter(|n| n.is_power_of_two() && *n <= MAX_LIGHTS)
        .ok_or_else(|| SettingError::MedianCutLights {
            name: name.to_owned(),
            value: value.to_owned(),
        })
}

impl ViewSettings {
    pub fn decompose_settings(&self) -> DecomposeSettings {
        DecomposeSettings {
            threshold: self.threshold,
            ..DecomposeSettings::for_mode(self.decompose_mode, self.order)
        }
    }

    /// Switches the decomposition mode; the lights' bounce light follows the mode's rule
    /// ([`lights_indirect_default`]) until it is set again.
    pub fn set_decompose_mode(&mut self, mode: DecomposeMode) {
        if mode != self.decompose_mode {
            self.decompose_mode = mode;
            self.lights_indirect = lights_indirect_default(mode);
        }
    }

    /// Applies a `set NAME VALUE` of a script.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), SettingError> {
        let number = || finite(name, value);
        let switch = || switch(name, value);
        match name {
            "rotation" => self.rotation_deg = number()?,
            "animate" => self.animate = switch()?,
            "speed" => self.animate_speed = number()?,
            "mode" => self.mode = named(name, value)?,
            "decompose" => self.set_decompose_mode(named(name, value)?),
            "threshold" => self.threshold = number()?,
            "order" => self.order = number()? as usize,
            "shadow_res" => self.shadow.resolution = number()? as u32,
            "pcf" => self.shadow.pcf_taps = number()? as u32,
            "pcf_from_radius" => self.shadow.from_angular_radius = switch()?,
            "lights_indirect" => self.lights_indirect = switch()?,
            "median_cut_lights" => self.median_cut_lights = median_cut_lights(name, value)?,
            "exposure" => self.exposure = number()?,
            "env" => self.env = PathBuf::from(value),
            "composite" => self.composite = switch()?,
            "wireframe" => self.wireframe = switch()?,
            "play_path" => self.play_path = switch()?,
            "soft_shadow" => self.soft_shadow = switch()?,
            _ => self.set_material(name, value)?,
        }
        Ok(())
    }

    /// `specular:N r,g,b` (or one value for all three) and `shininess:N s`, or the
    /// metallic-roughness layer's `metallic:N m` and `roughness:N r` (a layer replaces a
    /// Phong lobe, from glTF's defaults, 1 and 1), for object N (from 0).
    fn set_material(&mut self, name: &str, value: &str) -> Result<(), SettingError> {
        let unknown = || SettingError::Unknown(name.to_owned());
        let (what, index) = name.split_once(':').ok_or_else(unknown)?;
        let index: usize = index.parse().map_err(|_| SettingError::NoIndex {
            name: name.to_owned(),
        })?;
        let count = self.materials.len();
        let material = (self.materials.get_mut(index)).ok_or_else(|| SettingError::NoObject {
            name: name.to_owned(),
            index,
            count,
        })?;
        match what {
            "specular" => material.specular = parse_specular(name, value)?,
            "shininess" => {
                let s = finite(name, value)?;
                if !(s > 0.0 && s <= MAX_SHININESS) {
                    return Err(SettingError::ShininessOutOfRange {
                        name: name.to_owned(),
                        value: s,
                    });
                }
                material.shininess = s;
            }
            "metallic" | "roughness" => {
                let f = finite(name, value)?;
                if !(0.0..=1.0).contains(&f) {
                    return Err(SettingError::FactorOutOfRange {
                        name: name.to_owned(),
                        value: f,
                    });
                }
                let layer = material.layer.unwrap_or(foundation::material::Layer {
                    metallic: 1.0,
                    roughness: 1.0,
                });
                *material = match what {
                    "metallic" => Material::metallic_roughness(f, layer.roughness),
                    _ => Material::metallic_roughness(layer.metallic, f),
                };
            }
            _ => return Err(unknown()),
        }
        Ok(())
    }

    /// The `hprt render` arguments that draw exactly what the viewer shows.
    pub fn render_command(
        &self,
        scene: &Path,
        bake: &Path,
        camera: &Camera,
        output: &Path,
    ) -> Vec<String> {
        let v = |v: glam::Vec3| format!("{},{},{}", v.x, v.y, v.z);
        let on_off = |b: bool| if b { "on" } else { "off" }.to_owned();
        let composite: &[&str] = if self.composite {
            &["--composite", "live"]
        } else {
            &[]
        };
        let backplate = self
            .backplate
            .iter()
            .flat_map(|b| ["--backplate".to_owned(), b.display().to_string()]);
        let mut words: Vec<String> = vec![
            "hprt".into(),
            "render".into(),
            scene.display().to_string(),
            "--bake".into(),
            bake.display().to_string(),
            "--env".into(),
            self.env.display().to_string(),
            format!("--rotate={}", self.rotation_deg),
            "--mode".into(),
            self.mode.name().into(),
            "--decompose-mode".into(),
            self.decompose_mode.name().into(),
            "--threshold".into(),
            self.threshold.to_string(),
            "--order".into(),
            self.order.to_string(),
            "--shadow-res".into(),
            self.shadow.resolution.to_string(),
            "--pcf".into(),
            self.shadow.pcf_taps.to_string(),
            "--pcf-from-radius".into(),
            on_off(self.shadow.from_angular_radius),
            "--lights-indirect".into(),
            on_off(self.lights_indirect),
            "--lights".into(),
            self.median_cut_lights.to_string(),
            format!("--camera-position={}", v(camera.position)),
            format!("--camera-target={}", v(camera.target)),
            "--fov".into(),
            camera.fov_y_deg.to_string(),
            "--width".into(),
            camera.width.to_string(),
            "--height".into(),
            camera.height.to_string(),
            "--exposure".into(),
            self.exposure.to_string(),
            "-o".into(),
            output.display().to_string(),
        ];
        words.extend(composite.iter().map(|w| w.to_string()));
        words.extend(backplate);
        if self.object_offset != glam::Vec3::ZERO {
            words.push(format!("--move-objects={}", v(self.object_offset)));
        }
        words
    }
}

/// Quotes a word for a POSIX shell when needed.
pub fn shell_quote(word: &str) -> String {
    if !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+".contains(c))
    {
        word.to_owned()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> ViewSettings {
        ViewSettings {
            env: PathBuf::from("scenes/env/sunrise.exr"),
            rotation_deg: -100.0,
            animate: false,
            animate_speed: 20.0,
            mode: RenderMode::Hybrid,
            decompose_mode: DecomposeMode::Consistent,
            threshold: 0.05,
            order: 5,
            shadow: ShadowSettings::default(),
            lights_indirect: true,
            median_cut_lights: 8,
            exposure: 0.6,
            materials: vec![Material::DIFFUSE; 2],
            composite: false,
            wireframe: false,
            backplate: None,
            object_offset: glam::Vec3::ZERO,
            play_path: false,
            soft_shadow: true,
        }
    }

    #[test]
    fn materials_are_set_per_object() {
        let mut s = settings();
        s.set("specular:1", "0.1,0.2,0.3").unwrap();
        s.set("shininess:1", "60").unwrap();
        s.set("specular:0", "0.25").unwrap();
        assert_eq!(s.materials[1].specular, Rgb::new(0.1, 0.2, 0.3));
        assert_eq!(s.materials[1].shininess, 60.0);
        assert_eq!(s.materials[0].specular, Rgb::splat(0.25));
        s.set("roughness:0", "0.3").unwrap();
        assert_eq!(s.materials[0], Material::metallic_roughness(1.0, 0.3));
        s.set("metallic:0", "0").unwrap();
        assert_eq!(s.materials[0], Material::metallic_roughness(0.0, 0.3));
        for (name, value) in [
            ("specular:2", "0.1"),
            ("specular:x", "0.1"),
            ("specular:0", "1.5"),
            ("specular:0", "0.1,0.2"),
            ("shininess:0", "0"),
            ("gloss:0", "1"),
            ("metallic:0", "1.5"),
            ("roughness:0", "nan"),
        ] {
            assert!(s.set(name, value).is_err(), "{name} {value}");
        }
    }

    #[test]
    fn script_settings_apply_and_reject_nonsense() {
        let mut s = settings();
        s.set("rotation", "12.5").unwrap();
        s.set("mode", "prt").unwrap();
        s.set("pcf_from_radius", "off").unwrap();
        assert_eq!(
            (s.rotation_deg, s.mode, s.shadow.from_angular_radius),
            (12.5, RenderMode::Prt, false)
        );
        assert!(s.set("mode", "fancy").is_err());
        // A decomposition mode brings its rule for the lights' bounce light.
        s.set("decompose", "thesis").unwrap();
        assert!(!s.lights_indirect);
        s.set("lights_indirect", "on").unwrap();
        s.set("decompose", "thesis").unwrap();
        assert!(s.lights_indirect, "setting the same mode keeps a choice");
        s.set("decompose", "consistent").unwrap();
        assert!(s.lights_indirect);
        assert!(s.set("colour", "1").is_err());
        assert!(s.set("threshold", "x").is_err());
    }

    #[test]
    fn command_line_carries_every_setting() {
        let camera = Camera {
            position: glam::Vec3::new(1.0, 2.0, 3.0),
            target: glam::Vec3::ZERO,
            up: glam::Vec3::Y,
            fov_y_deg: 40.0,
            width: 320,
            height: 200,
        };
        let args = settings().render_command(
            Path::new("scenes/teapot.toml"),
            Path::new("t.bake"),
            &camera,
            Path::new("out.png"),
        );
        let line = args.join(" ");
        for needle in [
            "--rotate=-100",
            "--camera-position=1,2,3",
            "--width 320",
            "--pcf-from-radius on",
            "--exposure 0.6",
        ] {
            assert!(line.contains(needle), "{line}");
        }
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("--rotate=-1"), "--rotate=-1");
    }
}
