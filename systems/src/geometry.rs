//! Compiled scene geometry: triangles and analytic spheres behind one BVH.
//!
//! Primitive index convention (used in [`risotto_components::Hits::prim`] and everywhere
//! else): `0..num_triangles` are the triangles in the order given to [`SceneGeometry::build`],
//! `num_triangles..num_flat_prims` are the spheres in the order given, and in a scene with
//! instances ([`SceneGeometry::build_with_instances`]) instance `k`'s primitive `j` (its
//! object's primitive `j`) is `prim_base(k) + j`, the instances numbered one after another
//! from `num_flat_prims` ([`SceneGeometry::instance_of`] maps back by binary search, so
//! nothing is stored per instanced primitive). The BVH reorders its leaves; that order
//! never leaks out of this module and [`crate::intersect`].

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Affine3A, DVec3, Vec2, Vec3, Vec3A};
use obvhs::{aabb::Aabb, BvhBuildParams};

use crate::build_prims::{BuildPrims, PrimBoxes};
use crate::bvh2_build::build_bvh2;
use crate::bvh8::{Bvh8, InstanceLeaf, TriPacket8};
use crate::mesh_attributes::MeshAttributes;
use crate::primitive::{sphere_hit_dir, sphere_uv, Triangle};
use crate::simd8::{Backend, Kernel};

// The primitives live in `crate::primitive`, below the BVH that is built over them; these
// are their public paths.
pub(crate) use crate::primitive::{gamma, UNDERFLOW};
pub use crate::primitive::{
    sphere_point_error, surface_offset, triangle_point_error, Sphere, SurfaceSample,
};

mod instances;
mod surfaces;
pub use crate::triangle_mesh::{TriangleMesh, TriangleSet};
pub(crate) use instances::ray_to_object;
pub use instances::Instance;
pub use surfaces::SurfaceColumns;

/// All primitives of a compiled scene and the BVH over them.
///
/// One BVH over the triangles and the spheres' bounding boxes, so a ray visits every
/// primitive kind in a single traversal: uncompressed 8-wide nodes, built for large scenes
/// top down by binned SAH (`Bvh8::binned`, no binary tree: issue 36, memory per
/// triangle), for smaller ones by obvhs' PLOC builder and reinsertion optimizer collapsed
/// to 8-wide nodes, the binary tree dropped once collapsed (`BvhBuilder` chooses).
#[derive(Clone, Debug)]
pub struct SceneGeometry {
    /// Where triangle primitive `i` lies in `bvh8`'s packets (`packet * 8 + lane`): the
    /// triangles are stored once, in the leaves the traversal tests (issue 36).
    tri_slots: Vec<u32>,
    spheres: Vec<Sphere>,
    /// The binary BVH collapsed to an uncompressed 8-wide BVH with triangle-packet
    /// leaves (what the intersection systems traverse; see [`crate::intersect`]); `None`
    /// for an empty scene (obvhs cannot build an empty tree). Shared with the top-level
    /// BVH of the scenes that place this geometry as an object.
    bvh8: Option<Arc<Bvh8>>,
    /// The intersection kernel, checked to run on this CPU.
    backend: Backend,
    bounds: (Vec3, Vec3),
    /// Shading normals and texture coordinates of the meshes that have them (empty in most
    /// scenes: nothing is stored or looked up for meshes without).
    attributes: MeshAttributes,
    /// The objects the instances place, in object space (their BVHs are moved into
    /// `bvh8`'s objects, where the traversal finds them). Empty without instances.
    objects: Vec<SceneGeometry>,
    /// The instances in primitive order (`prim_base` increasing).
    instances: Vec<Instance>,
    /// Whether this geometry or one of its objects has mesh attributes.
    any_attributes: bool,
}

/// The triangles of a [`SceneGeometry`], for batch loops over hits: taken once before the
/// loop, so the loop keeps the arrays in registers instead of reloading them through the
/// geometry. A triangle's vertices are read from its BVH leaf packet, its normal and area
/// computed from them (`Triangle::new`, the same operations whenever they are made).
#[derive(Clone, Copy, Debug)]
pub struct Triangles<'a> {
    slots: &'a [u32],
    packets: &'a [TriPacket8],
}

