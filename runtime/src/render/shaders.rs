//! The WGSL of `shaders/`, loaded in one place. Every module is prefixed with the limits the
//! Rust side sizes its buffers by, as WGSL constants, so the two cannot disagree; the render
//! passes' modules also get `shaders/common.wgsl` (the uniform structs they share).

use foundation::composite;
use foundation::sh::num_coeffs;

/// Most lights drawn per frame (the light pass's uniform array).
pub const MAX_LIGHTS: usize = 32;
/// Highest SH order the GPU lighting buffers hold; bakes of higher orders are CPU-only.
pub const MAX_GPU_ORDER: usize = 8;
/// SH coefficients per channel at [`MAX_GPU_ORDER`].
pub(crate) const MAX_GPU_COEFFS: usize = MAX_GPU_ORDER * MAX_GPU_ORDER;
/// Distinct glossy materials a scene may have (the materials' uniform array; entry 0 is the
/// diffuse one).
pub(crate) const MAX_MATERIALS: usize = 32;
/// Texels per side of the metallic-roughness layer's split-sum table (n·v across, roughness
/// down).
pub(crate) const SPLIT_SUM_SIZE: usize = 32;
/// Invocations per workgroup of the per-vertex transfer pass.
pub(crate) const TRANSFER_WORKGROUP: u32 = 64;
/// Workgroups (bands of rows) summing the live composite's ratio floor.
pub(crate) const FLOOR_GROUPS: u32 = 64;
/// Entries of the floor's sums: one per band, then the total.
pub(crate) const FLOOR_SUMS: usize = FLOOR_GROUPS as usize + 1;

/// The shaders of `shaders/`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Shader {
    /// Per-vertex PRT radiance (compute).
    Transfer,
    /// The same, drawn into textures where there is no compute (WebGL2).
    TransferTexels,
    /// The PRT pass writing the G-buffer.
    Geometry,
    /// Depth from a light.
    Shadow,
    /// The lights' full-screen pass.
    Lights,
    /// Tone mapping to a window.
    Display,
    /// Reflection maps prefiltered with the Phong lobe.
    Prefilter,
    /// The live composite: the ratio's floor (compute).
    CompositeFloor,
    /// The proxies' edges over the composite.
    Wireframe,
}

impl Shader {
    fn file_name(self) -> &'static str {
        match self {
            Shader::Transfer => "transfer.wgsl",
            Shader::TransferTexels => "transfer_texels.wgsl",
            Shader::Geometry => "geometry.wgsl",
            Shader::Shadow => "shadow.wgsl",
            Shader::Lights => "lights.wgsl",
            Shader::Display => "display.wgsl",
            Shader::Prefilter => "prefilter.wgsl",
            Shader::CompositeFloor => "composite_floor.wgsl",
            Shader::Wireframe => "wireframe.wgsl",
        }
    }

    fn body(self) -> &'static str {
        match self {
            Shader::Transfer => include_str!("../../../shaders/transfer.wgsl"),
            Shader::TransferTexels => include_str!("../../../shaders/transfer_texels.wgsl"),
            Shader::Geometry => include_str!("../../../shaders/geometry.wgsl"),
            Shader::Shadow => include_str!("../../../shaders/shadow.wgsl"),
            Shader::Lights => include_str!("../../../shaders/lights.wgsl"),
            Shader::Display => include_str!("../../../shaders/display.wgsl"),
            Shader::Prefilter => include_str!("../../../shaders/prefilter.wgsl"),
            Shader::CompositeFloor => include_str!("../../../shaders/composite_floor.wgsl"),
            Shader::Wireframe => include_str!("../../../shaders/wireframe.wgsl"),
        }
    }

    /// The shared WGSL the shader builds on: the structs of `shaders/common.wgsl` for the
    /// render passes, the full-screen triangle of `shaders/fullscreen.wgsl` for full-screen
    /// passes, the transfer passes' lighting struct of `shaders/transfer_lighting.wgsl`.
    fn prelude(self) -> &'static [&'static str] {
        const COMMON: &str = include_str!("../../../shaders/common.wgsl");
        const FULLSCREEN: &str = include_str!("../../../shaders/fullscreen.wgsl");
        const GLOSSY: &str = include_str!("../../../shaders/glossy.wgsl");
        const ENVIRONMENT: &str = include_str!("../../../shaders/environment.wgsl");
        const COMPOSITE: &str = include_str!("../../../shaders/composite.wgsl");
        const LIGHTING: &str = include_str!("../../../shaders/transfer_lighting.wgsl");

        match self {
            Shader::Transfer => &[LIGHTING],
            Shader::TransferTexels => &[LIGHTING, FULLSCREEN],
            Shader::Geometry => &[COMMON, GLOSSY],
            Shader::Shadow => &[COMMON],
            Shader::Lights => &[COMMON, FULLSCREEN, GLOSSY, ENVIRONMENT, COMPOSITE],
            Shader::Display => &[FULLSCREEN],
            Shader::Prefilter => &[FULLSCREEN, GLOSSY],
            Shader::Wireframe => &[COMMON],
            Shader::CompositeFloor => &[],
        }
    }

    /// The complete WGSL source: constants, shared WGSL, the shader.
    pub(crate) fn source(self) -> String {
        let mut source = constants();
        for part in self.prelude() {
            source.push('\n');
            source.push_str(part);
        }
        source.push('\n');
        source.push_str(self.body());
        source
    }

    /// Entry point of the vertex stage of a full-screen pass.
    pub(crate) const FULLSCREEN_VERTEX: &'static str = "vs_fullscreen";

    pub(crate) fn module(self, device: &wgpu::Device) -> wgpu::ShaderModule {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(self.file_name()),
            source: wgpu::ShaderSource::Wgsl(self.source().into()),
        })
    }
}

