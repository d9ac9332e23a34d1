//! A scene of many copies of another's objects, side by side: a large bake made from a small
//! scene file.

use crate::error::{BenchError, Result};
use crate::inputs::load_scene;
use std::path::{Path, PathBuf};

/// A scene file of `instances` copies of `scene`'s objects, each moved along +X by the
/// scene's width and a gap, written into `dir`.
pub(super) fn synthetic_scene(scene: &Path, instances: u32, dir: &Path) -> Result<PathBuf> {
    let loaded = load_scene(scene)?;
    let (lo, hi) = loaded
        .geometry
        .mesh
        .bounds()
        .ok_or(BenchError::EmptyScene)?;
    let step = (hi.x - lo.x) * 1.1;
    let text = std::fs::read_to_string(scene).map_err(BenchError::file("cannot read", scene))?;
    let table: toml::Table = toml::from_str(&text).map_err(|cause| BenchError::SceneToml {
        path: scene.to_owned(),
        cause,
    })?;
    let base = scene.parent().unwrap_or(Path::new("."));
    let objects = (table.get("object").and_then(|o| o.as_array())).ok_or(BenchError::NoObjects)?;
    let mut copies = Vec::new();
    for k in 0..instances {
        for object in objects {
            let mut object = object
                .as_table()
                .cloned()
                .ok_or(BenchError::ObjectNotTable)?;
            if let Some(mesh) = object.get("mesh").and_then(|m| m.as_str()) {
                let path = std::path::absolute(base.join(mesh))
                    .map_err(BenchError::file("cannot resolve", base.join(mesh)))?;
                object.insert("mesh".into(), path.display().to_string().into());
            }
            object.insert("name".into(), format!("copy {k} {}", copies.len()).into());
            moved(&mut object, step * k as f32);
            copies.push(toml::Value::Table(object));
        }
    }
    let mut out = table.clone();
    out.remove("environment");
    out.insert("name".into(), format!("{instances} copies").into());
    out.insert("object".into(), toml::Value::Array(copies));
    let path = dir.join("synthetic.toml");
    std::fs::write(&path, toml::to_string(&out)?)
        .map_err(BenchError::file("cannot write", &path))?;
    Ok(path)
}

/// Moves `object` by `shift` along +X, after its own transform (which it keeps).
fn moved(object: &mut toml::Table, shift: f32) {
    let shift = [shift as f64, 0.0, 0.0];
    let mut transform = (object.get("transform").and_then(|t| t.as_table()))
        .cloned()
        .unwrap_or_default();
    let own = transform.get("translate").and_then(|t| t.as_array());
    let moved: Vec<toml::Value> = match own {
        Some(t) => (t.iter().zip(shift))
            .map(|(a, b)| (a.as_float().unwrap_or(0.0) + b).into())
            .collect(),
        None => shift.map(toml::Value::from).to_vec(),
    };
    transform.insert("translate".into(), toml::Value::Array(moved));
    object.insert("transform".into(), toml::Value::Table(transform));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_move_after_their_own_translation() {
        let mut object: toml::Table =
            toml::from_str("transform = { translate = [1.0, 2.0, 3.0] }").unwrap();
        moved(&mut object, 5.0);
        let translate = object["transform"]["translate"].as_array().unwrap();
        let values: Vec<f64> = translate.iter().map(|v| v.as_float().unwrap()).collect();
        assert_eq!(values, [6.0, 2.0, 3.0]);
        let mut bare = toml::Table::new();
        moved(&mut bare, 2.0);
        assert_eq!(bare["transform"]["translate"][0].as_float(), Some(2.0));
    }
}
