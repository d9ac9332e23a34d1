//! Scene files (TOML): objects with transforms and albedos, the camera, the default
//! environment map and the default bake settings. The format is described in `scenes/README.md`.

mod backplate;
mod build;
mod description;
mod geometry;
pub mod model;
mod model_files;
mod path;
mod rotation;
mod shape_objects;
mod spec_error;

pub use backplate::{BackplateError, load_backplate_image};
pub use description::{
    AnnulusSpec, Backplate, BackplateSpec, BoxSpec, EnvironmentSpec, ObjectRole, ObjectSpec,
    ProbeSpec, Scale, SceneFile, Transform,
};
pub use geometry::{NO_TEXTURE, SceneMesh, SceneObject};
pub use model_files::MAX_MATERIAL_ALBEDO;
pub use path::{Crossing, ModelPath, PathSpec, Pose, mesh_crosses};
pub use rotation::rotation_from_deg;

use crate::bake_settings::BakeSettings;
use crate::camera::Camera;
use crate::mesh::MeshError;
use std::path::{Path, PathBuf};

/// Why a scene could not be loaded. Every variant names the scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: {message}", path.display())]
    Parse { path: PathBuf, message: String },
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    #[error("{}: object \"{object}\": {cause}", scene.display())]
    Mesh {
        scene: PathBuf,
        object: String,
        cause: MeshError,
    },
}

/// A loaded scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub name: String,
    /// The scene file it was loaded from.
    pub path: PathBuf,
    pub geometry: SceneMesh,
    pub camera: Camera,
    /// Default environment, its path resolved relative to the scene file.
    pub environment: Option<EnvironmentSpec>,
    pub bake: BakeSettings,
    /// The picture its objects are composited into, when it has proxies.
    pub backplate: Option<Backplate>,
    /// The light probes of its room (the proxies), files resolved.
    pub probes: Vec<crate::probe::ProbeSource>,
    /// Where its virtual objects are carried, frame by frame (the centre of their bounds).
    pub model_path: Option<ModelPath>,
    /// Every file the scene was read from: the scene file (or model) and each object's mesh.
    pub sources: Vec<PathBuf>,
}

