//! Reads the workspace's Rust sources as tokens: functions with their lengths, and the imports
//! between files (through `use` and `crate::`/`super::` paths, following re-exports to the file
//! that defines an item).

use super::imports::{PathRef, absolute, strongly_connected, use_tree};
use super::tokens::{Tok, Token, is_ident, is_punct, matching, tokens};
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// The crates whose imports are checked, each with its source folder.
pub const CRATES: [&str; 9] = [
    "foundation",
    "bench",
    "precompute",
    "reference",
    "runtime",
    "report",
    "capture",
    "python",
    ".",
];
/// Folders whose files are only size-checked: tests and benchmarks.
const OTHER_FOLDERS: [&str; 3] = ["tests", "runtime/benches", "precompute/benches"];

pub struct SourceFile {
    pub path: PathBuf,
    pub text: String,
    pub lines: usize,
    /// A test or benchmark file, or a module declared under `#[cfg(test)]`.
    pub is_test_file: bool,
    /// Module path inside its crate (empty for the crate root); `None` outside a crate.
    module: Option<Vec<String>>,
    krate: usize,
}

pub struct SourceTree {
    files: Vec<SourceFile>,
}

/// Token ranges of items under `#[cfg(test)]` (test modules, test helpers).
fn test_spans(toks: &[Token]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i + 6 < toks.len() {
        let cfg_test = is_punct(&toks[i], '#')
            && is_punct(&toks[i + 1], '[')
            && is_ident(&toks[i + 2], "cfg")
            && is_punct(&toks[i + 3], '(')
            && is_ident(&toks[i + 4], "test")
            && is_punct(&toks[i + 5], ')');
        if !cfg_test {
            i += 1;
            continue;
        }
        let start = i;
        // The item: up to its first `;` or its body's closing brace, whichever comes first.
        let mut k = i + 7;
        while k < toks.len() && !is_punct(&toks[k], ';') && !is_punct(&toks[k], '{') {
            k += if is_punct(&toks[k], '[') {
                matching(toks, k) - k + 1
            } else {
                1
            };
        }
        let end = if k < toks.len() && is_punct(&toks[k], '{') {
            matching(toks, k)
        } else {
            k
        };
        spans.push((start, end));
        i = end + 1;
    }
    spans
}

/// The names of modules declared `#[cfg(test)] mod name;` in a file.
fn test_module_declarations(toks: &[Token]) -> Vec<String> {
    let mut names = Vec::new();
    for (start, end) in test_spans(toks) {
        let body = &toks[start..=end.min(toks.len() - 1)];
        if let Some(m) = body.iter().position(|t| is_ident(t, "mod"))
            && let Some(Tok::Ident(name)) = body.get(m + 1).map(|t| &t.tok)
            && body.get(m + 2).is_some_and(|t| is_punct(t, ';'))
        {
            names.push(name.clone());
        }
    }
    names
}

pub struct FunctionSpan {
    pub name: String,
    pub line: usize,
    pub lines: usize,
    pub in_test: bool,
}

/// Every function with a body: its name, first line, length in lines and whether it is test
/// code.
pub fn function_spans(toks: &[Token]) -> Vec<FunctionSpan> {
    let tests = test_spans(toks);
    let mut spans = Vec::new();
    for i in 0..toks.len().saturating_sub(1) {
        let Tok::Ident(name) = &toks[i + 1].tok else {
            continue;
        };
        if !is_ident(&toks[i], "fn") {
            continue;
        }
        let mut k = i + 2;
        while k < toks.len() && !is_punct(&toks[k], '{') && !is_punct(&toks[k], ';') {
            k += if is_punct(&toks[k], '(') || is_punct(&toks[k], '[') {
                matching(toks, k) - k + 1
            } else {
                1
            };
        }
        if k >= toks.len() || is_punct(&toks[k], ';') {
            continue;
        }
        let end = matching(toks, k);
        spans.push(FunctionSpan {
            name: name.clone(),
            line: toks[i].line,
            lines: toks[end].line - toks[i].line + 1,
            in_test: tests.iter().any(|&(s, e)| s <= i && i <= e),
        });
    }
    spans
}

