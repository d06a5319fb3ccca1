//! The render loop of a sweep: every variant's points, level by level (an spp count of the
//! uniform variants, a noise target of the adaptive ones).

use super::*;

/// The largest spp of the points rendered (of the adaptive variants too, or not).
pub(super) fn largest_spp(
    raw: &[Vec<RawPoint>],
    variants: &[Variant],
    adaptive: bool,
) -> Option<u32> {
    raw.iter()
        .zip(variants)
        .filter(|(_, v)| adaptive || v.adaptive.is_none())
        .flat_map(|(c, _)| c.iter().map(|p| p.spp))
        .max()
}

/// The render loop of [`run`].
pub(super) struct Levels<'a, 'p> {
    pub(super) options: &'a ConvergeOptions,
    pub(super) seed: u64,
    pub(super) progress: &'a Progress<'p>,
}

impl Levels<'_, '_> {
    /// Renders the points of the variants that `which` selects into `raw`, level by level
    /// (spp or noise target outermost, so that slow drifts of the machine's load spread
    /// over all variants alike): the uniform ones at each spp count, the adaptive ones at
    /// each noise target with at most `cap` spp. With a time budget a curve ends at its
    /// first point whose mean render time reaches the budget; an adaptive curve also ends
    /// at its first point where every pixel took the cap (a smaller target would render
    /// the same image).
    pub(super) fn render(
        &self,
        scene: &mut CompiledScene,
        raw: &mut [Vec<RawPoint>],
        which: impl Fn(&Variant) -> bool,
        cap: u32,
    ) -> Result<(), ConvergeError> {
        let options = self.options;
        let mut active: Vec<bool> = options.variants.iter().map(which).collect();
        for level in 0.. {
            if !active.iter().any(|&a| a) {
                break;
            }
            for (v, variant) in options.variants.iter().enumerate() {
                if !active[v] {
                    continue;
                }
                let Some((spp, noise_target)) = self.level(variant, level, cap) else {
                    active[v] = false;
                    continue;
                };
                let target = noise_target.map(|relative_error| NoiseTarget {
                    relative_error: relative_error as f32,
                    min_spp: options.adaptive.min_spp,
                    rule: variant.adaptive.unwrap_or_default(),
                });
                let mut renders = Vec::new();
                for r in 0..options.repeats {
                    (self.progress.stage)(&format!(
                        "{}, {}, repeat {}/{}",
                        variant.label(),
                        match noise_target {
                            Some(x) => format!("noise target {x} (at most {spp} spp)"),
                            None => format!("{spp} spp"),
                        },
                        r + 1,
                        options.repeats
                    ));
                    renders.push(timed_render(
                        scene,
                        &options.render,
                        &variant.techniques,
                        (spp, target),
                        self.seed.wrapping_add(r as u64),
                        self.progress,
                    )?);
                }
                if let SppPlan::Budget(budget) = options.plan {
                    let n = renders.len() as f64;
                    if renders.iter().map(|s| s.seconds).sum::<f64>() / n >= budget {
                        active[v] = false;
                    }
                }
                if variant.adaptive.is_some() && renders.iter().all(|s| s.spp_min >= spp) {
                    active[v] = false;
                }
                raw[v].push(RawPoint {
                    spp,
                    noise_target,
                    renders,
                });
            }
        }
        Ok(())
    }

    /// The spp and noise target of `variant`'s point number `level`; `None` past its last.
    fn level(&self, variant: &Variant, level: usize, cap: u32) -> Option<(u32, Option<f64>)> {
        let targets = &self.options.adaptive.noise_targets;
        match (&self.options.plan, variant.adaptive.is_some()) {
            (SppPlan::List(spps), false) => spps.get(level).map(|&s| (s, None)),
            (SppPlan::List(_), true) => targets.get(level).map(|&x| (cap, Some(x))),
            (SppPlan::Budget(_), _) if level >= BUDGET_LEVELS => None,
            (SppPlan::Budget(_), false) => Some((1 << level, None)),
            (SppPlan::Budget(_), true) => {
                let first = targets.first().copied().unwrap_or(DEFAULT_NOISE_TARGETS[0]);
                Some((cap, Some(first * 0.5f64.powi(level as i32))))
            }
        }
    }
}
