//! The registry of techniques: every estimator choice that trades time for error is a named
//! technique with its values, its default and the scene features it applies to (DESIGN.md,
//! "Accuracy and its cost"). `risotto techniques SCENE` lists [`applicable`] ones,
//! `risotto render --technique NAME=VALUE` sets one, and `risotto converge` sweeps them.
//!
//! A new technique is one entry of [`REGISTRY`] (its `get` and `set` read and write a field
//! of [`Techniques`]) plus that field's use in [`Techniques::render_options`].

use crate::heterogeneous::Tracking;
use crate::integrator::LightingTechnique;
use crate::media::Scattering;
use crate::render::RenderOptions;
use crate::scene::Features;
use crate::subsurface::SubsurfaceMode;
use risotto_systems::independent_sampler::SamplerKind;
use std::fmt;

/// One value a technique can take.
#[derive(Clone, Copy, Debug)]
pub struct TechniqueValue {
    /// Its name (`NAME=VALUE`).
    pub name: &'static str,
    /// What it does.
    pub summary: &'static str,
    /// Whether it converges to the scene's exact image in a scene with these features
    /// (false for an approximation, such as single scattering only): only such values may
    /// render a reference.
    pub converges: fn(&Features) -> bool,
}

/// [`TechniqueValue::converges`] of an unbiased estimator.
fn always(_: &Features) -> bool {
    true
}

/// A registered technique.
pub struct Technique {
    /// Its name (`NAME=VALUE`).
    pub name: &'static str,
    /// What it chooses.
    pub summary: &'static str,
    /// Its values.
    pub values: &'static [TechniqueValue],
    /// The value used unless one is given.
    pub default: &'static str,
    /// The scenes it applies to, in words.
    pub applies_to: &'static str,
    /// Whether it applies to a scene with these features.
    pub applies: fn(&Features) -> bool,
    /// The value set in a selection.
    get: fn(&Techniques) -> &'static str,
    /// Sets a value (one of `values`).
    set: fn(&mut Techniques, &str),
}

