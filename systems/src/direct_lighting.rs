//! The direct-lighting system: from a group's light samples and its Bxdf's response to them,
//! the shadow rays (next-event estimation) with their multiple-importance weights.
//!
//! One implementation serves every caller: surface and volume points shaded by the global
//! integrator (MIS against the Bxdf or phase-function sample the path continues with, Veach
//! 1997 sec. 9.2, power heuristic) and the lighting delegate volume integrators call at
//! in-volume points (no MIS: no phase-function sample is taken there, so light sampling alone
//! must carry the whole estimate, see [`LightMis`]).

use crate::lights::{power_heuristic, LightSampleColumns};
use crate::path::Vertices;
use crate::ray::{offset_origin, shadow_ray, InteriorBoundaries};
use glam::{BVec4A, Vec4};
use risotto_components::{Rgb, ShadowRayColumns};

/// How a light sample is weighted against the other technique that could produce the same
/// light path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightMis {
    /// Power heuristic against the Bxdf pdf: the path continues with a Bxdf sample, which
    /// counts the emitters it hits with the complementary weight.
    PowerHeuristic,
    /// Weight 1: nothing else will count this light path (light sampling only, or the
    /// lighting delegate at points where no Bxdf sample is taken).
    None,
}

/// Light samples of a group's points and the Bxdf's response to them.
pub struct LightColumns<'a> {
    /// Light sample per point (pdf 0: no shadow ray).
    pub samples: LightSampleColumns<'a>,
    /// Bxdf value `f * |cos|` (phase function: `albedo * p`) for the sample's direction.
    pub value: &'a [Rgb],
    /// Bxdf pdf of the sample's direction (for MIS); overwritten with the contribution
    /// factor of [`light_weights`].
    pub pdf: &'a mut [f32],
    /// Scratch: the points that may get a shadow ray.
    pub points: &'a mut [u32],
}

/// Overwrites `b_pdf[k]` (the Bxdf pdf of light sample `k`) with `w / l_pdf[k]`, the factor
/// of the sample's shadow-ray contribution: `w` the power heuristic against the Bxdf pdf,
/// or 1 for Dirac lights and without MIS. Four points per SSE operation, the operations of
/// `power_heuristic` and the division in the same order (IEEE operations round the same in
/// any lane), so the same bits as the scalar formula; the two divisions leave the
/// spawn loop's dependency chain. Values where `l_pdf` is 0 are meaningless.
pub fn light_weights(l_pdf: &[f32], b_pdf: &mut [f32], delta: &[bool], no_mis: bool) {
    let m = b_pdf.len();
    let (l_pdf, delta) = (&l_pdf[..m], &delta[..m]);
    let (l4, l_rest) = l_pdf.as_chunks::<4>();
    let (d4, d_rest) = delta.as_chunks::<4>();
    let (b4, b_rest) = b_pdf.as_chunks_mut::<4>();
    for ((l, d), b) in l4.iter().zip(d4).zip(b4) {
        let (pa, pb) = (Vec4::from_array(*l), Vec4::from_array(*b));
        let (a, bb) = (pa * pa, pb * pb);
        let w = a / (a + bb);
        let w = Vec4::select(w.is_finite_mask() & a.is_finite_mask(), w, Vec4::ONE);
        let w = Vec4::select(a.cmpne(Vec4::ZERO), w, Vec4::ZERO);
        let dirac = BVec4A::new(d[0] | no_mis, d[1] | no_mis, d[2] | no_mis, d[3] | no_mis);
        let w = Vec4::select(dirac, Vec4::ONE, w);
        *b = (w / pa).to_array();
    }
    for ((&l, &d), b) in l_rest.iter().zip(d_rest).zip(b_rest) {
        let w = if d | no_mis {
            1.0
        } else {
            power_heuristic(l, *b)
        };
        *b = w / l;
    }
}

