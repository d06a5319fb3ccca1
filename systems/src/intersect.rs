//! Ray/scene intersection systems: closest hit and occlusion over columns of rays.
//!
//! Traversal runs over the uncompressed 8-wide BVH of [`SceneGeometry`] (f32 child boxes
//! stored as SoA rows, triangle leaves as 8-lane packets, see `crate::bvh8`), with eight
//! SIMD lanes: one ray against eight child boxes is a dozen lane-wise multiply-adds and
//! min/max with no decoding, and one ray against the up to eight triangles of a leaf is one
//! pass of the watertight test. The kernels are generic over the lane implementation
//! (`crate::simd8`) and instantiated twice, selected by [`Kernel`]: portable code, and AVX2
//! with FMA in the node test, chosen at run time when the CPU has them. The node test
//! honours the ray's `tmin` and widens every slab by a bound on its floating-point error (a
//! per-ray constant, see `NODE_SLACK`), so a box is never culled when the primitive test
//! would report a hit inside it (a plain slab test loses rays grazing box faces, e.g. along
//! the edges of an axis-aligned mesh); it also culls, with exact comparisons, children
//! whose box lies wholly behind the origin across an axis, which the triangle test would
//! reject anyway, so a ray spawned on a wall does not visit the wall's leaf (a third of
//! the leaf visits on the Cornell box). Closest-hit rays visit hit children, leaves
//! included, nearest entry distance first and skip stacked ones beyond the closest hit so
//! far; shadow rays test a node's hit leaves at once and stop at the first hit.
//! Primitive tests:
//! - triangles: watertight test of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle
//!   Intersection", JCGT 2(1)), two-sided. The scalar form ([`WatertightRay`]) works on
//!   triangles stored coordinate by coordinate ([`PackedTriangle`]) so the three vertices
//!   are sheared and the three edge functions evaluated together; the leaf packets run the
//!   same operations in the same order with one triangle per lane (bit-identical results,
//!   no fused multiply-add), and leave lanes with an edge function exactly zero to the
//!   scalar test and its double-precision fallback. Rays through shared edges and vertices
//!   of a closed mesh cannot slip through;
//! - spheres: the quadratic in the form of Haines et al. 2019 ("Precision Improvements for
//!   Ray/Sphere Intersection", Ray Tracing Gems ch. 7), evaluated in double precision so
//!   tiny spheres far away and huge spheres seen from close by stay accurate.
//!
//! Hits are accepted for `tmin < t < tmax`; a triangle hit must also be farther beyond
//! `tmin` than the rounding-error bound of its computed `t` (pbrt-v4's conservative t, with
//! the terms that grow with the distance to the origin tightened, see `t_error_bound`), so
//! that rays spawned on a large triangle, or walks that restart just past a hit, do not find
//! the same surface again. For rays from a free origin ([`FREE_ORIGIN`], camera rays) a hit
//! within the f32 bound is decided again in double precision, whose bound is 2^29 times
//! smaller: a camera 1e-6 above a 40-unit floor sees the floor.
//!
//! Instances ([`SceneGeometry::build_with_instances`]): a top-level leaf may be an instance
//! (flagged like a sphere leaf, so only the sphere branch tests for it); the ray is mapped
//! into the instance's object space by the inverse transform (direction not renormalised, so
//! `t` and `tmax` carry over), its per-ray constants are set up for that one ray, and the
//! object's own BVH is traversed with a second stack. The visitors take a `TOP` const
//! parameter: object-level visitors have no instance branch, so two levels are all there is.
//!
//! | file | holds |
//! |---|---|
//! | `intersect.rs` | the kernels' choice ([`Kernel`]), the traversals, the closest-hit and occlusion kernels |
//! | `intersect/all_hits.rs` | [`intersect_all`]: every hit along a segment, for walks past their hits |
//! | `intersect/ray_block.rs` | per-ray constants eight rays at a time, the 8-wide node test |
//! | `intersect/packet.rs` | the watertight test on a leaf's eight triangles at once |
//! | `intersect/triangle.rs` | the scalar watertight test and the error bound of its `t` |
//! | `intersect/sphere.rs` | the double-precision sphere roots |
//! | `intersect/instance_tests.rs` | instanced hits against flat copies and the analytic ellipsoid |

