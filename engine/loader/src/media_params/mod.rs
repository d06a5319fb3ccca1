//! The scene-file parameters of the built-in media: heterogeneous media (density grids and
//! patterns, emission), homogeneous media with pattern coefficients, pattern `albedo` and
//! `g`, and the `subsurface` material. The built-in media themselves live in
//! `risotto-builtins`; this is only how a scene file's keys become their parameters.

pub mod heterogeneous;
pub mod patterns;
pub mod subsurface;
