//! Validation and preparation of a freshly read mesh.

use super::error::MeshError;
use super::triangle_mesh::{RawMesh, TriangleMesh};
use glam::{IVec3, Vec3, Vec4};
use std::collections::HashMap;
use std::path::Path;

/// What the clean-up changed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CleanupReport {
    /// Triangles dropped because their area is zero (or they repeat a vertex).
    pub zero_area_skipped: usize,
    /// Vertices merged into a coincident one.
    pub welded_vertices: usize,
}

/// How a mesh is prepared.
#[derive(Debug, Clone, Copy)]
pub struct MeshCleanup {
    /// Weld coincident vertices; `None` welds exactly when the file carries no normals
    /// (smooth per-vertex transfer needs shared vertices along patch and face seams).
    pub weld: Option<bool>,
    /// Welding distance relative to the bounding-box diagonal.
    pub weld_tolerance: f32,
}

impl Default for MeshCleanup {
    fn default() -> Self {
        Self {
            weld: None,
            weld_tolerance: 1e-6,
        }
    }
}

impl MeshCleanup {
    pub fn run(
        &self,
        path: &Path,
        raw: RawMesh,
    ) -> Result<(TriangleMesh, CleanupReport), MeshError> {
        let invalid = |message: String| MeshError::Invalid {
            path: path.to_owned(),
            message,
        };
        validate(&raw).map_err(invalid)?;
        if raw.triangles.is_empty() {
            return Err(MeshError::Empty {
                path: path.to_owned(),
                detail: String::new(),
            });
        }
        let diagonal = bounds_diagonal(&raw.positions);
        let mut report = CleanupReport::default();
        let input_triangles = raw.triangles.len();
        // Texture seams are split vertices on purpose: a textured mesh is not welded unless
        // asked (and then each welded vertex keeps the first one's coordinates).
        let weld = self
            .weld
            .unwrap_or(raw.normals.is_none() && raw.uvs.is_none());
        let raw = match weld {
            true => welded(raw, self.weld_tolerance * diagonal, &mut report),
            false => raw,
        };
        let RawMesh {
            positions,
            normals,
            mut triangles,
            uvs,
            tangents,
        } = raw;

        let min_double_area = (1e-7 * diagonal).powi(2);
        triangles.retain(|&[a, b, c]| {
            let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
            a != b && b != c && a != c && (pb - pa).cross(pc - pa).length() > min_double_area
        });
        report.zero_area_skipped = input_triangles - triangles.len();
        if triangles.is_empty() {
            return Err(MeshError::Empty {
                path: path.to_owned(),
                detail: format!(" (all {input_triangles} triangles have zero area)"),
            });
        }
        if report.zero_area_skipped > 0 {
            log::warn!(
                "{}: skipped {} zero-area triangle(s)",
                path.display(),
                report.zero_area_skipped
            );
        }

        let computed = smooth_normals(&positions, &triangles);
        let normals = match normals {
            // Keep the file's normals where they are usable.
            Some(given) => given
                .iter()
                .zip(&computed)
                .map(|(n, fallback)| n.try_normalize().unwrap_or(*fallback))
                .collect(),
            None => computed,
        };
        let mesh = remove_unreferenced(TriangleMesh {
            positions,
            normals,
            triangles,
            uvs: uvs.unwrap_or_default(),
            tangents: tangents.map(unit_tangents).unwrap_or_default(),
        });
        Ok((mesh, report))
    }
}

use crate::infra::limits::MAX_COORDINATE;

