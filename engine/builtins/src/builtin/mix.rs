//! The `mix` material: two materials blended by an amount (pbrt-v4's `MixMaterial`,
//! Mitsuba 3's `blendbsdf`): `f = (1 - t) f_a + t f_b` at every point, `t` a number or a
//! grey pattern in [0, 1].
//!
//! pbrt-v4 picks one of the two materials per hit (by a hash of the hit), Mitsuba blends
//! the lobes; both have the mixture as their expectation, which is what this closure
//! evaluates and samples: a direction is drawn from `a` with probability `1 - t` and from
//! `b` with probability `t` (one sampler dimension), and weighted by the mixture's value over
//! the mixture's pdf, `((1 - t) f_a + t f_b) / ((1 - t) p_a + t p_b)` (the one-sample model
//! of Veach's thesis, sec. 9.2.4, with the balance heuristic: no variance added over sampling
//! the mixture directly). A Dirac sample of one component keeps its weight, its discrete
//! probability times that of choosing it. Each component is built on its own view of the
//! context ([`ShadingContext::component`]), so their parameters and patterns are its own.
//!
//! Components may only reflect: a component with an interior, transmission or opacity is
//! refused ([`MixMaterial::new`]), because which volume a path enters, and what shadow rays
//! see through the surface, must not depend on a random choice per hit.

use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};
use risotto_engine::plugin::*;
use risotto_systems::pattern::PatternGraph;
use risotto_systems::sampler::PathSampler;
use std::sync::Arc;

/// The amount of `b` in a [`MixMaterial`].
#[derive(Clone, Debug, PartialEq)]
pub enum MixAmount {
    /// One value in [0, 1].
    Constant(f32),
    /// A pattern (its channels' mean, clamped to [0, 1]).
    Pattern(Arc<PatternGraph>),
}

/// Two materials blended: `(1 - amount) a + amount b`.
pub struct MixMaterial {
    a: Box<dyn BxdfFactory>,
    b: Box<dyn BxdfFactory>,
    amount: MixAmount,
}

/// The hints a component may have: it reflects, and may read surface `u, v`.
const COMPONENT_HINTS: InstanceHints = InstanceHints::READS_SURFACE_UV;

impl MixMaterial {
    /// The blend of `a` and `b`; an error naming the component (`"a"` or `"b"`) that has an
    /// interior, transmits or has opacity.
    pub fn new(
        a: Box<dyn BxdfFactory>,
        b: Box<dyn BxdfFactory>,
        amount: MixAmount,
    ) -> Result<Self, (&'static str, String)> {
        for (key, f) in [("a", &a), ("b", &b)] {
            let extra = InstanceHints(f.instance_hints().0 & !COMPONENT_HINTS.0);
            if extra != InstanceHints::NONE {
                return Err((
                    key,
                    "a mix component must only reflect: no interior, transmission or opacity \
                     (which volume a path enters and what shadow rays see must not depend on \
                     a random choice per hit)"
                        .to_owned(),
                ));
            }
        }
        Ok(MixMaterial { a, b, amount })
    }
}

impl BxdfFactory for MixMaterial {
    fn instance_hints(&self) -> InstanceHints {
        let uv = match &self.amount {
            MixAmount::Pattern(g) if g.reads_uv() => InstanceHints::READS_SURFACE_UV,
            _ => InstanceHints::NONE,
        };
        self.a.instance_hints() | self.b.instance_hints() | uv
    }

    fn begin_scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        mode: ShadingMode,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        let n = ctx.num_points();
        let amount: &'a [f32] = match &self.amount {
            MixAmount::Constant(t) => arena.alloc_slice_fill_copy(n, t.clamp(0.0, 1.0)),
            MixAmount::Pattern(_) => match ctx.eval_param("amount") {
                Some(col) => arena.alloc_slice_fill_iter(
                    col.iter()
                        .map(|c| ((c.r + c.g + c.b) / 3.0).clamp(0.0, 1.0)),
                ),
                None => arena.alloc_slice_fill_copy(n, 0.5),
            },
        };
        let ca: &'a ShadingContext<'a> = arena.alloc(ctx.component(&*self.a, 1));
        let cb: &'a ShadingContext<'a> = arena.alloc(ctx.component(&*self.b, 2));
        arena.alloc(MixBxdf {
            a: self.a.begin_scatter(ca, mode, arena),
            b: self.b.begin_scatter(cb, mode, arena),
            fa: &*self.a,
            fb: &*self.b,
            amount,
            arena,
        })
    }

    fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        match (name, &self.amount) {
            ("amount", MixAmount::Constant(t)) => Some(ParamValue::Float(*t)),
            ("amount", MixAmount::Pattern(g)) => Some(ParamValue::Pattern(g)),
            _ => None,
        }
    }
}

