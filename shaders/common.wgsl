// Per-frame data shared by the geometry and light passes.
struct Frame {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // Width, height, 1/width, 1/height.
    viewport: vec4<f32>,
    // cos and sin of the environment's rotation about +Y, the angle between the rays of the
    // image centre's neighbouring pixels, then unused.
    env_rotation: vec4<f32>,
    light_count: u32,
    // Bit 1: show the environment behind the scene; bit 3: reflections not occluded by the
    // bake (the "ibl" peer).
    flags: u32,
    // PCF kernel: taps per side (odd).
    pcf_taps: u32,
    // The live composite: the shadow-map layer of the proxies' own map of light i is the
    // light's layer plus this (0: none, the proxies cannot shadow themselves, or not
    // compositing).
    proxy_layers: u32,
    // Bit 2 of flags: the first pass shades by the normal with these (A_l L_k / π, RGB in
    // xyz, bands 0–2) instead of the per-vertex radiance.
    sh_irradiance: array<vec4<f32>, 9>,
    // The camera's position (xyz) for glossy surfaces' view direction.
    camera_position: vec4<f32>,
    // World → the frame of the reflection maps (the map's own, for a turning map).
    reflection_to_map: mat4x4<f32>,
};

struct Light {
    // Direction the light comes from (unit), w unused.
    direction: vec4<f32>,
    // RGB power (∫ L dω over the source), w unused.
    power: vec4<f32>,
    // World to shadow-map clip space (orthographic).
    shadow_matrix: mat4x4<f32>,
    // x: world size of a shadow-map texel, y: world depth range of the map,
    // z: tan of the source's angular radius, w: shadow-map layer.
    params: vec4<f32>,
    // x: tan of the angular radius of the source's halo (at least the source's), y: fraction of
    // the power from the source itself (the rest from the halo), zw unused.
    source: vec4<f32>,
};

// A depth in [0, 1] split over two half floats (about 22 bits together), for colour targets
// that every backend can render to.
fn encode_depth(depth: f32) -> vec4<f32> {
    let high = unpack2x16float(pack2x16float(vec2<f32>(depth, 0.0))).x;
    return vec4<f32>(high, depth - high, 0.0, 1.0);
}

fn decode_depth(encoded: vec4<f32>) -> f32 {
    return encoded.x + encoded.y;
}
