//! Glossy materials on the GPU: a uniform table of the scene's distinct specular lobes and
//! metallic-roughness layers (entry 0 the diffuse one) with the layer's split-sum table, a
//! per-vertex index into it with the vertex's specular occlusion, and the shininess slots the
//! reflection maps are prefiltered for (`shaders/glossy.wgsl`; a layer's slot is its
//! roughness's [`equivalent_shininess`]).

use super::error::RenderError;
use super::pass_helpers::writable_buffer;
use super::shaders::{MAX_MATERIALS, SPLIT_SUM_SIZE};
use bytemuck::{Pod, Zeroable};
use foundation::material::Material;
use foundation::material::metallic_roughness::{SplitSumTable, equivalent_shininess};
use foundation::scene::SceneMesh;
use foundation::settings::{InvalidSettings, SettingsProblem};
use wgpu::util::DeviceExt;

/// Matches `Material` in `shaders/glossy.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct MaterialUniform {
    specular: [f32; 4],
    slot: [u32; 4],
    layer: [f32; 4],
}

/// Visible normals per texel of the table.
const SPLIT_SUM_SAMPLES: u32 = 512;

/// Matches `Materials` in `shaders/glossy.wgsl`: the entries, then the split-sum table, two
/// texels `(A, B)` per vector.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct MaterialsUniform {
    entries: [MaterialUniform; MAX_MATERIALS],
    split_sum: [[f32; 4]; SPLIT_SUM_SIZE * SPLIT_SUM_SIZE / 2],
}

/// The split-sum table, made once per process (a few milliseconds).
fn split_sum_texels() -> &'static [[f32; 4]; SPLIT_SUM_SIZE * SPLIT_SUM_SIZE / 2] {
    static TABLE: std::sync::OnceLock<[[f32; 4]; SPLIT_SUM_SIZE * SPLIT_SUM_SIZE / 2]> =
        std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let table = SplitSumTable::new(SPLIT_SUM_SIZE, SPLIT_SUM_SAMPLES);
        let mut out = [[0.0; 4]; SPLIT_SUM_SIZE * SPLIT_SUM_SIZE / 2];
        for (k, pair) in out.iter_mut().enumerate() {
            for (half, texel) in [2 * k, 2 * k + 1].into_iter().enumerate() {
                let [a, b] = table.texel(texel % SPLIT_SUM_SIZE, texel / SPLIT_SUM_SIZE);
                pair[2 * half] = a;
                pair[2 * half + 1] = b;
            }
        }
        out
    })
}

/// The reflection-map shininess of a material with a lobe or a layer.
fn slot_shininess(m: &Material) -> f32 {
    match m.layer {
        Some(layer) => equivalent_shininess(layer.roughness),
        None => m.shininess,
    }
}

/// Per vertex: its material's index and its visibility cone.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MaterialVertex {
    index: u32,
    visibility: [f32; 4],
}

pub(crate) const MATERIAL_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<MaterialVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![5 => Uint32, 6 => Float32x4],
};

/// The distinct glossy materials of a set of objects, and each object's index (0: diffuse).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MaterialTable {
    /// Distinct glossy and layered materials; table entry `i + 1`.
    pub glossy: Vec<Material>,
    /// Per object, its entry.
    pub object_entries: Vec<u32>,
    /// Distinct shininess values: the reflection maps' slots.
    pub shininess: Vec<f32>,
}

impl MaterialTable {
    pub(crate) fn new(materials: &[Material]) -> Result<Self, InvalidSettings> {
        let mut glossy: Vec<Material> = Vec::new();
        let mut shininess: Vec<f32> = Vec::new();
        let mut object_entries = Vec::with_capacity(materials.len());
        for m in materials {
            if m.is_lambertian() {
                object_entries.push(0);
                continue;
            }
            let i = match glossy.iter().position(|g| g == m) {
                Some(i) => i,
                None => {
                    glossy.push(*m);
                    glossy.len() - 1
                }
            };
            let s = slot_shininess(m);
            if !shininess.contains(&s) {
                shininess.push(s);
            }
            object_entries.push(i as u32 + 1);
        }
        if glossy.len() >= MAX_MATERIALS {
            return Err(InvalidSettings::new(
                "materials",
                SettingsProblem::TooManyGlossyMaterials {
                    count: glossy.len(),
                    max: MAX_MATERIALS - 1,
                },
            ));
        }
        Ok(Self {
            glossy,
            object_entries,
            shininess,
        })
    }

    /// Each entry: `k_s` and the slot's shininess (its lobe's width in the specular
    /// occlusion), the slot, and for a layer (metallic, roughness, 1).
    fn uniform(&self) -> MaterialsUniform {
        let mut out = MaterialsUniform {
            entries: [MaterialUniform::zeroed(); MAX_MATERIALS],
            split_sum: *split_sum_texels(),
        };
        for (entry, m) in out.entries[1..].iter_mut().zip(&self.glossy) {
            let shininess = slot_shininess(m);
            let slot = self
                .shininess
                .iter()
                .position(|s| *s == shininess)
                .unwrap_or(0);
            let layer = m
                .layer
                .map_or([0.0; 4], |l| [l.metallic, l.roughness, 1.0, 0.0]);
            *entry = MaterialUniform {
                specular: m.specular.extend(shininess).to_array(),
                slot: [slot as u32, 0, 0, 0],
                layer,
            };
        }
        out
    }
}