impl fmt::Debug for Technique {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Technique")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// Whether some light (an emitter the lighting techniques estimate) is in the scene.
fn has_lights(f: &Features) -> bool {
    f.area_lights || f.distant_lights || f.point_lights || f.environment || f.emissive_media
}

/// Every technique, in listing order.
pub static REGISTRY: &[Technique] = &[
    Technique {
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
                converges: |f| !(f.point_lights || f.distant_lights),
            },
        ],
        default: "mis",
        applies_to: "scenes with lights (emitters, distant, point, environment, emissive media)",
        applies: has_lights,
        get: |t| match t.lighting {
            LightingTechnique::Mis => "mis",
            LightingTechnique::NeeOnly => "nee",
            LightingTechnique::BxdfOnly => "bxdf",
        },
        set: |t, v| {
            t.lighting = match v {
                "nee" => LightingTechnique::NeeOnly,
                "bxdf" => LightingTechnique::BxdfOnly,
                _ => LightingTechnique::Mis,
            }
        },
    },
    Technique {
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
        applies: |_| true,
        get: |t| match t.sampler {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Independent => "independent",
        },
        set: |t, v| {
            t.sampler = match v {
                "independent" => SamplerKind::Independent,
                _ => SamplerKind::Sobol,
            }
        },
    },
    Technique {
        name: "scattering",
        summary: "single or multiple scattering in scattering media",
        values: &[
            TechniqueValue {
                name: "scene",
                summary: "as each medium's `scattering` says",
                converges: always,
            },
            TechniqueValue {
                name: "multiple",
                summary: "every order: walk where light sampling cannot help, else bounce",
                converges: always,
            },
            TechniqueValue {
                name: "walk",
                summary: "every order, walked inside the volume integrator (exits only)",
                converges: always,
            },
            TechniqueValue {
                name: "bounce",
                summary: "every order: each scattering point goes back to the path tracer",
                converges: always,
            },
            TechniqueValue {
                name: "single",
                summary:
                    "single scattering through the lighting delegate (biased: no higher orders)",
                converges: |_| false,
            },
        ],
        default: "scene",
        applies_to: "scenes with scattering media",
        applies: |f| f.scattering_media,
        get: |t| match t.scattering {
            None => "scene",
            Some(Scattering::Multiple) => "multiple",
            Some(Scattering::Walk) => "walk",
            Some(Scattering::Bounce) => "bounce",
            Some(Scattering::Single) => "single",
        },
        set: |t, v| {
            t.scattering = match v {
                "multiple" => Some(Scattering::Multiple),
                "walk" => Some(Scattering::Walk),
                "bounce" => Some(Scattering::Bounce),
                "single" => Some(Scattering::Single),
                _ => None,
            }
        },
    },
    Technique {
        name: "subsurface",
        summary: "random walk or diffusion in subsurface materials",
        values: &[
            TechniqueValue {
                name: "scene",
                summary: "as each subsurface material's `mode` says",
                converges: always,
            },
            TechniqueValue {
                name: "random_walk",
                summary: "walk every path inside the boundary (exact)",
                converges: always,
            },
            TechniqueValue {
                name: "diffusion",
                summary: "normalized diffusion with probe rays (fast, approximate)",
                converges: |_| false,
            },
        ],
        default: "scene",
        applies_to: "scenes with subsurface materials",
        applies: |f| f.subsurface,
        get: |t| match t.subsurface {
            None => "scene",
            Some(SubsurfaceMode::RandomWalk) => "random_walk",
            Some(SubsurfaceMode::Diffusion) => "diffusion",
        },
        set: |t, v| {
            t.subsurface = match v {
                "random_walk" => Some(SubsurfaceMode::RandomWalk),
                "diffusion" => Some(SubsurfaceMode::Diffusion),
                _ => None,
            }
        },
    },
    Technique {
        name: "tracking",
        summary: "free-flight and transmittance estimators in heterogeneous media",
        values: &[
            TechniqueValue {
                name: "scene",
                summary: "as each heterogeneous medium's `tracking` says",
                converges: always,
            },
            TechniqueValue {
                name: "ratio",
                summary:
                    "ratio tracking for shadow rays (Novak et al. 2014); delta-tracked flights",
                converges: always,
            },
            TechniqueValue {
                name: "residual",
                summary: "residual ratio tracking, each majorant cell's minimum as control",
                converges: always,
            },
            TechniqueValue {
                name: "delta",
                summary: "delta tracking for shadow rays too (0 or 1)",
                converges: always,
            },
            TechniqueValue {
                name: "ray_marching",
                summary: "fixed-step ray marching of flights and shadow rays (biased)",
                converges: |_| false,
            },
            TechniqueValue {
                name: "unbiased_ray_marching",
                summary:
                    "power series around a marched pivot for shadow rays (Kettunen et al. 2021)",
                converges: always,
            },
        ],
        default: "scene",
        applies_to: "scenes with heterogeneous media",
        applies: |f| f.heterogeneous,
        get: |t| t.tracking.map_or("scene", Tracking::name),
        set: |t, v| t.tracking = Tracking::from_name(v),
    },
];

/// A bad technique name, value or use.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TechniqueError {
    /// No technique has this name.
    #[error("unknown technique \"{name}\" (known: {known})")]
    Unknown {
        /// The name given.
        name: String,
        /// The registered names.
        known: String,
    },
    /// The technique has no such value.
    #[error("technique {technique}: unknown value \"{value}\" (expected one of {expected})")]
    BadValue {
        /// The technique.
        technique: &'static str,
        /// The value given.
        value: String,
        /// Its values.
        expected: String,
    },
    /// Not of the form `NAME=VALUE`.
    #[error("\"{0}\": expected NAME=VALUE (e.g. lighting=nee)")]
    Malformed(String),
    /// The technique does not apply to the scene.
    #[error(
        "technique {technique}={value} does not apply to this scene: {technique} applies to {applies_to}"
    )]
    NotApplicable {
        /// The technique.
        technique: &'static str,
        /// The value given.
        value: String,
        /// What it applies to.
        applies_to: &'static str,
    },
}

