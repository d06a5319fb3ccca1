//! Every hit along each ray from one traversal, for walks that go on past the hits they
//! find (shadow rays through boundaries and media, `risotto_engine::transmission`).
//!
//! Such a walk asks, at each step, for the closest hit beyond `t0` (the last hit, moved
//! past by its error offset), and restarts from the root of the tree each time. One
//! traversal that records the [`MAX_HITS`] nearest hits of the whole segment answers most
//! of those questions at once. [`RayHits::next_after`] then says what a closest-hit query
//! ([`intersect_closest`](super::intersect_closest)) from a later `t0` would report, and
//! says [`NextHit::Query`] where the list cannot: a triangle hit close enough to `t0` that
//! its acceptance depends on the exact error bound of its `t` (see `t_error_bound`), a hit
//! the scalar fallback test decided, or the end of a full list.
//!
//! Replaying a later query from the list is exact because nothing in a hit but its
//! acceptance depends on `tmin`: the origin and direction stay those of the ray, so every
//! primitive test computes the same `t` and parameters; the triangle test accepts a hit
//! where `t > tmin` and `t - tmin` exceeds the error bound of `t`, which depends on the
//! triangle and the ray only ([`RayHits::bound`] keeps an upper bound of it); a sphere hit
//! is accepted where `t > tmin`. Of two hits at the same distance either may come first,
//! as for [`intersect_closest`](super::intersect_closest).

use super::*;

/// Hits kept per ray by [`intersect_all`]: enough for a shadow ray to cross two convex
/// volumes (four boundaries) with one traversal; rays with more query again.
pub const MAX_HITS: usize = 4;

/// The nearest hits of one ray with `tmin < t < tmax`, sorted by distance: the output of
/// [`intersect_all`]. Hit `j` (for `j < len`) is `t[j]`, `prim[j]`, and the surface
/// parameters `b1[j]`, `b2[j]` as [`intersect_closest`](super::intersect_closest) would
/// report them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHits {
    /// Hit distances, nondecreasing.
    pub t: [f32; MAX_HITS],
    /// Primitive indices ([`SceneGeometry`]).
    pub prim: [u32; MAX_HITS],
    /// First surface parameter (barycentric `b1`, or a sphere root's residual).
    pub b1: [f32; MAX_HITS],
    /// Second surface parameter (barycentric `b2`, or 0 on a sphere).
    pub b2: [f32; MAX_HITS],
    /// Per hit, a distance past a later `tmin` beyond which a query from that `tmin` would
    /// certainly accept the hit: an upper bound of a triangle hit's `t` error bound, 0 for
    /// a sphere, infinite for a hit decided by the scalar fallback test (whose acceptance
    /// only a new query decides).
    pub bound: [f32; MAX_HITS],
    /// Number of hits held.
    pub len: u8,
    /// Whether the segment has no hits beyond those held. `false` once the list is full:
    /// hits beyond the last one held are then unknown.
    pub complete: bool,
}

impl RayHits {
    /// No hits, nothing known beyond.
    pub const EMPTY: Self = Self {
        t: [f32::INFINITY; MAX_HITS],
        prim: [NO_HIT; MAX_HITS],
        b1: [0.0; MAX_HITS],
        b2: [0.0; MAX_HITS],
        bound: [0.0; MAX_HITS],
        len: 0,
        complete: false,
    };

    /// What a closest-hit query of the same ray from `tmin` (to the same `tmax`) would
    /// report, looking at the hits from index `from` on (those before it were taken
    /// already, and `tmin` lies past them).
    #[inline]
    pub fn next_after(&self, from: usize, tmin: f32) -> NextHit {
        for j in from..(self.len as usize).min(MAX_HITS) {
            let t = self.t[j];
            if t <= tmin {
                // Behind `tmin` (a hit at the distance of the one just taken): rejected.
                continue;
            }
            // The triangle test's comparison, `!(gap <= bound)` (no NaN here: `t` is a
            // hit's finite distance).
            if t - tmin > self.bound[j] {
                return NextHit::Hit(j);
            }
            // Within the bound: only the exact bound of a new query decides.
            return NextHit::Query;
        }
        if self.complete {
            NextHit::Miss
        } else {
            NextHit::Query
        }
    }

