//! The heterogeneous medium as a light ([`risotto_engine::plugin::volume_light`]): its majorant cells with
//! their emission bounds and tracking bounds.

use super::{emission_floor, HeterogeneousEmission, HeterogeneousMedium};
use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::grid::MajorantGrid;
use risotto_systems::volume_lights::{EmissionField, EmitterSupport, VolumeEmitter};

impl HeterogeneousMedium {
    /// The medium placed in `bounds` as a volume emitter over its majorant-grid cells:
    /// `j_max(cell)` from the emission's bound there (the density's times the colour, the
    /// emission grid's times its scale, or the emission pattern's interval bound), and the
    /// free flights' tracking bound (the extinction bound, raised in emitting cells to
    /// `minorant + EMISSION_COLLISIONS_PER_CELL / width` as the integrator's emissive
    /// segments raise it). Grid and pattern densities and emissions alike: the bounds are
    /// the majorant grids the integrator tracks against over the same box. `None` when the
    /// medium does not emit or the box has no volume.
    pub fn volume_emitter(
        &self,
        (lo, hi): (Vec3, Vec3),
        support: EmitterSupport,
    ) -> Option<VolumeEmitter> {
        let emission = self.emission.as_ref()?;
        // The density's majorant grid over this box (a pattern's is made per box).
        let density = match &self.density_pattern {
            Some(p) => p.majorants(lo, hi),
            None => self.majorants.clone(),
        };
        let (field, bound) = match emission {
            HeterogeneousEmission::FollowsDensity(c) => {
                let field = match &self.density_pattern {
                    Some(p) => EmissionField::Pattern {
                        graph: p.graph.clone(),
                        scale: *c,
                    },
                    None => EmissionField::Grid {
                        grid: self.density.clone(),
                        scale: *c,
                    },
                };
                // A per-channel density's majorants are extinction bounds: the emission
                // follows the largest channel's density (`self.density`), bounded afresh.
                let bound = match &self.density_channels {
                    Some(_) => std::sync::Arc::new(MajorantGrid::new(&self.density, density.res())),
                    None => density.clone(),
                };
                (field, bound)
            }
            HeterogeneousEmission::Grid {
                grid,
                scale,
                majorants,
            } => (
                EmissionField::Grid {
                    grid: grid.clone(),
                    scale: *scale,
                },
                majorants.clone(),
            ),
            HeterogeneousEmission::Pattern(p) => (
                EmissionField::Pattern {
                    graph: p.graph.clone(),
                    scale: Rgb::WHITE,
                },
                p.majorants(lo, hi),
            ),
        };
        let scale = match &field {
            EmissionField::Grid { scale, .. } | EmissionField::Pattern { scale, .. } => *scale,
        };
        let res = density.res();
        let floor = emission_floor((lo, hi), res);
        let smax = self.majorant_scale();
        let n = res.iter().product::<usize>();
        let (mut j_max, mut majorant) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for cz in 0..res[2] {
            for cy in 0..res[1] {
                for cx in 0..res[0] {
                    let b = bound.max_at(cx, cy, cz);
                    j_max.push(scale * b);
                    let mut m = density.max_at(cx, cy, cz) * smax;
                    if b > 0.0 {
                        m = m.max(density.min_at(cx, cy, cz) * smax + floor);
                    }
                    majorant.push(m);
                }
            }
        }
        VolumeEmitter::new((lo, hi), res, &j_max, majorant, field, support).ok()
    }
}
