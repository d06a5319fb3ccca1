//! The parameter cache of a shading context (the seed's "renderer built-in pattern cache"):
//! evaluated parameter columns keyed by material and name, in the worker's arena, counted;
//! and the sharing of a surface context's columns with the interior its rays enter.

use super::shading_context::ParamValue;
use bumpalo::Bump;
use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::pattern;
use std::cell::Cell;

/// The builtins a pattern reads, one entry per point.
#[derive(Clone, Copy)]
pub(super) struct PatternInputs<'a> {
    pub(super) p: &'a [Vec3],
    pub(super) u: &'a [f32],
    pub(super) v: &'a [f32],
}

/// Counts of parameter-cache lookups of a worker (plain `Cell`s: contexts and their caches
/// are arena data without destructors).
#[derive(Debug, Default)]
pub struct PatternCounters {
    /// Lookups answered by the cache.
    pub hits: Cell<u64>,
    /// Parameter evaluations (cache misses).
    pub evals: Cell<u64>,
    /// Of `evals`, the pattern evaluations of medium coefficients: those volume integrators
    /// made point by point ([`ShadingContext::count_pattern_evals`](super::ShadingContext::count_pattern_evals)) and the columns
    /// evaluated for contexts inside a volume (a phase function's `g` pattern).
    pub volume_evals: Cell<u64>,
    /// Lookups of an interior's context answered from the cache of the surface context its
    /// rays left from ([`ParamCache::sharing`]): columns not evaluated again.
    pub shared: Cell<u64>,
}

/// Entries a [`ParamCache`] holds; a context pulling more distinct parameters re-evaluates
/// the extra ones (counted as evaluations).
const CACHE_SLOTS: usize = 8;

/// A cached column: the material, the parameter's name and its values (a cache may serve
/// contexts of several materials: a volume's and those of the volumes overlapping it).
type CachedColumn<'a> = (u32, &'a str, &'a [Rgb]);

/// The parameter cache of one shading context: evaluated columns keyed by material and
/// parameter name, allocated in the worker's arena. Plain data (it may itself live in the
/// arena).
///
/// A cache may share the columns of another (the seed: when the renderer binds the same
/// shading context to a surface's Bxdf and to the interior its rays enter, "both plugins
/// share the same pattern cache; a shared subgraph executes once"): a column its context
/// asks for that the other holds for the same material is gathered from it, row `rows[i]`
/// for point `i`, instead of being evaluated ([`ParamCache::sharing`]).
pub struct ParamCache<'a> {
    pub(super) arena: &'a Bump,
    pub(super) counters: &'a PatternCounters,
    slots: [Cell<Option<CachedColumn<'a>>>; CACHE_SLOTS],
    shares: Option<(&'a dyn HeldColumns, &'a [u32])>,
}

/// The columns a cache holds, looked up without evaluating (a trait object, so that a cache
/// can share one that lives longer).
trait HeldColumns {
    /// The column held for `material`'s parameter `name`.
    fn held(&self, material: u32, name: &str) -> Option<&[Rgb]>;
}

impl HeldColumns for ParamCache<'_> {
    fn held(&self, material: u32, name: &str) -> Option<&[Rgb]> {
        self.slots.iter().find_map(|s| match s.get() {
            Some((m, key, column)) if m == material && key == name => Some(column),
            _ => None,
        })
    }
}

impl<'a> ParamCache<'a> {
    /// An empty cache whose columns go to `arena`, counting into `counters`.
    pub fn new(arena: &'a Bump, counters: &'a PatternCounters) -> Self {
        ParamCache {
            arena,
            counters,
            slots: Default::default(),
            shares: None,
        }
    }

    /// An empty cache that answers from `other` what `other` holds: its context's point `i`
    /// is point `rows[i]` of `other`'s context (RIS `shadingCtxIndex`), with the same
    /// builtins. Counted as [`PatternCounters::shared`].
    pub fn sharing<'o: 'a>(
        arena: &'a Bump,
        counters: &'a PatternCounters,
        other: &'a ParamCache<'o>,
        rows: &'a [u32],
    ) -> Self {
        ParamCache {
            shares: Some((other, rows)),
            ..ParamCache::new(arena, counters)
        }
    }

    /// Forgets every cached column (the builtins they were evaluated at changed).
    pub fn flush(&self) {
        for s in &self.slots {
            s.set(None);
        }
    }
}

/// A parameter cache as contexts see it (a trait object, so that a context stays covariant
/// in its lifetime while the cache's `Cell`s are not).
pub(super) trait ParamLookup {
    /// The column of `value` (parameter `name` of `material`) at the points of `at`, cached;
    /// `in_volume`: the points lie inside a volume (a miss counts as a volume evaluation
    /// too).
    fn column(
        &self,
        material: u32,
        name: &str,
        value: ParamValue<'_>,
        at: PatternInputs<'_>,
        in_volume: bool,
    ) -> &[Rgb];
}

impl ParamLookup for ParamCache<'_> {
    fn column(
        &self,
        material: u32,
        name: &str,
        value: ParamValue<'_>,
        at: PatternInputs<'_>,
        in_volume: bool,
    ) -> &[Rgb] {
        self.get_or_eval(
            material,
            name,
            at.p.len(),
            in_volume,
            |column| match value {
                ParamValue::Float(f) => column.fill(Rgb::splat(f)),
                ParamValue::Color(c) => column.fill(c),
                ParamValue::Pattern(graph) => {
                    // The nodes' block columns live in the arena with the result.
                    let scratch = self
                        .arena
                        .alloc_slice_fill_copy(graph.scratch_len(column.len()), Rgb::BLACK);
                    pattern::eval_with(graph, at.p, at.u, at.v, column, scratch);
                }
            },
        )
    }
}

impl<'a> ParamCache<'a> {
    /// The column of `material`'s parameter `name` for `n` points: from the cache, gathered
    /// from the cache it shares, or evaluated with `eval` (which fills the column); then
    /// cached.
    fn get_or_eval(
        &self,
        material: u32,
        name: &str,
        n: usize,
        in_volume: bool,
        eval: impl FnOnce(&mut [Rgb]),
    ) -> &'a [Rgb] {
        for s in &self.slots {
            match s.get() {
                Some((m, key, column)) if m == material && key == name && column.len() == n => {
                    self.counters.hits.set(self.counters.hits.get() + 1);
                    return column;
                }
                _ => {}
            }
        }
        let shared = self
            .shares
            .filter(|(_, rows)| rows.len() == n)
            .and_then(|(other, rows)| Some((other.held(material, name)?, rows)));
        let column = self.arena.alloc_slice_fill_copy(n, Rgb::BLACK);
        match shared {
            Some((held, rows)) if rows.iter().all(|&r| (r as usize) < held.len()) => {
                for (c, &r) in column.iter_mut().zip(rows) {
                    *c = held[r as usize];
                }
                self.counters.shared.set(self.counters.shared.get() + 1);
            }
            _ => {
                self.counters.evals.set(self.counters.evals.get() + 1);
                if in_volume {
                    let v = &self.counters.volume_evals;
                    v.set(v.get() + 1);
                }
                eval(column);
            }
        }
        let column: &'a [Rgb] = column;
        if let Some(free) = self.slots.iter().find(|s| s.get().is_none()) {
            free.set(Some((material, self.arena.alloc_str(name), column)));
        }
        column
    }
}
