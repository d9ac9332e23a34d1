use super::*;
use naga::{AddressSpace, ImageClass, ImageDimension, ScalarKind, StorageAccess, TypeInner};

fn module(shader: Shader) -> naga::Module {
    naga::front::wgsl::parse_str(&shader.source()).expect("the shaders parse (shaders.rs)")
}

/// Whether the WGSL variable `var` holds what `resource` declares.
fn holds(module: &naga::Module, var: &naga::GlobalVariable, resource: Resource) -> bool {
    let image = |dimension: Dim| match dimension {
        Dim::D2 => (ImageDimension::D2, false),
        Dim::D2Array => (ImageDimension::D2, true),
        Dim::Cube => (ImageDimension::Cube, false),
        _ => (ImageDimension::D3, false),
    };
    let inner = &module.types[var.ty].inner;
    match resource {
        Resource::Uniform | Resource::DynamicUniform { .. } => var.space == AddressSpace::Uniform,
        Resource::Storage { read_only } => matches!(var.space,
            AddressSpace::Storage { access } if access.contains(StorageAccess::STORE) != read_only),
        Resource::Texture { dimension, .. } => matches!(*inner,
            TypeInner::Image { dim, arrayed, class: ImageClass::Sampled { kind: ScalarKind::Float, multi: false } }
                if (dim, arrayed) == image(dimension)),
        Resource::DepthTexture { dimension } => matches!(*inner,
            TypeInner::Image { dim, arrayed, class: ImageClass::Depth { multi: false } }
                if (dim, arrayed) == image(dimension)),
        Resource::Sampler(ty) => matches!(*inner,
            TypeInner::Sampler { comparison } if comparison == (ty == SamplerBindingType::Comparison)),
    }
}

/// Every declared group is exactly its shader's: the same names at the same numbers, each
/// holding what the Rust side binds, and nothing the Rust side does not declare.
#[test]
fn declarations_match_the_wgsl() {
    for decl in ALL {
        let module = module(decl.shader);
        let mut in_wgsl: Vec<(u32, &str, &naga::GlobalVariable)> = module
            .global_variables
            .iter()
            .filter_map(|(_, var)| {
                let b = var.binding.as_ref()?;
                (b.group == decl.group).then(|| (b.binding, var.name.as_deref().unwrap_or(""), var))
            })
            .collect();
        in_wgsl.sort_by_key(|(number, ..)| *number);
        let wgsl: Vec<(u32, &str)> = in_wgsl.iter().map(|(n, name, _)| (*n, *name)).collect();
        let declared: Vec<(u32, &str)> = decl
            .bindings
            .iter()
            .enumerate()
            .map(|(k, b)| (k as u32, b.name))
            .collect();
        assert_eq!(
            declared, wgsl,
            "{}: bindings of group {}",
            decl.label, decl.group
        );
        for ((_, name, var), b) in in_wgsl.iter().zip(decl.bindings) {
            assert!(
                holds(&module, var, b.resource),
                "{}: `{name}` is not a {:?} in the WGSL",
                decl.label,
                b.resource
            );
        }
    }
}

/// The Rust copies of WGSL structs have the WGSL's size (so arrays of them keep their
/// stride), and the dynamic offsets step by it.
#[test]
fn rust_structs_have_the_wgsl_layout() {
    use super::super::{materials, reflection_maps, uniforms};
    use std::mem::size_of;
    let structs = [
        (
            Shader::Transfer,
            "Lighting",
            size_of::<uniforms::LightingUniform>(),
        ),
        (
            Shader::TransferTexels,
            "Lighting",
            size_of::<uniforms::LightingUniform>(),
        ),
        (Shader::Lights, "Frame", size_of::<uniforms::FrameUniform>()),
        (Shader::Lights, "Light", size_of::<uniforms::LightUniform>()),
        // The entries' stride and the split-sum table after them.
        (
            Shader::Lights,
            "Materials",
            size_of::<materials::MaterialsUniform>(),
        ),
        (Shader::Prefilter, "Job", size_of::<reflection_maps::Job>()),
        (Shader::Prefilter, "Job", PREFILTER_JOB_SIZE as usize),
        (Shader::Shadow, "ShadowView", SHADOW_VIEW_SIZE as usize),
        (
            Shader::Lights,
            "Backplate",
            size_of::<super::super::composite::BackplateUniform>(),
        ),
        (
            Shader::Display,
            "Display",
            size_of::<uniforms::DisplayUniform>(),
        ),
    ];
    for (shader, name, rust_size) in structs {
        let module = module(shader);
        let mut layouter = naga::proc::Layouter::default();
        layouter
            .update(module.to_ctx())
            .expect("the shaders lay out");
        let (handle, _) = module
            .types
            .iter()
            .find(|(_, ty)| ty.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("{shader:?} has no struct {name}"));
        assert_eq!(
            layouter[handle].size as usize, rust_size,
            "{shader:?}: {name} in WGSL against its Rust copy"
        );
    }
}
