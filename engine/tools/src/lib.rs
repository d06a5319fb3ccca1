//! risotto's tools over rendered images: `converge` (error against time per technique, with
//! plots behind the default `plots` feature), `merge` (partial EXRs of split renders back
//! into one image) and `compare` (error metrics between two images).

pub mod compare;
pub mod converge;
pub mod merge;
