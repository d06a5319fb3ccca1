//! Techniques: every estimator choice that trades time for error is a named technique with
//! its values, its default and the scenes it applies to (DESIGN.md, "Accuracy and its cost").
//! `risotto techniques SCENE` lists the ones that apply, `risotto render --technique
//! NAME=VALUE` sets one, and `risotto converge` sweeps them.
//!
//! Two kinds, listed and swept alike:
//! - the **global integrator's own** ([`CORE`]: `lighting`, `sampler`), which apply by the
//!   scene's [`Features`];
//! - **plug-in techniques**, declared as data by a material's factory
//!   ([`BxdfFactory::techniques`](crate::plugin::BxdfFactory::techniques)): a plug-in
//!   technique applies to a scene when one of its materials declares it, and its chosen value
//!   reaches the plug-in through [`IntegratorContext::technique`]
//!   (`None`: the default, usually "as the material says"). The contract names no plug-in:
//!   the built-in media declare `scattering`, `subsurface` and `tracking` exactly as a
//!   user's plug-in declares its own.
//!
//! [`IntegratorContext::technique`]: crate::plugin::IntegratorContext::technique

use crate::integrator::{GlobalIntegrator, LightingTechnique};
use crate::path_tracer::visible_emitters::VisibleEmitters;
pub use crate::plugin::technique::{
    always, never, PluginTechniques, Technique, TechniqueError, TechniqueValue, MAX_PLUGIN_CHOICES,
};
use crate::render::RenderOptions;
use crate::scene::{CompiledScene, Features};
use risotto_systems::independent_sampler::SamplerKind;

/// Whether some light (an emitter the lighting techniques estimate) is in the scene.
fn has_lights(f: &Features) -> bool {
    f.area_lights
        || f.distant_lights
        || f.point_lights
        || f.spot_lights
        || f.environment
        || f.emissive_media
}

/// `lighting`: how the path tracer estimates direct lighting.
pub static LIGHTING: Technique = Technique {
    name: "lighting",
    summary: "how direct lighting is estimated at surface and volume vertices",
    values: &[
        TechniqueValue {
            name: "mis",
            summary: "light and Bxdf sampling, power-heuristic MIS (Veach 1997)",
            converges: always,
        },
        TechniqueValue {
            name: "nee",
            summary: "light sampling only (next-event estimation)",
            converges: always,
        },
        TechniqueValue {
            name: "bxdf",
            summary: "Bxdf sampling only (no shadow rays; Dirac lights are invisible)",
            converges: |f| !(f.point_lights || f.spot_lights || f.distant_lights),
        },
    ],
    default: "mis",
    applies_to: "scenes with lights (emitters, distant, point, spot, environment, emissive media)",
};

/// `sampler`: where each path's random numbers come from.
pub static SAMPLER: Technique = Technique {
    name: "sampler",
    summary: "where each path's random numbers come from",
    values: &[
        TechniqueValue {
            name: "sobol",
            summary: "padded Owen-scrambled Sobol (Burley 2020), the pixel jitter digitally shifted; stratified",
            converges: always,
        },
        TechniqueValue {
            name: "independent",
            summary: "independent uniform random numbers (the baseline)",
            converges: always,
        },
    ],
    default: "sobol",
    applies_to: "every scene",
};

/// `integrator`: which global integrator renders.
pub static INTEGRATOR: Technique = Technique {
    name: "integrator",
    summary: "the global integrator: which strategies make each path",
    values: &[
        TechniqueValue {
            name: "path",
            summary: "path tracing from the camera, with light sampling at every vertex",
            converges: always,
        },
        TechniqueValue {
            name: "light",
            summary: "light tracing: paths from the lights, splatted where they meet the camera (not through glass: a Dirac surface between a vertex and the camera blocks it)",
            converges: |f| !f.emissive_media_without_lights && !f.transmissive,
        },
        TechniqueValue {
            name: "bdpt",
            summary: "bidirectional path tracing: camera and light subpaths, every connection, MIS (Veach 1997)",
            converges: always,
        },
        TechniqueValue {
            name: "vcm",
            summary: "vertex connection and merging: bdpt and merging of light vertices within a shrinking radius (Georgiev et al. 2012); consistent",
            converges: always,
        },
    ],
    default: "path",
    applies_to: "scenes with lights (emitters, distant, point, spot, environment, emissive media)",
};

