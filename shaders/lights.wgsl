// Second pass, added onto the first: each directional light's Lambertian contribution
// ρ/π · power · max(0, n·d) · visibility, visibility by percentage-closer filtering of its
// shadow map. Pixels that see no geometry show the environment map.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> lights: array<Light, MAX_LIGHTS>;
@group(0) @binding(2) var depth_buffer: texture_2d<f32>;
@group(0) @binding(3) var normal_buffer: texture_2d<f32>;
@group(0) @binding(4) var albedo_buffer: texture_2d<f32>;
@group(0) @binding(5) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(6) var shadow_sampler: sampler_comparison;
@group(0) @binding(7) var environment: texture_2d<f32>;
// The shadow maps' depths as plain floats (for the blocker search).
@group(0) @binding(8) var shadow_depths: texture_2d_array<f32>;

const PI: f32 = 3.14159265358979;

// Pipeline constants: the renderer builds one pipeline per combination, so the shader run per
// pixel contains only the code it needs.
// Whether lights cast shadows.
override SHADOWED: bool = true;
// Whether PCF kernels are sized from the light's angular radius (blocker search).
override KERNEL_FROM_RADIUS: bool = true;

// Equirectangular lookup, constant per texel (CONVENTIONS.md).
fn environment_radiance(w_world: vec3<f32>) -> vec3<f32> {
    // The map is turned by the rotation: look up R_y(-angle) w.
    let c = frame.env_rotation.x;
    let s = frame.env_rotation.y;
    let w = vec3<f32>(w_world.x * c - w_world.z * s, w_world.y, w_world.x * s + w_world.z * c);
    let size = vec2<f32>(textureDimensions(environment));
    var u = atan2(w.x, -w.z) / (2.0 * PI);
    u = u - floor(u);
    let v = acos(clamp(w.y, -1.0, 1.0)) / PI;
    let texel = min(vec2<u32>(vec2<f32>(u, v) * size), vec2<u32>(size) - vec2<u32>(1u));
    return textureLoad(environment, texel, 0).xyz;
}

fn shadow_coordinates(light: Light, position: vec3<f32>) -> vec3<f32> {
    let clip = light.shadow_matrix * vec4<f32>(position, 1.0);
    return vec3<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5, clip.z);
}