use std::marker::PhantomData;

use glam::{Vec3, Vec3A, Vec4, Vec4Swizzles};
use risotto_components::NO_HIT;

use crate::bvh8::{
    Bvh8, InstanceLeaf, Node8, SphereLeaf, TriPacket8, INDEX_MASK, INSTANCE, LEAF, SPHERE, WIDTH,
};
use crate::geometry::{ray_to_object, SceneGeometry};
#[cfg(target_arch = "x86_64")]
use crate::simd8::Avx2;
use crate::simd8::{Backend, Lanes8, Mask8, Portable, Row8, Simd};
// The kernels' choice is the public name of `crate::simd8`'s backends, defined there so
// that the geometry, which holds one, does not depend on this module.
pub use crate::simd8::Kernel;

mod packet;
mod ray_block;
mod sphere;
mod triangle;

use packet::*;
use ray_block::*;
pub use sphere::intersect_sphere;

/// The ray of instance leaf `index` of `bvh` in its object's space (the same `t`, since
/// the direction is mapped without renormalising): the leaf, the object's BVH and the
/// one-ray block its traversal reads (what every query's instance step starts from).
#[inline(always)]
fn object_ray<S: Simd>(
    s: S,
    bvh: &Bvh8,
    index: usize,
    origin: Vec3,
    direction: Vec3,
    tmin: f32,
) -> (&InstanceLeaf, &Bvh8, RayBlock) {
    let leaf = &bvh.instances[index];
    let object = &bvh.objects[leaf.object as usize];
    let (o, d) = ray_to_object(&leaf.to_object, origin, direction);
    let mut block = RayBlock::zero();
    block.set(s, &[o], &[d], &[tmin], object.max_abs);
    (leaf, object, block)
}

#[cfg(test)]
pub(crate) use sphere::sphere_root_for_tests;
use sphere::*;
use triangle::*;
pub use triangle::{PackedTriangle, TriangleHit, WatertightRay, FREE_ORIGIN};

/// A stacked child of the closest-hit traversal ([`Node8::child`] encoding) with its entry
/// distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    t: f32,
}

impl Entry {
    /// Child `c` of `node` with entry distance `t[c]`.
    #[inline(always)]
    fn new(node: &Node8, t: &[f32; WIDTH], c: usize) -> Self {
        Self {
            child: node.child[c],
            t: t[c],
        }
    }
}

