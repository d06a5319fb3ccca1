//! Per-ray constants set up eight rays at a time ([`RayBlock`]) and the 8-wide node test
//! (widened slab test plus the exact cull of boxes behind the origin).

use super::*;

/// Smallest direction component used in the slab test; `1/d` is clamped to `1e20` so no
/// infinities (and `0 * inf` NaNs) arise for axis-parallel rays.
pub(super) const MIN_DIR: f32 = 1e-20;

/// Relative slab widening of the node test. A slab distance is computed as
/// `b * inv + near_orig` with `inv = fl(1/d)` and `near_orig = fl(fl(-o * inv) -+ s)`: with
/// unit roundoff `u = 2^-24` its error against `(b - o) / d` is below
/// `u (3 |b| + 4 |o|) / |d| + 2 u s` (standard model, Higham 2002 ch. 3: two roundings in
/// `b * inv`, two in `-o * inv`, one in the widening and one in the sum; a fused
/// multiply-add drops one of them), and `|b|` is at most the largest box coordinate
/// magnitude `B` on that axis. Widening by `s = 8 u (B + |o|) |inv|` therefore covers it on
/// every axis, for every node of the tree, so the widening is a per-ray constant folded
/// into `near_orig`/`far_orig`.
pub(super) const NODE_SLACK: f32 = 4.0 * f32::EPSILON;

/// Rays set up together: one lane of a [`RayBlock`] each.
pub(super) const BLOCK: usize = 8;

/// The per-ray constants of both tests for up to [`BLOCK`] rays, one row per constant and
/// one lane per ray. [`RayBlock::set`] computes them for all lanes at once, with the same
/// operations per lane as [`shear`] and the per-ray formulas documented on the rows (so the
/// same bits), in the kernels' 8-lane operations: about 15 instructions per ray, where one
/// ray at a time it took about a hundred (cornell, 1 spp: closest-hit kernel 128.8M ->
/// 116.8M instructions, occlusion 37.2M -> 31.2M). The
/// traversal then reads ray `l`'s constants straight from lane `l` of the rows (one
/// broadcast from memory each, where a test needs them).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct RayBlock {
    /// The node test's rows `3 r + a`, axis `a`: `r = 0` is `1 / d`, with components below
    /// [`MIN_DIR`] clamped; `r = 1` and `r = 2` are the slab distance offsets of the box
    /// minimum and maximum planes, `-o / d - s` for the near one (the minimum where
    /// `d > 0`) and `-o / d + s` for the far one, so the widening `s` (see [`NODE_SLACK`])
    /// moves both planes outwards.
    pub(super) node: [[f32; BLOCK]; 9],
    /// The triangle test's rows ([`WatertightRay`]'s constants): the origin permuted to
    /// `(kx, ky, kz)`, then the shear `(Sx, Sy, Sz)`, then `|d[kx]|` and `|d[ky]|`.
    pub(super) tri: [[f32; BLOCK]; 8],
    /// The origin (rows 0 to 2) and the direction (rows 3 to 5), for the sphere and
    /// scalar fallback tests.
    pub(super) od: [[f32; BLOCK]; 6],
    /// The node test's exact cull of boxes behind the origin (see [`intersect_node8`]),
    /// axis `a`: row `a` the sign `±1` of `d[a]`, row `3 + a` the threshold `±o[a]` (sign
    /// times origin), so that `sign * bound <= threshold` on the box maximum (`d[a] > 0`)
    /// or minimum (`d[a] < 0`) says the box is behind; `-inf` (nothing behind) where
    /// `d[a] = 0` or `tmin < 0`.
    pub(super) cull: [[f32; BLOCK]; 6],
    /// Bit `l` set where ray `l`'s dominant direction axis is X, and where it is Y (the
    /// permutation of [`shear`], see [`RayBlock::axes`]).
    pub(super) x_dominant: u32,
    pub(super) y_dominant: u32,
}

/// `(kx, ky, kz)` of [`shear`], indexed by "X dominant" + 2 "Y dominant" (never both).
pub(super) const SHEAR_AXES: [[Axis; 3]; 4] = [
    [Axis::X, Axis::Y, Axis::Z],
    [Axis::Y, Axis::Z, Axis::X],
    [Axis::Z, Axis::X, Axis::Y],
    [Axis::X, Axis::Y, Axis::Z],
];

impl RayBlock {
    /// A block to [`Self::set`] (all zero).
    pub(super) fn zero() -> Self {
        RayBlock {
            node: [[0.0; BLOCK]; 9],
            tri: [[0.0; BLOCK]; 8],
            od: [[0.0; BLOCK]; 6],
            cull: [[0.0; BLOCK]; 6],
            x_dominant: 0,
            y_dominant: 0,
        }
    }

