//! The dependency graph between the top-level modules of a crate, read from its sources, and
//! a check that it has no cycle. Standard library only, so that any crate's tests can use it:
//! `mod module_graph;` from a test in this folder, or from another crate
//! `#[path = "<relative path to this file>"] mod module_graph;`, then
//! `module_graph::assert_acyclic(&module_graph::read(src_dir))`.
//!
//! Module `a` depends on module `b` when code anywhere under `a` (its file `a.rs` or
//! `a/mod.rs` and the files of its submodules) names a path `crate::b...` (also inside
//! `crate::{...}` groups and as a macro's `$crate::b`) or climbs to the crate root with
//! `super::` and names `b` there. What does not count:
//! - comments, doc comments included: an intra-doc link to a module is no dependency;
//! - test code: an item under `#[cfg(test)]` (an inline `mod tests { .. }`, a test helper)
//!   and the files of a module declared under it (`#[cfg(test)] mod tests;`), and files that
//!   start with `#![cfg(test)]`. Unit tests may reach up to the modules that use the one
//!   they test;
//! - `#[path]` attributes (module files are found by the usual layout only) and paths
//!   through re-exports of the crate root (`crate::item`, where `item` is not a module).

#![allow(
    dead_code,
    reason = "each test crate that includes this module uses a subset"
)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// For each top-level module, the modules it depends on, each with the files (relative to
/// the source folder) that name it.
pub type Graph = BTreeMap<String, BTreeMap<String, BTreeSet<String>>>;

/// The graph of the crate whose sources (`lib.rs` or `main.rs` and the module files) are in
/// `src`.
///
/// # Panics
/// If the folder or a file in it cannot be read.
pub fn read(src: &Path) -> Graph {
    let mut files = Vec::new();
    collect(src, src, &mut files);
    graph(&files)
}

/// The `.rs` files under `dir` as (path relative to `src`, text), sorted.
fn collect(src: &Path, dir: &Path, out: &mut Vec<(PathBuf, String)>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let mut paths: Vec<PathBuf> = entries
        .map(|e| e.expect("directory entry").path())
        .collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            collect(src, &p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let text =
                std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            out.push((p.strip_prefix(src).expect("under src").to_path_buf(), text));
        }
    }
}

/// The graph of the files `(path relative to the source folder, text)`.
pub fn graph(files: &[(PathBuf, String)]) -> Graph {
    let parsed: Vec<(Vec<String>, String, Vec<Tok>)> = files
        .iter()
        .map(|(path, text)| (module_path(path), path.display().to_string(), tokens(text)))
        .collect();
    let modules: BTreeSet<&str> = parsed
        .iter()
        .filter_map(|(m, _, _)| m.first().map(String::as_str))
        .collect();
    // Two passes: a file learns that it is test code from its parent's declaration.
    let mut test_only = BTreeSet::new();
    let mut refs = Vec::new();
    for (module, _, toks) in &parsed {
        refs.push(scan(module, toks, &mut test_only));
    }
    let mut g = Graph::new();
    for ((module, name, toks), refs) in parsed.iter().zip(refs) {
        let inner_cfg_test = toks.starts_with(&attr(true));
        let in_tests = (1..=module.len()).any(|n| test_only.contains(&module[..n]));
        let Some(from) = module.first() else { continue };
        if inner_cfg_test || in_tests {
            continue;
        }
        g.entry(from.clone()).or_default();
        for to in refs {
            if to != *from && modules.contains(to.as_str()) {
                let files = g.entry(from.clone()).or_default().entry(to).or_default();
                files.insert(name.clone());
            }
        }
    }
    g
}

/// The module path of a file: `a.rs` and `a/mod.rs` are `[a]`, `a/b.rs` is `[a, b]`, the
/// crate root `[]`.
fn module_path(path: &Path) -> Vec<String> {
    let mut parts: Vec<String> = path
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.strip_suffix(".rs").unwrap_or(&last);
    let root = parts.is_empty() && matches!(stem, "lib" | "main");
    if stem != "mod" && !root {
        parts.push(stem.to_string());
    }
    parts
}

/// A token of Rust source, as far as paths need: identifiers, `::` and single characters.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Punct(char),
}