/// Closest-hit traversal of the 8-wide BVH: hit children, leaves and inner nodes alike, are
/// visited nearest entry distance first, and stacked children that start beyond the shrunk
/// `tmax` are skipped, so leaves behind the closest hit are never tested.
/// [`ClosestRay::leaf`] tests a leaf child and may shrink `tmax`.
#[inline(always)]
fn traverse_closest<S: Simd, const TOP: bool>(
    s: S,
    bvh: &Bvh8,
    ray: &NodeRay<S::F>,
    stack: &mut [Entry],
    tmax: &mut f32,
    leaf: &mut ClosestRay<'_, S, TOP>,
) {
    // A fixed slice ([`Bvh8::stack_capacity`] entries) and a local depth `sp` (a register,
    // where a `Vec`'s length would be loaded and stored through memory at every push).
    let mut sp = 0usize;
    let nodes = &bvh.nodes;
    let mut cur = 0u32;
    loop {
        if cur & LEAF == 0 {
            let node = &nodes[cur as usize];
            let (mask, tnear) = intersect_node8(s, node, ray, *tmax);
            if mask != 0 {
                let c0 = mask.trailing_zeros() as usize & 7;
                let rest = mask & (mask - 1);
                if rest == 0 {
                    cur = node.child[c0];
                    continue;
                }
                let t = tnear.to_array();
                let c1 = rest.trailing_zeros() as usize & 7;
                let rest = rest & (rest - 1);
                if rest == 0 {
                    // Two children: stack the farther, visit the nearer.
                    let (near, far) = if t[c1] < t[c0] { (c1, c0) } else { (c0, c1) };
                    stack[sp] = Entry::new(node, &t, far);
                    sp += 1;
                    cur = node.child[near];
                    continue;
                }
                // Three or more: stack all, sorted far to near (insertion sort), and visit
                // the nearest.
                let base = sp;
                stack[sp] = Entry::new(node, &t, c0);
                stack[sp + 1] = Entry::new(node, &t, c1);
                sp += 2;
                let mut m = rest;
                while m != 0 {
                    let c = m.trailing_zeros() as usize & 7;
                    m &= m - 1;
                    stack[sp] = Entry::new(node, &t, c);
                    sp += 1;
                }
                let st = &mut stack[base..sp];
                for i in 1..st.len() {
                    let e = st[i];
                    let mut j = i;
                    while j > 0 && st[j - 1].t < e.t {
                        st[j] = st[j - 1];
                        j -= 1;
                    }
                    st[j] = e;
                }
            }
        } else {
            leaf.leaf(bvh, cur, tmax);
        }
        loop {
            if sp == 0 {
                return;
            }
            sp -= 1;
            let e = stack[sp];
            if e.t <= *tmax {
                cur = e.child;
                break;
            }
        }
    }
}

/// What a leaves-first traversal ([`traverse_leaves_first`]) does at a leaf child.
trait LeafVisitor<S: Simd> {
    /// Tests leaf child `child` against the segment up to `tmax` (which it may shrink);
    /// `true` ends the traversal.
    fn visit(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) -> bool;
}

/// Traversal of the 8-wide BVH that tests the hit leaf children of a node as soon as the
/// node is visited (for shadow rays a blocker found early ends the ray, and testing them
/// costs less than stacking them), then visits the hit inner children nearest first.
/// Returns whether the visitor ended it.
#[inline(always)]
fn traverse_leaves_first<S: Simd, V: LeafVisitor<S>>(
    s: S,
    bvh: &Bvh8,
    ray: &NodeRay<S::F>,
    stack: &mut [u32],
    tmax: &mut f32,
    leaf: &mut V,
) -> bool {
    // As in `traverse_closest`: a fixed slice and a local depth.
    let mut sp = 0usize;
    let nodes = &bvh.nodes;
    let mut index = 0usize;
    loop {
        let node = &nodes[index];
        let (mask, tnear) = intersect_node8(s, node, ray, *tmax);
        let mut leaves = mask & node.leaf_mask;
        while leaves != 0 {
            let c = leaves.trailing_zeros() as usize & 7;
            leaves &= leaves - 1;
            if leaf.visit(bvh, node.child[c], tmax) {
                return true;
            }
        }
        let mut inner = mask & !node.leaf_mask;
        if inner != 0 {
            let c0 = inner.trailing_zeros() as usize & 7;
            inner &= inner - 1;
            if inner == 0 {
                index = node.child[c0] as usize;
                continue;
            }
            let t = tnear.to_array();
            // The hit inner children sorted far to near (insertion sort): all but the
            // nearest are stacked, so they are popped nearest first.
            let mut order = [0usize; WIDTH];
            order[0] = c0;
            let mut k = 1;
            while inner != 0 {
                let c = inner.trailing_zeros() as usize & 7;
                inner &= inner - 1;
                let mut j = k;
                while j > 0 && t[order[j - 1] & 7] < t[c] {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = c;
                k += 1;
            }
            for &c in &order[..k - 1] {
                stack[sp] = node.child[c & 7];
                sp += 1;
            }
            index = node.child[order[k - 1] & 7] as usize;
            continue;
        }
        if sp == 0 {
            return false;
        }
        sp -= 1;
        index = stack[sp] as usize;
    }
}

#[inline(always)]
fn check_lengths(n: usize, lens: &[usize]) {
    assert!(
        lens.iter().all(|&l| l == n),
        "column lengths differ: {n} vs {lens:?}"
    );
}

/// The columns of [`intersect_closest`].
struct ClosestColumns<'a> {
    origin: &'a [Vec3],
    direction: &'a [Vec3],
    tmin: &'a [f32],
    tmax: &'a [f32],
    t: &'a mut [f32],
    prim: &'a mut [u32],
    b1: &'a mut [f32],
    b2: &'a mut [f32],
}

