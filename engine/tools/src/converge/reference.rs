//! The technique a rendered reference uses when none is given: the sweep's most efficient
//! variant among those that converge to the exact image, judged without a reference (module
//! docs of [`crate::converge`]).

use super::*;

/// The variant that renders a reference best: among the uniform ones that converge to the
/// exact image ([`Techniques::converges`]; an adaptive variant's stopping rule is biased),
/// the one with the largest `1 / (MSE x seconds)` at its largest spp, its MSE estimated
/// without a reference from two independent renders `a`, `b` (seeds) of that point as
/// `mean (a - b)^2 / 2` (for an unbiased estimator `E (a - b)^2 = 2 Var`, and its MSE is
/// its variance). A sweep with one repeat renders the second image of each candidate with
/// `extra_seed`.
pub(super) fn most_efficient_converging(
    scene: &mut CompiledScene,
    base: &RenderOptions,
    variants: &[Variant],
    raw: &[Vec<RawPoint>],
    extra_seed: u64,
    progress: &Progress,
) -> Result<Techniques, ConvergeError> {
    let registry = TechniqueRegistry::for_scene(scene);
    let mut best: Option<(f64, &Techniques)> = None;
    for (variant, points) in variants.iter().zip(raw) {
        let techniques = &variant.techniques;
        if variant.adaptive.is_some() || !techniques.converges(&registry) {
            continue;
        }
        let Some(RawPoint { spp, renders, .. }) = points.last() else {
            continue;
        };
        let extra;
        let (a, b) = match renders.as_slice() {
            [a, b, ..] => (a, b),
            [a] => {
                (progress.stage)(&format!(
                    "{}, {spp} spp, second seed (choosing the reference's technique)",
                    techniques.label()
                ));
                extra = timed_render(scene, base, techniques, (*spp, None), extra_seed, progress)?;
                (a, &extra)
            }
            [] => continue,
        };
        let (_, noise_mse, _) = combine_halves(&a.image, &b.image);
        // combine_halves gives mean (a - b)^2 / 4.
        let mse = 2.0 * noise_mse;
        let seconds = a.seconds.min(b.seconds);
        let efficiency = 1.0 / (mse * seconds).max(f64::MIN_POSITIVE);
        if best.is_none_or(|(e, _)| efficiency > e) {
            best = Some((efficiency, techniques));
        }
    }
    best.map(|(_, t)| *t).ok_or_else(|| {
        ConvergeError::Options(
            "no swept technique converges to the exact image to render the reference with; \
             give one with --reference-technique"
                .into(),
        )
    })
}
