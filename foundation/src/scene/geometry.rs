//! The assembled scene: every object's triangles in one world-space mesh, with per-vertex
//! albedo, the objects' ranges, textures and materials.

use crate::color::Rgb;
use crate::material::metallic_roughness::{MetallicRoughness, hemispherical_split_sum};
use crate::material::{Layer, Material};
use crate::mesh::TriangleMesh;
use crate::scene::ObjectRole;
use crate::texture::{AlbedoTexture, Emission, NormalMap};
use std::sync::Arc;

/// A named part of the scene mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneObject {
    pub name: String,
    /// The albedo, or for a textured object the factor its texture is multiplied by.
    pub albedo: Rgb,
    pub vertices: std::ops::Range<u32>,
    pub triangles: std::ops::Range<u32>,
    /// Index into [`SceneMesh::textures`] of its base colour texture.
    pub texture: Option<usize>,
    /// Index into [`SceneMesh::normal_maps`] of its normal map (the mesh then has tangents).
    pub normal_map: Option<usize>,
    /// Index into [`SceneMesh::emissions`] of the light it emits.
    pub emission: Option<usize>,
    /// Its specular lobe, if glossy (the albedo above is its diffuse `k_d`).
    pub material: Material,
    /// A virtual object, or a proxy of a real surface.
    pub role: ObjectRole,
}

/// Marks a triangle without a texture in [`SceneMesh::triangle_textures`].
pub const NO_TEXTURE: u32 = u32::MAX;

/// All objects merged into one world-space mesh, with a per-vertex albedo.
#[derive(Debug, Clone, Default)]
pub struct SceneMesh {
    /// World-space geometry; its texture coordinates are empty unless an object is textured.
    pub mesh: TriangleMesh,
    /// Per vertex: its object's albedo, or for a textured object the factor its texture is
    /// multiplied by (the bake's transfer is then per unit texel value: CONVENTIONS.md,
    /// "Textured albedo").
    pub albedo: Vec<Rgb>,
    pub objects: Vec<SceneObject>,
    /// Base colour textures of the textured objects.
    pub textures: Vec<Arc<AlbedoTexture>>,
    /// Normal maps of the normal-mapped objects. The bake does not read them (CONVENTIONS.md,
    /// "Normal maps"), so they are not in [`Self::content_hash`].
    pub normal_maps: Vec<NormalMap>,
    /// What the emitting objects emit. The bake does not carry their light to other surfaces
    /// (CONVENTIONS.md, "Emission"), so they are not in [`Self::content_hash`].
    pub emissions: Vec<Emission>,
}

impl SceneMesh {
    /// BLAKE3 hash of everything a bake depends on: positions, normals, triangles, albedos,
    /// textures and glossy materials.
    pub fn content_hash(&self) -> [u8; 32] {
        let mut hasher = blake3::Hasher::new();
        hasher.update(b"hprt scene mesh v1");
        hasher.update(&(self.mesh.positions.len() as u64).to_le_bytes());
        hasher.update(&(self.mesh.triangles.len() as u64).to_le_bytes());
        for v in self
            .mesh
            .positions
            .iter()
            .chain(&self.mesh.normals)
            .chain(&self.albedo)
        {
            for c in v.to_array() {
                hasher.update(&c.to_le_bytes());
            }
        }
        for t in &self.mesh.triangles {
            for i in t {
                hasher.update(&i.to_le_bytes());
            }
        }
        // Textures count only where there are some, so untextured scenes keep their hashes
        // (and their cached bakes).
        if !self.textures.is_empty() {
            hasher.update(b"textured");
            for uv in &self.mesh.uvs {
                hasher.update(&uv.x.to_le_bytes());
                hasher.update(&uv.y.to_le_bytes());
            }
            for o in &self.objects {
                hasher.update(&o.texture.map_or(u64::MAX, |t| t as u64).to_le_bytes());
            }
            for t in &self.textures {
                hasher.update(&(t.width as u64).to_le_bytes());
                hasher.update(&(t.height as u64).to_le_bytes());
                for texel in &t.texels {
                    for c in texel.to_array() {
                        hasher.update(&c.to_le_bytes());
                    }
                }
            }
        }
        // Glossy objects reflect their specular energy in the interreflection; diffuse scenes
        // keep their hashes.
        if let Some(materials) = self.material_hash() {
            hasher.update(&materials);
        }
        *hasher.finalize().as_bytes()
    }

