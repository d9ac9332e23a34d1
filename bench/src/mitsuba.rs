//! Mitsuba 3 run from its Python package, for the reference benchmark: the same scene exported
//! as `hprt export` exports it, rendered and timed by Mitsuba, so both renderers are measured
//! in one run.

use crate::error::{BenchError, Result};
use foundation::image_io::{RgbImageF32, read_exr};
use foundation::scene::SceneMesh;
use reference::export::{ExportSettings, export_mitsuba};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A Python interpreter with Mitsuba 3 and the variant to run.
pub(crate) struct Mitsuba {
    python: String,
    pub(crate) variant: &'static str,
    /// `DRJIT_LIBLLVM_PATH` for the LLVM variant.
    llvm: Option<PathBuf>,
    pub(crate) version: String,
}

/// Where Debian puts the LLVM libraries Dr.Jit can use (LLVM 15 aborts: README).
const LLVM_CANDIDATES: [&str; 4] = [
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/x86_64-linux-gnu/libLLVM-18.so",
    "/usr/lib/x86_64-linux-gnu/libLLVM-17.so",
    "/usr/lib/x86_64-linux-gnu/libLLVM-16.so",
];

impl Mitsuba {
    /// `HPRT_MITSUBA_PYTHON`, else `target/mitsuba-venv` (what `tests/run.sh` installs), else
    /// `python3`, if it imports Mitsuba; the LLVM variant where an LLVM library is found
    /// (`DRJIT_LIBLLVM_PATH`, else the usual Debian paths), else `scalar_rgb`.
    pub(crate) fn find() -> Option<Self> {
        let mut candidates: Vec<String> = Vec::new();
        if let Ok(p) = std::env::var("HPRT_MITSUBA_PYTHON") {
            candidates.push(p);
        }
        // Absolute, not canonical: the venv's interpreter is a link whose target has no
        // Mitsuba.
        let venv = Path::new("target/mitsuba-venv/bin/python");
        if let (true, Ok(venv)) = (venv.exists(), std::path::absolute(venv)) {
            candidates.push(venv.to_string_lossy().into_owned());
        }
        candidates.push("python3".into());
        let (python, version) = candidates.into_iter().find_map(|python| {
            let out = Command::new(&python)
                .args(["-c", "import mitsuba; print(mitsuba.__version__)"])
                .output()
                .ok()?;
            out.status.success().then(|| {
                (
                    python,
                    String::from_utf8_lossy(&out.stdout).trim().to_owned(),
                )
            })
        })?;
        let llvm = std::env::var_os("DRJIT_LIBLLVM_PATH")
            .map(PathBuf::from)
            .or_else(|| {
                LLVM_CANDIDATES
                    .iter()
                    .map(PathBuf::from)
                    .find(|p| p.exists())
            });
        Some(Self {
            python,
            variant: if llvm.is_some() {
                "llvm_ad_rgb"
            } else {
                "scalar_rgb"
            },
            llvm,
            version,
        })
    }

    /// Exports `geometry` into `dir`, renders it `repeat` times and returns each render's
    /// seconds (the first includes the LLVM variant's kernel compilation) and the last image.
    pub(crate) fn render(
        &self,
        dir: &Path,
        geometry: &SceneMesh,
        map: &foundation::envmap::EnvMap,
        settings: &ExportSettings,
        repeat: usize,
    ) -> Result<(Vec<f64>, RgbImageF32)> {
        export_mitsuba(dir, geometry, map, settings)?;
        let script = format!(
            r#"
import time
import drjit as dr
import mitsuba as mi
mi.set_variant("{variant}")
import thinsheet
import phong
# Timed with Mitsuba's own two-sided BSDF, its fastest; the image to compare shows the
# front on both sides, as hprt does (CONVENTIONS.md, "Surfaces").
scene = mi.load_file("scene.xml")
for k in range({repeat}):
    start = time.perf_counter()
    image = mi.render(scene, seed=k)
    dr.eval(image)
    dr.sync_thread()
    print("seconds", time.perf_counter() - start, flush=True)
image = mi.render(mi.load_file("scene.xml", surface="thinsheet"), seed=0)
mi.util.write_bitmap("mitsuba.exr", image)
"#,
            variant = self.variant,
            repeat = repeat.max(1)
        );
        let mut command = Command::new(&self.python);
        command.args(["-c", &script]).current_dir(dir);
        if let Some(llvm) = &self.llvm {
            command.env("DRJIT_LIBLLVM_PATH", llvm);
        }
        let out = command
            .output()
            .map_err(|source| BenchError::MitsubaStart {
                python: self.python.clone(),
                source,
            })?;
        if !out.status.success() {
            return Err(BenchError::Mitsuba {
                variant: self.variant,
                stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
            });
        }
        let seconds = String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| l.strip_prefix("seconds ")?.trim().parse().ok())
            .collect();
        Ok((seconds, read_exr(&dir.join("mitsuba.exr"))?))
    }
}

/// Relative difference of the mean luminance of `ours` and `theirs` over `covered` pixels.
pub(crate) fn covered_mean_difference(
    ours: &RgbImageF32,
    theirs: &RgbImageF32,
    covered: &[f32],
) -> f64 {
    let mean = |image: &RgbImageF32| {
        let (sum, n) = image
            .pixels
            .iter()
            .zip(covered)
            .filter(|(_, c)| **c > 0.5)
            .fold((0.0f64, 0usize), |(s, n), (p, _)| {
                (s + f64::from(foundation::luminance(*p)), n + 1)
            });
        sum / n.max(1) as f64
    };
    mean(ours) / mean(theirs) - 1.0
}
