//! risotto systems.
