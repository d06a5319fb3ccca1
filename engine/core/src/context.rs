//! The integrator context (RIS `RixIntegratorContext`): the renderer's ray-tracing services
//! for global and volume integrators.

use crate::plugin::{IntegratorContext, PluginTechniques};
use crate::scene::CompiledScene;
use crate::shade_groups::{ShadeGroup, ShadeGroups, ShadingMode};
use crate::stats::{System, SystemStats, VolumeEvent};
use glam::Vec3;
use risotto_components::{Hits, Rays, Rgb, ShadingPoints, VolumeStack, NO_HIT};
use risotto_systems::geometry::{SceneGeometry, SurfaceColumns, SurfaceSample};
use risotto_systems::intersect::intersect_closest;
use risotto_systems::lights::LightSet;
use risotto_systems::mesh_attributes::{arbitrary_tangent, sphere_tangent};
use risotto_systems::terminator::terminator_lifts;

/// Reusable buffers of [`IntegratorContext::nearest_hits`], kept by a worker across calls so
/// the per-bounce path does not allocate.
#[derive(Debug, Default)]
pub struct HitScratch {
    /// The hits of the last [`IntegratorContext::trace`] in the first `traced` rows. The
    /// columns only grow: a batch's first bounce traces more rays than the last bounce of
    /// the batch before, and rows kept from earlier calls spare writing defaults into rows
    /// `intersect_closest` overwrites (it writes every row it is given).
    hits: Hits,
    /// Rays of the last `trace` (rows of `hits` that are its answers).
    traced: usize,
    /// Rays that hit a surface of material `m`, in ray order.
    buckets: Vec<Vec<u32>>,
    /// Rays that hit nothing.
    escaped: Vec<u32>,
    /// The buckets concatenated: the rays of the shading points, in point order.
    sorted: Vec<u32>,
    /// At least as many zero vectors and white colours as the largest batch so far: the
    /// 12-byte columns are sized by copying from these (`Vec::resize` writes 12-byte values
    /// one at a time; a copy is a memcpy).
    zeros: Vec<Vec3>,
    whites: Vec<Rgb>,
}

/// Ray-tracing services bound to one compiled scene and one worker: everything a global or
/// volume integrator gets from the renderer (the seed's `RixIntegratorContext`). Built-in
/// plug-ins see exactly what a user's plug-in sees: its methods, nothing behind them.
pub struct RenderContext<'s> {
    /// The scene (the engine's own stages read it; plug-ins get its parts through methods).
    pub(crate) scene: &'s CompiledScene,
    /// The worker's statistics (plug-ins count through the `count_*` methods).
    pub(crate) stats: &'s mut SystemStats,
    scratch: HitScratch,
    techniques: PluginTechniques,
    /// Whether the caller of a volume's `transmission` uses its `emission` output.
    emission_wanted: bool,
    /// Majorant violations a volume's `transmission` reported (it sees the context shared).
    violations: std::cell::Cell<u64>,
    /// Dense majorant segments a volume integrated exactly, and their lookups.
    dense_segments: std::cell::Cell<(u64, u64)>,
    /// Tentative collisions of a volume's `transmission`.
    shadow_collisions: std::cell::Cell<u64>,
}

impl<'s> RenderContext<'s> {
    /// A context for `scene`, recording into `stats`.
    pub fn new(scene: &'s CompiledScene, stats: &'s mut SystemStats) -> Self {
        Self::with_scratch(scene, stats, HitScratch::default())
    }

    /// A context reusing the buffers of an earlier one ([`Self::into_scratch`]).
    pub fn with_scratch(
        scene: &'s CompiledScene,
        stats: &'s mut SystemStats,
        scratch: HitScratch,
    ) -> Self {
        RenderContext {
            scene,
            stats,
            scratch,
            techniques: PluginTechniques::default(),
            emission_wanted: true,
            violations: std::cell::Cell::new(0),
            dense_segments: std::cell::Cell::new((0, 0)),
            shadow_collisions: std::cell::Cell::new(0),
        }
    }

