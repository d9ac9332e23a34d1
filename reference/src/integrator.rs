//! The path tracer: next-event estimation with environment importance sampling, combined by
//! multiple importance sampling (power heuristic) with sampling of the surface's BRDF:
//! cosine-weighted for a Lambertian surface; for a glossy one ([`foundation::material`]) the
//! diffuse part or the Phong lobe, chosen by their reflectances' luminance (one-sample MIS
//! over the two: the pdf is their mixture); for a metallic-roughness one the diffuse base or
//! the GGX layer's visible normals, alike.

use super::light::{EnvironmentLight, PendingTexel};
use super::sampler::PathSampler;
use foundation::bvh::RAY_OFFSET_FRACTION;
use foundation::bvh::{Hit, SceneBvh, Skip};
use foundation::color::{Rgb, luminance};
use foundation::infra::huge_pages::HugePageTable;
use foundation::material::{Material, SurfaceBsdf};
use foundation::sampling::{Frame, cosine_hemisphere, cosine_hemisphere_pdf, power_heuristic};
use foundation::scene::{NO_TEXTURE, SceneMesh};
use glam::Vec3;

/// A shading point.
#[derive(Debug, Clone, Copy)]
pub struct SurfacePoint {
    pub position: Vec3,
    /// Interpolated vertex normal: the Lambertian cosine and sampling hemisphere.
    pub shading_normal: Vec3,
    /// Geometric normal on the front side: rays leave from this side.
    pub front_normal: Vec3,
    pub albedo: Rgb,
    /// The specular lobe (diffuse surfaces: [`Material::DIFFUSE`]).
    pub material: Material,
    /// The radiance it emits toward every direction (zero for most surfaces).
    pub emitted: Rgb,
    /// Which triangles a ray leaving the point must not hit: the one it leaves, or, for a ray
    /// leaving a vertex, every triangle sharing the vertex (as in the bake).
    pub leaving: Skip,
}

/// One path's estimate of the radiance leaving its first point.
#[derive(Debug, Clone, Copy, Default)]
pub struct PathEstimate {
    pub radiance: Rgb,
    /// The part of `radiance` reflected by the first point's specular lobe (zero on diffuse
    /// surfaces): what decides a report's highlight region.
    pub specular: Rgb,
    pub direct: DirectVisibility,
}

/// Light reaching the first shading point directly from the environment, in luminance: what
/// is visible and what would be without occlusion (their ratio is the direct visibility).
#[derive(Debug, Clone, Copy, Default)]
pub struct DirectVisibility {
    pub visible: f32,
    pub unoccluded: f32,
}

/// What a hit reads of each corner.
#[derive(Debug, Clone, Copy)]
struct ShadingVertex {
    position: Vec3,
    normal: Vec3,
    albedo: Rgb,
}

/// What a hit reads of its triangle: its corners' records in one place (two cache lines,
/// asked for together), not behind their indices.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct ShadingTriangle {
    corners: [ShadingVertex; 3],
    front_normal: Vec3,
}

/// One radiance estimate per call; everything it needs is borrowed.
pub struct Integrator<'a> {
    pub geometry: &'a SceneMesh,
    pub bvh: &'a SceneBvh,
    pub light: &'a EnvironmentLight<'a>,
    /// Indirect bounces after the first shading point (0: direct lighting only).
    pub bounces: u32,
    offset: f32,
    /// The mesh's shading data regrouped so that a hit reads one record, its triangle's,
    /// with its corners inside (a path's hits land anywhere in the mesh: each read is a cache
    /// miss, and a corner read through an index would wait on the triangle's).
    triangles: HugePageTable<ShadingTriangle>,
    /// Per triangle, its texture in `geometry.textures` or [`NO_TEXTURE`]; empty for an
    /// untextured scene, whose hits then read nothing more than before.
    triangle_textures: Vec<u32>,
    /// Per triangle, its normal map in `geometry.normal_maps` or [`NO_TEXTURE`]; empty for a
    /// scene without normal maps.
    triangle_normal_maps: Vec<u32>,
    /// Per triangle, its emission in `geometry.emissions` or [`NO_TEXTURE`]; empty for a scene
    /// that emits nothing, whose paths then end on their last bounce as before.
    triangle_emissions: Vec<u32>,
    /// Per triangle, its material; empty for a diffuse scene.
    triangle_materials: HugePageTable<Material>,
}

