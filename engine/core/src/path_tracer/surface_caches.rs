//! The parameter caches of the surface groups shaded last, for the interiors their rays
//! enter next. The seed: when a ray refracts into a volume, the renderer "may also call
//! BeginScatter on the factory at the same time ... and bind the same shading context to
//! both ... both plugins will share the same renderer built-in pattern cache. If they pull on
//! the same pattern subgraph, the shared subgraph will only need to be executed once." Here
//! the Bxdf's context lives in the shade stage and the interior's in the next trace stage, so
//! the shade stage keeps each group's cache (in the batch arena) with the rows of the ray
//! queue its continuing rays went to, and the trace stage binds an interior whose rays all
//! left one such group, of the interior's own material, to a cache that shares it
//! ([`ParamCache::sharing`], through each ray's `shading_ctx_index`). Only the first trace
//! round of a bounce sees them: rays past an index-matched boundary left no shaded point.

use crate::plugin::ParamCache;
use std::ops::Range;

/// One shaded group's cache.
struct SurfaceCache<'a> {
    /// Rows of the next ray queue its continuing rays were written to.
    rays: Range<usize>,
    /// The group's material.
    material: u32,
    cache: &'a ParamCache<'a>,
}

/// The caches of the groups shaded in the last shade stage whose material computes an
/// interior, in ray-queue order.
#[derive(Default)]
pub(super) struct SurfaceCaches<'a> {
    groups: Vec<SurfaceCache<'a>>,
}

impl<'a> SurfaceCaches<'a> {
    /// Forgets every group (their rays have been traced).
    pub(super) fn clear(&mut self) {
        self.groups.clear();
    }

    /// Records the cache of a group of `material` whose continuing rays went to rows `rays`
    /// of the next ray queue (after every group recorded before).
    pub(super) fn push(&mut self, rays: Range<usize>, material: u32, cache: &'a ParamCache<'a>) {
        if !rays.is_empty() {
            debug_assert!(self.groups.last().is_none_or(|g| g.rays.end <= rays.start));
            self.groups.push(SurfaceCache {
                rays,
                material,
                cache,
            });
        }
    }

    /// The cache shared by every ray row of `rows` (rows of the ray queue the shade stage
    /// wrote), when they all left one group of `material`; `None` otherwise.
    pub(super) fn common(
        &self,
        mut rows: impl Iterator<Item = usize>,
        material: u32,
    ) -> Option<&'a ParamCache<'a>> {
        let first = rows.next()?;
        let g = self.group_of(first)?;
        let group = &self.groups[g];
        (group.material == material && rows.all(|r| group.rays.contains(&r))).then_some(group.cache)
    }

    /// The group whose rows hold `row`.
    fn group_of(&self, row: usize) -> Option<usize> {
        let g = self.groups.partition_point(|g| g.rays.end <= row);
        (g < self.groups.len() && self.groups[g].rays.contains(&row)).then_some(g)
    }
}