    /// Sets the constants of the rays `origin[l] + t * direction[l]` (at most [`BLOCK`];
    /// lanes past them get a zero ray, never read) in a tree whose box coordinates are at
    /// most `max_abs` in magnitude per axis, computed on the lanes of `s`. Every row is
    /// overwritten.
    #[inline(always)]
    pub(super) fn set<S: Simd>(
        &mut self,
        s: S,
        origin: &[Vec3],
        direction: &[Vec3],
        tmin: &[f32],
        max_abs: Vec3A,
    ) {
        let b = self;
        let (o, d) = match (origin.first_chunk(), direction.first_chunk()) {
            (Some(origin), Some(direction)) => (s.load_xyz(origin), s.load_xyz(direction)),
            _ => {
                // A partial block: the rays, then zero rays.
                let mut rays = [[Vec3::ZERO; BLOCK]; 2];
                for (l, (o, d)) in origin.iter().zip(direction).take(BLOCK).enumerate() {
                    (rays[0][l], rays[1][l]) = (*o, *d);
                }
                (s.load_xyz(&rays[0]), s.load_xyz(&rays[1]))
            }
        };
        for a in 0..3 {
            b.od[a] = o[a].to_array();
            b.od[3 + a] = d[a].to_array();
        }
        let mut tmins = [f32::NAN; BLOCK];
        for (t, &tmin) in tmins.iter_mut().zip(tmin) {
            *t = tmin;
        }
        let cull_on = s.splat(0.0).le(s.load(&Row8(tmins)));
        for a in 0..3 {
            let sign = S::F::select(d[a].lt(s.splat(0.0)), s.splat(-1.0), s.splat(1.0));
            let live = (d[a].lt(s.splat(0.0)) | d[a].gt(s.splat(0.0))) & cull_on;
            b.cull[a] = sign.to_array();
            b.cull[3 + a] = S::F::select(live, sign * o[a], s.splat(f32::NEG_INFINITY)).to_array();
        }
        for a in 0..3 {
            // NodeRay: `1 / d` clamped, and the widened plane offsets.
            let tiny = d[a].abs().lt(s.splat(MIN_DIR));
            let clamped = s.splat(1.0 / MIN_DIR).copysign(d[a]);
            let inv = S::F::select(tiny, clamped, s.splat(1.0) / d[a]);
            let c = (o[a] * inv).neg();
            let widening = inv.abs() * s.splat(NODE_SLACK);
            let slack = ((s.splat(max_abs[a]) + o[a].abs()) * widening).copysign(inv);
            b.node[a] = inv.to_array();
            b.node[3 + a] = (c - slack).to_array();
            b.node[6 + a] = (c + slack).to_array();
        }
        // `shear` on every lane: selects for its branches, the same comparisons.
        let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
        let x_beats_y = ax.gt(ay);
        let x_dominant = x_beats_y & ax.gt(az);
        let y_dominant = ay.gt(az).and_not(x_beats_y);
        let pick = |v: &[S::F; 3], x: usize, y: usize, z: usize| {
            S::F::select(x_dominant, v[x], S::F::select(y_dominant, v[y], v[z]))
        };
        // kz is X, Y or Z; kx and ky follow it cyclically.
        let (dkx, dky, dkz) = (pick(&d, 1, 2, 0), pick(&d, 2, 0, 1), pick(&d, 0, 1, 2));
        b.tri[0] = pick(&o, 1, 2, 0).to_array();
        b.tri[1] = pick(&o, 2, 0, 1).to_array();
        b.tri[2] = pick(&o, 0, 1, 2).to_array();
        b.tri[3] = (dkx / dkz).to_array();
        b.tri[4] = (dky / dkz).to_array();
        b.tri[5] = (s.splat(1.0) / dkz).to_array();
        b.tri[6] = dkx.abs().to_array();
        b.tri[7] = dky.abs().to_array();
        b.x_dominant = x_dominant.bits();
        b.y_dominant = y_dominant.bits();
    }

    /// Ray `l`'s `(kx, ky, kz)`.
    #[inline(always)]
    pub(super) fn axes(&self, l: usize) -> [Axis; 3] {
        let l = l % BLOCK;
        SHEAR_AXES[((self.x_dominant >> l) & 1 | ((self.y_dominant >> l) & 1) << 1) as usize]
    }

    /// Ray `l`'s origin.
    #[inline(always)]
    pub(super) fn origin(&self, l: usize) -> Vec3 {
        let l = l % BLOCK;
        Vec3::new(self.od[0][l], self.od[1][l], self.od[2][l])
    }

    /// Ray `l`'s direction.
    #[inline(always)]
    pub(super) fn direction(&self, l: usize) -> Vec3 {
        let l = l % BLOCK;
        Vec3::new(self.od[3][l], self.od[4][l], self.od[5][l])
    }
}

