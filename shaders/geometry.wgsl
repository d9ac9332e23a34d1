// First pass: the scene with its per-vertex PRT radiance (depth written), plus the normal and
// albedo the light pass needs. Both sides of a triangle show its front (no culling).
//
// Textured objects: their transfer is baked per unit texel value, so the interpolated radiance
// and the vertex albedo (the texture's factor) are both multiplied by the texel here. Untextured
// objects are drawn with a white texel: unchanged.
//
// Layered objects (glTF's metallic-roughness) take the same reflection at their equivalent
// shininess, scaled by the split-sum E, over (1 − metallic)(1 − E) of their PRT radiance.
//
// Normal-mapped objects shade with the normal their map gives (glTF's tangent space): the
// G-buffer holds it for the lights, reflections leave by it, and the PRT radiance, baked for the
// vertex normal, is scaled by the SH irradiance at the mapped normal over that at the vertex
// normal (CONVENTIONS.md, "Normal maps").
//
// Emitting objects add the radiance they emit (glTF's emission), which the bake does not
// carry to other surfaces (CONVENTIONS.md, "Emission").
//
// Glossy objects add k_s times their specular occlusion times the prefiltered reflection map of
// their shininess at the mirror direction (the environment beyond the lights; the lights' lobes
// are the light pass's), and write their material index into the normal's w.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var albedo_texture: texture_2d<f32>;
@group(1) @binding(1) var albedo_sampler: sampler;
@group(1) @binding(2) var normal_texture: texture_2d<f32>;
@group(1) @binding(3) var emissive_texture: texture_2d<f32>;
@group(1) @binding(4) var<uniform> surface: Surface;

struct Surface {
    // x: the normal map's scale; y: 1 where the object has a normal map.
    normal_map: vec4<f32>,
    // rgb: the radiance it emits (glTF's emissive factor times strength); w: 1 where the
    // emissive texture multiplies it.
    emission: vec4<f32>,
};
@group(0) @binding(1) var<uniform> materials: Materials;
// Six layers (one cube) per shininess slot.
@group(0) @binding(2) var reflection_maps: texture_2d_array<f32>;
@group(0) @binding(3) var reflection_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) radiance: vec4<f32>,
    @location(4) uv: vec2<f32>,
    @location(5) material: u32,
    // The cone the vertex sees the sky in: its bent normal (xyz) and the bake's unoccluded
    // fraction V (w), cosine-weighted.
    @location(6) visibility: vec4<f32>,
    // The interreflected part of `radiance`.
    @location(7) indirect: vec4<f32>,
    // glTF's tangent: xyz along +u, w the bitangent's sign (zero without a normal map).
    @location(10) tangent: vec4<f32>,
};

// The live composite's (`vs_composite`): the radiance of the proxies alone (their transfer
// baked without the virtual objects; zero on the objects) and whether the vertex is a proxy's.
struct ProxyIn {
    @location(8) without_objects: vec4<f32>,
    @location(9) proxy: f32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) albedo: vec3<f32>,
    @location(2) radiance: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) @interpolate(flat) material: u32,
    @location(5) visibility: vec4<f32>,
    @location(6) position: vec3<f32>,
    @location(7) indirect: vec3<f32>,
    @location(8) without_objects: vec3<f32>,
    @location(9) @interpolate(flat) proxy: f32,
    @location(10) tangent: vec4<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    return vertex(in);
}

fn vertex(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(in.position, 1.0);
    out.normal = in.normal;
    out.albedo = in.albedo;
    out.radiance = in.radiance.xyz;
    out.uv = in.uv;
    out.material = in.material;
    out.visibility = in.visibility;
    out.position = in.position;
    out.indirect = in.indirect.xyz;
    out.tangent = in.tangent;
    return out;
}

@vertex
fn vs_composite(in: VertexIn, proxy: ProxyIn) -> VertexOut {
    var out = vertex(in);
    out.without_objects = proxy.without_objects.xyz;
    out.proxy = proxy.proxy;
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    // The depth again, as a colour the light pass can read on every backend (OpenGL cannot
    // load from depth textures).
    @location(3) depth: vec4<f32>,
};

// ρ/π E(n) from `frame.sh_irradiance`: the real SH of bands 0–2 at n (CONVENTIONS.md: polar
// axis +Y, azimuth from +Z toward +X, no Condon–Shortley phase).
fn sh_irradiance_over_pi(n: vec3<f32>) -> vec3<f32> {
    let c = frame.sh_irradiance;
    var e = c[0].xyz * 0.282095;
    e += 0.488603 * (c[1].xyz * n.x + c[2].xyz * n.y + c[3].xyz * n.z);
    e += c[4].xyz * (1.092548 * n.z * n.x);
    e += c[5].xyz * (1.092548 * n.x * n.y);
    e += c[6].xyz * (0.315392 * (3.0 * n.y * n.y - 1.0));
    e += c[7].xyz * (1.092548 * n.z * n.y);
    e += c[8].xyz * (0.546274 * (n.z * n.z - n.x * n.x));
    return e;
}