impl<'a> Integrator<'a> {
    pub fn new(
        geometry: &'a SceneMesh,
        bvh: &'a SceneBvh,
        light: &'a EnvironmentLight<'a>,
        bounces: u32,
    ) -> Self {
        let mesh = &geometry.mesh;
        Self {
            geometry,
            bvh,
            light,
            bounces,
            offset: RAY_OFFSET_FRACTION * geometry.diagonal(),
            triangles: HugePageTable::new((0..mesh.triangle_count()).map(|t| ShadingTriangle {
                corners: mesh.triangles[t].map(|v| {
                    let v = v as usize;
                    ShadingVertex {
                        position: mesh.positions[v],
                        normal: mesh.normals[v],
                        albedo: geometry.albedo[v],
                    }
                }),
                front_normal: mesh.front_normal(t),
            })),
            triangle_textures: if geometry.is_textured() {
                geometry.triangle_textures()
            } else {
                Vec::new()
            },
            triangle_normal_maps: match geometry.normal_maps.is_empty() {
                true => Vec::new(),
                false => geometry.triangle_normal_maps(),
            },
            triangle_emissions: match geometry.emissions.is_empty() {
                true => Vec::new(),
                false => geometry.triangle_emissions(),
            },
            triangle_materials: if !geometry.is_lambertian() {
                geometry.triangle_materials()
            } else {
                Vec::new()
            }
            .into(),
        }
    }