/// Ray `l` of a [`RayBlock`] for the 8-wide node test. Its per-axis values stay in the
/// block and are broadcast to the child lanes where the node test reads them (one
/// `vbroadcastss` from memory each, see [`intersect_node8`]): a ray visits little more than
/// one node on average in small scenes, and splatting all nine once per ray costs a
/// broadcast and a spill each.
pub(super) struct NodeRay<'a, F> {
    pub(super) block: &'a RayBlock,
    pub(super) lane: usize,
    pub(super) tmin: F,
}

impl<'a, F: Lanes8> NodeRay<'a, F> {
    #[inline(always)]
    pub(super) fn new<S: Simd<F = F>>(s: S, block: &'a RayBlock, lane: usize, tmin: f32) -> Self {
        Self {
            block,
            lane: lane % BLOCK,
            tmin: s.splat(tmin),
        }
    }
}

/// Near and far slab distances of the eight child boxes along axis `a`: the distances to
/// the minimum and maximum planes, ordered (which one is near depends on the sign of
/// `d[a]`; ordering them costs a min and a max, picking rows by the sign an address
/// computation per row). (Helpers of the kernels are functions, not closures: closures
/// would not inherit the AVX2 target feature, and the intrinsics would not be inlined into
/// them.)
#[inline(always)]
pub(super) fn slab<S: Simd>(
    s: S,
    b: &[Row8; 6],
    k: &[[f32; BLOCK]; 9],
    l: usize,
    a: usize,
) -> (S::F, S::F) {
    let l = l % BLOCK;
    let inv = s.splat(k[a][l]);
    let lo = s.load(&b[2 * a]).mul_add(inv, s.splat(k[3 + a][l]));
    let hi = s.load(&b[2 * a + 1]).mul_add(inv, s.splat(k[6 + a][l]));
    (lo.min(hi), lo.max(hi))
}

/// Slab test of the ray against the eight children of a node: the hit mask (bit `c` for
/// child `c`) and the entry distances.
#[inline(always)]
pub(super) fn intersect_node8<S: Simd>(
    s: S,
    node: &Node8,
    ray: &NodeRay<S::F>,
    tmax: f32,
) -> (u32, S::F) {
    // `black_box` only keeps the compiler from hoisting the nine broadcasts out of the
    // traversal loop into the per-ray set-up (and spilling them there); the values read are
    // those of `ray` either way, so correctness does not depend on it.
    let k = std::hint::black_box(&ray.block.node);
    let (nx, fx) = slab(s, &node.bounds, k, ray.lane, 0);
    let (ny, fy) = slab(s, &node.bounds, k, ray.lane, 1);
    let (nz, fz) = slab(s, &node.bounds, k, ray.lane, 2);
    let tnear = nx.max(ny).max(nz.max(ray.tmin));
    let tfar = fx.min(fy).min(fz.min(s.splat(tmax)));
    // Exact cull of children whose box lies wholly on or behind the plane through the
    // origin across an axis `a` (`max_a <= o_a` for `d_a > 0`, `min_a >= o_a` for
    // `d_a < 0`, exact comparisons): every point of such a box has `t* <= 0` on the ray's
    // line, so for `tmin >= 0` the triangle test rejects all its triangles (a computed `t`
    // is within its error bound of `t*`, and hits with `t <= tmin + bound` are rejected,
    // see `t_error_bound`). The widened slab test above keeps such boxes, as the widening
    // exceeds the offset of a ray spawned on a surface from that surface: without this
    // the ray would visit the leaf it starts on. Spheres have no such bound, so subtrees
    // holding one ([`Node8::tri_only`]) are kept.
    let c = std::hint::black_box(&ray.block.cull);
    let behind = behind_axis(s, &node.bounds, c, ray.lane, 0)
        | behind_axis(s, &node.bounds, c, ray.lane, 1)
        | behind_axis(s, &node.bounds, c, ray.lane, 2);
    let culled = behind.bits() & node.tri_only;
    (tnear.le(tfar).bits() & node.valid & !culled, tnear)
}

/// The children whose box is behind the ray origin across axis `a` (see
/// [`intersect_node8`]; `c` is [`RayBlock::cull`], `l` the ray's lane).
#[inline(always)]
pub(super) fn behind_axis<S: Simd>(
    s: S,
    b: &[Row8; 6],
    c: &[[f32; BLOCK]; 6],
    l: usize,
    a: usize,
) -> <S::F as Lanes8>::Mask {
    let l = l % BLOCK;
    let sign = s.splat(c[a][l]);
    let bound = S::F::select_negative(sign, s.load(&b[2 * a]), s.load(&b[2 * a + 1]));
    (bound * sign).le(s.splat(c[3 + a][l]))
}