/// Direct-lighting system: writes to `out` from row `start` on one shadow ray per point of
/// the group whose light sample has a non-black contribution `throughput * weight * f * Le *
/// w / pdf` (`weight`: an extra factor per point of the group, the lighting delegate's
/// caller's weights, `None` for 1; power heuristic weight `w` unless the sample is a Dirac light or `mis` is
/// [`LightMis::None`]), and returns the number of rows written. `boundaries` (when volume
/// stacks can be non-empty) copies the rays' stacks and records crossings of the surface the
/// shadow ray starts on; `None` means every stack is empty, and the rows' stacks are left as
/// they are. Every other column of the rows written is overwritten; the `dimension` column is
/// `dimension[r]` of the incoming ray `r` (usually its own column: the vertex's first sampler dimension; the shadow ray's estimators draw
/// from their own, decorrelated sequence starting there, fresh per bounce).
///
/// Written for few instructions per row: the output rows exist up front (no per-column
/// capacity checks), columns are re-sliced to one length each so that a row needs at most
/// one bounds check per length, and one pass in point order both decides which points get a
/// ray and fills the row.
#[allow(
    clippy::too_many_arguments,
    reason = "the columns it reads and writes, named"
)]
pub fn spawn_shadow_rays(
    from: Vertices<'_>,
    weight: Option<&[Rgb]>,
    dimension: &[u32],
    light: LightColumns<'_>,
    mis: LightMis,
    boundaries: Option<InteriorBoundaries<'_>>,
    out: &mut ShadowRayColumns<'_>,
    start: usize,
) -> usize {
    let lift = from.terminator_lift && from.on_surface;
    let Vertices {
        points: pts,
        range,
        on_surface,
        incoming,
        ..
    } = from.clone();
    let ray_id = &pts.ray_id[range.clone()];
    let (m, n) = (ray_id.len(), incoming.len());
    let rows = start..start + m;
    let (o_origin, o_direction, o_tmax, o_contribution, o_weight) = (
        &mut out.origin[rows.clone()],
        &mut out.direction[rows.clone()],
        &mut out.tmax[rows.clone()],
        &mut out.contribution[rows.clone()],
        &mut out.weight[rows.clone()],
    );
    let (o_path, o_dimension, o_stack) = (
        &mut out.path[rows.clone()],
        &mut out.dimension[rows.clone()],
        &mut out.volume_stack[rows],
    );
    // One pass: the point columns are read in order, the incoming-ray columns through the
    // one `r` loaded per point.
    let in_throughput = &incoming.throughput[..n];
    let (in_path, in_dimension) = (&incoming.path[..n], &dimension[..n]);
    let ls = &light.samples;
    let (l_wi, l_distance, l_radiance) = (&ls.wi[..m], &ls.distance[..m], &ls.radiance[..m]);
    let l_margin = &ls.margin[..m];
    let l_pdf = &ls.pdf[..m];
    let value = &light.value[..m];
    let (p, ng) = (&pts.p[range.clone()][..m], &pts.ng[range.clone()][..m]);
    let p_offset = &pts.p_offset[range.clone()][..m];
    // The factors `w / pdf` of all points, vectorised.
    light_weights(
        l_pdf,
        &mut light.pdf[..m],
        &ls.delta[..m],
        mis == LightMis::None,
    );
    let factor = &light.pdf[..m];
    // The points with a sample the Bxdf reflects, listed without a branch (a branch on it in
    // the loop below mispredicts about half the time).
    let points = &mut light.points[..m];
    let mut listed = 0;
    for k in 0..m {
        points[listed] = k as u32;
        listed += ((l_pdf[k] != 0.0) & !is_black(value[k])) as usize;
    }
    let mut count = 0;
    for &k in &points[..listed] {
        let k = k as usize;
        let r = ray_id[k] as usize;
        let mut w = in_throughput[r] * value[k];
        if let Some(weight) = weight {
            w *= weight[k];
        }
        let c = w * l_radiance[k] * factor[k];
        if is_black(c) {
            continue;
        }
        let wi = l_wi[k];
        o_contribution[count] = c;
        o_weight[count] = w * factor[k];
        o_direction[count] = wi;
        o_path[count] = in_path[r];
        o_dimension[count] = in_dimension[r];
        // Origin offset by its error bound to the side of the surface the ray leaves to
        // (`crate::ray`).
        // Rays to the viewer's side of a smooth mesh leave from its smooth surface
        // (`crate::terminator`).
        let (p, ng) = (p[k], ng[k]);
        o_origin[count] = if lift {
            offset_origin(from.leaving_point(range.start + k, wi), ng, p_offset[k], wi)
        } else if on_surface {
            offset_origin(p, ng, p_offset[k], wi)
        } else {
            p
        };
        // Aimed at the light point from the origin itself, stopping short of it by the
        // light point's own bound (`shadow_ray`).
        (o_direction[count], o_tmax[count]) =
            shadow_ray(p, o_origin[count], wi, l_distance[k], l_margin[k]);
        if let Some(b) = boundaries {
            let stack = &mut o_stack[count];
            *stack = incoming.volume_stack[r].clone();
            // A shadow ray leaving through the surface it starts on enters (or leaves) that
            // shape's interior.
            let i = range.start + k;
            // A lifted ray starts on the viewer's side, above the triangle, whichever side
            // of its plane it goes to.
            let crosses = (wi.dot(ng) >= 0.0) != (pts.vn[i].dot(ng) >= 0.0);
            if on_surface && crosses && !(lift && from.lifted(i, wi)) {
                b.cross(stack, pts.shape[i], pts.front_face[i]);
            }
        }
        count += 1;
    }
    count
}

