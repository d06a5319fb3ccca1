//! Which global integrator renders a scene: a name the scene file (`[render] integrator`),
//! `--technique integrator=NAME` and the render options share. Its own module so that the
//! scene's settings can name it without importing the integrator contract (which imports
//! the scene).

/// Which global integrator renders (the `integrator` technique; `[render] integrator` in a
/// scene file).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum GlobalIntegrator {
    /// The path tracer (`path_tracer::PathTracer`).
    #[default]
    Path,
    /// Light tracing alone (`bidir::Strategy::Light`).
    Light,
    /// Bidirectional path tracing (`bidir::Strategy::Bdpt`).
    Bdpt,
}

impl GlobalIntegrator {
    /// Every integrator, in listing order.
    pub const ALL: [GlobalIntegrator; 3] = [
        GlobalIntegrator::Path,
        GlobalIntegrator::Light,
        GlobalIntegrator::Bdpt,
    ];

    /// The name scene files and `--technique integrator=NAME` use.
    pub fn name(self) -> &'static str {
        match self {
            GlobalIntegrator::Path => "path",
            GlobalIntegrator::Light => "light",
            GlobalIntegrator::Bdpt => "bdpt",
        }
    }

    /// The integrator called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }
}
