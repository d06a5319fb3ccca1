//! The surface points of a batch of triangle hits, eight at a time: [`Triangles::write_surfaces`],
//! what shading does with every closest hit. Point by point, [`Triangles::surface_at`]
//! reads a triangle's vertices from its BVH leaf packet, computes its normal
//! (`Triangle::new`), the barycentric point and its error bound
//! ([`crate::primitive::triangle_point_error`]): about 138 instructions a hit on the
//! Cornell box, most of them single-lane float arithmetic. Here the nine vertex coordinates
//! of eight hits are loaded into nine rows (a packet holds each coordinate of its eight
//! triangles in a row, but eight hits are on eight packets' triangles) and the arithmetic
//! runs on `simd8` lanes, operation for operation the scalar code's (no fused multiply-add,
//! the same square root and division), so every lane is the bits of
//! [`Triangles::surface_at`]: about 60 instructions a hit, half of them the loads into lanes.
//! Those are plain loads, not AVX2 gathers: fewer instructions, but slower than the loads
//! on CPUs whose microcode mitigates gather data sampling. The normal is not stored per
//! triangle (issue 36: memory per triangle); it is recomputed per hit, as before.

use glam::Vec3;

use super::Triangles;
use crate::bvh8::WIDTH;
use crate::primitive::{gamma, UNDERFLOW};
use crate::simd8::{Backend, Kernel8, Lanes8, Mask8, Row8, Simd};

/// The shading-point columns [`Triangles::write_surfaces`] writes, row `k` for hit `k`
/// of its `rows` (all as long as `rows`): the fields of [`Triangles::surface_at`]'s
/// [`SurfaceSample`](super::SurfaceSample) that shading keeps.
#[derive(Debug)]
pub struct SurfaceColumns<'a> {
    /// `p`.
    pub p: &'a mut [Vec3],
    /// `ng`.
    pub ng: &'a mut [Vec3],
    /// [`SurfaceSample::offset`](super::SurfaceSample::offset).
    pub p_offset: &'a mut [f32],
    /// `uv.x` (`b1`).
    pub u: &'a mut [f32],
    /// `uv.y` (`b2`).
    pub v: &'a mut [f32],
}

impl Triangles<'_> {
    /// For each `k`, the surface of hit `rows[k]` (a row of `prim`, `b1`, `b2`, the hit
    /// columns) written to row `k` of `out` when its primitive is a triangle outside
    /// instances: the bits of [`Self::surface_at`]. The rows of other hits (spheres,
    /// primitives of instances) are left as they are; returns whether there were any.
    ///
    /// # Panics
    /// When the columns of `out` are not as long as `rows`, `prim`, `b1` and `b2` differ
    /// in length or a row is not one of theirs.
    pub fn write_surfaces(
        &self,
        rows: &[u32],
        prim: &[u32],
        b1: &[f32],
        b2: &[f32],
        out: SurfaceColumns<'_>,
    ) -> bool {
        self.write_surfaces_on(Backend::best(), rows, prim, b1, b2, out)
    }

    /// [`Self::write_surfaces`] on the lanes of `backend`.
    pub(crate) fn write_surfaces_on(
        &self,
        backend: Backend,
        rows: &[u32],
        prim: &[u32],
        b1: &[f32],
        b2: &[f32],
        out: SurfaceColumns<'_>,
    ) -> bool {
        let count = rows.len();
        assert!(
            out.p.len() == count
                && out.ng.len() == count
                && out.p_offset.len() == count
                && out.u.len() == count
                && out.v.len() == count,
            "write_surfaces: output column lengths"
        );
        assert!(
            b1.len() == prim.len() && b2.len() == prim.len(),
            "write_surfaces: hit column lengths"
        );
        backend.run(TriangleSurfaces {
            tris: *self,
            rows,
            prim,
            b1,
            b2,
            out,
        })
    }

    /// Row `k` of `out` from hit `rows[k]` as [`Self::surface_at`] gives it, point by
    /// point (the partial last block, blocks with other primitives and the lanes whose
    /// normal needs `Triangle::new`'s double-precision cross product); whether a hit was
    /// not a triangle.
    #[inline(always)]
    fn write_surface(
        &self,
        i: usize,
        hits: Hits<'_>,
        k: usize,
        out: &mut SurfaceColumns<'_>,
    ) -> bool {
        match self.surface_at(hits.prim[i], hits.b1[i], hits.b2[i]) {
            Some(s) => {
                out.p[k] = s.p;
                out.ng[k] = s.ng;
                out.p_offset[k] = s.offset();
                out.u[k] = s.uv.x;
                out.v[k] = s.uv.y;
                false
            }
            None => true,
        }
    }

    /// The vertex coordinates and barycentrics of the eight hits `rows`, or `None` when
    /// one of them is not a triangle outside instances.
    #[inline(always)]
    fn gather(&self, rows: &[u32; 8], hits: Hits<'_>) -> Option<Eight> {
        let mut g = Eight {
            v: [Row8([0.0; 8]); 9],
            b1: Row8([0.0; 8]),
            b2: Row8([0.0; 8]),
        };
        for (l, &i) in rows.iter().enumerate() {
            let i = i as usize;
            let slot = *self.slots.get(hits.prim[i] as usize)? as usize;
            let (packet, lane) = (&self.packets[slot / WIDTH], slot % WIDTH);
            for c in 0..9 {
                g.v[c].0[l] = packet.v[c / 3][c % 3].0[lane];
            }
            g.b1.0[l] = hits.b1[i];
            g.b2.0[l] = hits.b2[i];
        }
        Some(g)
    }
}