/// The technique named `name`.
pub fn find(name: &str) -> Result<&'static Technique, TechniqueError> {
    REGISTRY
        .iter()
        .find(|t| t.name == name)
        .ok_or_else(|| TechniqueError::Unknown {
            name: name.to_string(),
            known: REGISTRY
                .iter()
                .map(|t| t.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// The techniques that apply to a scene with `features`.
pub fn applicable(features: &Features) -> impl Iterator<Item = &'static Technique> + '_ {
    REGISTRY.iter().filter(move |t| (t.applies)(features))
}

/// A choice of value for every technique.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Techniques {
    /// `lighting`.
    pub lighting: LightingTechnique,
    /// `sampler`.
    pub sampler: SamplerKind,
    /// `scattering` (`None`: as each medium says).
    pub scattering: Option<Scattering>,
    /// `subsurface` (`None`: as each material says).
    pub subsurface: Option<SubsurfaceMode>,
    /// `tracking` (`None`: as each heterogeneous medium says).
    pub tracking: Option<Tracking>,
}

impl Techniques {
    /// The value of technique `name`.
    pub fn get(&self, name: &str) -> Result<&'static str, TechniqueError> {
        Ok((find(name)?.get)(self))
    }

    /// Sets technique `name` to `value`.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), TechniqueError> {
        let t = find(name)?;
        if !t.values.iter().any(|v| v.name == value) {
            return Err(TechniqueError::BadValue {
                technique: t.name,
                value: value.to_string(),
                expected: t
                    .values
                    .iter()
                    .map(|v| v.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        (t.set)(self, value);
        Ok(())
    }

    /// Applies `NAME=VALUE`, returning the technique.
    pub fn assign(&mut self, assignment: &str) -> Result<&'static Technique, TechniqueError> {
        let (name, value) = assignment
            .split_once('=')
            .ok_or_else(|| TechniqueError::Malformed(assignment.to_string()))?;
        let (name, value) = (name.trim(), value.trim());
        self.set(name, value)?;
        find(name)
    }

    /// The defaults with the `+`-separated assignments `spec` applied
    /// (`lighting=nee+sampler=independent`).
    pub fn parse(spec: &str) -> Result<Self, TechniqueError> {
        let mut t = Techniques::default();
        for a in spec.split('+') {
            t.assign(a)?;
        }
        Ok(t)
    }

    /// The `(technique, value)` pairs that differ from the defaults.
    pub fn non_default(&self) -> Vec<(&'static str, &'static str)> {
        REGISTRY
            .iter()
            .map(|t| (t.name, (t.get)(self)))
            .filter(|&(name, v)| find(name).is_ok_and(|t| t.default != v))
            .collect()
    }

    /// An error unless every technique whose value is not its default applies to a scene
    /// with `features` (a default value changes nothing, so it is allowed anywhere).
    pub fn check_applicable(&self, features: &Features) -> Result<(), TechniqueError> {
        for t in REGISTRY {
            let v = (t.get)(self);
            if v != t.default && !(t.applies)(features) {
                return Err(TechniqueError::NotApplicable {
                    technique: t.name,
                    value: v.to_string(),
                    applies_to: t.applies_to,
                });
            }
        }
        Ok(())
    }

    /// Whether every chosen value converges to the scene's exact image in a scene with
    /// `features` ([`TechniqueValue::converges`]).
    pub fn converges(&self, features: &Features) -> bool {
        REGISTRY.iter().all(|t| {
            let v = (t.get)(self);
            t.values
                .iter()
                .find(|x| x.name == v)
                .is_some_and(|x| (x.converges)(features))
        })
    }

    /// A short label: the non-default assignments (`lighting=nee`), or every technique's
    /// default joined by `+` when all are defaults (leaving out defaults that defer to the
    /// scene, such as `scattering=scene`).
    pub fn label(&self) -> String {
        let pairs = self.non_default();
        let pairs = if pairs.is_empty() {
            REGISTRY
                .iter()
                .filter(|t| t.default != "scene")
                .map(|t| (t.name, t.default))
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
            technique: self.lighting,
            sampler: self.sampler,
            volume: crate::plugin::VolumeTechniques {
                scattering: self.scattering,
                subsurface: self.subsurface,
                tracking: self.tracking,
            },
            ..base
        }
    }

    /// Every variant a sweep over the techniques that apply to `features` renders: the
    /// defaults, then each applicable technique's other values one at a time (the others at
    /// their defaults).
    pub fn variants(features: &Features) -> Vec<Techniques> {
        let mut out = vec![Techniques::default()];
        for t in applicable(features) {
            for v in t.values.iter().filter(|v| v.name != t.default) {
                let mut x = Techniques::default();
                (t.set)(&mut x, v.name);
                out.push(x);
            }
        }
        out
    }
}

/// The listing `risotto techniques SCENE` prints: each applicable technique with its values
/// (`*` marks the default) and what it applies to.
pub fn listing(features: &Features) -> String {
    let mut s = String::new();
    for t in applicable(features) {
        s += &format!("{}: {} (applies to {})\n", t.name, t.summary, t.applies_to);
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
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_value_round_trips_and_defaults_are_values() {
        for t in REGISTRY {
            assert!(t.values.iter().any(|v| v.name == t.default), "{}", t.name);
            for v in t.values {
                let mut x = Techniques::default();
                x.set(t.name, v.name).unwrap();
                assert_eq!(x.get(t.name).unwrap(), v.name);
            }
            assert_eq!(Techniques::default().get(t.name).unwrap(), t.default);
        }
    }

    #[test]
    fn bad_names_values_and_forms_are_named_in_the_error() {
        let e = Techniques::parse("lighting=nee+shading=fast").unwrap_err();
        assert!(e.to_string().contains("\"shading\""), "{e}");
        let e = Techniques::parse("sampler=halton").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("halton") && msg.contains("sobol, independent"),
            "{msg}"
        );
        assert!(matches!(
            Techniques::parse("lighting"),
            Err(TechniqueError::Malformed(_))
        ));
    }

    #[test]
    fn applicability_follows_the_scene_features() {
        let lit = Features {
            area_lights: true,
            ..Features::default()
        };
        let dark = Features::default();
        let names = |f: &Features| applicable(f).map(|t| t.name).collect::<Vec<_>>();
        assert_eq!(names(&lit), ["lighting", "sampler"]);
        assert_eq!(names(&dark), ["sampler"]);
        let nee = Techniques::parse("lighting=nee").unwrap();
        assert!(nee.check_applicable(&lit).is_ok());
        let e = nee.check_applicable(&dark).unwrap_err();
        assert!(e.to_string().contains("lighting=nee"), "{e}");
        // The default value applies anywhere.
        assert!(Techniques::default().check_applicable(&dark).is_ok());
    }

    #[test]
    fn variants_are_the_defaults_and_one_change_at_a_time() {
        let lit = Features {
            environment: true,
            ..Features::default()
        };
        let labels: Vec<String> = Techniques::variants(&lit)
            .iter()
            .map(|t| t.label())
            .collect();
        assert_eq!(
            labels,
            [
                "lighting=mis+sampler=sobol",
                "lighting=nee",
                "lighting=bxdf",
                "sampler=independent"
            ]
        );
        let dark: Vec<String> = Techniques::variants(&Features::default())
            .iter()
            .map(|t| t.label())
            .collect();
        assert_eq!(dark, ["lighting=mis+sampler=sobol", "sampler=independent"]);
    }
}
