//! risotto engine.
