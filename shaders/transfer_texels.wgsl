// Per-vertex PRT where there are no compute shaders or storage buffers (WebGL2): the same sums
// as shaders/transfer.wgsl, drawn as one full-screen triangle over two targets with a texel
// per vertex (row-major, `target_width` to a row), which the renderer then copies into the
// vertex buffers the compute pass would have written. The targets are 32-bit unsigned
// integers holding the floats' bits: WebGL2 can draw into those without extensions, and the
// copies come out as the f32 vec4s the geometry pass reads. The transfer lies in float textures,
// each vertex's 3·n floats ([channel][coefficient]) starting a new texel.

@group(0) @binding(0) var<uniform> lighting: Lighting;
@group(0) @binding(1) var full_transfer: texture_2d<f32>;
@group(0) @binding(2) var indirect_transfer: texture_2d<f32>;

struct VertexRadiance {
    @location(0) radiance: vec4<u32>,
    @location(1) indirect: vec4<u32>,
};

// The texel holding float `i` of a transfer texture.
fn texel_of(i: u32) -> vec2<u32> {
    let texel = i / 4u;
    return vec2<u32>(texel % lighting.transfer_width, texel / lighting.transfer_width);
}

fn full_at(i: u32) -> f32 {
    return textureLoad(full_transfer, texel_of(i), 0)[i % 4u];
}

fn indirect_at(i: u32) -> f32 {
    return textureLoad(indirect_transfer, texel_of(i), 0)[i % 4u];
}

@fragment
fn fs_transfer(@builtin(position) pixel: vec4<f32>) -> VertexRadiance {
    let v = u32(pixel.y) * lighting.target_width + u32(pixel.x);
    var result: VertexRadiance;
    if v >= lighting.vertex_count {
        result.radiance = vec4<u32>(0u);
        result.indirect = vec4<u32>(0u);
        return result;
    }
    let n = lighting.coeff_count;
    let first = v * ((3u * n + 3u) / 4u) * 4u;
    var out = vec3<f32>(0.0);
    var indirect = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c = c + 1u) {
        let base = first + c * n;
        var sum = 0.0;
        var bounced = 0.0;
        for (var k = 0u; k < n; k = k + 1u) {
            let t_full = full_at(base + k);
            let t_indirect = indirect_at(base + k);
            sum = sum + t_full * lighting.sh[k][c] + t_indirect * lighting.lights_sh[k][c];
            bounced = bounced + t_indirect * (lighting.sh[k][c] + lighting.lights_sh[k][c]);
        }
        out[c] = sum;
        indirect[c] = bounced;
    }
    result.radiance = bitcast<vec4<u32>>(vec4<f32>(out, 1.0));
    result.indirect = bitcast<vec4<u32>>(vec4<f32>(indirect, 1.0));
    return result;
}