/// No sphere hit: the closest hit so far is a triangle or nothing.
const NO_SPHERE: u32 = u32::MAX;

/// A closest-hit ray during traversal: its constants and the closest hit so far. `TOP`:
/// a ray of the top-level BVH, which may reach instance leaves; an object-level ray (in an
/// instance's object space) never does, and has no code for them.
struct ClosestRay<'a, S: Simd, const TOP: bool> {
    s: S,
    tri: PacketRay<'a, S::F>,
    tmin: f32,
    prim: u32,
    /// Sphere leaf of the closest hit, or [`NO_SPHERE`].
    sphere: u32,
    /// The double-precision root of the closest sphere hit (when `sphere` is one).
    sphere_t: f64,
    b1: f32,
    b2: f32,
    /// The stack of the traversals of instances' objects ([`Bvh8::object_stack_capacity`];
    /// empty without instances and at object level).
    object_stack: &'a mut [Entry],
}

impl<S: Simd, const TOP: bool> ClosestRay<'_, S, TOP> {
    /// Tests leaf child `child`, shrinking `tmax` to a closer hit.
    #[inline(always)]
    fn leaf(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) {
        let index = (child & INDEX_MASK) as usize;
        if child & SPHERE != 0 {
            if TOP && child & INSTANCE != 0 {
                self.instance(bvh, index, tmax);
                return;
            }
            let leaf = &bvh.spheres[index];
            let (o, d) = (self.tri.origin(), self.tri.direction());
            if let Some(t64) = sphere_leaf_t64(leaf, o, d, self.tmin, *tmax) {
                let ts = t64 as f32;
                if ts < *tmax {
                    *tmax = ts;
                    self.prim = leaf.prim;
                    self.sphere = index as u32;
                    self.sphere_t = t64;
                }
            }
            return;
        }
        let p = &bvh.packets[index];
        let r = intersect_packet(self.s, &self.tri, p, self.tmin, *tmax);
        let mut lanes = (r.hit | r.fallback) & p.valid;
        if lanes == 0 {
            return;
        }
        let (t, b1, b2) = (r.t.to_array(), r.b1.to_array(), r.b2.to_array());
        // Lanes in order, each kept only if nearer than the best so far: the same hit as
        // testing the triangles one by one (ties go to the lower lane).
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize & 7;
            lanes &= lanes - 1;
            let h = if r.fallback & (1 << l) == 0 {
                TriangleHit {
                    t: t[l],
                    b1: b1[l],
                    b2: b2[l],
                }
            } else {
                let (o, d) = (self.tri.origin().into(), self.tri.direction().into());
                match packet_lane_scalar(p, l, o, d, self.tmin, *tmax) {
                    Some(h) => h,
                    None => continue,
                }
            };
            if h.t < *tmax {
                *tmax = h.t;
                self.prim = p.prim[l];
                self.sphere = NO_SPHERE;
                self.b1 = h.b1;
                self.b2 = h.b2;
            }
        }
    }

    /// Traverses the object of instance leaf `index` with the ray mapped into its object
    /// space (same `t`), taking a closer hit with its primitive numbered in the scene.
    #[inline(always)]
    fn instance(&mut self, bvh: &Bvh8, index: usize, tmax: &mut f32) {
        let s = self.s;
        let (leaf, object, block) = object_ray(
            s,
            bvh,
            index,
            self.tri.origin(),
            self.tri.direction(),
            self.tmin,
        );
        let node_ray = NodeRay::new(s, &block, 0, self.tmin);
        let mut inner = ClosestRay::<S, false> {
            s,
            tri: PacketRay::new(s, &block, 0),
            tmin: self.tmin,
            prim: NO_HIT,
            sphere: NO_SPHERE,
            sphere_t: 0.0,
            b1: 0.0,
            b2: 0.0,
            object_stack: &mut [],
        };
        traverse_closest(s, object, &node_ray, self.object_stack, tmax, &mut inner);
        if inner.prim != NO_HIT {
            self.prim = leaf.prim_base + inner.prim;
            self.sphere = inner.sphere;
            self.sphere_t = inner.sphere_t;
            self.b1 = inner.b1;
            self.b2 = inner.b2;
        }
    }
}

