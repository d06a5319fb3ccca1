//! Spawning rays off surfaces: where a new ray's origin goes, where a shadow ray towards a
//! sampled light point must stop, and crossing interior boundaries.
//!
//! # Error-bounded origins (pbrt-v4 sec. 6.8, "Managing Rounding Error")
//!
//! Every computed surface point `p` carries `p_error`, a conservative per-component absolute
//! bound of its rounding error: some point of the exact surface lies in the box
//! `p +- p_error` ([`crate::geometry::SurfaceSample::p_error`]; triangles:
//! [`crate::geometry::triangle_point_error`], spheres:
//! [`crate::geometry::sphere_point_error`]). The box's extent along the unit geometric normal
//! `ng` is `offset = dot(|ng|, p_error)`; tables keep that scalar (one `f32` per shading
//! point rather than a `Vec3`, since every use is along `ng`).
//!
//! - A ray leaving `p` in direction `wi` starts at `p + offset ng` on `wi`'s side of the
//!   surface, each component then rounded one float away from `p` along the offset
//!   (pbrt-v4 sec. 6.8.5, `OffsetRayOrigin`): [`spawn_origin`]. The offset is relative to
//!   each coordinate's own magnitude, so a floor at `y = 0` far along `x` is offset by
//!   nothing along `y` (its `y` coordinates are exact) and a second floor `1e-4` above it
//!   is seen.
//! - A shadow ray towards a light point `q` stops short of it by the light point's own
//!   offset measured along the ray (`offset_q / |cos_light|`, the light sample's `margin`,
//!   which also bounds the rounding of `q` as the shadow ray rebuilds it) and then by the
//!   relative `SHADOW_EPSILON` of the remaining length: pbrt-v4's `SpawnRayTo` between two
//!   offset points with `tmax = 1 - ShadowEpsilon` ([`shadow_ray`]). Lights at infinity
//!   keep `tmax` infinite.
//! - Rays that keep their origin on a boundary and skip it with `tmin` (pass-throughs,
//!   shadow rays through transmitting surfaces, walks) use the same `offset` along the ray:
//!   `offset / |cos|` ([`skip_tmin`]).
//! - Points with no computed surface (inside a volume, given by a user) are not offset.
use glam::Vec3;
use risotto_components::{StackEvent, VolumeEntry, VolumeStack};

/// Per-shape data for crossing interior boundaries, from the compiled scene: whether rays
/// crossing shape `s` enter or leave a volume the renderer tracks (`tracked[s]`), and that
/// volume's stack entry (`entry[s]`), and which rays leaving a surface cross it.
#[derive(Clone, Copy, Debug)]
pub struct InteriorBoundaries<'a> {
    /// Whether each shape's interior is tracked on volume stacks.
    pub tracked: &'a [bool],
    /// Each shape's stack entry (meaningful where `tracked`).
    pub entry: &'a [VolumeEntry],
    /// `false`: a ray leaving a surface crosses it when its lobe transmits (with consistent
    /// shading normals, the same as its side). `true`: when its direction and the viewer lie
    /// on different sides of the geometric normal, whatever the lobe (shading normals
    /// evaluated in the shading frame alone, which keeps directions the two normals classify
    /// differently; Mitsuba 3's `SurfaceInteraction::target_medium`).
    pub by_geometric_side: bool,
}

impl InteriorBoundaries<'_> {
    /// Records a crossing of `shape` on `stack` (entering on a front face, leaving on a back
    /// face) when the shape is tracked; `None` when it is not.
    #[inline]
    pub fn cross(
        &self,
        stack: &mut VolumeStack,
        shape: u32,
        front_face: bool,
    ) -> Option<StackEvent> {
        let s = shape as usize;
        self.tracked[s].then(|| stack.cross(self.entry[s], front_face))
    }
}

