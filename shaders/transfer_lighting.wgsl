// The SH lighting the per-vertex transfer passes dot with every vertex's transfer
// (shaders/transfer.wgsl, shaders/transfer_texels.wgsl; `LightingUniform` in Rust).

struct Lighting {
    vertex_count: u32,
    // Coefficients used per channel (n² of the bake's order).
    coeff_count: u32,
    // The texel pass's rows: texels to a row of the transfer textures, and texels (vertices)
    // to a row of the targets. Unused by the compute pass.
    transfer_width: u32,
    target_width: u32,
    // RGB coefficient k in sh[k].xyz.
    sh: array<vec4<f32>, MAX_SH_COEFFS>,
    lights_sh: array<vec4<f32>, MAX_SH_COEFFS>,
};