/// `visible_emitters`: how the emission seen directly from the camera is sampled.
pub static VISIBLE_EMITTERS: Technique = Technique {
    name: "visible_emitters",
    summary: "how the emission seen directly from the camera is sampled (the path tracer)",
    values: &[
        TechniqueValue {
            name: "supersampled",
            summary: "4 pixel points per path sample (the pixel's next Sobol points), each a quarter: emitter edges resolved 4x finer",
            converges: always,
        },
        TechniqueValue {
            name: "paths",
            summary: "the paths' own camera rays alone",
            converges: always,
        },
    ],
    default: "supersampled",
    applies_to: "scenes with emissive triangles and no volumes, transmissive or partly opaque surfaces (at most 32 emissive triangles, camera in no volume)",
};

/// Whether the extra camera points of `visible_emitters` can apply to a scene with these
/// features (`path_tracer::visible_emitters::applies` checks the rest).
fn visible_emitters_apply(f: &Features) -> bool {
    f.area_lights && !(f.volumes || f.transmissive || f.opacity || f.emissive_media)
}

/// Whether a technique of the global integrator applies to a scene with these features.
pub type Applies = fn(&Features) -> bool;

/// The global integrator's own techniques, in listing order, each with the scenes it
/// applies to.
pub static CORE: [(&Technique, Applies); 4] = [
    (&INTEGRATOR, has_lights),
    (&LIGHTING, has_lights),
    (&SAMPLER, |_| true),
    (&VISIBLE_EMITTERS, visible_emitters_apply),
];

/// The techniques known in one scene: the global integrator's ([`CORE`]) and those its
/// materials declare.
#[derive(Clone, Debug)]
pub struct TechniqueRegistry {
    features: Features,
    plugins: Vec<&'static Technique>,
}

impl TechniqueRegistry {
    /// The techniques of a scene with `features` whose materials declare `plugins` (the
    /// first declaration of a name counts).
    pub fn new(
        features: Features,
        plugins: impl IntoIterator<Item = &'static Technique>,
    ) -> TechniqueRegistry {
        let mut r = TechniqueRegistry {
            features,
            plugins: Vec::new(),
        };
        for t in plugins {
            let known = CORE.iter().any(|(c, _)| c.name == t.name)
                || r.plugins.iter().any(|p| p.name == t.name);
            if !known {
                r.plugins.push(t);
            }
        }
        r
    }

    /// The techniques of `scene`: [`CORE`] and every technique its materials declare
    /// ([`BxdfFactory::techniques`](crate::plugin::BxdfFactory::techniques)).
    pub fn for_scene(scene: &CompiledScene) -> TechniqueRegistry {
        let declared = scene
            .materials
            .iter()
            .flat_map(|m| m.factory.techniques().iter().copied());
        TechniqueRegistry::new(scene.features, declared)
    }

    /// The technique named `name`.
    pub fn find(&self, name: &str) -> Result<&'static Technique, TechniqueError> {
        self.all()
            .find(|t| t.name == name)
            .ok_or_else(|| TechniqueError::Unknown {
                name: name.to_string(),
                known: self.all().map(|t| t.name).collect::<Vec<_>>().join(", "),
            })
    }

    /// Every technique known here, applicable or not: [`CORE`], then the plug-ins'.
    fn all(&self) -> impl Iterator<Item = &'static Technique> + '_ {
        CORE.iter()
            .map(|(t, _)| *t)
            .chain(self.plugins.iter().copied())
    }

    /// Whether `t` applies to the scene (a plug-in technique applies wherever it is
    /// declared).
    pub fn applies(&self, t: &Technique) -> bool {
        match CORE.iter().find(|(c, _)| c.name == t.name) {
            Some((_, applies)) => applies(&self.features),
            None => self.plugins.iter().any(|p| p.name == t.name),
        }
    }

    /// The techniques that apply to the scene, in listing order.
    pub fn applicable(&self) -> impl Iterator<Item = &'static Technique> + '_ {
        self.all().filter(|t| self.applies(t))
    }

    /// The scene's features.
    pub fn features(&self) -> &Features {
        &self.features
    }
}

