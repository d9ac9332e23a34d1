//! The scene exactly as hprt sees it, as a Mitsuba 3 scene, so anyone can cross-check the
//! reference renderer against an independent one. See the README's "Cross-checking with
//! Mitsuba 3" for the mapping.

use foundation::Rgb;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::{RgbImageF32, write_exr};
use foundation::infra::atomic_file::write_atomic;
use foundation::mesh::TriangleMesh;
use foundation::scene::{SceneMesh, SceneObject};
use foundation::texture::Emission;
use std::path::{Path, PathBuf};

mod ply;
pub(crate) use ply::ply_bytes;

#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{}: {message}", path.display())]
    Write { path: PathBuf, message: String },
}

/// What the exported scene renders.
#[derive(Debug, Clone)]
pub struct ExportSettings {
    pub camera: Camera,
    pub rotation_deg: f32,
    pub spp: u32,
    pub bounces: u32,
}

/// Mitsuba's `max_depth` for hprt's `bounces`: depth 1 is the directly visible environment,
/// depth 2 adds direct lighting, each further level one indirect bounce.
pub fn mitsuba_max_depth(bounces: u32) -> u32 {
    bounces + 2
}

/// The sub-mesh of one scene object (its own vertex range).
fn object_mesh(geometry: &SceneMesh, object: usize) -> TriangleMesh {
    let o = &geometry.objects[object];
    let mesh = &geometry.mesh;
    let (v0, v1) = (o.vertices.start as usize, o.vertices.end as usize);
    TriangleMesh {
        positions: mesh.positions[v0..v1].to_vec(),
        normals: mesh.normals[v0..v1].to_vec(),
        triangles: mesh.triangles[o.triangles.start as usize..o.triangles.end as usize]
            .iter()
            .map(|t| t.map(|i| i - v0 as u32))
            .collect(),
        uvs: mesh.uvs.get(v0..v1).map(<[_]>::to_vec).unwrap_or_default(),
        tangents: match o.normal_map {
            Some(_) => mesh.tangents[v0..v1].to_vec(),
            None => Vec::new(),
        },
    }
}

/// The texture file of textured object `index`.
fn texture_file_for(name: &str, index: usize) -> String {
    file_name_for(name, index).replace(".ply", ".exr")
}

/// The emission file of object `index`, whose emission is textured.
fn emission_file_for(name: &str, index: usize) -> String {
    file_name_for(name, index).replace(".ply", "_emission.exr")
}

/// The normal map file of normal-mapped object `index`.
fn normal_map_file_for(name: &str, index: usize) -> String {
    file_name_for(name, index).replace(".ply", "_normals.exr")
}

fn file_name_for(name: &str, index: usize) -> String {
    let clean: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{index:02}_{clean}.ply")
}

/// The Mitsuba 3 scene description.
pub(crate) fn scene_xml(geometry: &SceneMesh, settings: &ExportSettings) -> String {
    let c = &settings.camera;
    let v = |v: glam::Vec3| format!("{}, {}, {}", v.x, v.y, v.z);
    let mut xml = format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<!-- Exported by hprt; see its README, "Cross-checking with Mitsuba 3". -->
<scene version="3.0.0">
    <!-- How the backs of triangles look. twosided: as surfaces of their own, facing the
         other way. hprt shows the front's radiance on both sides (CONVENTIONS.md,
         "Surfaces"); for exactly that, import thinsheet.py from this folder and load with
         surface="thinsheet". Glossy objects use hprt's Phong material, metallic-roughness
         ones glTF's: import phong.py and metallic_roughness.py from this folder before
         loading. -->
    <default name="surface" value="twosided"/>
    <integrator type="path">
        <!-- hprt bounces = {bounces} -->
        <integer name="max_depth" value="{max_depth}"/>
        <integer name="rr_depth" value="{rr_depth}"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world">
            <lookat origin="{origin}" target="{target}" up="{up}"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="{spp}"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="{width}"/>
            <integer name="height" value="{height}"/>
            <string name="pixel_format" value="rgb"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="envmap">
        <string name="filename" value="envmap.exr"/>
        <transform name="to_world">
            <rotate y="1" angle="{rotation}"/>
        </transform>
    </emitter>
"#,
        bounces = settings.bounces,
        max_depth = mitsuba_max_depth(settings.bounces),
        rr_depth = mitsuba_max_depth(settings.bounces) + 1,
        fov = c.fov_y_deg,
        origin = v(c.position),
        target = v(c.target),
        up = v(c.up),
        spp = settings.spp,
        width = c.width,
        height = c.height,
        rotation = settings.rotation_deg,
    );
    for (i, o) in geometry.objects.iter().enumerate() {
        xml.push_str(&shape_xml(o, i, o.emission.map(|e| &geometry.emissions[e])));
    }
    xml.push_str("</scene>\n");
    xml
}