    /// Length of the bounding-box diagonal (the scale for ray epsilons).
    pub fn diagonal(&self) -> f32 {
        self.mesh
            .bounds()
            .map(|(lo, hi)| (hi - lo).length())
            .unwrap_or(1.0)
    }

    /// Adds `mesh` (already in world space) as a new object.
    pub fn push_object(&mut self, name: String, mesh: &TriangleMesh, albedo: Rgb) {
        let v0 = self.mesh.vertex_count() as u32;
        let t0 = self.mesh.triangle_count() as u32;
        self.mesh.append(mesh);
        self.albedo
            .extend(std::iter::repeat_n(albedo, mesh.vertex_count()));
        self.objects.push(SceneObject {
            name,
            albedo,
            vertices: v0..self.mesh.vertex_count() as u32,
            triangles: t0..self.mesh.triangle_count() as u32,
            texture: None,
            normal_map: None,
            emission: None,
            material: Material::DIFFUSE,
            role: ObjectRole::Object,
        });
    }

    /// Makes the last object pushed emit `emission`.
    pub fn set_emission(&mut self, emission: Emission) {
        let index = match self.emissions.iter().position(|e| *e == emission) {
            Some(i) => i,
            None => {
                self.emissions.push(emission);
                self.emissions.len() - 1
            }
        };
        if let Some(object) = self.objects.last_mut() {
            object.emission = Some(index);
        }
    }

    /// Gives the last object pushed `map` (its mesh must have had tangents).
    pub fn set_normal_map(&mut self, map: NormalMap) {
        debug_assert!(self.mesh.tangents.len() == self.mesh.vertex_count());
        let index = match self.normal_maps.iter().position(|m| {
            Arc::ptr_eq(&m.texture, &map.texture) && m.scale.to_bits() == map.scale.to_bits()
        }) {
            Some(i) => i,
            None => {
                self.normal_maps.push(map);
                self.normal_maps.len() - 1
            }
        };
        if let Some(object) = self.objects.last_mut() {
            object.normal_map = Some(index);
        }
    }

    /// Adds `mesh` (world space, with texture coordinates) whose albedo is `factor` times
    /// `texture` looked up at each point.
    pub fn push_textured_object(
        &mut self,
        name: String,
        mesh: &TriangleMesh,
        factor: Rgb,
        texture: Arc<AlbedoTexture>,
    ) {
        debug_assert_eq!(mesh.uvs.len(), mesh.vertex_count());
        let index = match self.textures.iter().position(|t| Arc::ptr_eq(t, &texture)) {
            Some(i) => i,
            None => {
                self.textures.push(texture);
                self.textures.len() - 1
            }
        };
        self.push_object(name, mesh, factor);
        if let Some(object) = self.objects.last_mut() {
            object.texture = Some(index);
        }
    }

    /// Per triangle, its object's role.
    pub fn triangle_roles(&self) -> Vec<ObjectRole> {
        let mut out = vec![ObjectRole::Object; self.mesh.triangle_count()];
        for o in &self.objects {
            out[o.triangles.start as usize..o.triangles.end as usize].fill(o.role);
        }
        out
    }

    /// Whether any object is a proxy of a real surface.
    pub fn has_proxies(&self) -> bool {
        self.objects.iter().any(|o| o.role == ObjectRole::Proxy)
    }

    /// The objects of `role` alone (the room's proxies, the virtual objects), as
    /// [`Self::subset`] keeps them.
    pub fn of_role(&self, role: ObjectRole) -> SceneMesh {
        self.subset(|o| o.role == role)
    }

