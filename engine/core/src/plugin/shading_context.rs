//! The shading context (RIS `RixShadingContext`): a group of shading points with the builtins
//! as columns, the parameter cache a Bxdf and a volume integrator bound to the same context
//! share, and the mutable volume-sampling child context of the seed's "Shading in a Volume"
//! (`BeginVolumeSampling` / `SetBuiltinVar` / `EndVolumeSampling`).
//!
//! # Parameters and the cache
//!
//! [`ShadingContext::eval_param`] evaluates a material parameter (what the factory answers
//! in [`BxdfFactory::param`]) for every point of the context, once: the column is kept in the
//! context's [`ParamCache`] (keyed by material and name, its columns in the worker's
//! per-batch arena), so a Bxdf and a volume integrator pulling the same parameter on one
//! context evaluate it once; an interior entered from a shaded surface shares that
//! surface's cache ([`ParamCache::sharing`]).
//! A parameter is a constant or a pattern graph ([`ParamValue::Pattern`], a
//! [`risotto_systems::pattern::PatternGraph`] the factory owns), evaluated over the context's
//! `P`, `u` and `v` columns at once. Lookups and evaluations are counted
//! ([`PatternCounters`], in the stats as `pattern_cache_hits`, `pattern_cache_shared` and
//! `pattern_evals`). Setting a builtin on a volume-sampling context flushes its cache
//! (patterns may depend on `P`, `u`, `v`, `w`).
//!
//! # Shading in a volume
//!
//! ```
//! # use risotto_engine::plugin::*;
//! # use risotto_components::{ShadingPoints, ShadingPointRow, Rgb};
//! # use glam::Vec3;
//! # let mut table = ShadingPoints::default();
//! # for i in 0..3 { table.push(ShadingPointRow::in_volume(Vec3::ZERO, Vec3::X, i, 0)); }
//! # let ctx = ShadingContext::new(&table, 0..3, ShadingMode::Interior, 0, &[])
//! #     .with_volume_bounds(Vec3::splat(-1.0), Vec3::splat(1.0));
//! // Inside a volume integrator's `nearest_hits`: a child context at points along the rays.
//! let mut vctx = ctx.begin_volume_sampling();
//! let p: Vec<Vec3> = (0..3).map(|i| Vec3::new(0.25 * i as f32, 0.0, 0.0)).collect();
//! vctx.set_builtin(Builtin::P, &p); // also moves u, v, w with P
//! assert_eq!(vctx.context().u()[2], 0.75); // (0.5 - (-1)) / 2
//! // Keep the first and the last point as a VolumeScatter group for the path tracer.
//! let mut out = ShadeGroups::default();
//! vctx.end_volume_sampling(&[true, false, true], &mut out);
//! assert_eq!(out.groups[0].mode, ShadingMode::VolumeScatter);
//! assert_eq!(out.points.len(), 2);
//! ```

pub use super::param_cache::{ParamCache, PatternCounters};
use super::param_cache::{ParamLookup, PatternInputs};
pub use super::volume_space::VolumeSpace;
use crate::plugin::{BxdfFactory, VolumeIntegrator};
use crate::shade_groups::{ShadeGroups, ShadingMode};
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::{Rgb, ShadingPoints, VolumeEntry};
use risotto_systems::pattern::PatternGraph;
use std::ops::Range;

/// Another volume overlapping the innermost one, with its own integrator (built by the
/// renderer through its factory's `begin_interior`).
pub struct OverlappingVolume<'a> {
    /// Which volume.
    pub entry: VolumeEntry,
    /// Its factory.
    pub factory: &'a dyn BxdfFactory,
    /// Its integrator (None when its factory computes no interior).
    pub integrator: Option<&'a (dyn VolumeIntegrator + 'a)>,
}

/// A material parameter's value as its factory gives it (RIS: a parameter's connection):
/// a constant, or a pattern graph borrowed from the factory (a reference, so the value stays
/// plain `Copy` data that contexts in the arena can hold).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamValue<'a> {
    /// One number for every point (broadcast to all three channels).
    Float(f32),
    /// One colour for every point.
    Color(Rgb),
    /// A pattern graph, evaluated at the context's `P`, `u`, `v`.
    Pattern(&'a PatternGraph),
}