/// One object as a Mitsuba shape: its mesh file and its BSDF (diffuse, hprt's Phong, or
/// glTF's metallic-roughness).
fn shape_xml(o: &SceneObject, i: usize, emission: Option<&Emission>) -> String {
    let a = o.albedo;
    let reflectance = match o.texture {
        // The texture with the object's factor folded in, linear, looked up bilinearly
        // with repeat wrapping (Mitsuba's defaults, and hprt's reference).
        Some(_) => bitmap_xml("reflectance", &texture_file_for(&o.name, i)),
        None => rgb_xml("reflectance", a),
    };
    let m = &o.material;
    let surface = if let Some(layer) = m.layer {
        format!(
            r#"<bsdf type="hprtmetallicroughness">
                {reflectance}
                <float name="metallic" value="{}"/>
                <float name="roughness" value="{}"/>
            </bsdf>"#,
            layer.metallic, layer.roughness
        )
    } else if m.is_glossy() {
        format!(
            r#"<bsdf type="hprtphong">
                {reflectance}
                <rgb name="specular" value="{}, {}, {}"/>
                <float name="exponent" value="{}"/>
            </bsdf>"#,
            m.specular.x, m.specular.y, m.specular.z, m.shininess
        )
    } else {
        format!(
            r#"<bsdf type="diffuse">
                {reflectance}
            </bsdf>"#
        )
    };
    // A normal map (its scale folded into the texels) perturbs the shading frame of the
    // BSDF it wraps, with hprt's tangents (CONVENTIONS.md, "Normal maps").
    let inner = match o.normal_map {
        Some(_) => format!(
            r#"<bsdf type="hprtnormalmap">
                {}
                {surface}
            </bsdf>"#,
            bitmap_xml("normalmap", &normal_map_file_for(&o.name, i))
        ),
        None => surface,
    };
    format!(
        r#"    <shape type="ply" id="{id}">
        <string name="filename" value="meshes/{file}"/>
        <boolean name="face_normals" value="false"/>
        <bsdf type="$surface">
            {inner}
        </bsdf>{emitter}
    </shape>
"#,
        id = xml_escape(&o.name),
        file = file_name_for(&o.name, i),
        emitter = emitter_xml(o, i, emission),
    )
}

/// An emitting object's `area` emitter: its factor, or its texture times its factor as a
/// linear EXR. Mitsuba's area lights emit from the front only; hprt's from both sides (seen
/// only where a back faces the viewer).
fn emitter_xml(o: &SceneObject, i: usize, emission: Option<&Emission>) -> String {
    let Some(e) = emission else {
        return String::new();
    };
    let radiance = match e.texture {
        Some(_) => bitmap_xml("radiance", &emission_file_for(&o.name, i)),
        None => rgb_xml("radiance", e.factor),
    };
    format!(
        r#"
        <emitter type="area">
            {radiance}
        </emitter>"#
    )
}

/// A linear EXR of `textures/` as the texture parameter `name`, looked up bilinearly with
/// repeat wrapping (Mitsuba's defaults, and hprt's reference).
fn bitmap_xml(name: &str, file: &str) -> String {
    format!(
        r#"<texture type="bitmap" name="{name}">
                    <string name="filename" value="textures/{file}"/>
                    <boolean name="raw" value="true"/>
                </texture>"#
    )
}