// Occluders around `uv` within `radius` texels: a 3×3 grid of shadow-map texels, each compared
// with the receiver plane's depth there. Returns (mean occluder depth, fraction of the texels
// that occlude): fraction 0 means fully lit, 1 fully in umbra.
fn blockers(layer: i32, uv: vec2<f32>, receiver: f32, slope: vec2<f32>, radius: f32) -> vec2<f32> {
    let size = vec2<f32>(textureDimensions(shadow_depths));
    let texel = vec2<i32>(uv * size);
    let slack = (abs(slope.x) + abs(slope.y)) * 2.0 / size.x + 1e-5;
    var sum = 0.0;
    var count = 0.0;
    for (var y = -1; y <= 1; y = y + 1) {
        for (var x = -1; x <= 1; x = x + 1) {
            let offset = vec2<i32>(vec2<f32>(f32(x), f32(y)) * radius);
            let at = clamp(texel + offset, vec2<i32>(0), vec2<i32>(size) - vec2<i32>(1));
            let depth = decode_depth(textureLoad(shadow_depths, at, layer, 0));
            let local = vec2<f32>(at - texel) / size;
            let plane = receiver + dot(slope, vec2<f32>(2.0 * local.x, -2.0 * local.y)) - slack;
            if depth < plane {
                sum = sum + depth;
                count = count + 1.0;
            }
        }
    }
    if count == 0.0 {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(sum / count, count / 9.0);
}

// Depth slope of the receiver's tangent plane in shadow-map clip space: how the light-space
// depth of the surface changes per unit of clip x and y. Comparing each PCF tap against the
// receiver's own depth at that tap (not at the kernel centre) removes the self-shadowing that
// wide kernels cause on surfaces that graze the light.
fn receiver_depth_slope(light: Light, normal: vec3<f32>) -> vec2<f32> {
    let m = light.shadow_matrix;
    let ax = vec3<f32>(m[0][0], m[1][0], m[2][0]);
    let ay = vec3<f32>(m[0][1], m[1][1], m[2][1]);
    let az = vec3<f32>(m[0][2], m[1][2], m[2][2]);
    let det = dot(ax, cross(ay, normal));
    if abs(det) < 1e-6 {
        return vec2<f32>(0.0);
    }
    let slope = vec2<f32>(dot(az, cross(ay, normal)), dot(az, cross(normal, ax))) / det;
    // Bounded: a surface edge-on to the light would otherwise get an unbounded slope.
    return clamp(slope, vec2<f32>(-50.0), vec2<f32>(50.0));
}

// Fraction of `light` visible at `coords`: a taps × taps grid of hardware-filtered (2×2)
// comparisons spread over `radius` texels, each against the receiver plane's depth there.
fn pcf(light: Light, coords: vec3<f32>, slope: vec2<f32>, radius: f32) -> f32 {
    let layer = i32(light.params.w);
    let size = vec2<f32>(textureDimensions(shadow_maps));
    let taps = i32(frame.pcf_taps);
    let half_taps = taps / 2;
    let step = select(radius / f32(max(half_taps, 1)), 0.0, half_taps == 0);
    // Half a texel of slack for the bilinear footprint of each comparison.
    let slack = 0.5 * (abs(slope.x) + abs(slope.y)) * 2.0 / size.x + 1e-5;
    var lit = 0.0;
    for (var y = -half_taps; y <= half_taps; y = y + 1) {
        for (var x = -half_taps; x <= half_taps; x = x + 1) {
            let offset = vec2<f32>(f32(x), f32(y)) * step / size;
            // uv → clip: x = 2u - 1, y = 1 - 2v.
            let depth = coords.z + dot(slope, vec2<f32>(2.0 * offset.x, -2.0 * offset.y)) - slack;
            lit = lit + textureSampleCompareLevel(shadow_maps, shadow_sampler, coords.xy + offset, layer, depth);
        }
    }
    return lit / f32(taps * taps);
}

// How much of the area within `radius` texels of `coords` is lit, roughly: 4 gathered
// comparisons = 16 texels. 1: all lit, 0: all shadowed, in between: a shadow edge.
fn coverage(layer: i32, coords: vec3<f32>, slope: vec2<f32>, radius: f32) -> f32 {
    let size = vec2<f32>(textureDimensions(shadow_maps));
    let slack = (abs(slope.x) + abs(slope.y)) * 2.0 / size.x + 1e-5;
    var lit = 0.0;
    for (var k = 0; k < 4; k = k + 1) {
        let corner = vec2<f32>(f32(k & 1) * 2.0 - 1.0, f32(k >> 1u) * 2.0 - 1.0) * (0.5 * radius);
        let offset = corner / size;
        let depth = coords.z + dot(slope, vec2<f32>(2.0 * offset.x, -2.0 * offset.y)) - slack;
        lit = lit + dot(textureGatherCompare(shadow_maps, shadow_sampler, coords.xy + offset, layer, depth), vec4<f32>(1.0));
    }
    return lit / 16.0;
}

fn visibility(index: u32, position: vec3<f32>, normal: vec3<f32>) -> f32 {
    let light = lights[index];
    let coords = shadow_coordinates(light, position + normal * (0.5 * light.params.x));
    if coords.x < 0.0 || coords.x > 1.0 || coords.y < 0.0 || coords.y > 1.0 || coords.z > 1.0 {
        return 1.0;
    }
    let slope = receiver_depth_slope(light, normal);
    let layer = i32(light.params.w);
    // The widest the kernel can be: a penumbra of a distant source of angular radius α behind
    // an occluder at distance d has a half-width d tan α, and d is at most the scene's depth.
    var widest = f32(frame.pcf_taps / 2u) + 1.0;
    if KERNEL_FROM_RADIUS {
        widest = clamp(light.params.y * light.params.z / light.params.x, 1.0, 32.0);
    }
    if !KERNEL_FROM_RADIUS && frame.pcf_taps == 1u {
        // The cheapest filter: one hardware 2×2 comparison.
        return pcf(light, coords, slope, 1.0);
    }
    // Most pixels are plainly lit or in umbra: decide those from 16 texels.
    let around = coverage(layer, coords, slope, widest);
    if around == 1.0 || around == 0.0 {
        return around;
    }
    var radius = 1.0;
    if KERNEL_FROM_RADIUS {
        let found = blockers(layer, coords.xy, coords.z, slope, widest);
        if found.y == 0.0 {
            return 1.0;
        }
        let distance = max(coords.z - found.x, 0.0) * light.params.y;
        radius = clamp(distance * light.params.z / light.params.x, 1.0, 32.0);
    }
    return pcf(light, coords, slope, radius);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(pixel.xy);
    let depth = decode_depth(textureLoad(depth_buffer, texel, 0));
    let ndc = vec2<f32>(pixel.x * frame.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * frame.viewport.w * 2.0);
    if depth >= 1.0 {
        if (frame.flags & 2u) == 0u {
            return vec4<f32>(0.0);
        }
        let far = frame.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
        let near = frame.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
        let direction = normalize(far.xyz / far.w - near.xyz / near.w);
        return vec4<f32>(environment_radiance(direction), 0.0);
    }
    let world = frame.inv_view_proj * vec4<f32>(ndc, depth, 1.0);
    let position = world.xyz / world.w;
    let normal = textureLoad(normal_buffer, texel, 0).xyz;
    let albedo = textureLoad(albedo_buffer, texel, 0).xyz;
    let diffuse = albedo / PI;
    var sum = vec3<f32>(0.0);
    // A constant trip count with an early break lets the compiler unroll the loop and index
    // the light array with constants.
    for (var i = 0u; i < 32u; i = i + 1u) {
        if i >= frame.light_count {
            break;
        }
        let direction = lights[i].direction.xyz;
        let cosine = dot(normal, direction);
        if cosine > 0.0 {
            var v = 1.0;
            if SHADOWED {
                v = visibility(i, position, normal);
            }
            sum = sum + diffuse * lights[i].power.xyz * (cosine * v);
        }
    }
    return vec4<f32>(sum, 0.0);
}
