// Second pass, added onto the first: each directional light's contribution
// (ρ/π · max(0, n·d) + k_s D_s'(r·d)) · power · visibility, or a metallic-roughness surface's
// f cos (its GGX lobe widened likewise), the Phong lobe of glossy surfaces
// widened by the source's size (s' < s, still normalised: CONVENTIONS.md, "Glossy materials"), visibility by percentage-closer soft shadows on its
// shadow map (blocker search, then PCF over the penumbra the source's size gives). Pixels that see no geometry show the environment map.

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
// Trilinear, wrapping in azimuth.
@group(0) @binding(9) var environment_sampler: sampler;
@group(0) @binding(10) var<uniform> materials: Materials;


const PI: f32 = 3.14159265358979;

// Pipeline constants: the renderer builds one pipeline per combination, so the shader run per
// pixel contains only the code it needs.
// Whether lights cast shadows.
override SHADOWED: bool = true;
// Whether PCF kernels are sized from the light's angular radius (blocker search).
override KERNEL_FROM_RADIUS: bool = true;

fn shadow_coordinates(light: Light, position: vec3<f32>) -> vec3<f32> {
    let clip = light.shadow_matrix * vec4<f32>(position, 1.0);
    return vec3<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5, clip.z);
}

// Samples of the blocker search and of the PCF kernel: the centre plus points of a Vogel
// (golden-angle) spiral, which covers the unit disc evenly at any count. The spiral is turned
// per pixel, so what falls between its points on one pixel is sampled on its neighbours.
const BLOCKER_SAMPLES: u32 = 12u;
const PCF_SAMPLES: u32 = 12u;
const GOLDEN_ANGLE: f32 = 2.39996323;
// Largest search and PCF radius, in shadow-map texels. Penumbra errors of the teapot under the
// studio, hall and forest maps (2048² maps) were lowest at 32–64 texels and grew beyond (the
// receiver's tangent plane and one mean blocker depth stand for less of a wider kernel); 64
// cost half as much again on llvmpipe (CONVENTIONS.md).
const MAX_KERNEL: f32 = 32.0;

// Point `i` of an `n`-point Vogel spiral on the unit disc, turned by `phase` radians.
fn vogel(i: u32, n: u32, phase: f32) -> vec2<f32> {
    let r = sqrt((f32(i) + 0.5) / f32(n));
    let a = f32(i) * GOLDEN_ANGLE + phase;
    return r * vec2<f32>(cos(a), sin(a));
}

// Interleaved gradient noise (Jimenez 2014): a per-pixel angle with little low-frequency
// structure, so the turned spirals dither instead of banding.
fn pixel_phase(pixel: vec2<f32>) -> f32 {
    return 2.0 * PI * fract(52.9829189 * fract(dot(pixel, vec2<f32>(0.06711056, 0.00583715))));
}