fn split_sum_texel(i: u32, j: u32) -> vec2<f32> {
    let k = j * SPLIT_SUM_SIZE + i;
    let pair = materials.split_sum[k / 2u];
    return select(pair.xy, pair.zw, (k & 1u) == 1u);
}

// The split-sum terms (A, B) at n·v and roughness, bilinear between texel centres.
fn split_sum(cos_v: f32, roughness: f32) -> vec2<f32> {
    let n = f32(SPLIT_SUM_SIZE);
    let p = clamp(vec2<f32>(cos_v, roughness) * n - 0.5, vec2<f32>(0.0), vec2<f32>(n - 1.0));
    let k = min(vec2<u32>(floor(p)), vec2<u32>(SPLIT_SUM_SIZE - 2u));
    let t = p - vec2<f32>(k);
    let top = mix(split_sum_texel(k.x, k.y), split_sum_texel(k.x + 1u, k.y), t.x);
    let bottom = mix(split_sum_texel(k.x, k.y + 1u), split_sum_texel(k.x + 1u, k.y + 1u), t.x);
    return mix(top, bottom, t.y);
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    return shade(in);
}

struct CompositeOut {
    @location(0) color: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) depth: vec4<f32>,
    // The proxies alone (CONVENTIONS.md, "Compositing"): their PRT radiance without the
    // objects, alpha 1 where a proxy is nearest, 0 on the objects.
    @location(4) without_objects: vec4<f32>,
};

// The live composite's first pass: as `fs_main`, plus the image of the proxies alone (the
// light pass adds their lights without the objects).
@fragment
fn fs_composite(in: VertexOut) -> CompositeOut {
    let shaded = shade(in);
    var out: CompositeOut;
    out.color = shaded.color;
    out.normal = shaded.normal;
    out.albedo = shaded.albedo;
    out.depth = shaded.depth;
    let texel = textureSample(albedo_texture, albedo_sampler, in.uv).rgb;
    if in.proxy > 0.5 {
        var without = in.without_objects * texel;
        // Unshadowed SH per pixel does not depend on the objects: as the scene's.
        if (frame.flags & 4u) != 0u {
            without = shaded.color.xyz;
        }
        out.without_objects = vec4<f32>(without, 1.0);
    }
    return out;
}

// The shading normal of a tangent-space normal map's texel (`perturbed_normal` in
// foundation/src/mesh/tangents.rs): the tangent made orthogonal to n, the bitangent
// cross(n, t) times the sign, x and y scaled; n itself where the frame is degenerate.
fn perturbed_normal(n: vec3<f32>, tangent: vec4<f32>, texel: vec3<f32>, scale: f32) -> vec3<f32> {
    let along = tangent.xyz - n * dot(n, tangent.xyz);
    if dot(along, along) < 1e-12 {
        return n;
    }
    let t = normalize(along);
    let b = cross(n, t) * select(1.0, -1.0, tangent.w < 0.0);
    let m = (texel * 2.0 - 1.0) * vec3<f32>(scale, scale, 1.0);
    let mapped = t * m.x + b * m.y + n * m.z;
    if dot(mapped, mapped) < 1e-12 {
        return n;
    }
    return normalize(mapped);
}

// What the PRT radiance, baked for the vertex normal, is scaled by at a mapped normal: the
// unshadowed SH irradiance's luminance there over at the vertex normal, kept within [0, 4]
// (1 where the vertex normal sees almost no light).
fn normal_map_ratio(vertex_normal: vec3<f32>, mapped: vec3<f32>) -> f32 {
    let weights = vec3<f32>(0.2126, 0.7152, 0.0722);
    let at_vertex = dot(max(sh_irradiance_over_pi(vertex_normal), vec3<f32>(0.0)), weights);
    let at_mapped = dot(max(sh_irradiance_over_pi(mapped), vec3<f32>(0.0)), weights);
    return select(1.0, clamp(at_mapped / at_vertex, 0.0, 4.0), at_vertex > 1e-6);
}

