//! The layered Bxdf against things that are not itself: the bare base under an
//! index-matched coat, the closed-form albedo of a smooth coat over a Lambertian base, the
//! white furnace, reciprocity, and the sampler against the evaluation bin by bin.

use super::*;
use crate::bxdf::{fresnel_dielectric, sample_cosine_hemisphere};
use crate::microfacet::Ggx;
use crate::rough_conductor::RoughConductor;
use crate::rough_dielectric::RoughDielectric;
use crate::sampler::SplitMix64 as Rng;

fn dir(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

fn layered(alpha: f32, eta: f32, thickness: f32, albedo: Rgb, max_depth: u32) -> Layered {
    Layered {
        coat: Coat::new(Ggx::isotropic(alpha), eta),
        thickness,
        albedo,
        g: 0.0,
        max_depth,
        n_samples: 1,
    }
}

fn copper(alpha: f32) -> RoughConductor {
    let cu = crate::conductor::metal("Cu").unwrap();
    RoughConductor::new(
        Ggx::isotropic(alpha),
        Rgb::from_array(cu.eta),
        Rgb::from_array(cu.k),
        Rgb::WHITE,
        false,
    )
}

fn close(a: Rgb, b: Rgb, rel: f32) -> bool {
    a.to_array()
        .into_iter()
        .zip(b.to_array())
        .all(|(x, y)| (x - y).abs() <= rel * y.abs().max(1e-6))
}

/// An index-matched coat (`eta = 1`) is a Dirac pass-through: the layered Bxdf is the bare
/// base times the slab's transmittance in and out, `exp(-t / cos_o) exp(-t / cos_i)`, for
/// every walk (so exactly, not only in expectation); with a vanishing slab it is the base.
#[test]
fn index_matched_coat_is_the_bare_base_times_the_slab_transmittance() {
    let mut rng = Rng(3);
    let cu = copper(0.3);
    let bases = [
        Base::Diffuse(Rgb::new(0.2, 0.5, 0.9)),
        Base::RoughConductor(&cu),
    ];
    for base in bases {
        for thickness in [f32::MIN_POSITIVE, 0.01, 0.3] {
            let l = layered(0.5, 1.0, thickness, Rgb::BLACK, 10);
            for _ in 0..500 {
                let wo = dir(rng.f32() * 1.5, rng.f32() * std::f32::consts::TAU);
                let wi = dir(rng.f32() * 1.5, rng.f32() * std::f32::consts::TAU);
                let bare = match base {
                    Base::Diffuse(r) => r * (wi.z / PI),
                    Base::RoughConductor(c) => c.eval(wo, wi).0,
                    Base::SmoothConductor { .. } => unreachable!(),
                };
                let slab = tr(thickness, wo) * tr(thickness, wi);
                let got = l.eval(&base, wo, wi, &mut rng);
                assert!(
                    close(got, bare * slab, 1e-4),
                    "{thickness} {wo} {wi}: {got:?} vs {:?}",
                    bare * slab
                );
                // Two-sided: seen from below, the mirrored pair.
                let below = l.eval(&base, -wo, -wi, &mut rng);
                assert!(close(below, got, 1e-4));
            }
        }
    }
}

/// Mean of `weight` over `n` samples from `wo`, and its standard error.
fn sampled_albedo(l: &Layered, base: &Base<'_>, wo: Vec3, n: usize, seed: u64) -> (Rgb, f32) {
    let mut rng = Rng(seed);
    let (mut sum, mut sum2) = (Rgb::BLACK, 0.0f64);
    for _ in 0..n {
        let (uc, u) = (rng.f32(), rng.vec2());
        if let Some(s) = l.sample(base, wo, uc, u, rng.next_u64()) {
            assert!(s.weight.is_finite() && s.pdf > 0.0 && s.wi.z > 0.0, "{s:?}");
            sum += s.weight;
            sum2 += (s.weight.g as f64).powi(2);
        }
    }
    let mean = sum * (1.0 / n as f32);
    let var = (sum2 / n as f64 - (mean.g as f64).powi(2)).max(0.0);
    (mean, (var / n as f64).sqrt() as f32)
}

/// The internal diffuse Fresnel reflectance of the coat seen from inside,
/// `2 int_0^1 F(mu) mu dmu` by a midpoint rule, F at the inside cosine.
fn internal_diffuse_reflectance(eta: f32) -> f32 {
    const N: usize = 20_000;
    (0..N)
        .map(|i| {
            let mu = (i as f32 + 0.5) / N as f32;
            2.0 * fresnel_dielectric(-mu, eta) * mu / N as f32
        })
        .sum()
}

/// A smooth non-absorbing coat over a Lambertian base of reflectance `R`, seen at normal
/// incidence: the coat reflects `F0`; the rest enters, and every visit to the base returns
/// `R` of it as a diffuse field of which `1 - Fdr_int` escapes (the remainder goes back down):
/// `A = F0 + (1 - F0) R (1 - Fdr_int) / (1 - R Fdr_int)`, the geometric series of the
/// interreflections. Both the sampler's mean weight and the integral of the evaluation
/// (plus the Dirac `F0` it leaves out) give it.
#[test]
fn smooth_coat_over_lambertian_matches_the_closed_form_albedo() {
    for (eta, r) in [(1.5f32, 0.8f32), (1.33, 0.5), (2.0, 1.0)] {
        let l = layered(0.0, eta, f32::MIN_POSITIVE, Rgb::BLACK, 200);
        let base = Base::Diffuse(Rgb::splat(r));
        let f0 = fresnel_dielectric(1.0, eta);
        let fdr = internal_diffuse_reflectance(eta);
        let expected = f0 + (1.0 - f0) * r * (1.0 - fdr) / (1.0 - r * fdr);
        let (mean, se) = sampled_albedo(&l, &base, Vec3::Z, 200_000, 11);
        assert!(
            (mean.g - expected).abs() < 5.0 * se + 2e-3,
            "eta {eta} R {r}: sampled {} vs {expected} (se {se})",
            mean.g
        );
        // The evaluation integrated by cosine sampling: E[f cos / (cos / pi)].
        let mut rng = Rng(5);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let wi = sample_cosine_hemisphere(rng.vec2());
            sum += (l.eval(&base, Vec3::Z, wi, &mut rng).g * PI / wi.z) as f64;
        }
        let diffuse = (sum / n as f64) as f32;
        assert!(
            (diffuse + f0 - expected).abs() < 0.01 * expected,
            "eta {eta} R {r}: eval {} vs {expected}",
            diffuse + f0
        );
    }
}