// Occluders within `radius` texels of `uv`: the centre texel and a spiral of texels, each
// compared with the receiver plane's depth there. The centre is always among them, so a point
// in any umbra, however thin its occluder, finds a blocker. Returns (mean occluder depth,
// occluding samples); 0 occluding samples means fully lit.
fn blockers(layer: i32, uv: vec2<f32>, receiver: f32, slope: vec2<f32>, radius: f32, phase: f32) -> vec2<f32> {
    let size = vec2<f32>(textureDimensions(shadow_depths));
    let last = vec2<i32>(size) - vec2<i32>(1);
    let slack = (abs(slope.x) + abs(slope.y)) * 2.0 / size.x + 1e-5;
    var sum = 0.0;
    var count = 0.0;
    for (var i = 0u; i <= BLOCKER_SAMPLES; i = i + 1u) {
        var offset = vec2<f32>(0.0);
        if i > 0u {
            offset = vogel(i - 1u, BLOCKER_SAMPLES, phase) * radius;
        }
        let at = clamp(vec2<i32>(floor(uv * size + offset)), vec2<i32>(0), last);
        let depth = decode_depth(textureLoad(shadow_depths, at, layer, 0));
        let local = (vec2<f32>(at) + 0.5) / size - uv;
        // Extrapolated past the map's far plane, the receiver is as far as nothing drawn.
        let plane = min(receiver + dot(slope, vec2<f32>(2.0 * local.x, -2.0 * local.y)) - slack, 1.0);
        if depth < plane {
            sum = sum + depth;
            count = count + 1.0;
        }
    }
    if count == 0.0 {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(sum / count, count);
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
fn pcf(layer: i32, coords: vec3<f32>, slope: vec2<f32>, radius: f32) -> f32 {
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

// Distance from the kernel's centre, in texels, of the point at fraction `u` of the power of
// a source that is a disc of radius `core` holding `fraction` of it inside a disc of radius
// `halo` holding the rest (the inverse of the pair's radial distribution; a uniform disc when
// `fraction` is 1).
fn source_radius(u: f32, core: f32, halo: f32, fraction: f32) -> f32 {
    // Inside the core both discs contribute: F(r) = r² (f / core² + (1 − f) / halo²).
    let density = fraction / (core * core) + (1.0 - fraction) / (halo * halo);
    if u <= density * core * core {
        return sqrt(u / density);
    }
    // Outside it only the halo: F(r) = f + (1 − f) r² / halo².
    return halo * sqrt((u - fraction) / (1.0 - fraction));
}

// Fraction of `light` visible at `coords` through a kernel shaped as its source, a core disc
// of `core` texels in a halo disc of `halo` texels: the centre and a turned spiral of
// hardware-filtered (2×2) comparisons, each against the receiver plane's depth there, the
// spiral's radii spaced so each point stands for an equal share of the source's power.
fn pcf_source(layer: i32, coords: vec3<f32>, slope: vec2<f32>, core: f32, halo: f32, fraction: f32, phase: f32) -> f32 {
    let size = vec2<f32>(textureDimensions(shadow_maps));
    let slack = 0.5 * (abs(slope.x) + abs(slope.y)) * 2.0 / size.x + 1e-5;
    var lit = 0.0;
    for (var i = 0u; i <= PCF_SAMPLES; i = i + 1u) {
        var offset = vec2<f32>(0.0);
        if i > 0u {
            let point = vogel(i - 1u, PCF_SAMPLES, phase);
            // The Vogel point's radius is √u; move it to the source's radius at u.
            let u = (f32(i - 1u) + 0.5) / f32(PCF_SAMPLES);
            offset = point * (source_radius(u, core, halo, fraction) / sqrt(u)) / size;
        }
        let depth = min(coords.z + dot(slope, vec2<f32>(2.0 * offset.x, -2.0 * offset.y)) - slack, 1.0);
        lit = lit + textureSampleCompareLevel(shadow_maps, shadow_sampler, coords.xy + offset, layer, depth);
    }
    return lit / f32(PCF_SAMPLES + 1u);
}

// World-space offset along the normal before the shadow lookup (normal-offset bias): a texel's
// footprint, growing as the surface turns from the light, where the depth of one shadow-map
// texel spreads over more of the receiver.
fn normal_offset(light: Light, normal: vec3<f32>) -> vec3<f32> {
    let cosine = clamp(dot(normal, light.direction.xyz), 0.0, 1.0);
    let sine = sqrt(1.0 - cosine * cosine);
    return normal * (light.params.x * sine);
}

// Fraction of light `index` visible at `position` through its shadow map in `layer`.
fn visibility(index: u32, layer: i32, position: vec3<f32>, normal: vec3<f32>, phase: f32) -> f32 {
    let light = lights[index];
    let coords = shadow_coordinates(light, position + normal_offset(light, normal));
    if coords.x < 0.0 || coords.x > 1.0 || coords.y < 0.0 || coords.y > 1.0 || coords.z > 1.0 {
        return 1.0;
    }
    let slope = receiver_depth_slope(light, normal);
    if !KERNEL_FROM_RADIUS {
        return pcf(layer, coords, slope, 1.0);
    }
    // Search as wide as the widest penumbra can be: a distant source of angular radius α
    // behind an occluder at distance d gives a half-width d tan α, d at most the map's depth.
    // No early exit: every pixel searches the whole disc, so no shadow narrower than the
    // kernel is skipped.
    let widest = clamp(light.params.y * light.source.x / light.params.x, 1.0, MAX_KERNEL);
    let found = blockers(layer, coords.xy, coords.z, slope, widest, phase);
    if found.y == 0.0 {
        return 1.0;
    }
    let distance = max(coords.z - found.x, 0.0) * light.params.y;
    let core = clamp(distance * light.params.z / light.params.x, 0.75, MAX_KERNEL);
    let halo = clamp(distance * light.source.x / light.params.x, core, MAX_KERNEL);
    return pcf_source(layer, coords, slope, core, halo, light.source.y, phase);
}

// The background: the environment where no geometry is (when shown).
fn background(pixel: vec2<f32>) -> vec4<f32> {
    if (frame.flags & 2u) == 0u {
        return vec4<f32>(0.0);
    }
    let ndc = pixel_ndc(pixel);
    let direction = view_ray(ndc);
    let next = view_ray(ndc + vec2<f32>(2.0 * frame.viewport.z, 0.0));
    let pixel_angle = acos(clamp(dot(direction, next), -1.0, 1.0));
    return vec4<f32>(environment_radiance(direction, pixel_angle), 0.0);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let depth = decode_depth(textureLoad(depth_buffer, vec2<i32>(pixel.xy), 0));
    if depth >= 1.0 {
        return background(pixel.xy);
    }
    return vec4<f32>(direct_light(pixel.xy, depth, false).with_objects, 0.0);
}

// Normalised device coordinates of a pixel (its centre when given one).
fn pixel_ndc(pixel: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(pixel.x * frame.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * frame.viewport.w * 2.0);
}

struct Lit {
    with_objects: vec3<f32>,
    // The same lights as the proxies alone receive them (when asked).
    without_objects: vec3<f32>,
};

// Light `index`'s visibility through every occluder (x) and, with `proxies_alone`, through
// the proxies alone (y: their own map, `frame.proxy_layers` layers on). The proxies are among
// every occluder, so where a light is wholly visible it is through the proxies alone too:
// their map is read only where the light is shadowed. One call site of `visibility` in a loop
// whose trip count the compiler cannot know: a second inlined copy made software rasterizers'
// shaders far slower.
fn visibilities(index: u32, position: vec3<f32>, normal: vec3<f32>, phase: f32, proxies_alone: bool) -> vec2<f32> {
    var v = vec2<f32>(1.0);
    // No layers of their own: the proxies cannot shadow themselves (all light).
    let maps = select(1u, 2u, proxies_alone && frame.proxy_layers > 0u);
    for (var k = 0u; k < maps; k = k + 1u) {
        let layer = i32(lights[index].params.w) + i32(k * frame.proxy_layers);
        let seen = visibility(index, layer, position, normal, phase);
        if k == 0u {
            v = vec2<f32>(seen, 1.0);
            if seen >= 1.0 {
                break;
            }
        } else {
            v.y = seen;
        }
    }
    return v;
}

// A light's angular variance per axis: its core and halo discs (tangents of their radii)
// weighted by their shares of the power. What widens a glossy lobe toward it.
fn source_variance(light: Light) -> f32 {
    let core = light.params.z;
    let halo = light.source.x;
    let share = light.source.y;
    return (share * core * core + (1.0 - share) * halo * halo) / 4.0;
}

// Every light's direct contribution at the surface the G-buffer holds at `pixel`, and with
// `proxies_alone` also as the proxies alone receive it.
fn direct_light(pixel: vec2<f32>, depth: f32, proxies_alone: bool) -> Lit {
    let texel = vec2<i32>(pixel);
    let world = frame.inv_view_proj * vec4<f32>(pixel_ndc(pixel), depth, 1.0);
    let position = world.xyz / world.w;
    let normal_and_material = textureLoad(normal_buffer, texel, 0);
    let normal = normal_and_material.xyz;
    let albedo = textureLoad(albedo_buffer, texel, 0).xyz;
    let diffuse = albedo / PI;
    let material = materials.entries[u32(normal_and_material.w + 0.5)];
    let glossy = material.specular.r + material.specular.g + material.specular.b > 0.0;
    let layered = material.layer.z > 0.5;
    let view = normalize(frame.camera_position.xyz - position);
    var r = vec3<f32>(0.0);
    if glossy {
        r = mirror_direction(view, normal);
    }
    let front = front_view(view, normal);
    let roughness_alpha = max(material.layer.y * material.layer.y, 1e-3);
    let phase = pixel_phase(pixel);
    var sum = vec3<f32>(0.0);
    var without = vec3<f32>(0.0);
    // A constant trip count with an early break lets the compiler unroll the loop and index
    // the light array with constants.
    for (var i = 0u; i < 32u; i = i + 1u) {
        if i >= frame.light_count {
            break;
        }
        let direction = lights[i].direction.xyz;
        let cosine = dot(normal, direction);
        if cosine > 0.0 {
            var v = vec2<f32>(1.0);
            if SHADOWED {
                v = visibilities(i, position, normal, phase, proxies_alone);
            }
            if layered {
                // The layer's lobe widened by the source as the Phong lobe is: its peak
                // matches Phong's at 1/s = 2α², so the source's variance adds half of itself
                // to α² (CONVENTIONS.md, "Metallic-roughness materials").
                let alpha = sqrt(roughness_alpha * roughness_alpha + 0.5 * source_variance(lights[i]));
                let f_cos = layer_f_cos(normal, front, direction, albedo, material.layer.x, alpha);
                sum = sum + f_cos * lights[i].power.xyz * v.x;
                without = without + f_cos * lights[i].power.xyz * v.y;
            } else if glossy {
                let shininess = 1.0 / (1.0 / material.specular.w + source_variance(lights[i]));
                let specular = material.specular.rgb * phong_lobe(dot(r, direction), shininess);
                sum = sum + (diffuse * cosine + specular) * lights[i].power.xyz * v.x;
                without = without + (diffuse * cosine + specular) * lights[i].power.xyz * v.y;
            } else {
                sum = sum + diffuse * lights[i].power.xyz * (cosine * v.x);
                without = without + diffuse * lights[i].power.xyz * (cosine * v.y);
            }
        }
    }
    return Lit(sum, without);
}
