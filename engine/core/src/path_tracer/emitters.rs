//! Emitters hit by path rays (area lights, the environment): the depth budget and the MIS
//! weight against light sampling, shared by the escaped, pass-through and shade stages.

use super::PathTracer;
use crate::integrator::LightingTechnique;
use crate::scene::CompiledScene;
use glam::Vec3;
use risotto_components::{Paths, Rays, Rgb, ShadingPoints, NO_HIT};
use risotto_systems::lights::{power_heuristic, LightSet};

impl PathTracer {
    /// The light set the shade stage samples: under MIS a constant environment is left to
    /// Bxdf sampling (`CompiledScene::mis_lights`); light sampling alone must sample all.
    pub(super) fn nee_lights<'s>(&self, scene: &'s CompiledScene) -> &'s LightSet {
        match self.technique {
            LightingTechnique::Mis => &scene.mis_lights,
            _ => &scene.lights,
        }
    }

    /// Whether an emitter seen along ray `r` is inside the path-length budget.
    pub(super) fn emission_counts(&self, scene: &CompiledScene, rays: &Rays, r: usize) -> bool {
        // The ray is segment depth+1 of its path.
        (rays.depth[r] as u32 + 1) <= scene.settings.max_depth
    }

    /// MIS weight of an emitter hit by ray `r` (Bxdf-sampled) against light sampling.
    pub(super) fn emitter_mis(
        &self,
        rays: &Rays,
        r: usize,
        light_pdf: impl FnOnce() -> f32,
    ) -> f32 {
        if rays.depth[r] == 0 || rays.lobe[r].is_specular() || rays.pdf[r] <= 0.0 {
            return 1.0;
        }
        match self.technique {
            LightingTechnique::BxdfOnly => 1.0,
            LightingTechnique::NeeOnly => 0.0,
            LightingTechnique::Mis => power_heuristic(rays.pdf[r], light_pdf()),
        }
    }

    /// Adds the emission of the surface at point `i` (hit by incoming ray `r`), if any, times
    /// `transmission`; returns 1 if the value added is not finite (NaN provenance), else 0.
    #[allow(clippy::too_many_arguments, reason = "the columns it reads, named")]
    pub(super) fn surface_emission(
        &self,
        scene: &CompiledScene,
        pts: &ShadingPoints,
        incoming: &Rays,
        paths: &mut Paths,
        r: usize,
        i: usize,
        transmission: Rgb,
    ) -> usize {
        let shape = pts.shape[i];
        if shape == u32::MAX || !pts.front_face[i] {
            return 0;
        }
        let Some(le) = scene.shapes[shape as usize].emission else {
            return 0;
        };
        self.add_emission(scene, pts, incoming, paths, r, i, le, transmission)
    }

    /// Adds the emission `le` of the front face of emissive shape at point `i` (hit by
    /// incoming ray `r`) to the ray's path, if inside the depth budget, MIS-weighted. Kept
    /// out of line: the shade loop tests the (rare) emissive front faces itself. Returns 1 if
    /// the value added is not finite (NaN provenance), else 0.
    #[allow(clippy::too_many_arguments, reason = "the columns it reads, named")]
    #[inline(never)]
    pub(super) fn add_emission(
        &self,
        scene: &CompiledScene,
        pts: &ShadingPoints,
        incoming: &Rays,
        paths: &mut Paths,
        r: usize,
        i: usize,
        le: Rgb,
        transmission: Rgb,
    ) -> usize {
        if !self.emission_counts(scene, incoming, r) {
            return 0;
        }
        let shape = pts.shape[i];
        let p = pts.p[i];
        let ng = pts.ng[i];
        let prev = incoming.prev_p[r];
        let mut w = self.emitter_mis(incoming, r, || {
            light_pdf_at(scene, shape, prev, p, ng, incoming, r)
        });
        // A camera ray's first hit (no lobe yet: not a ray that passed a null pane at depth
        // 0): its share of the directly visible emission (`visible_emitters`).
        if incoming.depth[r] == 0 && incoming.lobe[r] == risotto_components::LobeSampled::NONE {
            w *= super::visible_emitters::share(self.visible_emitters);
        }
        let path = incoming.path[r] as usize;
        let c = incoming.throughput[r] * transmission * le * w;
        paths.radiance[path] += c;
        // Non-finite because of this emitter only (a non-finite throughput or transmission
        // was counted where it was produced).
        (!c.is_finite() & incoming.throughput[r].is_finite() & transmission.is_finite()) as usize
    }
}

/// Light-sampling pdf (solid angle at `from`, including selection) of the point `p` on the
/// emissive shape `shape` hit by ray `r`.
fn light_pdf_at(
    scene: &CompiledScene,
    shape: u32,
    from: Vec3,
    p: Vec3,
    ng: Vec3,
    rays: &Rays,
    r: usize,
) -> f32 {
    let prim = hit_prim(scene, rays, r);
    if prim == NO_HIT || scene.shape_of_prim(prim) != shape {
        return 0.0;
    }
    scene.mis_lights.area_pdf(prim, from, p, ng)
}

/// The primitive ray `r` of `rays` hits (`NO_HIT` for none). The hit primitive is not stored
/// on shading points; it is found by re-intersecting the ray (cheap and rare: only for
/// emitter hits after a non-specular bounce).
pub(crate) fn hit_prim(scene: &CompiledScene, rays: &Rays, r: usize) -> u32 {
    let mut t = [0.0f32];
    let mut prim = [NO_HIT];
    let (mut b1, mut b2) = ([0.0f32], [0.0f32]);
    risotto_systems::intersect::intersect_closest(
        &scene.geometry,
        &[rays.origin[r]],
        &[rays.direction[r]],
        &[rays.tmin[r]],
        &[rays.tmax[r]],
        &mut t,
        &mut prim,
        &mut b1,
        &mut b2,
    );
    prim[0]
}
