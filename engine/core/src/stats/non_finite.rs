//! NaN provenance (module docs of [`crate::stats`]): the stages whose outputs are checked,
//! the count of a column's non-finite values, and the first cases kept for `--replay`.

/// A stage whose output is checked for NaN and infinity. The discriminant indexes
/// [`SystemStats::non_finite`](super::SystemStats::non_finite).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    /// A surface Bxdf's samples (weight or pdf) and its evaluations towards light samples
    /// (value or pdf).
    Bxdf,
    /// The same for a phase function at in-volume points (the shade stage's and the
    /// lighting delegate's).
    Phase,
    /// A volume integrator's `nearest_hits`: the transmissions of the points and escaped
    /// rays it returned.
    Volume,
    /// Light samples (radiance or pdf) of direct lighting and of the lighting delegate.
    Lighting,
    /// Shadow-ray contributions after the transmission walk (surfaces that let shadows pass,
    /// volume integrators' `transmission`), finite before it.
    Transmission,
    /// Emission of surfaces hit by path rays, and emission of media along path rays
    /// ([`ShadeGroups::emitted`](crate::shade_groups::ShadeGroups::emitted)), as added to
    /// the path (when the path's throughput and transmission were finite).
    Emission,
    /// Environment radiance seen by escaped rays, as added to the path (when the path's
    /// throughput and transmission were finite).
    Environment,
}

impl Stage {
    /// Number of stages.
    pub const COUNT: usize = 7;
    /// Every stage, in discriminant order.
    pub const ALL: [Stage; Stage::COUNT] = [
        Stage::Bxdf,
        Stage::Phase,
        Stage::Volume,
        Stage::Lighting,
        Stage::Transmission,
        Stage::Emission,
        Stage::Environment,
    ];

    /// The snake_case name used in JSON and in the summary.
    pub const fn name(self) -> &'static str {
        match self {
            Stage::Bxdf => "bxdf",
            Stage::Phase => "phase",
            Stage::Volume => "volume",
            Stage::Lighting => "lighting",
            Stage::Transmission => "transmission",
            Stage::Emission => "emission",
            Stage::Environment => "environment",
        }
    }
}

/// How many of `values` have a NaN or infinite channel (branch-free: a sum of flags).
#[inline]
pub fn count_non_finite<'a>(
    values: impl IntoIterator<Item = &'a risotto_components::Rgb>,
) -> usize {
    values.into_iter().map(|v| !v.is_finite() as usize).sum()
}

/// How many non-finite cases (pixel, sample, depth, stage) the stats keep: those of the
/// [`MAX_NON_FINITE_CASES`] smallest `(pixel index, sample index)` keys among all camera
/// samples that had a non-finite value, so which ones are kept depends neither on the
/// number of threads nor on the batch size or tiling.
pub const MAX_NON_FINITE_CASES: usize = 8;

/// One camera sample in which a stage produced a non-finite value, as a worker records it:
/// plain ids, named by [`NonFiniteCase`] when the render's stats are gathered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NonFiniteEvent {
    /// Pixel index `y * width + x` in the full image.
    pub pixel: u32,
    /// Sample index within the pixel (without the sampler's address bits).
    pub sample: u32,
    /// Path depth at the vertex where the value appeared: the scattering vertices before it
    /// (the depth of the ray that arrived there; 0 = the first surface or volume event seen
    /// from the camera). Shadow rays count at the vertex that cast them.
    pub depth: u32,
    /// The stage that produced it.
    pub stage: Stage,
    /// The material involved, by index in the compiled scene, where there is one: the
    /// surface's (Bxdf, emission) or the volume's (phase function, volume integrator); for
    /// light samples the material of the lit point. `None` for transmission (shadow-ray walk)
    /// and the environment.
    pub material: Option<u32>,
}

impl NonFiniteEvent {
    /// The camera sample: what the kept cases are chosen (smallest first) and deduplicated by.
    #[inline]
    pub fn key(&self) -> (u32, u32) {
        (self.pixel, self.sample)
    }
    /// Of two events of one camera sample, the one kept has the smaller rank: the shallower,
    /// then the earlier stage in [`Stage::ALL`] order.
    #[inline]
    pub(super) fn rank(&self) -> (u32, Stage) {
        (self.depth, self.stage)
    }
}

/// A kept [`NonFiniteEvent`] with its pixel's coordinates, the material's name and the seed:
/// what `risotto render --replay X,Y,SAMPLE` re-runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NonFiniteCase {
    /// Pixel column (0 = left).
    pub x: u32,
    /// Pixel row (0 = top).
    pub y: u32,
    /// Sample index within the pixel.
    pub sample: u32,
    /// Path depth ([`NonFiniteEvent::depth`]).
    pub depth: u32,
    /// The stage that produced the value.
    pub stage: Stage,
    /// The material's name ([`NonFiniteEvent::material`]).
    pub material: Option<String>,
    /// The render seed.
    pub seed: u64,
}

impl NonFiniteCase {
    /// Names `event` of a render of an image `width` pixels wide with seed `seed`;
    /// `material_name` names a material index.
    pub fn of(
        event: &NonFiniteEvent,
        width: u32,
        seed: u64,
        material_name: impl Fn(u32) -> Option<String>,
    ) -> Self {
        let width = width.max(1);
        NonFiniteCase {
            x: event.pixel % width,
            y: event.pixel / width,
            sample: event.sample,
            depth: event.depth,
            stage: event.stage,
            material: event.material.and_then(material_name),
            seed,
        }
    }
    /// The `--replay X,Y,SAMPLE` argument that re-runs this sample.
    pub fn replay_arg(&self) -> String {
        format!("--replay {},{},{}", self.x, self.y, self.sample)
    }
}
