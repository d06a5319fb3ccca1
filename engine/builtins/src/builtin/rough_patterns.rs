//! Microfacet materials whose roughness (`alpha`, `alpha_u`, `alpha_v`) or, for the rough
//! conductor, complex index (`eta`, `k`) is a pattern, evaluated per shading point; and
//! `rough_plastic` with an `alpha` pattern (its coat's tables follow the roughness the same way).
//!
//! A context's lobes are built once per point into the worker's arena (one
//! [`RoughConductor`] or [`RoughDielectric`] per point), then sampled and evaluated by the
//! same closures as the constant materials' ([`super::rough`], over a slice of lobes). The energy compensation's
//! albedo tables follow the roughness through a [`RoughnessGrid`] built when the material
//! was loaded, over the interval the pattern's values lie in, and interpolated per point
//! (the interpolation error is measured in `risotto_systems::roughness_grid`'s tests). The
//! conductor's `F_avg` (Kulla & Conty's average Fresnel) is computed once when `eta` and
//! `k` are constants, and per point when either is a pattern: a table would have to span
//! `(eta, k)` per channel (two dimensions each, over ranges a pattern may make wide), while
//! the per-point 64-cosine quadrature costs about as much as one table lookup chain and is
//! exact to its 1e-4. Materials whose parameters are all numbers never reach this file.

use super::material::pattern_column;
use super::rough::{RoughConductorBxdf, RoughDielectricBxdf, RoughPlasticBxdf};
use bumpalo::Bump;
use risotto_components::Rgb;
use risotto_engine::plugin::*;
use risotto_systems::energy_compensation::AlbedoTable;
use risotto_systems::microfacet::Microfacet;
use risotto_systems::pattern::PatternGraph;
use risotto_systems::rough_conductor::{fresnel_average, RoughConductor};
use risotto_systems::rough_dielectric::RoughDielectric;
use risotto_systems::rough_plastic::{CoatTables, RoughPlastic};
use risotto_systems::roughness_grid::RoughnessGrid;
use std::sync::Arc;

/// A parameter that is one value for the whole material or a pattern graph (whose values
/// the scene loader has checked against the parameter's range by interval bounds).
#[derive(Clone, Debug, PartialEq)]
pub enum Varying<T> {
    /// The same value at every point.
    Constant(T),
    /// A pattern, evaluated per point through the context's cache.
    Pattern(Arc<PatternGraph>),
}

impl<T: Copy> Varying<T> {
    /// The graph, if a pattern.
    fn pattern(&self) -> Option<&PatternGraph> {
        match self {
            Varying::Constant(_) => None,
            Varying::Pattern(g) => Some(g),
        }
    }

    /// The parameter over `ctx`'s points: a constant (`Err`) or the pattern's column
    /// (`Ok`), read through the context's cache under the parameter's `name`.
    fn column<'a>(
        &self,
        ctx: &ShadingContext<'a>,
        name: &str,
        arena: &'a Bump,
    ) -> Result<&'a [Rgb], T> {
        match self {
            Varying::Constant(v) => Err(*v),
            Varying::Pattern(g) => Ok(pattern_column(ctx, name, g, arena)),
        }
    }
}

/// A column or a constant, read at point `i` (a grey pattern's first channel for a
/// number).
fn at<T: Copy>(v: &Result<&[Rgb], T>, i: usize, grey: impl Fn(Rgb) -> T) -> T {
    match v {
        Ok(column) => grey(column[i]),
        Err(c) => *c,
    }
}

/// The roughness of a microfacet lobe, a number or a grey pattern per axis.
#[derive(Clone, Debug, PartialEq)]
pub struct VaryingRoughness {
    /// The distribution's family (its roughness is replaced per point).
    pub family: Microfacet,
    /// `alpha` (isotropic) or `alpha_u`.
    pub alpha_u: Varying<f32>,
    /// `alpha_v`; `None` for an isotropic lobe (`alpha_v = alpha_u`).
    pub alpha_v: Option<Varying<f32>>,
}

impl VaryingRoughness {
    /// The scene-file keys of the two roughnesses (`alpha` for an isotropic lobe).
    fn keys(&self) -> (&'static str, &'static str) {
        match self.alpha_v {
            None => ("alpha", "alpha"),
            Some(_) => ("alpha_u", "alpha_v"),
        }
    }

