//! The sweep's variants, one curve each: a choice of techniques ([`Techniques`]) and how the
//! samples are spread over the pixels, `adaptive = off | on | unbiased` ([`ADAPTIVE`]).
//!
//! `adaptive=on` (and `unbiased`, the other stopping rule) is not an estimator technique of
//! the engine (`render` asks for it with `--noise-target X`, a number, not a `--technique`
//! value) but a dimension of the sweep,
//! written in `--techniques` specs like one (`adaptive=on`, `lighting=nee+adaptive=on`) and
//! listed by `risotto techniques` beside them, so its curve is compared with the uniform ones
//! on the same plot and table. Its points are renders at decreasing noise targets rather
//! than increasing spp counts ([`AdaptivePlan`]).

use super::ConvergeError;
use risotto_engine::integrator::GlobalIntegrator;
use risotto_engine::render::StoppingRule;
use risotto_engine::scene::CompiledScene;
use risotto_engine::technique::{
    always, never, Technique, TechniqueRegistry, TechniqueValue, Techniques,
};

/// `adaptive`: uniform sampling, or adaptive sampling to a noise target with the window
/// (`on`) or the unbiased stopping rule ([`StoppingRule`]), as `converge` sweeps it and
/// `risotto techniques` lists it. It applies where the scene's integrator is
/// the path tracer: the bidirectional integrators refuse a noise target (their light paths
/// splat onto every pixel, stopped or not).
pub static ADAPTIVE: Technique = Technique {
    name: "adaptive",
    summary: "how samples are spread over the pixels; converge sweeps it (--noise-targets), render asks for it with --noise-target X",
    values: &[
        TechniqueValue {
            name: "off",
            summary: "uniform: every pixel takes each point's spp",
            converges: always,
        },
        TechniqueValue {
            name: "on",
            summary: "adaptive: a pixel stops at the noise target, its 3x3 window deciding (biased where light arrives by rare paths: Kirk and Arvo 1991); converge only, points at noise targets",
            converges: never,
        },
        TechniqueValue {
            name: "unbiased",
            summary: "adaptive, decided by a discarded pilot and the preceding pixels, never a pixel's own samples (render --stopping-rule unbiased): unbiased; converge only, points at noise targets",
            converges: always,
        },
    ],
    default: "off",
    applies_to: "scenes the path tracer renders; not with integrator=light, bdpt or vcm",
};

/// Where the first `--noise-targets` of an adaptive curve starts, each next one half the
/// one before: `0.4, 0.2, ..., 0.00625` (seven points, as the default spp list). Halving a
/// pixel's relative error takes about four times its samples (the standard error falls as
/// `n^-1/2`), so where pixels stop between the minimum and the cap one step of the targets
/// spans about two doublings of the spp list.
pub const DEFAULT_NOISE_TARGETS: [f64; 7] = [0.4, 0.2, 0.1, 0.05, 0.025, 0.0125, 0.00625];

/// Samples every pixel of an adaptive point takes before any stops (`render
/// --noise-target`'s default `--min-spp`).
pub const DEFAULT_MIN_SPP: u32 = 16;

/// How the points of the adaptive curves are rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptivePlan {
    /// The relative errors, one point each, descending (with a time budget: the first is
    /// halved until a render takes the budget). Defaults to [`DEFAULT_NOISE_TARGETS`].
    pub noise_targets: Vec<f64>,
    /// Samples every pixel takes before any stops, >= 1. Defaults to [`DEFAULT_MIN_SPP`].
    pub min_spp: u32,
}

impl Default for AdaptivePlan {
    fn default() -> Self {
        AdaptivePlan {
            noise_targets: DEFAULT_NOISE_TARGETS.to_vec(),
            min_spp: DEFAULT_MIN_SPP,
        }
    }
}

impl AdaptivePlan {
    /// An error unless the targets are positive, finite and descending and the minimum is
    /// at least one sample.
    pub fn check(&self) -> Result<(), ConvergeError> {
        let t = &self.noise_targets;
        if t.is_empty()
            || t.iter().any(|x| !(x.is_finite() && *x > 0.0))
            || t.windows(2).any(|w| w[1] >= w[0])
        {
            return Err(ConvergeError::Options(format!(
                "--noise-targets {t:?}: need one or more positive relative errors, \
                 descending (e.g. 0.4,0.2,0.1)"
            )));
        }
        if self.min_spp == 0 {
            return Err(ConvergeError::Options(
                "--min-spp 0: must be at least 1".into(),
            ));
        }
        Ok(())
    }

    /// Whether a pixel can stop before `cap` samples: it stops at the earliest after two
    /// looks at its error, at `min_spp` and `2 min_spp` samples, so only below a cap above
    /// `2 min_spp`.
    pub fn can_stop_below(&self, cap: u32) -> bool {
        self.min_spp.saturating_mul(2) < cap
    }
}