/// Components a material built of others may have per level ([`ShadingContext::component`]).
/// The component path is kept in 8 bits: components nest at most 3 levels deep.
pub const MAX_COMPONENTS: u32 = 3;

/// A group of shading points that share a material, with the RIS builtins as columns
/// (`P`, `Ng`, `Nn`, `Vn`, `VLen`, `u`, `v`, `w`, `transmission`, ray id).
pub struct ShadingContext<'a> {
    points: &'a ShadingPoints,
    range: Range<usize>,
    mode: ShadingMode,
    material: u32,
    overlapping: &'a [OverlappingVolume<'a>],
    factory: Option<&'a dyn BxdfFactory>,
    cache: Option<&'a dyn ParamLookup>,
    /// Where the cache's columns go and what it counts into (for child contexts' caches).
    cache_parts: Option<(&'a Bump, &'a PatternCounters)>,
    volume_space: Option<VolumeSpace>,
    /// Shading normals that replace the points' own ([`ShadingContext::with_shading_normals`]).
    nn: Option<&'a [Vec3]>,
    /// 0 for the material itself; `k` for its `k`-th component material
    /// ([`ShadingContext::component`]), whose parameters are cached apart.
    component: u32,
}

impl<'a> ShadingContext<'a> {
    /// A context over rows `range` of `points`.
    pub fn new(
        points: &'a ShadingPoints,
        range: Range<usize>,
        mode: ShadingMode,
        material: u32,
        overlapping: &'a [OverlappingVolume<'a>],
    ) -> Self {
        ShadingContext {
            points,
            range,
            mode,
            material,
            overlapping,
            factory: None,
            cache: None,
            cache_parts: None,
            volume_space: None,
            nn: None,
            component: 0,
        }
    }
    /// Binds the factory of the context's material: [`eval_param`](Self::eval_param) asks it
    /// for parameters.
    pub fn with_factory(mut self, factory: &'a dyn BxdfFactory) -> Self {
        self.factory = Some(factory);
        self
    }
    /// Binds a parameter cache, where [`eval_param`](Self::eval_param) keeps its columns
    /// (without one it returns `None`). The renderer binds one to every context it makes.
    pub fn with_cache<'c: 'a>(mut self, cache: &'a ParamCache<'c>) -> Self {
        self.cache = Some(cache);
        self.cache_parts = Some((cache.arena, cache.counters));
        self
    }
    /// Sets the bounds of the volume the context's points are in, for a shape written in
    /// world coordinates (object space = world space; [`VolumeSpace::world`]):
    /// volume-sampling contexts derive `u, v, w` from them.
    pub fn with_volume_bounds(self, min: Vec3, max: Vec3) -> Self {
        self.with_volume_space(VolumeSpace::world(min, max))
    }
    /// Sets the object space of the volume the context's points are in (its shape's
    /// transform and object-space bounds): volume-sampling contexts derive `u, v, w` from
    /// it. The renderer binds the space of the shape whose interior it is.
    pub fn with_volume_space(mut self, space: VolumeSpace) -> Self {
        self.volume_space = Some(space);
        self
    }
    /// Number of points (RIS `numPts`).
    pub fn num_points(&self) -> usize {
        self.range.len()
    }
    /// The bounds `u, v, w` are measured in, in the volume's object space
    /// ([`VolumeSpace::bounds`]), if set; for the world-space box use
    /// [`volume_space`](Self::volume_space)'s `world_bounds`.
    pub fn volume_bounds(&self) -> Option<(Vec3, Vec3)> {
        self.volume_space.map(|s| s.bounds)
    }
    /// The object space of the volume ([`with_volume_space`](Self::with_volume_space)): its
    /// bounds and transforms, what `u, v, w` and a medium's grids are measured in; `None`
    /// when not set.
    pub fn volume_space(&self) -> Option<VolumeSpace> {
        self.volume_space
    }
    /// Why this context exists.
    pub fn mode(&self) -> ShadingMode {
        self.mode
    }
    /// Material (factory) index of every point.
    pub fn material(&self) -> u32 {
        self.material
    }
    /// The factory bound to the context, if any.
    pub fn factory(&self) -> Option<&'a dyn BxdfFactory> {
        self.factory
    }
    /// The table and rows the context's builtins come from.
    pub fn rows(&self) -> (&'a ShadingPoints, Range<usize>) {
        (self.points, self.range.clone())
    }
    /// Positions `P`.
    pub fn p(&self) -> &'a [Vec3] {
        &self.points.p[self.range.clone()]
    }
    /// Geometric normals `Ng`.
    pub fn ng(&self) -> &'a [Vec3] {
        &self.points.ng[self.range.clone()]
    }
    /// Error offsets of the positions along `Ng` (`dot(|Ng|, p_error)`, 0 inside volumes):
    /// what rays spawned here move off the surface by (`risotto_systems::ray::spawn_origin`).
    pub fn p_offset(&self) -> &'a [f32] {
        &self.points.p_offset[self.range.clone()]
    }
    /// Shading normals `Nn` (those of [`with_shading_normals`](Self::with_shading_normals)
    /// in such a view).
    pub fn nn(&self) -> &'a [Vec3] {
        match self.nn {
            None => &self.points.nn[self.range.clone()],
            Some(nn) => nn,
        }
    }
    /// A view of this context whose shading normals are `nn` (one per point) instead of the
    /// points' own: the same points, mode, factory and parameter cache, so patterns are
    /// evaluated once for both. What a two-sided closure hands the one-sided closure it
    /// wraps, with the normals that face away from the viewer flipped (Mitsuba 3's
    /// `twosided` flips the local frame the same way). Only [`nn`](Self::nn) changes:
    /// [`rows`](Self::rows) still gives the table's own columns.
    ///
    /// # Panics
    /// When `nn` does not have one entry per point.
    pub fn with_shading_normals<'b>(&self, nn: &'b [Vec3]) -> ShadingContext<'b>
    where
        'a: 'b,
    {
        assert_eq!(nn.len(), self.range.len(), "one shading normal per point");
        ShadingContext {
            nn: Some(nn),
            ..self.view()
        }
    }

    /// This context, borrowed for a shorter lifetime: the base of the derived views
    /// ([`Self::with_shading_normals`], [`Self::component`]), which replace a field or two.
    fn view<'b>(&self) -> ShadingContext<'b>
    where
        'a: 'b,
    {
        ShadingContext {
            points: self.points,
            range: self.range.clone(),
            mode: self.mode,
            material: self.material,
            overlapping: self.overlapping,
            factory: self.factory,
            cache: self.cache,
            cache_parts: self.cache_parts,
            volume_space: self.volume_space,
            nn: self.nn,
            component: self.component,
        }
    }

    /// The same points seen by component `index` (1 to [`MAX_COMPONENTS`]) of the context's
    /// material: a material built of other materials (a `mix`) hands each its own view, in
    /// which [`eval_param`](Self::eval_param) asks `factory` (the component's) and caches its
    /// columns apart from the material's and the other components' (so two components may
    /// both have a `reflectance`).
    ///
    /// # Panics
    /// When `index` is 0 or above [`MAX_COMPONENTS`].
    pub fn component<'b>(&self, factory: &'b dyn BxdfFactory, index: u32) -> ShadingContext<'b>
    where
        'a: 'b,
    {
        assert!(
            (1..=MAX_COMPONENTS).contains(&index),
            "component {index} of a material (1 to {MAX_COMPONENTS})"
        );
        ShadingContext {
            factory: Some(factory),
            component: self.component * (MAX_COMPONENTS + 1) + index,
            ..self.view()
        }
    }

    /// The parameter cache's key of this context's parameters: the material, and the
    /// component path in the high bits (materials number below 2^24).
    fn param_owner(&self) -> u32 {
        self.material | (self.component << 24)
    }
    /// Unit tangents orthogonal to `Nn`, one per point: with `Nn` they fix the frame of an
    /// anisotropic Bxdf (`s = tangent`, `t = Nn x tangent`), so its roughness along `s`
    /// follows the texture's `u` direction. On meshes with texture coordinates it is `dP/du`
    /// made orthogonal to `Nn`; on spheres the direction of increasing `phi` (`u`); elsewhere
    /// (meshes without uvs, quads, boxes, points inside volumes) some unit vector orthogonal
    /// to `Nn` that varies continuously with it.
    pub fn tangent(&self) -> &'a [Vec3] {
        &self.points.tangent[self.range.clone()]
    }
    /// Directions towards the viewer `Vn`.
    pub fn vn(&self) -> &'a [Vec3] {
        &self.points.vn[self.range.clone()]
    }
    /// Incident segment lengths `VLen`.
    pub fn vlen(&self) -> &'a [f32] {
        &self.points.vlen[self.range.clone()]
    }
    /// Parameters `u`.
    pub fn u(&self) -> &'a [f32] {
        &self.points.u[self.range.clone()]
    }
    /// Parameters `v`.
    pub fn v(&self) -> &'a [f32] {
        &self.points.v[self.range.clone()]
    }
    /// Parameters `w`.
    pub fn w(&self) -> &'a [f32] {
        &self.points.w[self.range.clone()]
    }
    /// Transmission over each point's incident segment.
    pub fn transmission(&self) -> &'a [Rgb] {
        &self.points.transmission[self.range.clone()]
    }
    /// Index of the ray that produced each point.
    pub fn ray_id(&self) -> &'a [u32] {
        &self.points.ray_id[self.range.clone()]
    }
    /// Whether each ray arrived on the front face.
    pub fn front_face(&self) -> &'a [bool] {
        &self.points.front_face[self.range.clone()]
    }
    /// IOR of the medium outside each point's shape (see
    /// [`ShadingPointRow::ior_outside`](risotto_components::ShadingPointRow::ior_outside)).
    pub fn ior_outside(&self) -> &'a [f32] {
        &self.points.ior_outside[self.range.clone()]
    }
    /// Shape index of each point (`u32::MAX` inside volumes).
    pub fn shape(&self) -> &'a [u32] {
        &self.points.shape[self.range.clone()]
    }
    /// The other volumes that overlap this context's volume (RIS `GetOverlappingVolumes`).
    pub fn overlapping_volumes(&self) -> &'a [OverlappingVolume<'a>] {
        self.overlapping
    }

    /// Material parameter `name` at every point (RIS `EvalParam`), evaluated once per context
    /// and cached (see the module docs). `None` when the context has no factory or cache
    /// bound, or the factory has no such parameter.
    pub fn eval_param(&self, name: &str) -> Option<&'a [Rgb]> {
        let value = self.factory?.param(name)?;
        let cache = self.cache?;
        let at = PatternInputs {
            p: self.p(),
            u: self.u(),
            v: self.v(),
        };
        let in_volume = self.mode != ShadingMode::Scatter;
        Some(cache.column(self.param_owner(), name, value, at, in_volume))
    }

    /// Counts `n` pattern evaluations made outside [`eval_param`](Self::eval_param) (a
    /// volume integrator evaluating a pattern coefficient point by point) into the
    /// context's cache counters (the stats' `pattern_evals` and `volume_pattern_evals`);
    /// without a cache, nothing.
    pub fn count_pattern_evals(&self, n: u64) {
        if let Some((_, counters)) = self.cache_parts {
            counters.evals.set(counters.evals.get() + n);
            counters.volume_evals.set(counters.volume_evals.get() + n);
        }
    }

    /// Starts shading inside the volume (RIS `BeginVolumeSampling`): a mutable child context
    /// that inherits this context's builtins, except `u, v, w`, which are the position of `P`
    /// in the volume's object space relative to its bounds
    /// ([`with_volume_space`](Self::with_volume_space); 0 without one). It has its own parameter cache, flushed whenever a builtin is set.
    pub fn begin_volume_sampling(&self) -> VolumeSampling<'a> {
        let mut points = ShadingPoints::with_capacity(self.num_points());
        points.extend_from_range(self.points, self.range.clone());
        let cache = self
            .cache_parts
            .map(|(arena, counters)| ParamCache::new(arena, counters));
        let mut v = VolumeSampling {
            points,
            material: self.material,
            factory: self.factory,
            cache,
            volume_space: self.volume_space,
        };
        v.update_uvw();
        v
    }
}