fn rgb_xml(name: &str, c: Rgb) -> String {
    format!(r#"<rgb name="{name}" value="{}, {}, {}"/>"#, c.x, c.y, c.z)
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The Mitsuba 3 plugin that reproduces hprt's surfaces (both sides show the front), registered
/// as `thinsheet` when imported.
pub(crate) const THIN_SHEET_PLUGIN: &str = include_str!("thinsheet.py");

/// The Mitsuba 3 plugin of hprt's glossy material (Lambert plus a normalised Phong lobe,
/// CONVENTIONS.md, "Glossy materials"), registered as `hprtphong` when imported.
pub(crate) const PHONG_PLUGIN: &str = include_str!("phong.py");

/// glTF's metallic-roughness material as a Mitsuba 3 BSDF plugin, registered as
/// `hprtmetallicroughness` when imported.
pub(crate) const METALLIC_ROUGHNESS_PLUGIN: &str = include_str!("metallic_roughness.py");

/// glTF's tangent-space normal map as a Mitsuba 3 BSDF wrapper with hprt's tangents,
/// registered as `hprtnormalmap` when imported.
pub(crate) const NORMAL_MAP_PLUGIN: &str = include_str!("normal_map.py");

/// Every file [`export_mitsuba`] writes into `dir` for `geometry`.
pub fn export_files(dir: &Path, geometry: &SceneMesh) -> Vec<PathBuf> {
    let objects = geometry.objects.iter().enumerate();
    let meshes = objects
        .clone()
        .map(|(i, o)| dir.join("meshes").join(file_name_for(&o.name, i)));
    let textures = objects
        .clone()
        .filter(|(_, o)| o.texture.is_some())
        .map(|(i, o)| dir.join("textures").join(texture_file_for(&o.name, i)));
    let normal_maps = objects
        .clone()
        .filter(|(_, o)| o.normal_map.is_some())
        .map(|(i, o)| dir.join("textures").join(normal_map_file_for(&o.name, i)));
    let emissions = objects
        .filter(|(_, o)| {
            o.emission
                .is_some_and(|e| geometry.emissions[e].texture.is_some())
        })
        .map(|(i, o)| dir.join("textures").join(emission_file_for(&o.name, i)));
    let fixed = [
        "envmap.exr",
        "thinsheet.py",
        "phong.py",
        "metallic_roughness.py",
        "normal_map.py",
        "scene.xml",
    ]
    .map(|f| dir.join(f));
    meshes
        .chain(textures)
        .chain(normal_maps)
        .chain(emissions)
        .chain(fixed)
        .collect()
}

/// Writes `dir/scene.xml`, the plugins (`dir/*.py`), `dir/envmap.exr`, `dir/meshes/*.ply` and, for
/// textured objects, `dir/textures/*.exr`.
pub fn export_mitsuba(
    dir: &Path,
    geometry: &SceneMesh,
    map: &EnvMap,
    settings: &ExportSettings,
) -> Result<(), ExportError> {
    let error = |path: &Path, message: String| ExportError::Write {
        path: path.to_owned(),
        message,
    };
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).map_err(|e| error(&meshes, e.to_string()))?;
    for i in 0..geometry.objects.len() {
        let path = meshes.join(file_name_for(&geometry.objects[i].name, i));
        write_atomic(&path, &ply_bytes(&object_mesh(geometry, i)))
            .map_err(|e| error(&path, e.to_string()))?;
    }
    for (i, o) in geometry.objects.iter().enumerate() {
        let Some(t) = o.texture else { continue };
        let texture = &geometry.textures[t];
        let folder = dir.join("textures");
        std::fs::create_dir_all(&folder).map_err(|e| error(&folder, e.to_string()))?;
        let path = folder.join(texture_file_for(&o.name, i));
        let texels = texture.texels.iter().map(|t| *t * o.albedo).collect();
        let image = RgbImageF32::new(texture.width, texture.height, texels);
        write_exr(&path, &image).map_err(|e| error(&path, e.to_string()))?;
    }
    for (i, o) in geometry.objects.iter().enumerate() {
        let Some(m) = o.normal_map else { continue };
        let map = &geometry.normal_maps[m];
        let folder = dir.join("textures");
        std::fs::create_dir_all(&folder).map_err(|e| error(&folder, e.to_string()))?;
        let path = folder.join(normal_map_file_for(&o.name, i));
        // (2 t − 1)(s, s, 1) is what the plugin reads as 2 t' − 1: the scale folded in.
        let scaled = |t: Rgb| {
            (((t * 2.0 - Rgb::ONE) * Rgb::new(map.scale, map.scale, 1.0)) + Rgb::ONE) * 0.5
        };
        let texels = map.texture.texels.iter().map(|t| scaled(*t)).collect();
        let image = RgbImageF32::new(map.texture.width, map.texture.height, texels);
        write_exr(&path, &image).map_err(|e| error(&path, e.to_string()))?;
    }
    for (i, o) in geometry.objects.iter().enumerate() {
        let Some(e) = o.emission.map(|e| &geometry.emissions[e]) else {
            continue;
        };
        let Some(texture) = &e.texture else { continue };
        let folder = dir.join("textures");
        std::fs::create_dir_all(&folder).map_err(|e| error(&folder, e.to_string()))?;
        let path = folder.join(emission_file_for(&o.name, i));
        let texels = texture.texels.iter().map(|t| *t * e.factor).collect();
        let image = RgbImageF32::new(texture.width, texture.height, texels);
        write_exr(&path, &image).map_err(|e| error(&path, e.to_string()))?;
    }
    let env_path = dir.join("envmap.exr");
    let image = RgbImageF32::new(map.width(), map.height(), map.texels().to_vec());
    write_exr(&env_path, &image).map_err(|e| error(&env_path, e.to_string()))?;
    for (name, plugin) in [
        ("thinsheet.py", THIN_SHEET_PLUGIN),
        ("phong.py", PHONG_PLUGIN),
        ("metallic_roughness.py", METALLIC_ROUGHNESS_PLUGIN),
        ("normal_map.py", NORMAL_MAP_PLUGIN),
    ] {
        let plugin_path = dir.join(name);
        write_atomic(&plugin_path, plugin.as_bytes())
            .map_err(|e| error(&plugin_path, e.to_string()))?;
    }
    let xml_path = dir.join("scene.xml");
    write_atomic(&xml_path, scene_xml(geometry, settings).as_bytes())
        .map_err(|e| error(&xml_path, e.to_string()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::color::Rgb;
    use foundation::mesh::{LoadOptions, box_mesh, read_mesh};
    use glam::Vec3;

    #[test]
    fn exported_ply_reads_back_identically() {
        let mesh = box_mesh(Vec3::ZERO, Vec3::ONE, [2, 1, 3], [false; 6]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("box.ply");
        std::fs::write(&path, ply_bytes(&mesh)).unwrap();
        let back = read_mesh(&path, &LoadOptions::default()).unwrap();
        assert_eq!(back.positions, mesh.positions);
        assert_eq!(back.normals.unwrap(), mesh.normals);
        assert_eq!(back.triangles, mesh.triangles);
    }

    #[test]
    fn scene_xml_names_every_object_and_the_depth() {
        let mut geometry = SceneMesh::default();
        geometry.push_object(
            "table top".into(),
            &box_mesh(Vec3::ZERO, Vec3::ONE, [1, 1, 1], [false; 6]),
            Rgb::splat(0.5),
        );
        let settings = ExportSettings {
            camera: Camera {
                position: Vec3::new(0.0, 1.0, 5.0),
                target: Vec3::ZERO,
                up: Vec3::Y,
                fov_y_deg: 40.0,
                width: 64,
                height: 48,
            },
            rotation_deg: 30.0,
            spp: 16,
            bounces: 3,
        };
        let xml = scene_xml(&geometry, &settings);
        assert!(xml.contains("<integer name=\"max_depth\" value=\"5\"/>"));
        // Mitsuba's own two-sided BSDF by default; the plugin written beside it on request.
        assert!(xml.contains("<default name=\"surface\" value=\"twosided\"/>"));
        assert!(xml.contains("<bsdf type=\"$surface\">"));
        assert!(THIN_SHEET_PLUGIN.contains("mi.register_bsdf(\"thinsheet\""));
        assert!(xml.contains("meshes/00_table_top.ply"));
        assert!(xml.contains("<rotate y=\"1\" angle=\"30\"/>"));
        assert!(xml.contains("<rfilter type=\"box\"/>"));
        let dir = tempfile::tempdir().unwrap();
        export_mitsuba(
            dir.path(),
            &geometry,
            &EnvMap::uniform(8, 4, Rgb::ONE),
            &settings,
        )
        .unwrap();
        assert!(dir.path().join("meshes/00_table_top.ply").exists());
        assert!(dir.path().join("envmap.exr").exists());
        // An emitting object gets an area emitter of its radiance; a textured one its texture
        // times its factor, written beside the scene.
        assert!(!xml.contains("<emitter type=\"area\">"));
        let texture = std::sync::Arc::new(foundation::texture::AlbedoTexture {
            width: 1,
            height: 1,
            texels: vec![Rgb::new(0.5, 1.0, 0.25)],
        });
        for (texture, want) in [
            (None, "value=\"2, 4, 8\""),
            (Some(texture), "_emission.exr"),
        ] {
            let mut lit = geometry.clone();
            let factor = Rgb::new(2.0, 4.0, 8.0);
            lit.set_emission(Emission { factor, texture });
            let xml = scene_xml(&lit, &settings);
            assert!(
                xml.contains("<emitter type=\"area\">") && xml.contains(want),
                "{xml}"
            );
            export_mitsuba(
                dir.path(),
                &lit,
                &EnvMap::uniform(8, 4, Rgb::ONE),
                &settings,
            )
            .unwrap();
            assert!(export_files(dir.path(), &lit).iter().all(|f| f.exists()));
        }
        let written =
            foundation::image_io::read_exr(&dir.path().join("textures/00_table_top_emission.exr"))
                .unwrap();
        assert_eq!(written.pixels[0], Rgb::new(1.0, 4.0, 2.0));
    }
}