/// The relative shortening of a shadow ray between two offset points (pbrt-v4's
/// `ShadowEpsilon`): covers the rounding of the ray's direction and length and of the
/// intersection distance of the emitter it stops before.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// Direction and `tmax` of a shadow ray from `origin` (the surface point `p` moved off its
/// surface by [`spawn_origin`]) to the light point `q = p + distance * wi` (`wi` unit, from the
/// light sample), stopping `margin` short of `q` along the ray (the light sample's bound of
/// `q`'s distance to its surface along the ray, see the module docs) and then by
/// [`SHADOW_EPSILON`] of the rest, so that it never reaches the emitter it aims at. The ray
/// aims at `q` from `origin` itself: kept along `wi` from `p`, its line would miss `q` by
/// about the origin's offset and cross an oblique emitter early. A light at infinity
/// (`distance` infinite) keeps `wi` with no `tmax`.
#[inline]
pub fn shadow_ray(p: Vec3, origin: Vec3, wi: Vec3, distance: f32, margin: f32) -> (Vec3, f32) {
    if !distance.is_finite() {
        return (wi, f32::INFINITY);
    }
    let light = p + wi * distance;
    let d = light - origin;
    let length = d.length();
    if length.is_nan() || length <= 0.0 {
        return (wi, 0.0);
    }
    (d / length, (length - margin) * (1.0 - SHADOW_EPSILON))
}

/// `offset` signed to move a point along `ng` to the side `wi` points to: `(side of ng) *
/// offset` as `ng * toward(..)`, the same bits (negating a product's factor negates the
/// product), with the sign set by a bit operation instead of a branch on the (random)
/// direction.
#[inline]
pub fn toward(wi: Vec3, ng: Vec3, offset: f32) -> f32 {
    // Flip unless `wi . ng >= 0` (a NaN dot product flips, as the branch did).
    let keep_side = (wi.dot(ng) >= 0.0) as u32;
    f32::from_bits(offset.to_bits() ^ ((keep_side ^ 1) << 31))
}

/// `x` moved one float in the direction of `dir`'s sign (`x` itself for `dir = 0`): the
/// rounding of pbrt-v4's `OffsetRayOrigin`, so that the rounded sum `p + offset` cannot land
/// back inside the error box. `x.next_up()` / `x.next_down()` for finite `x`, by bit
/// selects: the sign of `dir` is random (the side a sampled direction leaves to), and a
/// branch on it mispredicts half the time in the spawn loops. Moving towards `dir` adds one
/// to `x`'s bits when both have the same sign (the magnitude grows) and subtracts one
/// otherwise; a zero `x` becomes the smallest subnormal of `dir`'s sign.
#[inline(always)]
fn round_away(x: f32, dir: f32) -> f32 {
    let (xb, db) = (x.to_bits(), dir.to_bits());
    let select = |c: bool, a: u32, b: u32| {
        let m = (c as u32).wrapping_neg();
        (a & m) | (b & !m)
    };
    let same_sign = (xb ^ db) >> 31 == 0;
    let moved = xb.wrapping_add(select(same_sign, 1, u32::MAX));
    let from_zero = 1 | (db & 0x8000_0000);
    let moved = select(x == 0.0, from_zero, moved);
    f32::from_bits(select(dir != 0.0, moved, xb))
}

/// Origin of a ray leaving the surface point `p` (geometric normal `ng`, error offset
/// `offset = dot(|ng|, p_error)`) in direction `wi`: `p + offset ng` on the side `wi` goes
/// to, each component rounded away from `p` (pbrt-v4's `OffsetRayOrigin`, see the module
/// docs); inside a volume (`on_surface` false: no surface to re-hit) `p` itself.
#[inline]
pub fn spawn_origin(p: Vec3, ng: Vec3, offset: f32, wi: Vec3, on_surface: bool) -> Vec3 {
    if on_surface {
        offset_origin(p, ng, offset, wi)
    } else {
        p
    }
}

/// [`spawn_origin`] of a surface point.
///
/// On x86-64 the three components go through one SSE2 register
/// ([`offset_origin_sse2`]): the same IEEE products, sums and bit selects as the scalar
/// form ([`offset_origin_scalar`], the reference; tested bit for bit), a third of the
/// instructions. The spawn loops call it for every continuing and shadow ray.
#[inline(always)]
pub fn offset_origin(p: Vec3, ng: Vec3, offset: f32, wi: Vec3) -> Vec3 {
    #[cfg(target_arch = "x86_64")]
    {
        offset_origin_sse2(p, ng, offset, wi)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        offset_origin_scalar(p, ng, offset, wi)
    }
}

/// [`offset_origin`] one component at a time: the reference of the SIMD form.
#[inline(always)]
pub fn offset_origin_scalar(p: Vec3, ng: Vec3, offset: f32, wi: Vec3) -> Vec3 {
    let off = ng * toward(wi, ng, offset);
    let o = p + off;
    Vec3::new(
        round_away(o.x, off.x),
        round_away(o.y, off.y),
        round_away(o.z, off.z),
    )
}

