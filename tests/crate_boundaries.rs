//! The engine's crates follow who may know whom (issue 31): Cargo enforces the direction
//! between crates (components <- systems <- core <- builtins <- loader; tools <- core); these
//! tests check what Cargo cannot:
//! - inside every crate, the top-level modules depend on each other without a cycle
//!   (production code; `module_graph` says what counts);
//! - no built-in names the scene world, the stats, the intersector or a loader type: a
//!   built-in gets everything through the plug-in contract, as a user's plug-in does;
//! - the core engine's dependencies name no plotting, VDB, TOML or OBJ crate, so an embedder
//!   who builds scenes in code compiles none of them.

#[path = "../systems/tests/module_graph/mod.rs"]
mod module_graph;

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file below `dir`, with its text.
fn sources(dir: &Path) -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).unwrap();
                out.push((p, text));
            }
        }
    }
    out
}

#[test]
fn every_crate_s_modules_form_a_dag() {
    let mut cycles = Vec::new();
    for krate in [
        "components",
        "systems",
        "engine/core",
        "engine/builtins",
        "engine/loader",
        "engine/tools",
        ".",
    ] {
        let g = module_graph::read(&root().join(krate).join("src"));
        assert!(g.len() > 1 || krate == ".", "{krate}: no modules read");
        if let Some(cycle) = module_graph::find_cycle(&g) {
            cycles.push(format!("{krate}: {}", cycle.join(" -> ")));
        }
    }
    assert!(cycles.is_empty(), "import cycles:\n{}", cycles.join("\n"));
    // The reader sees the engine's own edges at all.
    let core = module_graph::read(&root().join("engine/core/src"));
    assert!(core["path_tracer"].contains_key("integrator"), "{core:#?}");
}

/// Names a built-in must not use: the compiled scene and the worker's stats (behind the
/// integrator context's methods), the intersector (`IntegratorContext::closest_hits`), and
/// anything of the scene-file loader.
const FORBIDDEN_IN_BUILTINS: [&str; 6] = [
    "CompiledScene",
    "SystemStats",
    "intersect_closest",
    "risotto_loader",
    "MaterialParams",
    "scene_file",
];

#[test]
fn no_built_in_reaches_past_the_contract() {
    let files = sources(&root().join("engine/builtins/src"));
    assert!(files.len() > 10);
    let mut found = Vec::new();
    for (path, text) in &files {
        for (n, line) in text.lines().enumerate() {
            for name in FORBIDDEN_IN_BUILTINS {
                if line.contains(name) {
                    found.push(format!("{}:{}: {name}", path.display(), n + 1));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "built-ins past the contract:\n{}",
        found.join("\n")
    );
    let manifest = std::fs::read_to_string(root().join("engine/builtins/Cargo.toml")).unwrap();
    assert!(!manifest.contains("risotto-loader") && !manifest.contains("risotto-tools"));
}

#[test]
fn the_core_engine_depends_on_no_file_format_or_plotting_crate() {
    let manifest = std::fs::read_to_string(root().join("engine/core/Cargo.toml")).unwrap();
    let deps = manifest
        .split("[dependencies]")
        .nth(1)
        .expect("a [dependencies] table")
        .split("\n[")
        .next()
        .unwrap();
    for name in [
        "plotters",
        "vdb-rs",
        "toml",
        "tobj",
        "dejavu",
        "risotto-loader",
    ] {
        assert!(
            !deps.lines().any(|l| l.trim_start().starts_with(name)),
            "engine/core depends on {name}"
        );
    }
    assert!(deps.contains("risotto-systems"), "{deps}");
}

/// The library an embedder depends on (`risotto` with `default-features = false`) pulls in
/// none of the driver's crates: each is optional and enabled only by the `cli` feature, and
/// what a plug-in needs (the workspace crates, glam, bumpalo) is not optional.
#[test]
fn the_driver_s_crates_are_behind_the_cli_feature() {
    let manifest: toml::Table = std::fs::read_to_string(root().join("Cargo.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let deps = manifest["dependencies"].as_table().unwrap();
    let cli: Vec<&str> = manifest["features"]["cli"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let optional = |name: &str| deps[name].get("optional").and_then(|o| o.as_bool()) == Some(true);
    for name in ["clap", "indicatif", "signal-hook", "anyhow"] {
        assert!(optional(name), "{name} is not optional");
        assert!(
            cli.contains(&format!("dep:{name}").as_str()),
            "cli lacks {name}"
        );
    }
    for name in [
        "risotto-engine",
        "risotto-builtins",
        "risotto-loader",
        "glam",
        "bumpalo",
    ] {
        assert!(!optional(name), "{name} must come with the library");
    }
    let bin = &manifest["bin"].as_array().unwrap()[0];
    assert_eq!(
        bin["required-features"].as_array().unwrap()[0].as_str(),
        Some("cli")
    );
    // Publishable: the package name is free on crates.io (`risotto` is another project's),
    // while the library and the command keep the name `risotto`.
    assert_eq!(
        manifest["package"]["name"].as_str(),
        Some("risotto-renderer")
    );
    assert_eq!(manifest["lib"]["name"].as_str(), Some("risotto"));
    assert_eq!(bin["name"].as_str(), Some("risotto"));
    // Every workspace crate a published crate depends on carries a version beside its path.
    let workspace = manifest["workspace"]["dependencies"].as_table().unwrap();
    for (name, dep) in workspace.iter().filter(|(n, _)| n.starts_with("risotto-")) {
        assert!(
            dep.get("version").is_some(),
            "{name} has a path but no version"
        );
    }
}