/// Finite coordinates, finite normals of the right count, indices in range.
fn validate(raw: &RawMesh) -> Result<(), String> {
    if let Some(i) = raw.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "vertex {i} has a non-finite coordinate {:?}",
            raw.positions[i].to_array()
        ));
    }
    if let Some(i) = raw
        .positions
        .iter()
        .position(|p| p.abs().max_element() > MAX_COORDINATE)
    {
        return Err(format!(
            "vertex {i} has a coordinate beyond ±{MAX_COORDINATE:e} ({:?}): areas and normals \
             would overflow in single precision",
            raw.positions[i].to_array()
        ));
    }
    if let Some(normals) = &raw.normals {
        if normals.len() != raw.positions.len() {
            return Err(format!(
                "{} normals for {} vertices",
                normals.len(),
                raw.positions.len()
            ));
        }
        if let Some(i) = normals.iter().position(|n| !n.is_finite()) {
            return Err(format!("vertex {i} has a non-finite normal"));
        }
    }
    if let Some(uvs) = &raw.uvs {
        if uvs.len() != raw.positions.len() {
            return Err(format!(
                "{} texture coordinates for {} vertices",
                uvs.len(),
                raw.positions.len()
            ));
        }
        if let Some(i) = uvs.iter().position(|t| !t.is_finite()) {
            return Err(format!("vertex {i} has non-finite texture coordinates"));
        }
    }
    if let Some(tangents) = &raw.tangents
        && tangents.len() != raw.positions.len()
    {
        return Err(format!(
            "{} tangents for {} vertices",
            tangents.len(),
            raw.positions.len()
        ));
    }
    let n = raw.positions.len() as u32;
    if let Some((t, i)) = raw
        .triangles
        .iter()
        .enumerate()
        .find_map(|(t, tri)| tri.iter().find(|&&i| i >= n).map(|&i| (t, i)))
    {
        return Err(format!(
            "triangle {t} refers to vertex {i}, but there are only {n} vertices"
        ));
    }
    Ok(())
}

fn bounds_diagonal(positions: &[Vec3]) -> f32 {
    let (lo, hi) = positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).length().max(f32::MIN_POSITIVE)
}

/// Merges vertices closer than `tolerance`. Returns the old-to-new index map and, for each
/// new vertex, the old vertex it keeps. A vertex joins the first kept vertex within reach,
/// searching the 27 grid cells around it in a fixed order and each cell in the order its
/// vertices were kept.
fn weld_positions(positions: &[Vec3], tolerance: f32) -> (Vec<u32>, Vec<u32>) {
    /// A grid cell's kept vertices, as a chain through `next`: its first and last.
    struct Cell {
        first: u32,
        last: u32,
    }
    const END: u32 = u32::MAX;
    let cell_of = |p: Vec3| (p / tolerance).floor().as_ivec3();
    // A fast fixed hash: the cells are the mesh's own, nothing adversarial to spread.
    let mut grid: HashMap<IVec3, Cell, foldhash::fast::FixedState> =
        HashMap::with_capacity_and_hasher(positions.len(), Default::default());
    let mut next: Vec<u32> = Vec::new();
    let mut remap = Vec::with_capacity(positions.len());
    let mut kept: Vec<u32> = Vec::new();
    for p in positions {
        let cell = cell_of(*p);
        let mut found = None;
        'search: for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(near) = grid.get(&(cell + IVec3::new(dx, dy, dz))) else {
                        continue;
                    };
                    let mut c = near.first;
                    while c != END {
                        if positions[kept[c as usize] as usize].distance(*p) <= tolerance {
                            found = Some(c);
                            break 'search;
                        }
                        c = next[c as usize];
                    }
                }
            }
        }
        let index = found.unwrap_or_else(|| {
            let new = kept.len() as u32;
            kept.push(remap.len() as u32);
            next.push(END);
            match grid.get_mut(&cell) {
                Some(chain) => {
                    next[chain.last as usize] = new;
                    chain.last = new;
                }
                None => {
                    grid.insert(
                        cell,
                        Cell {
                            first: new,
                            last: new,
                        },
                    );
                }
            }
            new
        });
        remap.push(index);
    }
    (remap, kept)
}

