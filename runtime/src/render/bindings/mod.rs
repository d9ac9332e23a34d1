//! Every bind group of `shaders/`, declared once by the names the WGSL gives its bindings.
//! Layouts and bind groups are built from these declarations, bind groups take their resources
//! by name, and a test checks each declaration against the WGSL (names, numbers, kinds), so a
//! binding that drifts fails the test suite instead of the driver.

use super::shaders::Shader;
use wgpu::{SamplerBindingType, ShaderStages as Stages, TextureViewDimension as Dim};

/// What a binding holds, as the Rust side declares it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Resource {
    Uniform,
    /// A uniform read at a dynamic offset, `size` bytes at a time.
    DynamicUniform {
        size: u64,
    },
    Storage {
        read_only: bool,
    },
    /// A float texture.
    Texture {
        dimension: Dim,
        filterable: bool,
    },
    DepthTexture {
        dimension: Dim,
    },
    Sampler(SamplerBindingType),
}

/// One binding: the WGSL variable's name, the stages that read it and what it holds. Its
/// number is its place in the group's list.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Binding {
    pub name: &'static str,
    pub stages: Stages,
    pub resource: Resource,
}

/// One bind group of a shader.
#[derive(Debug)]
pub(crate) struct BindGroupDecl {
    pub label: &'static str,
    pub shader: Shader,
    pub group: u32,
    pub bindings: &'static [Binding],
}

const fn binding(name: &'static str, stages: Stages, resource: Resource) -> Binding {
    Binding {
        name,
        stages,
        resource,
    }
}

const FRAGMENT: Stages = Stages::FRAGMENT;
const FLOAT_2D: Resource = Resource::Texture {
    dimension: Dim::D2,
    filterable: false,
};
const FILTERABLE_2D: Resource = Resource::Texture {
    dimension: Dim::D2,
    filterable: true,
};
const FILTERABLE_ARRAY: Resource = Resource::Texture {
    dimension: Dim::D2Array,
    filterable: true,
};
const FILTERING: Resource = Resource::Sampler(SamplerBindingType::Filtering);

/// `shaders/transfer.wgsl`: the per-vertex transfer pass.
pub(crate) const TRANSFER: BindGroupDecl = BindGroupDecl {
    label: "transfer",
    shader: Shader::Transfer,
    group: 0,
    bindings: &[
        binding("lighting", Stages::COMPUTE, Resource::Uniform),
        binding(
            "full_transfer",
            Stages::COMPUTE,
            Resource::Storage { read_only: true },
        ),
        binding(
            "indirect_transfer",
            Stages::COMPUTE,
            Resource::Storage { read_only: true },
        ),
        binding(
            "radiance",
            Stages::COMPUTE,
            Resource::Storage { read_only: false },
        ),
        binding(
            "indirect_radiance",
            Stages::COMPUTE,
            Resource::Storage { read_only: false },
        ),
    ],
};

/// `shaders/transfer_texels.wgsl`: the transfer pass drawn into textures (WebGL2).
pub(crate) const TRANSFER_TEXELS: BindGroupDecl = BindGroupDecl {
    label: "transfer texels",
    shader: Shader::TransferTexels,
    group: 0,
    bindings: &[
        binding("lighting", FRAGMENT, Resource::Uniform),
        binding("full_transfer", FRAGMENT, FLOAT_2D),
        binding("indirect_transfer", FRAGMENT, FLOAT_2D),
    ],
};

/// `shaders/geometry.wgsl`, group 0: the frame, the materials and the reflection maps.
pub(crate) const PRT_FRAME: BindGroupDecl = BindGroupDecl {
    label: "prt pass frame",
    shader: Shader::Geometry,
    group: 0,
    bindings: &[
        binding("frame", Stages::VERTEX_FRAGMENT, Resource::Uniform),
        binding("materials", FRAGMENT, Resource::Uniform),
        binding("reflection_maps", FRAGMENT, FILTERABLE_ARRAY),
        binding("reflection_sampler", FRAGMENT, FILTERING),
    ],
};

