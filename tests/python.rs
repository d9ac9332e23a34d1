//! The Python module (`python/`) on every test run: its tests (`python/tests/`, pytest, against
//! this checkout's command line and path tracer; they run the examples and the README's Python
//! examples too) and `mypy --strict` over the tests, the examples and the package's stubs.
//!
//! `tests/run.sh` builds and installs the module with `pip install ./python` into a private
//! virtual environment (`target/python-venv`) and points `HPRT_PYTHON` at its interpreter.
//! Without it the test fails and says why; it never skips.

use std::path::Path;
use std::process::Command;

/// What the tests import besides the module.
const PACKAGES: &str = "numpy mypy pytest matplotlib tqdm";

/// The interpreter with the module and [`PACKAGES`] installed, or a panic that says how to get
/// them.
fn python() -> String {
    let python = std::env::var("HPRT_PYTHON").unwrap_or_else(|_| "python3".into());
    let imports = format!("import hprt, {}", PACKAGES.replace(' ', ", "));
    let check = Command::new(&python).args(["-c", &imports]).output();
    match check {
        Ok(out) if out.status.success() => python,
        other => {
            let reason = match other {
                Ok(out) => String::from_utf8_lossy(&out.stderr).into_owned(),
                Err(e) => e.to_string(),
            };
            let log = std::env::var("HPRT_PYTHON_INSTALL_LOG")
                .ok()
                .and_then(|p| std::fs::read_to_string(p).ok())
                .unwrap_or_default();
            panic!(
                "{python} cannot import hprt and {PACKAGES} ({reason}); tests/run.sh installs \
                 them into target/python-venv (`pip install {PACKAGES}` and `pip install \
                 ./python`). Install log:\n{log}"
            );
        }
    }
}

fn run(python: &str, args: &[&str]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(python)
        .args(args)
        .current_dir(root)
        .env("HPRT_BIN", env!("CARGO_BIN_EXE_hprt"))
        .output()
        .expect("the interpreter runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(out.status.success(), "{python} {args:?} failed:\n{text}");
}

#[test]
fn the_python_module_passes_its_tests_and_strict_typing() {
    let python = python();
    run(
        &python,
        &[
            "-m",
            "pytest",
            "python/tests",
            "-v",
            "-p",
            "no:cacheprovider",
        ],
    );
    run(
        &python,
        &[
            "-m",
            "mypy",
            "--strict",
            "python/tests",
            "python/examples",
            "python/hprt",
        ],
    );
}
