//! Opacity (the seed's opacity shaders): a surface whose material has
//! [`InstanceHints::OPACITY`](crate::plugin::InstanceHints::OPACITY) is present with
//! probability `a`, its `opacity` parameter, evaluated through the shading context's
//! parameter cache like any other parameter.
//!
//! The two estimators of the same transport, and why they differ:
//! - **Path rays** (camera and indirect) pass the surface unchanged with probability `1 - a`
//!   and scatter with probability `a` (the path tracer's pass-through stage). The choice's
//!   probability cancels the weight `1 - a` (or `a`) of each branch, so the throughput does
//!   not change: an unbiased, Russian-roulette-like choice between "no surface" and "the
//!   surface" (pbrt-v4's stochastic alpha test, Mitsuba's `mask` with its null lobe).
//! - **Shadow rays** are multiplied by `1 - a` at each crossing (`crate::transmission`),
//!   in addition to the volumes' `transmission`. The expectation is the same as passing
//!   stochastically, `E[1{u >= a}] = 1 - a`, but a deterministic factor adds no variance
//!   (a stochastic pass would turn a 50% leaf into a 0-or-1 shadow per sample), and shadow
//!   rays have no later choice for the probability to be spent on.
//!
//! A light sample's MIS weight uses the Bxdf's and the light's pdfs only: passing through a
//! surface is not a change of direction, so a Bxdf-sampled ray that reaches an emitter
//! through a cut-out carries the same pdf as the shadow ray towards the same point, and the
//! two estimates stay consistent. Emission of a surface with opacity is not masked
//! (Mitsuba's `mask` wraps the Bxdf only; its area emitter emits everywhere): a path ray
//! collects it whether it then passes or scatters, and a light sample on it is not
//! attenuated by its own opacity.

pub use crate::plugin::{opacity_of, opacity_parameter};
use crate::plugin::{ParamCache, PatternCounters, ShadingContext};
use crate::scene::CompiledScene;
use crate::shade_groups::ShadingMode;
use bumpalo::Bump;
use risotto_components::{Rgb, ShadingPoints};
use std::ops::Range;

/// Seed salt of the opacity choices' sampler sequence: each choice draws dimension
/// `dimension + passes` of the ray (its vertex's first dimension and how many surfaces it
/// has passed since) from a sequence of its own, so that no other dimension of the path
/// moves (scenes without opacity render byte for byte as before) and successive crossings
/// draw different dimensions.
pub const OPACITY_SEED_SALT: u32 = 0x2c1b_3c6d;

/// Whether a ray with uniform sample `u` in [0, 1) passes a surface of opacity `a`: with
/// probability `1 - a` (never when `a = 1`, always when `a = 0`).
#[inline]
pub fn passes(u: f32, a: f32) -> bool {
    u >= a
}

/// The opacity of rows `range` of `points` (all of `material`), through a shading context
/// with the material's factory and a parameter cache in `arena` counting into `counters`,
/// written to `out` (one per row): what the factory's
/// [`BxdfFactory::opacity`](crate::plugin::BxdfFactory::opacity) answers (by default its
/// `opacity` parameter; a material without one is opaque).
pub fn eval_opacity(
    scene: &CompiledScene,
    points: &ShadingPoints,
    range: Range<usize>,
    material: u32,
    arena: &Bump,
    counters: &PatternCounters,
    out: &mut Vec<f32>,
) {
    out.clear();
    let factory = scene.materials[material as usize].factory.as_ref();
    let cache = ParamCache::new(arena, counters);
    let n = range.len();
    let ctx = ShadingContext::new(points, range, ShadingMode::Scatter, material, &[])
        .with_factory(factory)
        .with_cache(&cache);
    out.resize(n, 1.0);
    factory.opacity(&ctx, out);
    for a in out.iter_mut() {
        // A user's factory may answer anything: a probability is clamped (NaN is opaque).
        *a = if a.is_nan() { 1.0 } else { a.clamp(0.0, 1.0) };
    }
}

/// A shadow ray's crossing of a surface with opacity, as the transmission walk finds it:
/// the ray (a row of the walk's tables), the hit as [`intersect_all`] wrote it, and the
/// surface's material and shape.
///
/// [`intersect_all`]: risotto_systems::intersect::intersect_all
#[derive(Clone, Copy, Debug)]
pub struct ShadowCrossing {
    /// Shadow-ray row.
    pub ray: u32,
    /// Primitive hit.
    pub prim: u32,
    /// Hit distance and barycentrics (or a sphere's root residual).
    pub t: f32,
    /// See `t`.
    pub b1: f32,
    /// See `t`.
    pub b2: f32,
    /// The surface's material.
    pub material: u32,
    /// The surface's shape.
    pub shape: u32,
    /// Index of refraction outside the surface, from the shadow ray's volume stack (as the
    /// trace stage gives path rays' points: a pane's reflectance depends on it).
    pub ior_outside: f32,
}

