//! Multiple importance sampling over every way a bidirectional integrator makes one path,
//! computed incrementally along the subpaths.
//!
//! This is the recursive formulation of Georgiev, Křivánek, Davidovič and Slusallek, "Light
//! transport simulation with vertex connection and merging" (SIGGRAPH Asia 2012), as its
//! technical report "Implementing vertex connection and merging" (Georgiev 2012) writes it:
//! each subpath carries sums of pdf ratios (`dVCM`, `dVC`; [`SubpathMis`] says why not `dVM`), updated at every
//! vertex from the forward and reverse pdfs of the sampled direction, so that the weight of a
//! connection, a merge or an emitter hit is computed from the two end vertices alone,
//! whatever the path length (eqs. 14-20 of the report). With merging off (`vm_weight = 0`,
//! `vc_weight = 0`) the same quantities give bidirectional path tracing's weights (Veach
//! 1997, ch. 10) over the connection strategies and light tracing.
//!
//! Conventions:
//! - `mis(x) = x^2`: the power heuristic with exponent 2 (Veach 1997, eq. 9.13) on every ratio.
//! - Pdfs are per unit solid angle (`_w`) or per unit area (`_a`); a point inside a medium
//!   has no surface and its cosine is 1 (area measure becomes volume measure).
//! - The distance-sampling pdfs of media and Russian roulette are left out of every strategy's
//!   pdf alike: the weights are then those of slightly different densities, but they are
//!   computed from the same function for every strategy, so they still sum to one over the
//!   strategies that can make a path (Veach 1997, sec. 9.2: any such partition of unity keeps
//!   the combination unbiased; only its variance depends on the choice).
//! - Light tracing's strategy counts `light_paths` light subpaths per iteration against one
//!   camera sample per pixel; the camera's pdfs are per unit film area normalised over the
//!   whole image (`Camera::pdf_direction`), so the ratio carries
//!   `light_paths / (width * height)` ([`MisFactors::light_paths_per_pixel`]).

/// The heuristic applied to every pdf ratio: the power heuristic, exponent 2.
#[inline]
pub fn mis(x: f32) -> f32 {
    x * x
}

/// The merging constants of one kind of vertex: surface points merge light vertices within
/// a disk of radius `r` (`eta = pi r^2 N_L`), points in media within a ball (`eta = 4/3 pi
/// r^3 N_L`, the point-point estimator of Křivánek et al. 2014, "Unifying points, beams and
/// paths in volumetric light transport simulation").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexFactors {
    /// `mis(eta)`: how much more likely merging at such a vertex is than connecting there
    /// (0 without merging).
    pub vm_weight: f32,
    /// `mis(1 / eta)` (0 without merging, where it never multiplies anything used).
    pub vc_weight: f32,
}

impl VertexFactors {
    fn of_eta(eta: f32) -> Self {
        VertexFactors {
            vm_weight: mis(eta),
            vc_weight: mis(1.0 / eta),
        }
    }
}

/// The constants of one iteration's weights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MisFactors {
    /// Light subpaths per iteration over the image's pixel count (light tracing's count
    /// against the camera's one sample per pixel).
    pub light_paths_per_pixel: f32,
    /// Light subpaths whose vertices a camera vertex merges: the iteration's (`N_L` of the
    /// kernels; 0 without merging).
    pub merged_light_paths: f32,
    /// Merging at surface vertices.
    pub surface: VertexFactors,
    /// Merging at points in media.
    pub volume: VertexFactors,
}

impl MisFactors {
    /// Bidirectional path tracing (connections and light tracing, no merging).
    pub fn connections_only(light_paths_per_pixel: f32) -> Self {
        MisFactors {
            light_paths_per_pixel,
            merged_light_paths: 0.0,
            surface: VertexFactors::default(),
            volume: VertexFactors::default(),
        }
    }

    /// Vertex connection and merging with merge radius `radius` and `light_paths` light
    /// subpaths per iteration (eq. 11 of the report: `eta_vcm = pi r^2 N_L` on surfaces;
    /// the ball's volume in media).
    pub fn vcm(radius: f32, light_paths: f32, light_paths_per_pixel: f32) -> Self {
        let pi = std::f32::consts::PI;
        MisFactors {
            light_paths_per_pixel,
            merged_light_paths: light_paths,
            surface: VertexFactors::of_eta(pi * radius * radius * light_paths),
            volume: VertexFactors::of_eta(4.0 / 3.0 * pi * radius.powi(3) * light_paths),
        }
    }

