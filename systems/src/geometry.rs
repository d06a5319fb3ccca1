//! Compiled scene geometry: triangles and analytic spheres behind one BVH.
//!
//! Primitive index convention (used in [`risotto_components::Hits::prim`] and everywhere
//! else): `0..num_triangles` are the triangles in the order given to [`SceneGeometry::build`],
//! `num_triangles..num_prims` are the spheres in the order given. The BVH reorders its leaves;
//! that order never leaks out of this module and [`crate::intersect`].

use std::f32::consts::PI;

use glam::{DVec3, Vec2, Vec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    bvh2::reinsertion::ReinsertionOptimizer,
    cwbvh::{bvh2_to_cwbvh::bvh2_to_cwbvh, CwBvh},
    ploc::PlocBuilder,
    BvhBuildParams,
};

use crate::bvh8::{bvh2_depth, median_bvh2, Bvh8, MAX_BVH2_DEPTH};
use crate::primitive::{sphere_hit_dir, sphere_uv, Triangle};
use crate::simd8::{Backend, Kernel};

// The primitives live in `crate::primitive`, below the BVH that is built over them; these
// are their public paths.
pub(crate) use crate::primitive::{gamma, UNDERFLOW};
pub use crate::primitive::{
    sphere_point_error, surface_offset, triangle_point_error, Sphere, SurfaceSample, Triangles,
};

/// All primitives of a compiled scene and the BVH over them.
///
/// One binary BVH (obvhs' PLOC builder and reinsertion optimizer) over the triangles and the
/// spheres' bounding boxes, so a ray visits every primitive kind in a single traversal. The
/// intersection systems traverse it collapsed to uncompressed 8-wide nodes; the obvhs
/// CWBVH collapse (Ylitie et al. 2017, "Efficient Incoherent Ray Traversal on GPUs Through
/// Compressed Wide BVHs") is kept alongside for [`Self::bvh`].
#[derive(Clone, Debug)]
pub struct SceneGeometry {
    triangles: Vec<Triangle>,
    spheres: Vec<Sphere>,
    /// `None` for an empty scene (obvhs cannot build an empty tree).
    bvh: Option<CwBvh>,
    /// The same binary BVH collapsed to an uncompressed 8-wide BVH with triangle-packet
    /// leaves (what the intersection systems traverse; see [`crate::intersect`]).
    bvh8: Option<Bvh8>,
    /// The intersection kernel, checked to run on this CPU.
    backend: Backend,
    bounds: (Vec3, Vec3),
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

impl SceneGeometry {
    /// Builds the geometry and its BVH. Triangles may be degenerate (they are never hit).
    ///
    /// # Panics
    /// If a vertex, centre or radius is not finite, a radius is not positive, or there are
    /// more than `u32::MAX - 1` primitives.
    pub fn build(triangles: Vec<[Vec3; 3]>, spheres: Vec<Sphere>) -> Self {
        let num_prims = triangles.len() + spheres.len();
        assert!(
            num_prims < u32::MAX as usize,
            "too many primitives: {num_prims}"
        );
        for tri in &triangles {
            assert!(
                tri.iter().all(|v| v.is_finite()),
                "non-finite vertex in {tri:?}"
            );
        }
        for s in &spheres {
            assert!(
                s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0,
                "invalid sphere {s:?}"
            );
        }

        // Triangle boxes are exact (min/max of the vertices); sphere boxes are padded.
        let mut aabbs: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                Aabb::new(
                    Vec3A::from(t[0].min(t[1]).min(t[2])),
                    Vec3A::from(t[0].max(t[1]).max(t[2])),
                )
            })
            .collect();
        let mut indices: Vec<u32> = (0..triangles.len() as u32).collect();