impl Triangles<'_> {
    /// [`SceneGeometry::surface_at`] when `prim` is a triangle outside instances, `None` for
    /// a sphere or a primitive of an instance. A few instructions and the common case:
    /// batch loops inline it and call `surface_at` for spheres, writing the result of each
    /// branch directly (not merging two results through memory).
    #[inline(always)]
    pub fn surface_at(&self, prim: u32, b1: f32, b2: f32) -> Option<SurfaceSample> {
        let slot = *self.slots.get(prim as usize)?;
        Some(Bvh8::slot_triangle(self.packets, slot).surface_at(b1, b2))
    }

    /// Triangle primitive `prim` (below the number of triangles).
    #[inline(always)]
    fn get(&self, prim: usize) -> Triangle {
        Bvh8::slot_triangle(self.packets, self.slots[prim])
    }
}

/// Relative padding of sphere boxes: `center +- radius` is rounded, and the box must
/// contain the sphere exactly for traversal to be conservative.
const BOX_PAD: f32 = 4.0 * f32::EPSILON;

///
/// Clamped to the finite range: a box beyond `f32::MAX` contains no representable point more
/// than the clamped one, and infinite box coordinates would make slab tests NaN.
fn padded_box(lo: Vec3, hi: Vec3) -> Aabb {
    let pad_lo = lo.abs() * BOX_PAD + Vec3::splat(f32::MIN_POSITIVE);
    let pad_hi = hi.abs() * BOX_PAD + Vec3::splat(f32::MIN_POSITIVE);
    let finite = |v: Vec3| v.clamp(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
    Aabb::new(
        Vec3A::from(finite(lo - pad_lo)),
        Vec3A::from(finite(hi + pad_hi)),
    )
}

/// How the 8-wide BVH is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BvhBuilder {
    /// obvhs' PLOC and reinsertion, collapsed SAH-optimally to 8-wide nodes
    /// ([`Bvh8::from_bvh2`]).
    Ploc,
    /// Top-down binned SAH writing the 8-wide nodes directly ([`Bvh8::binned`]).
    Binned,
}

/// Scenes of at least this many primitives are built by [`BvhBuilder::Binned`]. On the
/// displaced-sphere meshes of `benches/README.md` its tree renders in fewer instructions
/// than the collapsed PLOC tree (4 spp, callgrind, `render_tile`: 20k triangles -4.1 %, 50k -5.3 %,
/// 200k -2.8 %, 2M -3.1 %), on small scenes of large triangles in more (a 320-triangle
/// icosphere in a room, `scenes/mesh.toml`: +8.8 %; the Cornell box +10 % of the whole process), where the
/// collapse's exact SAH over every assignment of subtrees to slots and its volume term
/// pay; and below the peak it matters little what the build holds.
pub(crate) const BINNED_MIN: usize = 16 * 1024;

impl BvhBuilder {
    /// The builder for a scene of `count` primitives.
    fn for_prims(count: usize) -> Self {
        if count >= BINNED_MIN {
            Self::Binned
        } else {
            Self::Ploc
        }
    }
}

impl SceneGeometry {
    /// Builds the geometry and its BVH. Triangles may be degenerate (they are never hit).
    ///
    /// # Panics
    /// If a vertex, centre or radius is not finite, a radius is not positive, or there are
    /// more than `u32::MAX - 1` primitives.
    pub fn build(triangles: Vec<[Vec3; 3]>, spheres: Vec<Sphere>) -> Self {
        Self::build_with_instances(triangles, spheres, Vec::new(), &[])
    }

    /// [`Self::build`] with instances: `objects` are geometries built in object space (by
    /// [`Self::build`], with their attributes set), and each `(object, to_world)` of
    /// `instances` places `objects[object]` in the world by the affine map `to_world` (any
    /// invertible one: rotation, non-uniform scale, mirroring). Two levels: the top BVH holds
    /// the triangles, the spheres and one leaf per instance (its object's box mapped to the
    /// world); a ray reaching an instance leaf is mapped into object space (by the inverse
    /// map, its direction not renormalised, so its parameter `t` is the world one) and
    /// traverses the object's own BVH. An object's geometry is stored once whatever the
    /// number of its instances; see the module doc for the primitive numbering.
    ///
    /// # Panics
    /// As [`Self::build`]; also if an object is empty or has instances itself, an instance
    /// names no object, a map is not invertible, or there are more than `u32::MAX - 1`
    /// primitives counting every instance's (callers check that first:
    /// [`Self::count_instanced_prims`]).
    pub fn build_with_instances(
        triangles: Vec<[Vec3; 3]>,
        spheres: Vec<Sphere>,
        objects: Vec<SceneGeometry>,
        instances: &[(u32, Affine3A)],
    ) -> Self {
        let triangles = TriangleSet::Soup(triangles);
        Self::build_using(triangles, spheres, objects, instances, None).0
    }