    /// The pattern of parameter `name`, if the roughness has one under that name.
    fn param(&self, name: &str) -> Option<&PatternGraph> {
        let (u, v) = self.keys();
        match (&self.alpha_v, name) {
            (_, n) if n == u => self.alpha_u.pattern(),
            (Some(alpha_v), n) if n == v => alpha_v.pattern(),
            _ => None,
        }
    }

    /// True when a pattern reads `uv`.
    fn reads_uv(&self) -> bool {
        let reads = |v: &Varying<f32>| v.pattern().is_some_and(|g| g.reads_uv());
        reads(&self.alpha_u) || self.alpha_v.as_ref().is_some_and(reads)
    }

    /// One lobe per point of `ctx`, in the arena: `make(i, distribution, alpha_u,
    /// alpha_v)` with the point's roughnesses and its distribution of the family.
    fn per_point<'a, T>(
        &self,
        ctx: &ShadingContext<'a>,
        arena: &'a Bump,
        make: impl Fn(usize, Microfacet, f32, f32) -> T,
    ) -> &'a [T] {
        let (ku, kv) = self.keys();
        let u = self.alpha_u.column(ctx, ku, arena);
        let v = self.alpha_v.as_ref().map(|v| v.column(ctx, kv, arena));
        arena.alloc_slice_fill_with(ctx.num_points(), |i| {
            let au = at(&u, i, |c| c.r);
            let av = v.as_ref().map_or(au, |v| at(v, i, |c| c.r));
            make(i, self.family.with_alphas(au, av), au, av)
        })
    }
}

/// `rough_conductor` with a roughness or complex-index pattern.
#[derive(Clone, Debug, PartialEq)]
pub struct VaryingConductor {
    /// The roughness.
    pub roughness: VaryingRoughness,
    /// Real part of the complex index per channel.
    pub eta: Varying<Rgb>,
    /// Imaginary part per channel.
    pub k: Varying<Rgb>,
    /// Fresnel tint (`specular_reflectance`).
    pub tint: Rgb,
    /// The white lobe's albedo tables over the roughness interval, when energy
    /// compensation is on.
    pub grid: Option<RoughnessGrid<AlbedoTable>>,
}

impl VaryingConductor {
    /// The per-point lobes over `ctx`.
    fn lobes<'a>(&self, ctx: &ShadingContext<'a>, arena: &'a Bump) -> &'a [RoughConductor] {
        let eta = self.eta.column(ctx, "eta", arena);
        let k = self.k.column(ctx, "k", arena);
        // F_avg once when the index is constant (module docs).
        let shared_f_avg = match (&eta, &k, &self.grid) {
            (Err(eta), Err(k), Some(_)) => Some(fresnel_average(*eta, *k)),
            _ => None,
        };
        self.roughness
            .per_point(ctx, arena, |i, distribution, au, av| {
                let (eta, k) = (at(&eta, i, |c| c), at(&k, i, |c| c));
                let table = self.grid.as_ref().map(|g| g.at(au, av));
                RoughConductor::with_table(distribution, eta, k, self.tint, table, || {
                    shared_f_avg.unwrap_or_else(|| fresnel_average(eta, k))
                })
            })
    }

    /// The instance hints' share of the patterns.
    pub fn hints(&self) -> InstanceHints {
        let reads = |v: &Varying<Rgb>| v.pattern().is_some_and(|g| g.reads_uv());
        if self.roughness.reads_uv() || reads(&self.eta) || reads(&self.k) {
            InstanceHints::READS_SURFACE_UV
        } else {
            InstanceHints::NONE
        }
    }

    /// The pattern of parameter `name` (`alpha`, `alpha_u`, `alpha_v`, `eta`, `k`).
    pub fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        let graph = match name {
            "eta" => self.eta.pattern(),
            "k" => self.k.pattern(),
            _ => self.roughness.param(name),
        };
        graph.map(ParamValue::Pattern)
    }

    /// The closure at the points of `ctx`.
    pub fn scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        arena.alloc(RoughConductorBxdf {
            lobe: self.lobes(ctx, arena),
        })
    }
}

