//! The watertight test on the eight triangles of a leaf packet at once, bit-identical to
//! the scalar test ([`super::triangle`]) lane by lane.

use super::*;

/// Ray `l` of a [`RayBlock`] for the packet triangle test: [`WatertightRay`]'s constants,
/// kept in the block and broadcast to the triangle lanes in [`intersect_packet`] (as
/// [`NodeRay`]'s).
pub(super) struct PacketRay<'a, F> {
    pub(super) block: &'a RayBlock,
    pub(super) lane: usize,
    pub(super) kx: Axis,
    pub(super) ky: Axis,
    pub(super) kz: Axis,
    pub(super) lanes: PhantomData<F>,
}

impl<'a, F: Lanes8> PacketRay<'a, F> {
    #[inline(always)]
    pub(super) fn new<S: Simd<F = F>>(_: S, block: &'a RayBlock, lane: usize) -> Self {
        let lane = lane % BLOCK;
        let [kx, ky, kz] = block.axes(lane);
        Self {
            block,
            lane,
            kx,
            ky,
            kz,
            lanes: PhantomData,
        }
    }

    /// The ray's origin (for the sphere and scalar fallback tests).
    #[inline(always)]
    pub(super) fn origin(&self) -> Vec3 {
        self.block.origin(self.lane)
    }

    /// The ray's direction.
    #[inline(always)]
    pub(super) fn direction(&self) -> Vec3 {
        self.block.direction(self.lane)
    }
}

/// [`PacketRay`]'s constants on every lane, for one packet test.
pub(super) struct PacketLanes<F> {
    pub(super) ox: F,
    pub(super) oy: F,
    pub(super) oz: F,
    pub(super) sx: F,
    pub(super) sy: F,
    pub(super) sz: F,
}

/// The outcome of [`intersect_packet`]: lanes accepted (`hit`, with their `t` and
/// barycentrics; the vectors are meaningless where `hit` is 0) and lanes left to the scalar
/// test (`fallback`: an edge function is exactly zero, or, for a free origin, the hit lies
/// within the f32 error bound of the origin; both are resolved in f64 there).
pub(super) struct PacketHits<F> {
    pub(super) hit: u32,
    pub(super) fallback: u32,
    pub(super) t: F,
    pub(super) b1: F,
    pub(super) b2: F,
    /// Per accepted lane, an upper bound on the error bound of its `t`: a later query from
    /// any `tmin' < t` accepts the hit if `t - tmin' > bound` (what
    /// [`intersect_all`](all_hits) records to replay those queries).
    pub(super) bound: F,
}

/// One vertex of eight triangles translated, permuted and sheared, as in the scalar test:
/// `(A[kx] - Sx A[kz], A[ky] - Sy A[kz], A[kz])` with `A` relative to the origin.
#[inline(always)]
pub(super) fn shear_vertex<S: Simd>(
    s: S,
    r: &PacketRay<S::F>,
    l: &PacketLanes<S::F>,
    v: &[Row8; 3],
) -> (S::F, S::F, S::F) {
    let z = s.load(&v[r.kz as usize]) - l.oz;
    let x = (s.load(&v[r.kx as usize]) - l.ox) - l.sx * z;
    let y = (s.load(&v[r.ky as usize]) - l.oy) - l.sy * z;
    (x, y, z)
}