/// A builtin a volume-sampling context can replace (RIS `SetBuiltinVar`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builtin {
    /// Position; also moves `u, v, w` (derived from it).
    P,
    /// Direction towards the viewer.
    Vn,
    /// Volume parameter `u`.
    U,
    /// Volume parameter `v`.
    V,
    /// Volume parameter `w`.
    W,
}

/// The mutable child context of [`ShadingContext::begin_volume_sampling`]: its own copy of
/// the points (owned: it lives on the volume integrator's stack, not in the arena) and its own
/// parameter cache. [`context`](Self::context) views it as a [`ShadingMode::VolumeScatter`]
/// context (for building the phase function, [`ShadingContext::eval_param`], or the lighting
/// delegate); [`end_volume_sampling`](Self::end_volume_sampling) hands the points that stay
/// to the global integrator.
pub struct VolumeSampling<'a> {
    points: ShadingPoints,
    material: u32,
    factory: Option<&'a dyn BxdfFactory>,
    cache: Option<ParamCache<'a>>,
    volume_space: Option<VolumeSpace>,
}

impl<'a> VolumeSampling<'a> {
    /// Number of points.
    pub fn num_points(&self) -> usize {
        self.points.len()
    }

    /// Replaces builtin `b` with `values` (one per point) and flushes the parameter cache.
    /// Vector builtins take [`Vec3`]s; `u`, `v`, `w` take their value in `x`.
    ///
    /// # Panics
    /// When `values` has not one entry per point.
    pub fn set_builtin(&mut self, b: Builtin, values: &[Vec3]) {
        assert_eq!(values.len(), self.points.len(), "one value per point");
        match b {
            Builtin::P => {
                self.points.p.copy_from_slice(values);
                self.update_uvw();
            }
            Builtin::Vn => {
                self.points.vn.copy_from_slice(values);
                // Inside a volume the normals face the viewer (no surface).
                self.points.nn.copy_from_slice(values);
                self.points.ng.copy_from_slice(values);
                for (t, &n) in self.points.tangent.iter_mut().zip(values) {
                    *t = n.any_orthonormal_vector();
                }
            }
            Builtin::U => set_scalar(&mut self.points.u, values),
            Builtin::V => set_scalar(&mut self.points.v, values),
            Builtin::W => set_scalar(&mut self.points.w, values),
        }
        if let Some(c) = &self.cache {
            c.flush();
        }
    }