/// The Rust limits, and the composite's constants (`foundation::composite`), as WGSL
/// constants.
fn constants() -> String {
    format!(
        "// Generated from runtime/src/render/shaders.rs.\n\
         const MAX_LIGHTS: u32 = {MAX_LIGHTS}u;\n\
         const MAX_SH_COEFFS: u32 = {}u;\n\
         const MAX_MATERIALS: u32 = {MAX_MATERIALS}u;\n\
         const SPLIT_SUM_SIZE: u32 = {SPLIT_SUM_SIZE}u;\n\
         const SPLIT_SUM_PAIRS: u32 = {}u;\n\
         const TRANSFER_WORKGROUP: u32 = {TRANSFER_WORKGROUP}u;\n\
         const FLOOR_GROUPS: u32 = {FLOOR_GROUPS}u;\n\
         const FLOOR_SUMS: u32 = {FLOOR_SUMS}u;\n\
         const MAX_RATIO: f32 = {};\n\
         const RATIO_FLOOR: f32 = {};\n",
        num_coeffs(MAX_GPU_ORDER),
        SPLIT_SUM_SIZE * SPLIT_SUM_SIZE / 2,
        wgsl_float(composite::MAX_RATIO),
        wgsl_float(composite::RATIO_FLOOR),
    )
}

/// `x` as a WGSL float literal that reads back as the same `f32` (Rust's shortest round-trip
/// form, with a decimal point where it has neither point nor exponent).
fn wgsl_float(x: f32) -> String {
    let text = format!("{x:?}");
    if text.contains(['.', 'e', 'E']) {
        text
    } else {
        format!("{text}.0")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every shader parses and validates with the generated constants, and none writes a
    /// limit by hand.
    #[test]
    fn shaders_validate_and_take_their_limits_from_rust() {
        for shader in [
            Shader::Transfer,
            Shader::TransferTexels,
            Shader::Geometry,
            Shader::Shadow,
            Shader::Lights,
            Shader::Display,
            Shader::Prefilter,
            Shader::CompositeFloor,
            Shader::Wireframe,
        ] {
            let source = shader.source();
            let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| {
                panic!("{}: {}", shader.file_name(), e.emit_to_string(&source))
            });
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::all(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {e:?}", shader.file_name()));
            for literal in [format!(", {MAX_LIGHTS}>"), format!(", {MAX_GPU_COEFFS}>")] {
                assert!(
                    !shader.body().contains(&literal),
                    "{} sizes an array by hand ({literal})",
                    shader.file_name()
                );
            }
            // Declared once, by the generated constants: a shader declaring one by hand again
            // fails to parse, with the name.
            for generated in ["MAX_RATIO", "RATIO_FLOOR"] {
                assert_eq!(source.matches(&format!("const {generated}")).count(), 1);
            }
        }
    }

    /// The generated floats read back as the Rust values.
    #[test]
    fn generated_floats_are_exact() {
        for x in [8.0f32, 1e-3, 0.1, 3.0e-12, 1.5e20] {
            let text = wgsl_float(x);
            assert_eq!(text.parse::<f32>().unwrap(), x, "{text}");
            assert!(text.contains(['.', 'e']), "{text}");
        }
    }
}