/// The white furnace: a white base under a smooth coat over a slab that absorbs nothing
/// (vanishing thickness, or a white scattering medium) reflects everything, at any angle
/// (up to the walk's length limit, set long here); a slab of optical depth 0.01 at the
/// default walk length loses a little and never gains.
#[test]
fn white_furnace_conserves_energy_under_a_smooth_coat() {
    for (thickness, albedo) in [(f32::MIN_POSITIVE, Rgb::BLACK), (0.5, Rgb::WHITE)] {
        let l = layered(0.0, 1.5, thickness, albedo, 400);
        for theta in [0.0f32, 0.8, 1.4] {
            let wo = dir(theta, 0.3);
            let (mean, se) = sampled_albedo(&l, &Base::Diffuse(Rgb::WHITE), wo, 40_000, 7);
            assert!(
                (mean.g - 1.0).abs() < 5.0 * se + 1e-3,
                "t {thickness} theta {theta}: {} (se {se})",
                mean.g
            );
        }
    }
    let l = layered(0.0, 1.5, 0.01, Rgb::BLACK, 10);
    let (mean, se) = sampled_albedo(&l, &Base::Diffuse(Rgb::WHITE), Vec3::Z, 40_000, 9);
    assert!(mean.g < 1.0 - 3.0 * se && mean.g > 0.8, "{}", mean.g);
}