/// `shaders/geometry.wgsl`, group 1: an object's textures (albedo, normal map and emission,
/// sampled alike), the normal map's scale and the emission's factor.
pub(crate) const SURFACE_TEXTURES: BindGroupDecl = BindGroupDecl {
    label: "surface textures",
    shader: Shader::Geometry,
    group: 1,
    bindings: &[
        binding("albedo_texture", FRAGMENT, FILTERABLE_2D),
        binding("albedo_sampler", FRAGMENT, FILTERING),
        binding("normal_texture", FRAGMENT, FILTERABLE_2D),
        binding("emissive_texture", FRAGMENT, FILTERABLE_2D),
        binding("surface", FRAGMENT, Resource::Uniform),
    ],
};

/// Bytes of one shadow view (`ShadowView` in `shaders/shadow.wgsl`: a light's view-projection).
pub(crate) const SHADOW_VIEW_SIZE: u64 = 64;

/// `shaders/shadow.wgsl`: one light's view, at a dynamic offset.
pub(crate) const SHADOW_VIEW: BindGroupDecl = BindGroupDecl {
    label: "shadow view",
    shader: Shader::Shadow,
    group: 0,
    bindings: &[binding(
        "view",
        Stages::VERTEX,
        Resource::DynamicUniform {
            size: SHADOW_VIEW_SIZE,
        },
    )],
};

/// `shaders/lights.wgsl`: the G-buffer, the shadow maps and the environment.
pub(crate) const LIGHTS: BindGroupDecl = BindGroupDecl {
    label: "light pass",
    shader: Shader::Lights,
    group: 0,
    bindings: &[
        binding("frame", FRAGMENT, Resource::Uniform),
        binding("lights", FRAGMENT, Resource::Uniform),
        binding("depth_buffer", FRAGMENT, FLOAT_2D),
        binding("normal_buffer", FRAGMENT, FLOAT_2D),
        binding("albedo_buffer", FRAGMENT, FLOAT_2D),
        binding(
            "shadow_maps",
            FRAGMENT,
            Resource::DepthTexture {
                dimension: Dim::D2Array,
            },
        ),
        binding(
            "shadow_sampler",
            FRAGMENT,
            Resource::Sampler(SamplerBindingType::Comparison),
        ),
        binding("environment", FRAGMENT, FILTERABLE_2D),
        binding(
            "shadow_depths",
            FRAGMENT,
            Resource::Texture {
                dimension: Dim::D2Array,
                filterable: false,
            },
        ),
        binding("environment_sampler", FRAGMENT, FILTERING),
        binding("materials", FRAGMENT, Resource::Uniform),
    ],
};

/// Bytes of one prefilter job (`Job` in `shaders/prefilter.wgsl`).
pub(crate) const PREFILTER_JOB_SIZE: u64 = 32;

/// `shaders/prefilter.wgsl`: one face's job (at a dynamic offset) and the source cube.
pub(crate) const PREFILTER: BindGroupDecl = BindGroupDecl {
    label: "prefilter",
    shader: Shader::Prefilter,
    group: 0,
    bindings: &[
        binding(
            "job",
            FRAGMENT,
            Resource::DynamicUniform {
                size: PREFILTER_JOB_SIZE,
            },
        ),
        binding("source", FRAGMENT, FILTERABLE_ARRAY),
        binding("source_sampler", FRAGMENT, FILTERING),
    ],
};

/// `shaders/display.wgsl`: tone mapping the renderer's image to a window.
pub(crate) const DISPLAY: BindGroupDecl = BindGroupDecl {
    label: "display",
    shader: Shader::Display,
    group: 0,
    bindings: &[
        binding("display", FRAGMENT, Resource::Uniform),
        binding("image", FRAGMENT, FLOAT_2D),
    ],
};

/// `shaders/composite_floor.wgsl`: the composite (B's luminance in its alpha), and the sums of
/// the ratio's floor.
pub(crate) const COMPOSITE_FLOOR: BindGroupDecl = BindGroupDecl {
    label: "composite floor",
    shader: Shader::CompositeFloor,
    group: 0,
    bindings: &[
        binding(
            "composite_image",
            Stages::COMPUTE,
            Resource::Texture {
                dimension: Dim::D2,
                filterable: false,
            },
        ),
        binding(
            "sums",
            Stages::COMPUTE,
            Resource::Storage { read_only: false },
        ),
    ],
};