    /// Inserts a hit in distance order, keeping the [`MAX_HITS`] nearest; `tmax` shrinks
    /// to the farthest held once the list is full (farther hits are not needed).
    #[inline(always)]
    fn insert(&mut self, t: f32, prim: u32, b1: f32, b2: f32, bound: f32, tmax: &mut f32) {
        let mut j = self.len as usize;
        if j == MAX_HITS {
            if t >= self.t[MAX_HITS - 1] {
                return;
            }
            j -= 1;
        } else {
            self.len += 1;
        }
        while j > 0 && self.t[j - 1] > t {
            self.t[j] = self.t[j - 1];
            self.prim[j] = self.prim[j - 1];
            self.b1[j] = self.b1[j - 1];
            self.b2[j] = self.b2[j - 1];
            self.bound[j] = self.bound[j - 1];
            j -= 1;
        }
        self.t[j] = t;
        self.prim[j] = prim;
        self.b1[j] = b1;
        self.b2[j] = b2;
        self.bound[j] = bound;
        if self.len as usize == MAX_HITS {
            self.complete = false;
            *tmax = self.t[MAX_HITS - 1];
        }
    }
}

/// The answer of [`RayHits::next_after`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NextHit {
    /// Hit `j` of the list.
    Hit(usize),
    /// No hit up to `tmax`.
    Miss,
    /// The list cannot tell: query again from `tmin`.
    Query,
}

/// A ray collecting every hit during traversal.
struct AllRay<'a, S: Simd, const TOP: bool> {
    s: S,
    tri: PacketRay<'a, S::F>,
    tmin: f32,
    hits: RayHits,
    /// The stack of the instances' traversals (as for closest hits; empty at object level).
    object_stack: &'a mut [u32],
    /// Added to the primitive indices of hits (an instance's first primitive at object
    /// level, 0 at the top).
    prim_base: u32,
}

/// All-hits traversal is [`traverse_leaves_first`] with a visitor that never ends it and
/// shrinks `tmax` only once the ray's list is full.
impl<S: Simd, const TOP: bool> LeafVisitor<S> for AllRay<'_, S, TOP> {
    /// Records the hits of leaf child `child` before `tmax` (which shrinks when the list
    /// fills).
    #[inline(always)]
    fn visit(&mut self, bvh: &Bvh8, child: u32, tmax: &mut f32) -> bool {
        let index = (child & INDEX_MASK) as usize;
        if child & SPHERE != 0 {
            if TOP && child & INSTANCE != 0 {
                self.instance(bvh, index, tmax);
                return false;
            }
            let leaf = &bvh.spheres[index];
            let (o, d) = (self.tri.origin(), self.tri.direction());
            let cr = leaf.center_radius;
            if let Some((t0, t1)) = sphere_roots64(o, d, cr.truncate(), cr.w, self.tmin, *tmax) {
                for root in [t0, t1] {
                    if sphere_root_in_range(root, self.tmin, *tmax) {
                        let (b1, b2) = sphere_hit_params(root);
                        self.hits.insert(
                            root as f32,
                            self.prim_base + leaf.prim,
                            b1,
                            b2,
                            0.0,
                            tmax,
                        );
                    }
                }
            }
            return false;
        }
        let p = &bvh.packets[index];
        let r = intersect_packet(self.s, &self.tri, p, self.tmin, *tmax);
        let mut lanes = (r.hit | r.fallback) & p.valid;
        if lanes == 0 {
            return false;
        }
        let (t, b1, b2) = (r.t.to_array(), r.b1.to_array(), r.b2.to_array());
        let bound = r.bound.to_array();
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize & 7;
            lanes &= lanes - 1;
            if r.fallback & (1 << l) == 0 {
                self.hits.insert(
                    t[l],
                    self.prim_base + p.prim[l],
                    b1[l],
                    b2[l],
                    bound[l],
                    tmax,
                );
            } else {
                let (o, d) = (self.tri.origin().into(), self.tri.direction().into());
                if let Some(h) = packet_lane_scalar(p, l, o, d, self.tmin, *tmax) {
                    self.hits.insert(
                        h.t,
                        self.prim_base + p.prim[l],
                        h.b1,
                        h.b2,
                        f32::INFINITY,
                        tmax,
                    );
                }
            }
        }
        false
    }
}