    /// The objects `keep` accepts, as a scene mesh of their own (their names, albedos,
    /// textures, materials and roles kept; triangles in the same order).
    pub fn subset(&self, keep: impl Fn(&SceneObject) -> bool) -> SceneMesh {
        let mut out = SceneMesh::default();
        for o in self.objects.iter().filter(|o| keep(o)) {
            let (v0, v1) = (o.vertices.start as usize, o.vertices.end as usize);
            let part = TriangleMesh {
                positions: self.mesh.positions[v0..v1].to_vec(),
                normals: self.mesh.normals[v0..v1].to_vec(),
                triangles: self.mesh.triangles
                    [o.triangles.start as usize..o.triangles.end as usize]
                    .iter()
                    .map(|t| t.map(|i| i - o.vertices.start))
                    .collect(),
                uvs: match self.mesh.uvs.is_empty() {
                    true => Vec::new(),
                    false => self.mesh.uvs[v0..v1].to_vec(),
                },
                tangents: match o.normal_map {
                    None => Vec::new(),
                    Some(_) => self.mesh.tangents[v0..v1].to_vec(),
                },
            };
            match o.texture {
                Some(t) => out.push_textured_object(
                    o.name.clone(),
                    &part,
                    o.albedo,
                    self.textures[t].clone(),
                ),
                None => out.push_object(o.name.clone(), &part, o.albedo),
            }
            if let Some(map) = o.normal_map {
                out.set_normal_map(self.normal_maps[map].clone());
            }
            if let Some(e) = o.emission {
                out.set_emission(self.emissions[e].clone());
            }
            if let Some(last) = out.objects.last_mut() {
                last.material = o.material;
                last.role = o.role;
            }
        }
        out
    }

    /// Moves the virtual objects (not the proxies) by `offset`.
    /// Collapses the virtual objects (not the proxies) to `point`: their triangles lose their
    /// area and no ray meets them, while every vertex keeps its index. A bake of the scene so
    /// collapsed is the proxies' without the objects, with the same samples per vertex as a
    /// bake with them.
    pub fn collapse_objects(&mut self, point: glam::Vec3) {
        for o in self.objects.iter().filter(|o| o.role == ObjectRole::Object) {
            let range = o.vertices.start as usize..o.vertices.end as usize;
            self.mesh.positions[range].fill(point);
        }
    }

    pub fn move_objects(&mut self, offset: glam::Vec3) {
        for o in self.objects.iter().filter(|o| o.role == ObjectRole::Object) {
            let range = o.vertices.start as usize..o.vertices.end as usize;
            for p in &mut self.mesh.positions[range] {
                *p += offset;
            }
        }
    }

    /// Puts the objects, placed by the scene with their centre at `rest_centre`, at `pose`:
    /// turned about that centre, then moved so that it is at the pose's.
    pub fn pose_objects(&mut self, rest_centre: glam::Vec3, pose: super::Pose) {
        let rotation = pose.rotation.normalize();
        for o in self.objects.iter().filter(|o| o.role == ObjectRole::Object) {
            let range = o.vertices.start as usize..o.vertices.end as usize;
            for p in &mut self.mesh.positions[range.clone()] {
                *p = pose.centre + rotation * (*p - rest_centre);
            }
            for n in &mut self.mesh.normals[range] {
                *n = (rotation * *n).normalize_or_zero();
            }
        }
    }

    /// Whether any object reflects view-dependently (a Phong lobe or a metallic-roughness
    /// layer): the renderer then prefilters reflection maps, reports measure highlights.
    pub fn is_glossy(&self) -> bool {
        !self.is_lambertian()
    }

    /// Per triangle, its object's material.
    pub fn triangle_materials(&self) -> Vec<Material> {
        let mut out = vec![Material::DIFFUSE; self.mesh.triangle_count()];
        for o in &self.objects {
            out[o.triangles.start as usize..o.triangles.end as usize].fill(o.material);
        }
        out
    }

    /// Whether every object is Lambertian (no lobe, no layer).
    pub fn is_lambertian(&self) -> bool {
        self.objects.iter().all(|o| o.material.is_lambertian())
    }