/// `shaders/composite.wgsl` (part of the light pass), group 1: the live composite's inputs.
pub(crate) const COMPOSITE: BindGroupDecl = BindGroupDecl {
    label: "composite",
    shader: Shader::Lights,
    group: 1,
    bindings: &[
        binding("backplate", FRAGMENT, Resource::Uniform),
        binding("with_objects", FRAGMENT, FLOAT_2D),
        binding("without_objects", FRAGMENT, FLOAT_2D),
        binding("photograph", FRAGMENT, FILTERABLE_2D),
        binding("photograph_sampler", FRAGMENT, FILTERING),
        binding("floor_sums", FRAGMENT, Resource::Uniform),
    ],
};

/// `shaders/wireframe.wgsl`: the frame's camera.
pub(crate) const WIREFRAME: BindGroupDecl = BindGroupDecl {
    label: "wireframe",
    shader: Shader::Wireframe,
    group: 0,
    bindings: &[binding("frame", Stages::VERTEX, Resource::Uniform)],
};

/// Every declaration, for the test against the WGSL.
#[cfg(test)]
pub(crate) const ALL: [&BindGroupDecl; 11] = [
    &TRANSFER,
    &TRANSFER_TEXELS,
    &PRT_FRAME,
    &SURFACE_TEXTURES,
    &SHADOW_VIEW,
    &LIGHTS,
    &PREFILTER,
    &DISPLAY,
    &COMPOSITE_FLOOR,
    &COMPOSITE,
    &WIREFRAME,
];

impl Resource {
    fn binding_type(self) -> wgpu::BindingType {
        use wgpu::{BindingType, BufferBindingType, TextureSampleType};
        let buffer = |ty, has_dynamic_offset, min_binding_size| BindingType::Buffer {
            ty,
            has_dynamic_offset,
            min_binding_size,
        };
        let texture = |sample_type, view_dimension| BindingType::Texture {
            sample_type,
            view_dimension,
            multisampled: false,
        };
        match self {
            Resource::Uniform => buffer(BufferBindingType::Uniform, false, None),
            Resource::DynamicUniform { size } => buffer(
                BufferBindingType::Uniform,
                true,
                wgpu::BufferSize::new(size),
            ),
            Resource::Storage { read_only } => {
                buffer(BufferBindingType::Storage { read_only }, false, None)
            }
            Resource::Texture {
                dimension,
                filterable,
            } => texture(TextureSampleType::Float { filterable }, dimension),
            Resource::DepthTexture { dimension } => texture(TextureSampleType::Depth, dimension),
            Resource::Sampler(ty) => BindingType::Sampler(ty),
        }
    }
}

impl BindGroupDecl {
    /// The group's layout: binding `k` is the `k`-th declared.
    pub(crate) fn layout(&self, device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let entries: Vec<wgpu::BindGroupLayoutEntry> = self
            .bindings
            .iter()
            .enumerate()
            .map(|(k, b)| wgpu::BindGroupLayoutEntry {
                binding: k as u32,
                visibility: b.stages,
                ty: b.resource.binding_type(),
                count: None,
            })
            .collect();
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(self.label),
            entries: &entries,
        })
    }

    /// A bind group of `layout` (made by [`Self::layout`]) from resources given by their
    /// bindings' names, in the declared order.
    pub(crate) fn bind_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        resources: &[(&str, wgpu::BindingResource)],
    ) -> wgpu::BindGroup {
        let declared: Vec<&str> = self.bindings.iter().map(|b| b.name).collect();
        let given: Vec<&str> = resources.iter().map(|(name, _)| *name).collect();
        assert_eq!(
            given, declared,
            "{} ({:?}, group {}): resources against the declaration",
            self.label, self.shader, self.group
        );
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .iter()
            .enumerate()
            .map(|(k, (_, resource))| wgpu::BindGroupEntry {
                binding: k as u32,
                resource: resource.clone(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout,
            entries: &entries,
        })
    }
}

#[cfg(test)]
mod tests;