/// Angle-weighted vertex normals (Thürmer & Wüthrich), robust to uneven tessellation.
pub(super) fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for tri in triangles {
        let p = tri.map(|i| positions[i as usize]);
        let Some(face_normal) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() else {
            continue;
        };
        for corner in 0..3 {
            let e1 = p[(corner + 1) % 3] - p[corner];
            let e2 = p[(corner + 2) % 3] - p[corner];
            let angle = e1.angle_between(e2);
            if angle.is_finite() {
                sums[tri[corner] as usize] += face_normal * angle;
            }
        }
    }
    // A vertex whose faces cancel out (a fold) falls back to its first face's normal.
    let mut normals: Vec<Option<Vec3>> = sums.iter().map(|s| s.try_normalize()).collect();
    for tri in triangles {
        let p = tri.map(|i| positions[i as usize]);
        if let Some(face_normal) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() {
            for &i in tri {
                normals[i as usize].get_or_insert(face_normal);
            }
        }
    }
    normals.into_iter().map(|n| n.unwrap_or(Vec3::Y)).collect()
}

/// `raw` with the vertices within `tolerance` of each other merged (each keeps the first
/// one's attributes), counted in `report`.
fn welded(raw: RawMesh, tolerance: f32, report: &mut CleanupReport) -> RawMesh {
    let (remap, kept) = weld_positions(&raw.positions, tolerance);
    report.welded_vertices = raw.positions.len() - kept.len();
    RawMesh {
        positions: kept.iter().map(|&i| raw.positions[i as usize]).collect(),
        normals: raw
            .normals
            .as_deref()
            .map(|n| kept.iter().map(|&i| n[i as usize]).collect()),
        uvs: raw
            .uvs
            .as_deref()
            .map(|t| kept.iter().map(|&i| t[i as usize]).collect()),
        tangents: raw
            .tangents
            .as_deref()
            .map(|t| kept.iter().map(|&i| t[i as usize]).collect()),
        triangles: raw
            .triangles
            .iter()
            .map(|t| t.map(|i| remap[i as usize]))
            .collect(),
    }
}

/// Tangents as the renderers read them: unit xyz and a w of exactly ±1. A tangent of zero
/// length or with a non-finite component becomes zero, which draws its vertex without the
/// normal map (documented in CONVENTIONS.md, "Normal maps"), rather than a NaN.
fn unit_tangents(tangents: Vec<Vec4>) -> Vec<Vec4> {
    tangents
        .into_iter()
        .map(|t| match (t.truncate().try_normalize(), t.w.is_finite()) {
            (Some(xyz), true) => xyz.extend(if t.w < 0.0 { -1.0 } else { 1.0 }),
            _ => Vec4::ZERO,
        })
        .collect()
}

