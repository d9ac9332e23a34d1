//! Bicubic Bézier patches in the `.bpt` text format (Newell's teapot): first line the number of
//! patches; each patch a line `3 3` followed by 16 control points `x y z`, row-major.

use super::error::MeshError;
use super::triangle_mesh::RawMesh;
use glam::Vec3;
use std::path::Path;

/// One bicubic Bézier patch; `control[4 * row + column]`.
#[derive(Debug, Clone, PartialEq)]
pub struct BezierPatch {
    pub control: [Vec3; 16],
}

impl BezierPatch {
    /// The surface point at parameters `(s, t)`: `s` runs along rows, `t` along columns.
    pub fn point(&self, s: f32, t: f32) -> Vec3 {
        let bs = bernstein3(s);
        let bt = bernstein3(t);
        let mut p = Vec3::ZERO;
        for (r, br) in bs.iter().enumerate() {
            for (c, bc) in bt.iter().enumerate() {
                p += self.control[4 * r + c] * (br * bc);
            }
        }
        p
    }
}

fn bernstein3(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

/// Parses a `.bpt` file, reporting the line of any error.
pub(crate) fn read_bpt(path: &Path, bytes: &[u8]) -> Result<Vec<BezierPatch>, MeshError> {
    let syntax = |line: usize, message: String| MeshError::Syntax {
        path: path.to_owned(),
        line,
        message,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| MeshError::Invalid {
        path: path.to_owned(),
        message: format!("not a text file: {e}"),
    })?;
    // Non-empty lines with their 1-based numbers.
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let last_line = text.lines().count();
    let mut next_line = |what: &str| {
        lines
            .next()
            .ok_or_else(|| syntax(last_line, format!("file ends early: expected {what}")))
    };

    let (line, count_text) = next_line("the number of patches")?;
    let count: usize = count_text.parse().map_err(|_| {
        syntax(
            line,
            format!("expected the number of patches, got {count_text:?}"),
        )
    })?;
    let mut patches = Vec::with_capacity(count.min(1 << 16));
    for patch in 0..count {
        let (line, degrees) = next_line(&format!("the degrees of patch {patch}"))?;
        let degrees: Vec<&str> = degrees.split_whitespace().collect();
        if degrees != ["3", "3"] {
            return Err(syntax(
                line,
                format!(
                    "patch {patch}: only bicubic patches (\"3 3\") are supported, got {degrees:?}"
                ),
            ));
        }
        let mut control = [Vec3::ZERO; 16];
        for (k, point) in control.iter_mut().enumerate() {
            let (line, text) = next_line(&format!("control point {k} of patch {patch}"))?;
            let coords: Vec<f32> = text
                .split_whitespace()
                .map(|c| c.parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|_| syntax(line, format!("expected \"x y z\", got {text:?}")))?;
            match coords[..] {
                [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
                    *point = Vec3::new(x, y, z)
                }
                [_, _, _] => {
                    return Err(syntax(line, format!("non-finite coordinate in {text:?}")));
                }
                _ => {
                    return Err(syntax(
                        line,
                        format!("expected 3 coordinates, got {text:?}"),
                    ));
                }
            }
        }
        patches.push(BezierPatch { control });
    }
    if let Some((line, extra)) = lines.next() {
        return Err(syntax(
            line,
            format!("unexpected data after {count} patches: {extra:?}"),
        ));
    }
    Ok(patches)
}

/// Tessellates each patch into `segments × segments` quads (two triangles each). Triangles
/// that collapse (the degenerate rows at the teapot's lid knob and bottom centre) are left out,
/// so no zero-area triangle or NaN normal is ever produced. Seams are welded later.
/// Winding: the face normal is `∂P/∂t × ∂P/∂s` (s along rows, t along columns), which makes
/// every patch of Newell's teapot face outwards.
pub(crate) fn tessellate_patches(patches: &[BezierPatch], segments: u32) -> RawMesh {
    let n = segments.max(1) as usize;
    let mut mesh = RawMesh::default();
    for patch in patches {
        let base = mesh.positions.len() as u32;
        let size = patch
            .control
            .iter()
            .fold(Vec3::splat(f32::MIN), |m, p| m.max(*p))
            - patch
                .control
                .iter()
                .fold(Vec3::splat(f32::MAX), |m, p| m.min(*p));
        let collapse = 1e-5 * size.length();
        for i in 0..=n {
            for j in 0..=n {
                mesh.positions
                    .push(patch.point(i as f32 / n as f32, j as f32 / n as f32));
            }
        }
        let at = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
        for i in 0..n {
            for j in 0..n {
                // Wound so the face normal is ∂P/∂t × ∂P/∂s: outward for Newell's data.
                for tri in [
                    [at(i, j), at(i + 1, j + 1), at(i + 1, j)],
                    [at(i, j), at(i, j + 1), at(i + 1, j + 1)],
                ] {
                    let p = tri.map(|v| mesh.positions[v as usize]);
                    let collapsed = p[0].distance(p[1]) < collapse
                        || p[1].distance(p[2]) < collapse
                        || p[2].distance(p[0]) < collapse;
                    if !collapsed {
                        mesh.triangles.push(tri);
                    }
                }
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat_patch_text() -> String {
        let mut s = String::from("1\n3 3\n");
        for r in 0..4 {
            for c in 0..4 {
                s += &format!("{} {} 0\n", c, r);
            }
        }
        s
    }

    #[test]
    fn flat_patch_interpolates_its_corners() {
        let patches = read_bpt(Path::new("p.bpt"), flat_patch_text().as_bytes()).unwrap();
        assert_eq!(patches.len(), 1);
        let p = &patches[0];
        assert!((p.point(0.0, 0.0) - Vec3::ZERO).length() < 1e-6);
        assert!((p.point(1.0, 1.0) - Vec3::new(3.0, 3.0, 0.0)).length() < 1e-6);
        // Uniform control grid: the patch is the identity map scaled by 3.
        assert!((p.point(0.5, 0.25) - Vec3::new(0.75, 1.5, 0.0)).length() < 1e-5);
        let mesh = tessellate_patches(&patches, 4);
        assert_eq!(mesh.positions.len(), 25);
        assert_eq!(mesh.triangles.len(), 32);
    }

    #[test]
    fn collapsed_rows_produce_no_degenerate_triangles() {
        let mut patch = read_bpt(Path::new("p.bpt"), flat_patch_text().as_bytes()).unwrap();
        for c in 0..4 {
            patch[0].control[c] = Vec3::new(1.5, 0.0, 1.0);
        }
        let mesh = tessellate_patches(&patch, 8);
        assert_eq!(mesh.triangles.len(), 2 * 64 - 8);
        for t in &mesh.triangles {
            let p = t.map(|i| mesh.positions[i as usize]);
            assert!((p[1] - p[0]).cross(p[2] - p[0]).length() > 1e-8);
        }
    }

    #[test]
    fn errors_name_the_line() {
        let mut text = flat_patch_text();
        text = text.replacen("2 1 0", "2 x 0", 1);
        let err = read_bpt(Path::new("bad.bpt"), text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(err.contains("bad.bpt: line 9"), "{err}");

        let err = read_bpt(Path::new("short.bpt"), b"2\n3 3\n0 0 0\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("file ends early"), "{err}");

        let err = read_bpt(Path::new("deg.bpt"), b"1\n2 2\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 2") && err.contains("bicubic"), "{err}");
    }
}
