// Prefiltered reflection maps: one face of one shininess per draw, each texel the remainder
// cube map convolved with the normalised Phong lobe around the texel's direction,
// ∫ D_s(r·ω) L(ω) dω, by a quadrature over the lobe's support (not a mip-level lookup, which
// is too sharp for a Phong lobe: the lobe's tails reach well past one texel of its level).

struct Job {
    face: u32,
    shininess: f32,
    // Face size of the target, of the source's level 0, and the source's mip levels.
    target_size: f32,
    source_size: f32,
    source_levels: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
};

@group(0) @binding(0) var<uniform> job: Job;
@group(0) @binding(1) var source: texture_2d_array<f32>;
@group(0) @binding(2) var source_sampler: sampler;

// Quadrature points per side of the square around the lobe's axis.
const QUADRATURE_SIDE: i32 = 16;

// The lobe's support, where cos^s α is at least 1e-3 of its peak (at most 90°), sampled on a
// square grid in the tangent plane mapped onto the sphere by the exponential map (Jacobian
// sin ρ / ρ), each point read from the source level whose texels are as wide as the grid step
// (so nothing between points is missed). Normalised by the weights' sum: the quadrature's
// own integral of the lobe, so a constant map stays constant.
fn prefiltered(r: vec3<f32>, shininess: f32) -> vec3<f32> {
    let edge = min(acos(pow(1e-3, 1.0 / max(shininess, 1e-3))), 0.5 * GLOSSY_PI);
    let step = 2.0 * edge / f32(QUADRATURE_SIDE);
    let texel = 0.5 * GLOSSY_PI / job.source_size;
    let lod = clamp(log2(step / texel), 0.0, job.source_levels - 1.0);
    let helper = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(r.y) > 0.9);
    let t1 = normalize(cross(helper, r));
    let t2 = cross(r, t1);
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    for (var i = 0; i < QUADRATURE_SIDE; i = i + 1) {
        for (var j = 0; j < QUADRATURE_SIDE; j = j + 1) {
            let x = -edge + (f32(i) + 0.5) * step;
            let y = -edge + (f32(j) + 0.5) * step;
            let rho = sqrt(x * x + y * y);
            if rho >= edge {
                continue;
            }
            let w = pow(cos(rho), shininess) * sin(rho) / rho;
            let direction = cos(rho) * r + (sin(rho) / rho) * (x * t1 + y * t2);
            sum = sum + w * sample_cube(source, source_sampler, 0u, direction, lod);
            total = total + w;
        }
    }
    return sum / max(total, 1e-30);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let r = cube_direction(job.face, pixel.xy / job.target_size);
    return vec4<f32>(prefiltered(r, job.shininess), 1.0);
}