/// [`offset_origin`] with the three components in the lanes of one SSE2 register (SSE2 is
/// part of x86-64, so no run-time check): `round_away`'s selects lane-wise. The sign test
/// `(x ^ dir) >> 31` becomes an arithmetic shift, all ones for opposite signs, so the step
/// `select(same sign, 1, -1)` is `shift | 1`; `x == 0` and `dir != 0` are the float compares
/// of the scalar form (`!=` true, `==` false for NaN in both).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[allow(unsafe_code, reason = "SSE2 intrinsics, part of the x86-64 baseline")]
pub fn offset_origin_sse2(p: Vec3, ng: Vec3, offset: f32, wi: Vec3) -> Vec3 {
    use glam::Vec3A;
    use std::arch::x86_64::*;
    let off = Vec3A::from(ng) * toward(wi, ng, offset);
    let o = Vec3A::from(p) + off;
    let (o, off) = (__m128::from(o), __m128::from(off));
    // SAFETY: SSE2 is part of the x86-64 baseline; the intrinsics read and write registers only.
    let r = unsafe {
        let (xb, db) = (_mm_castps_si128(o), _mm_castps_si128(off));
        let step = _mm_or_si128(
            _mm_srai_epi32::<31>(_mm_xor_si128(xb, db)),
            _mm_set1_epi32(1),
        );
        let moved = _mm_add_epi32(xb, step);
        let sign = _mm_set1_epi32(i32::MIN);
        let from_zero = _mm_or_si128(_mm_and_si128(db, sign), _mm_set1_epi32(1));
        let zero = _mm_setzero_ps();
        let at_zero = _mm_castps_si128(_mm_cmpeq_ps(o, zero));
        let moved = _mm_or_si128(
            _mm_and_si128(at_zero, from_zero),
            _mm_andnot_si128(at_zero, moved),
        );
        let dir = _mm_castps_si128(_mm_cmpneq_ps(off, zero));
        _mm_castsi128_ps(_mm_or_si128(
            _mm_and_si128(dir, moved),
            _mm_andnot_si128(dir, xb),
        ))
    };
    Vec3::from(Vec3A::from(r))
}

/// `tmin` past a hit at `t` on a surface (error offset `offset`, geometric normal `ng`) of a
/// ray (direction `d`) that keeps its origin and walks on along its line (shadow rays
/// through transmitting surfaces, probes): the surface's offset measured along the ray
/// (cosine clamped at `1e-3`) and 4 ulps of the whole, for the rounding of `t` itself (a
/// neighbouring triangle of the same surface computes its own `t` at a shared edge).
#[inline]
pub fn tmin_past_hit(t: f32, offset: f32, ng: Vec3, d: Vec3) -> f32 {
    ((t + offset / d.dot(ng).abs().max(1e-3)) * (1.0 + 4.0 * f32::EPSILON)).next_up()
}

/// The largest `t` at which the point `o + t d`, computed in f32, is surely on the near side
/// of a hit at `t_hit` on a surface (error offset `offset`, geometric normal `ng`): the hit
/// less the surface's offset and the point's own rounding bound `gamma(3) (|o| + |t d|)`
/// projected on `ng`, both measured along the ray (cosine clamped at `1e-3`). Events inside
/// a volume (scattering points of walks and media) are kept below it, so that the next
/// segment, spawned from the event without an offset, sees the boundary again.
#[inline]
pub fn before_hit(t_hit: f32, offset: f32, ng: Vec3, o: Vec3, d: Vec3) -> f32 {
    let point = crate::geometry::surface_offset(
        ng,
        (o.abs() + (d * t_hit).abs()) * crate::geometry::gamma(4.0),
    );
    t_hit - (offset + point) / d.dot(ng).abs().max(1e-3)
}

/// About 4 ulps of `p`'s largest coordinate: the rounding scale of a point computed from
/// coordinates of that size, for callers that have no error bound of their own (a point
/// given by a user, a point inside a volume) and need a length scale for probes and gates,
/// not for spawning rays off surfaces (which [`spawn_origin`] does with the surface's bound).
#[inline]
pub fn coordinate_epsilon(p: Vec3) -> f32 {
    p.abs().max_element() * 5e-7 + 1e-9
}