        // Without obvhs' spatial pre-splits: on the bench mesh and on a room with large
        // walls and long slivers they did not speed up traversal (benches/README.md) while
        // doubling build time, and their clipped boxes would need padding.
        let params = BvhBuildParams::medium_build();
        let tri_count = triangles.len() as u32;
        for (i, s) in spheres.iter().enumerate() {
            aabbs.push(padded_box(
                s.center - Vec3::splat(s.radius),
                s.center + Vec3::splat(s.radius),
            ));
            indices.push(tri_count + i as u32);
        }

        let mut bounds = (Vec3::ZERO, Vec3::ZERO);
        let (bvh, bvh8) = if aabbs.is_empty() {
            (None, None)
        } else {
            let mut lo = Vec3::splat(f32::INFINITY);
            let mut hi = Vec3::splat(f32::NEG_INFINITY);
            for t in &triangles {
                for v in t {
                    lo = lo.min(*v);
                    hi = hi.max(*v);
                }
            }
            let finite = |v: Vec3| v.clamp(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
            for s in &spheres {
                lo = lo.min(finite(s.center - Vec3::splat(s.radius)));
                hi = hi.max(finite(s.center + Vec3::splat(s.radius)));
            }
            bounds = (lo, hi);

            // Same pipeline as obvhs' `build_cwbvh_from_tris` (PLOC, reinsertion, collapse
            // to 8-wide nodes with up to 3 primitives per leaf), but over our own boxes so
            // spheres can share the tree.
            let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
                params.ploc_search_distance,
                &aabbs,
                indices,
                params.sort_precision,
                params.search_depth_threshold,
            );
            if bvh2_depth(&bvh2) <= MAX_BVH2_DEPTH {
                ReinsertionOptimizer::default().run(
                    &mut bvh2,
                    params.reinsertion_batch_ratio,
                    None,
                );
            }
            // PLOC chains equal boxes (see `MAX_BVH2_DEPTH`); a median split bounds the depth.
            if bvh2_depth(&bvh2) > MAX_BVH2_DEPTH {
                bvh2 = median_bvh2(&aabbs, &(0..aabbs.len() as u32).collect::<Vec<_>>());
            }
            // obvhs' collapse prices nodes by f32 half areas summed over the tree: infinite
            // costs leave its slot assignment undefined (out-of-bounds panics). It is only
            // kept for benchmarks and diagnostics, so scenes that would overflow go without.
            let depth = bvh2_depth(&bvh2) as f64;
            let root = &bvh2.nodes[0].aabb;
            let e = |a: usize| (root.max[a] as f64 - root.min[a] as f64).max(0.0);
            let half_area = (e(0) + e(1)) * e(2) + e(0) * e(1);
            let cwbvh_cost = half_area * (aabbs.len() as f64) * (depth + 1.0) * 2.0;
            let bvh = (cwbvh_cost < f32::MAX as f64)
                .then(|| bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false));
            let bvh8 = Bvh8::from_bvh2(&bvh2, &triangles, &spheres);
            (bvh, Some(bvh8))
        };

        Self {
            triangles: triangles.into_iter().map(Triangle::new).collect(),
            spheres,
            bvh,
            bvh8,
            backend: Kernel::best().backend().expect("the best kernel runs here"),
            bounds,
        }
    }

    /// Number of triangles (they are primitives `0..num_triangles()`).
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Number of spheres (primitives `num_triangles()..num_prims()`).
    pub fn num_spheres(&self) -> usize {
        self.spheres.len()
    }

    /// Number of primitives.
    pub fn num_prims(&self) -> usize {
        self.triangles.len() + self.spheres.len()
    }

    /// World AABB `(min, max)` of every primitive; `(0, 0)` for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Vertices of triangle `i` (a primitive index below `num_triangles()`).
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].v.map(Vec3::from)
    }

    /// Sphere number `i` (primitive `num_triangles() + i`).
    pub fn sphere(&self, i: usize) -> Sphere {
        self.spheres[i]
    }

    /// The scene's BVH collapsed to obvhs' compressed 8-wide CWBVH (`None` for an empty
    /// scene, and for one so large that obvhs' f32 SAH costs would overflow: extents beyond
    /// about 1e17 units). Its `primitive_indices` map leaf slots to primitive indices. Exposed for
    /// benchmarks and diagnostics; the intersection systems traverse an uncompressed 8-wide
    /// collapse of the same binary BVH instead.
    pub fn bvh(&self) -> Option<&CwBvh> {
        self.bvh.as_ref()
    }

    /// The 8-wide BVH (`None` for an empty scene) and the kernel that traverses it.
    pub(crate) fn bvh8(&self) -> Option<(&Bvh8, Backend)> {
        self.bvh8.as_ref().map(|b| (b, self.backend))
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
            None => self.sphere_surface_at(prim as usize, origin, direction, t, b1),
        }
    }

    /// Whether the ray hits primitive `prim` from the front, against its geometric normal
    /// (`direction . ng < 0` with `ng` of [`Self::surface_at`], the ray and hit as there),
    /// without the hit point or the normalised normal: what a walk that only tracks which
    /// side it crosses needs. Spheres test the unnormalised f64 direction from the centre,
    /// so the answer can differ from the f32 `ng` only for rays within rounding of tangent.
    #[inline]
    pub fn hit_is_front(&self, prim: u32, origin: Vec3, direction: Vec3, t: f32, b1: f32) -> bool {
        if (prim as usize) < self.triangles.len() {
            direction.dot(self.triangles[prim as usize].ng()) < 0.0
        } else {
            let s = self.spheres[prim as usize - self.triangles.len()];
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
    /// `InstanceHints::READS_SURFACE_UV`).
    pub fn surface_uv(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> Vec2 {
        if (prim as usize) < self.triangles.len() {
            Vec2::new(b1, b2)
        } else {
            let s = self.spheres[prim as usize - self.triangles.len()];
            sphere_uv(sphere_hit_dir(s, origin, direction, t, b1))
        }
    }

    /// The triangles, for batch loops over hits ([`Triangles::surface_at`]).
    #[inline(always)]
    pub fn triangles(&self) -> Triangles<'_> {
        Triangles(&self.triangles)
    }

    /// The sphere case of [`Self::surface_at`].
    #[inline(never)]
    fn sphere_surface_at(
        &self,
        prim: usize,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
    ) -> SurfaceSample {
        let s = self.spheres[prim - self.triangles.len()];
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

    /// Surface area of primitive `prim`.
    pub fn prim_area(&self, prim: u32) -> f32 {
        let prim = prim as usize;
        if prim < self.triangles.len() {
            self.triangles[prim].ng_area.w
        } else {
            let r = self.spheres[prim - self.triangles.len()].radius;
            4.0 * PI * r * r
        }
    }

    /// Samples a point uniformly by area on primitive `prim` (for area lights) from
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
        if prim < self.triangles.len() {
            let tri = &self.triangles[prim];
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
            let s = self.spheres[prim - self.triangles.len()];
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64;

    /// The triangle records against the vertices they were built from, in double precision:
    /// interpolated points, normals, areas; spheres are not triangles.
    #[test]
    fn triangle_records_match_their_vertices() {
        let mut rng = SplitMix64(3);
        let mut v = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 20.0 - Vec3::splat(10.0);
        let tris: Vec<[Vec3; 3]> = (0..50).map(|_| [v(), v(), v()]).collect();
        let sphere = Sphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 0.5,
        };
        let geom = SceneGeometry::build(tris.clone(), vec![sphere]);
        let view = geom.triangles();
        let mut rng = SplitMix64(4);
        for (i, t) in tris.iter().enumerate() {
            assert_eq!(geom.triangle(i), *t);
            let [a, b, c] = t.map(|x| x.as_dvec3());
            let cross = (b - a).cross(c - a);
            let area = geom.prim_area(i as u32) as f64;
            assert!((area - 0.5 * cross.length()).abs() <= 1e-5 * area.max(1.0));
            let (b1, b2) = (rng.f32() * 0.5, rng.f32() * 0.5);
            let s = view.surface_at(i as u32, b1, b2).unwrap();
            let d = f32::MAX;
            assert_eq!(s, geom.surface_at(i as u32, Vec3::ZERO, Vec3::Z, d, b1, b2));
            let (b1d, b2d) = (b1 as f64, b2 as f64);
            let p = a * (1.0 - b1d - b2d) + b * b1d + c * b2d;
            assert!((s.p.as_dvec3() - p).length() < 1e-5, "{:?} {p:?}", s.p);
            assert!((s.ng.as_dvec3() - cross.normalize()).length() < 1e-6);
            assert_eq!(s.uv, Vec2::new(b1, b2));
            let (q, n) = geom.sample_prim(i as u32, Vec2::new(b1, b2));
            assert_eq!(n, s.ng);
            assert!((q.as_dvec3() - a).dot(n.as_dvec3()).abs() < 1e-4);
        }
        assert!(view.surface_at(tris.len() as u32, 0.25, 0.5).is_none());
        assert_eq!(geom.num_prims(), tris.len() + 1);
    }

    #[test]
    fn hit_is_front_agrees_with_the_surface_normal() {
        let tri = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let ball = Sphere {
            center: Vec3::new(0.0, 0.0, 5.0),
            radius: 1.0,
        };
        let geom = SceneGeometry::build(vec![tri], vec![ball]);
        let cases = [
            (Vec3::new(0.0, 0.0, 2.0), -Vec3::Z), // triangle, from its front
            (Vec3::new(0.0, 0.0, -2.0), Vec3::Z), // triangle, from behind
            (Vec3::new(0.2, 0.1, 10.0), -Vec3::Z), // sphere from outside
            (Vec3::new(0.2, 0.1, 5.0), Vec3::new(0.6, 0.0, 0.8)), // sphere from inside
        ];
        for (o, d) in cases {
            let n = 1;
            let (mut t, mut prim) = (vec![0.0; n], vec![0; n]);
            let (mut b1, mut b2) = (vec![0.0; n], vec![0.0; n]);
            crate::intersect::intersect_closest(
                &geom,
                &[o],
                &[d],
                &[0.0],
                &[f32::INFINITY],
                &mut t,
                &mut prim,
                &mut b1,
                &mut b2,
            );
            let s = geom.surface_at(prim[0], o, d, t[0], b1[0], b2[0]);
            assert_eq!(
                geom.hit_is_front(prim[0], o, d, t[0], b1[0]),
                d.dot(s.ng) < 0.0,
                "ray from {o:?} along {d:?}"
            );
        }
        let front = |o: Vec3, d: Vec3| {
            let (mut t, mut prim) = (vec![0.0], vec![0]);
            let (mut b1, mut b2) = (vec![0.0], vec![0.0]);
            crate::intersect::intersect_closest(
                &geom,
                &[o],
                &[d],
                &[0.0],
                &[f32::INFINITY],
                &mut t,
                &mut prim,
                &mut b1,
                &mut b2,
            );
            geom.hit_is_front(prim[0], o, d, t[0], b1[0])
        };
        assert!(front(Vec3::new(0.0, 0.0, 2.0), -Vec3::Z));
        assert!(!front(Vec3::new(0.0, 0.0, -2.0), Vec3::Z));
        assert!(front(Vec3::new(0.2, 0.1, 10.0), -Vec3::Z));
        assert!(!front(Vec3::new(0.2, 0.1, 5.0), Vec3::Z));
    }

    #[test]
    fn sphere_normals_come_from_the_double_precision_root() {
        // A tiny sphere far away: the f32 `t` alone is off by ~1e-3 of the radius, so a
        // normal from `origin + t direction` would tilt by ~1e-3 rad; `t + b1` keeps it to
        // f32 rounding of the normal.
        let sphere = Sphere {
            center: Vec3::new(1.0e4, 3.0, -2.0),
            radius: 1.0e-3,
        };
        let geom = SceneGeometry::build(vec![], vec![sphere]);
        let n = 2000;
        let (mut origin, mut direction) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        for k in 0..n {
            // Aim at points of a spiral on the sphere's visible side.
            let z = 1.0 - (k as f64 + 0.5) / n as f64;
            let (sn, cs) = (k as f64 * 2.399963).sin_cos();
            let r = (1.0 - z * z).sqrt();
            let target = sphere.center.as_dvec3()
                + DVec3::new(-z, r * cs, r * sn) * (0.9 * sphere.radius as f64);
            direction[k] = target.normalize().as_vec3();
        }
        let (tmin, tmax) = (vec![0.0; n], vec![f32::INFINITY; n]);
        let (mut t, mut prim) = (vec![0.0; n], vec![0; n]);
        let (mut b1, mut b2) = (vec![0.0; n], vec![0.0; n]);
        crate::intersect::intersect_closest(
            &geom, &origin, &direction, &tmin, &tmax, &mut t, &mut prim, &mut b1, &mut b2,
        );
        let mut worst = 0.0f64;
        for k in 0..n {
            assert_eq!(prim[k], 0, "ray {k} aims inside the sphere");
            // Reference: the near root in f64 from the same f32 inputs.
            let (f, d) = (-sphere.center.as_dvec3(), direction[k].as_dvec3());
            let (a, b) = (d.length_squared(), f.dot(d));
            let l = f - d * (b / a);
            let rr = (sphere.radius as f64).powi(2);
            let q = -(b + (a * (rr - l.length_squared())).sqrt().copysign(b));
            let t_ref = (f.length_squared() - rr) / q;
            let n_ref = (f + d * t_ref).normalize();
            let s = geom.surface_at(0, origin[k], direction[k], t[k], b1[k], b2[k]);
            worst = worst.max(s.ng.as_dvec3().angle_between(n_ref));
        }
        assert!(worst < 1e-6, "worst normal error {worst} rad");
        origin.clear();
        // The parameters of a hit at the pole.
        let up = SceneGeometry::build(
            vec![],
            vec![Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            }],
        );
        let uv = up.surface_uv(0, Vec3::new(0.0, 0.0, 3.0), -Vec3::Z, 2.0, 0.0, 0.0);
        assert_eq!(uv.y, 0.0, "+z is the pole theta = 0");
    }

    /// The hit direction's series for 1/|h| against `normalize` (a square root and a
    /// division) over spheres from tiny to huge, near and far from the origin, for hits with
    /// and without the f64 residual: equal to within a few f64 ulps, far under the f32
    /// rounding of the normal and the 2^-48 f64 part of the point's error bound.
    #[test]
    fn sphere_hit_direction_series_matches_normalize() {
        let mut rng = SplitMix64(11);
        let mut worst = 0.0f64;
        for k in 0..20_000 {
            let scale = 10f32.powi((k % 13) as i32 - 6);
            let center = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5)
                * scale
                * [1.0, 1e3][k % 2];
            let s = Sphere {
                center,
                radius: scale * (0.1 + rng.f32()),
            };
            // A ray from outside at the sphere's centre, slightly off.
            let d = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize();
            let o = center - d * s.radius * 3.0 + d.any_orthonormal_vector() * s.radius * 0.3;
            let Some(t64) = crate::intersect::sphere_root_for_tests(o, d, s) else {
                continue;
            };
            let t = t64 as f32;
            for b1 in [(t64 - t as f64) as f32, f32::NAN] {
                let n = sphere_hit_dir(s, o, d, t, b1);
                let t64b = t as f64 + if b1.is_finite() { b1 as f64 } else { 0.0 };
                let h = (o.as_dvec3() - center.as_dvec3()) + d.as_dvec3() * t64b;
                let exact = h.normalize();
                worst = worst.max((n - exact).abs().max_element());
            }
        }
        assert!(worst < 8.0 * f64::EPSILON, "largest difference {worst:e}");
    }
}