/// `rough_dielectric` with a roughness pattern.
#[derive(Clone, Debug, PartialEq)]
pub struct VaryingDielectric {
    /// The roughness.
    pub roughness: VaryingRoughness,
    /// The material's index (against vacuum).
    pub eta: f32,
    /// Multiplies transmitted light.
    pub tint: Rgb,
    /// The albedo tables seen from outside (`eta`) and inside (`1 / eta`) over the
    /// roughness interval, when energy compensation is on.
    pub grid: Option<RoughnessGrid<[AlbedoTable; 2]>>,
}

impl VaryingDielectric {
    /// The instance hints' share of the patterns (the surface transmits).
    pub fn hints(&self) -> InstanceHints {
        if self.roughness.reads_uv() {
            InstanceHints::TRANSMITS | InstanceHints::READS_SURFACE_UV
        } else {
            InstanceHints::TRANSMITS
        }
    }

    /// The pattern of parameter `name` (`alpha`, `alpha_u`, `alpha_v`).
    pub fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        self.roughness.param(name).map(ParamValue::Pattern)
    }

    /// The closure at the points of `ctx`: per point, the lobe at the material's index
    /// with interpolated tables ([`RoughDielectricBxdf`] applies the outside's index).
    pub fn scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        let lobes = self
            .roughness
            .per_point(ctx, arena, |_, distribution, au, av| {
                let tables = self.grid.as_ref().map(|g| g.at(au, av));
                RoughDielectric::with_tables(distribution, self.eta, self.tint, tables)
            });
        arena.alloc(RoughDielectricBxdf { lobe: lobes })
    }
}

/// `rough_plastic` with a roughness pattern (isotropic, as the constant one).
#[derive(Clone, Debug, PartialEq)]
pub struct VaryingPlastic {
    /// The roughness (`alpha_v` is `None`).
    pub roughness: VaryingRoughness,
    /// `n_coat / n_outside`.
    pub eta: f32,
    /// The coat's specular colour.
    pub specular: Rgb,
    /// The internal-scattering model ([`RoughPlastic::nonlinear`]).
    pub nonlinear: bool,
    /// The coat's tables over the roughness interval.
    pub grid: RoughnessGrid<CoatTables>,
    /// The base's reflectance.
    pub diffuse: Varying<Rgb>,
}

impl VaryingPlastic {
    /// The instance hints' share of the patterns.
    pub fn hints(&self) -> InstanceHints {
        let diffuse = self.diffuse.pattern().is_some_and(|g| g.reads_uv());
        if self.roughness.reads_uv() || diffuse {
            InstanceHints::READS_SURFACE_UV
        } else {
            InstanceHints::NONE
        }
    }

    /// The parameter `name` (`alpha`, `diffuse_reflectance`).
    pub fn param(&self, name: &str) -> Option<ParamValue<'_>> {
        match (name, &self.diffuse) {
            ("diffuse_reflectance", Varying::Constant(c)) => Some(ParamValue::Color(*c)),
            ("diffuse_reflectance", Varying::Pattern(g)) => Some(ParamValue::Pattern(g)),
            _ => self.roughness.param(name).map(ParamValue::Pattern),
        }
    }

    /// The closure at the points of `ctx`: a coat per point with interpolated tables.
    pub fn scatter<'a>(
        &'a self,
        ctx: &'a ShadingContext<'a>,
        arena: &'a Bump,
    ) -> &'a mut (dyn Bxdf + 'a) {
        let coats = self
            .roughness
            .per_point(ctx, arena, |_, distribution, a, _| {
                let tables = self.grid.at(a, a);
                RoughPlastic::with_tables(
                    distribution,
                    self.eta,
                    self.specular,
                    self.nonlinear,
                    tables,
                )
            });
        match self.diffuse.column(ctx, "diffuse_reflectance", arena) {
            Err(diffuse) => arena.alloc(RoughPlasticBxdf {
                lobe: coats,
                diffuse,
            }),
            Ok(diffuse) => arena.alloc(RoughPlasticBxdf {
                lobe: coats,
                diffuse,
            }),
        }
    }
}