    /// BLAKE3 hash of the objects' materials where any is not Lambertian (part of
    /// [`Self::content_hash`]); `None` for a diffuse scene.
    pub(crate) fn material_hash(&self) -> Option<[u8; 32]> {
        if self.is_lambertian() {
            return None;
        }
        let mut hasher = blake3::Hasher::new();
        hasher.update(b"hprt materials v1");
        for o in &self.objects {
            hasher.update(&o.triangles.start.to_le_bytes());
            for c in o.material.specular.to_array() {
                hasher.update(&c.to_le_bytes());
            }
            hasher.update(&o.material.shininess.to_le_bytes());
            // Only layered objects add bytes: the hashes of Phong scenes stay as they were.
            if let Some(layer) = o.material.layer {
                hasher.update(b"layer");
                hasher.update(&layer.metallic.to_le_bytes());
                hasher.update(&layer.roughness.to_le_bytes());
            }
        }
        Some(*hasher.finalize().as_bytes())
    }

    /// Whether any object is textured.
    pub fn is_textured(&self) -> bool {
        !self.textures.is_empty()
    }

    /// Per triangle, the index of its texture, or [`NO_TEXTURE`].
    pub fn triangle_textures(&self) -> Vec<u32> {
        self.per_triangle(|o| o.texture)
    }

    /// Per triangle, the index of its normal map in [`Self::normal_maps`], or [`NO_TEXTURE`].
    pub fn triangle_normal_maps(&self) -> Vec<u32> {
        self.per_triangle(|o| o.normal_map)
    }

    /// Per triangle, the index of its emission in [`Self::emissions`], or [`NO_TEXTURE`].
    pub fn triangle_emissions(&self) -> Vec<u32> {
        self.per_triangle(|o| o.emission)
    }

    fn per_triangle(&self, index: impl Fn(&SceneObject) -> Option<usize>) -> Vec<u32> {
        let mut out = vec![NO_TEXTURE; self.mesh.triangle_count()];
        for o in &self.objects {
            if let Some(t) = index(o) {
                out[o.triangles.start as usize..o.triangles.end as usize].fill(t as u32);
            }
        }
        out
    }

    /// Per vertex, the albedo it reflects toward other surfaces in the bake's interreflection:
    /// its object's albedo, or for a textured object the factor times the texture averaged
    /// around the vertex ([`crate::texture::vertex_average`]); a glossy object adds its
    /// specular reflectance, reflected as if diffusely (its lobe's energy reaches the other
    /// surfaces; its direction does not: CONVENTIONS.md, "Glossy materials"); a layered one
    /// reflects its layer's hemispherical albedo and the base under it ([`layered_albedo`]).
    pub fn reflected_albedo(&self) -> Vec<Rgb> {
        let mut albedo = self.albedo.clone();
        for o in &self.objects {
            let Some(t) = o.texture else { continue };
            let (v0, v1) = (o.vertices.start as usize, o.vertices.end as usize);
            let local: Vec<[u32; 3]> = self.mesh.triangles
                [o.triangles.start as usize..o.triangles.end as usize]
                .iter()
                .map(|tri| tri.map(|i| i - v0 as u32))
                .collect();
            let averages =
                crate::texture::vertex_average(&self.textures[t], &self.mesh.uvs[v0..v1], &local);
            for (a, avg) in albedo[v0..v1].iter_mut().zip(averages) {
                *a *= avg;
            }
        }
        for o in self.objects.iter().filter(|o| o.material.is_glossy()) {
            for a in &mut albedo[o.vertices.start as usize..o.vertices.end as usize] {
                *a += o.material.specular;
            }
        }
        for o in &self.objects {
            let Some(layer) = o.material.layer else {
                continue;
            };
            let (a, b) = hemispherical_split_sum(layer.roughness, 16, 256);
            for base in &mut albedo[o.vertices.start as usize..o.vertices.end as usize] {
                *base = layered_albedo(*base, layer, (a, b));
            }
        }
        albedo
    }
}

