// Per-pixel unshadowed SH shading (flag bit 2 of `Frame`), shared by the PRT pass and the
// live composite's proxy pass. Expects `frame` declared by the shader.

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