/// The tokens of `text` without comments, literals and lifetimes.
fn tokens(text: &str) -> Vec<Tok> {
    let c: Vec<char> = text.chars().collect();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let ident_char = |x: char| x.is_alphanumeric() || x == '_';
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let x = c[i];
        if x == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if x == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && at(i + 1) == '*' {
                    (depth, i) = (depth + 1, i + 2);
                } else if c[i] == '*' && at(i + 1) == '/' {
                    (depth, i) = (depth - 1, i + 2);
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if x == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if (x == 'r' || (x == 'b' && at(i + 1) == 'r'))
            && matches!(at(i + 1 + (x == 'b') as usize), '"' | '#')
            && !(i > 0 && ident_char(c[i - 1]))
        {
            // A raw string `r#"..."#` (or a raw identifier `r#name`, lexed as `name`).
            let mut j = i + 1 + (x == 'b') as usize;
            let hashes = c[j..].iter().take_while(|&&h| h == '#').count();
            j += hashes;
            if at(j) != '"' {
                i = j;
                continue;
            }
            // Past the closing quote followed by as many `#`.
            i = j + 1;
            while i < c.len() && !(c[i] == '"' && (1..=hashes).all(|k| at(i + k) == '#')) {
                i += 1;
            }
            i += 1 + hashes;
        } else if x == '\'' {
            if at(i + 1) == '\\' {
                // An escape: past `'\x`, then to the closing quote.
                i += 3;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if at(i + 2) == '\'' {
                i += 3;
            } else {
                // A lifetime or label.
                i += 1;
                while i < c.len() && ident_char(c[i]) {
                    i += 1;
                }
            }
        } else if ident_char(x) {
            let start = i;
            while i < c.len() && ident_char(c[i]) {
                i += 1;
            }
            if !x.is_ascii_digit() {
                out.push(Tok::Ident(c[start..i].iter().collect()));
            }
        } else if x == ':' && at(i + 1) == ':' {
            out.push(Tok::PathSep);
            i += 2;
        } else {
            if !x.is_whitespace() {
                out.push(Tok::Punct(x));
            }
            i += 1;
        }
    }
    out
}

/// The tokens of `#[cfg(test)]`, or of `#![cfg(test)]` if `inner`.
fn attr(inner: bool) -> Vec<Tok> {
    let mut t = vec![Tok::Punct('#')];
    if inner {
        t.push(Tok::Punct('!'));
    }
    let ident = |s: &str| Tok::Ident(s.to_string());
    t.extend([Tok::Punct('['), ident("cfg"), Tok::Punct('(')]);
    t.extend([ident("test"), Tok::Punct(')'), Tok::Punct(']')]);
    t
}

/// The index just past the group that opens at `toks[i]` (`(`, `[` or `{`).
fn skip_group(toks: &[Tok], mut i: usize) -> usize {
    let mut depth = 0i32;
    while i < toks.len() {
        match toks[i] {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(')' | ']' | '}') => depth -= 1,
            _ => {}
        }
        i += 1;
        if depth == 0 {
            break;
        }
    }
    i
}

/// The top-level names that the file of module `module` refers to outside test code; adds
/// the modules it declares under `#[cfg(test)]` to `test_only`.
fn scan(module: &[String], toks: &[Tok], test_only: &mut BTreeSet<Vec<String>>) -> Vec<String> {
    let cfg_test = attr(false);
    let ident = |i: usize, s: &str| matches!(toks.get(i), Some(Tok::Ident(x)) if x == s);
    let punct = |i: usize, p: char| toks.get(i) == Some(&Tok::Punct(p));
    let sep = |i: usize| toks.get(i) == Some(&Tok::PathSep);
    let name = |i: usize| match toks.get(i) {
        Some(Tok::Ident(x)) => Some(x.clone()),
        _ => None,
    };
    let mut refs = Vec::new();
    // Inline modules open at the current brace depth: (name, depth inside its braces).
    let mut inline: Vec<(String, i32)> = Vec::new();
    let mut depth = 0i32;
    let mut i = 0;
    while i < toks.len() {
        if toks[i..].starts_with(&cfg_test) {
            // Skip the attribute, any further attributes and the item.
            let mut j = i + cfg_test.len();
            while punct(j, '#') && punct(j + 1, '[') {
                j = skip_group(toks, j + 1);
            }
            // The item ends with its `{ .. }` body, a `;`, or (a field, a variant, a match
            // arm) a `,` or the `}` around it, outside its parameters and generics.
            let item = j;
            let mut nest = 0i32;
            while j < toks.len() {
                let arrow = j > 0 && matches!(toks[j - 1], Tok::Punct('-' | '='));
                match toks[j] {
                    Tok::Punct('(' | '[' | '<') => nest += 1,
                    Tok::Punct(')' | ']') => nest -= 1,
                    Tok::Punct('>') if !arrow => nest -= 1,
                    Tok::Punct(',') if nest == 0 => {
                        j += 1;
                        break;
                    }
                    Tok::Punct('}') if nest == 0 => break,
                    Tok::Punct('{') if nest == 0 => {
                        j = skip_group(toks, j);
                        break;
                    }
                    Tok::Punct(';') if nest == 0 => {
                        let decl = toks[item..j].windows(2).find_map(|w| match w {
                            [Tok::Ident(m), Tok::Ident(n)] if m == "mod" => Some(n.clone()),
                            _ => None,
                        });
                        if let Some(n) = decl {
                            let mut path = module.to_vec();
                            path.extend(inline.iter().map(|(m, _)| m.clone()));
                            path.push(n);
                            test_only.insert(path);
                        }
                        j += 1;
                        break;
                    }
                    _ => {}
                }
                j += 1;
            }
            i = j;
            continue;
        }
        match &toks[i] {
            Tok::Punct('{') => {
                depth += 1;
                if i >= 2 && ident(i - 2, "mod") {
                    inline.push((name(i - 1).unwrap_or_default(), depth));
                }
            }
            Tok::Punct('}') => {
                if inline.last().is_some_and(|&(_, d)| d == depth) {
                    inline.pop();
                }
                depth -= 1;
            }
            Tok::Ident(x) if x == "crate" && sep(i + 1) => refs.extend(names(toks, i + 2)),
            Tok::Ident(x) if x == "super" && (i == 0 || !sep(i - 1)) => {
                // `super::` climbs one module; at the crate root, the next name is top-level.
                let (mut ups, mut j) = (0, i);
                while ident(j, "super") && sep(j + 1) {
                    (ups, j) = (ups + 1, j + 2);
                }
                if ups == module.len() + inline.len() {
                    refs.extend(names(toks, j));
                }
            }
            _ => {}
        }
        i += 1;
    }
    refs
}

/// The first segments of the paths that start at `toks[i]`: one name, or the names that
/// begin each member of a `{ .. }` group.
fn names(toks: &[Tok], i: usize) -> Vec<String> {
    match toks.get(i) {
        Some(Tok::Ident(x)) => vec![x.clone()],
        Some(Tok::Punct('{')) => {
            let end = skip_group(toks, i);
            let mut out = Vec::new();
            let (mut depth, mut first) = (0, true);
            for t in &toks[i + 1..end - 1] {
                match t {
                    Tok::Punct('{') => depth += 1,
                    Tok::Punct('}') => depth -= 1,
                    Tok::Punct(',') if depth == 0 => first = true,
                    Tok::Ident(x) if first && depth == 0 => {
                        out.push(x.clone());
                        first = false;
                    }
                    _ => first = false,
                }
            }
            out
        }
        _ => Vec::new(),
    }
}

/// A cycle of `g` as the modules along it, the first repeated at the end, if there is one.
pub fn find_cycle(g: &Graph) -> Option<Vec<String>> {
    /// Depth-first search from `m`; `path` holds the modules on the stack.
    fn visit<'a>(
        g: &'a Graph,
        m: &'a str,
        path: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
    ) -> Option<Vec<String>> {
        if let Some(k) = path.iter().position(|&p| p == m) {
            let mut cycle: Vec<String> = path[k..].iter().map(|s| s.to_string()).collect();
            cycle.push(m.to_string());
            return Some(cycle);
        }
        if !done.insert(m) {
            return None;
        }
        path.push(m);
        for to in g.get(m).into_iter().flat_map(|e| e.keys()) {
            if let Some(c) = visit(g, to, path, done) {
                return Some(c);
            }
        }
        path.pop();
        None
    }
    let mut done = BTreeSet::new();
    g.keys()
        .find_map(|m| visit(g, m, &mut Vec::new(), &mut done))
}

/// Panics with a cycle of `g` and the files that make each of its edges, if `g` has one.
pub fn assert_acyclic(g: &Graph) {
    if let Some(cycle) = find_cycle(g) {
        let edges: Vec<String> = cycle
            .windows(2)
            .map(|w| {
                let files: Vec<&str> = g[&w[0]][&w[1]].iter().map(String::as_str).collect();
                format!("  {} -> {}  (in {})", w[0], w[1], files.join(", "))
            })
            .collect();
        panic!(
            "the top-level modules have a cycle: {}\n{}",
            cycle.join(" -> "),
            edges.join("\n")
        );
    }
}