/// A choice of value for every technique of a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Techniques {
    /// `integrator` (`None`: not chosen, the scene's).
    pub integrator: Option<GlobalIntegrator>,
    /// `lighting`.
    pub lighting: LightingTechnique,
    /// `sampler`.
    pub sampler: SamplerKind,
    /// `visible_emitters`.
    pub visible_emitters: VisibleEmitters,
    /// Every plug-in technique (unlisted: its default).
    pub plugins: PluginTechniques,
}

impl Techniques {
    /// The value of technique `name` (known in `registry`).
    pub fn get(
        &self,
        registry: &TechniqueRegistry,
        name: &str,
    ) -> Result<&'static str, TechniqueError> {
        let t = registry.find(name)?;
        Ok(match t.name {
            "integrator" => self.integrator.unwrap_or_default().name(),
            "lighting" => match self.lighting {
                LightingTechnique::Mis => "mis",
                LightingTechnique::NeeOnly => "nee",
                LightingTechnique::BxdfOnly => "bxdf",
            },
            "sampler" => match self.sampler {
                SamplerKind::Sobol => "sobol",
                SamplerKind::Independent => "independent",
            },
            "visible_emitters" => match self.visible_emitters {
                VisibleEmitters::Supersampled => "supersampled",
                VisibleEmitters::Paths => "paths",
            },
            _ => self.plugins.get(t.name).unwrap_or(t.default),
        })
    }

    /// Sets technique `name` (known in `registry`) to `value`.
    pub fn set(
        &mut self,
        registry: &TechniqueRegistry,
        name: &str,
        value: &str,
    ) -> Result<(), TechniqueError> {
        let t = registry.find(name)?;
        let v = t.value(value)?;
        match t.name {
            "integrator" => self.integrator = GlobalIntegrator::from_name(v.name),
            "lighting" => {
                self.lighting = match v.name {
                    "nee" => LightingTechnique::NeeOnly,
                    "bxdf" => LightingTechnique::BxdfOnly,
                    _ => LightingTechnique::Mis,
                }
            }
            "sampler" => {
                self.sampler = match v.name {
                    "independent" => SamplerKind::Independent,
                    _ => SamplerKind::Sobol,
                }
            }
            "visible_emitters" => {
                self.visible_emitters = match v.name {
                    "paths" => VisibleEmitters::Paths,
                    _ => VisibleEmitters::Supersampled,
                }
            }
            // A default is no choice: the same selection compares equal however written.
            _ if v.name == t.default => self.plugins.remove(t.name),
            _ => self.plugins = self.plugins.with(t.name, v.name)?,
        }
        Ok(())
    }

    /// Applies `NAME=VALUE`, returning the technique.
    pub fn assign(
        &mut self,
        registry: &TechniqueRegistry,
        assignment: &str,
    ) -> Result<&'static Technique, TechniqueError> {
        let (name, value) = assignment
            .split_once('=')
            .ok_or_else(|| TechniqueError::Malformed(assignment.to_string()))?;
        let (name, value) = (name.trim(), value.trim());
        self.set(registry, name, value)?;
        registry.find(name)
    }

    /// The defaults with the `+`-separated assignments `spec` applied
    /// (`lighting=nee+sampler=independent`).
    pub fn parse(registry: &TechniqueRegistry, spec: &str) -> Result<Self, TechniqueError> {
        let mut t = Techniques::default();
        for a in spec.split('+') {
            t.assign(registry, a)?;
        }
        Ok(t)
    }

    /// The `(technique, value)` pairs that differ from the defaults: the global
    /// integrator's, then the plug-ins' by name.
    pub fn non_default(&self) -> Vec<(&'static str, &'static str)> {
        let core = TechniqueRegistry::new(Features::default(), []);
        let mut out: Vec<_> = CORE
            .iter()
            .filter_map(|(t, _)| {
                let v = self.get(&core, t.name).ok()?;
                (v != t.default).then_some((t.name, v))
            })
            .collect();
        out.extend(self.plugins.iter());
        out
    }

    /// An error unless every technique whose value is not its default applies to the scene
    /// of `registry` (a default value changes nothing, so it is allowed anywhere).
    pub fn check_applicable(&self, registry: &TechniqueRegistry) -> Result<(), TechniqueError> {
        for (name, value) in self.non_default() {
            let t = registry.find(name)?;
            if !registry.applies(t) {
                return Err(TechniqueError::NotApplicable {
                    technique: t.name,
                    value: value.to_string(),
                    applies_to: t.applies_to,
                });
            }
        }
        Ok(())
    }

    /// Whether every chosen value converges to the exact image of the scene of `registry`
    /// ([`TechniqueValue::converges`]); a choice of a technique the scene does not know
    /// changes nothing there.
    pub fn converges(&self, registry: &TechniqueRegistry) -> bool {
        self.non_default().iter().all(|&(name, value)| {
            registry
                .find(name)
                .ok()
                .and_then(|t| t.value(value).ok())
                .is_none_or(|v| (v.converges)(registry.features()))
        })
    }

    /// A short label: the non-default assignments (`lighting=nee`, `integrator=bdpt`), or
    /// the path tracer's lighting and sampler defaults joined by `+` when all are defaults
    /// (`lighting=mis+sampler=sobol`; the label every sweep's default row has had).
    pub fn label(&self) -> String {
        let pairs = self.non_default();
        let pairs = if pairs.is_empty() {
            // The path tracer is implied, and so are the defaults of the techniques that
            // apply to few scenes (`visible_emitters`).
            CORE.iter()
                .filter(|(t, _)| t.name != INTEGRATOR.name && t.name != VISIBLE_EMITTERS.name)
                .map(|(t, _)| (t.name, t.default))
                .collect()
        } else {
            pairs
        };
        pairs
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join("+")
    }

    /// `base` with these techniques.
    pub fn render_options(&self, base: RenderOptions) -> RenderOptions {
        RenderOptions {
            integrator: self.integrator.or(base.integrator),
            technique: self.lighting,
            sampler: self.sampler,
            visible_emitters: self.visible_emitters,
            plugin_techniques: self.plugins,
            ..base
        }
    }

    /// Every variant a sweep over the techniques that apply to the scene of `registry`
    /// renders: the defaults, then each applicable technique's other values one at a time
    /// (the others at their defaults).
    pub fn variants(registry: &TechniqueRegistry) -> Vec<Techniques> {
        let mut out = vec![Techniques::default()];
        for t in registry.applicable() {
            for v in t.values.iter().filter(|v| v.name != t.default) {
                let mut x = Techniques::default();
                if x.set(registry, t.name, v.name).is_ok() {
                    out.push(x);
                }
            }
        }
        out
    }
}

