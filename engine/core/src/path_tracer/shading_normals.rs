//! Shading normals that differ from the geometric normal (meshes with vertex normals): the
//! directions for which the two disagree are discarded, so light neither leaks through a
//! surface nor is reflected from below it.
//!
//! A Bxdf decides between reflection and transmission with its shading normal `Nn`; the
//! ray that leaves the point decides with the geometric one `Ng`. Where they disagree (near
//! the silhouette of a coarse mesh with smooth normals), a "reflected" direction actually
//! goes through the surface, and light arriving from behind it is "reflected" to the viewer:
//! a leak. The treatment here is pbrt-v3's (Pharr, Jakob and Humphreys, 3rd ed., sec. 9.1,
//! `BSDF::f`, which evaluates only the reflection lobes when `wi` and `wo` lie on the same
//! side of `Ng` and only the transmission lobes otherwise) and Veach 1997's (sec. 5.3.2,
//! "the use of shading normals"): keep a direction `wi` only where its classification as
//! reflection or transmission by `Ng` agrees with that by `Nn`. It needs no knowledge of a
//! Bxdf's lobes, so it applies to every plug-in. Mitsuba 3 instead evaluates in the shading
//! frame alone, which leaks; pbrt-v4 does the same. The cost is a small darkening where the
//! normals disagree strongly (the discarded directions), which vanishes as the mesh is
//! refined (`tests/mesh_attributes.rs` measures both).
//!
//! On a closed mesh with the shadow-terminator offset (`risotto_systems::terminator`) that
//! darkening is the terminator of a coarse mesh: near it the light arrives at directions the
//! shading normal calls reflection and the flat facet transmission. At a point lifted to the
//! smooth surface such directions are kept ([`kept_when_lifted`]) and their rays leave from
//! the smooth surface; the mesh, being closed, still stops every ray towards a light behind
//! it, so nothing leaks.
//!
//! The bidirectional integrators (`crate::bidir`) apply the same checks to both subpaths
//! and their connections, and Veach's adjoint correction (1997, sec. 5.3, eq. 5.19) to
//! light subpaths: scattering of importance with shading normals is not symmetric, and the
//! light-path throughput is multiplied by `|wo . Nn| |wi . Ng| / (|wo . Ng| |wi . Nn|)`.

use risotto_components::{LobeSampled, Rgb, ShadingPoints};
use risotto_systems::bxdf_samples::BxdfSamples;
use std::ops::Range;

/// Whether leaving the point with normals `ng`, `nn`, seen from `vn`, in direction `wi` is
/// reflection by both normals or transmission by both.
#[inline]
pub(crate) fn sides_agree(ng: glam::Vec3, nn: glam::Vec3, vn: glam::Vec3, wi: glam::Vec3) -> bool {
    let geometric = wi.dot(ng) * vn.dot(ng) > 0.0;
    let shading = wi.dot(nn) * vn.dot(nn) > 0.0;
    geometric == shading
}

/// Whether a direction `wi` leaving a point lifted to the smooth surface of its mesh
/// (`risotto_systems::terminator`) is kept: where the normals agree, and also where the
/// shading normal calls it reflection and the geometric one transmission. Such a ray leaves
/// from the smooth surface, above the triangle, and reaches the light only if the mesh does
/// not block it (it crosses the triangle or a neighbour otherwise): the light a smooth
/// surface sees at grazing angles, which discarding it would darken (the shadow terminator
/// of coarse meshes). It cannot leak light from behind a closed mesh, whose triangles stop
/// it.
#[inline]
pub(crate) fn kept_when_lifted(
    ng: glam::Vec3,
    nn: glam::Vec3,
    vn: glam::Vec3,
    wi: glam::Vec3,
) -> bool {
    sides_agree(ng, nn, vn, wi) || wi.dot(nn) * vn.dot(nn) > 0.0
}

/// Makes the Bxdf samples of the points `range` whose direction the normals disagree on
/// "no sample" (the path ends there, as for an absorbed sample). With `lifted` (the caller
/// spawns from `terminator_lift`, the scene has meshes with the offset), points with a
/// non-zero lift keep what [`kept_when_lifted`] keeps.
pub(crate) fn discard_bxdf_samples(
    points: &ShadingPoints,
    range: Range<usize>,
    lifted: bool,
    samples: &mut BxdfSamples,
) {
    let (ng, nn, vn) = (
        &points.ng[range.clone()],
        &points.nn[range.clone()],
        &points.vn[range.clone()],
    );
    let lift = &points.terminator_lift[range];
    let keep = |k: usize, wi| {
        if lifted && lift[k] != glam::Vec3::ZERO {
            kept_when_lifted(ng[k], nn[k], vn[k], wi)
        } else {
            sides_agree(ng[k], nn[k], vn[k], wi)
        }
    };
    for k in 0..ng.len() {
        if samples.pdf[k] > 0.0 && !keep(k, samples.wi[k]) {
            samples.pdf[k] = 0.0;
            samples.weight[k] = Rgb::BLACK;
            samples.lobe[k] = LobeSampled::NONE;
        }
    }
}

/// Zeroes the Bxdf values towards the light samples `wi` of the points `range` whose
/// direction the normals disagree on (`lifted` as for [`discard_bxdf_samples`]).
pub(super) fn discard_light_directions(
    points: &ShadingPoints,
    range: Range<usize>,
    lifted: bool,
    wi: &[glam::Vec3],
    value: &mut [Rgb],
) {
    let (ng, nn, vn) = (
        &points.ng[range.clone()],
        &points.nn[range.clone()],
        &points.vn[range.clone()],
    );
    let lift = &points.terminator_lift[range];
    for k in 0..ng.len() {
        let keep = if lifted && lift[k] != glam::Vec3::ZERO {
            kept_when_lifted(ng[k], nn[k], vn[k], wi[k])
        } else {
            sides_agree(ng[k], nn[k], vn[k], wi[k])
        };
        if !keep {
            value[k] = Rgb::BLACK;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn directions_the_normals_classify_differently_are_discarded() {
        let ng = Vec3::Z;
        // A shading normal tilted 60 degrees towards +x.
        let nn = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
        let vn = Vec3::new(0.0, 0.0, 1.0);
        // Above both planes: reflection by both.
        assert!(sides_agree(ng, nn, vn, Vec3::new(0.0, 0.6, 0.8)));
        // Below the geometric plane but above the shading one: a leak, discarded.
        let leak = Vec3::new(0.9, 0.0, -0.2).normalize();
        assert!(leak.dot(nn) > 0.0);
        assert!(!sides_agree(ng, nn, vn, leak));
        // Below both: transmission by both (kept for Bxdfs that transmit).
        assert!(sides_agree(
            ng,
            nn,
            vn,
            Vec3::new(-0.3, 0.0, -0.9).normalize()
        ));
        // With nn == ng nothing is ever discarded.
        for wi in [
            leak,
            Vec3::X,
            -Vec3::Z,
            Vec3::new(0.1, 0.2, 0.3).normalize(),
        ] {
            assert!(sides_agree(ng, ng, vn, wi));
        }
    }
}