impl<S: Simd, const TOP: bool> AllRay<'_, S, TOP> {
    /// Collects the hits on the object of instance leaf `index` into this ray's list (the
    /// ray mapped into its object space, same `t`; the list's `tmax` shrinking as it
    /// fills), numbered in the scene.
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
        let mut inner = AllRay::<S, false> {
            s,
            tri: PacketRay::new(s, &block, 0),
            tmin: self.tmin,
            hits: self.hits,
            object_stack: &mut [],
            prim_base: leaf.prim_base,
        };
        traverse_leaves_first(s, object, &node_ray, self.object_stack, tmax, &mut inner);
        self.hits = inner.hits;
    }
}

/// The columns of [`intersect_all`].
struct AllColumns<'a> {
    origin: &'a [Vec3],
    direction: &'a [Vec3],
    tmin: &'a [f32],
    tmax: &'a [f32],
    hits: &'a mut [RayHits],
}

/// [`intersect_all`] on the lanes of `s`.
#[inline(always)]
fn all_kernel<S: Simd>(s: S, bvh: &Bvh8, c: AllColumns) {
    let mut stack = vec![0u32; bvh.stack_capacity()];
    let mut object_stack = vec![0u32; bvh.object_stack_capacity()];
    let mut block = RayBlock::zero();
    let n = c.origin.len();
    let (origin, direction) = (&c.origin[..n], &c.direction[..n]);
    let (tmin, tmax, hits) = (&c.tmin[..n], &c.tmax[..n], &mut c.hits[..n]);
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
            let mut ray = AllRay::<S, true> {
                s,
                tri: PacketRay::new(s, &block, lane),
                tmin: ray_tmin,
                hits: RayHits {
                    complete: true,
                    ..RayHits::EMPTY
                },
                object_stack: &mut object_stack,
                prim_base: 0,
            };
            let mut ray_tmax = tmax[i];
            traverse_leaves_first(s, bvh, &node_ray, &mut stack, &mut ray_tmax, &mut ray);
            hits[i] = ray.hits;
        }
    }
}

kernel_dispatch!(all_dispatch, all_avx2, all_kernel, AllColumns);

/// The [`MAX_HITS`] nearest hits of every ray `origin[i] + t * direction[i]` with
/// `tmin[i] < t < tmax[i]`, each accepted as [`intersect_closest`](super::intersect_closest)
/// would accept it from `tmin[i]`, into `hits[i]` (see [`RayHits`]; where there are more,
/// `complete` is false). Runs the geometry's [`Kernel`].
///
/// # Panics
/// If the columns have different lengths.
pub fn intersect_all(
    geom: &SceneGeometry,
    origin: &[Vec3],
    direction: &[Vec3],
    tmin: &[f32],
    tmax: &[f32],
    hits: &mut [RayHits],
) {
    let n = origin.len();
    check_lengths(n, &[direction.len(), tmin.len(), tmax.len(), hits.len()]);
    let Some((bvh, backend)) = geom.bvh8() else {
        hits.fill(RayHits {
            complete: true,
            ..RayHits::EMPTY
        });
        return;
    };
    all_dispatch(
        backend,
        bvh,
        AllColumns {
            origin,
            direction,
            tmin,
            tmax,
            hits,
        },
    );
}

#[cfg(test)]
mod tests;
