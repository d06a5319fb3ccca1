//! pbrt-v4's microfacet roughness (`roughness`, `uroughness`, `vroughness`,
//! `remaproughness`) as risotto's `alpha` or `alpha_u` / `alpha_v`: numbers, or float
//! textures as roughness patterns.

use risotto_engine::diagnostics::SceneError;

use super::convert::Converter;
use super::params::Params;
use crate::import::Entity;

/// The roughness keys, in pbrt's order.
const KEYS: [&str; 3] = ["roughness", "uroughness", "vroughness"];

/// The smallest alpha risotto is given: smaller ones act as it (a mirror in all but name),
/// as pbrt's smooth conductor.
const MIN_ALPHA: f64 = 1e-4;

impl Converter<'_> {
    /// True when some roughness is a float texture.
    fn roughness_is_textured(p: &Params) -> bool {
        p.list
            .iter()
            .any(|q| q.ty == "texture" && KEYS.contains(&q.name.as_str()))
    }

    /// `roughness` or `uroughness` / `vroughness` as numbers, remapped to GGX alphas as
    /// pbrt-v4 does when `remaproughness` is true: `alpha = sqrt(roughness)`
    /// (`TrowbridgeReitzDistribution::RoughnessToAlpha`).
    fn roughness_numbers(&self, p: &Params) -> Result<(f64, f64), SceneError> {
        let lx = &self.lx;
        let nonneg = |k: &str, d: f64| p.float_where(lx, k, d, ">= 0", |r| r >= 0.0);
        let r = nonneg("roughness", 0.0)?;
        let u = nonneg("uroughness", r)?;
        let v = nonneg("vroughness", r)?;
        let remap = p.bool(lx, "remaproughness", true)?;
        let (au, av) = if remap { (u.sqrt(), v.sqrt()) } else { (u, v) };
        for (a, k) in [(au, "uroughness"), (av, "vroughness")] {
            if a > 1.0 {
                let q = p
                    .list
                    .iter()
                    .find(|q| q.name.ends_with(k) || q.name.ends_with("roughness"))
                    .expect("given");
                return Err(p.error(
                    lx,
                    q,
                    format!("gives the GGX alpha {a}, above risotto's limit of 1"),
                ));
            }
        }
        Ok((au, av))
    }

    /// Whether pbrt-v4 takes its smooth branch (every alpha below 1e-3,
    /// `TrowbridgeReitzDistribution::EffectivelySmooth`); never with a roughness texture.
    pub(super) fn effectively_smooth(&self, p: &Params) -> Result<bool, SceneError> {
        if Self::roughness_is_textured(p) {
            return Ok(false);
        }
        let (au, av) = self.roughness_numbers(p)?;
        Ok(au.max(av) < 1e-3)
    }

    /// Sets `alpha` (isotropic) or `alpha_u` / `alpha_v` on `t`. Numbers as
    /// [`Self::roughness_numbers`], at least [`MIN_ALPHA`]. A float texture becomes the
    /// roughness pattern: under `remaproughness` (pbrt's default) raised to the power 1/2
    /// (a `power` pattern), then clamped to `[MIN_ALPHA, 1]` by a `remap` (pbrt allows
    /// alphas above 1 and 0, risotto's microfacets not; a texture's values cannot be
    /// checked one by one as a number is).
    pub(super) fn set_roughness(&self, p: &Params, t: &mut Entity) -> Result<(), SceneError> {
        if !Self::roughness_is_textured(p) {
            let (u, v) = self.roughness_numbers(p)?;
            let (u, v) = (u.max(MIN_ALPHA), v.max(MIN_ALPHA));
            if u == v {
                t.set("alpha", u);
            } else {
                t.set("alpha_u", u);
                t.set("alpha_v", v);
            }
            return Ok(());
        }
        let remap = p.bool(&self.lx, "remaproughness", true)?;
        let mut values = Vec::with_capacity(3);
        for k in KEYS {
            let value = match self.colour_value(p, k, true)? {
                None => None,
                Some(toml::Value::Array(c)) => {
                    let r = c.first().and_then(|v| v.as_float()).unwrap_or(0.0);
                    if r.is_nan() || r < 0.0 {
                        let q = p.list.iter().find(|q| q.name == k).expect("given");
                        return Err(p.error(&self.lx, q, format!("must be >= 0, got {r}")));
                    }
                    let a = if remap { r.sqrt() } else { r };
                    Some(toml::Value::Float(a.clamp(MIN_ALPHA, 1.0)))
                }
                Some(texture) => Some(alpha_pattern(texture, remap)),
            };
            values.push(value);
        }
        let r = values[0].clone().unwrap_or(toml::Value::Float(MIN_ALPHA));
        let u = values[1].clone().unwrap_or_else(|| r.clone());
        let v = values[2].clone().unwrap_or_else(|| r.clone());
        if u == v {
            t.set("alpha", u);
        } else {
            t.set("alpha_u", u);
            t.set("alpha_v", v);
        }
        Ok(())
    }
}

/// The roughness texture `texture` (a pattern table) as an alpha pattern: `sqrt` when
/// `remap`, clamped to `[MIN_ALPHA, 1]`.
fn alpha_pattern(texture: toml::Value, remap: bool) -> toml::Value {
    let table = |pairs: Vec<(&str, toml::Value)>| {
        toml::Value::Table(pairs.into_iter().map(|(k, v)| (k.to_owned(), v)).collect())
    };
    let alpha = if remap {
        table(vec![
            ("pattern", "power".into()),
            ("a", texture),
            ("exponent", 0.5.into()),
        ])
    } else {
        texture
    };
    let range = || toml::Value::Array(vec![MIN_ALPHA.into(), 1.0.into()]);
    table(vec![
        ("pattern", "remap".into()),
        ("a", alpha),
        ("from", range()),
        ("to", range()),
    ])
}