    /// The violations [`Self::count_majorant_violations`] recorded so far, reset to 0.
    pub fn take_majorant_violations(&self) -> u64 {
        self.violations.replace(0)
    }

    /// The dense segments and their lookups [`Self::count_dense_segments`] recorded so far,
    /// reset to 0.
    pub fn take_dense_segments(&self) -> (u64, u64) {
        self.dense_segments.replace((0, 0))
    }

    /// The collisions [`Self::count_shadow_collisions`] recorded so far, reset to 0.
    pub fn take_shadow_collisions(&self) -> u64 {
        self.shadow_collisions.replace(0)
    }

    /// The context with the render's choices for plug-in techniques, which plug-ins read
    /// through [`Self::technique`].
    pub fn with_techniques(mut self, techniques: PluginTechniques) -> Self {
        self.techniques = techniques;
        self
    }

    /// This context, telling volumes' `transmission` whether its `emission` output is used
    /// (default `true`).
    pub fn with_emission_wanted(mut self, wanted: bool) -> Self {
        self.emission_wanted = wanted;
        self
    }

    /// Gives the buffers back for the next context.
    pub fn into_scratch(mut self) -> HitScratch {
        std::mem::take(&mut self.scratch)
    }
}

impl IntegratorContext for RenderContext<'_> {
    fn count_majorant_violations(&self, n: u64) {
        self.violations.set(self.violations.get() + n);
    }

    fn count_dense_segments(&self, segments: u64, lookups: u64) {
        let (s, l) = self.dense_segments.get();
        self.dense_segments.set((s + segments, l + lookups));
    }

    fn count_shadow_collisions(&self, n: u64) {
        self.shadow_collisions.set(self.shadow_collisions.get() + n);
    }

    fn count_volume_events(&mut self, event: VolumeEvent, n: usize) {
        self.stats.volume_event(event, n);
    }

    fn count_volume_pattern_evals(&mut self, n: u64) {
        self.stats.pattern_evals += n;
        self.stats.volume_pattern_evals += n;
    }

    fn scene_bounds(&self) -> (Vec3, Vec3) {
        self.scene.geometry.bounds()
    }

    fn max_depth(&self) -> u32 {
        self.scene.settings.max_depth
    }

    fn lights(&self) -> &LightSet {
        &self.scene.lights
    }

    fn closest_hits(
        &mut self,
        origin: &[Vec3],
        direction: &[Vec3],
        tmin: &[f32],
        tmax: &[f32],
        out: &mut Hits,
    ) {
        let n = origin.len();
        out.t.resize(n, 0.0);
        out.prim.resize(n, NO_HIT);
        out.b1.resize(n, 0.0);
        out.b2.resize(n, 0.0);
        if n == 0 {
            return;
        }
        let geometry = &self.scene.geometry;
        self.stats.time(System::Intersect, n, || {
            intersect_closest(
                geometry,
                origin,
                direction,
                tmin,
                tmax,
                &mut out.t,
                &mut out.prim,
                &mut out.b1,
                &mut out.b2,
            )
        });
    }

    fn surface_at(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> SurfaceSample {
        self.scene
            .geometry
            .surface_at(prim, origin, direction, t, b1, b2)
    }

    fn shape_of(&self, prim: u32) -> u32 {
        self.scene.shape_of_prim(prim)
    }

    fn clearance(&self, p: Vec3, cap: f32) -> f32 {
        risotto_systems::clearance::clearance(&self.scene.geometry, p, cap)
    }

    fn emission_wanted(&self) -> bool {
        self.emission_wanted
    }

    fn technique(&self, name: &str) -> Option<&'static str> {
        self.techniques.get(name)
    }

    fn techniques(&self) -> PluginTechniques {
        self.techniques
    }

    fn ior_outside(&self, stack: &VolumeStack, shape: u32) -> f32 {
        ior_outside(self.scene, stack, shape)
    }

    fn nearest_hits(&mut self, rays: &Rays, out: &mut ShadeGroups) {
        self.trace(rays);
        self.shade_traced(rays, None, out);
    }

    fn trace(&mut self, rays: &Rays) -> &[f32] {
        let n = rays.len();
        let geometry = &self.scene.geometry;
        let hits = &mut self.scratch.hits;
        if hits.len() < n {
            hits.t.resize(n, 0.0);
            hits.prim.resize(n, NO_HIT);
            hits.b1.resize(n, 0.0);
            hits.b2.resize(n, 0.0);
        }
        self.scratch.traced = n;
        if n > 0 {
            self.stats.time(System::Intersect, n, || {
                intersect_closest(
                    geometry,
                    &rays.origin,
                    &rays.direction,
                    &rays.tmin,
                    &rays.tmax,
                    &mut hits.t[..n],
                    &mut hits.prim[..n],
                    &mut hits.b1[..n],
                    &mut hits.b2[..n],
                )
            });
        }
        let hits = &mut self.scratch.hits;
        for (t, &prim) in hits.t[..n].iter_mut().zip(&hits.prim[..n]) {
            if prim == NO_HIT {
                *t = f32::INFINITY;
            }
        }
        &hits.t[..n]
    }

    fn traced_surface(&self, rays: &Rays, i: usize) -> Option<SurfaceSample> {
        assert!(
            i < self.scratch.traced,
            "traced_surface of a ray not traced"
        );
        let h = &self.scratch.hits;
        if h.prim[i] == NO_HIT {
            return None;
        }
        let s = self.scene.geometry.surface_at(
            h.prim[i],
            rays.origin[i],
            rays.direction[i],
            h.t[i],
            h.b1[i],
            h.b2[i],
        );
        Some(s)
    }

    fn shade_traced(&mut self, rays: &Rays, keep: Option<&[bool]>, out: &mut ShadeGroups) {
        let n = rays.len();
        assert_eq!(
            self.scratch.traced, n,
            "shade_traced after trace of these rays"
        );
        if let Some(keep) = keep {
            assert_eq!(keep.len(), n, "one flag per ray");
        }
        if n == 0 {
            return;
        }
        let scene = self.scene;
        let geometry = &scene.geometry;
        let s = &mut self.scratch;
        let hits = &mut s.hits;
        // Hit rays are grouped by material (a bucket per material, concatenated in material
        // order: groups come out contiguous, so each factory runs once per call), escaped
        // rays go to their own list. Every array is taken as a slice before its loop: stores
        // into the scratch could otherwise alias the `Vec` headers, and the compiler would
        // reload pointers and lengths on every iteration.
        s.buckets.resize_with(scene.materials.len(), Vec::new);
        group_by_material(scene, &hits.prim[..n], keep, &mut s.buckets, &mut s.escaped);
        s.sorted.clear();
        for m in material_order(scene) {
            s.sorted.extend_from_slice(&s.buckets[m]);
        }
        let count = s.sorted.len();
        if s.zeros.len() < n {
            s.zeros.resize(n, Vec3::ZERO);
            s.whites.resize(n, Rgb::WHITE);
        }
        out.misses.extend_from_slice(&s.escaped);
        out.miss_transmission
            .extend_from_slice(&s.whites[..s.escaped.len()]);
        // The shading points of all hits, in sorted order. The columns of `write_surfaces`
        // and those only some points overwrite are sized first (12-byte ones by copying from
        // prepared constants: `Vec::resize` writes 12-byte values one at a time) and then
        // written by index in passes over the sorted rays; `write_ray_columns` appends the
        // columns it computes for every point; the columns that are constant per group or
        // copies of another column are filled in bulk afterwards.
        let base = out.points.len();
        let pts = &mut out.points;
        let end = base + count;
        pts.p.extend_from_slice(&s.zeros[..count]);
        pts.ng.extend_from_slice(&s.zeros[..count]);
        pts.p_offset.resize(end, 0.0);
        pts.terminator_lift.extend_from_slice(&s.zeros[..count]);
        pts.u.resize(end, 0.0);
        pts.v.resize(end, 0.0);
        // Vacuum unless the ray travels inside volumes (`write_ray_columns`).
        pts.ior_outside.resize(end, 1.0);
        let sorted = &s.sorted[..count];
        write_surfaces(
            geometry,
            scene.features.surface_uv,
            sorted,
            hits,
            rays,
            pts,
            base,
        );
        write_ray_columns(scene, sorted, hits, rays, pts, base);
        pts.nn.extend_from_slice(&pts.ng[base..end]);
        write_tangents(geometry, sorted, hits, pts, base);
        if geometry.has_attributes() {
            write_mesh_attributes(geometry, sorted, hits, pts, base);
        }
        if scene.features.terminator_offset {
            // Pass 5: where rays to the viewer's side leave smooth meshes from.
            self.stats.terminator_lifts +=
                terminator_lifts(geometry, hits, sorted, pts, base..end) as u64;
        }
        pts.w.resize(end, 0.0);
        pts.transmission.extend_from_slice(&s.whites[..count]);
        pts.ray_id.extend_from_slice(&s.sorted[..count]);
        let mut start = base;
        for m in material_order(scene) {
            let b = &s.buckets[m];
            if !b.is_empty() {
                let end = start + b.len();
                pts.material.resize(end, m as u32);
                out.groups.push(ShadeGroup {
                    material: m as u32,
                    mode: ShadingMode::Scatter,
                    range: start..end,
                });
                start = end;
            }
        }
        debug_assert!(pts.is_consistent(), "a shading-point column was not filled");
    }
}