    /// Sets the incident segment length of every point (`VLen`: the distance the ray
    /// travelled to the point inside the volume).
    pub fn set_vlen(&mut self, vlen: &[f32]) {
        self.points.vlen.copy_from_slice(vlen);
    }

    /// Moves every point to distance `t[i]` along ray `i` of `rays` (the rays this context's
    /// points start on): `P = origin + t direction` and `VLen = t`, where free flights
    /// stopped.
    ///
    /// # Panics
    /// When `rays` and `t` do not have one entry per point.
    pub fn set_along_rays(&mut self, rays: &risotto_components::Rays, t: &[f32]) {
        assert_eq!(rays.len(), t.len(), "one distance per ray");
        let p: Vec<Vec3> = (0..rays.len())
            .map(|i| rays.origin[i] + rays.direction[i] * t[i])
            .collect();
        self.set_builtin(Builtin::P, &p);
        self.set_vlen(t);
    }

    /// Sets the transmission of every point's incident segment (what the global integrator
    /// multiplies into the path: for a free-flight sample, the estimator's weight).
    pub fn set_transmission(&mut self, transmission: &[Rgb]) {
        self.points.transmission.copy_from_slice(transmission);
    }

    /// The points as a [`ShadingMode::VolumeScatter`] context, sharing this child's cache.
    pub fn context(&self) -> ShadingContext<'_> {
        ShadingContext {
            points: &self.points,
            range: 0..self.points.len(),
            mode: ShadingMode::VolumeScatter,
            material: self.material,
            overlapping: &[],
            factory: self.factory,
            cache: self.cache.as_ref().map(|c| c as &dyn ParamLookup),
            cache_parts: self.cache.as_ref().map(|c| (c.arena, c.counters)),
            volume_space: self.volume_space,
            nn: None,
            component: 0,
        }
    }

    /// Ends volume sampling (RIS `EndVolumeSampling(membership)`): appends the points with
    /// `membership[i]` to `out` as one [`ShadingMode::VolumeScatter`] group of the volume's
    /// material (nothing when none is kept). Their `ray_id`s are those of the parent
    /// context's points.
    ///
    /// # Panics
    /// When `membership` has not one entry per point.
    pub fn end_volume_sampling(self, membership: &[bool], out: &mut ShadeGroups) {
        assert_eq!(membership.len(), self.points.len(), "one flag per point");
        let start = out.points.len();
        let rows: Vec<u32> = (0..membership.len() as u32)
            .filter(|&i| membership[i as usize])
            .collect();
        out.points.extend_gather(&self.points, &rows);
        out.close_group(self.material, ShadingMode::VolumeScatter, start);
    }

    /// `u, v, w` from `P` and the volume's space ([`VolumeSpace::uvw`]; 0 without one).
    fn update_uvw(&mut self) {
        let Some(space) = self.volume_space else {
            return;
        };
        for (i, p) in self.points.p.iter().enumerate() {
            let uvw = space.uvw(*p);
            self.points.u[i] = uvw.x;
            self.points.v[i] = uvw.y;
            self.points.w[i] = uvw.z;
        }
    }
}

