// Shows the renderer's linear HDR image in the window: tone mapping 1 - exp(-exposure c)
// (CONVENTIONS.md), then the sRGB transfer function unless the surface applies it.

struct Display {
    exposure: f32,
    encode_srgb: u32,
    _pad0: u32,
    _pad1: u32,
};

@group(0) @binding(0) var<uniform> display: Display;
@group(0) @binding(1) var image: texture_2d<f32>;

fn srgb(x: f32) -> f32 {
    let c = clamp(x, 0.0, 1.0);
    if c <= 0.0031308 {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(image));
    let texel = min(vec2<i32>(pixel.xy), size - vec2<i32>(1));
    let radiance = max(textureLoad(image, texel, 0).xyz, vec3<f32>(0.0));
    var c = vec3<f32>(1.0) - exp(-display.exposure * radiance);
    if display.encode_srgb != 0u {
        c = vec3<f32>(srgb(c.x), srgb(c.y), srgb(c.z));
    }
    return vec4<f32>(c, 1.0);
}
