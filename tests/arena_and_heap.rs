//! No heap memory in the arena (issue 9, item 5): the per-batch arena never runs destructors,
//! so whatever the engine puts there must be plain data, and heap use must not grow with the
//! number of batches a worker renders.
//!
//! This binary counts every allocation (its own global allocator), so it holds only these
//! tests, serialised by a lock.
#![allow(
    unsafe_code,
    reason = "a counting global allocator wraps the system allocator"
)]

use risotto::builtins::builtin::{
    BeerInterior, DielectricBxdf, DiffuseBxdf, MirrorBxdf, NullBxdf, NullInterior,
};
use risotto::engine::plugin::{OverlappingVolume, ParamCache, ShadingContext};
use risotto::engine::render::{render, RenderOptions};
use risotto::loader::load::{compile_scene, load_scene_file, MaterialRegistry};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The system allocator, counting live bytes and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static LOCK: Mutex<()> = Mutex::new(());

fn grew(bytes: usize) {
    let live = LIVE.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(live, Ordering::Relaxed);
}

// SAFETY: every call is forwarded to `System` with the caller's arguments; the counters
// only observe sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded as is.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            grew(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Peak live heap bytes above the start while rendering `scenes/liquid-in-glass.toml` at
/// 16 x 16 pixels with `spp` samples, one thread, four samples per batch (so `spp / 4`
/// batches, all in one tile and one worker), and the bytes still live after the render and its
/// output are gone.
fn render_bytes(spp: u32) -> (usize, usize) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/liquid-in-glass.toml");
    let mut scene = load_scene_file(&file, &MaterialRegistry::with_builtins()).unwrap();
    scene.settings.width = 16;
    scene.settings.height = 16;
    scene.settings.spp = spp;
    scene.camera.width = 16;
    scene.camera.height = 16;
    let compiled = compile_scene(scene).unwrap();
    let options = RenderOptions {
        threads: Some(1),
        batch_size: 16 * 16 * 4,
        tile_size: 16,
        ..RenderOptions::default()
    };
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = render(&compiled, &options, &|_| {}).unwrap();
    let peak = PEAK.load(Ordering::Relaxed) - base;

    assert_eq!(out.stats.counters.nan_dropped, 0);
    assert_eq!(
        out.stats.counters.samples,
        16 * 16 * spp as u64,
        "every sample"
    );
    drop(out);
    let retained = LIVE.load(Ordering::Relaxed).saturating_sub(base);
    (peak, retained)
}

#[test]
fn heap_use_does_not_grow_with_the_number_of_batches() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // Warm up once (lazy statics, the thread pool's first use), then N and 4N batches.
    render_bytes(8);
    let (few, _) = render_bytes(4 * 16);
    let (many, retained) = render_bytes(4 * 64);
    eprintln!("peak heap: {few} B for 16 batches, {many} B for 64; {retained} B retained");
    // Nothing a batch allocated outlives the render (heap tables moved into the arena, whose
    // reset runs no destructors, would: about 30 KB per batch of this scene). What stays
    // is the thread pool's per-thread state.
    assert!(
        retained < 64 * 1024,
        "{retained} B still allocated after rendering 64 batches"
    );
    // Peak use: the image and stats are the same size for both; reused buffers grow to the
    // largest batch seen (which the longer render samples a little further into the tail),
    // and the arena's chunks double (bumpalo), so a tail batch a little larger than any
    // before can add one chunk (measured: 0.23 MB here; none when the arena starts large),
    // hence a slack of 1/4 of the shorter render's peak (a leak of 30 KB per batch adds
    // 1.4 MB here, more than three times that slack).
    assert!(
        many <= few + few / 4,
        "peak heap grew with the number of batches: {few} B for 16, {many} B for 64"
    );
}

#[test]
fn what_the_engine_puts_in_the_arena_has_no_drop_glue() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    use std::mem::needs_drop;
    // Built-in closures (Bxdfs, phase function, interiors).
    assert!(!needs_drop::<DiffuseBxdf>());
    // A patterned reflectance is a column borrowed from the arena; a parameter value borrows
    // its pattern graph from the factory.
    assert!(!needs_drop::<DiffuseBxdf<&'static [risotto_components::Rgb]>>());
    assert!(!needs_drop::<risotto::engine::plugin::ParamValue<'static>>());
    assert!(!needs_drop::<DielectricBxdf>());
    assert!(!needs_drop::<MirrorBxdf>());
    assert!(!needs_drop::<risotto::builtins::phase::PhaseBxdf<'static>>());
    assert!(!needs_drop::<NullBxdf>());
    assert!(!needs_drop::<NullInterior>());
    assert!(!needs_drop::<BeerInterior>());
    // The contexts, caches and overlapping-volume lists the renderer allocates per bundle.
    assert!(!needs_drop::<ShadingContext<'static>>());
    assert!(!needs_drop::<ParamCache<'static>>());
    assert!(!needs_drop::<OverlappingVolume<'static>>());
    // The check itself can fail: a table owning heap columns has drop glue.
    assert!(needs_drop::<risotto_components::ShadingPoints>());
}
