//! pbrt-v4 materials, textures and lights, as risotto materials, patterns and lights
//! (media: `media.rs`).

use glam::DVec3;
use risotto_engine::diagnostics::SceneError;

use super::convert::{Converter, MaterialDef, MaterialRef};
use super::lexer::At;
use super::params::{Colour, Params};
use crate::import::{path_for_toml, Entity};

/// pbrt-v4's named metal spectra (`metal-Au-eta` / `metal-Au-k`) that risotto's conductor
/// presets (Mitsuba 3's RGB tables) also hold.
const METALS: &[&str] = &["Ag", "Al", "Au", "Cu", "MgO", "TiO2"];

impl Converter<'_> {
    /// A colour parameter as a TOML value (a colour or, with `textures`, a pattern).
    pub(super) fn colour_value(
        &self,
        p: &Params,
        name: &str,
        textures: bool,
    ) -> Result<Option<toml::Value>, SceneError> {
        let c = p.colour(&self.lx, name, textures, &|q| self.spectrum_colour(p, q))?;
        let q = || p.list.iter().find(|q| q.name == name).expect("given");
        Ok(match c {
            None => None,
            Some(Colour::Rgb(c)) => Some(c.to_vec().into()),
            Some(Colour::Texture(t)) => match self.textures.get(&t) {
                Some(v) => Some(v.clone()),
                None => return Err(p.error(&self.lx, q(), format!("no texture named \"{t}\""))),
            },
            Some(Colour::Named(n)) => {
                return Err(p.error(
                    &self.lx,
                    q(),
                    format!("the named spectrum \"{n}\" is not supported here"),
                ))
            }
        })
    }

    /// A material definition (`Material` or `MakeNamedMaterial`).
    pub(super) fn material(
        &mut self,
        ty: &str,
        p: &Params,
        at: &At,
        name: &str,
    ) -> Result<MaterialDef, SceneError> {
        let mut t = Entity::new(None);
        let lx = &self.lx;
        for k in ["displacement", "normalmap"] {
            if let Some(q) = p.ignore(k) {
                return Err(p.error(lx, q, "is not supported"));
            }
        }
        let mut transmits = false;
        match ty {
            "diffuse" => {
                t.set("type", "diffuse");
                t.set(
                    "reflectance",
                    self.colour_value(p, "reflectance", true)?
                        .unwrap_or(0.5.into()),
                );
                // pbrt's diffuse reflects on both sides.
                t.set("two_sided", true);
            }
            "conductor" => {
                t.set("type", "rough_conductor");
                self.set_roughness(p, &mut t)?;
                let eta = p.colour(lx, "eta", false, &|q| self.spectrum_colour(p, q))?;
                let k = p.colour(lx, "k", false, &|q| self.spectrum_colour(p, q))?;
                let refl = self.colour_value(p, "reflectance", false)?;
                match (eta, k, refl) {
                    (None, None, None) => t.set("material", "Cu"),
                    (None, None, Some(r)) => {
                        // pbrt-v4 `ConductorMaterial` with a reflectance: eta = 1 and
                        // k = 2 sqrt(r) / sqrt(1 - r), whose normal-incidence Fresnel
                        // reflectance is r.
                        let r: Vec<f64> = r
                            .as_array()
                            .expect("rgb")
                            .iter()
                            .map(|x| x.as_float().unwrap_or(0.0).clamp(0.0, 0.9999))
                            .collect();
                        t.set("eta", vec![1.0; 3]);
                        t.set(
                            "k",
                            r.iter()
                                .map(|r| 2.0 * r.sqrt() / (1.0 - r).sqrt())
                                .collect::<Vec<_>>(),
                        );
                    }
                    (Some(Colour::Named(e)), Some(Colour::Named(k)), None) => {
                        let metal = |s: &str, suffix: &str| {
                            s.strip_prefix("metal-")
                                .and_then(|s| s.strip_suffix(suffix))
                                .map(str::to_owned)
                        };
                        match (metal(&e, "-eta"), metal(&k, "-k")) {
                            (Some(a), Some(b)) if a == b && METALS.contains(&a.as_str()) => t.set("material", a.as_str()),
                            _ => return Err(self.error(at, &p.entity, format!("the spectra \"{e}\" / \"{k}\" are not a metal risotto knows ({})", METALS.join(", ")))),
                        }
                    }
                    (Some(Colour::Rgb(e)), Some(Colour::Rgb(k)), None) => {
                        t.set("eta", e.to_vec());
                        t.set("k", k.to_vec());
                    }
                    _ => {
                        return Err(self.error(
                            at,
                            &p.entity,
                            "give eta and k (both rgb or both named metal spectra), or reflectance",
                        ))
                    }
                }
                t.set("two_sided", true);
                t.set("energy_compensation", false);
            }
            "dielectric" | "thindielectric" => {
                let eta = match p.colour(lx, "eta", false, &|q| self.spectrum_colour(p, q))? {
                    None => 1.5,
                    Some(Colour::Rgb([a, b, c])) if a == b && b == c => a,
                    Some(_) => {
                        let q = p.list.iter().find(|q| q.name == "eta").expect("given");
                        return Err(p.error(lx, q, "a wavelength-dependent index (dispersion) is not supported; give one number"));
                    }
                };
                if eta.is_nan() || eta <= 0.0 {
                    let q = p.list.iter().find(|q| q.name == "eta").expect("given");
                    return Err(p.error(lx, q, format!("must be > 0, got {eta}")));
                }
                transmits = true;
                if ty == "thindielectric" {
                    t.set("type", "thin_dielectric");
                } else {
                    // pbrt-v4 treats alpha below 1e-3 as perfectly smooth
                    // (`TrowbridgeReitzDistribution::EffectivelySmooth`); a roughness
                    // texture keeps the rough one.
                    if self.effectively_smooth(p)? {
                        t.set("type", "dielectric");
                    } else {
                        t.set("type", "rough_dielectric");
                        self.set_roughness(p, &mut t)?;
                        t.set("energy_compensation", false);
                    }
                }
                t.set("ior", eta);
            }
            "interface" => {
                t.set("type", "interface");
                transmits = true;
            }
            "coateddiffuse" | "coatedconductor" => {
                // The branch `coated` reads these names (pbrt's, with underscores).
                t.set(
                    "type",
                    if ty == "coateddiffuse" {
                        "coated_diffuse"
                    } else {
                        "coated_conductor"
                    },
                );
                let floats: &[(&str, &str)] = if ty == "coateddiffuse" {
                    &[
                        ("roughness", "roughness"),
                        ("uroughness", "uroughness"),
                        ("vroughness", "vroughness"),
                        ("thickness", "thickness"),
                        ("g", "g"),
                    ]
                } else {
                    &[
                        ("interface.roughness", "interface_roughness"),
                        ("interface.uroughness", "interface_uroughness"),
                        ("interface.vroughness", "interface_vroughness"),
                        ("conductor.roughness", "conductor_roughness"),
                        ("conductor.uroughness", "conductor_uroughness"),
                        ("conductor.vroughness", "conductor_vroughness"),
                        ("thickness", "thickness"),
                        ("g", "g"),
                        ("interface.eta", "interface_eta"),
                    ]
                };
                for (from, to) in floats {
                    if p.has(from) {
                        t.set(to, p.float(lx, from, 0.0)?);
                    }
                }
                let colours: &[(&str, &str)] = if ty == "coateddiffuse" {
                    &[("reflectance", "reflectance"), ("albedo", "albedo")]
                } else {
                    &[
                        ("reflectance", "reflectance"),
                        ("albedo", "albedo"),
                        ("conductor.eta", "conductor_eta"),
                        ("conductor.k", "conductor_k"),
                    ]
                };
                for (from, to) in colours {
                    if let Some(v) =
                        self.colour_value(p, from, *from == "reflectance" && ty == "coateddiffuse")?
                    {
                        t.set(to, v);
                    }
                }
                if ty == "coateddiffuse" && p.has("eta") {
                    t.set("eta", p.float(lx, "eta", 1.5)?);
                }
                for (from, to) in [("maxdepth", "max_depth"), ("nsamples", "n_samples")] {
                    if p.has(from) {
                        t.set(to, p.int(lx, from, 10)?);
                    }
                }
                if p.has("remaproughness") {
                    t.set("remap_roughness", p.bool(lx, "remaproughness", true)?);
                }
            }
            "mix" => {
                // pbrt-v4 picks `materials[1]` with probability `amount` per hit (by a hash
                // of the hit); risotto's `mix` blends the two: the same expectation.
                let names = match p.ignore("materials").map(|q| (&q.values, q)) {
                    Some((super::params::Values::Strs(v), _)) if v.len() == 2 => v.clone(),
                    Some((_, q)) => return Err(p.error(lx, q, "expected two material names")),
                    None => {
                        return Err(self.error(
                            at,
                            &p.entity,
                            "a mix needs \"string materials\" [ \"a\" \"b\" ]",
                        ))
                    }
                };
                let amount = self.colour_value(p, "amount", true)?;
                let mut parts = Vec::new();
                for n in &names {
                    let Some(def) = self.named_materials.get(n).cloned() else {
                        let q = p.ignore("materials").expect("read above");
                        return Err(p.error(&self.lx, q, format!("no material named \"{n}\" (define it with MakeNamedMaterial first)")));
                    };
                    parts.push(self.emit_component(&def));
                }
                t.set("type", "mix");
                t.set("a", parts[0].as_str());
                t.set("b", parts[1].as_str());
                if let Some(amount) = amount {
                    t.set("amount", amount);
                }
            }
            _ => {
                return Err(self.error(at, &p.entity, format!("material \"{ty}\" is not supported (diffuse, conductor, dielectric, thindielectric, interface, coateddiffuse, coatedconductor)")));
            }
        }
        p.ignore("type");
        Ok(MaterialDef {
            table: t.table,
            name: name.to_owned(),
            origin: self.origin(at),
            transmits,
        })
    }

    /// The TOML name of named material `def` as a component of a mix (written on first use,
    /// without interior or opacity; shared with shapes that use it plainly).
    fn emit_component(&mut self, def: &MaterialDef) -> String {
        let key = (
            format!(
                "{}@{}:{}",
                def.name,
                def.origin.file.display(),
                def.origin.line
            ),
            String::new(),
        );
        if let Some(name) = self.emitted.get(&key) {
            return name.clone();
        }
        let name = self.unique(&def.name);
        self.scene.materials.push((
            name.clone(),
            Entity {
                table: def.table.clone(),
                origin: Some(def.origin.clone()),
            },
        ));
        self.emitted.insert(key, name.clone());
        name
    }

    /// The TOML name of the material a shape gets here (written on first use, with the
    /// shape's inside medium as its interior).
    pub(super) fn material_for_shape(
        &mut self,
        at: &At,
        entity: &str,
    ) -> Result<String, SceneError> {
        let def = match self.gs.material.clone() {
            MaterialRef::Default => MaterialDef {
                table: Entity::new(None)
                    .with("type", "diffuse")
                    .with("reflectance", 0.5)
                    .with("two_sided", true)
                    .table,
                name: "default".into(),
                origin: self.origin(at),
                transmits: false,
            },
            MaterialRef::Anonymous(i) => self.anonymous[i].clone(),
            MaterialRef::Named(n, nat) => match self.named_materials.get(&n) {
                Some(d) => d.clone(),
                None => {
                    return Err(self.error(
                        &nat,
                        "NamedMaterial",
                        format!("no material named \"{n}\" (define it with MakeNamedMaterial)"),
                    ))
                }
            },
        };
        let inside = self.gs.inside.clone();
        let opacity = self.shape_opacity.take();
        let key = (
            format!(
                "{}@{}:{}{}",
                def.name,
                def.origin.file.display(),
                def.origin.line,
                opacity
                    .as_ref()
                    .map_or(String::new(), |o| format!(" opacity {o}"))
            ),
            inside.clone(),
        );
        if let Some(name) = self.emitted.get(&key) {
            return Ok(name.clone());
        }
        let mut table = def.table.clone();
        if !inside.is_empty() && inside != self.gs.outside {
            if !def.transmits && table.get("type").and_then(|t| t.as_str()) != Some("interface") {
                return Err(self.error(at, entity, format!("the shape holds medium \"{inside}\" but its material is opaque; use an \"interface\" or dielectric material")));
            }
            let (medium, _) = self.media[&inside].clone();
            table.insert("interior".into(), toml::Value::Table(medium));
            self.media_used.push(inside.clone());
        }
        if let Some(o) = opacity {
            table.insert("opacity".into(), o);
        }
        let base = if inside.is_empty() {
            def.name.clone()
        } else {
            format!("{} in {inside}", def.name)
        };
        let base = if table.contains_key("opacity") {
            format!("{base} cut out")
        } else {
            base
        };
        let name = self.unique(&base);
        self.scene.materials.push((
            name.clone(),
            Entity {
                table,
                origin: Some(def.origin),
            },
        ));
        self.emitted.insert(key, name.clone());
        Ok(name)
    }

    /// `Texture "name" "spectrum"|"float" "class"` as a pattern value.
    pub(super) fn texture(
        &mut self,
        class: &str,
        ty: &str,
        p: &Params,
        at: &At,
        entity: &str,
    ) -> Result<toml::Value, SceneError> {
        if class != "spectrum" && class != "float" {
            return Err(self.error(
                at,
                entity,
                format!("texture type \"{class}\" must be \"spectrum\" or \"float\""),
            ));
        }
        let lx = &self.lx;
        let mut t = toml::Table::new();
        let mapping = p
            .string(lx, "mapping")?
            .map(|(m, _)| m.to_owned())
            .unwrap_or("uv".into());
        if mapping != "uv" {
            return Err(self.error(
                at,
                entity,
                format!("texture mapping \"{mapping}\" is not supported (only \"uv\")"),
            ));
        }
        for (k, d) in [
            ("uscale", 1.0),
            ("vscale", 1.0),
            ("udelta", 0.0),
            ("vdelta", 0.0),
        ] {
            if !matches!(ty, "checkerboard" | "imagemap")
                || (ty == "checkerboard" && k.ends_with("delta"))
            {
                if let Some(q) = p.ignore(k) {
                    if p.float(lx, k, d)? != d {
                        return Err(p.error(
                            lx,
                            q,
                            "texture coordinate scales and offsets are not supported",
                        ));
                    }
                }
            }
        }
        let float_or_tex = |name: &str, d: f64| -> Result<toml::Value, SceneError> {
            Ok(self
                .colour_value(p, name, true)?
                .unwrap_or(vec![d; 3].into()))
        };
        match ty {
            "imagemap" => {
                let Some((file, _)) = p.string(lx, "filename")? else {
                    return Err(self.error(at, entity, "needs \"string filename\""));
                };
                let path = self.lx.resolve(at, file);
                t.insert("pattern".into(), "image".into());
                t.insert("path".into(), path_for_toml(&path, self.options.toml_dir).into());
                // pbrt-v4 flips t (`st[1] = 1 - st[1]`), so v = 0 is the image's bottom
                // row, as in risotto; it repeats, as risotto's image does.
                if let Some((w, q)) = p.string(lx, "wrap")? {
                    if !matches!(w, "repeat" | "clamp") {
                        return Err(p.error(lx, q, "only \"repeat\" and \"clamp\" wrapping are supported"));
                    }
                    if w == "clamp" {
                        t.insert("wrap".into(), "clamp".into());
                    }
                }
                if let Some((f, q)) = p.string(lx, "filter")? {
                    match f {
                        "bilinear" => {}
                        "point" => {
                            t.insert("filter".into(), "nearest".into());
                        }
                        _ => {
                            return Err(p.error(lx, q, "only \"bilinear\" and \"point\" filtering are supported (no MIP maps)"))
                        }
                    }
                }
                // pbrt-v4's UVMapping: (su u + du, sv v + dv), before the lookup's t flip.
                let (su, sv) = (p.float(lx, "uscale", 1.0)?, p.float(lx, "vscale", 1.0)?);
                let (du, dv) = (p.float(lx, "udelta", 0.0)?, p.float(lx, "vdelta", 0.0)?);
                if (su, sv, du, dv) != (1.0, 1.0, 0.0, 0.0) {
                    let row = |r: [f64; 3]| toml::Value::Array(r.map(toml::Value::Float).to_vec());
                    let mut m = toml::Table::new();
                    m.insert("u".into(), row([su, 0.0, du]));
                    m.insert("v".into(), row([0.0, sv, dv]));
                    t.insert("uv_transform".into(), toml::Value::Table(m));
                }
                if let Some((enc, q)) = p.string(lx, "encoding")? {
                    let png = file.to_ascii_lowercase().ends_with(".png");
                    if (png && enc != "sRGB") || (!png && enc != "linear") {
                        return Err(p.error(lx, q, "risotto decodes PNG from sRGB and EXR as linear; other encodings are not supported"));
                    }
                }
                if p.bool(lx, "invert", false)? {
                    let q = p.list.iter().find(|q| q.name == "invert").expect("given");
                    return Err(p.error(lx, q, "inverted image textures are not supported"));
                }
                let scale = p.float(lx, "scale", 1.0)?;
                if scale != 1.0 {
                    let mut s = toml::Table::new();
                    s.insert("pattern".into(), "scale".into());
                    s.insert("a".into(), toml::Value::Table(t));
                    s.insert("factor".into(), vec![scale; 3].into());
                    return Ok(toml::Value::Table(s));
                }
            }
            "constant" => {
                t.insert("pattern".into(), "constant".into());
                t.insert("value".into(), float_or_tex("value", 1.0)?);
            }
            "scale" => {
                let a = float_or_tex("tex", 1.0)?;
                let s = float_or_tex("scale", 1.0)?;
                if s.is_array() {
                    t.insert("pattern".into(), "scale".into());
                    t.insert("a".into(), a);
                    t.insert("factor".into(), s);
                } else {
                    t.insert("pattern".into(), "multiply".into());
                    t.insert("a".into(), a);
                    t.insert("b".into(), s);
                }
            }
            "mix" => {
                t.insert("pattern".into(), "mix".into());
                t.insert("a".into(), float_or_tex("tex1", 0.0)?);
                t.insert("b".into(), float_or_tex("tex2", 1.0)?);
                t.insert("t".into(), float_or_tex("amount", 0.5)?);
            }
            "checkerboard" => {
                if p.int(lx, "dimension", 2)? != 2 {
                    return Err(self.error(at, entity, "only 2D checkerboards are supported"));
                }
                let (su, sv) = (p.float(lx, "uscale", 1.0)?, p.float(lx, "vscale", 1.0)?);
                if su != sv || su.is_nan() || su <= 0.0 {
                    return Err(self.error(at, entity, "the checkerboard's uscale and vscale must be equal and > 0"));
                }
                // pbrt: tex1 where floor(s) + floor(t) is even; risotto's `a` likewise.
                let a = float_or_tex("tex1", 1.0)?;
                let b = float_or_tex("tex2", 0.0)?;
                if !a.is_array() || !b.is_array() {
                    return Err(self.error(at, entity, "the checkerboard's tex1 and tex2 must be values, not textures"));
                }
                t.insert("pattern".into(), "checker".into());
                t.insert("space".into(), "uv".into());
                t.insert("scale".into(), su.into());
                t.insert("a".into(), a);
                t.insert("b".into(), b);
            }
            _ => return Err(self.error(at, entity, format!("texture \"{ty}\" is not supported (imagemap, constant, scale, mix, checkerboard)"))),
        }
        Ok(toml::Value::Table(t))
    }

    /// `LightSource`.
    pub(super) fn light(&mut self, ty: &str, p: &Params, at: &At) -> Result<(), SceneError> {
        let lx = &self.lx;
        let m = self.world_root * self.gs.ctm;
        let scale = p.float(lx, "scale", 1.0)?;
        if let Some(q) = p.ignore("power").or_else(|| p.ignore("illuminance")) {
            return Err(p.error(
                lx,
                q,
                "is not supported (give the radiance or intensity and scale)",
            ));
        }
        let rgb = |name: &str| -> Result<Vec<f64>, SceneError> {
            match p.colour(lx, name, false, &|q| self.spectrum_colour(p, q))? {
                None => Ok(vec![scale; 3]),
                Some(Colour::Rgb(c)) => Ok(c.iter().map(|c| c * scale).collect()),
                Some(_) => {
                    let q = p.list.iter().find(|q| q.name == name).expect("given");
                    Err(p.error(lx, q, "give an rgb value"))
                }
            }
        };
        let v3 = |name: &str, d: DVec3| -> Result<DVec3, SceneError> {
            Ok(p.vec3(lx, name)?.map_or(d, DVec3::from))
        };
        let mut e = Entity::new(Some(self.origin(at)));
        match ty {
            "point" => {
                let pos = m.transform_point3(v3("from", DVec3::ZERO)?);
                e.set("type", "point");
                e.set("position", pos.to_array().to_vec());
                e.set("intensity", rgb("I")?);
            }
            "spot" => {
                let from = v3("from", DVec3::ZERO)?;
                let to = v3("to", DVec3::Z)?;
                let dir = m.transform_vector3(to - from);
                let cone = p.float_where(lx, "coneangle", 30.0, "in (0, 90]", |a| {
                    a > 0.0 && a <= 90.0
                })?;
                let delta = p.float_where(lx, "conedelta", 5.0, "in [0, coneangle)", |d| {
                    d >= 0.0 && d < cone
                })?;
                e.set("type", "spot");
                e.set("position", m.transform_point3(from).to_array().to_vec());
                e.set("direction", dir.to_array().to_vec());
                e.set("intensity", rgb("I")?);
                e.set("cutoff_angle", cone);
                e.set("beam_width", cone - delta);
                if delta > 0.0 {
                    self.warnings.push(format!(
                        "{}:{}: the spot light's falloff is linear in the angle over the last {delta} degrees (pbrt's is a smoothstep in the cosine): the edge of the beam differs slightly",
                        lx.path(at).display(),
                        lx.line(at)
                    ));
                }
            }
            "distant" => {
                let from = v3("from", DVec3::ZERO)?;
                let to = v3("to", DVec3::Z)?;
                // The light travels from `from` towards `to`.
                let dir = m.transform_vector3(to - from);
                if dir.length_squared() == 0.0 {
                    return Err(self.error(at, &p.entity, "from and to coincide"));
                }
                e.set("type", "distant");
                e.set("direction", dir.to_array().to_vec());
                e.set("irradiance", rgb("L")?);
            }
            "infinite" => {
                if let Some(q) = p.ignore("portal") {
                    return Err(p.error(lx, q, "portals are not supported"));
                }
                e.set("type", "environment");
                match p.string(lx, "filename")? {
                    // pbrt-v4's `ImageInfiniteLight`: an equal-area octahedral square in the
                    // light's frame (`renderFromLight`, here the CTM), looked up nearest-texel,
                    // its RGB times `scale` the radiance (no photometric normalisation for
                    // images, unlike `L`).
                    Some((file, q)) => {
                        if p.has("L") {
                            return Err(p.error(lx, q, "give either L or a filename, not both"));
                        }
                        let path = self.lx.resolve(at, file);
                        e.set("map", path_for_toml(&path, self.options.toml_dir));
                        e.set("projection", "equal_area");
                        e.set("radiance", scale);
                        e.set("transform", self.transform_value(&m, at, &p.entity)?);
                    }
                    None => e.set("radiance", rgb("L")?),
                }
            }
            _ => {
                return Err(self.error(
                    at,
                    &p.entity,
                    format!("light \"{ty}\" is not supported (point, spot, distant, infinite)"),
                ))
            }
        }
        if self.object.is_some() {
            return Err(self.error(
                at,
                &p.entity,
                "lights inside an object (ObjectBegin) are not supported",
            ));
        }
        self.scene.lights.push(e);
        Ok(())
    }
}
