//! What nearest-hit queries answer: shading points grouped by material and shading mode,
//! plus the rays that escaped (and, from volume integrators, the rays they walked and what
//! an emissive medium emitted along the rays). Both the renderer's [`IntegratorContext`](crate::plugin::IntegratorContext)
//! and volume integrators write it; the global integrator shades it.

use glam::Vec3;
use risotto_components::{Rays, Rgb, ShadingPointRow, ShadingPoints};
use std::ops::Range;

/// Why a closure is being built (RIS `RixSCShadingMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadingMode {
    /// Shading a surface hit.
    Scatter,
    /// Shading a point inside a volume (`k_RixSCVolumeScatterQuery`): the factory returns a
    /// phase function.
    VolumeScatter,
    /// Building an interior for a ray that travels through the volume.
    Interior,
}

/// Shading points grouped by material, plus rays that escaped to the environment.
#[derive(Default, Debug)]
pub struct ShadeGroups {
    /// All points of all groups; each group is a contiguous range.
    pub points: ShadingPoints,
    /// The groups.
    pub groups: Vec<ShadeGroup>,
    /// Rays (ids in the table passed to `nearest_hits`) that left the scene.
    pub misses: Vec<u32>,
    /// Transmission applied to each escaped ray (parallel to `misses`).
    pub miss_transmission: Vec<Rgb>,
    /// Rays that a volume integrator walked inside its volume before they reached the point
    /// (or miss) it returns for them: the global integrator takes each one's last segment
    /// as the ray that arrived there.
    pub walked: WalkedRays,
    /// Radiance emitted by the volume along the rays' travel before the points (or misses)
    /// returned for them: what an emissive medium sends back towards each ray's origin.
    pub emitted: EmittedRadiance,
}

/// Radiance a volume integrator's medium emitted along the rays it answered, before the
/// point (or miss, or absorption) it returns for each (the contract of emissive media:
/// [`VolumeIntegrator::nearest_hits`](crate::plugin::VolumeIntegrator::nearest_hits)).
///
/// Row `k` says that ray `ray[k]` of the answered table receives `radiance[k]` at its
/// origin, **before** its own throughput: the global integrator adds
/// `throughput[ray[k]] * radiance[k]` to the ray's path. The integrator has already
/// applied everything that happened inside the volume -- the transmittance to the emitting
/// points, the weights of its own estimators (a random walk's throughput at each of its
/// steps, a tracking estimator's null-collision weights) -- and any MIS weight against a
/// light-sampling technique of its own (the built-in media have none: their emission is
/// counted along path rays only, with weight 1). A ray may have several rows (their sum
/// counts) or none; rows for rays that the integrator absorbs still count (the light was
/// emitted before the ray ended). The path tracer counts them only for rays whose segment
/// is inside the path-length budget (every ray it traces is).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmittedRadiance {
    /// Ray id in the answered table.
    pub ray: Vec<u32>,
    /// Radiance arriving at the ray's origin, per channel (finite, >= 0).
    pub radiance: Vec<Rgb>,
}

impl EmittedRadiance {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.ray.len()
    }
    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.ray.is_empty()
    }
    /// Removes every row.
    pub fn clear(&mut self) {
        self.ray.clear();
        self.radiance.clear();
    }
    /// Appends `radiance` for ray `ray` (nothing when it is black).
    pub fn push(&mut self, ray: u32, radiance: Rgb) {
        if !radiance.is_black() {
            self.ray.push(ray);
            self.radiance.push(radiance);
        }
    }
}

/// The rays of a [`ShadeGroups`] that a volume integrator scattered inside its volume (a
/// random walk run within the integrator, the built-ins' `random_walk`) before they arrived where
/// their point lies. Row `k` says that ray `ray[k]` of the answered table arrived along the
/// segment `origin[k] + t direction[k]`, `t` in `[tmin[k], tmax[k]]`, after `vertices[k]`
/// scattering events in the volume. The global integrator replaces the ray's geometry by
/// that segment, counts the events as bounces and, since the walk sampled no lights at its
/// events, gives emitters found by the last segment their full weight (no MIS).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WalkedRays {
    /// Ray id in the answered table.
    pub ray: Vec<u32>,
    /// Start of the last segment: the last scattering event.
    pub origin: Vec<Vec3>,
    /// Unit direction of the last segment.
    pub direction: Vec<Vec3>,
    /// Smallest hit distance of the last segment.
    pub tmin: Vec<f32>,
    /// Largest hit distance of the last segment.
    pub tmax: Vec<f32>,
    /// Scattering events of the walk (at least 1).
    pub vertices: Vec<u32>,
}