/// The watertight test of [`WatertightRay::intersect_packed`] on the eight triangles of a
/// packet at once, with the same operations in the same order on every lane (no fused
/// multiply-add), so a lane's `t`, barycentrics and decision are bit-identical to the
/// scalar test's on that triangle. Lanes with an edge function exactly zero, and lanes of a
/// free-origin ray whose hit lies within the error bound, are reported in `fallback`
/// instead.
#[inline(always)]
pub(super) fn intersect_packet<S: Simd>(
    s: S,
    r: &PacketRay<S::F>,
    p: &TriPacket8,
    tmin: f32,
    tmax: f32,
) -> PacketHits<S::F> {
    // `black_box`: see `intersect_node8` (keeps the broadcasts here, out of the set-up).
    let k = std::hint::black_box(&r.block.tri);
    let lane = r.lane % BLOCK;
    let l = PacketLanes {
        ox: s.splat(k[0][lane]),
        oy: s.splat(k[1][lane]),
        oz: s.splat(k[2][lane]),
        sx: s.splat(k[3][lane]),
        sy: s.splat(k[4][lane]),
        sz: s.splat(k[5][lane]),
    };
    let (x0, y0, z0) = shear_vertex(s, r, &l, &p.v[0]);
    let (x1, y1, z1) = shear_vertex(s, r, &l, &p.v[1]);
    let (x2, y2, z2) = shear_vertex(s, r, &l, &p.v[2]);
    // The lanes (U, V, W) of the scalar test, one triangle per lane.
    let u = x2 * y1 - y2 * x1;
    let v = x0 * y2 - y0 * x2;
    let w = x1 * y0 - y1 * x0;
    let zero = s.splat(0.0);
    let fallback = (u.eq(zero) | v.eq(zero) | w.eq(zero)).bits();
    let (all_neg, any_neg) = u.sign_bits_all_any(v, w);
    let same_sign = all_neg | !any_neg;
    let mut hit = same_sign & !fallback & 0xff;
    if hit == 0 {
        return PacketHits {
            hit,
            fallback,
            t: u,
            b1: v,
            b2: w,
            bound: u,
        };
    }
    let det = u + v + w;
    hit &= !det.eq(zero).bits();
    let (z0, z1, z2) = (z0 * l.sz, z1 * l.sz, z2 * l.sz);
    let scaled_t = u * z0 + v * z1 + w * z2;
    let inv_det = s.splat(1.0) / det;
    let t = scaled_t * inv_det;
    let below_tmax = t.lt(s.splat(tmax)).bits();
    // Rays from a free origin also look again at hits f32 put at or behind it (`near`).
    let behind = if from_free_origin(tmin) {
        hit & below_tmax & !t.gt(zero).bits()
    } else {
        0
    };
    hit &= t.gt(s.splat(tmin)).bits() & below_tmax;
    if hit | behind == 0 {
        return PacketHits {
            hit,
            fallback,
            t,
            b1: v,
            b2: w,
            bound: t,
        };
    }
    // `t_error_bound` per lane, the same operations (max is exact, so the order of the
    // maxima is free).
    let max_x = x0.abs().max(x1.abs()).max(x2.abs());
    let max_y = y0.abs().max(y1.abs()).max(y2.abs());
    let max_z = z0.abs().max(z1.abs()).max(z2.abs());
    let (g2, g3, g7) = (
        s.splat(gamma(2.0)),
        s.splat(gamma(3.0)),
        s.splat(gamma(7.0)),
    );
    let (adx, ady) = (s.splat(k[6][lane]), s.splat(k[7][lane]));
    let delta_z = g3 * max_z;
    let delta_x = g7 * (max_x + adx * max_z);
    let delta_y = g7 * (max_y + ady * max_z);
    let delta_e = s.splat(2.0) * (g2 * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let kk = s.splat(3.0) * delta_e * inv_det.abs();
    let base = s.splat(gamma(10.0)) * max_z;
    let gap = t - s.splat(tmin);
    // The bound with `min(lever, max_z)` taken as `max_z` is at least the bound (rounding
    // is monotone), so hits beyond it are accepted without the lever: nearly every hit,
    // so the weighted-mean term is only computed for hits close to `tmin`.
    let bound_max = base + kk * max_z;
    let sure = hit & !gap.le(bound_max).bits();
    let mut keep = sure;
    if sure != hit {
        let spread = (z0 - t).abs().max((z1 - t).abs()).max((z2 - t).abs());
        let lever = S::F::select(
            kk.le(s.splat(0.5)),
            (s.splat(1.0) + s.splat(2.0) * kk) * (spread + delta_z),
            max_z,
        );
        keep = hit & !gap.le(base + kk * lever.min(max_z)).bits();
    }
    // Rays from a free origin decide hits within the bound of it in double precision (the
    // scalar test's `near_hit_f64`), on either side (the larger bound: the f64 test
    // decides exactly).
    let fallback = if from_free_origin(tmin) {
        let near_behind = behind & (zero - t).le(bound_max).bits();
        fallback | (hit & !keep) | near_behind
    } else {
        fallback
    };
    hit = keep;
    PacketHits {
        hit,
        fallback,
        t,
        b1: v * inv_det,
        b2: w * inv_det,
        bound: bound_max,
    }
}

/// The scalar test on lane `l` of a packet, for lanes [`intersect_packet`] leaves to it.
#[cold]
#[inline(never)]
pub(super) fn packet_lane_scalar(
    p: &TriPacket8,
    l: usize,
    o: Vec3A,
    d: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<TriangleHit> {
    let [v0, v1, v2] = p.triangle(l);
    WatertightRay::new(o.into(), d.into()).intersect_packed(
        &PackedTriangle::new(v0, v1, v2),
        tmin,
        tmax,
    )
}
