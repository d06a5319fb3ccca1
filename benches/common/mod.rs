//! What the benches share: loading a scene of the repository as the driver does.

use risotto::engine::scene::CompiledScene;
use risotto::loader::load::{compile_scene, load_scene_file, MaterialRegistry};
use std::path::Path;

/// The scene file at `relative` (from the repository root), loaded with the built-in
/// materials and compiled.
pub fn compile(relative: &str) -> CompiledScene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
    let scene = load_scene_file(&path, &MaterialRegistry::with_builtins()).unwrap();
    compile_scene(scene).unwrap()
}
