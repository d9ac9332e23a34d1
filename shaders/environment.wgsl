// The environment as the camera sees it: shared by the light pass (the background behind the
// scene) and the composite pass (the environment backplate). Expects `frame`, `environment`
// and `environment_sampler` declared by the shader.

// The background seen along `w_world`: the equirectangular map (CONVENTIONS.md) filtered at the
// mip level whose texels span `pixel_angle` radians, the angle between neighbouring pixels'
// rays (bilinear when magnified, no aliasing when minified).
fn environment_radiance(w_world: vec3<f32>, pixel_angle: f32) -> vec3<f32> {
    // The map is turned by the rotation: look up R_y(-angle) w.
    let c = frame.env_rotation.x;
    let s = frame.env_rotation.y;
    let w = vec3<f32>(w_world.x * c - w_world.z * s, w_world.y, w_world.x * s + w_world.z * c);
    let size = vec2<f32>(textureDimensions(environment));
    var u = atan2(w.x, -w.z) / (2.0 * PI);
    u = u - floor(u);
    let v = acos(clamp(w.y, -1.0, 1.0)) / PI;
    // Explicit level: derivatives of u jump at the map's seam.
    let lod = max(log2(pixel_angle * size.x / (2.0 * PI)), 0.0);
    return textureSampleLevel(environment, environment_sampler, vec2<f32>(u, v), lod).xyz;
}

// The unit direction of the camera ray through `ndc`.
fn view_ray(ndc: vec2<f32>) -> vec3<f32> {
    let far = frame.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    let near = frame.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
    return normalize(far.xyz / far.w - near.xyz / near.w);
}