    /// The surface point where a ray from `origin` along `direction` hit. Either side of a
    /// triangle shows its front (CONVENTIONS.md, "Surfaces").
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let triangle = &self.triangles[hit.triangle as usize];
        let weights = hit.barycentrics();
        let mut position = Vec3::ZERO;
        let mut normal = Vec3::ZERO;
        let mut albedo = Rgb::ZERO;
        for (vertex, w) in triangle.corners.iter().zip(weights) {
            position += vertex.position * w;
            normal += vertex.normal * w;
            albedo += vertex.albedo * w;
        }
        if let Some(&texture) = self.triangle_textures.get(hit.triangle as usize)
            && texture != NO_TEXTURE
        {
            // The texel's albedo (times the object's factor, interpolated above).
            albedo *= self.geometry.textures[texture as usize].bilinear(self.hit_uv(hit));
        }
        let front = triangle.front_normal;
        let mut shading_normal = normal.try_normalize().unwrap_or(front);
        if let Some(&map) = self.triangle_normal_maps.get(hit.triangle as usize)
            && map != NO_TEXTURE
        {
            shading_normal = self.mapped_normal(hit, shading_normal, map as usize);
        }
        SurfacePoint {
            emitted: self.emitted(hit),
            position,
            shading_normal,
            front_normal: front,
            albedo,
            material: self
                .triangle_materials
                .get(hit.triangle as usize)
                .copied()
                .unwrap_or_default(),
            leaving: Skip::Triangle(hit.triangle),
        }
    }

    /// The radiance the surface emits at a hit (both sides alike: CONVENTIONS.md, "Emission").
    fn emitted(&self, hit: &Hit) -> Rgb {
        match self.triangle_emissions.get(hit.triangle as usize) {
            Some(&e) if e != NO_TEXTURE => {
                let emission = &self.geometry.emissions[e as usize];
                match emission.texture {
                    None => emission.factor,
                    Some(_) => emission.radiance(self.hit_uv(hit)),
                }
            }
            _ => Rgb::ZERO,
        }
    }

    /// The interpolated texture coordinates at a hit.
    fn hit_uv(&self, hit: &Hit) -> glam::Vec2 {
        let mesh = &self.geometry.mesh;
        mesh.triangles[hit.triangle as usize]
            .iter()
            .zip(hit.barycentrics())
            .map(|(i, w)| mesh.uvs[*i as usize] * w)
            .sum()
    }

    /// The shading normal a normal map gives at a hit whose interpolated normal is `n`.
    fn mapped_normal(&self, hit: &Hit, n: Vec3, map: usize) -> Vec3 {
        let mesh = &self.geometry.mesh;
        let corners = mesh.triangles[hit.triangle as usize];
        let mut tangent: glam::Vec4 = corners
            .iter()
            .zip(hit.barycentrics())
            .map(|(i, w)| mesh.tangents[*i as usize] * w)
            .sum();
        // The sign is the corners' (one per triangle in a well-made mesh).
        tangent.w = mesh.tangents[corners[0] as usize].w;
        self.geometry.normal_maps[map].shading_normal(n, tangent, self.hit_uv(hit))
    }

    /// The point at vertex `v`, with rays leaving as in the bake.
    pub fn vertex(&self, v: u32) -> SurfacePoint {
        let mesh = &self.geometry.mesh;
        let normal = mesh.normals[v as usize];
        SurfacePoint {
            position: mesh.positions[v as usize],
            shading_normal: normal,
            front_normal: normal,
            // The bake's points: light from the environment alone.
            emitted: Rgb::ZERO,
            // On a textured object, the texture's factor: as the bake, per unit texel value.
            albedo: self.geometry.albedo[v as usize],
            material: self
                .geometry
                .objects
                .iter()
                .find(|o| o.vertices.contains(&v))
                .map_or(Material::DIFFUSE, |o| o.material),
            leaving: Skip::VertexTriangles(v),
        }
    }

    #[inline]
    fn origin(&self, p: &SurfacePoint) -> Vec3 {
        p.position + p.front_normal * self.offset
    }

    #[inline]
    fn trace(&self, p: &SurfacePoint, w: Vec3) -> Option<Hit> {
        self.bvh
            .closest_hit(self.origin(p), w, 0.0, f32::INFINITY, p.leaving)
    }

    #[inline]
    fn occluded(&self, p: &SurfacePoint, w: Vec3) -> bool {
        self.bvh
            .occluded(self.origin(p), w, 0.0, f32::INFINITY, p.leaving)
    }

    /// One estimate of the radiance leaving `start` toward `wo` (unit, toward the viewer;
    /// only glossy surfaces depend on it), with `self.bounces` indirect bounces, and the direct
    /// visibility seen at `start`. Counts the rays traced in `rays`.
    pub fn radiance(
        &self,
        start: &SurfacePoint,
        wo: Vec3,
        sampler: &mut impl PathSampler,
        rays: &mut u64,
    ) -> PathEstimate {
        let mut out = PathEstimate::default();
        let mut path = PathVertex {
            point: *start,
            wo,
            before: Rgb::ONE,
            specular_before: Rgb::ZERO,
        };
        // The first vertex's light sample; later ones are drawn as soon as the ray that finds
        // their vertex returns (below).
        let mut light_sample = self.light.sample_texel(sampler.next_2d());
        for depth in 0..=self.bounces {
            let point = path.point;
            // Light the point emits itself, seen along the path (an emitter is found by the
            // path alone, not sampled: weight 1).
            out.radiance += path.before * point.emitted;
            let bsdf = if point.material.is_lambertian() {
                None
            } else {
                let bsdf =
                    SurfaceBsdf::new(point.shading_normal, point.albedo, &point.material, path.wo);
                match bsdf {
                    Some(bsdf) => Some(bsdf),
                    None => break,
                }
            };
            if let Some(sample) = light_sample {
                self.next_event(&path, bsdf.as_ref(), sample, depth, rays, &mut out);
            }
            // Continuation by the BSDF; on escape it is the other MIS strategy for the
            // environment.
            let Some(scatter) = path.scatter(bsdf.as_ref(), sampler.next_2d(), depth) else {
                break;
            };
            let w = scatter.direction;
            // The environment seen along an escaping continuation, MIS-weighted; its texel
            // is asked for now and read after the ray.
            let escape = self.light.escape_texel(w);
            let escaped = || {
                let (le, pdf_light) = self.light.texel_value(escape);
                le * power_heuristic(scatter.pdf, pdf_light)
            };
            *rays += 1;
            if depth == self.bounces {
                self.last_segment(&path, w, escaped, &mut out);
                break;
            }
            match self.trace(&point, w) {
                None => {
                    path.add(escaped(), &mut out);
                    break;
                }
                Some(hit) => {
                    // The next vertex's light sample does not depend on where it is: drawn
                    // first (the sampler's order is unchanged), its table reads overlap the
                    // reads of the hit's shading data, asked of the cache before it.
                    foundation::infra::prefetch::prefetch(
                        self.triangles.as_ptr().wrapping_add(hit.triangle as usize),
                    );
                    light_sample = self.light.sample_texel(sampler.next_2d());
                    path.point = self.surface(&hit);
                    path.wo = -w;
                }
            }
        }
        out
    }

    /// The path's last segment, along `w`: what it reaches counts, the environment (its
    /// radiance `escaped()`) or an emitter. Without emitters only whether it escapes matters:
    /// an occlusion ray suffices.
    fn last_segment(
        &self,
        path: &PathVertex,
        w: Vec3,
        escaped: impl FnOnce() -> Rgb,
        out: &mut PathEstimate,
    ) {
        if self.triangle_emissions.is_empty() {
            if !self.occluded(&path.point, w) {
                path.add(escaped(), out);
            }
        } else if let Some(hit) = self.trace(&path.point, w) {
            out.radiance += path.before * self.emitted(&hit);
        } else {
            path.add(escaped(), out);
        }
    }

    /// Next-event estimation toward the environment from the path's current point, with the
    /// light sample `(w, texel)`: adds its MIS-weighted contribution (and, at the first point,
    /// the direct visibility) to `out`.
    #[inline]
    fn next_event(
        &self,
        path: &PathVertex,
        bsdf: Option<&SurfaceBsdf>,
        (w, texel): (Vec3, PendingTexel),
        depth: u32,
        rays: &mut u64,
        out: &mut PathEstimate,
    ) {
        let point = &path.point;
        let cos = point.shading_normal.dot(w);
        if cos <= 0.0 {
            return;
        }
        *rays += 1;
        let visible = !self.occluded(point, w);
        // Read after the ray, which gave the texel time to arrive.
        let (le, pdf_light) = self.light.texel_value(texel);
        if depth == 0 && pdf_light > 0.0 {
            let weight = luminance(le) * cos / pdf_light;
            out.direct.unoccluded += weight;
            if visible {
                out.direct.visible += weight;
            }
        }
        if !visible || pdf_light <= 0.0 {
            return;
        }
        match bsdf {
            None => {
                // A Lambertian point's weight (cos/pdf cancels): the arithmetic of a diffuse
                // path is the same as before glossy surfaces existed.
                let throughput = path.before * point.albedo;
                let pdf_surface = cosine_hemisphere_pdf(cos);
                let mis = power_heuristic(pdf_light, pdf_surface);
                let factor = cosine_hemisphere_pdf(cos) / pdf_light * mis;
                out.radiance += throughput * le * factor;
                // Only paths through a glossy first point carry a specular part.
                if !self.triangle_materials.is_empty() {
                    out.specular += path.specular_before * point.albedo * le * factor;
                }
            }
            Some(bsdf) => {
                let f = bsdf.eval(w);
                let scale = le * (power_heuristic(pdf_light, f.pdf) / pdf_light);
                out.radiance += path.before * (f.diffuse + f.specular) * scale;
                out.specular += if depth == 0 {
                    path.before * f.specular * scale
                } else {
                    path.specular_before * (f.diffuse + f.specular) * scale
                };
            }
        }
    }
}