/// The hit columns [`Triangles::write_surfaces`] reads (equally long).
#[derive(Clone, Copy)]
struct Hits<'a> {
    prim: &'a [u32],
    b1: &'a [f32],
    b2: &'a [f32],
}

/// Eight triangle hits as rows: `v[3 i + a]` coordinate `a` of vertex `i`, lane `l` hit `l`.
struct Eight {
    v: [Row8; 9],
    b1: Row8,
    b2: Row8,
}

/// The arguments of [`Triangles::write_surfaces`], as a [`Kernel8`].
struct TriangleSurfaces<'a> {
    tris: Triangles<'a>,
    rows: &'a [u32],
    prim: &'a [u32],
    b1: &'a [f32],
    b2: &'a [f32],
    out: SurfaceColumns<'a>,
}

impl Kernel8 for TriangleSurfaces<'_> {
    type Output = bool;
    #[inline(always)]
    fn run<S: Simd>(self, s: S) -> bool {
        let TriangleSurfaces {
            tris,
            rows,
            prim,
            b1,
            b2,
            out,
        } = self;
        // Cut to their lengths here, past the call into the lanes' instantiation: the
        // compiler then drops the bounds checks a row's `b1`, `b2` and output rows repeat.
        let (n, count) = (prim.len(), rows.len());
        let hits = Hits {
            prim,
            b1: &b1[..n],
            b2: &b2[..n],
        };
        let mut out = SurfaceColumns {
            p: &mut out.p[..count],
            ng: &mut out.ng[..count],
            p_offset: &mut out.p_offset[..count],
            u: &mut out.u[..count],
            v: &mut out.v[..count],
        };
        let mut others = false;
        let (rows8, rest) = rows.as_chunks::<8>();
        let blocks = rows8.len();
        for (b, block) in rows8.iter().enumerate() {
            let k = b * 8;
            let Some(g) = tris.gather(block, hits) else {
                // A sphere or an instance's primitive among them (rare: hits come sorted
                // by material, so spheres are together), point by point.
                for (j, &i) in block.iter().enumerate() {
                    others |= tris.write_surface(i as usize, hits, k + j, &mut out);
                }
                continue;
            };
            let wide = surfaces_eight(s, &g, k, &mut out);
            // Normals whose cross product overflows f32 (edges beyond about 1e19):
            // `Triangle::new` widens to f64, point by point.
            let mut bits = wide;
            while bits != 0 {
                let j = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                tris.write_surface(block[j] as usize, hits, k + j, &mut out);
            }
        }
        for (j, &i) in rest.iter().enumerate() {
            others |= tris.write_surface(i as usize, hits, blocks * 8 + j, &mut out);
        }
        others
    }
}

