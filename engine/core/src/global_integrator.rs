//! The choice of global integrator, as plain data the scene and the techniques name.

/// Which global integrator renders (the `integrator` technique; `[render] integrator` in a
/// scene file).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum GlobalIntegrator {
    /// The path tracer ([`PathTracer`](crate::path_tracer::PathTracer)).
    #[default]
    Path,
    /// Light tracing alone ([`Strategy::Light`](crate::bidir::Strategy::Light)).
    Light,
    /// Bidirectional path tracing ([`Strategy::Bdpt`](crate::bidir::Strategy::Bdpt)).
    Bdpt,
    /// Vertex connection and merging ([`Strategy::Vcm`](crate::bidir::Strategy::Vcm)).
    Vcm,
}

impl GlobalIntegrator {
    /// Every integrator, in listing order.
    pub const ALL: [GlobalIntegrator; 4] = [
        GlobalIntegrator::Path,
        GlobalIntegrator::Light,
        GlobalIntegrator::Bdpt,
        GlobalIntegrator::Vcm,
    ];

    /// The name scene files and `--technique integrator=NAME` use.
    pub fn name(self) -> &'static str {
        match self {
            GlobalIntegrator::Path => "path",
            GlobalIntegrator::Light => "light",
            GlobalIntegrator::Bdpt => "bdpt",
            GlobalIntegrator::Vcm => "vcm",
        }
    }

    /// The integrator called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }
}
