//! BSDFs to risotto materials: `diffuse`, `dielectric`, `thindielectric`,
//! `roughdielectric`, `conductor`, `roughconductor`, `plastic`, `roughplastic`, `null`,
//! and the wrappers `twosided` and `mask`. Each distinct (BSDF, interior medium) pair of
//! the scene becomes one `[materials.NAME]`.

use std::rc::Rc;

use risotto_engine::diagnostics::SceneError;

use super::values::{Colour, Props};
use super::xml::Node;
use super::{props, Converter, MadeMaterial};
use crate::import::spectrum::SpectrumUse;
use crate::import::Entity;

/// Materials of risotto that take `two_sided`.
const TWO_SIDED_TYPES: &[&str] = &["diffuse", "plastic", "rough_conductor", "rough_plastic"];

/// Mitsuba's parameters that choose a sampling strategy only (same expected image).
const SAMPLING_ONLY: &[&str] = &["sample_visible"];

impl Converter<'_> {
    /// The name of the material for `bsdf` (Mitsuba's default, a diffuse of reflectance
    /// 0.5, when `None`) with the interior `interior` (already converted), made on first use.
    pub(super) fn material(
        &mut self,
        bsdf: Option<Rc<Node>>,
        interior: Option<(Rc<Node>, toml::Table)>,
        shape: &Node,
    ) -> Result<String, SceneError> {
        let same = |a: &Option<Rc<Node>>, b: Option<&Rc<Node>>| match (a, b) {
            (Some(a), Some(b)) => Rc::ptr_eq(a, b),
            (None, None) => true,
            _ => false,
        };
        let mut table = match &bsdf {
            Some(b) => self.bsdf_table(b)?,
            None => Entity::new(self.origin(shape))
                .with("type", "diffuse")
                .with("reflectance", 0.5),
        };
        if let Some((_, interior)) = &interior {
            table.set("interior", toml::Value::Table(interior.clone()));
        }
        for m in &self.materials {
            if same(&m.bsdf, bsdf.as_ref()) && same(&m.interior, interior.as_ref().map(|i| &i.0)) {
                if let Some(e) = self.scene.materials.iter().find(|(n, _)| *n == m.name) {
                    if e.1.table == table.table {
                        return Ok(m.name.clone());
                    }
                }
            }
        }
        // Named after the BSDF's id, else the shape's, with the medium's after a `+`.
        let fallback = shape.attr("id").unwrap_or("material");
        let bsdf_name = match &bsdf {
            Some(b) => b.attr("id").unwrap_or(fallback),
            None => "default",
        };
        let base = match &interior {
            None => bsdf_name.to_owned(),
            Some((m, _)) => format!("{bsdf_name}+{}", m.attr("id").unwrap_or("medium")),
        };
        let mut used: Vec<String> = self
            .scene
            .materials
            .iter()
            .map(|(n, _)| n.clone())
            .collect();
        let name = Converter::unique(&mut used, &base);
        self.materials.push(MadeMaterial {
            bsdf,
            interior: interior.map(|i| i.0),
            name: name.clone(),
        });
        self.scene.materials.push((name.clone(), table));
        Ok(name)
    }

    /// The material table of one BSDF element (wrappers included).
    fn bsdf_table(&mut self, node: &Rc<Node>) -> Result<Entity, SceneError> {
        let p = props(self.cx, node)?;
        let kind = p.kind()?;
        let mut e = Entity::new(self.origin(&p.node));
        let mut harmless: &[&str] = &[];
        match kind.as_str() {
            "diffuse" => {
                e.set("type", "diffuse");
                e.set(
                    "reflectance",
                    self.colour(&p, "reflectance", SpectrumUse::Reflectance)?
                        .unwrap_or(toml::Value::Float(0.5)),
                );
            }
            "dielectric" | "thindielectric" => {
                let ior = p.ior("int_ior", "bk7")? / p.ior("ext_ior", "air")?;
                e.set(
                    "type",
                    if kind == "dielectric" {
                        "dielectric"
                    } else {
                        "thin_dielectric"
                    },
                );
                e.set("ior", ior);
                // Mitsuba's thindielectric flags its transmission `Null`: its volumetric
                // path tracers do not count it as a bounce (`path` does).
                if kind == "thindielectric" && self.volumetric {
                    e.set("null_transmission", true);
                }
                let r = self.constant(&p, "specular_reflectance")?;
                let t = self.constant(&p, "specular_transmittance")?;
                match (r, t) {
                    (None, None) => {}
                    (r, t)
                        if kind == "dielectric"
                            && r.unwrap_or([1.0; 3]) == t.unwrap_or([1.0; 3]) =>
                    {
                        e.set("tint", rgb(r.or(t).unwrap_or([1.0; 3])));
                    }
                    _ => {
                        return Err(p.error(
                            Some("specular_transmittance"),
                            "different specular_reflectance and specular_transmittance are not \
                             converted (risotto's dielectric has one tint for both; the thin \
                             one has none)",
                        ))
                    }
                }
            }
            "roughdielectric" => {
                e.set("type", "rough_dielectric");
                let ext = p.ior("ext_ior", "air")?;
                e.set("ior", p.ior("int_ior", "bk7")? / ext);
                self.roughness(&p, &mut e)?;
                if let Some(t) = self.constant(&p, "specular_transmittance")? {
                    e.set("tint", rgb(t));
                }
                if self
                    .constant(&p, "specular_reflectance")?
                    .is_some_and(|r| r != [1.0; 3])
                {
                    return Err(p.error(
                        Some("specular_reflectance"),
                        "specular_reflectance other than 1 is not converted for roughdielectric",
                    ));
                }
                e.set("energy_compensation", false);
                harmless = SAMPLING_ONLY;
            }
            "conductor" | "roughconductor" => {
                let material = p.string("material")?;
                let eta = self.constant_use(&p, "eta", SpectrumUse::Unbounded)?;
                let k = self.constant_use(&p, "k", SpectrumUse::Unbounded)?;
                let spec = self.constant(&p, "specular_reflectance")?;
                let perfect =
                    material.as_deref().unwrap_or("none") == "none" && eta.is_none() && k.is_none();
                if kind == "conductor" && perfect {
                    // Mitsuba's "none": eta 0, k 1, a perfect mirror times specular_reflectance.
                    e.set("type", "conductor");
                    e.set("reflectance", rgb(spec.unwrap_or([1.0; 3])));
                } else {
                    e.set("type", "rough_conductor");
                    if kind == "conductor" {
                        // risotto's smooth conductor has no complex index: the rough one at
                        // its smallest roughness (a mirror in all but name, as in Mitsuba).
                        e.set("alpha", 1e-4);
                    } else {
                        self.roughness(&p, &mut e)?;
                    }
                    if let Some(m) = material {
                        e.set("material", m);
                    }
                    match (eta, k) {
                        (Some(eta), Some(k)) => {
                            e.set("eta", rgb(eta));
                            e.set("k", rgb(k));
                        }
                        (None, None) => {}
                        _ => {
                            return Err(p.error(
                                Some("eta"),
                                "give both eta and k, or neither (then `material`)",
                            ))
                        }
                    }
                    if let Some(s) = spec {
                        e.set("specular_reflectance", rgb(s));
                    }
                    e.set("energy_compensation", false);
                }
                harmless = SAMPLING_ONLY;
            }
            "plastic" | "roughplastic" => {
                e.set(
                    "type",
                    if kind == "plastic" {
                        "plastic"
                    } else {
                        "rough_plastic"
                    },
                );
                if let Some(d) = self.colour(&p, "diffuse_reflectance", SpectrumUse::Reflectance)? {
                    e.set("diffuse_reflectance", d);
                }
                if let Some(s) = self.constant(&p, "specular_reflectance")? {
                    e.set("specular_reflectance", rgb(s));
                }
                e.set("int_ior", p.ior("int_ior", "polypropylene")?);
                e.set("ext_ior", p.ior("ext_ior", "air")?);
                if let Some(n) = p.boolean("nonlinear")? {
                    e.set("nonlinear", n);
                }
                if kind == "roughplastic" {
                    if p.has("alpha_u") || p.has("alpha_v") {
                        return Err(
                            p.error(Some("alpha_u"), "roughplastic is isotropic: use alpha")
                        );
                    }
                    // rough_plastic has no energy compensation (its diffuse lobe is its own
                    // account of the light between the layers), so nothing to switch off.
                    self.roughness(&p, &mut e)?;
                }
                harmless = SAMPLING_ONLY;
            }
            "null" => {
                e.set("type", "interface");
            }
            "twosided" => {
                let inner = p.unnamed("bsdf")?;
                let inner =
                    match &inner[..] {
                        [one] => one.clone(),
                        [a, b] if Rc::ptr_eq(a, b) => a.clone(),
                        _ => return Err(p.error(
                            None,
                            "twosided with two different BSDFs (one per side) is not converted; \
                             give one nested BSDF",
                        )),
                    };
                p.finish(&[])?;
                let mut e = self.bsdf_table(&inner)?;
                let t = e
                    .table
                    .get("type")
                    .and_then(|t| t.as_str())
                    .unwrap_or("")
                    .to_owned();
                if t == "conductor" {
                    // risotto's smooth conductor reflects on both sides already.
                } else if TWO_SIDED_TYPES.contains(&t.as_str()) {
                    e.set("two_sided", true);
                } else {
                    return Err(p.error(
                        None,
                        format!(
                            "twosided around a BSDF that becomes risotto's `{t}` is not \
                             supported (only {})",
                            TWO_SIDED_TYPES.join(", ")
                        ),
                    ));
                }
                e.origin = self.origin(&p.node);
                return Ok(e);
            }
            "blendbsdf" => {
                // Mitsuba's blend, (1 - weight) first + weight second: risotto's `mix` of
                // the two nested BSDFs, each written as a material of its own.
                let weight = self.float_or_texture(&p, "weight")?.ok_or_else(|| {
                    p.error(
                        Some("weight"),
                        "a blendbsdf needs its weight (a float or a texture)",
                    )
                })?;
                let inner = p.unnamed("bsdf")?;
                let [a, b] = &inner[..] else {
                    return Err(p.error(None, "a blendbsdf blends two nested BSDFs"));
                };
                p.finish(&[])?;
                let node = p.node.clone();
                let a = self.material(Some(a.clone()), None, &node)?;
                let b = self.material(Some(b.clone()), None, &node)?;
                let mut e = Entity::new(self.origin(&node));
                e.set("type", "mix");
                e.set("a", a);
                e.set("b", b);
                e.set("amount", weight);
                return Ok(e);
            }
            "mask" => {
                let opacity = self
                    .float_or_texture(&p, "opacity")?
                    .unwrap_or(toml::Value::Float(0.5));
                let inner = p.one_unnamed("bsdf")?.ok_or_else(|| {
                    p.error(None, "a mask needs the BSDF it masks (a nested <bsdf>)")
                })?;
                p.finish(&[])?;
                let mut e = self.bsdf_table(&inner)?;
                e.set("opacity", opacity);
                e.origin = self.origin(&p.node);
                return Ok(e);
            }
            other => {
                return Err(p.error(
                    Some("type"),
                    format!(
                        "bsdf type \"{other}\" is not supported (diffuse, dielectric, \
                         thindielectric, roughdielectric, conductor, roughconductor, plastic, \
                         roughplastic, null, twosided, mask, blendbsdf)"
                    ),
                ))
            }
        }
        p.finish(harmless)?;
        Ok(e)
    }

    /// `alpha` or `alpha_u` / `alpha_v` (default 0.1) and `distribution` (Mitsuba's default
    /// is Beckmann; risotto's GGX, so it is written unless GGX); `masking = "separable"`
    /// always (Mitsuba's microfacet lobes use `G1(wo) G1(wi)`, risotto's default is the
    /// height-correlated form).
    fn roughness(&self, p: &Props<'_>, e: &mut Entity) -> Result<(), SceneError> {
        e.set("masking", "separable");
        let d = p
            .string("distribution")?
            .unwrap_or_else(|| "beckmann".into());
        match d.as_str() {
            "ggx" => {}
            "beckmann" => e.set("distribution", "beckmann"),
            other => {
                return Err(p.error(
                    Some("distribution"),
                    format!("distribution \"{other}\" is not ggx or beckmann"),
                ))
            }
        }
        let (a, u, v) = (
            self.alpha(p, "alpha")?,
            self.alpha(p, "alpha_u")?,
            self.alpha(p, "alpha_v")?,
        );
        match (a, u, v) {
            (a, None, None) => e.set("alpha", a.unwrap_or(toml::Value::Float(0.1))),
            (None, Some(u), Some(v)) => {
                e.set("alpha_u", u);
                e.set("alpha_v", v);
            }
            _ => return Err(p.error(Some("alpha"), "give alpha, or both alpha_u and alpha_v")),
        }
        Ok(())
    }

    /// A roughness as TOML: a number, or the pattern table of a `<texture>` (Mitsuba's
    /// float textures: a grey `bitmap`, a `checkerboard`), which risotto's loader checks
    /// is grey and within `(0, 1]`.
    fn alpha(&self, p: &Props<'_>, name: &str) -> Result<Option<toml::Value>, SceneError> {
        if let Ok(Some(Colour::Texture(t))) = p.colour(name, SpectrumUse::Reflectance) {
            return Ok(Some(self.float_texture(&t)?));
        }
        Ok(p.float(name)?.map(toml::Value::Float))
    }

    /// A float parameter that may be a texture (a mask's opacity, a blend weight) as TOML:
    /// a number when grey, else an RGB array or the pattern of a texture read as a float.
    fn float_or_texture(
        &self,
        p: &Props<'_>,
        name: &str,
    ) -> Result<Option<toml::Value>, SceneError> {
        Ok(match p.colour(name, SpectrumUse::Reflectance)? {
            None => None,
            Some(Colour::Rgb(c)) if c[0] == c[1] && c[1] == c[2] => Some(toml::Value::Float(c[0])),
            Some(Colour::Rgb(c)) => Some(rgb(c)),
            Some(Colour::Texture(t)) => Some(self.float_texture(&t)?),
        })
    }

    /// A colour parameter as TOML: an RGB array or a pattern table.
    fn colour(
        &self,
        p: &Props<'_>,
        name: &str,
        use_: SpectrumUse,
    ) -> Result<Option<toml::Value>, SceneError> {
        Ok(match p.colour(name, use_)? {
            None => None,
            Some(Colour::Rgb(c)) => Some(rgb(c)),
            Some(Colour::Texture(t)) => Some(self.texture(&t)?),
        })
    }

    /// A constant reflectance-like colour (a texture is an error).
    fn constant(&self, p: &Props<'_>, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        self.constant_use(p, name, SpectrumUse::Reflectance)
    }

    /// A constant colour for `use_` (a texture is an error).
    pub(super) fn constant_use(
        &self,
        p: &Props<'_>,
        name: &str,
        use_: SpectrumUse,
    ) -> Result<Option<[f64; 3]>, SceneError> {
        match p.colour(name, use_)? {
            None => Ok(None),
            Some(Colour::Rgb(c)) => Ok(Some(c)),
            Some(Colour::Texture(_)) => Err(p.error(
                Some(name),
                format!("`{name}` cannot be a texture here (a constant colour only)"),
            )),
        }
    }
}

/// An RGB colour as a TOML array.
pub(super) fn rgb(c: [f64; 3]) -> toml::Value {
    toml::Value::Array(c.iter().map(|x| toml::Value::Float(*x)).collect())
}