/// The majorant violations, dense segments and shadow collisions counted through the shared context and not
/// taken yet go to the worker's stats when the context ends.
impl Drop for RenderContext<'_> {
    fn drop(&mut self) {
        self.stats.majorant_violations += self.violations.replace(0);
        let (segments, lookups) = self.dense_segments.replace((0, 0));
        self.stats.dense_segments += segments;
        self.stats.dense_lookups += lookups;
        self.stats.shadow_collisions += self.shadow_collisions.replace(0);
    }
}

// The passes that write the shading-point columns `base..base + sorted.len()` from the hits
// of the rays `sorted` (rows of `hits` and `rays`). Each is its own function, and each loop
// leaves the rare cases (spheres, rays inside volumes) to a second loop: a loop with few
// pointers and no call inside keeps everything in registers, where one loop inside the big
// function spilled about a dozen values per point. Every slice is cut to its exact length
// first, so the compiler drops the bounds checks on the outputs.

/// The order in which hits are grouped by material: index-matched materials last, so that
/// the points the pass-through stage removes tend to end the hit queue, where removing them
/// moves no other point (the order of groups is otherwise free).
fn material_order(scene: &CompiledScene) -> impl Iterator<Item = usize> + '_ {
    let matched = |m: &usize| {
        scene.material_info[*m]
            .hints
            .contains(crate::plugin::InstanceHints::INDEX_MATCHED)
    };
    let n = scene.material_info.len();
    (0..n)
        .filter(move |m| !matched(m))
        .chain((0..n).filter(matched))
}

