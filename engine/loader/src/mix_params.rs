//! `type = "mix"`: two materials of the scene blended by an amount
//! ([`risotto_builtins::builtin::MixMaterial`]). The loader builds it (not a registry
//! constructor): its components are other materials of the file, named by `a` and `b`, each
//! built again through the registry for the mix (so they may also be used on their own).

use crate::scene_file::{ColourParam, MaterialDesc};
use risotto_builtins::builtin::{MixAmount, MixMaterial};
use risotto_components::Rgb;
use risotto_engine::diagnostics::{SceneError, SceneErrorKind};
use risotto_engine::plugin::BxdfFactory;
use std::sync::Arc;

/// The type name the loader builds itself.
pub const MIX: &str = "mix";

/// How deep mixes may nest (a mix of mixes of mixes): the components' parameter caches are
/// told apart by a path of this many levels
/// ([`risotto_engine::plugin::MAX_COMPONENTS`]).
const MAX_DEPTH: usize = 3;

/// A material's factory builder: the registry's `build` (material, depth).
pub(crate) type Build<'a> =
    &'a dyn Fn(&MaterialDesc, usize) -> Result<Box<dyn BxdfFactory>, SceneError>;

/// The factory of mix material `m` of `materials` (`depth`: how many mixes contain it),
/// its components built by `build`.
pub(crate) fn mix(
    m: &MaterialDesc,
    materials: &[MaterialDesc],
    build: Build<'_>,
    depth: usize,
) -> Result<Box<dyn BxdfFactory>, SceneError> {
    let p = &m.params;
    p.deny_unknown(&["a", "b", "amount"])?;
    if depth >= MAX_DEPTH {
        return Err(p.error(
            None,
            format!("mixes nest at most {MAX_DEPTH} deep (a mix of mixes of mixes)"),
        ));
    }
    let component = |key: &str| -> Result<Box<dyn BxdfFactory>, SceneError> {
        let name = p.string(key, None)?;
        let Some(c) = materials.iter().find(|c| c.name == name) else {
            return Err(p.location(Some(key)).error(
                SceneErrorKind::UnknownReference,
                format!("unknown material `{name}` (a mix blends two materials of the scene)"),
            ));
        };
        if c.name == m.name {
            return Err(p.error(Some(key), "a mix cannot contain itself"));
        }
        build(c, depth + 1)
    };
    let (a, b) = (component("a")?, component("b")?);
    let amount = match p.colour_or_pattern("amount", Rgb::splat(0.5), [0.0, 1.0])? {
        ColourParam::Constant(c) => MixAmount::Constant(c.average()),
        ColourParam::Pattern(g) => MixAmount::Pattern(Arc::new(g)),
    };
    MixMaterial::new(a, b, amount)
        .map(|f| Box::new(f) as Box<dyn BxdfFactory>)
        .map_err(|(key, message)| p.error(Some(key), message))
}