/// The mixture closure ([`MixMaterial`]).
pub struct MixBxdf<'a> {
    a: &'a mut (dyn Bxdf + 'a),
    b: &'a mut (dyn Bxdf + 'a),
    fa: &'a dyn BxdfFactory,
    fb: &'a dyn BxdfFactory,
    /// The amount of `b` per point, in [0, 1].
    amount: &'a [f32],
    /// The worker's per-batch arena, for the per-point columns of each call (plain data).
    arena: &'a Bump,
}

impl Bxdf for MixBxdf<'_> {
    fn lobes(&self) -> LobeSampled {
        self.a.lobes() | self.b.lobes()
    }

    fn generate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        samplers: &mut [PathSampler],
        out: &mut BxdfSamples,
    ) {
        let n = ctx.num_points();
        let (ca, cb) = (ctx.component(self.fa, 1), ctx.component(self.fb, 2));
        // The choice first, then both components sample every point: each point's sampler
        // advances by the same dimensions whichever component it takes.
        let arena = self.arena;
        let from_b: &[bool] = arena.alloc_slice_fill_iter(
            samplers
                .iter_mut()
                .take(n)
                .zip(self.amount)
                .map(|(s, &t)| s.next_1d() < t),
        );
        self.a.generate_samples(&ca, samplers, out);
        // The table of `b`'s samples owns vectors, so it is not the arena's (no destructors).
        let mut sb = BxdfSamples::default();
        sb.reset(n);
        self.b.generate_samples(&cb, samplers, &mut sb);
        let wi: &[Vec3] =
            arena.alloc_slice_fill_iter(
                (0..n).map(|i| if from_b[i] { sb.wi[i] } else { out.wi[i] }),
            );
        let (fa, pa) = columns(arena, n);
        let (fb, pb) = columns(arena, n);
        self.a.evaluate_samples(&ca, wi, fa, pa);
        self.b.evaluate_samples(&cb, wi, fb, pb);
        for i in 0..n {
            let t = self.amount[i];
            let (chosen, p_choice) = if from_b[i] {
                (&sb, t)
            } else {
                (&*out, 1.0 - t)
            };
            let (pdf, lobe, eta, weight) = (
                chosen.pdf[i],
                chosen.lobe[i],
                chosen.eta[i],
                chosen.weight[i],
            );
            out.wi[i] = wi[i];
            out.lobe[i] = lobe;
            out.eta[i] = eta;
            if pdf <= 0.0 || p_choice <= 0.0 {
                out.pdf[i] = 0.0;
                out.weight[i] = Rgb::BLACK;
            } else if !lobe.contains(LobeSampled::DIFFUSE) {
                // A Dirac sample: no other lobe reaches its direction.
                out.pdf[i] = pdf * p_choice;
                out.weight[i] = weight;
            } else {
                let p = (1.0 - t) * pa[i] + t * pb[i];
                let f = fa[i] * (1.0 - t) + fb[i] * t;
                out.pdf[i] = p;
                out.weight[i] = if p > 0.0 { f * (1.0 / p) } else { Rgb::BLACK };
            }
        }
    }

    fn evaluate_samples(
        &mut self,
        ctx: &ShadingContext<'_>,
        wi: &[Vec3],
        value: &mut [Rgb],
        pdf: &mut [f32],
    ) {
        let n = ctx.num_points();
        let (ca, cb) = (ctx.component(self.fa, 1), ctx.component(self.fb, 2));
        self.a.evaluate_samples(&ca, wi, value, pdf);
        let (fb, pb) = columns(self.arena, n);
        self.b.evaluate_samples(&cb, wi, fb, pb);
        for i in 0..n {
            let t = self.amount[i];
            value[i] = value[i] * (1.0 - t) + fb[i] * t;
            pdf[i] = (1.0 - t) * pdf[i] + t * pb[i];
        }
    }

    fn albedo(&self, ctx: &ShadingContext<'_>, out: &mut [Rgb]) {
        let n = ctx.num_points();
        let (ca, cb) = (ctx.component(self.fa, 1), ctx.component(self.fb, 2));
        self.a.albedo(&ca, out);
        let ab = self.arena.alloc_slice_fill_copy(n, Rgb::BLACK);
        self.b.albedo(&cb, ab);
        for i in 0..n {
            let t = self.amount[i];
            out[i] = out[i] * (1.0 - t) + ab[i] * t;
        }
    }
}

/// A zeroed value column and pdf column of `n` rows in `arena`.
fn columns(arena: &Bump, n: usize) -> (&mut [Rgb], &mut [f32]) {
    (
        arena.alloc_slice_fill_copy(n, Rgb::BLACK),
        arena.alloc_slice_fill_copy(n, 0.0f32),
    )
}