/// A rough coat loses what its single-scattering GGX interface loses at every crossing and
/// internal reflection (pbrt-v4 has no compensation either). With a white Lambertian base
/// and no absorption, every return to the base makes the field inside cosine-distributed
/// again, so the albedo is a geometric series over the interface's own mean weights,
/// measured here with the rough dielectric's sampler alone: `A = R(wo) + T(wo) t / (1 - r)`
/// with `R`, `T` the reflected and transmitted mean weights from `wo`, and `t`, `r` those of
/// a cosine-distributed field arriving from inside. The layered sampler (its walk, with a
/// white scattering slab too) must give the same.
#[test]
fn rough_coat_white_furnace_matches_the_interface_series() {
    let mut rng = Rng(31);
    for alpha in [0.2f32, 0.7] {
        let d = RoughDielectric::new(Ggx::isotropic(alpha), 1.5, Rgb::WHITE, false);
        let n = 200_000;
        // Mean reflected and transmitted weights from `wo` (either side).
        let mut split = |wo: &mut dyn FnMut(&mut Rng) -> Vec3| {
            let (mut r, mut t) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let w = wo(&mut rng);
                if let Some(s) = d.sample(w, rng.vec2(), rng.f32()) {
                    if s.wi.z * w.z > 0.0 {
                        r += s.weight.g as f64;
                    } else {
                        t += s.weight.g as f64;
                    }
                }
            }
            ((r / n as f64) as f32, (t / n as f64) as f32)
        };
        let (r_in, t_in) = split(&mut |rng: &mut Rng| -sample_cosine_hemisphere(rng.vec2()));
        for theta in [0.0f32, 1.2] {
            let wo = dir(theta, 0.3);
            let (r_o, t_o) = split(&mut |_: &mut Rng| wo);
            let expected = r_o + t_o * t_in / (1.0 - r_in);
            for (thickness, albedo) in [(f32::MIN_POSITIVE, Rgb::BLACK), (0.3, Rgb::WHITE)] {
                let l = layered(alpha, 1.5, thickness, albedo, 1000);
                let (mean, se) = sampled_albedo(&l, &Base::Diffuse(Rgb::WHITE), wo, 100_000, 3);
                assert!(
                    (mean.g - expected).abs() < 5.0 * se + 0.01 * expected,
                    "alpha {alpha} theta {theta} t {thickness}: {} (se {se}) vs {expected}",
                    mean.g
                );
                assert!(mean.g < 1.0);
            }
        }
    }
}