/// [`intersect_closest`] on the lanes of `s`.
#[inline(always)]
fn closest_kernel<S: Simd>(s: S, bvh: &Bvh8, c: ClosestColumns) {
    let mut stack = vec![Entry { child: 0, t: 0.0 }; bvh.stack_capacity()];
    let mut object_stack = vec![Entry { child: 0, t: 0.0 }; bvh.object_stack_capacity()];
    let mut block = RayBlock::zero();
    // Every column cut to the same length, so that indexing needs no bounds checks.
    let n = c.origin.len();
    let (origin, direction) = (&c.origin[..n], &c.direction[..n]);
    let (tmin, tmax) = (&c.tmin[..n], &c.tmax[..n]);
    let (t, prim) = (&mut c.t[..n], &mut c.prim[..n]);
    let (b1, b2) = (&mut c.b1[..n], &mut c.b2[..n]);
    for start in (0..n).step_by(BLOCK) {
        let end = n.min(start + BLOCK);
        block.set(
            s,
            &origin[start..end],
            &direction[start..end],
            &tmin[start..end],
            bvh.max_abs,
        );
        for i in start..end {
            let (lane, ray_tmin) = (i - start, tmin[i]);
            let node_ray = NodeRay::new(s, &block, lane, ray_tmin);
            let mut ray = ClosestRay::<S, true> {
                s,
                tri: PacketRay::new(s, &block, lane),
                tmin: ray_tmin,
                prim: NO_HIT,
                sphere: NO_SPHERE,
                sphere_t: 0.0,
                b1: 0.0,
                b2: 0.0,
                object_stack: &mut object_stack,
            };
            let mut best_t = tmax[i];
            traverse_closest(s, bvh, &node_ray, &mut stack, &mut best_t, &mut ray);
            if ray.prim == NO_HIT {
                t[i] = f32::INFINITY;
                prim[i] = NO_HIT;
                b1[i] = 0.0;
                b2[i] = 0.0;
            } else {
                if ray.sphere != NO_SPHERE {
                    (ray.b1, ray.b2) = sphere_hit_params(ray.sphere_t);
                }
                t[i] = best_t;
                prim[i] = ray.prim;
                b1[i] = ray.b1;
                b2[i] = ray.b2;
            }
        }
    }
}

/// The columns of [`intersect_occluded`].
struct OccludedColumns<'a> {
    origin: &'a [Vec3],
    direction: &'a [Vec3],
    tmin: &'a [f32],
    tmax: &'a [f32],
    occluded: &'a mut [bool],
}

/// A shadow ray's constants during traversal (`TOP` as for [`ClosestRay`]).
struct AnyRay<'a, S: Simd, const TOP: bool> {
    s: S,
    tri: PacketRay<'a, S::F>,
    tmin: f32,
    /// The stack of the instances' traversals (as [`ClosestRay::object_stack`]).
    object_stack: &'a mut [u32],
}