    /// [`Self::build_with_instances`] with the triangles as a [`TriangleSet`]: a soup, or a
    /// [`TriangleMesh`] whose triangle `i` is `mesh.triangle(i)`, which gives the same
    /// primitive numbering, tree and hits as the soup of its triangles without the soup or
    /// the weld.
    ///
    /// # Panics
    /// As [`Self::build_with_instances`]; also if an index of a mesh is not one of its
    /// vertices.
    pub fn build_set_with_instances(
        triangles: TriangleSet,
        spheres: Vec<Sphere>,
        objects: Vec<SceneGeometry>,
        instances: &[(u32, Affine3A)],
    ) -> Self {
        Self::build_set_keeping_indices(triangles, spheres, objects, instances).0
    }

    /// [`Self::build_set_with_instances`], also handing back the triangles' vertex indices
    /// as the build held them (a mesh's own, in triangle order; a soup's welded ones; empty
    /// where the build kept a soup as given or built nothing), which the build would
    /// otherwise free: a mesh's vertex attributes index their normals by the same corners,
    /// and need not hold a second copy while the tree is built (issue 36).
    ///
    /// # Panics
    /// As [`Self::build_set_with_instances`].
    pub fn build_set_keeping_indices(
        triangles: TriangleSet,
        spheres: Vec<Sphere>,
        objects: Vec<SceneGeometry>,
        instances: &[(u32, Affine3A)],
    ) -> (Self, Vec<[u32; 3]>) {
        if let TriangleSet::Mesh(mesh) = &triangles {
            assert!(mesh.indices_in_range(), "a triangle index is not a vertex");
        }
        Self::build_using(triangles, spheres, objects, instances, None)
    }

    /// [`Self::build`] with the BVH made by `builder` whatever the scene's size (the tests
    /// of each builder).
    #[cfg(test)]
    pub(crate) fn build_with_builder(
        triangles: Vec<[Vec3; 3]>,
        spheres: Vec<Sphere>,
        builder: BvhBuilder,
    ) -> Self {
        let triangles = TriangleSet::Soup(triangles);
        Self::build_using(triangles, spheres, Vec::new(), &[], Some(builder)).0
    }

