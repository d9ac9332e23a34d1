// The floor ε of the live composite's ratio (CONVENTIONS.md, "Compositing": 10⁻³ × the mean
// luminance of the proxies alone over the proxy pixels), for the next frame, estimated from
// every FLOOR_STRIDE-th pixel of every FLOOR_STRIDE-th row (a guard against dividing by
// nothing needs no more) and summed in two steps: each of FLOOR_GROUPS workgroups sums a
// share of those rows, then one invocation adds the shares into the last entry (luminance
// sum, pixel count).

// The composite, whose alpha is B's luminance on the proxy pixels and -1 elsewhere.
@group(0) @binding(0) var composite_image: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> sums: array<vec4<f32>, FLOOR_SUMS>;

const FLOOR_LANES: u32 = 64u;
const FLOOR_STRIDE: u32 = 4u;
var<workgroup> lane_sums: array<vec2<f32>, FLOOR_LANES>;

@compute @workgroup_size(FLOOR_LANES)
fn partial_sums(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let size = textureDimensions(composite_image);
    var sum = vec2<f32>(0.0);
    for (var y = group.x * FLOOR_STRIDE; y < size.y; y = y + FLOOR_GROUPS * FLOOR_STRIDE) {
        for (var x = lane * FLOOR_STRIDE; x < size.x; x = x + FLOOR_LANES * FLOOR_STRIDE) {
            let luminance = textureLoad(composite_image, vec2<u32>(x, y), 0).w;
            if luminance >= 0.0 {
                sum = sum + vec2<f32>(luminance, 1.0);
            }
        }
    }
    lane_sums[lane] = sum;
    workgroupBarrier();
    for (var stride = FLOOR_LANES / 2u; stride > 0u; stride = stride / 2u) {
        if lane < stride {
            lane_sums[lane] = lane_sums[lane] + lane_sums[lane + stride];
        }
        workgroupBarrier();
    }
    if lane == 0u {
        sums[group.x] = vec4<f32>(lane_sums[0], 0.0, 0.0);
    }
}

@compute @workgroup_size(1)
fn total() {
    var sum = vec2<f32>(0.0);
    for (var g = 0u; g < FLOOR_GROUPS; g = g + 1u) {
        sum = sum + sums[g].xy;
    }
    sums[FLOOR_GROUPS] = vec4<f32>(sum, 0.0, 0.0);
}