    /// The factors of a vertex in a medium (`true`) or on a surface.
    #[inline]
    pub fn at(&self, in_medium: bool) -> VertexFactors {
        if in_medium {
            self.volume
        } else {
            self.surface
        }
    }
}

/// The running pdf-ratio sums of one subpath (the report's `dVCM` and `dVC`).
///
/// The report's third sum, `dVM`, is always `dVC / mis(eta)`: the two start in that ratio
/// (eq. 33) and their updates (eqs. 35-39) keep it, `dVM`'s being `dVC`'s divided by
/// `mis(eta)` term by term. So it is not carried: a merge's weight divides `dVC` by the
/// `eta` of the vertex where it merges ([`merge_weight`]), which also gives the right weights
/// when surface and medium vertices merge with different kernels (their `eta` differ, and
/// `dVC` collects each vertex's own, `+ mis(eta_v)` in [`SubpathMis::scatter`]); the
/// recursion is checked against full path pdfs in the tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubpathMis {
    /// `dVCM`.
    pub vcm: f32,
    /// `dVC`.
    pub vc: f32,
}

impl SubpathMis {
    /// A light subpath leaving a light (report eqs. 31-33): `direct_pdf` is the density with
    /// which next-event estimation picks the start point (per unit area for lights with a
    /// position, per unit solid angle for lights at infinity), `emission_pdf` the density of
    /// the emitted ray (position times direction), `cos_at_light` the cosine of the emitted
    /// direction at the light (1 for lights at infinity and points). Dirac lights (a point
    /// or a direction) cannot be hit, so no strategy connects to their start: `vc = 0`.
    pub fn light_start(direct_pdf: f32, emission_pdf: f32, cos_at_light: f32, delta: bool) -> Self {
        let vc = if delta {
            0.0
        } else {
            mis(cos_at_light / emission_pdf)
        };
        SubpathMis {
            vcm: mis(direct_pdf / emission_pdf),
            vc,
        }
    }

    /// A camera subpath leaving the camera with a ray of film-normalised solid-angle pdf
    /// `camera_pdf_w` (report eq. 31 with `N_L` light paths per iteration).
    pub fn camera_start(camera_pdf_w: f32, light_paths_per_pixel: f32) -> Self {
        SubpathMis {
            vcm: mis(light_paths_per_pixel / camera_pdf_w),
            vc: 0.0,
        }
    }

    /// The subpath reaches a vertex at `distance` from the last one, arriving at cosine
    /// `cos_in` (1 in a medium) (report eqs. 34-36). `from_infinity` is true for the first
    /// segment of a subpath from a light at infinity, whose start has no distance.
    pub fn arrive(&mut self, distance: f32, cos_in: f32, from_infinity: bool) {
        if !from_infinity {
            self.vcm *= mis(distance * distance);
        }
        let c = 1.0 / mis(cos_in);
        self.vcm *= c;
        self.vc *= c;
    }

    /// The subpath scatters at a vertex into a direction sampled with solid-angle pdf
    /// `pdf_w` (reverse pdf `pdf_rev_w`) and cosine `cos_out` (report eqs. 37-39), with the
    /// vertex's merging factors `v`; a Dirac lobe (`specular`) cannot be connected or merged
    /// at, and its forward and reverse pdfs cancel.
    pub fn scatter(
        &mut self,
        pdf_w: f32,
        pdf_rev_w: f32,
        cos_out: f32,
        specular: bool,
        v: VertexFactors,
    ) {
        if specular {
            self.vcm = 0.0;
            self.vc *= mis(cos_out);
        } else {
            let g = mis(cos_out / pdf_w);
            self.vc = g * (self.vc * mis(pdf_rev_w) + self.vcm + v.vm_weight);
            self.vcm = mis(1.0 / pdf_w);
        }
    }
}

/// The weight of a camera subpath hitting an emitter (report eq. 42): `direct_pdf_a` the
/// density with which next-event estimation picks that point (per unit solid angle for
/// lights at infinity), `emission_pdf_w` the density with which the light emits that ray.
/// Paths of one segment (emitters seen directly) have weight 1: no other strategy makes them.
pub fn emitter_hit_weight(
    camera: &SubpathMis,
    direct_pdf_a: f32,
    emission_pdf_w: f32,
    first_segment: bool,
) -> f32 {
    if first_segment {
        return 1.0;
    }
    let w_camera = mis(direct_pdf_a) * camera.vcm + mis(emission_pdf_w) * camera.vc;
    1.0 / (1.0 + w_camera)
}