/// `f(wo, wi) = f(wi, wo)` in expectation (both directions in vacuum): averaged over many
/// walks, within five standard errors.
#[test]
fn layered_bxdf_is_reciprocal_in_expectation() {
    let cu = copper(0.4);
    let cases: [(Layered, Base<'_>); 3] = [
        (
            layered(0.3, 1.5, 0.1, Rgb::BLACK, 10),
            Base::Diffuse(Rgb::splat(0.7)),
        ),
        (
            layered(0.0, 1.5, 0.2, Rgb::new(0.9, 0.5, 0.2), 10),
            Base::Diffuse(Rgb::splat(0.6)),
        ),
        (
            layered(0.2, 1.4, 0.05, Rgb::splat(0.8), 10),
            Base::RoughConductor(&cu),
        ),
    ];
    let mut rng = Rng(17);
    for (l, base) in cases.iter() {
        for (a, b) in [
            ((0.2f32, 0.0f32), (1.1f32, 2.5f32)),
            ((0.9, 1.0), (0.4, 4.0)),
        ] {
            let (wo, wi) = (dir(a.0, a.1), dir(b.0, b.1));
            let stats = |wo: Vec3, wi: Vec3, rng: &mut Rng| {
                let n = 40_000;
                let (mut s, mut s2) = (0.0f64, 0.0f64);
                for _ in 0..n {
                    // f = (f cos_i) / cos_i.
                    let v = (l.eval(base, wo, wi, rng).g / wi.z) as f64;
                    s += v;
                    s2 += v * v;
                }
                let m = s / n as f64;
                (m, ((s2 / n as f64 - m * m) / n as f64).sqrt())
            };
            let (f1, e1) = stats(wo, wi, &mut rng);
            let (f2, e2) = stats(wi, wo, &mut rng);
            assert!(
                (f1 - f2).abs() < 5.0 * (e1 * e1 + e2 * e2).sqrt() + 1e-4 * f1,
                "{wo} {wi}: {f1} ({e1}) vs {f2} ({e2})"
            );
        }
    }
}

/// The sampler against the evaluation: over bins of (cos theta, phi), the mean of the
/// sample weights falling in a bin (`int_bin f cos`, what the sampler estimates) equals the
/// evaluation integrated over the bin (by uniform hemisphere sampling), within five standard
/// errors, for rough coats over diffuse and conductor bases, with and without a scattering
/// slab. (The sampler's density is not in closed form: pbrt-v4's `PDF` is an approximation
/// used only for MIS, so the check is on what the sampler's weights integrate to.)
#[test]
fn sample_weights_integrate_the_evaluation_bin_by_bin() {
    const NT: usize = 4;
    const NP: usize = 4;
    let cu = copper(0.25);
    let cases: [(Layered, Base<'_>); 3] = [
        (
            layered(0.3, 1.5, 0.05, Rgb::BLACK, 10),
            Base::Diffuse(Rgb::splat(0.8)),
        ),
        (
            layered(0.5, 1.5, 0.3, Rgb::splat(0.9), 10),
            Base::Diffuse(Rgb::splat(0.5)),
        ),
        (
            layered(0.15, 1.5, 0.01, Rgb::BLACK, 10),
            Base::RoughConductor(&cu),
        ),
    ];
    let bin = |w: Vec3| {
        let i = ((w.z * NT as f32) as usize).min(NT - 1);
        let phi = w.y.atan2(w.x).rem_euclid(std::f32::consts::TAU);
        let j = ((phi / std::f32::consts::TAU * NP as f32) as usize).min(NP - 1);
        i * NP + j
    };
    for (c, (l, base)) in cases.iter().enumerate() {
        let wo = dir(0.6, 0.0);
        let mut rng = Rng(100 + c as u64);
        let n = 200_000;
        let mut sampled = vec![(0.0f64, 0.0f64); NT * NP];
        for _ in 0..n {
            let (uc, u) = (rng.f32(), rng.vec2());
            if let Some(s) = l.sample(base, wo, uc, u, rng.next_u64()) {
                let v = s.weight.g as f64;
                let b = &mut sampled[bin(s.wi)];
                b.0 += v;
                b.1 += v * v;
            }
        }
        let mut evaluated = vec![(0.0f64, 0.0f64); NT * NP];
        for _ in 0..n {
            let u = rng.vec2();
            let wi = dir(u.x.acos(), u.y * std::f32::consts::TAU);
            // Uniform hemisphere: pdf 1 / 2pi.
            let v = (l.eval(base, wo, wi, &mut rng).g * 2.0 * PI) as f64;
            let b = &mut evaluated[bin(wi)];
            b.0 += v;
            b.1 += v * v;
        }
        for k in 0..NT * NP {
            let stat = |(s, s2): (f64, f64)| {
                let m = s / n as f64;
                (m, ((s2 / n as f64 - m * m) / n as f64).sqrt())
            };
            let (a, ea) = stat(sampled[k]);
            let (b, eb) = stat(evaluated[k]);
            assert!(
                (a - b).abs() < 5.0 * (ea * ea + eb * eb).sqrt() + 1e-4,
                "case {c} bin {k}: sampled {a} ({ea}) vs evaluated {b} ({eb})"
            );
        }
    }
}

/// The density estimate: positive wherever the Bxdf is (the uniform tenth), zero for a
/// transmission, deterministic for a given generator state. It is pbrt-v4's heuristic, not
/// a normalised density: for a rough coat over a diffuse base it adds the coat's
/// reflection-only density (which integrates to about 1: no Fresnel factor) to the
/// one-bounce estimate (about 1 more, counted in the inside directions), so its mean
/// integrates to about `0.1 + 0.9 * 2 = 1.9` (measured: 2.16).
#[test]
fn density_estimate_covers_the_lobe_as_pbrt_v4s_does() {
    let l = layered(0.3, 1.5, 0.01, Rgb::BLACK, 10);
    let base = Base::Diffuse(Rgb::splat(0.5));
    let wo = dir(0.5, 1.0);
    let mut rng = Rng(1);
    assert_eq!(l.pdf(&base, wo, -wo, &mut rng), 0.0);
    let (mut a, mut b) = (Rng(9), Rng(9));
    assert_eq!(
        l.pdf(&base, wo, Vec3::Z, &mut a),
        l.pdf(&base, wo, Vec3::Z, &mut b)
    );
    let n = 200_000;
    let mut sum = 0.0f64;
    for _ in 0..n {
        let u = rng.vec2();
        let wi = dir(u.x.acos(), u.y * std::f32::consts::TAU);
        let p = l.pdf(&base, wo, wi, &mut rng);
        assert!(p >= 0.1 / (4.0 * PI) * 0.999, "{p}");
        sum += (p * 2.0 * PI) as f64;
    }
    let integral = sum / n as f64;
    assert!((1.7..2.5).contains(&integral), "{integral}");
}

/// The restricted samplers of the rough dielectric, which the walk uses, against their own
/// densities: the mean of `1 / pdf` over samples is the solid angle the lobe reaches
/// (`2pi` for a reflection lobe that covers the upper hemisphere), and the mean weight of
/// the reflection-only sampler is `int F D G2 / (4 cos_o)`, which the unrestricted sampler's
/// reflections give with their Fresnel choice divided out.
#[test]
fn restricted_dielectric_samplers_agree_with_the_unrestricted_one() {
    let d = RoughDielectric::new(Ggx::isotropic(0.4), 1.5, Rgb::WHITE, false);
    let wo = dir(0.7, 0.2);
    let mut rng = Rng(21);
    let n = 200_000;
    let (mut refl_only, mut refl_both, mut trans_only, mut trans_both) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..n {
        let (u, ul) = (rng.vec2(), rng.f32());
        if let Some(s) = d.sample_lobes(wo, u, ul, Lobes::Reflection) {
            assert!(s.wi.z > 0.0);
            let (v, p) = d.eval_lobes(wo, s.wi, Lobes::Reflection);
            assert!((p - s.pdf).abs() <= 1e-4 * p && close(v * (1.0 / p), s.weight, 1e-4));
            refl_only += s.weight.g as f64;
        }
        if let Some(s) = d.sample_lobes(wo, u, ul, Lobes::Transmission) {
            assert!(s.wi.z < 0.0);
            trans_only += s.weight.g as f64;
        }
        if let Some(s) = d.sample(wo, u, ul) {
            if s.wi.z > 0.0 {
                refl_both += s.weight.g as f64;
            } else {
                trans_both += s.weight.g as f64;
            }
        }
    }
    let (ro, rb) = (refl_only / n as f64, refl_both / n as f64);
    let (to, tb) = (trans_only / n as f64, trans_both / n as f64);
    assert!(
        (ro - rb).abs() < 0.02 * rb.max(0.01),
        "reflection {ro} vs {rb}"
    );
    assert!((to - tb).abs() < 0.02 * tb, "transmission {to} vs {tb}");
}
