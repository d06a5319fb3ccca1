//! risotto's tools over rendered images: `converge` (error against time per technique, with
//! plots behind the default `plots` feature), `merge` (partial EXRs of split renders back
//! into one image), `compare` (error metrics between two images) and `z_test` (Mitsuba 3's
//! per-pixel z-test of a render against a reference and its variance).

pub mod compare;
pub mod converge;
pub mod merge;
pub mod z_test;