/// Rows `k..k + 8` of `out` from the eight triangle hits `g` on the lanes of `s`:
/// `Triangle::new`'s normal, `Triangle::surface_at`'s point and error bound and the
/// offset along the normal, operation for operation (see the scalar code for the math).
/// Returns the lanes whose `|(v1 - v0) x (v2 - v0)|^2` is not finite, where
/// `Triangle::new` takes another path: their rows are to be rewritten.
#[inline(always)]
fn surfaces_eight<S: Simd>(s: S, g: &Eight, k: usize, out: &mut SurfaceColumns<'_>) -> u32 {
    let [ax, ay, az] = [s.load(&g.v[0]), s.load(&g.v[1]), s.load(&g.v[2])];
    let [bx, by, bz] = [s.load(&g.v[3]), s.load(&g.v[4]), s.load(&g.v[5])];
    let [cx, cy, cz] = [s.load(&g.v[6]), s.load(&g.v[7]), s.load(&g.v[8])];
    let (b1, b2) = (s.load(&g.b1), s.load(&g.b2));
    let (zero, one, inf) = (s.splat(0.0), s.splat(1.0), s.splat(f32::INFINITY));
    // Triangle::new: c = (v1 - v0) x (v2 - v0) as Vec3::cross, |c|^2 as Vec3::dot
    // ((x x + y y) + z z).
    let (ex, ey, ez) = (bx - ax, by - ay, bz - az);
    let (fx, fy, fz) = (cx - ax, cy - ay, cz - az);
    let nx = ey * fz - fy * ez;
    let ny = ez * fx - fz * ex;
    let nz = ex * fy - fx * ey;
    let len2 = nx * nx + ny * ny + nz * nz;
    let wide = len2.lt(inf).bits() ^ 0xff;
    // Vec3::normalize_or_zero: c / |c| as c * (1 / sqrt(|c|^2)), zero unless that
    // reciprocal is finite and positive.
    let rcp = one / len2.sqrt();
    let unit = rcp.gt(zero) & rcp.lt(inf);
    let ngx = S::F::select(unit, nx * rcp, zero);
    let ngy = S::F::select(unit, ny * rcp, zero);
    let ngz = S::F::select(unit, nz * rcp, zero);
    // Triangle::point: b0 = (1 - b1) - b2, p = (v0 b0 + v1 b1) + v2 b2.
    let b0 = one - b1 - b2;
    let px = ax * b0 + bx * b1 + cx * b2;
    let py = ay * b0 + by * b1 + cy * b2;
    let pz = az * b0 + bz * b1 + cz * b2;
    // triangle_point_error: (sum |v_i| |b_i|) gamma(4) + |v0| (gamma(3) ((1 + |b1|) + |b2|)),
    // plus a subnormal.
    let (a0, a1, a2) = (b0.abs(), b1.abs(), b2.abs());
    let (g4, under) = (s.splat(gamma(4.0)), s.splat(UNDERFLOW));
    let w0 = s.splat(gamma(3.0)) * (one + a1 + a2);
    let bary = [a0, a1, a2, w0, g4, under];
    let errx = point_error([ax, bx, cx], bary);
    let erry = point_error([ay, by, cy], bary);
    let errz = point_error([az, bz, cz], bary);
    // surface_offset: |ng| . p_error.
    let offset = ngx.abs() * errx + ngy.abs() * erry + ngz.abs() * errz;
    s.store_xyz([px, py, pz], block(out.p, k));
    s.store_xyz([ngx, ngy, ngz], block(out.ng, k));
    *block(out.p_offset, k) = offset.to_array();
    *block(out.u, k) = g.b1.0;
    *block(out.v, k) = g.b2.0;
    wide
}

/// One coordinate of `triangle_point_error`: `v` that coordinate of the three vertices,
/// `[|b0|, |b1|, |b2|, gamma(3) ((1 + |b1|) + |b2|), gamma(4), UNDERFLOW]`. A function,
/// not a closure: a closure's body would not be compiled with the kernel's target features
/// unless inlined.
#[inline(always)]
fn point_error<F: Lanes8>(v: [F; 3], [a0, a1, a2, w0, g4, under]: [F; 6]) -> F {
    let [v0, v1, v2] = [v[0].abs(), v[1].abs(), v[2].abs()];
    (v0 * a0 + v1 * a1 + v2 * a2) * g4 + v0 * w0 + under
}

/// Rows `k..k + 8` of `column`.
#[inline(always)]
fn block<T>(column: &mut [T], k: usize) -> &mut [T; 8] {
    (&mut column[k..k + 8])
        .try_into()
        .expect("eight rows are eight")
}

#[cfg(test)]
mod tests;