    /// [`Self::build_with_instances`] by `builder`, or the one [`BvhBuilder::for_prims`]
    /// picks.
    fn build_using(
        triangles: TriangleSet,
        spheres: Vec<Sphere>,
        objects: Vec<SceneGeometry>,
        instances: &[(u32, Affine3A)],
        builder: Option<BvhBuilder>,
    ) -> (Self, Vec<[u32; 3]>) {
        let num_prims = triangles.len() + spheres.len();
        assert!(
            num_prims < u32::MAX as usize,
            "too many primitives: {num_prims}"
        );
        let placed = instances::place(&objects, instances, num_prims as u32);
        triangles.for_each(|tri| {
            assert!(
                tri.iter().all(|v| v.is_finite()),
                "non-finite vertex in {tri:?}"
            );
        });
        for s in &spheres {
            assert!(
                s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0,
                "invalid sphere {s:?}"
            );
        }

        let mut bounds = (Vec3::ZERO, Vec3::ZERO);
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        triangles.for_each(|t| {
            for v in t {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        });
        let finite = |v: Vec3| v.clamp(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
        for s in &spheres {
            lo = lo.min(finite(s.center - Vec3::splat(s.radius)));
            hi = hi.max(finite(s.center + Vec3::splat(s.radius)));
        }
        for (blo, bhi) in &placed.boxes {
            lo = lo.min(finite(*blo));
            hi = hi.max(finite(*bhi));
        }

        // The build's primitives: the triangles (their boxes exact, min/max of the
        // vertices) with their vertices welded, then the spheres' and the instances' padded
        // boxes; primitive `i` at position `i`. No box is stored for a triangle: the build's
        // peak, not its total, is what a large mesh runs out of (issue 36).
        let tri_count = triangles.len();
        let boxes: Vec<(Vec3, Vec3)> = spheres
            .iter()
            .map(|s| {
                padded_box(
                    s.center - Vec3::splat(s.radius),
                    s.center + Vec3::splat(s.radius),
                )
            })
            .chain(placed.boxes.iter().map(|&(lo, hi)| padded_box(lo, hi)))
            .map(|b| (b.min.into(), b.max.into()))
            .collect();
        let prims = match triangles {
            TriangleSet::Soup(soup) => BuildPrims::new(soup, boxes),
            TriangleSet::Mesh(mesh) => BuildPrims::from_mesh(mesh, boxes),
        };

        // Without obvhs' spatial pre-splits: on the bench mesh and on a room with large
        // walls and long slivers they did not speed up traversal (benches/README.md) while
        // doubling build time, and their clipped boxes would need padding.
        let params = BvhBuildParams::medium_build();
        let mut tri_slots = Vec::new();
        let mut indices = Vec::new();
        let bvh8 = if prims.count() == 0 {
            None
        } else {
            bounds = (lo, hi);
            // obvhs' PLOC and reinsertion over the boxes, so spheres can share the tree,
            // with the runs PLOC stalls on built apart. Each intermediate is freed as soon as
            // the next is built (the binary tree inside the collapse).
            let builder = builder.unwrap_or(BvhBuilder::for_prims(prims.count()));
            let mut bvh8 = match builder {
                BvhBuilder::Binned => Bvh8::binned(&prims, &spheres),
                BvhBuilder::Ploc => {
                    let bvh2 = build_bvh2(&prims, &params);
                    Bvh8::from_bvh2(bvh2, &prims, &spheres)
                }
            };
            indices = prims.into_corners();
            tri_slots = bvh8.triangle_slots(tri_count);
            if !placed.instances.is_empty() {
                bvh8.instances = placed
                    .instances
                    .iter()
                    .map(|i| InstanceLeaf {
                        to_object: i.to_object,
                        object: i.object,
                        prim_base: i.prim_base,
                    })
                    .collect();
                // The objects' BVHs, shared where the traversal reads them.
                bvh8.objects = objects
                    .iter()
                    .map(|o| Arc::clone(o.bvh8.as_ref().expect("objects are not empty")))
                    .collect();
            }
            Some(Arc::new(bvh8))
        };

        let any_attributes = objects.iter().any(|o| o.any_attributes);
        let geometry = Self {
            tri_slots,
            spheres,
            bvh8,
            backend: Kernel::best().backend().expect("the best kernel runs here"),
            bounds,
            attributes: MeshAttributes::default(),
            objects: if placed.instances.is_empty() {
                Vec::new()
            } else {
                objects
            },
            instances: placed.instances,
            any_attributes,
        };
        (geometry, indices)
    }

    /// Sets the meshes' vertex attributes (their ranges must be triangle primitives).
    ///
    /// # Panics
    /// When a range of `attributes` reaches past the triangles.
    pub fn set_attributes(&mut self, attributes: MeshAttributes) {
        assert!(
            attributes.max_prim_end() <= self.tri_slots.len(),
            "vertex attributes of primitives that are not triangles"
        );
        self.attributes = attributes;
        self.any_attributes =
            !self.attributes.is_empty() || self.objects.iter().any(|o| o.any_attributes);
    }

    /// The meshes' vertex attributes (empty unless [`Self::set_attributes`] gave some), of
    /// the triangles outside instances (an instance's are its object's; what a hit on any
    /// triangle gets: [`Self::mesh_shading`]).
    #[inline(always)]
    pub fn attributes(&self) -> &MeshAttributes {
        &self.attributes
    }

    /// Number of triangles (they are primitives `0..num_triangles()`).
    pub fn num_triangles(&self) -> usize {
        self.tri_slots.len()
    }

    /// Number of spheres (primitives `num_triangles()..num_prims()`).
    pub fn num_spheres(&self) -> usize {
        self.spheres.len()
    }

    /// Number of primitives outside instances (the triangles and the spheres).
    pub fn num_flat_prims(&self) -> usize {
        self.tri_slots.len() + self.spheres.len()
    }

    /// Number of primitives, every instance's included.
    pub fn num_prims(&self) -> usize {
        self.instances.last().map_or(self.num_flat_prims(), |i| {
            i.prim_base as usize + self.objects[i.object as usize].num_prims()
        })
    }

    /// World AABB `(min, max)` of every primitive; `(0, 0)` for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Vertices of triangle `i` (a primitive index below `num_triangles()`).
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles().get(i).v.map(Vec3::from)
    }

    /// Sphere number `i` (primitive `num_triangles() + i`).
    pub fn sphere(&self, i: usize) -> Sphere {
        self.spheres[i]
    }

    /// The 8-wide BVH (`None` for an empty scene) and the kernel that traverses it.
    pub(crate) fn bvh8(&self) -> Option<(&Bvh8, Backend)> {
        self.bvh8.as_deref().map(|b| (b, self.backend))
    }

    /// The intersection kernel in use ([`Kernel::best`] unless set).
    pub fn kernel(&self) -> Kernel {
        self.backend.kernel()
    }

    /// Selects the intersection kernel (tests and benchmarks compare them; all report the
    /// same hits).
    ///
    /// # Panics
    /// If this CPU does not run `kernel` ([`Kernel::is_supported`]).
    pub fn set_kernel(&mut self, kernel: Kernel) {
        self.backend = kernel
            .backend()
            .unwrap_or_else(|| panic!("{kernel:?} kernel not supported on this CPU"));
    }

    /// Geometry at a hit of the ray `origin + t * direction` on primitive `prim`, with the
    /// hit's `t`, `b1`, `b2` as written by [`crate::intersect::intersect_closest`] for that
    /// same ray.
    ///
    /// Triangles: `p` is interpolated from the vertices with the barycentrics (more accurate
    /// than `origin + t * direction`), `uv = (b1, b2)`. Spheres: `t + b1` is the
    /// double-precision root (`b1` its residual against `t`), from which the direction from
    /// the centre to the hit is computed in double precision, so the normal stays accurate
    /// even where `t` alone has lost precision (tiny spheres far away); `p` is the
    /// corresponding point on the sphere, and `uv = (0, 0)` (see [`Self::surface_uv`]).
    #[inline(always)]
    pub fn surface_at(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> SurfaceSample {
        match self.triangles().surface_at(prim, b1, b2) {
            Some(s) => s,
            None => self.sphere_surface_at(prim as usize, origin, direction, t, b1, b2),
        }
    }

    /// Whether the ray hits primitive `prim` from the front, against its geometric normal
    /// (`direction . ng < 0` with `ng` of [`Self::surface_at`], the ray and hit as there),
    /// without the hit point or the normalised normal: what a walk that only tracks which
    /// side it crosses needs. Spheres test the unnormalised f64 direction from the centre,
    /// so the answer can differ from the f32 `ng` only for rays within rounding of tangent.
    #[inline]
    pub fn hit_is_front(&self, prim: u32, origin: Vec3, direction: Vec3, t: f32, b1: f32) -> bool {
        if (prim as usize) < self.tri_slots.len() {
            direction.dot(self.triangles().get(prim as usize).ng()) < 0.0
        } else if prim as usize >= self.num_flat_prims() {
            self.instance_hit_is_front(prim, origin, direction, t, b1)
        } else {
            let s = self.spheres[prim as usize - self.tri_slots.len()];
            let t64 = t as f64 + if b1.is_finite() { b1 as f64 } else { 0.0 };
            let d = direction.as_dvec3();
            let h = (origin.as_dvec3() - s.center.as_dvec3()) + d * t64;
            h.dot(d) < 0.0
        }
    }

    /// Surface parameters of a hit (the ray and `t`, `b1`, `b2` as for
    /// [`Self::surface_at`]). Triangles: the barycentrics `(b1, b2)` of `v1` and `v2`;
    /// spheres: `(phi / 2pi, theta / pi)` with `theta` the polar angle from `+z` and `phi`
    /// the azimuth from `+x` towards `+y`, in `[0, 2pi)`. Shading points get these only in
    /// scenes with a material that asks for them (the engine's
    /// `InstanceHints::READS_SURFACE_UV`). Triangles of meshes with texture coordinates get
    /// theirs from [`Self::attributes`] instead.
    pub fn surface_uv(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> Vec2 {
        if (prim as usize) < self.tri_slots.len() {
            Vec2::new(b1, b2)
        } else if prim as usize >= self.num_flat_prims() {
            self.instance_surface_uv(prim, origin, direction, t, b1, b2)
        } else {
            let s = self.spheres[prim as usize - self.tri_slots.len()];
            sphere_uv(sphere_hit_dir(s, origin, direction, t, b1))
        }
    }

    /// The triangles, for batch loops over hits ([`Triangles::surface_at`]).
    #[inline(always)]
    pub fn triangles(&self) -> Triangles<'_> {
        Triangles {
            slots: &self.tri_slots,
            packets: self.bvh8.as_ref().map_or(&[], |b| &b.packets),
        }
    }

    /// The sphere case of [`Self::surface_at`], and that of primitives of instances.
    #[inline(never)]
    fn sphere_surface_at(
        &self,
        prim: usize,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> SurfaceSample {
        if prim >= self.num_flat_prims() {
            return self.instance_surface_at(prim as u32, origin, direction, t, b1, b2);
        }
        let s = self.spheres[prim - self.tri_slots.len()];
        let n = sphere_hit_dir(s, origin, direction, t, b1);
        // The point in double precision, rounded once: its distance to the sphere is then
        // under an ulp of its own largest coordinate, which the spawn offset (relative to
        // that coordinate) covers. `centre + n r` in f32 erred by ulps of |centre| + r: at
        // the top of a unit sphere centred at (0, -1, 0), where p is near zero, a 6e-8
        // error against a 1e-9 offset put a quarter of the shadow rays inside (acne).
        let p = (s.center.as_dvec3() + n * s.radius as f64).as_vec3();
        SurfaceSample {
            p,
            ng: n.as_vec3(),
            uv: Vec2::ZERO,
            p_error: sphere_point_error(s.center, s.radius, p),
        }
    }

    /// Surface area of primitive `prim` (not of an instance: instanced primitives are never
    /// lights).
    pub fn prim_area(&self, prim: u32) -> f32 {
        let prim = prim as usize;
        if prim < self.tri_slots.len() {
            self.triangles().get(prim).area()
        } else {
            let r = self.spheres[prim - self.tri_slots.len()].radius;
            4.0 * PI * r * r
        }
    }

    /// Samples a point uniformly by area on primitive `prim` (for area lights; not of an
    /// instance) from
    /// `u` in `[0, 1)^2`. Returns the point and the unit geometric normal (as in
    /// [`Self::surface_at`]); the area-measure pdf is `1 / prim_area(prim)`. Degenerate
    /// triangles (zero area) return a zero normal. [`Self::sample_surface`] also returns the
    /// point's error bound.
    #[inline]
    pub fn sample_prim(&self, prim: u32, u: Vec2) -> (Vec3, Vec3) {
        let s = self.sample_surface(prim, u);
        (s.p, s.ng)
    }

    /// [`Self::sample_prim`] with the point's error bound (`p_error`; `uv` is `(0, 0)`).
    /// Triangles: the barycentrics of the Heitz map, `b2 = (1 - b0) - b1` rounded, bounded
    /// as [`triangle_point_error`] with the roles of `v0` and `v2` swapped. Spheres: the
    /// point on the unit sphere in double precision, rounded once (bound:
    /// [`sphere_point_error`]).
    #[inline]
    pub fn sample_surface(&self, prim: u32, u: Vec2) -> SurfaceSample {
        let prim = prim as usize;
        if prim < self.tri_slots.len() {
            let tri = self.triangles().get(prim);
            // Heitz 2019, "A Low-Distortion Map Between Triangle and Square": folds the
            // square onto the triangle so that the map is area preserving (uniform).
            let (b0, b1) = if u.x < u.y {
                let b0 = u.x * 0.5;
                (b0, u.y - b0)
            } else {
                let b1 = u.y * 0.5;
                (u.x - b1, b1)
            };
            let b2 = 1.0 - b0 - b1;
            let [v0, v1, v2] = tri.v;
            SurfaceSample {
                p: (v0 * b0 + v1 * b1 + v2 * b2).into(),
                ng: tri.ng(),
                uv: Vec2::ZERO,
                p_error: triangle_point_error([v2, v1, v0], b2, b1, b0),
            }
        } else {
            use std::f64::consts::PI as PI64;
            let s = self.spheres[prim - self.tri_slots.len()];
            // Archimedes: z = cos(theta) is uniform on [-1, 1] for area-uniform points.
            let z = 1.0 - 2.0 * u.x as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * PI64 * u.y as f64;
            let n = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            let p = (s.center.as_dvec3() + n * s.radius as f64).as_vec3();
            SurfaceSample {
                p,
                ng: n.as_vec3(),
                uv: Vec2::ZERO,
                p_error: sphere_point_error(s.center, s.radius, p),
            }
        }
    }
}
