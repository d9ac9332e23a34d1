//! The layout rules of the source tree (README, "Layout"), checked on every test run: no import
//! cycle between files, no function over 80 lines outside tests, no source file over 500 lines,
//! no printing from a library (progress and warnings go through what the caller gives).
//!
//! The checks read the sources as text with a small tokenizer (strings, characters and comments
//! skipped), which is all these rules need.

#[path = "layout/imports.rs"]
mod imports;
#[path = "layout/scan.rs"]
mod scan;
#[path = "layout/tokens.rs"]
mod tokens;

use scan::{CRATES, SourceTree, function_spans, prints_outside_tests};
use std::path::{Path, PathBuf};
use tokens::tokens;

const MAX_FUNCTION_LINES: usize = 80;
const MAX_FILE_LINES: usize = 500;

fn tree() -> SourceTree {
    SourceTree::read(Path::new(env!("CARGO_MANIFEST_DIR")))
}

#[test]
fn no_source_file_is_over_500_lines() {
    let tree = tree();
    let long: Vec<String> = tree
        .all_files()
        .filter(|f| f.lines > MAX_FILE_LINES)
        .map(|f| format!("{} ({} lines)", f.path.display(), f.lines))
        .collect();
    assert!(
        long.is_empty(),
        "files over {MAX_FILE_LINES} lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn no_function_outside_tests_is_over_80_lines() {
    let tree = tree();
    let mut long = Vec::new();
    for file in tree.all_files().filter(|f| !f.is_test_file) {
        for span in function_spans(&tokens(&file.text)) {
            if !span.in_test && span.lines > MAX_FUNCTION_LINES {
                long.push(format!(
                    "{}:{} fn {} ({} lines)",
                    file.path.display(),
                    span.line,
                    span.name,
                    span.lines
                ));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn no_import_cycle_between_files() {
    let tree = tree();
    let cycles = tree.import_cycles();
    let shown: Vec<String> = cycles
        .iter()
        .map(|cycle| {
            cycle
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(" -> ")
        })
        .collect();
    assert!(
        cycles.is_empty(),
        "import cycles between files:\n{}",
        shown.join("\n")
    );
}

/// The checks themselves: each finds what it must on a small made-up crate.
/// Libraries report through a `Progress` or the `log` facade the program (or the Python
/// module) routes; only the program, `src/`, prints.
#[test]
fn libraries_never_print() {
    let tree = tree();
    let program = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = Vec::new();
    for file in tree
        .all_files()
        .filter(|f| !f.is_test_file && !f.path.starts_with(&program))
    {
        for line in prints_outside_tests(&tokens(&file.text)) {
            found.push(format!("{}:{line}", file.path.display()));
        }
    }
    assert!(found.is_empty(), "a library prints:\n{}", found.join("\n"));
}

#[test]
fn the_checks_find_what_they_look_for() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("lib/src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\npub use a::Thing;\n").unwrap();
    std::fs::write(
        src.join("a/mod.rs"),
        "mod inner;\npub use inner::Thing;\nuse crate::b::helper;\npub fn local() {}\n",
    )
    .unwrap();
    std::fs::write(src.join("a/inner.rs"), "pub struct Thing;\n").unwrap();
    let long_body = "    let x = 1;\n".repeat(MAX_FUNCTION_LINES);
    std::fs::write(
        src.join("b.rs"),
        format!(
            "use crate::a::{{Thing, local}}; // \"crate::x\" in a string or comment is no import\n\
             pub fn helper() {{\n{long_body}}}\n#[cfg(test)]\nmod tests {{\n    fn long() {{\n{long_body}}}\n}}\n"
        ),
    )
    .unwrap();
    let tree = SourceTree::read_crates(&[dir.path().join("lib")]);
    let cycles = tree.import_cycles();
    assert_eq!(cycles.len(), 1, "{cycles:?}");
    let names: Vec<String> = cycles[0]
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into())
        .collect();
    assert!(
        names.contains(&"b.rs".into()) && names.contains(&"mod.rs".into()),
        "{names:?}"
    );
    // `crate::a::Thing` is a re-export: that edge goes to a/inner.rs, which is in no cycle;
    // the cycle is b.rs <-> a/mod.rs through `local` and `helper`.
    assert!(!names.contains(&"inner.rs".into()), "{names:?}");
    let b = tree.all_files().find(|f| f.path.ends_with("b.rs")).unwrap();
    let spans = function_spans(&tokens(&b.text));
    let helper = spans.iter().find(|s| s.name == "helper").unwrap();
    assert!(helper.lines > MAX_FUNCTION_LINES && !helper.in_test);
    assert!(spans.iter().find(|s| s.name == "long").unwrap().in_test);
    assert!(b.lines > 2 * MAX_FUNCTION_LINES);
    let printing = "fn f() {\n    println!(\"x\");\n    log::info!(\"y\");\n}\n\
                    // eprintln!(\"in a comment\")\n#[cfg(test)]\nmod tests {\n    fn g() { dbg!(1); }\n}\n";
    assert_eq!(prints_outside_tests(&tokens(printing)), [2]);
}

/// Every path the documentation names (in backticks) exists, so the layout table and the
/// conventions follow the tree. The README's table of rooms still to be built is exempt.
#[test]
fn the_documentation_names_paths_that_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut missing = Vec::new();
    let mut docs: Vec<PathBuf> = ["README.md", "CONVENTIONS.md", "scenes/README.md"]
        .iter()
        .map(PathBuf::from)
        .collect();
    docs.extend(
        std::fs::read_dir(root.join("docs"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .map(|p| PathBuf::from("docs").join(p.file_name().unwrap())),
    );
    for doc in &docs {
        let text = std::fs::read_to_string(root.join(doc)).unwrap();
        let doc = doc.display();
        let mut in_rooms = false;
        for line in text.lines() {
            if line.starts_with("Rooms for the work now being built") {
                in_rooms = true;
            } else if in_rooms && !line.starts_with('|') && !line.is_empty() {
                in_rooms = false;
            }
            if in_rooms {
                continue;
            }
            for path in backticked_repo_paths(line) {
                if !root.join(&path).exists() {
                    missing.push(format!("{doc}: {path}"));
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "paths named but absent:\n{}",
        missing.join("\n")
    );
}

/// Every folder of source (each crate's `src/`, the Python module's, the shaders) is in the
/// README's Layout tables: named in full, or by its own name in the row of its parent folder.
#[test]
fn the_layout_table_names_every_source_folder() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let layout = readme
        .split("\n## Layout")
        .nth(1)
        .and_then(|rest| rest.split("\n## ").next())
        .expect("README has a Layout section");
    let rows: Vec<Vec<&str>> = layout
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| l.split('`').skip(1).step_by(2).collect())
        .collect();
    let named = |path: &str| rows.iter().any(|r| r.contains(&path));
    let mut folders = Vec::new();
    for top in CRATES {
        folders.extend(source_folders(&root.join(top).join("src"), root));
    }
    let missing: Vec<String> = folders
        .into_iter()
        .filter(|f| {
            let (parent, name) = f.rsplit_once('/').unwrap_or(("", f));
            let in_parent_row = rows.iter().any(|r| {
                r.contains(&format!("{parent}/").as_str())
                    && (r.contains(&name) || r.contains(&format!("{name}/").as_str()))
            });
            // A crate's `src/` is its row in the crates' table.
            let crate_row = name == "src" && named(&format!("{parent}/"));
            !named(&format!("{f}/")) && !in_parent_row && !crate_row
        })
        .collect();
    assert!(
        missing.is_empty(),
        "source folders the README's Layout does not name:\n{}",
        missing.join("\n")
    );
}

/// `dir` and every folder below it, relative to `root`, `/`-separated.
fn source_folders(dir: &Path, root: &Path) -> Vec<String> {
    let mut out = vec![
        dir.strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .trim_start_matches("./")
            .to_owned(),
    ];
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(source_folders(&path, root));
        }
    }
    out
}

/// Paths in backticks that start at one of the repository's top-level folders.
fn backticked_repo_paths(line: &str) -> Vec<String> {
    const TOP: [&str; 11] = [
        "foundation/",
        "capture/",
        "python/",
        "precompute/",
        "reference/",
        "runtime/",
        "src/",
        "shaders/",
        "tests/",
        "scenes/",
        "docs/",
    ];
    line.split('`')
        .skip(1)
        .step_by(2)
        .filter(|s| TOP.iter().any(|t| s.starts_with(t)))
        .filter(|s| !s.contains(['{', '*', ' ']))
        .map(|s| {
            s.split("::")
                .next()
                .unwrap_or(s)
                .trim_end_matches('/')
                .to_owned()
        })
        .collect()
}

/// Every limit in `foundation/src/infra/limits.rs` is listed, with why, in CONVENTIONS.md.
#[test]
fn every_limit_is_documented() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let limits = std::fs::read_to_string(root.join("foundation/src/infra/limits.rs")).unwrap();
    let conventions = std::fs::read_to_string(root.join("CONVENTIONS.md")).unwrap();
    let names: Vec<&str> = limits
        .lines()
        .filter_map(|l| l.strip_prefix("pub const "))
        .filter_map(|l| l.split(':').next())
        .collect();
    assert!(names.len() >= 5, "{names:?}");
    let missing: Vec<&&str> = names
        .iter()
        .filter(|n| !conventions.contains(&format!("`{n}`")))
        .collect();
    assert!(
        missing.is_empty(),
        "limits missing from CONVENTIONS.md: {missing:?}"
    );
}
