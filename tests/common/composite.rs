//! The composite tests' scene: a box on a proxy floor in a temporary folder with a map.

use super::repo;
use std::path::{Path, PathBuf};

/// A scene file: a box (`role` of the floor as given) on a floor slab, lit by `map.exr`,
/// with `backplate` appended verbatim.
pub fn floor_scene(dir: &Path, name: &str, floor_role: &str, backplate: &str) {
    std::fs::write(
        dir.join(name),
        format!(
            "[camera]\nposition = [0, 3, 5]\ntarget = [0, 0.3, 0]\nfov_y_deg = 50\nwidth = 40\nheight = 30\n\
             [environment]\nmap = \"map.exr\"\n{backplate}\n\
             [[object]]\nname = \"box\"\nbox = {{ min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] }}\nalbedo = [0.6, 0.4, 0.3]\n\
             [[object]]\nname = \"floor\"\nrole = \"{floor_role}\"\n\
             box = {{ min = [-4, -0.2, -4], max = [4, 0, 4], segments = [8, 1, 8] }}\nalbedo = [0.4, 0.4, 0.4]\n"
        ),
    )
    .unwrap();
}

/// A temporary folder holding the scenes' map, `map.exr`: the folder (kept while it lives) and
/// its path.
pub fn workspace() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_owned();
    std::fs::copy(repo().join("tests/data/hall_dwab.exr"), d.join("map.exr")).unwrap();
    (dir, d)
}

/// The `[backplate]` of a composite into the environment map itself.
pub const ENVIRONMENT: &str = "[backplate]\nimage = \"environment\"";