/// Drops vertices no triangle uses (left over from degenerate or welded triangles).
fn remove_unreferenced(mesh: TriangleMesh) -> TriangleMesh {
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    let mut out = TriangleMesh::default();
    for tri in &mesh.triangles {
        let mapped = tri.map(|i| {
            let slot = &mut new_index[i as usize];
            if *slot == u32::MAX {
                *slot = out.positions.len() as u32;
                out.positions.push(mesh.positions[i as usize]);
                out.normals.push(mesh.normals[i as usize]);
                if let Some(uv) = mesh.uvs.get(i as usize) {
                    out.uvs.push(*uv);
                }
                if let Some(t) = mesh.tangents.get(i as usize) {
                    out.tangents.push(*t);
                }
            }
            *slot
        });
        out.triangles.push(mapped);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn quad_with_seam() -> RawMesh {
        // Two triangles of a unit square whose shared edge is duplicated (a seam), plus a
        // degenerate triangle.
        RawMesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0 + 1e-8, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(2.0, 2.0, 0.0),
            ],
            normals: None,
            triangles: vec![[0, 1, 2], [3, 4, 5], [0, 1, 0], [0, 2, 6]],
            uvs: None,
            tangents: None,
        }
    }

    #[test]
    fn welds_seams_and_drops_degenerate_triangles() {
        let (mesh, report) = MeshCleanup::default()
            .run(&PathBuf::from("seam.obj"), quad_with_seam())
            .unwrap();
        assert_eq!(report.welded_vertices, 2);
        // [0,1,0] repeats a vertex; [0,2,6] is collinear.
        assert_eq!(report.zero_area_skipped, 2);
        assert_eq!(mesh.triangle_count(), 2);
        assert_eq!(mesh.vertex_count(), 4);
        for n in &mesh.normals {
            assert!((*n - Vec3::Z).length() < 1e-6);
        }
    }

    #[test]
    fn rejects_non_finite_coordinates_naming_the_vertex() {
        let mut raw = quad_with_seam();
        raw.positions[4].y = f32::NAN;
        let err = MeshCleanup::default()
            .run(&PathBuf::from("bad.ply"), raw)
            .unwrap_err()
            .to_string();
        assert!(err.contains("bad.ply") && err.contains("vertex 4"), "{err}");
    }

    #[test]
    fn rejects_out_of_range_indices_and_empty_meshes() {
        let mut raw = quad_with_seam();
        raw.triangles.push([0, 1, 99]);
        let err = MeshCleanup::default()
            .run(&PathBuf::from("x.obj"), raw)
            .unwrap_err()
            .to_string();
        assert!(err.contains("triangle 4") && err.contains("99"), "{err}");

        let raw = RawMesh {
            positions: vec![Vec3::ZERO; 3],
            normals: None,
            triangles: vec![[0, 1, 2]],
            uvs: None,
            tangents: None,
        };
        let err = MeshCleanup::default()
            .run(&PathBuf::from("flat.obj"), raw)
            .unwrap_err();
        assert!(matches!(err, MeshError::Empty { .. }), "{err}");
    }

    /// The chained grid against a plain one (a list per cell): the same vertices kept, the
    /// same vertex joined, on a cloud with several vertices per cell and per reach.
    #[test]
    fn welding_keeps_the_first_vertex_within_reach_in_search_order() {
        let tolerance = 0.01;
        let mut state = 7u64;
        let mut next = || {
            state = crate::sampling::mix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let positions: Vec<Vec3> = (0..4000)
            .map(|_| Vec3::new(next(), next(), next()) * 0.2)
            .collect();
        let cell_of = |p: Vec3| (p / tolerance).floor().as_ivec3();
        let mut grid: HashMap<IVec3, Vec<u32>> = HashMap::new();
        let (mut remap, mut kept) = (Vec::new(), Vec::<u32>::new());
        for (i, p) in positions.iter().enumerate() {
            let cell = cell_of(*p);
            let mut found = None;
            for (dz, dy, dx) in
                (-1..=1).flat_map(|z| (-1..=1).flat_map(move |y| (-1..=1).map(move |x| (z, y, x))))
            {
                let list = grid.get(&(cell + IVec3::new(dx, dy, dz)));
                let near =
                    |&&c: &&u32| positions[kept[c as usize] as usize].distance(*p) <= tolerance;
                found = found.or_else(|| list.and_then(|l| l.iter().find(near)).copied());
            }
            remap.push(found.unwrap_or_else(|| {
                kept.push(i as u32);
                grid.entry(cell).or_default().push(kept.len() as u32 - 1);
                kept.len() as u32 - 1
            }));
        }
        let (welded_remap, welded_kept) = weld_positions(&positions, tolerance);
        assert!(kept.len() < 3000 && kept.len() > 500, "{} kept", kept.len());
        assert_eq!(welded_kept, kept);
        assert_eq!(welded_remap, remap);
    }

    #[test]
    fn smooth_normals_of_a_cube_corner_point_along_the_diagonal() {
        // Three faces of a cube meeting at the origin, facing outwards (-x, -y, -z).
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let triangles = vec![[0, 2, 1], [0, 3, 2], [0, 1, 3]];
        let n = smooth_normals(&positions, &triangles);
        assert!(
            (n[0] - Vec3::splat(-1.0).normalize()).length() < 1e-6,
            "{:?}",
            n[0]
        );
    }
}