/// Clears `buckets` (one per material) and `escaped`, then appends the index of every ray
/// whose hit is on a surface of material `m` to `buckets[m]` and of every miss to `escaped`.
/// Its own function for the same reason as the passes below.
#[inline(never)]
fn group_by_material(
    scene: &CompiledScene,
    prims: &[u32],
    keep: Option<&[bool]>,
    buckets: &mut [Vec<u32>],
    escaped: &mut Vec<u32>,
) {
    for b in buckets.iter_mut() {
        b.clear();
    }
    escaped.clear();
    let prim_material = &scene.prim_material[..];
    // One loop for both cases, its body inline (as a closure called from two loops it was
    // a call per hit).
    let keep = keep.map(|k| &k[..prims.len()]);
    for (i, &prim) in prims.iter().enumerate() {
        if keep.is_some_and(|k| !k[i]) {
            continue;
        }
        if prim == NO_HIT {
            escaped.push(i as u32);
        } else {
            // Primitives of instances (past the table) look theirs up.
            let m = match prim_material.get(prim as usize) {
                Some(&m) => m,
                None => scene.material_of_prim(prim),
            };
            buckets[m as usize].push(i as u32);
        }
    }
}

/// Pass 1: `p`, `ng`, `p_offset`, `u`, `v` (on spheres `u = v = 0` unless `sphere_uv`: some material
/// reads them, [`crate::plugin::InstanceHints::READS_SURFACE_UV`]).
#[inline(never)]
fn write_surfaces(
    geometry: &SceneGeometry,
    sphere_uv: bool,
    sorted: &[u32],
    hits: &Hits,
    rays: &Rays,
    pts: &mut ShadingPoints,
    base: usize,
) {
    let (n, count) = (hits.len(), sorted.len());
    let (p, ng) = (&mut pts.p[base..][..count], &mut pts.ng[base..][..count]);
    let p_offset = &mut pts.p_offset[base..][..count];
    let (u, v) = (&mut pts.u[base..][..count], &mut pts.v[base..][..count]);
    let (prims, b1, b2) = (&hits.prim[..n], &hits.b1[..n], &hits.b2[..n]);
    let triangles = geometry.triangles();
    // Triangles eight at a time; spheres and instances' primitives are left to the loop below.
    let out = SurfaceColumns {
        p: &mut *p,
        ng: &mut *ng,
        p_offset: &mut *p_offset,
        u: &mut *u,
        v: &mut *v,
    };
    if triangles.write_surfaces(sorted, prims, b1, b2, out) {
        for (k, &i) in sorted.iter().enumerate() {
            let i = i as usize;
            if triangles.surface_at(prims[i], b1[i], b2[i]).is_none() {
                let surf = geometry.surface_at(
                    prims[i],
                    rays.origin[i],
                    rays.direction[i],
                    hits.t[i],
                    b1[i],
                    b2[i],
                );
                p[k] = surf.p;
                ng[k] = surf.ng;
                p_offset[k] = surf.offset();
                let uv = if sphere_uv {
                    geometry.surface_uv(
                        prims[i],
                        rays.origin[i],
                        rays.direction[i],
                        hits.t[i],
                        b1[i],
                        b2[i],
                    )
                } else {
                    surf.uv
                };
                u[k] = uv.x;
                v[k] = uv.y;
            }
        }
    }
}