/// The lines of `println!`, `print!`, `eprintln!`, `eprint!` and `dbg!` outside test code.
pub fn prints_outside_tests(toks: &[Token]) -> Vec<usize> {
    const PRINTS: [&str; 5] = ["println", "print", "eprintln", "eprint", "dbg"];
    let tests = test_spans(toks);
    (0..toks.len().saturating_sub(1))
        .filter(|&i| PRINTS.iter().any(|p| is_ident(&toks[i], p)) && is_punct(&toks[i + 1], '!'))
        .filter(|&i| !tests.iter().any(|&(s, e)| s <= i && i <= e))
        .map(|i| toks[i].line)
        .collect()
}

/// The paths a file refers to outside its test code: `use` trees, and paths in code that
/// start with `crate`, `super`, `self` or one of `children` (the file's child modules).
fn path_refs(toks: &[Token], children: &BTreeSet<String>) -> Vec<PathRef> {
    let tests = test_spans(toks);
    let in_test = |i: usize| tests.iter().any(|&(s, e)| s <= i && i <= e);
    let mut refs = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        if in_test(i) {
            i += 1;
            continue;
        }
        if is_ident(&toks[i], "use") {
            let reexport = i > 0 && (is_ident(&toks[i - 1], "pub") || is_punct(&toks[i - 1], ')'));
            let mut paths = Vec::new();
            i = use_tree(toks, i + 1, &[], &mut paths);
            refs.extend(
                paths
                    .into_iter()
                    .map(|segments| PathRef { segments, reexport }),
            );
            continue;
        }
        let starts_path = matches!(&toks[i].tok, Tok::Ident(s)
            if s == "crate" || s == "super" || s == "self" || children.contains(s))
            && toks.get(i + 1).is_some_and(|t| t.tok == Tok::PathSep)
            && (i == 0 || toks[i - 1].tok != Tok::PathSep);
        if starts_path {
            let mut segments = Vec::new();
            while let Some(Tok::Ident(s)) = toks.get(i).map(|t| &t.tok) {
                segments.push(s.clone());
                if toks.get(i + 1).is_some_and(|t| t.tok == Tok::PathSep) {
                    i += 2;
                } else {
                    i += 1;
                    break;
                }
            }
            refs.push(PathRef {
                segments,
                reexport: false,
            });
            continue;
        }
        i += 1;
    }
    refs
}

impl SourceTree {
    /// The workspace at `root`: its crates and its test and benchmark files.
    pub fn read(root: &Path) -> Self {
        let crates: Vec<PathBuf> = CRATES.iter().map(|c| root.join(c)).collect();
        let mut tree = Self::read_crates(&crates);
        for folder in OTHER_FOLDERS {
            for path in rust_files(&root.join(folder)) {
                let text = std::fs::read_to_string(&path).unwrap();
                tree.files.push(SourceFile {
                    lines: text.lines().count(),
                    path,
                    text,
                    is_test_file: true,
                    module: None,
                    krate: usize::MAX,
                });
            }
        }
        tree
    }

    /// The crates in `dirs` (each with a `src/` holding `lib.rs` or `main.rs`).
    pub fn read_crates(dirs: &[PathBuf]) -> Self {
        let mut files = Vec::new();
        for (krate, dir) in dirs.iter().enumerate() {
            let src = dir.join("src");
            let root = ["lib.rs", "main.rs"]
                .iter()
                .map(|r| src.join(r))
                .find(|p| p.exists());
            let Some(root) = root else { continue };
            collect_module(&root, Vec::new(), krate, false, &mut files);
        }
        Self { files }
    }

    pub fn all_files(&self) -> impl Iterator<Item = &SourceFile> {
        self.files.iter()
    }

    /// Sets of files that import each other, directly or through others (strongly connected
    /// components of more than one file).
    pub fn import_cycles(&self) -> Vec<Vec<PathBuf>> {
        let edges = self.import_edges();
        strongly_connected(self.files.len(), &edges)
            .into_iter()
            .filter(|c| c.len() > 1)
            .map(|c| c.into_iter().map(|f| self.files[f].path.clone()).collect())
            .collect()
    }