// The PRT radiance and the G-buffer of one fragment.
fn shade(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    let vertex_normal = normalize(in.normal);
    let texel = textureSample(albedo_texture, albedo_sampler, in.uv).rgb;
    var normal = vertex_normal;
    out.color = vec4<f32>(in.radiance * texel, 1.0);
    // The surface's flags are uniform: the branches below sample in uniform control flow, and
    // objects without a normal map or emissive texture read neither.
    if surface.normal_map.y > 0.5 {
        let normal_texel = textureSample(normal_texture, albedo_sampler, in.uv).rgb;
        normal = perturbed_normal(vertex_normal, in.tangent, normal_texel, surface.normal_map.x);
        out.color = vec4<f32>(out.color.xyz * normal_map_ratio(vertex_normal, normal), 1.0);
    }
    if (frame.flags & 4u) != 0u {
        out.color = vec4<f32>(in.albedo * texel * max(sh_irradiance_over_pi(normal), vec3<f32>(0.0)), 1.0);
    }
    if in.material != 0u {
        let material = materials.entries[in.material];
        let r = mirror_direction(normalize(frame.camera_position.xyz - in.position), normal);
        let r_map = (frame.reflection_to_map * vec4<f32>(r, 0.0)).xyz;
        let environment = sample_cube(reflection_maps, reflection_sampler, 6u * material.slot.x, r_map, 0.0);
        // Specular occlusion by cones (CONVENTIONS.md, "Glossy materials"): the sky is seen
        // in a cone around the bent normal whose cosine-weighted share of the hemisphere is V
        // (half-angle asin √V), the lobe is a cone of about 1/√(s + 1) around r, and the share
        // of the lobe inside the sky's cone sees the environment, the rest the occluders,
        // whose mean radiance is the bake's interreflected radiance over the albedo,
        // E_occluded / π, divided by their share 1 − V.
        let unoccluded = clamp(in.visibility.w, 0.0, 1.0);
        let bent = normalize(in.visibility.xyz + vec3<f32>(0.0, 0.0, 1e-12));
        let sky_cone = asin(sqrt(unoccluded));
        let lobe_cone = 1.0 / sqrt(material.specular.w + 1.0);
        let offset = acos(clamp(dot(r, bent), -1.0, 1.0));
        var seen = clamp((sky_cone - offset) / (2.0 * lobe_cone) + 0.5, 0.0, 1.0);
        if material.layer.z > 0.5 {
            // The split sum's E already leaves out the lobe's share below the horizon (GGX's
            // masking): only what the occluders hide beyond it is theirs, the share seen over
            // that seen by an unoccluded point (whose sky is the hemisphere around n).
            let open = clamp((0.5 * GLOSSY_PI - acos(clamp(dot(r, normal), -1.0, 1.0))) / (2.0 * lobe_cone) + 0.5, 0.0, 1.0);
            seen = select(seen, min(seen / open, 1.0), open > 1e-3);
        }
        let seen_albedo = in.albedo;
        let occluded_light = select(vec3<f32>(0.0), in.indirect / max(seen_albedo, vec3<f32>(1e-4)), seen_albedo > vec3<f32>(1e-4));
        let occluders = max(occluded_light, vec3<f32>(0.0)) / max(1.0 - unoccluded, 0.05);
        // The "ibl" peer: no occlusion from the bake.
        if (frame.flags & 8u) != 0u {
            seen = 1.0;
        }
        let reflected = seen * environment + (1.0 - seen) * occluders;
        if material.layer.z > 0.5 {
            // The layer reflects E = F₀ A + B of the environment (split sum) and lets the
            // base below it keep (1 − E) of its PRT radiance, which the bake holds for the
            // base colour: (1 − metallic) of it is the diffuse colour (CONVENTIONS.md,
            // "Metallic-roughness materials").
            let base = in.albedo * texel;
            let metallic = material.layer.x;
            let front = front_view(normalize(frame.camera_position.xyz - in.position), normal);
            let terms = split_sum(dot(normal, front), material.layer.y);
            let e = layer_f0(base, metallic) * terms.x + terms.y;
            let diffuse = out.color.xyz * (1.0 - metallic) * (1.0 - e);
            out.color = vec4<f32>(diffuse + e * reflected, 1.0);
        } else {
            out.color = out.color + vec4<f32>(material.specular.rgb * reflected, 0.0);
        }
    }
    // Emission: added as it is, from both sides (the light pass adds the lights' on top).
    var emitted = surface.emission.rgb;
    if surface.emission.w > 0.5 {
        emitted *= textureSample(emissive_texture, albedo_sampler, in.uv).rgb;
    }
    out.color = out.color + vec4<f32>(emitted, 0.0);
    // w: the material index (exact in a half float) for the light pass.
    out.normal = vec4<f32>(normal, f32(in.material));
    out.albedo = vec4<f32>(in.albedo * texel, 1.0);
    out.depth = encode_depth(in.clip.z);
    return out;
}
