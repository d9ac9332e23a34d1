// The proxies' edges over the composite, to line the proxies up with the photograph: bright
// green lines, at no depth test (hidden edges show too).

@group(0) @binding(0) var<uniform> frame: Frame;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.view_proj * vec4<f32>(position, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    // Far above any exposure's white: saturated green once tone mapped.
    return vec4<f32>(0.0, 1e4, 0.0, 1.0);
}