/// The buffers of [`attenuate_shadow_crossings`], kept by the walk's scratch so that a walk
/// allocates nothing once they have grown.
#[derive(Default)]
pub struct CrossingScratch {
    /// This round's crossings.
    pub crossings: Vec<ShadowCrossing>,
    points: ShadingPoints,
    opacity: Vec<f32>,
}

/// Multiplies `contribution` and `transmittance` of each crossing's shadow ray by the
/// fraction of light the surface lets through, `(1 - a) + a T` for opacity `a` at the hit and
/// the material's shadow transmittance `T` (black unless it also has
/// [`InstanceHints::TRANSMISSION_SHADOWS`](crate::plugin::InstanceHints::TRANSMISSION_SHADOWS)):
/// the surface is absent with probability `1 - a`, present with `a` (module docs: why shadow
/// rays take the expectation instead of a stochastic choice). The hits become shading
/// points (position, normal, `u`, `v` as the trace stage writes them), grouped by material,
/// and each group's opacity is evaluated through a parameter cache as for path rays.
#[allow(clippy::too_many_arguments, reason = "the walk's tables, named")]
pub fn attenuate_shadow_crossings(
    scene: &CompiledScene,
    origin: &[glam::Vec3],
    direction: &[glam::Vec3],
    scratch: &mut CrossingScratch,
    arena: &Bump,
    counters: &PatternCounters,
    contribution: &mut [Rgb],
    transmittance: &mut [Rgb],
) {
    let CrossingScratch {
        crossings,
        points,
        opacity,
    } = scratch;
    if crossings.is_empty() {
        return;
    }
    crossings.sort_by_key(|c| c.material);
    points.clear();
    let geometry = &scene.geometry;
    for c in crossings.iter() {
        let i = c.ray as usize;
        let (o, d) = (origin[i], direction[i]);
        let s = geometry.surface_at(c.prim, o, d, c.t, c.b1, c.b2);
        let is_triangle = geometry
            .triangles()
            .surface_at(c.prim, c.b1, c.b2)
            .is_some();
        let is_sphere = !is_triangle && geometry.is_sphere(c.prim);
        // As the trace stage writes them (`context::write_surfaces`): sphere parameters only
        // in scenes where some material reads them (a primitive of an instance gets its
        // object's parameters as there).
        let mut uv = if !is_triangle && (!is_sphere || scene.features.surface_uv) {
            geometry.surface_uv(c.prim, o, d, c.t, c.b1, c.b2)
        } else {
            s.uv
        };
        // A mesh's own normals, tangent and texture coordinates, as
        // `context::write_mesh_attributes` gives the trace stage's points: an alpha texture
        // on a mesh is looked up where camera rays see it.
        use risotto_systems::mesh_attributes::arbitrary_tangent;
        let (mut nn, mut tangent) = match is_triangle {
            true => (s.ng, arbitrary_tangent(s.ng)),
            false => (s.ng, geometry.tangent_at(c.prim, s.ng)),
        };
        if !is_sphere {
            if let Some(a) = geometry.mesh_shading(c.prim, c.b1, c.b2, s.ng) {
                (nn, tangent) = (a.nn, a.tangent);
                uv = a.uv.unwrap_or(uv);
            }
        }
        points.push(risotto_components::ShadingPointRow {
            p: s.p,
            ng: s.ng,
            p_offset: s.offset(),
            terminator_lift: glam::Vec3::ZERO,
            nn,
            tangent,
            vn: -d,
            vlen: c.t,
            u: uv.x,
            v: uv.y,
            w: 0.0,
            transmission: Rgb::WHITE,
            ray_id: c.ray,
            material: c.material,
            shape: c.shape,
            front_face: d.dot(s.ng) < 0.0,
            ior_outside: c.ior_outside,
        });
    }
    let mut start = 0;
    while start < crossings.len() {
        let material = crossings[start].material;
        let end = start
            + crossings[start..]
                .iter()
                .take_while(|c| c.material == material)
                .count();
        eval_opacity(
            scene,
            points,
            start..end,
            material,
            arena,
            counters,
            opacity,
        );
        let through = scene.material_info[material as usize].shadow_transmittance;
        let through = match scene.material_info[material as usize]
            .hints
            .contains(crate::plugin::InstanceHints::TRANSMISSION_SHADOWS)
        {
            true => through,
            false => Rgb::BLACK,
        };
        for (c, &a) in crossings[start..end].iter().zip(opacity.iter()) {
            let factor = Rgb::splat(1.0 - a) + through * a;
            contribution[c.ray as usize] *= factor;
            transmittance[c.ray as usize] *= factor;
        }
        start = end;
    }
    crossings.clear();
}
