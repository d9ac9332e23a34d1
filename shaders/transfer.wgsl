// Per-vertex PRT: outgoing radiance dot(t_c, l_c) from the baked transfer vectors and the SH
// lighting (CONVENTIONS.md, "Transfer"). One invocation per vertex.
//
// radiance = full_transfer · sh  +  indirect_transfer · lights_sh
// where `sh` is the SH part of the lighting and `lights_sh` the directional lights projected
// into SH (their bounce light; their direct light is drawn with shadow maps).

@group(0) @binding(0) var<uniform> lighting: Lighting;
// Layout [vertex][channel][coefficient].
@group(0) @binding(1) var<storage, read> full_transfer: array<f32>;
@group(0) @binding(2) var<storage, read> indirect_transfer: array<f32>;
@group(0) @binding(3) var<storage, read_write> radiance: array<vec4<f32>>;
// The interreflected part alone: over the albedo, the light glossy surfaces see from the
// occluders around them (shaders/geometry.wgsl).
@group(0) @binding(4) var<storage, read_write> indirect_radiance: array<vec4<f32>>;

@compute @workgroup_size(TRANSFER_WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let v = id.x;
    if v >= lighting.vertex_count {
        return;
    }
    let n = lighting.coeff_count;
    var out = vec3<f32>(0.0);
    var indirect = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c = c + 1u) {
        let base = (v * 3u + c) * n;
        var sum = 0.0;
        var bounced = 0.0;
        for (var k = 0u; k < n; k = k + 1u) {
            sum = sum + full_transfer[base + k] * lighting.sh[k][c]
                      + indirect_transfer[base + k] * lighting.lights_sh[k][c];
            bounced = bounced + indirect_transfer[base + k] * (lighting.sh[k][c] + lighting.lights_sh[k][c]);
        }
        out[c] = sum;
        indirect[c] = bounced;
    }
    radiance[v] = vec4<f32>(out, 1.0);
    indirect_radiance[v] = vec4<f32>(indirect, 1.0);
}