/// What a metallic-roughness surface of base colour `base` reflects in all, over every view
/// (cosine-weighted): its layer's hemispherical albedo `E = F₀ A + B` and the base under it,
/// `c_diff (1 − E)` (as the renderer splits them: CONVENTIONS.md, "Metallic-roughness
/// materials"). `terms`: the layer's [`hemispherical_split_sum`].
fn layered_albedo(base: Rgb, layer: Layer, terms: (f32, f32)) -> Rgb {
    let material = MetallicRoughness {
        base_color: base,
        metallic: layer.metallic,
        roughness: layer.roughness,
    };
    let (diffuse, f0) = material.diffuse_and_f0();
    let specular = f0 * terms.0 + Rgb::splat(terms.1);
    diffuse * (Rgb::ONE - specular) + specular
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::box_mesh;
    use crate::scene::Pose;
    use glam::{Quat, Vec3};

    /// A posed object is turned about its rest centre and moved there, normals turned with
    /// it; the proxies stay.
    #[test]
    fn posing_turns_the_objects_about_their_centre() {
        let mut geometry = SceneMesh::default();
        let model = box_mesh(
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(3.0, 1.0, 1.0),
            [1; 3],
            [false; 6],
        );
        geometry.push_object("model".into(), &model, Rgb::splat(0.5));
        let floor = box_mesh(
            Vec3::splat(-5.0),
            Vec3::new(5.0, -4.0, 5.0),
            [1; 3],
            [false; 6],
        );
        geometry.push_object("floor".into(), &floor, Rgb::splat(0.5));
        geometry.objects[1].role = ObjectRole::Proxy;
        let rest = geometry.clone();
        let centre = Vec3::new(2.0, 0.5, 0.5);
        let pose = Pose {
            centre: Vec3::new(0.0, 0.5, 0.0),
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
        };
        geometry.pose_objects(centre, pose);
        let (lo, hi) = geometry.of_role(ObjectRole::Object).mesh.bounds().unwrap();
        // 2 × 1 × 1 along x turns into 1 × 1 × 2 along z, about the new centre.
        assert!(lo.distance(Vec3::new(-0.5, 0.0, -1.0)) < 1e-5, "{lo}");
        assert!(hi.distance(Vec3::new(0.5, 1.0, 1.0)) < 1e-5, "{hi}");
        for v in 0..model.vertex_count() {
            let turned = pose.rotation * rest.mesh.normals[v];
            assert!(geometry.mesh.normals[v].distance(turned) < 1e-6);
        }
        let proxies = model.vertex_count()..geometry.mesh.vertex_count();
        assert_eq!(
            geometry.mesh.positions[proxies.clone()],
            rest.mesh.positions[proxies]
        );
    }

    /// A layered object reflects to other surfaces what its layer and base do over every
    /// view: a white dielectric everything (the layer takes from the base what it reflects),
    /// a smooth metal the hemispherical mean of Schlick's Fresnel, `F₀ + (1 − F₀)/21`, a
    /// black dielectric that of `F₀ = 0.04`.
    #[test]
    fn layered_objects_reflect_their_hemispherical_albedo() {
        let cases = [
            (Rgb::ONE, 0.0, 0.6, 1.0),
            (Rgb::splat(0.9), 1.0, 0.1, 0.9 + 0.1 / 21.0),
            (Rgb::ZERO, 0.0, 0.1, 0.04 + 0.96 / 21.0),
        ];
        for (base, metallic, roughness, want) in cases {
            let mut geometry = SceneMesh::default();
            let cube = box_mesh(Vec3::ZERO, Vec3::ONE, [1; 3], [false; 6]);
            geometry.push_object("cube".into(), &cube, base);
            geometry.objects[0].material = Material::metallic_roughness(metallic, roughness);
            for a in geometry.reflected_albedo() {
                assert!(
                    (a - Rgb::splat(want)).abs().max_element() < 0.005 * want,
                    "base {base}, metallic {metallic}, roughness {roughness}: {a} vs {want}"
                );
            }
        }
    }
}