/// One curve of the sweep: its techniques, uniform or adaptive.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Variant {
    /// The techniques.
    pub techniques: Techniques,
    /// `adaptive=on` or `unbiased`: points at noise targets ([`AdaptivePlan`]) with this
    /// stopping rule; `None` (`off`), at spp counts.
    pub adaptive: Option<StoppingRule>,
}

impl From<Techniques> for Variant {
    fn from(techniques: Techniques) -> Variant {
        Variant {
            techniques,
            adaptive: None,
        }
    }
}

impl Variant {
    /// The defaults with the `+`-separated assignments of `spec` applied,
    /// `adaptive=off|on|unbiased` among them (`lighting=nee+adaptive=on`), checked against `scene`
    /// ([`Variant::check`]).
    pub fn parse(scene: &CompiledScene, spec: &str) -> Result<Variant, ConvergeError> {
        let registry = TechniqueRegistry::for_scene(scene);
        let mut techniques = Vec::new();
        let mut adaptive = None;
        for a in spec.split('+') {
            match a.split_once('=') {
                Some((name, value)) if name.trim() == ADAPTIVE.name => {
                    adaptive = match ADAPTIVE.value(value.trim())?.name {
                        "on" => Some(StoppingRule::Window),
                        "unbiased" => Some(StoppingRule::Unbiased),
                        _ => None,
                    };
                }
                _ => techniques.push(a),
            }
        }
        let techniques = match techniques.is_empty() {
            true => Techniques::default(),
            false => Techniques::parse(&registry, &techniques.join("+"))?,
        };
        let v = Variant {
            techniques,
            adaptive,
        };
        v.check(scene)?;
        Ok(v)
    }

    /// `--techniques all`: the defaults, each applicable technique's other values one at a
    /// time ([`Techniques::variants`]), and `adaptive=on` once, on the defaults, where it
    /// applies ([`adaptive_applies`]).
    pub fn all(scene: &CompiledScene) -> Vec<Variant> {
        let registry = TechniqueRegistry::for_scene(scene);
        let mut out: Vec<Variant> = Techniques::variants(&registry)
            .into_iter()
            .map(Variant::from)
            .collect();
        if adaptive_applies(scene) {
            out.push(Variant {
                techniques: Techniques::default(),
                adaptive: Some(StoppingRule::Window),
            });
        }
        out
    }

    /// An error unless every chosen technique applies to `scene` and, with `adaptive=on`,
    /// the integrator that renders is the path tracer (the engine refuses a noise target
    /// with the others; here it is refused before any render).
    pub fn check(&self, scene: &CompiledScene) -> Result<(), ConvergeError> {
        self.techniques
            .check_applicable(&TechniqueRegistry::for_scene(scene))?;
        let integrator = self.integrator(scene);
        if self.adaptive.is_some() && integrator != GlobalIntegrator::Path {
            return Err(ConvergeError::Options(format!(
                "{}: adaptive sampling (a noise target) needs the path tracer, and this \
                 variant renders with integrator={} (it splats light paths onto every \
                 pixel, stopped or not); sweep adaptive=on with integrator=path",
                self.label(),
                integrator.name()
            )));
        }
        Ok(())
    }

    /// The global integrator that renders this variant in `scene`.
    fn integrator(&self, scene: &CompiledScene) -> GlobalIntegrator {
        self.techniques
            .integrator
            .unwrap_or(scene.settings.integrator)
    }

    /// The curve's label: the techniques' ([`Techniques::label`]), or for an adaptive
    /// variant its non-default techniques followed by `adaptive=on` (`adaptive=on` alone on
    /// the defaults).
    pub fn label(&self) -> String {
        let Some(rule) = self.adaptive else {
            return self.techniques.label();
        };
        self.techniques
            .non_default()
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .chain(std::iter::once(format!(
                "{}={}",
                ADAPTIVE.name,
                adaptive_value(rule)
            )))
            .collect::<Vec<_>>()
            .join("+")
    }
}

/// The `adaptive` value that asks for `rule`.
pub fn adaptive_value(rule: StoppingRule) -> &'static str {
    match rule {
        StoppingRule::Window => "on",
        StoppingRule::Unbiased => "unbiased",
    }
}

/// Whether `adaptive=on` applies to `scene`: the integrator it asks for is the path tracer.
pub fn adaptive_applies(scene: &CompiledScene) -> bool {
    scene.settings.integrator == GlobalIntegrator::Path
}

/// The lines `risotto techniques SCENE` adds for [`ADAPTIVE`] after the techniques, where
/// it applies (nothing elsewhere, as for a technique that does not apply).
pub fn listing(scene: &CompiledScene) -> String {
    match adaptive_applies(scene) {
        true => risotto_engine::technique::listing_entry(&ADAPTIVE),
        false => String::new(),
    }
}
