// Glossy materials (CONVENTIONS.md, "Glossy materials"): the normalised Phong lobe, the mirror
// direction, glTF's metallic-roughness layer ("Metallic-roughness materials": GGX, Smith
// height-correlated visibility, Schlick's Fresnel, and the split-sum table), and cube maps stored as six layers of a 2D array (faces in the order +X, -X, +Y,
// -Y, +Z, -Z, each read as `foundation/src/envmap/faces.rs` does: (forward, right, down)).

struct Material {
    // k_s in rgb, shininess s in w (k_s = 0: diffuse; a layer's s is its equivalent one).
    specular: vec4<f32>,
    // x: the reflection-map slot of its shininess.
    slot: vec4<u32>,
    // A metallic-roughness layer: (metallic, roughness, 1, 0); zero without one.
    layer: vec4<f32>,
};

struct Materials {
    // Entry 0 is the diffuse material.
    entries: array<Material, MAX_MATERIALS>,
    // The split-sum terms (A, B) over n·v (across) and roughness (down), texel centres at
    // (k + 0.5)/SPLIT_SUM_SIZE, two texels per vector.
    split_sum: array<vec4<f32>, SPLIT_SUM_PAIRS>,
};

const GLOSSY_PI: f32 = 3.14159265358979;

// D_s(α) = (s + 1)/(2π) cos^s α, zero beyond 90°.
fn phong_lobe(cos_alpha: f32, shininess: f32) -> f32 {
    if cos_alpha <= 0.0 {
        return 0.0;
    }
    return (shininess + 1.0) / (2.0 * GLOSSY_PI) * pow(cos_alpha, shininess);
}

// The layer's F₀ and diffuse colour: F₀ = lerp(0.04, base, metallic), c = (1 − metallic) base.
fn layer_f0(base: vec3<f32>, metallic: f32) -> vec3<f32> {
    return mix(vec3<f32>(0.04), base, metallic);
}

// f cos of the metallic-roughness BRDF toward unit `l` for the view `v` (both toward the
// outside, `v` in front of `n`) at GGX's α: the base's (1 − F) c/π and the layer's F D V, each
// times n·l. As `foundation/src/material/metallic_roughness.rs`.
fn layer_f_cos(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base: vec3<f32>, metallic: f32, alpha: f32) -> vec3<f32> {
    let cos_l = dot(n, l);
    if cos_l <= 0.0 {
        return vec3<f32>(0.0);
    }
    let cos_v = max(dot(n, v), 1e-4);
    let h = normalize(v + l);
    let fresnel = layer_f0(base, metallic) + (1.0 - layer_f0(base, metallic)) * pow(1.0 - clamp(dot(v, h), 0.0, 1.0), 5.0);
    let a2 = alpha * alpha;
    let cos_h = max(dot(n, h), 0.0);
    let d_denominator = cos_h * cos_h * (a2 - 1.0) + 1.0;
    let d = a2 / (GLOSSY_PI * d_denominator * d_denominator);
    let gv = cos_l * sqrt(cos_v * cos_v * (1.0 - a2) + a2);
    let gl = cos_v * sqrt(cos_l * cos_l * (1.0 - a2) + a2);
    let visibility = 0.5 / max(gv + gl, 1e-12);
    let diffuse = (1.0 - fresnel) * (1.0 - metallic) * base / GLOSSY_PI;
    return (diffuse + fresnel * d * visibility) * cos_l;
}

// The view `v` seen from the front of `n` (a view from behind mirrored through the tangent
// plane, as `mirror_direction` does).
fn front_view(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let c = dot(n, v);
    return select(v, v - 2.0 * c * n, c < 0.0);
}

// The mirror direction of the view `v` (toward the viewer) about `n`, a view from behind
// first mirrored through the tangent plane (both sides show the front).
fn mirror_direction(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let c = dot(n, v);
    let front = select(v, v - 2.0 * c * n, c < 0.0);
    return 2.0 * dot(n, front) * n - front;
}

// (forward, right, down) of a face.
fn face_forward(face: u32) -> vec3<f32> {
    switch face {
        case 0u: { return vec3<f32>(1.0, 0.0, 0.0); }
        case 1u: { return vec3<f32>(-1.0, 0.0, 0.0); }
        case 2u: { return vec3<f32>(0.0, 1.0, 0.0); }
        case 3u: { return vec3<f32>(0.0, -1.0, 0.0); }
        case 4u: { return vec3<f32>(0.0, 0.0, 1.0); }
        default: { return vec3<f32>(0.0, 0.0, -1.0); }
    }
}

fn face_right(face: u32) -> vec3<f32> {
    switch face {
        case 0u: { return vec3<f32>(0.0, 0.0, 1.0); }
        case 1u: { return vec3<f32>(0.0, 0.0, -1.0); }
        case 4u: { return vec3<f32>(-1.0, 0.0, 0.0); }
        default: { return vec3<f32>(1.0, 0.0, 0.0); }
    }
}

fn face_down(face: u32) -> vec3<f32> {
    switch face {
        case 2u: { return vec3<f32>(0.0, 0.0, -1.0); }
        case 3u: { return vec3<f32>(0.0, 0.0, 1.0); }
        default: { return vec3<f32>(0.0, -1.0, 0.0); }
    }
}

// The unit direction through texture coordinates `uv` of `face`.
fn cube_direction(face: u32, uv: vec2<f32>) -> vec3<f32> {
    let ab = uv * 2.0 - 1.0;
    return normalize(face_forward(face) + face_right(face) * ab.x + face_down(face) * ab.y);
}

// The face `w` falls on (ties as in cube.rs: x, then y, then z) and its texture coordinates.
fn cube_face_uv(w: vec3<f32>) -> vec3<f32> {
    let a = abs(w);
    var face = 0u;
    if a.x >= a.y && a.x >= a.z {
        face = select(1u, 0u, w.x > 0.0);
    } else if a.y >= a.z {
        face = select(3u, 2u, w.y > 0.0);
    } else {
        face = select(5u, 4u, w.z > 0.0);
    }
    let f = dot(w, face_forward(face));
    let ab = vec2<f32>(dot(w, face_right(face)), dot(w, face_down(face))) / f;
    return vec3<f32>(f32(face), ab * 0.5 + 0.5);
}

// Filtered radiance along `w` from the cube in layers 6·first_layer/6 … of `maps`.
fn sample_cube(maps: texture_2d_array<f32>, maps_sampler: sampler, first_layer: u32, w: vec3<f32>, lod: f32) -> vec3<f32> {
    let at = cube_face_uv(w);
    return textureSampleLevel(maps, maps_sampler, at.yz, i32(first_layer + u32(at.x)), lod).xyz;
}