impl WalkedRays {
    /// Number of walked rays.
    pub fn len(&self) -> usize {
        self.ray.len()
    }
    /// True when no ray was walked.
    pub fn is_empty(&self) -> bool {
        self.ray.is_empty()
    }
    /// Removes every row.
    pub fn clear(&mut self) {
        self.ray.clear();
        self.origin.clear();
        self.direction.clear();
        self.tmin.clear();
        self.tmax.clear();
        self.vertices.clear();
    }
    /// Writes each walked ray's last segment into its row of `rays` (the table answered):
    /// origin, direction, `tmin`, `tmax`, the last vertex `prev_p`, `depth` grown by the
    /// events (saturating), the lobe of a phase-function sample, and `pdf = 0` (the walk did
    /// no light sampling at its events, so an emitter hit by the last segment is not
    /// MIS-weighted against it).
    pub fn apply(&self, rays: &mut Rays) {
        let scatter = risotto_components::LobeSampled(
            risotto_components::LobeSampled::SCATTER.0 | risotto_components::LobeSampled::DIFFUSE.0,
        );
        for k in 0..self.len() {
            let r = self.ray[k] as usize;
            rays.origin[r] = self.origin[k];
            rays.direction[r] = self.direction[k];
            rays.tmin[r] = self.tmin[k];
            rays.tmax[r] = self.tmax[k];
            rays.prev_p[r] = self.origin[k];
            let events = self.vertices[k].min(u16::MAX as u32) as u16;
            rays.depth[r] = rays.depth[r].saturating_add(events);
            rays.lobe[r] = scatter;
            rays.pdf[r] = 0.0;
        }
    }
}

/// One group of a [`ShadeGroups`].
#[derive(Clone, Debug, PartialEq)]
pub struct ShadeGroup {
    /// Material (factory) index of the group's points.
    pub material: u32,
    /// Surface hits ([`ShadingMode::Scatter`]) or points inside a volume
    /// ([`ShadingMode::VolumeScatter`]).
    pub mode: ShadingMode,
    /// Rows of [`ShadeGroups::points`].
    pub range: Range<usize>,
}

impl ShadeGroups {
    /// Removes everything, keeping allocations.
    pub fn clear(&mut self) {
        self.points.clear();
        self.groups.clear();
        self.misses.clear();
        self.miss_transmission.clear();
        self.walked.clear();
        self.emitted.clear();
    }
    /// Appends a group made of `rows` (RIS `EndVolumeSampling` with a membership mask: pass the
    /// retained points only). Empty groups are not added.
    pub fn push_group(
        &mut self,
        material: u32,
        mode: ShadingMode,
        rows: impl IntoIterator<Item = ShadingPointRow>,
    ) {
        let start = self.points.len();
        for r in rows {
            self.points.push(r);
        }
        self.close_group(material, mode, start);
    }
    /// Makes the points appended since row `start` a group (nothing when there are none).
    pub fn close_group(&mut self, material: u32, mode: ShadingMode, start: usize) {
        let end = self.points.len();
        if end > start {
            self.groups.push(ShadeGroup {
                material,
                mode,
                range: start..end,
            });
        }
    }
    /// Multiplies the transmission of every point by `transmittance(VLen)` and of every
    /// escaped ray by `transmittance(tmax)` of its ray in `rays` (the table this was answered
    /// for): what a homogeneous, non-scattering interior does to the hits `nearest_hits`
    /// returns.
    pub fn attenuate_segments(&mut self, rays: &Rays, transmittance: impl Fn(f32) -> Rgb) {
        for (tr, &vlen) in self.points.transmission.iter_mut().zip(&self.points.vlen) {
            *tr *= transmittance(vlen);
        }
        for (tr, &ray) in self.miss_transmission.iter_mut().zip(&self.misses) {
            *tr *= transmittance(rays.tmax[ray as usize]);
        }
    }
    /// Records an escaped ray.
    pub fn push_miss(&mut self, ray_id: u32, transmission: Rgb) {
        self.misses.push(ray_id);
        self.miss_transmission.push(transmission);
    }
    /// Transmission column of group `g`, for a volume integrator to write.
    pub fn transmission_mut(&mut self, g: usize) -> &mut [Rgb] {
        let r = self.groups[g].range.clone();
        &mut self.points.transmission[r]
    }
    /// Segment lengths `VLen` of group `g`.
    pub fn vlen(&self, g: usize) -> &[f32] {
        &self.points.vlen[self.groups[g].range.clone()]
    }
    /// Ray ids of group `g`.
    pub fn ray_id(&self, g: usize) -> &[u32] {
        &self.points.ray_id[self.groups[g].range.clone()]
    }
    /// Total number of points.
    pub fn num_points(&self) -> usize {
        self.points.len()
    }
    /// [`append_offset`](Self::append_offset), moving `src`'s tables instead of copying
    /// them when that gives the same result: this queue is empty, the offset is 0 and
    /// `src`'s groups tile its points in order (no point outside a group, which
    /// `append_offset` would drop). `src` is left with this queue's old (empty) tables, or
    /// as it was; its `walked` and `emitted` rows stay with it either way.
    pub fn take_or_append(&mut self, src: &mut ShadeGroups, ray_offset: u32) {
        let empty = self.points.is_empty() && self.groups.is_empty() && self.misses.is_empty();
        let mut next = 0;
        let tiles = src.groups.iter().all(|g| {
            let follows = g.range.start == next;
            next = g.range.end;
            follows
        }) && next == src.points.len();
        if empty && ray_offset == 0 && tiles {
            std::mem::swap(&mut self.points, &mut src.points);
            std::mem::swap(&mut self.groups, &mut src.groups);
            std::mem::swap(&mut self.misses, &mut src.misses);
            std::mem::swap(&mut self.miss_transmission, &mut src.miss_transmission);
        } else {
            self.append_offset(src, ray_offset);
        }
    }