    fn import_edges(&self) -> Vec<BTreeSet<usize>> {
        let by_module: HashMap<(usize, Vec<String>), usize> = self
            .files
            .iter()
            .enumerate()
            .filter_map(|(i, f)| f.module.clone().map(|m| ((f.krate, m), i)))
            .collect();
        let refs: Vec<Vec<PathRef>> = self
            .files
            .iter()
            .map(|f| match &f.module {
                Some(m) => path_refs(&tokens(&f.text), &self.children(f.krate, m)),
                None => Vec::new(),
            })
            .collect();
        // Re-exports: (file, exported name) -> the absolute path it names (`None`: an item of
        // another crate, which no file of this one defines).
        let mut reexports: HashMap<(usize, String), Option<Vec<String>>> = HashMap::new();
        for (i, f) in self.files.iter().enumerate() {
            let Some(m) = &f.module else { continue };
            for r in refs[i].iter().filter(|r| r.reexport) {
                let Some(name) = r.segments.last().filter(|n| *n != "*") else {
                    continue;
                };
                let abs = absolute(m, &r.segments, &self.children(f.krate, m));
                reexports.insert((i, name.clone()), abs);
            }
        }
        let resolve = |krate: usize, abs: &[String]| -> Option<usize> {
            let mut abs = abs.to_vec();
            for _ in 0..16 {
                let (file, rest) = (0..=abs.len()).rev().find_map(|n| {
                    by_module
                        .get(&(krate, abs[..n].to_vec()))
                        .map(|&f| (f, &abs[n..]))
                })?;
                match rest
                    .first()
                    .and_then(|name| reexports.get(&(file, name.clone())))
                {
                    Some(None) => return None,
                    Some(Some(target)) if target != &abs => {
                        let mut next = target.clone();
                        next.extend(rest[1..].iter().cloned());
                        abs = next;
                    }
                    _ => return Some(file),
                }
            }
            None
        };
        let mut edges = vec![BTreeSet::new(); self.files.len()];
        for (i, f) in self.files.iter().enumerate() {
            let Some(m) = &f.module else { continue };
            let children = self.children(f.krate, m);
            for r in &refs[i] {
                if r.reexport && r.segments.first().is_some_and(|s| children.contains(s)) {
                    continue; // a module re-exporting its own child is its facade, not a user
                }
                if let Some(abs) = absolute(m, &r.segments, &children)
                    && let Some(target) = resolve(f.krate, &abs)
                    && target != i
                {
                    edges[i].insert(target);
                }
            }
        }
        edges
    }

    fn children(&self, krate: usize, module: &[String]) -> BTreeSet<String> {
        self.files
            .iter()
            .filter(|f| f.krate == krate)
            .filter_map(|f| f.module.as_ref())
            .filter(|m| m.len() == module.len() + 1 && m.starts_with(module))
            .map(|m| m[module.len()].clone())
            .collect()
    }
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
    out
}

/// Reads the module in `path` and, recursively, the child modules it declares in files.
fn collect_module(
    path: &Path,
    module: Vec<String>,
    krate: usize,
    test: bool,
    out: &mut Vec<SourceFile>,
) {
    let text = std::fs::read_to_string(path).unwrap();
    let toks = tokens(&text);
    let test_children = test_module_declarations(&toks);
    let folder = if module.is_empty() || path.ends_with("mod.rs") {
        path.parent().unwrap().to_path_buf()
    } else {
        path.with_extension("")
    };
    let mut children = Vec::new();
    for k in 0..toks.len().saturating_sub(2) {
        if is_ident(&toks[k], "mod")
            && let Tok::Ident(name) = &toks[k + 1].tok
            && is_punct(&toks[k + 2], ';')
        {
            children.push(name.clone());
        }
    }
    out.push(SourceFile {
        lines: text.lines().count(),
        path: path.to_path_buf(),
        text,
        is_test_file: test,
        module: Some(module.clone()),
        krate,
    });
    for name in children {
        let file = [
            folder.join(format!("{name}.rs")),
            folder.join(&name).join("mod.rs"),
        ]
        .into_iter()
        .find(|p| p.exists());
        if let Some(file) = file {
            let mut child = module.clone();
            child.push(name.clone());
            collect_module(
                &file,
                child,
                krate,
                test || test_children.contains(&name),
                out,
            );
        }
    }
}
