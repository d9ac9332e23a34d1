// The live composite (CONVENTIONS.md, "Compositing"), the ratio form, drawn by the light
// pass's `fs_composite` (`shaders/lights.wgsl`): object pixels show the render with the
// objects (A); proxy pixels the backplate times A / B, B the proxies alone (their PRT radiance
// without the objects from the PRT pass, their lights through the proxies' own shadow maps);
// other pixels the backplate. The backplate is the environment as the camera sees it, or a
// photograph spanning the camera's vertical field of view, centred (so it stays put whatever
// the window's aspect).

struct Backplate {
    // x: 1 for a photograph, 0 for the environment; y: the photograph's width / height;
    // z: its height in pixels; w: unused.
    params: vec4<f32>,
};

@group(1) @binding(0) var<uniform> backplate: Backplate;
// The PRT pass's images: A's PRT radiance, and B's with alpha 1 where a proxy is nearest.
@group(1) @binding(1) var with_objects: texture_2d<f32>;
@group(1) @binding(2) var without_objects: texture_2d<f32>;
@group(1) @binding(3) var photograph: texture_2d<f32>;
@group(1) @binding(4) var photograph_sampler: sampler;
// Written by `shaders/composite_floor.wgsl` after the previous frame: the last entry is
// (luminance sum of B, proxy pixels).
@group(1) @binding(5) var<uniform> floor_sums: array<vec4<f32>, FLOOR_SUMS>;

// `MAX_RATIO` (the largest ratio) and `RATIO_FLOOR` (ε over the mean luminance of B) are
// generated from `foundation/src/composite.rs`.

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Per channel A / B; a channel of B at or below ε takes the luminance ratio, and where B's
// luminance is too the ratio is 1. Clamped to [0, MAX_RATIO].
fn shadow_ratio(a: vec3<f32>, b: vec3<f32>, epsilon: f32) -> vec3<f32> {
    let yb = luminance(b);
    var grey = 1.0;
    if yb > epsilon {
        grey = luminance(a) / yb;
    }
    let per_channel = a / max(b, vec3<f32>(1e-30));
    let r = select(vec3<f32>(grey), per_channel, b > vec3<f32>(epsilon));
    return clamp(r, vec3<f32>(0.0), vec3<f32>(MAX_RATIO));
}

// The backplate at `pixel`, whose camera ray is `direction` (the environment's mip level from
// the image centre's pixel angle, `frame.env_rotation.z`).
fn backplate_radiance(pixel: vec2<f32>, direction: vec3<f32>) -> vec3<f32> {
    if backplate.params.x > 0.5 {
        let height = frame.viewport.y;
        let u = 0.5 + (pixel.x - 0.5 * frame.viewport.x) / (height * backplate.params.y);
        if u < 0.0 || u > 1.0 {
            return vec3<f32>(0.0);
        }
        let lod = max(log2(backplate.params.z / height), 0.0);
        return textureSampleLevel(photograph, photograph_sampler, vec2<f32>(u, pixel.y / height), lod).xyz;
    }
    return environment_radiance(direction, frame.env_rotation.z);
}

// The composite at `pixel` (alpha: the luminance of B on proxy pixels, for the next frame's
// ε; -1 elsewhere).
@fragment
fn fs_composite(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(pixel.xy);
    let depth = decode_depth(textureLoad(depth_buffer, texel, 0));
    if depth >= 1.0 {
        return vec4<f32>(backplate_radiance(pixel.xy, view_ray(pixel_ndc(pixel.xy))), -1.0);
    }
    let b_prt = textureLoad(without_objects, texel, 0);
    let proxy = b_prt.w > 0.5;
    let lit = direct_light(pixel.xy, depth, proxy);
    let a = textureLoad(with_objects, texel, 0).xyz + lit.with_objects;
    if !proxy {
        return vec4<f32>(a, -1.0);
    }
    let b = b_prt.xyz + lit.without_objects;
    let sums = floor_sums[FLOOR_GROUPS].xy;
    let epsilon = RATIO_FLOOR * sums.x / max(sums.y, 1.0);
    let world = frame.inv_view_proj * vec4<f32>(pixel_ndc(pixel.xy), depth, 1.0);
    let direction = normalize(world.xyz / world.w - frame.camera_position.xyz);
    let shown = backplate_radiance(pixel.xy, direction);
    return vec4<f32>(shown * shadow_ratio(a, b, epsilon), luminance(b));
}
