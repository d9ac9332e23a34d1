// First pass: the scene with its per-vertex PRT radiance (depth written), plus the normal and
// albedo the light pass needs. Both sides of a triangle show its front (no culling).
//
// Textured objects: their transfer is baked per unit texel value, so the interpolated radiance
// and the vertex albedo (the texture's factor) are both multiplied by the texel here. Untextured
// objects are drawn with a white texel: unchanged.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var albedo_texture: texture_2d<f32>;
@group(1) @binding(1) var albedo_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) radiance: vec4<f32>,
    @location(4) uv: vec2<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) albedo: vec3<f32>,
    @location(2) radiance: vec3<f32>,
    @location(3) uv: vec2<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(in.position, 1.0);
    out.normal = in.normal;
    out.albedo = in.albedo;
    out.radiance = in.radiance.xyz;
    out.uv = in.uv;
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    // The depth again, as a colour the light pass can read on every backend (OpenGL cannot
    // load from depth textures).
    @location(3) depth: vec4<f32>,
};

// ρ/π E(n) from `frame.sh_irradiance`: the real SH of bands 0–2 at n (CONVENTIONS.md: polar
// axis +Y, azimuth from +Z toward +X, no Condon–Shortley phase).
fn sh_irradiance_over_pi(n: vec3<f32>) -> vec3<f32> {
    let c = frame.sh_irradiance;
    var e = c[0].xyz * 0.282095;
    e += 0.488603 * (c[1].xyz * n.x + c[2].xyz * n.y + c[3].xyz * n.z);
    e += c[4].xyz * (1.092548 * n.z * n.x);
    e += c[5].xyz * (1.092548 * n.x * n.y);
    e += c[6].xyz * (0.315392 * (3.0 * n.y * n.y - 1.0));
    e += c[7].xyz * (1.092548 * n.z * n.y);
    e += c[8].xyz * (0.546274 * (n.z * n.z - n.x * n.x));
    return e;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    let normal = normalize(in.normal);
    let texel = textureSample(albedo_texture, albedo_sampler, in.uv).rgb;
    out.color = vec4<f32>(in.radiance * texel, 1.0);
    if (frame.flags & 4u) != 0u {
        out.color = vec4<f32>(in.albedo * texel * max(sh_irradiance_over_pi(normal), vec3<f32>(0.0)), 1.0);
    }
    out.normal = vec4<f32>(normal, 1.0);
    out.albedo = vec4<f32>(in.albedo * texel, 1.0);
    out.depth = encode_depth(in.clip.z);
    return out;
}
