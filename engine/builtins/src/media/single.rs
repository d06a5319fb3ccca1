//! Single scattering in a homogeneous medium through the lighting delegate (the seed's
//! "Single Scattering"; see the parent module's docs for the estimator).

use super::*;

impl HomogeneousInterior<'_> {
    /// Single scattering through the delegate (see the module docs), then the hits with the
    /// exact transmittance.
    #[allow(clippy::too_many_arguments, reason = "the bundle's columns, named")]
    pub(super) fn single_scatter(
        &self,
        rays: &Rays,
        samplers: &mut [PathSampler],
        u: &[[f32; DIMS_PER_SEGMENT]],
        tmax: &[f32],
        start: (usize, usize, usize),
        services: VolumeServices<'_, '_>,
        out: &mut ShadeGroups,
    ) {
        let m = &self.medium;
        let n = rays.len();
        let VolumeServices {
            ictx,
            lighting,
            factory,
            arena,
            ..
        } = services;
        let lighting = lighting.expect("called with a delegate");
        // Point and spot lights for equiangular sampling (chosen uniformly).
        let point_lights: Vec<Vec3> = ictx
            .lights()
            .lights()
            .iter()
            .filter_map(|l| match l {
                Light::Point { position, .. } | Light::Spot { position, .. } => Some(*position),
                _ => None,
            })
            .collect();
        let equiangular_mix = |o: Vec3, d: Vec3, tmax: f32, t: f32| -> f32 {
            if point_lights.is_empty() {
                return 0.0;
            }
            point_lights
                .iter()
                .map(|&l| equiangular_pdf(o, d, l, tmax, t))
                .sum::<f32>()
                / point_lights.len() as f32
        };
        let own = self.origins(rays);
        let parent = own.as_ref().map(|pts| {
            ShadingContext::new(pts, 0..n, ShadingMode::Interior, self.ctx.material(), &[])
        });
        let parent = parent.as_ref().unwrap_or(self.ctx);
        let techniques = if point_lights.is_empty() { 1 } else { 2 };
        let mut lit = 0;
        for technique in 0..techniques {
            let mut member = vec![false; n];
            let mut t = vec![0.0f32; n];
            let mut weight = vec![Rgb::BLACK; n];
            for i in 0..n {
                if tmax[i] == f32::INFINITY {
                    continue; // already outside (see `scatter_inside`)
                }
                let (o, d) = (rays.origin[i], rays.direction[i]);
                let pdf_channels = channel_pdf(rays.throughput[i]);
                let ti = if technique == 0 {
                    let f = sample_free_flight(
                        m.sigma_t,
                        m.sigma_s,
                        pdf_channels,
                        u[i][0],
                        u[i][1],
                        tmax[i],
                    );
                    if !f.scattered {
                        continue;
                    }
                    f.t
                } else {
                    let k = ((u[i][2] * point_lights.len() as f32) as usize)
                        .min(point_lights.len() - 1);
                    let (te, pdf) = equiangular_sample(o, d, point_lights[k], tmax[i], u[i][3]);
                    if pdf <= 0.0 || te >= tmax[i] {
                        continue;
                    }
                    te
                };
                let pdf = free_flight_pdf(m.sigma_t, pdf_channels, ti)
                    + equiangular_mix(o, d, tmax[i], ti);
                if !(pdf > 0.0 && pdf.is_finite()) {
                    continue;
                }
                let w = m.sigma_s * transmittance(m.sigma_t, ti) * (1.0 / pdf);
                if w.is_finite() && !w.is_black() {
                    member[i] = true;
                    t[i] = ti;
                    weight[i] = w;
                }
            }
            let count = member.iter().filter(|&&b| b).count();
            if count == 0 {
                continue;
            }
            if let Some(graph) = &m.albedo_pattern {
                // The weights were of albedo 1: times the albedo at each point.
                let evals = scale_by_albedo(graph, rays, &t, &member, &mut weight);
                self.ctx.count_pattern_evals(evals);
            }
            lit += count;
            let mut v = parent.begin_volume_sampling();
            v.set_along_rays(rays, &t);
            // Light only the members: a context of those points alone.
            let mut pts = ShadingPoints::with_capacity(count);
            let mut w = Vec::with_capacity(count);
            let vctx = v.context();
            let (rows, range) = vctx.rows();
            for (i, &keep) in member.iter().enumerate() {
                if keep {
                    pts.push_from(rows, range.start + i);
                    w.push(weight[i]);
                }
            }
            let ctx = ShadingContext::new(
                &pts,
                0..count,
                ShadingMode::VolumeScatter,
                self.ctx.material(),
                &[],
            );
            let bxdf = factory.begin_scatter(&ctx, ShadingMode::VolumeScatter, arena);
            if m.g_pattern.is_some() {
                // This context has no cache: the phase Bxdf evaluated `g` at every point.
                self.ctx.count_pattern_evals(count as u64);
            }
            lighting.perform_direct_lighting(&ctx, bxdf, rays, samplers, &w);
        }
        ictx.count_volume_events(risotto_engine::stats::VolumeEvent::Scatter, lit);
        // The rays go on to their hits, attenuated exactly.
        for k in start.0..out.points.len() {
            out.points.transmission[k] *= transmittance(m.sigma_t, out.points.vlen[k]);
        }
        for k in start.2..out.misses.len() {
            let r = out.misses[k] as usize;
            out.miss_transmission[k] *= transmittance(m.sigma_t, rays.tmax[r]);
        }
    }
}