/// The number of rows `k` with `active[k]` whose `c[k]` or `x[k]` is not finite (NaN or
/// infinite): the non-finite count of a stage's outputs (a Bxdf's value and pdf, a light
/// sample's radiance and pdf). Non-finite values are rare, so a branch-free pass first asks
/// whether every value of the columns, active or not, is finite (`|v| < inf`, false for NaN:
/// `f32::is_finite`), four rows (sixteen values) in four `Vec4` compares; only when one is
/// not are the rows counted one by one.
pub fn non_finite_rows(active: &[bool], c: &[Rgb], x: &[f32]) -> usize {
    let m = active.len();
    let (c, x) = (&c[..m], &x[..m]);
    let (c4, c_rest) = c.as_chunks::<4>();
    let (x4, x_rest) = x.as_chunks::<4>();
    let mut finite = BVec4A::splat(true);
    for (c, x) in c4.iter().zip(x4) {
        let c = c.map(Rgb::to_array);
        let (c, _) = c.as_flattened().as_chunks::<4>();
        for v in [c[0], c[1], c[2], *x] {
            finite &= Vec4::from_array(v).is_finite_mask();
        }
    }
    let rest = c_rest.iter().zip(x_rest);
    if finite.all() && rest.fold(true, |f, (c, x)| f & c.is_finite() & x.is_finite()) {
        return 0;
    }
    (0..m)
        .filter(|&k| active[k] & !(c[k].is_finite() & x[k].is_finite()))
        .count()
}

/// `c.is_black()` without a branch per channel.
#[inline]
pub fn is_black(c: Rgb) -> bool {
    (c.r == 0.0) & (c.g == 0.0) & (c.b == 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_rows_counts_the_active_rows_with_a_non_finite_value() {
        // Eleven rows (two blocks of four and a rest of three); one non-finite value at a
        // time in each of the four values of each row, active or not.
        let n = 11;
        let active: Vec<bool> = (0..n).map(|k| k % 3 != 1).collect();
        let c0: Vec<Rgb> = (0..n)
            .map(|k| Rgb::new(k as f32, -1e38, f32::MAX))
            .collect();
        let x0: Vec<f32> = (0..n).map(|k| 0.5 - k as f32).collect();
        assert_eq!(non_finite_rows(&active, &c0, &x0), 0);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for k in 0..n {
                for value in 0..4 {
                    let (mut c, mut x) = (c0.clone(), x0.clone());
                    match value {
                        0 => c[k].r = bad,
                        1 => c[k].g = bad,
                        2 => c[k].b = bad,
                        _ => x[k] = bad,
                    }
                    let expected = active[k] as usize;
                    assert_eq!(
                        non_finite_rows(&active, &c, &x),
                        expected,
                        "row {k} {value}"
                    );
                }
            }
        }
        // Several rows at once (row 10 inactive).
        let (mut c, mut x) = (c0.clone(), x0.clone());
        (c[0].g, x[2], c[9].b, x[10]) = (f32::NAN, f32::INFINITY, f32::NAN, f32::NAN);
        assert_eq!(non_finite_rows(&active, &c, &x), 3);
        assert_eq!(non_finite_rows(&[true; 3], &c, &x), 2);
    }

    #[test]
    fn light_weights_match_the_scalar_formula() {
        let l = [0.5, 0.0, 2.0, 1e30, 0.25, 3.0, 0.1];
        let b0 = [0.5, 1.0, 0.0, 1.0, 4.0, f32::INFINITY, 0.3];
        let d = [false, false, false, false, true, false, false];
        for no_mis in [false, true] {
            let mut b = b0;
            light_weights(&l, &mut b, &d, no_mis);
            for k in 0..l.len() {
                if l[k] == 0.0 {
                    continue;
                }
                let w = if d[k] || no_mis {
                    1.0
                } else {
                    power_heuristic(l[k], b0[k])
                };
                assert_eq!(b[k].to_bits(), (w / l[k]).to_bits(), "row {k}");
            }
        }
    }
}