fn set_scalar(column: &mut [f32], values: &[Vec3]) {
    for (c, v) in column.iter_mut().zip(values) {
        *c = v.x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plugin::{Bxdf, BxdfFactory, InstanceHints};
    use glam::Affine3A;
    use risotto_components::ShadingPointRow;

    struct Tinted;
    impl BxdfFactory for Tinted {
        fn instance_hints(&self) -> InstanceHints {
            InstanceHints::NONE
        }
        fn begin_scatter<'a>(
            &'a self,
            _ctx: &'a ShadingContext<'a>,
            _mode: ShadingMode,
            arena: &'a Bump,
        ) -> &'a mut (dyn Bxdf + 'a) {
            arena.alloc(crate::plugin::NullBxdf)
        }
        fn param(&self, name: &str) -> Option<ParamValue<'_>> {
            (name == "albedo").then_some(ParamValue::Color(Rgb::new(0.1, 0.2, 0.3)))
        }
    }

    fn table(n: u32) -> ShadingPoints {
        let mut t = ShadingPoints::default();
        for i in 0..n {
            t.push(ShadingPointRow::in_volume(Vec3::ZERO, Vec3::X, i, 0));
        }
        t
    }

    #[test]
    fn the_cache_evaluates_once_per_context_and_flushes_on_set_builtin() {
        let (arena, counters) = (Bump::new(), PatternCounters::default());
        let cache = ParamCache::new(&arena, &counters);
        let t = table(4);
        let ctx = ShadingContext::new(&t, 0..4, ShadingMode::Interior, 0, &[])
            .with_factory(&Tinted)
            .with_cache(&cache);
        let a = ctx.eval_param("albedo").unwrap();
        let b = ctx.eval_param("albedo").unwrap();
        assert_eq!(a, &[Rgb::new(0.1, 0.2, 0.3); 4][..]);
        assert!(std::ptr::eq(a, b), "the second lookup is the cached column");
        assert_eq!((counters.hits.get(), counters.evals.get()), (1, 1));
        assert!(ctx.eval_param("missing").is_none());
        // The child has its own cache; setting a builtin flushes it.
        let mut v = ctx.begin_volume_sampling();
        v.context().eval_param("albedo").unwrap();
        v.context().eval_param("albedo").unwrap();
        assert_eq!((counters.hits.get(), counters.evals.get()), (2, 2));
        v.set_builtin(Builtin::P, &[Vec3::ONE; 4]);
        v.context().eval_param("albedo").unwrap();
        assert_eq!((counters.hits.get(), counters.evals.get()), (2, 3));
    }

    #[test]
    fn uvw_are_measured_in_the_volumes_object_space() {
        // Object box [0, 2] x [0, 1] x [0, 1], turned 90 degrees about y (x -> -z) and moved
        // by (5, 0, 0): world bounds x in [5, 6], y in [0, 1], z in [-2, 0].
        let to_world = Affine3A::from_translation(Vec3::new(5.0, 0.0, 0.0))
            * Affine3A::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let space = VolumeSpace::new(
            (Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)),
            (Vec3::new(5.0, 0.0, -2.0), Vec3::new(6.0, 1.0, 0.0)),
            to_world,
        );
        assert!(!space.is_identity() && !space.is_axis_aligned());
        let moved = VolumeSpace::new(
            space.bounds,
            space.bounds,
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(2.0),
                Default::default(),
                Vec3::X,
            ),
        );
        assert!(moved.is_axis_aligned() && !moved.is_identity());
        let t = table(3);
        let ctx =
            ShadingContext::new(&t, 0..3, ShadingMode::Interior, 0, &[]).with_volume_space(space);
        assert_eq!(ctx.volume_space(), Some(space));
        assert_eq!(ctx.volume_bounds(), Some(space.bounds));
        let mut v = ctx.begin_volume_sampling();
        // World points of object points (2, 0.5, 0.5), (0, 0, 0) and (1, 1, 1).
        let world = [
            Vec3::new(5.5, 0.5, -2.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(6.0, 1.0, -1.0),
        ];
        v.set_builtin(Builtin::P, &world);
        let c = v.context();
        let expected = [
            Vec3::new(1.0, 0.5, 0.5),
            Vec3::ZERO,
            Vec3::new(0.5, 1.0, 1.0),
        ];
        for (i, e) in expected.iter().enumerate() {
            let got = Vec3::new(c.u()[i], c.v()[i], c.w()[i]);
            assert!(got.abs_diff_eq(*e, 1e-6), "point {i}: {got} != {e}");
        }
        // The world-space box would have given (0.5, 0.5, 0) for the first point.
        let flat = VolumeSpace::world(space.world_bounds.0, space.world_bounds.1);
        assert!(flat.is_identity());
        assert_eq!(flat.uvw(world[0]), Vec3::new(0.5, 0.5, 0.0));
        // Directions map without renormalising (world z is object -x).
        assert!(space
            .vector_to_object(Vec3::Z * 2.0)
            .abs_diff_eq(Vec3::NEG_X * 2.0, 1e-6));
    }

    #[test]
    fn volume_sampling_derives_uvw_and_keeps_the_members() {
        let t = table(3);
        let ctx = ShadingContext::new(&t, 1..3, ShadingMode::Interior, 7, &[])
            .with_volume_bounds(Vec3::ZERO, Vec3::new(2.0, 4.0, 8.0));
        let mut v = ctx.begin_volume_sampling();
        assert_eq!(v.num_points(), 2);
        v.set_builtin(
            Builtin::P,
            &[Vec3::new(1.0, 1.0, 2.0), Vec3::new(2.0, 4.0, 0.0)],
        );
        let c = v.context();
        assert_eq!((c.u()[0], c.v()[0], c.w()[0]), (0.5, 0.25, 0.25));
        assert_eq!((c.u()[1], c.v()[1], c.w()[1]), (1.0, 1.0, 0.0));
        assert_eq!(c.mode(), ShadingMode::VolumeScatter);
        v.set_builtin(Builtin::Vn, &[Vec3::Y, Vec3::Z]);
        let mut out = ShadeGroups::default();
        v.end_volume_sampling(&[false, true], &mut out);
        assert_eq!(out.groups.len(), 1);
        let g = &out.groups[0];
        assert_eq!(
            (g.material, g.mode, g.range.clone()),
            (7, ShadingMode::VolumeScatter, 0..1)
        );
        assert_eq!(out.points.ray_id[0], 2, "the parent's ray id");
        assert_eq!(out.points.vn[0], Vec3::Z);
        assert_eq!(out.points.p[0], Vec3::new(2.0, 4.0, 0.0));
        // No member: no group.
        let v = ctx.begin_volume_sampling();
        v.end_volume_sampling(&[false, false], &mut out);
        assert_eq!(out.groups.len(), 1);
    }
}
