//! Unit tests of the pbrt-v4 importer.