/// The table and the per-vertex buffer on the GPU.
pub(crate) struct GpuMaterials {
    pub uniform: wgpu::Buffer,
    pub vertex_buffer: wgpu::Buffer,
    pub table: MaterialTable,
    /// Per vertex: its object and visibility (to rewrite indices when materials change).
    vertex_objects: Vec<u32>,
    visibility: Vec<[f32; 4]>,
}

impl GpuMaterials {
    /// `visibility`: per vertex, its bent normal (xyz) and unoccluded fraction (w) from the
    /// bake: the cone of directions it sees the sky in (`shaders/geometry.wgsl`).
    pub(crate) fn new(
        device: &wgpu::Device,
        geometry: &SceneMesh,
        visibility: Vec<[f32; 4]>,
    ) -> Result<Self, RenderError> {
        let materials: Vec<Material> = geometry.objects.iter().map(|o| o.material).collect();
        let table = MaterialTable::new(&materials)?;
        let mut vertex_objects = vec![0u32; geometry.mesh.vertex_count()];
        for (i, o) in geometry.objects.iter().enumerate() {
            vertex_objects[o.vertices.start as usize..o.vertices.end as usize].fill(i as u32);
        }
        let uniform = writable_buffer(
            device,
            "materials",
            std::mem::size_of::<MaterialsUniform>(),
            wgpu::BufferUsages::UNIFORM,
        );
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertex materials"),
            contents: bytemuck::cast_slice(&vertices(&table, &vertex_objects, &visibility)),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        Ok(Self {
            uniform,
            vertex_buffer,
            table,
            vertex_objects,
            visibility,
        })
    }

    /// Uploads the table (call once after [`Self::new`] and after every change).
    pub(crate) fn write(&self, queue: &wgpu::Queue) {
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&self.table.uniform()));
    }

    /// Takes each vertex's new bent normal and unoccluded fraction (a turned object's).
    pub(crate) fn set_visibility(&mut self, queue: &wgpu::Queue, visibility: Vec<[f32; 4]>) {
        self.visibility = visibility;
        let data = vertices(&self.table, &self.vertex_objects, &self.visibility);
        queue.write_buffer(&self.vertex_buffer, 0, bytemuck::cast_slice(&data));
    }

    /// Gives the objects new materials (one per object); returns whether the shininess
    /// slots changed (the reflection maps must be prefiltered again).
    pub(crate) fn set(
        &mut self,
        queue: &wgpu::Queue,
        materials: &[Material],
    ) -> Result<bool, RenderError> {
        let table = MaterialTable::new(materials)?;
        let slots_changed = table.shininess != self.table.shininess;
        if table.object_entries != self.table.object_entries {
            let data = vertices(&table, &self.vertex_objects, &self.visibility);
            queue.write_buffer(&self.vertex_buffer, 0, bytemuck::cast_slice(&data));
        }
        self.table = table;
        self.write(queue);
        Ok(slots_changed)
    }
}

fn vertices(
    table: &MaterialTable,
    objects: &[u32],
    visibility: &[[f32; 4]],
) -> Vec<MaterialVertex> {
    objects
        .iter()
        .zip(visibility)
        .map(|(o, visibility)| MaterialVertex {
            index: table.object_entries.get(*o as usize).copied().unwrap_or(0),
            visibility: *visibility,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::Rgb;

    #[test]
    fn distinct_materials_share_entries_and_slots() {
        let a = Material::phong(Rgb::splat(0.2), 60.0);
        let b = Material::phong(Rgb::splat(0.4), 60.0);
        let c = Material::phong(Rgb::splat(0.2), 10.0);
        let table = MaterialTable::new(&[a, Material::DIFFUSE, b, a, c]).unwrap();
        assert_eq!(table.object_entries, [1, 0, 2, 1, 3]);
        assert_eq!(table.shininess, [60.0, 10.0]);
        let uniform = table.uniform().entries;
        assert_eq!(uniform[2].specular, [0.4, 0.4, 0.4, 60.0]);
        assert_eq!(uniform[3].slot[0], 1);
        assert_eq!(uniform[0].specular, [0.0; 4]);
        assert_eq!(uniform[1].layer, [0.0; 4]);
        let many: Vec<Material> = (0..MAX_MATERIALS)
            .map(|i| Material::phong(Rgb::splat(0.1), 1.0 + i as f32))
            .collect();
        assert!(MaterialTable::new(&many).is_err());
    }

    /// Layers take entries and slots as lobes do, their slot the roughness's equivalent
    /// shininess; the table carries the split-sum terms, texel by texel.
    #[test]
    fn layers_have_entries_slots_and_the_split_sum_table() {
        let copper = Material::metallic_roughness(1.0, 0.5);
        let table = MaterialTable::new(&[Material::DIFFUSE, copper, copper]).unwrap();
        assert_eq!(table.object_entries, [0, 1, 1]);
        assert_eq!(table.shininess, [equivalent_shininess(0.5)]);
        let uniform = table.uniform();
        assert_eq!(uniform.entries[1].layer, [1.0, 0.5, 1.0, 0.0]);
        assert_eq!(uniform.entries[1].specular[..3], [0.0; 3]);
        let reference = SplitSumTable::new(SPLIT_SUM_SIZE, SPLIT_SUM_SAMPLES);
        let (i, j) = (5, 17);
        let texel = j * SPLIT_SUM_SIZE + i;
        let pair = uniform.split_sum[texel / 2];
        let got = [pair[2 * (texel % 2)], pair[2 * (texel % 2) + 1]];
        assert_eq!(got, reference.texel(i, j));
    }
}
