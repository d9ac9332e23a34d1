//! The import graph's pieces: `use` trees expanded into paths, paths made absolute from the
//! module they are written in, and the graph's strongly connected components (its cycles).

use super::tokens::{Tok, Token, is_punct};
use std::collections::BTreeSet;

/// One path a file refers to, split into segments, and whether it is a re-export.
pub struct PathRef {
    pub segments: Vec<String>,
    pub reexport: bool,
}

/// Expands a `use` tree starting at `i` (after `use`) into full paths; returns them and the
/// index of the ending `;`.
pub fn use_tree(
    toks: &[Token],
    mut i: usize,
    prefix: &[String],
    out: &mut Vec<Vec<String>>,
) -> usize {
    let mut path = prefix.to_vec();
    loop {
        match &toks[i].tok {
            Tok::Ident(s) if s == "as" => {
                i += 2; // the alias names the same item
            }
            Tok::Ident(s) => {
                path.push(s.clone());
                i += 1;
            }
            Tok::PathSep => i += 1,
            Tok::Punct('*') => {
                path.push("*".into());
                i += 1;
            }
            Tok::Punct('{') => {
                i += 1;
                loop {
                    if is_punct(&toks[i], '}') {
                        break;
                    }
                    i = use_tree(toks, i, &path, out);
                    if is_punct(&toks[i], ',') {
                        i += 1;
                    }
                }
                return i + 1;
            }
            _ => {
                if path.len() > prefix.len() {
                    if path.last().is_some_and(|s| s == "self") {
                        path.pop();
                    }
                    out.push(path);
                }
                return i;
            }
        }
    }
}

/// `segments` (as written in module `module`) as a path from the crate root; `None` for paths
/// into other crates.
pub fn absolute(
    module: &[String],
    segments: &[String],
    children: &BTreeSet<String>,
) -> Option<Vec<String>> {
    let mut base: Vec<String> = module.to_vec();
    let mut rest = segments;
    match segments.first().map(String::as_str) {
        Some("crate") => {
            base.clear();
            rest = &segments[1..];
        }
        Some("self") => rest = &segments[1..],
        Some("super") => {
            while rest.first().is_some_and(|s| s == "super") {
                base.pop()?;
                rest = &rest[1..];
            }
        }
        Some(first) if children.contains(first) => {}
        _ => return None,
    }
    base.extend(rest.iter().filter(|s| *s != "*").cloned());
    Some(base)
}

/// Tarjan's strongly connected components.
pub fn strongly_connected(n: usize, edges: &[BTreeSet<usize>]) -> Vec<Vec<usize>> {
    struct State<'a> {
        edges: &'a [BTreeSet<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for &w in s.edges[v].clone().iter() {
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                comp.push(w);
                if w == v {
                    break;
                }
            }
            comp.sort();
            s.out.push(comp);
        }
    }
    let mut s = State {
        edges,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}