/// The listing `risotto techniques SCENE` prints: each applicable technique with its values
/// (`*` marks the default) and what it applies to.
pub fn listing(registry: &TechniqueRegistry) -> String {
    registry.applicable().map(listing_entry).collect()
}

/// One technique's lines of [`listing`]: `NAME: summary (applies to ...)`, then one
/// indented line per value (`*` marks the default). Also for choices listed beside the
/// techniques, such as `converge`'s `adaptive`.
pub fn listing_entry(t: &Technique) -> String {
    let mut s = format!("{}: {} (applies to {})\n", t.name, t.summary, t.applies_to);
    let width = t
        .values
        .iter()
        .map(|v| v.name.len())
        .max()
        .unwrap_or(0)
        .max(12);
    for v in t.values {
        let mark = if v.name == t.default { "*" } else { " " };
        s += &format!("  {mark} {}={:<width$} {}\n", t.name, v.name, v.summary);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A technique as a plug-in would declare it.
    static QUALITY: Technique = Technique {
        name: "quality",
        summary: "a plug-in's own choice",
        values: &[
            TechniqueValue {
                name: "scene",
                summary: "as the material says",
                converges: always,
            },
            TechniqueValue {
                name: "draft",
                summary: "an approximation",
                converges: never,
            },
        ],
        default: "scene",
        applies_to: "scenes with the plug-in's material",
    };

    fn lit() -> Features {
        Features {
            area_lights: true,
            ..Features::default()
        }
    }

    #[test]
    fn every_value_round_trips_and_defaults_are_values() {
        let reg = TechniqueRegistry::new(lit(), [&QUALITY]);
        for t in reg.applicable() {
            assert!(t.values.iter().any(|v| v.name == t.default), "{}", t.name);
            for v in t.values {
                let mut x = Techniques::default();
                x.set(&reg, t.name, v.name).unwrap();
                assert_eq!(x.get(&reg, t.name).unwrap(), v.name);
            }
            assert_eq!(Techniques::default().get(&reg, t.name).unwrap(), t.default);
        }
        // Setting a plug-in technique to its default is no choice at all.
        let mut x = Techniques::parse(&reg, "quality=draft").unwrap();
        assert_eq!(x.plugins.get("quality"), Some("draft"));
        x.set(&reg, "quality", "scene").unwrap();
        assert_eq!(x, Techniques::default());
    }

    #[test]
    fn bad_names_values_and_forms_are_named_in_the_error() {
        let reg = TechniqueRegistry::new(lit(), []);
        let e = Techniques::parse(&reg, "lighting=nee+shading=fast").unwrap_err();
        assert!(e.to_string().contains("\"shading\""), "{e}");
        let e = Techniques::parse(&reg, "sampler=halton").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("halton") && msg.contains("sobol, independent"),
            "{msg}"
        );
        assert!(matches!(
            Techniques::parse(&reg, "lighting"),
            Err(TechniqueError::Malformed(_))
        ));
        // A plug-in technique no material of the scene declares is unknown there.
        let e = Techniques::parse(&reg, "quality=draft").unwrap_err();
        assert!(matches!(e, TechniqueError::Unknown { .. }), "{e}");
    }

    #[test]
    fn applicability_follows_the_scene_features_and_declarations() {
        let names = |r: &TechniqueRegistry| r.applicable().map(|t| t.name).collect::<Vec<_>>();
        let lit = TechniqueRegistry::new(lit(), [&QUALITY, &QUALITY]);
        let dark = TechniqueRegistry::new(Features::default(), []);
        assert_eq!(
            names(&lit),
            [
                "integrator",
                "lighting",
                "sampler",
                "visible_emitters",
                "quality"
            ]
        );
        assert_eq!(names(&dark), ["sampler"]);
        let nee = Techniques::parse(&lit, "lighting=nee").unwrap();
        assert!(nee.check_applicable(&lit).is_ok());
        let e = nee.check_applicable(&dark).unwrap_err();
        assert!(e.to_string().contains("lighting=nee"), "{e}");
        // The default value applies anywhere.
        assert!(Techniques::default().check_applicable(&dark).is_ok());
        let draft = Techniques::parse(&lit, "quality=draft").unwrap();
        assert!(draft.check_applicable(&lit).is_ok());
        assert!(draft.check_applicable(&dark).is_err());
        assert!(!draft.converges(&lit) && Techniques::default().converges(&lit));
    }

    #[test]
    fn variants_are_the_defaults_and_one_change_at_a_time() {
        let env = Features {
            environment: true,
            ..Features::default()
        };
        let labels = |r: &TechniqueRegistry| {
            Techniques::variants(r)
                .iter()
                .map(|t| t.label())
                .collect::<Vec<_>>()
        };
        assert_eq!(
            labels(&TechniqueRegistry::new(env, [&QUALITY])),
            [
                "lighting=mis+sampler=sobol",
                "integrator=light",
                "integrator=bdpt",
                "integrator=vcm",
                "lighting=nee",
                "lighting=bxdf",
                "sampler=independent",
                "quality=draft"
            ]
        );
        assert_eq!(
            labels(&TechniqueRegistry::new(Features::default(), [])),
            ["lighting=mis+sampler=sobol", "sampler=independent"]
        );
    }

    #[test]
    fn plugin_choices_stay_sorted_and_bounded() {
        let names = ["h", "b", "f", "a", "g", "c", "e", "d"];
        let mut p = PluginTechniques::default();
        for n in names {
            p = p.with(n, "x").unwrap();
        }
        let order: Vec<_> = p.iter().map(|(n, _)| n).collect();
        assert_eq!(order, ["a", "b", "c", "d", "e", "f", "g", "h"]);
        // Replacing a value keeps the count; a ninth technique is refused.
        p = p.with("c", "y").unwrap();
        assert_eq!(p.get("c"), Some("y"));
        assert!(matches!(p.with("i", "x"), Err(TechniqueError::TooMany)));
        p.remove("a");
        assert_eq!(p.get("a"), None);
        assert!(p.with("i", "x").is_ok());
    }
}
