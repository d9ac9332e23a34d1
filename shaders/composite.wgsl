// The live composite (CONVENTIONS.md, "Compositing"), the ratio form: object pixels show the
// render with the objects (A); proxy pixels the backplate times A / B, B the proxies alone
// (`shaders/proxies.wgsl` and the lights without the objects); other pixels the backplate.
// The backplate is the environment as the camera sees it, or a photograph spanning the
// camera's vertical field of view, centred (so it stays put whatever the window's aspect).

struct Backplate {
    // x: 1 for a photograph, 0 for the environment; y: the photograph's width / height;
    // z: its height in pixels; w: unused.
    params: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> backplate: Backplate;
@group(0) @binding(2) var with_objects: texture_2d<f32>;
@group(0) @binding(3) var without_objects: texture_2d<f32>;
@group(0) @binding(4) var depth_buffer: texture_2d<f32>;
@group(0) @binding(5) var environment: texture_2d<f32>;
@group(0) @binding(6) var environment_sampler: sampler;
@group(0) @binding(7) var photograph: texture_2d<f32>;
@group(0) @binding(8) var photograph_sampler: sampler;
// Written by `shaders/composite_floor.wgsl`: the last entry is (luminance sum, pixels).
@group(0) @binding(9) var<uniform> floor_sums: array<vec4<f32>, FLOOR_SUMS>;

const PI: f32 = 3.14159265358979;
// The largest ratio (`MAX_RATIO` in `reference/src/composite.rs`).
const MAX_RATIO: f32 = 8.0;
// ε over the mean luminance of B (`RATIO_FLOOR` there).
const RATIO_FLOOR: f32 = 1e-3;

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

fn backplate_radiance(pixel: vec2<f32>) -> vec3<f32> {
    if backplate.params.x > 0.5 {
        let height = frame.viewport.y;
        let u = 0.5 + (pixel.x - 0.5 * frame.viewport.x) / (height * backplate.params.y);
        if u < 0.0 || u > 1.0 {
            return vec3<f32>(0.0);
        }
        let lod = max(log2(backplate.params.z / height), 0.0);
        return textureSampleLevel(photograph, photograph_sampler, vec2<f32>(u, pixel.y / height), lod).xyz;
    }
    let ndc = vec2<f32>(pixel.x * frame.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * frame.viewport.w * 2.0);
    let direction = view_ray(ndc);
    let next = view_ray(ndc + vec2<f32>(2.0 * frame.viewport.z, 0.0));
    return environment_radiance(direction, acos(clamp(dot(direction, next), -1.0, 1.0)));
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(pixel.xy);
    let depth = decode_depth(textureLoad(depth_buffer, texel, 0));
    if depth >= 1.0 {
        return vec4<f32>(backplate_radiance(pixel.xy), 1.0);
    }
    let a = textureLoad(with_objects, texel, 0).xyz;
    let b = textureLoad(without_objects, texel, 0);
    if b.w < 0.5 {
        return vec4<f32>(a, 1.0);
    }
    let sums = floor_sums[FLOOR_GROUPS].xy;
    let epsilon = RATIO_FLOOR * sums.x / max(sums.y, 1.0);
    let ratio = shadow_ratio(a, b.xyz, epsilon);
    return vec4<f32>(backplate_radiance(pixel.xy) * ratio, 1.0);
}