/// `tmin` of a ray that starts on a surface point `p` (error offset `offset`, geometric
/// normal `ng`) and must skip that surface along its line (direction `d`): past the
/// surface's error box and past the rounding of the points `p + t d` computed there
/// (`gamma(4) |p|` projected on `ng`, as [`before_hit`] allows at the far end), measured
/// along the ray with the cosine clamped at `1e-3` (a grazing ray skips 1000 offsets), raised
/// by one float so that a zero offset still excludes `t = 0`. Without the points' own
/// rounding, a scattering point sampled just past `tmin` in a dense medium could round back
/// across the boundary it has just crossed, and the next ray from it would enter again
/// (`tests/hard_media.rs`, mean free path 1e-7 in a unit ball).
#[inline]
pub fn skip_tmin(p: Vec3, offset: f32, ng: Vec3, d: Vec3) -> f32 {
    let point = crate::geometry::surface_offset(ng, p.abs() * crate::geometry::gamma(4.0));
    ((offset + point) / d.dot(ng).abs().max(1e-3)).next_up()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::SceneGeometry;
    use crate::intersect::{intersect_closest, intersect_occluded};
    use crate::lights::light_margin;
    use crate::sampler::SplitMix64;
    use glam::Vec2;
    use risotto_components::NO_HIT;

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn offset_origin_sse2_matches_the_scalar_form_bit_for_bit() {
        let mut rng = SplitMix64(37);
        let special = [
            0.0,
            -0.0,
            1e-45,
            -1e-45,
            f32::MIN_POSITIVE,
            1.0,
            -1.0,
            3e38,
            -3e38,
        ];
        let mut any = |rng: &mut SplitMix64| -> f32 {
            let u = rng.f32();
            if u < 0.2 {
                special[(rng.next_u64() % special.len() as u64) as usize]
            } else if u < 0.25 {
                [f32::INFINITY, f32::NEG_INFINITY, f32::NAN][(rng.next_u64() % 3) as usize]
            } else {
                // Magnitudes from 1e-30 to 1e30, either sign.
                let m = 10f32.powf(rng.f32() * 60.0 - 30.0);
                if rng.f32() < 0.5 {
                    -m
                } else {
                    m
                }
            }
        };
        let v = |rng: &mut SplitMix64, any: &mut dyn FnMut(&mut SplitMix64) -> f32| {
            Vec3::new(any(rng), any(rng), any(rng))
        };
        for case in 0..200_000 {
            let (p, ng, wi) = (
                v(&mut rng, &mut any),
                v(&mut rng, &mut any),
                v(&mut rng, &mut any),
            );
            let offset = any(&mut rng).abs();
            let (a, b) = (
                offset_origin_scalar(p, ng, offset, wi),
                offset_origin_sse2(p, ng, offset, wi),
            );
            // NaN payloads may differ (which operand's NaN a sum propagates is the
            // compiler's choice); every other value bit for bit.
            let same = |x: f32, y: f32| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
            assert!(
                (0..3).all(|i| same(a[i], b[i])),
                "case {case}: p {p}, ng {ng}, offset {offset}, wi {wi}: {a} against {b}"
            );
        }
    }

    #[test]
    fn toward_matches_the_branch() {
        let ng = Vec3::new(0.0, 1.0, 0.0);
        for wi in [Vec3::Y, -Vec3::Y, Vec3::X, Vec3::new(0.3, -0.2, 0.9)] {
            let branch = if wi.dot(ng) >= 0.0 { 0.25 } else { -0.25 };
            assert_eq!(toward(wi, ng, 0.25).to_bits(), f32::to_bits(branch));
        }
    }

    #[test]
    fn spawn_origin_leaves_to_the_side_of_the_direction() {
        let p = Vec3::new(100.0, 2.0, -3.0);
        let ng = Vec3::Z;
        let up = spawn_origin(p, ng, 1e-3, Vec3::new(0.1, 0.0, 0.9), true);
        let down = spawn_origin(p, ng, 1e-3, Vec3::new(0.1, 0.0, -0.9), true);
        assert!(up.z >= p.z + 1e-3 && down.z <= p.z - 1e-3);
        // Only the offset's components move (and are rounded away), by about the offset.
        assert_eq!((up.x, up.y), (p.x, p.y));
        assert!(up.z - p.z < 1e-3 + 1e-6);
        assert_eq!(spawn_origin(p, ng, 1e-3, -Vec3::Z, false), p);
        // An exact point (zero bound) is not moved.
        assert_eq!(spawn_origin(p, ng, 0.0, Vec3::Z, true), p);
    }

    #[test]
    fn round_away_is_next_up_or_down() {
        let xs = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            1e-30,
            -3.5e7,
            1e4,
            f32::MAX / 2.0,
        ];
        for x in xs {
            for dir in [1e-3f32, -1e-3, 0.0, -0.0, f32::from_bits(1), -1e30] {
                let want = if dir > 0.0 {
                    x.next_up()
                } else if dir < 0.0 {
                    x.next_down()
                } else {
                    x
                };
                assert_eq!(
                    round_away(x, dir).to_bits(),
                    want.to_bits(),
                    "{x} towards {dir}"
                );
            }
        }
    }

    /// The rounded origin lies beyond the error box along the normal, to the side of the
    /// direction: `(o - p) . ng >= offset` (in f64) for random points, normals and offsets
    /// from 1e-12 to 1e3 of the coordinates, which the unrounded `p + offset ng` misses for
    /// offsets below half an ulp.
    #[test]
    fn spawned_origins_clear_the_error_box() {
        let mut rng = SplitMix64(21);
        let mut unit = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3::ONE;
        let mut rng2 = SplitMix64(22);
        for _ in 0..20000 {
            let scale = 10f32.powf(rng2.f32() * 12.0 - 6.0);
            let p = unit() * scale;
            let ng = unit().normalize_or(Vec3::Y);
            let offset = scale * 10f32.powf(rng2.f32() * 15.0 - 12.0);
            let wi = unit();
            let o = offset_origin(p, ng, offset, wi);
            let side = if wi.dot(ng) >= 0.0 { 1.0 } else { -1.0 };
            let moved = (o.as_dvec3() - p.as_dvec3()).dot(ng.as_dvec3()) * side;
            let norm2 = ng.as_dvec3().length_squared();
            assert!(
                moved >= offset as f64 * norm2 * (1.0 - 1e-6),
                "p {p:?} ng {ng:?} offset {offset}: moved {moved}"
            );
        }
    }

    /// A ray spawned off one of two parallel quads `gap` apart, `far` units from the
    /// origin, sees the other quad, in both directions: through the top quad (transmission)
    /// down to the bottom one, and off the bottom quad (reflection) up to the top one. With
    /// the former offset (`5e-7` of the largest coordinate, `5e-3` at `1e4`) the second quad
    /// was skipped whenever `gap` was below it.
    #[test]
    fn thin_shells_far_from_the_origin_are_crossed() {
        let mut rng = SplitMix64(5);
        for (far, gap) in [
            (0.0f32, 1e-6f32),
            (1e2, 1e-4),
            (1e4, 1e-4),
            (1e4, 1e-6),
            (1e6, 1e-4),
        ] {
            let c = Vec3::new(far, 0.0, far);
            let quad = |y: f32| {
                let v = |x: f32, z: f32| c + Vec3::new(x, y, z);
                [
                    [v(-1.0, -1.0), v(-1.0, 1.0), v(1.0, 1.0)],
                    [v(-1.0, -1.0), v(1.0, 1.0), v(1.0, -1.0)],
                ]
            };
            let mut tris = quad(gap).to_vec();
            tris.extend(quad(0.0));
            let geom = SceneGeometry::build(tris, vec![]);
            let n = 500;
            let (mut o, mut d) = (vec![], vec![]);
            for _ in 0..n {
                let target = c + Vec3::new(rng.f32() - 0.5, 0.0, rng.f32() - 0.5);
                let from = target + Vec3::new(rng.f32() - 0.5, 1.0, rng.f32() - 0.5);
                o.push(from);
                d.push((target - from).normalize());
            }
            let trace = |o: &[Vec3], d: &[Vec3]| {
                let m = o.len();
                let (mut t, mut prim) = (vec![0.0; m], vec![NO_HIT; m]);
                let (mut b1, mut b2) = (vec![0.0; m], vec![0.0; m]);
                let (tmin, tmax) = (vec![0.0; m], vec![f32::INFINITY; m]);
                intersect_closest(
                    &geom, o, d, &tmin, &tmax, &mut t, &mut prim, &mut b1, &mut b2,
                );
                (t, prim, b1, b2)
            };
            let (t, prim, b1, b2) = trace(&o, &d);
            assert!(
                prim.iter().all(|&p| p < 2),
                "far {far}: camera rays hit the top quad"
            );
            // Transmission through the top quad.
            let (mut o2, mut d2) = (vec![], vec![]);
            for i in 0..n {
                let s = geom.surface_at(prim[i], o[i], d[i], t[i], b1[i], b2[i]);
                o2.push(spawn_origin(s.p, s.ng, s.offset(), d[i], true));
                d2.push(d[i]);
            }
            let (_, prim2, ..) = trace(&o2, &d2);
            let below = prim2.iter().filter(|&&p| p == 2 || p == 3).count();
            assert_eq!(
                below, n,
                "far {far}, gap {gap}: {below} of {n} see the bottom quad"
            );
            // Off the bottom quad, upwards: the top quad.
            let (t3, prim3, b13, b23) = trace(&o2, &d2);
            let (mut o4, mut d4) = (vec![], vec![]);
            for i in 0..n {
                let s = geom.surface_at(prim3[i], o2[i], d2[i], t3[i], b13[i], b23[i]);
                let up = d2[i] - 2.0 * d2[i].dot(s.ng) * s.ng;
                o4.push(spawn_origin(s.p, s.ng, s.offset(), up, true));
                d4.push(up.normalize());
            }
            let (_, prim4, ..) = trace(&o4, &d4);
            let above = prim4.iter().filter(|&&p| p < 2).count();
            assert_eq!(
                above, n,
                "far {far}, gap {gap}: {above} of {n} see the top quad again"
            );
        }
    }

    /// Shadow rays from a floor point to sampled points of a lamp 1 unit above (sharing the
    /// lamp's geometry as the only occluder) are never occluded by the lamp itself, near the
    /// origin and up to 1e6 units away, for origins spawned off the floor and the lamp's
    /// margin from its sample; the lamp flat and tilted by 30 degrees.
    #[test]
    fn shadow_rays_stop_short_of_their_light_point_at_any_offset() {
        let mut rng = SplitMix64(7);
        for far in [0.0f32, 1e2, 2e3, 1e4, 1e5, 1e6] {
            for tilt in [0.0f32, std::f32::consts::FRAC_PI_6] {
                let c = Vec3::new(far, 0.0, far);
                let (sn, cs) = tilt.sin_cos();
                // Lamp: the unit square at height 1 (both triangles), normal about -y.
                let corner = |x: f32, z: f32| c + Vec3::new(x * cs, 1.0 + x * sn, z);
                let (a, b, d, e) = (
                    corner(-0.5, -0.5),
                    corner(0.5, -0.5),
                    corner(0.5, 0.5),
                    corner(-0.5, 0.5),
                );
                let lamp = SceneGeometry::build(vec![[a, b, d], [a, d, e]], vec![]);
                let (mut origins, mut dirs, mut tmax) = (vec![], vec![], vec![]);
                for _ in 0..2000 {
                    let prim = (rng.next_u64() % 2) as u32;
                    let q = lamp.sample_surface(prim, Vec2::new(rng.f32(), rng.f32()));
                    // The floor point: exact (its bound is zero), so not moved.
                    let p = c + Vec3::new(rng.f32() * 4.0 - 2.0, 0.0, rng.f32() * 4.0 - 2.0);
                    let dq = q.p - p;
                    let dist = dq.length();
                    let wi = dq * (1.0 / dist);
                    let margin = light_margin(q.ng, q.p_error, q.p, dq, q.ng.dot(wi).abs());
                    let origin = spawn_origin(p, Vec3::Y, 0.0, wi, true);
                    let (dir, t) = shadow_ray(p, origin, wi, dist, margin);
                    origins.push(origin);
                    dirs.push(dir);
                    tmax.push(t);
                }
                let mut occluded = vec![false; origins.len()];
                let tmin = vec![0.0; origins.len()];
                intersect_occluded(&lamp, &origins, &dirs, &tmin, &tmax, &mut occluded);
                let hits = occluded.iter().filter(|&&o| o).count();
                assert_eq!(
                    hits, 0,
                    "offset {far}, tilt {tilt}: {hits} of 2000 rays hit their own lamp"
                );
                // And they reach almost to it: within 1e-6 relative of the coordinates plus
                // 1e-4 of the distance (an occluder that close to the lamp is still seen).
                if tilt == 0.0 {
                    for (i, &t) in tmax.iter().enumerate() {
                        let gap = (origins[i] + dirs[i] * t - c).y;
                        assert!(
                            gap > 1.0 - 1e-3 - 2e-6 * far,
                            "offset {far}: ray {i} stops at {gap}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn lights_at_infinity_have_no_tmax() {
        assert_eq!(
            shadow_ray(Vec3::ONE, Vec3::ONE, Vec3::Y, f32::INFINITY, 0.0),
            (Vec3::Y, f32::INFINITY)
        );
    }
}