/// Pass 3 (after `nn` is a copy of `ng`): `tangent`, [`sphere_tangent`] on spheres and
/// [`arbitrary_tangent`] of the normal on triangles (those of meshes with texture
/// coordinates get theirs in [`write_mesh_attributes`]).
#[inline(never)]
fn write_tangents(
    geometry: &SceneGeometry,
    sorted: &[u32],
    hits: &Hits,
    pts: &mut ShadingPoints,
    base: usize,
) {
    let count = sorted.len();
    let ng = &pts.ng[base..][..count];
    pts.tangent.extend(ng.iter().map(|&n| arbitrary_tangent(n)));
    if geometry.num_spheres() > 0 {
        let tangent = &mut pts.tangent[base..][..count];
        let (prims, tris) = (&hits.prim[..hits.len()], geometry.num_triangles());
        let flat = geometry.num_flat_prims();
        for k in 0..count {
            let prim = prims[sorted[k] as usize] as usize;
            if prim >= tris && prim < flat {
                tangent[k] = sphere_tangent(ng[k]);
            }
        }
    }
    if geometry.num_instances() > 0 {
        // An instanced sphere's tangent is its object's, mapped; an instanced triangle's
        // stays the arbitrary one.
        let tangent = &mut pts.tangent[base..][..count];
        let (prims, flat) = (&hits.prim[..hits.len()], geometry.num_flat_prims());
        for k in 0..count {
            let prim = prims[sorted[k] as usize];
            if prim as usize >= flat {
                tangent[k] = geometry.tangent_at(prim, ng[k]);
            }
        }
    }
}

