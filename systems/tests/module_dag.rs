//! The top-level modules of `risotto-systems` depend on each other without a cycle (issue 31
//! part 6): a module that needs something from a module that depends on it gets it moved
//! down into a module both can use. Production code only: comments (intra-doc links) and
//! `#[cfg(test)]` code do not count (see `module_graph`).

mod module_graph;

use module_graph::{assert_acyclic, find_cycle, graph, read};
use std::path::{Path, PathBuf};

#[test]
fn systems_modules_form_a_dag() {
    let g = read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    // The reader sees the crate's dependencies at all: a few that will not go away.
    for (from, to) in [
        ("geometry", "bvh8"),
        ("intersect", "geometry"),
        ("sampler", "simd8"),
    ] {
        assert!(
            g[from].contains_key(to),
            "{from} -> {to} not found in {g:#?}"
        );
    }
    assert_acyclic(&g);
}

/// The graph of in-memory files `(path, text)`.
fn graph_of(files: &[(&str, &str)]) -> module_graph::Graph {
    let files: Vec<(PathBuf, String)> = files
        .iter()
        .map(|&(p, t)| (PathBuf::from(p), t.to_string()))
        .collect();
    graph(&files)
}

#[test]
fn a_cycle_is_found_and_named() {
    let g = graph_of(&[
        ("lib.rs", "pub mod a; pub mod b; pub mod c;"),
        ("a.rs", "use crate::{b::X, c};"),
        ("b.rs", "mod inner;"),
        ("b/inner.rs", "pub fn f() { super::super::c::g() }"),
        ("c.rs", "pub fn g() { $crate::a::h!() }"),
    ]);
    assert_eq!(
        find_cycle(&g).expect("a cycle"),
        ["a", "b", "c", "a"].map(String::from)
    );
    assert!(g["b"]["c"].contains("b/inner.rs"));
    let panic = std::panic::catch_unwind(|| assert_acyclic(&g)).expect_err("a panic");
    let message = panic.downcast_ref::<String>().expect("a message");
    assert!(message.contains("a -> b -> c -> a"), "{message}");
}

#[test]
fn comments_literals_and_test_code_are_no_dependencies() {
    let g = graph_of(&[
        ("lib.rs", "pub mod a; pub mod b;"),
        ("a.rs", "pub fn f() -> u32 { 1 }\n#[cfg(test)]\nmod helper;"),
        (
            "b.rs",
            r##"
            //! Docs of b link to [`crate::a`].
            /* crate::a */
            use crate::a::f;
            const S: &str = "crate::a";
            const R: &str = r#"crate::a"#;
            const C: char = '{';
            fn g<'x>(s: &'x str) -> &'x str { s }
            pub struct P {
                #[cfg(test)]
                field: crate::a::T,
                kept: u32,
            }
            #[cfg(test)]
            mod tests;
            #[cfg(test)]
            mod inline { use crate::a::f; }
            "##,
        ),
        ("b/tests.rs", "use crate::a::f;"),
        ("a/helper.rs", "use crate::b::P;"),
    ]);
    assert_eq!(g["b"]["a"].iter().collect::<Vec<_>>(), ["b.rs"]);
    assert!(g["a"].is_empty(), "{g:#?}");
    // Without the `#[cfg(test)]`, `a`'s helper makes a cycle.
    let g = graph_of(&[
        ("b.rs", "use crate::a::f;"),
        ("a.rs", "mod helper;"),
        ("a/helper.rs", "use crate::b::P;"),
    ]);
    assert!(find_cycle(&g).is_some());
}