impl<S: Simd, const TOP: bool> LeafVisitor<S> for AnyRay<'_, S, TOP> {
    /// Whether leaf child `child` has a hit before `tmax` (which stays).
    #[inline(always)]
    fn visit(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) -> bool {
        let index = (child & INDEX_MASK) as usize;
        let tmax = *tmax;
        if child & SPHERE != 0 {
            if TOP && child & INSTANCE != 0 {
                return self.instance(bvh, index, tmax);
            }
            let (o, d) = (self.tri.origin(), self.tri.direction());
            return sphere_leaf_t(&bvh.spheres[index], o, d, self.tmin, tmax) < f32::INFINITY;
        }
        let p = &bvh.packets[index];
        let r = intersect_packet(self.s, &self.tri, p, self.tmin, tmax);
        if r.hit != 0 {
            return true;
        }
        let mut fallback = r.fallback & p.valid;
        while fallback != 0 {
            let l = fallback.trailing_zeros() as usize & 7;
            fallback &= fallback - 1;
            let (o, d) = (self.tri.origin().into(), self.tri.direction().into());
            if packet_lane_scalar(p, l, o, d, self.tmin, tmax).is_some() {
                return true;
            }
        }
        false
    }
}

impl<S: Simd, const TOP: bool> AnyRay<'_, S, TOP> {
    /// Whether the object of instance leaf `index` has a hit before `tmax`, with the ray
    /// mapped into its object space (same `t`).
    #[inline(always)]
    fn instance(&mut self, bvh: &Bvh8, index: usize, tmax: f32) -> bool {
        let s = self.s;
        let (_, object, block) = object_ray(
            s,
            bvh,
            index,
            self.tri.origin(),
            self.tri.direction(),
            self.tmin,
        );
        let node_ray = NodeRay::new(s, &block, 0, self.tmin);
        let mut inner = AnyRay::<S, false> {
            s,
            tri: PacketRay::new(s, &block, 0),
            tmin: self.tmin,
            object_stack: &mut [],
        };
        let mut t = tmax;
        traverse_leaves_first(s, object, &node_ray, self.object_stack, &mut t, &mut inner)
    }
}

/// [`intersect_occluded`] on the lanes of `s`.
#[inline(always)]
fn occluded_kernel<S: Simd>(s: S, bvh: &Bvh8, c: OccludedColumns) {
    let mut stack = vec![0u32; bvh.stack_capacity()];
    let mut object_stack = vec![0u32; bvh.object_stack_capacity()];
    let mut block = RayBlock::zero();
    // Every column cut to the same length, so that indexing needs no bounds checks.
    let n = c.origin.len();
    let (origin, direction) = (&c.origin[..n], &c.direction[..n]);
    let (tmin, tmax, occluded) = (&c.tmin[..n], &c.tmax[..n], &mut c.occluded[..n]);
    for start in (0..n).step_by(BLOCK) {
        let end = n.min(start + BLOCK);
        block.set(
            s,
            &origin[start..end],
            &direction[start..end],
            &tmin[start..end],
            bvh.max_abs,
        );
        for i in start..end {
            let (lane, ray_tmin) = (i - start, tmin[i]);
            let node_ray = NodeRay::new(s, &block, lane, ray_tmin);
            let mut ray = AnyRay::<S, true> {
                s,
                tri: PacketRay::new(s, &block, lane),
                tmin: ray_tmin,
                object_stack: &mut object_stack,
            };
            let mut ray_tmax = tmax[i];
            occluded[i] =
                traverse_leaves_first(s, bvh, &node_ray, &mut stack, &mut ray_tmax, &mut ray);
        }
    }
}

