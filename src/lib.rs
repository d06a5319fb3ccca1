//! risotto: a physically based CPU renderer with first-class volumes.
pub use risotto_components as components;
pub use risotto_engine as engine;
pub use risotto_systems as systems;
