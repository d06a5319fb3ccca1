//! Binding a volume's integrator to a bundle of rays or shadow segments (RIS
//! `BeginInterior` through `BeginOppositeVol` / `BeginIncidentVol`): the shading context at the
//! segments' starts, and the integrators of the volumes overlapping it.

use crate::plugin::*;
use crate::scene::CompiledScene;
use bumpalo::Bump;
use risotto_components::{ShadingPoints, VolumeEntry, VolumeStack};
use smallvec::SmallVec;

/// The interior of `stack`'s innermost volume `entry`, bound to a context over all of
/// `points` (one per ray or segment, at its start) that sees the stack's other interiors as
/// overlapping volumes; `None` when its factory builds no interior. Contexts carry the
/// factory, the parameter cache and the volume's object space and bounds; everything goes to the arena, which
/// holds only plain data here (the points stay with the caller).
pub(crate) fn bind_interior<'a>(
    scene: &'a CompiledScene,
    stack: &VolumeStack,
    entry: VolumeEntry,
    points: &'a ShadingPoints,
    cache: &'a ParamCache<'a>,
    arena: &'a Bump,
) -> Option<(&'a dyn BxdfFactory, &'a mut (dyn VolumeIntegrator + 'a))> {
    let m = points.len();
    let computes_interior = |e: &VolumeEntry| {
        scene.material_info[e.material as usize]
            .hints
            .contains(InstanceHints::COMPUTES_INTERIOR)
    };
    let context = |e: VolumeEntry, overlapping: &'a [OverlappingVolume<'a>]| {
        let space = scene.shape_space[e.shape as usize];
        let factory = scene.materials[e.material as usize].factory.as_ref();
        ShadingContext::new(points, 0..m, ShadingMode::Interior, e.material, overlapping)
            .with_factory(factory)
            .with_cache(cache)
            .with_volume_space(space)
    };
    // The other volumes' integrators are bound to contexts without overlaps.
    let others: SmallVec<[VolumeEntry; 4]> =
        stack.overlapping().filter(computes_interior).collect();
    let overlapping: &[OverlappingVolume] =
        arena.alloc_slice_fill_iter(others.into_iter().map(|e| {
            let factory = scene.materials[e.material as usize].factory.as_ref();
            let ctx = arena.alloc(context(e, &[]));
            OverlappingVolume {
                entry: e,
                factory,
                integrator: factory
                    .begin_interior(ctx, ShadingMode::Interior, arena)
                    .map(|v| &*v),
            }
        }));
    let ctx = arena.alloc(context(entry, overlapping));
    let factory = scene.materials[entry.material as usize].factory.as_ref();
    let integrator = factory.begin_interior(ctx, ShadingMode::Interior, arena)?;
    Some((factory, integrator))
}