/// Where a path is: its current point, the direction back toward the previous one, and its
/// weight up to the point, not counting the point's BSDF, with the part of that weight that
/// left the first point through its specular lobe.
struct PathVertex {
    point: SurfacePoint,
    wo: Vec3,
    before: Rgb,
    specular_before: Rgb,
}

/// A continuation direction and the pdf it was drawn with.
#[derive(Clone, Copy)]
struct Scatter {
    direction: Vec3,
    pdf: f32,
}

impl PathVertex {
    /// Draws the continuation from the point's BSDF (`bsdf`, or Lambertian) and moves the
    /// path's weights past the point; `None` where the sampled direction reflects nothing.
    #[inline]
    /// Adds the environment's radiance `le`, seen along the path's continuation, to `out`.
    fn add(&self, le: Rgb, out: &mut PathEstimate) {
        out.radiance += self.before * le;
        out.specular += self.specular_before * le;
    }

    fn scatter(
        &mut self,
        bsdf: Option<&SurfaceBsdf>,
        u: glam::Vec2,
        depth: u32,
    ) -> Option<Scatter> {
        let albedo = self.point.albedo;
        let (scatter, weight, specular_weight) = match bsdf {
            None => {
                let n = self.point.shading_normal;
                let w = Frame::from_normal(n).to_world(cosine_hemisphere(u));
                let pdf = cosine_hemisphere_pdf(n.dot(w));
                (Scatter { direction: w, pdf }, albedo, albedo)
            }
            Some(bsdf) => {
                let w = bsdf.sample(u);
                let f = bsdf.eval(w);
                if f.pdf <= 0.0 {
                    // Below the surface: the lobe's part past the horizon reflects nothing.
                    return None;
                }
                let weight = (f.diffuse + f.specular) / f.pdf;
                let specular = if depth == 0 {
                    f.specular / f.pdf
                } else {
                    weight
                };
                (
                    Scatter {
                        direction: w,
                        pdf: f.pdf,
                    },
                    weight,
                    specular,
                )
            }
        };
        self.specular_before = match (depth, bsdf) {
            (0, Some(_)) => self.before * specular_weight,
            (0, None) => Rgb::ZERO,
            _ => self.specular_before * specular_weight,
        };
        self.before *= weight;
        Some(scatter)
    }
}