    /// Appends `src`'s groups and misses, adding `ray_offset` to their ray ids (`src`
    /// answered a table whose rows were appended to this one's rays at that offset). Its
    /// [`walked`](Self::walked) rows are not copied: [`WalkedRays::apply`] them to the
    /// answered table before appending it. Nor are its [`emitted`](Self::emitted) rows:
    /// they belong to the answered table's rays, whose throughputs weigh them.
    pub fn append_offset(&mut self, src: &ShadeGroups, ray_offset: u32) {
        for g in &src.groups {
            let start = self.points.len();
            self.points.extend_from_range(&src.points, g.range.clone());
            for id in &mut self.points.ray_id[start..] {
                *id += ray_offset;
            }
            self.groups.push(ShadeGroup {
                material: g.material,
                mode: g.mode,
                range: start..self.points.len(),
            });
        }
        for (k, &r) in src.misses.iter().enumerate() {
            self.push_miss(r + ray_offset, src.miss_transmission[k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Groups of `sizes` points (material = group index), point `k` at `x = k`, ray `k`,
    /// and one miss.
    fn answers(sizes: &[usize]) -> ShadeGroups {
        let mut g = ShadeGroups::default();
        let mut k = 0;
        for (m, &n) in sizes.iter().enumerate() {
            let rows = (k..k + n).map(|k| {
                ShadingPointRow::in_volume(Vec3::new(k as f32, 0.0, 0.0), Vec3::Z, k as u32, 7)
            });
            g.push_group(m as u32, ShadingMode::Scatter, rows);
            k += n;
        }
        g.push_miss(k as u32, Rgb::splat(0.5));
        g
    }

    /// What a queue holds, as plain values: (material, range) per group, the points' ray
    /// ids and `x`, the misses.
    type Contents = (Vec<(u32, Range<usize>)>, Vec<u32>, Vec<f32>, Vec<u32>);

    fn contents(g: &ShadeGroups) -> Contents {
        let groups = g
            .groups
            .iter()
            .map(|x| (x.material, x.range.clone()))
            .collect();
        let xs = g.points.p.iter().map(|p| p.x).collect();
        (groups, g.points.ray_id.clone(), xs, g.misses.clone())
    }

    #[test]
    fn take_or_append_equals_append_offset() {
        // An empty queue and tiling groups: moved. A non-empty queue, an offset, or a point
        // outside every group: copied. The queue ends the same in every case.
        let mut loose = answers(&[2, 3]);
        loose
            .points
            .push(ShadingPointRow::in_volume(Vec3::ONE, Vec3::Z, 9, 7));
        let cases: [(Option<ShadeGroups>, ShadeGroups, u32); 4] = [
            (None, answers(&[2, 3]), 0),
            (None, answers(&[4]), 5),
            (Some(answers(&[1])), answers(&[2, 2]), 0),
            (None, loose, 0),
        ];
        for (i, (start, src, offset)) in cases.into_iter().enumerate() {
            let fresh = || {
                start
                    .as_ref()
                    .map_or_else(ShadeGroups::default, |s| answers(&[s.points.len()]))
            };
            let (mut copied, mut moved) = (fresh(), fresh());
            copied.append_offset(&src, offset);
            let mut src = src;
            let n = src.points.len();
            moved.take_or_append(&mut src, offset);
            assert_eq!(contents(&moved), contents(&copied), "case {i}");
            // Only the first case moves (and leaves `src` with the empty tables).
            assert_eq!(src.points.len(), if i == 0 { 0 } else { n }, "case {i}");
        }
    }
}