/// The weight of next-event estimation at a camera vertex (report eq. 44): the light sample
/// has solid-angle pdf `direct_pdf_w` (selection included) and would have been emitted with
/// `emission_pdf_w`; the Bxdf samples its direction with `bxdf_pdf_w` (and the reverse with
/// `bxdf_rev_pdf_w`); `cos_to_light` at the vertex, `cos_at_light` at the light. A Dirac
/// light cannot be hit by Bxdf sampling. `v`: the camera vertex's merging factors.
#[allow(clippy::too_many_arguments, reason = "the report's quantities, named")]
pub fn light_sample_weight(
    camera: &SubpathMis,
    direct_pdf_w: f32,
    emission_pdf_w: f32,
    bxdf_pdf_w: f32,
    bxdf_rev_pdf_w: f32,
    cos_to_light: f32,
    cos_at_light: f32,
    delta_light: bool,
    v: VertexFactors,
) -> f32 {
    let w_light = if delta_light {
        0.0
    } else {
        mis(bxdf_pdf_w / direct_pdf_w)
    };
    let w_camera = mis(emission_pdf_w * cos_to_light / (direct_pdf_w * cos_at_light))
        * (v.vm_weight + camera.vcm + camera.vc * mis(bxdf_rev_pdf_w));
    1.0 / (w_light + 1.0 + w_camera)
}

/// The weight of connecting a light vertex to the camera (light tracing, report eq. 46):
/// `camera_pdf_a` is the film-normalised density with which a camera ray reaches the light
/// vertex (per unit area there), `bxdf_rev_pdf_w` the light vertex's pdf of sampling its
/// incident direction given the direction to the camera; `v` the light vertex's merging
/// factors.
pub fn camera_connection_weight(
    light: &SubpathMis,
    camera_pdf_a: f32,
    bxdf_rev_pdf_w: f32,
    v: VertexFactors,
    light_paths_per_pixel: f32,
) -> f32 {
    let w_light = mis(camera_pdf_a / light_paths_per_pixel)
        * (v.vm_weight + light.vcm + light.vc * mis(bxdf_rev_pdf_w));
    1.0 / (w_light + 1.0)
}

/// The pdfs at both ends of a connection between a camera and a light vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConnectionPdfs {
    /// The camera vertex's Bxdf samples the connection direction with this solid-angle pdf,
    /// converted to area at the light vertex.
    pub camera_pdf_a: f32,
    /// The camera vertex's pdf of sampling its incident direction from the connection's.
    pub camera_rev_pdf_w: f32,
    /// The light vertex's Bxdf samples the connection direction with this pdf, converted to
    /// area at the camera vertex.
    pub light_pdf_a: f32,
    /// The light vertex's pdf of sampling its incident direction from the connection's.
    pub light_rev_pdf_w: f32,
}

/// The weight of connecting a camera vertex to a light vertex (report eq. 45), with the
/// merging factors of the camera vertex (`vc`) and the light vertex (`vl`).
pub fn connection_weight(
    camera: &SubpathMis,
    light: &SubpathMis,
    p: &ConnectionPdfs,
    vc: VertexFactors,
    vl: VertexFactors,
) -> f32 {
    let w_light =
        mis(p.camera_pdf_a) * (vl.vm_weight + light.vcm + light.vc * mis(p.light_rev_pdf_w));
    let w_camera =
        mis(p.light_pdf_a) * (vc.vm_weight + camera.vcm + camera.vc * mis(p.camera_rev_pdf_w));
    1.0 / (w_light + 1.0 + w_camera)
}

/// The weight of merging a light vertex at a camera vertex (report eq. 47): the camera
/// vertex's Bxdf samples the light vertex's incident direction with `camera_pdf_w` and its
/// own incident direction from there with `camera_rev_pdf_w`; `v` the merging factors of
/// the vertex (both are of one kind: surfaces merge with surfaces, media with media).
pub fn merge_weight(
    camera: &SubpathMis,
    light: &SubpathMis,
    camera_pdf_w: f32,
    camera_rev_pdf_w: f32,
    v: VertexFactors,
) -> f32 {
    let w_light = v.vc_weight * (light.vcm + light.vc * mis(camera_pdf_w));
    let w_camera = v.vc_weight * (camera.vcm + camera.vc * mis(camera_rev_pdf_w));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Solid-angle pdf to area pdf at a point `distance` away seen at cosine `cos_there`.
#[inline]
pub fn pdf_w_to_a(pdf_w: f32, distance: f32, cos_there: f32) -> f32 {
    pdf_w * cos_there.abs() / (distance * distance)
}

#[cfg(test)]
mod tests;