/// Pass 4, only in scenes with mesh attributes (after [`write_tangents`]): on triangles of
/// meshes with vertex normals or texture coordinates, the interpolated shading normal `nn`,
/// `u`, `v` and the tangent of [`MeshAttributes::shading`](risotto_systems::mesh_attributes::MeshAttributes::shading).
#[inline(never)]
fn write_mesh_attributes(
    geometry: &SceneGeometry,
    sorted: &[u32],
    hits: &Hits,
    pts: &mut ShadingPoints,
    base: usize,
) {
    let (n, count) = (hits.len(), sorted.len());
    let (prims, b1, b2) = (&hits.prim[..n], &hits.b1[..n], &hits.b2[..n]);
    let ng = &pts.ng[base..][..count];
    let (nn, tangent) = (
        &mut pts.nn[base..][..count],
        &mut pts.tangent[base..][..count],
    );
    let (u, v) = (&mut pts.u[base..][..count], &mut pts.v[base..][..count]);
    for k in 0..count {
        let i = sorted[k] as usize;
        let prim = prims[i];
        if let Some(s) = geometry.mesh_shading(prim, b1[i], b2[i], ng[k]) {
            nn[k] = s.nn;
            tangent[k] = s.tangent;
            if let Some(uv) = s.uv {
                u[k] = uv.x;
                v[k] = uv.y;
            }
        }
    }
}

/// Pass 2 (after [`write_surfaces`], it reads `ng`): appends `vn`, `vlen`, `front_face` and
/// `shape`, and writes `ior_outside` (sized by the caller). Every point gets a value of the
/// appended columns, so they are appended (one loop per column, each a few pointers) rather
/// than sized with defaults first and written by index.
#[inline(never)]
fn write_ray_columns(
    scene: &CompiledScene,
    sorted: &[u32],
    hits: &Hits,
    rays: &Rays,
    pts: &mut ShadingPoints,
    base: usize,
) {
    let (n, count) = (hits.len(), sorted.len());
    let (prims, t) = (&hits.prim[..n], &hits.t[..n]);
    let (direction, stacks) = (
        &rays.direction[..rays.len()],
        &rays.volume_stack[..rays.len()],
    );
    pts.vn
        .extend(sorted.iter().map(|&i| -direction[i as usize]));
    pts.vlen.extend(sorted.iter().map(|&i| t[i as usize]));
    // `d.dot(ng) < 0` with the ray's direction `d = -vn` (negation is exact).
    let (ng, vn) = (&pts.ng[base..][..count], &pts.vn[base..][..count]);
    (pts.front_face).extend(vn.iter().zip(ng).map(|(&vn, &ng)| (-vn).dot(ng) < 0.0));
    let prim_shape = &scene.prim_shape[..];
    pts.shape.extend(sorted.iter().map(|&i| {
        let prim = prims[i as usize];
        match prim_shape.get(prim as usize) {
            Some(&s) => s,
            None => scene.shape_of_prim(prim),
        }
    }));
    let (shape, ior) = (
        &pts.shape[base..][..count],
        &mut pts.ior_outside[base..][..count],
    );
    // Stacks get entries only in scenes with volumes, transmissive materials or a camera
    // inside a shape (only such shapes are tracked, `CompiledScene::tracks_interior`);
    // elsewhere the stack column is not read at all.
    let features = scene.features;
    let stacks_possible =
        features.volumes || features.transmissive || !scene.camera_stack.is_empty();
    if stacks_possible && sorted.iter().any(|&i| !stacks[i as usize].is_empty()) {
        for (k, &i) in sorted.iter().enumerate() {
            let stack = &stacks[i as usize];
            if !stack.is_empty() {
                ior[k] = ior_outside(scene, stack, shape[k]);
            }
        }
    }
}

/// IOR of the innermost volume of `stack` that is not `shape`'s own interior (1 in vacuum).
pub(crate) fn ior_outside(scene: &CompiledScene, stack: &VolumeStack, shape: u32) -> f32 {
    let mut best: Option<risotto_components::VolumeEntry> = None;
    for e in stack.entries() {
        if e.shape != shape && best.is_none_or(|b| e.priority >= b.priority) {
            best = Some(*e);
        }
    }
    best.map_or(1.0, |e| scene.material_info[e.material as usize].ior)
}