/// Variants of a scene: a part of its geometry (the room, the model) or geometry changed
/// (the model collapsed), the rest of the scene kept.
impl Scene {
    /// The files the scene reads (its sources, then `other`, its map and its probes' images):
    /// what a command's outputs must not overwrite, and what a reference band records.
    pub fn inputs<'a>(&'a self, other: &[Option<&'a Path>]) -> Vec<&'a Path> {
        let environment = self.environment.as_ref().map(|e| e.map.as_path());
        let probes = (self.probes.iter())
            .flat_map(|p| std::iter::once(p.image.as_path()).chain(p.distances.as_deref()));
        self.sources
            .iter()
            .map(PathBuf::as_path)
            .chain(other.iter().flatten().copied())
            .chain(environment)
            .chain(probes)
            .collect()
    }

    /// This scene with `geometry` in place of its own (its own is not copied).
    pub fn with_geometry(&self, geometry: SceneMesh) -> Scene {
        Scene {
            name: self.name.clone(),
            path: self.path.clone(),
            geometry,
            camera: self.camera,
            environment: self.environment.clone(),
            bake: self.bake,
            backplate: self.backplate.clone(),
            probes: self.probes.clone(),
            model_path: self.model_path.clone(),
            sources: self.sources.clone(),
        }
    }

    /// This scene's objects of `role` alone, the rest of the scene kept.
    pub fn of_role(&self, role: ObjectRole) -> Scene {
        self.with_geometry(self.geometry.of_role(role))
    }

    /// Named `name-suffix` (a part's bake is cached apart from the whole's).
    pub fn renamed(mut self, suffix: &str) -> Scene {
        self.name = format!("{}-{suffix}", self.name);
        self
    }

    /// Not composited into its backplate: its proxies drawn as surfaces of their own.
    pub fn without_backplate(mut self) -> Scene {
        self.backplate = None;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::material::Material;
    use crate::mesh::box_mesh;
    use glam::{Mat4, Vec3};
    use std::path::{Path, PathBuf};

    fn write_scene(dir: &Path, text: &str) -> PathBuf {
        let path = dir.join("s.toml");
        std::fs::write(&path, text).unwrap();
        path
    }

    const CAMERA: &str = "[camera]\nposition = [0, 1, 5]\ntarget = [0, 0, 0]\nfov_y_deg = 40\nwidth = 32\nheight = 24\n";

    #[test]
    fn loads_boxes_with_transforms_and_albedo() {
        let dir = tempfile::tempdir().unwrap();
        let text = format!(
            "{CAMERA}[[object]]\nname = \"slab\"\nbox = {{ min = [-1, -1, -1], max = [1, 1, 1], segments = [2, 2, 2] }}\n\
             albedo = [0.5, 0.4, 0.3]\ntransform = {{ scale = [2, 1, 1], rotate_deg = [0, 90, 0], translate = [0, 3, 0] }}\n"
        );
        let scene = Scene::load(&write_scene(dir.path(), &text)).unwrap();
        let (lo, hi) = scene.geometry.mesh.bounds().unwrap();
        // Scaled x by 2, then rotated 90° about Y: the long side lies along z.
        assert!((lo - Vec3::new(-1.0, 2.0, -2.0)).length() < 1e-5, "{lo}");
        assert!((hi - Vec3::new(1.0, 4.0, 2.0)).length() < 1e-5, "{hi}");
        assert_eq!(scene.geometry.objects[0].name, "slab");
        assert!(
            scene
                .geometry
                .albedo
                .iter()
                .all(|a| *a == Rgb::new(0.5, 0.4, 0.3))
        );
        assert_eq!(scene.bake, BakeSettings::default());
    }

    /// `[[probe]]` entries resolve against the scene's folder, default their names and
    /// images, and must be named once each, inside the room, in a scene that has one.
    #[test]
    fn probes_are_resolved_and_checked() {
        let dir = tempfile::tempdir().unwrap();
        let object = "[[object]]\nname = \"model\"\nbox = { min = [0,0,0], max = [1,1,1] }\nalbedo = [0.5, 0.5, 0.5]\n";
        let room = "[[object]]\nname = \"room\"\nrole = \"proxy\"\nbox = { min = [-4,0,-4], max = [4,3,4] }\nalbedo = [0.3, 0.3, 0.3]\n";
        let plate = "[backplate]\nimage = \"environment\"\n";
        let load = |text: String| Scene::load(&write_scene(dir.path(), &text));
        let probes = "[[probe]]\nposition = [1, 1.5, 0]\n\
                      [[probe]]\nname = \"door\"\nposition = [-3, 1, 2]\nimage = \"d.hdr\"\ndistances = \"d.exr\"\n";
        let scene = load(format!("{CAMERA}{plate}{object}{room}{probes}")).unwrap();
        let expected = [
            crate::probe::ProbeSource {
                name: "probe1".into(),
                position: Vec3::new(1.0, 1.5, 0.0),
                image: dir.path().join("probes/probe1.exr"),
                distances: None,
            },
            crate::probe::ProbeSource {
                name: "door".into(),
                position: Vec3::new(-3.0, 1.0, 2.0),
                image: dir.path().join("d.hdr"),
                distances: Some(dir.path().join("d.exr")),
            },
        ];
        assert_eq!(scene.probes, expected);
        // Probes make the proxies a room, drawn as it is: no backplate needed.
        let room_only = load(format!("{CAMERA}{object}{room}{probes}")).unwrap();
        assert_eq!((room_only.backplate, room_only.probes.len()), (None, 2));

        let error = |text: String| load(text).unwrap_err().to_string();
        let outside = "[[probe]]\nname = \"yard\"\nposition = [9, 1, 0]\n";
        let message = error(format!("{CAMERA}{plate}{object}{room}{outside}"));
        assert!(
            message.contains("\"yard\"") && message.contains("outside"),
            "{message}"
        );
        let twice = "[[probe]]\nname = \"a\"\nposition = [0, 1, 0]\n[[probe]]\nname = \"a\"\nposition = [1, 1, 0]\n";
        let message = error(format!("{CAMERA}{plate}{object}{room}{twice}"));
        assert!(message.contains("named twice"), "{message}");
        let message = error(format!("{CAMERA}{object}{probes}"));
        assert!(message.contains("role = \"proxy\""), "{message}");

        let path = "[path]\npoints = [[1, 0.5, 0], [-1, 0.5, 0]]\nframes = 3\n";
        let scene = load(format!("{CAMERA}{object}{path}")).unwrap();
        let positions = scene.model_path.unwrap().positions();
        assert_eq!(positions[1], Vec3::new(0.0, 0.5, 0.0));
        let still = "[path]\npoints = [[1, 0.5, 0]]\nframes = 3\n";
        let message = error(format!("{CAMERA}{object}{still}"));
        assert!(
            message.contains("[path]") && message.contains("two"),
            "{message}"
        );
    }

    #[test]
    fn proxies_and_backplates_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        let object = "[[object]]\nname = \"model\"\nbox = { min = [0,0,0], max = [1,1,1] }\nalbedo = [0.5, 0.5, 0.5]\n";
        let proxy = "[[object]]\nname = \"floor\"\nrole = \"proxy\"\nbox = { min = [-4,-1,-4], max = [4,0,4] }\nalbedo = [0.3, 0.3, 0.3]\n";
        let load = |text: String| Scene::load(&write_scene(dir.path(), &text));
        let scene = load(format!(
            "{CAMERA}[backplate]\nimage = \"environment\"\n{object}{proxy}"
        ))
        .unwrap();
        assert_eq!(scene.backplate, Some(Backplate::Environment));
        let roles: Vec<ObjectRole> = scene.geometry.objects.iter().map(|o| o.role).collect();
        assert_eq!(roles, [ObjectRole::Object, ObjectRole::Proxy]);
        let proxies = scene.geometry.of_role(ObjectRole::Proxy);
        assert_eq!(proxies.objects.len(), 1);
        assert_eq!(proxies.objects[0].name, "floor");
        assert_eq!(proxies.mesh.triangle_count(), 12);
        // The room as a scene of its own: the rest kept, then renamed and not composited.
        let room = scene.of_role(ObjectRole::Proxy);
        assert_eq!(room.geometry.content_hash(), proxies.content_hash());
        assert_eq!(
            (&room.name, &room.backplate),
            (&scene.name, &scene.backplate)
        );
        assert_eq!((room.camera, room.bake), (scene.camera, scene.bake));
        let room = room.renamed("room").without_backplate();
        assert_eq!(room.name, format!("{}-room", scene.name));
        assert_eq!(room.backplate, None);

        // A photograph resolves against the scene's folder and counts as an input.
        let scene = load(format!(
            "{CAMERA}[backplate]\nimage = \"plate.jpg\"\n{object}{proxy}"
        ))
        .unwrap();
        let plate = dir.path().join("plate.jpg");
        assert_eq!(scene.backplate, Some(Backplate::Image(plate.clone())));
        assert!(scene.sources.contains(&plate));

        let err = load(format!("{CAMERA}{object}{proxy}"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("s.toml") && err.contains("[backplate]"),
            "{err}"
        );
        let err = load(format!(
            "{CAMERA}[backplate]\nimage = \"environment\"\n{proxy}"
        ))
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("s.toml") && err.contains("every object is a proxy"),
            "{err}"
        );
        let err = load(format!(
            "{CAMERA}{}",
            object.replace("name", "role = \"ghost\"\nname")
        ))
        .unwrap_err()
        .to_string();
        assert!(err.contains("ghost") && err.contains("line"), "{err}");
    }

    #[test]
    fn errors_name_the_file_and_the_problem() {
        let dir = tempfile::tempdir().unwrap();
        let bad_albedo = format!(
            "{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\nalbedo = [1.2, 0, 0]\n"
        );
        let err = Scene::load(&write_scene(dir.path(), &bad_albedo))
            .unwrap_err()
            .to_string();
        assert!(err.contains("s.toml") && err.contains("albedo"), "{err}");

        let missing_mesh =
            format!("{CAMERA}[[object]]\nmesh = \"nope.ply\"\nalbedo = [0.5, 0.5, 0.5]\n");
        let err = Scene::load(&write_scene(dir.path(), &missing_mesh))
            .unwrap_err()
            .to_string();
        assert!(err.contains("nope.ply"), "{err}");

        let typo = format!(
            "{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\nalbedo = [0.5, 0.5, 0.5]\ncolour = 1\n"
        );
        let err = Scene::load(&write_scene(dir.path(), &typo))
            .unwrap_err()
            .to_string();
        assert!(err.contains("colour") && err.contains("line"), "{err}");

        let err = Scene::load(&dir.path().join("absent.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("absent.toml"), "{err}");
    }

    #[test]
    fn mirroring_transforms_keep_triangles_outward() {
        let cube = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [1, 1, 1], [false; 6]);
        let mirrored = cube
            .transformed(&Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)))
            .unwrap();
        for t in 0..mirrored.triangle_count() {
            let [a, b, c] = mirrored.corners(t);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0);
            assert!(
                n.normalize()
                    .dot(mirrored.normals[mirrored.triangles[t][0] as usize])
                    > 0.99
            );
        }
        assert!(
            cube.transformed(&Mat4::from_scale(Vec3::new(0.0, 1.0, 1.0)))
                .is_none()
        );
    }

    #[test]
    fn glossy_materials_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        let object = |extra: &str| {
            format!(
                "{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\nalbedo = [0.5, 0.4, 0.3]\n{extra}\n"
            )
        };
        let good = Scene::load(&write_scene(
            dir.path(),
            &object("specular = [0.5, 0.6, 0.7]\nshininess = 60"),
        ))
        .unwrap();
        assert_eq!(
            good.geometry.objects[0].material,
            Material::phong(Rgb::new(0.5, 0.6, 0.7), 60.0)
        );
        assert!(good.geometry.is_glossy() && good.geometry.material_hash().is_some());
        // The interreflection carries the lobe's energy: albedo + specular.
        assert!(
            good.geometry
                .reflected_albedo()
                .iter()
                .all(|a| (*a - Rgb::new(1.0, 1.0, 1.0)).abs().max_element() < 1e-6)
        );
        // The bake depends on the material, so the content hash does.
        let mut duller = good.geometry.clone();
        duller.objects[0].material.specular = Rgb::splat(0.1);
        assert_ne!(duller.content_hash(), good.geometry.content_hash());
        let mut diffuse = good.geometry.clone();
        diffuse.objects[0].material = Material::DIFFUSE;
        assert!(
            diffuse
                .reflected_albedo()
                .iter()
                .all(|a| *a == Rgb::new(0.5, 0.4, 0.3))
        );
        for (extra, needle) in [
            ("specular = [0.6, 0.1, 0.1]\nshininess = 60", "energy"),
            ("specular = [0.1, 0.1, 0.1]", "shininess"),
            ("shininess = 10", "specular"),
            ("specular = [0.1, 0.1, 0.1]\nshininess = 0", "shininess"),
            ("specular = [0.1, 0.1, 0.1]\nshininess = 1e6", "shininess"),
            ("specular = [-0.1, 0.1, 0.1]\nshininess = 8", "specular"),
        ] {
            let err = Scene::load(&write_scene(dir.path(), &object(extra)))
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("s.toml") && err.contains(needle),
                "{extra}: {err}"
            );
        }
    }

    #[test]
    fn metallic_roughness_materials_are_read_and_checked() {
        let dir = tempfile::tempdir().unwrap();
        let object = |extra: &str| {
            format!("{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\n{extra}\n")
        };
        let load = |extra: &str| Scene::load(&write_scene(dir.path(), &object(extra)));
        let metal = load("base_color = [0.9, 0.6, 0.3]\nmetallic = 1\nroughness = 0.4").unwrap();
        let o = &metal.geometry.objects[0];
        assert_eq!(o.material, Material::metallic_roughness(1.0, 0.4));
        assert_eq!(o.albedo, Rgb::new(0.9, 0.6, 0.3));
        assert!(!metal.geometry.is_lambertian() && metal.geometry.material_hash().is_some());
        // glTF's defaults for what is not given; its clamping (with a warning) for what is
        // out of range.
        let defaults = load("albedo = [0.5, 0.5, 0.5]\nroughness = 0.2").unwrap();
        assert_eq!(
            defaults.geometry.objects[0].material,
            Material::metallic_roughness(1.0, 0.2)
        );
        let clamped = load("base_color = [0.5, 0.5, 0.5]\nmetallic = -0.5\nroughness = 1.5");
        assert_eq!(
            clamped.unwrap().geometry.objects[0].material,
            Material::metallic_roughness(0.0, 1.0)
        );
        let mut rougher = metal.geometry.clone();
        rougher.objects[0].material = Material::metallic_roughness(1.0, 0.5);
        assert_ne!(rougher.content_hash(), metal.geometry.content_hash());
        for (extra, needle) in [
            (
                "base_color = [0.5, 0.5, 0.5]\nmetallic = nan",
                "not a number",
            ),
            (
                "base_color = [0.5, 0.5, 0.5]\nspecular = [0.1, 0.1, 0.1]\nshininess = 8",
                "not both",
            ),
            (
                "albedo = [0.5, 0.5, 0.5]\nbase_color = [0.5, 0.5, 0.5]",
                "not both",
            ),
            ("base_color = [1.5, 0.5, 0.5]", "[0, 1)"),
        ] {
            let err = load(extra).unwrap_err().to_string();
            assert!(
                err.contains("s.toml") && err.contains(needle),
                "{extra}: {err}"
            );
        }
    }

    #[test]
    fn content_hash_changes_with_albedo() {
        let cube = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [1, 1, 1], [false; 6]);
        let mut a = SceneMesh::default();
        a.push_object("a".into(), &cube, Rgb::splat(0.5));
        let mut b = SceneMesh::default();
        b.push_object("a".into(), &cube, Rgb::splat(0.6));
        assert_ne!(a.content_hash(), b.content_hash());
        assert_eq!(a.content_hash(), a.clone().content_hash());
    }
}