/// Defines `$dispatch(backend, bvh, columns)`, which runs the kernel `$kernel` (generic over
/// the lanes) on `backend`: its portable instantiation, or the one compiled with AVX2 and
/// FMA enabled (`$avx2`, chosen only where the CPU has them).
macro_rules! kernel_dispatch {
    ($dispatch:ident, $avx2:ident, $kernel:ident, $columns:ident) => {
        #[cfg(target_arch = "x86_64")]
        #[allow(
            unsafe_code,
            reason = "enables AVX2 and FMA for the kernel instantiation"
        )]
        #[target_feature(enable = "avx2,fma")]
        unsafe fn $avx2(s: Avx2, bvh: &Bvh8, c: $columns) {
            $kernel(s, bvh, c)
        }

        #[allow(
            unsafe_code,
            reason = "calls the AVX2 kernel on a CPU checked to have AVX2"
        )]
        fn $dispatch(backend: Backend, bvh: &Bvh8, c: $columns) {
            #[inline(never)]
            fn portable(bvh: &Bvh8, c: $columns) {
                $kernel(Portable, bvh, c)
            }
            match backend {
                Backend::Portable => portable(bvh, c),
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the token exists only if `Avx2::detect` found AVX2 and FMA on
                // this CPU.
                Backend::Avx2(s) => unsafe { $avx2(s, bvh, c) },
            }
        }
    };
}

kernel_dispatch!(
    closest_dispatch,
    closest_avx2,
    closest_kernel,
    ClosestColumns
);
kernel_dispatch!(
    occluded_dispatch,
    occluded_avx2,
    occluded_kernel,
    OccludedColumns
);

/// Closest hit of every ray `origin[i] + t * direction[i]` with `tmin[i] < t < tmax[i]`.
///
/// Writes the hit distance, the primitive index (see [`SceneGeometry`]) and the surface
/// parameters: barycentrics `(b1, b2)` for triangles, `(phi / 2pi, theta / pi)` for spheres
/// (as [`SceneGeometry::surface_at`] expects). A miss writes `prim = NO_HIT`,
/// `t = f32::INFINITY` and zero parameters. Of two hits at exactly the same distance either
/// may be reported. Runs the geometry's [`Kernel`].
///
/// # Panics
/// If the columns have different lengths.
#[allow(clippy::too_many_arguments, reason = "one slice per SoA column")]
pub fn intersect_closest(
    geom: &SceneGeometry,
    origin: &[Vec3],
    direction: &[Vec3],
    tmin: &[f32],
    tmax: &[f32],
    t: &mut [f32],
    prim: &mut [u32],
    b1: &mut [f32],
    b2: &mut [f32],
) {
    let n = origin.len();
    check_lengths(
        n,
        &[
            direction.len(),
            tmin.len(),
            tmax.len(),
            t.len(),
            prim.len(),
            b1.len(),
            b2.len(),
        ],
    );
    let Some((bvh, backend)) = geom.bvh8() else {
        t.fill(f32::INFINITY);
        prim.fill(NO_HIT);
        b1.fill(0.0);
        b2.fill(0.0);
        return;
    };
    closest_dispatch(
        backend,
        bvh,
        ClosestColumns {
            origin,
            direction,
            tmin,
            tmax,
            t,
            prim,
            b1,
            b2,
        },
    );
}

/// Whether each ray `origin[i] + t * direction[i]` hits anything with
/// `tmin[i] < t < tmax[i]` (shadow rays). Stops at the first hit found. Runs the
/// geometry's [`Kernel`].
///
/// # Panics
/// If the columns have different lengths.
pub fn intersect_occluded(
    geom: &SceneGeometry,
    origin: &[Vec3],
    direction: &[Vec3],
    tmin: &[f32],
    tmax: &[f32],
    occluded: &mut [bool],
) {
    let n = origin.len();
    check_lengths(
        n,
        &[direction.len(), tmin.len(), tmax.len(), occluded.len()],
    );
    let Some((bvh, backend)) = geom.bvh8() else {
        occluded.fill(false);
        return;
    };
    occluded_dispatch(
        backend,
        bvh,
        OccludedColumns {
            origin,
            direction,
            tmin,
            tmax,
            occluded,
        },
    );
}

mod all_hits;
pub use all_hits::{intersect_all, NextHit, RayHits, MAX_HITS};

#[cfg(test)]
mod binned_tests;
#[cfg(test)]
mod instance_tests;
#[cfg(test)]
mod surface_tests;
#[cfg(test)]
mod tests;
