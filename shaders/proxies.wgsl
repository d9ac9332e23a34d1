// The live composite's proxy pass (CONVENTIONS.md, "Compositing"): the proxies drawn again,
// with their PRT radiance baked without the virtual objects, only where the PRT pass found
// them nearest (equal depth), into the image of the proxies alone (alpha 1 marks them). The
// G-buffer's albedo alpha becomes 2 there, so the lights without the objects
// (`fs_without_objects` in `shaders/lights.wgsl`) shade those pixels alone.

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
    // Invariant, as in `shaders/geometry.wgsl`: the same depths, so the equal test passes.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) radiance: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) albedo: vec3<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(in.position, 1.0);
    out.radiance = in.radiance.xyz;
    out.uv = in.uv;
    out.normal = in.normal;
    out.albedo = in.albedo;
    return out;
}

struct FragmentOut {
    @location(0) without_objects: vec4<f32>,
    // Written to the albedo target's alpha only.
    @location(1) mark: vec4<f32>,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    let texel = textureSample(albedo_texture, albedo_sampler, in.uv).rgb;
    out.without_objects = vec4<f32>(in.radiance * texel, 1.0);
    // Unshadowed SH per pixel, as the PRT pass shades then.
    if (frame.flags & 4u) != 0u {
        let e = max(sh_irradiance_over_pi(normalize(in.normal)), vec3<f32>(0.0));
        out.without_objects = vec4<f32>(in.albedo * texel * e, 1.0);
    }
    out.mark = vec4<f32>(0.0, 0.0, 0.0, 2.0);
    return out;
}
