// Shadow maps: depth only, seen from a directional light (orthographic).

struct ShadowView {
    matrix: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> view: ShadowView;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return view.matrix * vec4<f32>(position, 1.0);
}

// The (unbiased) depth as a colour too, for the blocker search, which needs the occluders'
// depths and must run where depth textures cannot be loaded (OpenGL).
@fragment
fn fs_main(@builtin(position) clip: vec4<f32>) -> @location(0) vec4<f32> {
    return encode_depth(clip.z);
}
