// First pass: the scene with its per-vertex PRT radiance (depth written), plus the normal and
// albedo the light pass needs. Both sides of a triangle show its front (no culling).

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) radiance: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) albedo: vec3<f32>,
    @location(2) radiance: vec3<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(in.position, 1.0);
    out.normal = in.normal;
    out.albedo = in.albedo;
    out.radiance = in.radiance.xyz;
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

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    out.color = vec4<f32>(in.radiance, 1.0);
    out.normal = vec4<f32>(normalize(in.normal), 1.0);
    out.albedo = vec4<f32>(in.albedo, 1.0);
    out.depth = encode_depth(in.clip.z);
    return out;
}
