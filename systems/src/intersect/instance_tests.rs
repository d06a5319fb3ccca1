//! Tests of instanced geometry: hits on instances against the same geometry written out
//! flat (transformed copies), and against an analytic ellipsoid.

use glam::{Affine3A, DVec3, Quat, Vec2};

use super::*;
use crate::geometry::Sphere;
use crate::mesh_attributes::{MeshAttributes, VertexAttributes};
use crate::sampler::SplitMix64 as Rng;

fn rand_vec(rng: &mut Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.f32(), rng.f32(), rng.f32()) * (hi - lo) + Vec3::splat(lo)
}

/// A closed octahedron (8 triangles, outward winding) of radius 1 at the origin.
fn octahedron() -> Vec<[Vec3; 3]> {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let mut tris = Vec::new();
    for sx in [1.0f32, -1.0] {
        for sy in [1.0f32, -1.0] {
            for sz in [1.0f32, -1.0] {
                let (a, b, c) = (x * sx, y * sy, z * sz);
                // Outward when the three axes are right-handed.
                if sx * sy * sz > 0.0 {
                    tris.push([a, b, c]);
                } else {
                    tris.push([a, c, b]);
                }
            }
        }
    }
    tris
}

/// The placements tested: rotated, non-uniformly scaled, mirrored, translated.
fn placements() -> Vec<Affine3A> {
    vec![
        Affine3A::from_translation(Vec3::new(3.0, 0.0, 0.0)),
        Affine3A::from_scale_rotation_translation(
            Vec3::new(0.5, 1.5, 0.8),
            Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7),
            Vec3::new(-3.0, 1.0, 0.5),
        ),
        // Mirrored in x, turned about y.
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.4), Vec3::new(0.0, -2.5, 1.0))
            * Affine3A::from_scale(Vec3::new(-1.2, 0.9, 1.1)),
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.7),
            Quat::from_rotation_z(1.1),
            Vec3::new(0.0, 3.0, -1.0),
        ),
    ]
}

/// The object (an octahedron and a sphere), placed by [`placements`], instanced and flat:
/// the flat copy holds the mapped triangles in the same vertex order (so the same
/// barycentrics) and, for the placements that map the sphere to a sphere (uniform scale),
/// the mapped sphere. Returns both and, per instanced primitive, the flat one that is the
/// same surface (`None` for an ellipsoid).
fn scenes() -> (SceneGeometry, SceneGeometry, Vec<Option<u32>>) {
    let object_tris = octahedron();
    let object_sphere = Sphere {
        center: Vec3::new(0.0, 0.0, 2.5),
        radius: 0.6,
    };
    let object = SceneGeometry::build(object_tris.clone(), vec![object_sphere]);
    let placed = placements();
    let instances: Vec<(u32, Affine3A)> = placed.iter().map(|&m| (0, m)).collect();
    let instanced =
        SceneGeometry::build_with_instances(Vec::new(), Vec::new(), vec![object], &instances);

    let mut flat_tris = Vec::new();
    let mut flat_spheres = Vec::new();
    let mut sphere_of = Vec::new();
    for m in &placed {
        for t in &object_tris {
            flat_tris.push(t.map(|v| m.transform_point3(v)));
        }
        let scale = Vec3::from(m.matrix3.x_axis).length();
        let uniform = (Vec3::from(m.matrix3.y_axis).length() - scale).abs() < 1e-6
            && (Vec3::from(m.matrix3.z_axis).length() - scale).abs() < 1e-6;
        if uniform {
            sphere_of.push(Some(flat_spheres.len() as u32));
            flat_spheres.push(Sphere {
                center: m.transform_point3(object_sphere.center),
                radius: object_sphere.radius * scale,
            });
        } else {
            sphere_of.push(None);
        }
    }
    let nt = flat_tris.len() as u32;
    let flat = SceneGeometry::build(flat_tris, flat_spheres);
    let per = object_tris.len() as u32 + 1;
    let mapping = (0..placed.len() as u32 * per)
        .map(|p| {
            let (k, j) = (p / per, p % per);
            if j < per - 1 {
                Some(k * (per - 1) + j)
            } else {
                sphere_of[k as usize].map(|s| nt + s)
            }
        })
        .collect();
    (instanced, flat, mapping)
}

fn closest(
    g: &SceneGeometry,
    o: &[Vec3],
    d: &[Vec3],
    tmin: f32,
) -> (Vec<f32>, Vec<u32>, Vec<f32>, Vec<f32>) {
    let n = o.len();
    let (mut t, mut prim, mut b1, mut b2) = (vec![0.0; n], vec![0; n], vec![0.0; n], vec![0.0; n]);
    intersect_closest(
        g,
        o,
        d,
        &vec![tmin; n],
        &vec![f32::INFINITY; n],
        &mut t,
        &mut prim,
        &mut b1,
        &mut b2,
    );
    (t, prim, b1, b2)
}

/// Every kernel this CPU runs.
fn backends() -> Vec<Backend> {
    [Kernel::Portable, Kernel::Avx2]
        .iter()
        .filter_map(|k| k.backend())
        .collect()
}

fn mirrored(g: &SceneGeometry, prim: u32) -> bool {
    g.instance_of(prim)
        .is_some_and(|(k, _)| g.instances()[k].to_world.matrix3.determinant() < 0.0)
}

/// Instanced hits equal the flat copy's: same `t` (to rounding), the same surface (prim
/// mapping), normal (outward on mirrored instances too, where the flat copy's winding
/// faces in), uv, and the point within the flat point's error bounds; shadow rays and
/// every-hit queries agree; on every kernel.
#[test]
fn instanced_hits_equal_the_flat_copies() {
    let (mut inst, mut flat, mapping) = scenes();
    assert_eq!(inst.num_instances(), 4);
    assert_eq!(inst.num_prims(), 4 * 9);
    let mut rng = Rng(7);
    let n = 4000;
    let o: Vec<Vec3> = (0..n).map(|_| rand_vec(&mut rng, -6.0, 6.0)).collect();
    let d: Vec<Vec3> = (0..n)
        .map(|i| (rand_vec(&mut rng, -3.5, 3.5) - o[i]).normalize() * (0.5 + rng.f32()))
        .collect();
    for backend in backends() {
        inst.set_kernel(backend.kernel());
        flat.set_kernel(backend.kernel());
        let (ti, pi, b1i, b2i) = closest(&inst, &o, &d, 0.0);
        let (tf, pf, b1f, b2f) = closest(&flat, &o, &d, 0.0);
        let mut compared = 0;
        for i in 0..n {
            if pi[i] == NO_HIT {
                assert_eq!(pf[i], NO_HIT, "ray {i}: a miss on the instances only");
                continue;
            }
            let Some(want) = mapping[pi[i] as usize] else {
                continue;
            };
            // Rays that hit an ellipsoid first in one scene are skipped.
            assert_eq!(pf[i], want, "ray {i}: prim {} vs flat {}", pi[i], pf[i]);
            assert!(
                (ti[i] - tf[i]).abs() <= 1e-5 * tf[i].max(1.0),
                "ray {i}: t {} vs {}",
                ti[i],
                tf[i]
            );
            let si = inst.surface_at(pi[i], o[i], d[i], ti[i], b1i[i], b2i[i]);
            let sf = flat.surface_at(pf[i], o[i], d[i], tf[i], b1f[i], b2f[i]);
            let sign = if mirrored(&inst, pi[i]) && (pf[i] as usize) < flat.num_triangles() {
                -1.0
            } else {
                1.0
            };
            assert!(
                si.ng.dot(sf.ng * sign) > 0.9999,
                "ray {i}: ng {} vs {}",
                si.ng,
                sf.ng
            );
            assert!(
                (si.p - sf.p)
                    .abs()
                    .cmple(sf.p_error + si.p_error + Vec3::splat(2e-5))
                    .all(),
                "ray {i}: p {} vs {}",
                si.p,
                sf.p
            );
            assert_eq!(
                inst.hit_is_front(pi[i], o[i], d[i], ti[i], b1i[i]),
                si.ng.dot(d[i]) < 0.0
            );
            if (pf[i] as usize) < flat.num_triangles() {
                assert!(
                    (b1i[i] - b1f[i]).abs() < 1e-4 && (b2i[i] - b2f[i]).abs() < 1e-4,
                    "ray {i}: uv"
                );
            } else {
                let ui = inst.surface_uv(pi[i], o[i], d[i], ti[i], b1i[i], b2i[i]);
                assert!(ui.x.is_finite() && ui.y >= 0.0 && ui.y <= 1.0);
            }
            compared += 1;
        }
        assert!(compared > n / 10, "only {compared} hits compared");

        // Shadow rays: occluded exactly when the closest hit is before tmax.
        let tmax: Vec<f32> = (0..n)
            .map(|i| if i % 2 == 0 { 4.0 } else { f32::INFINITY })
            .collect();
        let mut occ = vec![false; n];
        intersect_occluded(&inst, &o, &d, &vec![0.0; n], &tmax, &mut occ);
        for i in 0..n {
            assert_eq!(occ[i], pi[i] != NO_HIT && ti[i] < tmax[i], "ray {i}");
        }
        // Every hit: the first is the closest, and all lie on instanced primitives.
        let mut all = vec![RayHits::EMPTY; n];
        intersect_all(
            &inst,
            &o,
            &d,
            &vec![0.0; n],
            &vec![f32::INFINITY; n],
            &mut all,
        );
        for i in 0..n {
            if pi[i] == NO_HIT {
                assert_eq!(all[i].len, 0, "ray {i}");
            } else {
                assert!(all[i].len >= 1);
                assert_eq!(all[i].t[0], ti[i], "ray {i}");
                assert_eq!(all[i].prim[0], pi[i], "ray {i}");
            }
        }
    }
}

/// A sphere instanced with a non-uniform, mirroring map is an ellipsoid: hits at the
/// analytic roots, with the analytic normal (the gradient of the implicit surface), front
/// from outside, uv of the object's sphere, and the point within its error bound of the
/// exact surface.
#[test]
fn instanced_sphere_is_the_analytic_ellipsoid() {
    let object = SceneGeometry::build(
        Vec::new(),
        vec![Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }],
    );
    let (a, b, c) = (2.0f64, 0.5, 1.25);
    let rot = Quat::from_rotation_y(0.3);
    let to_world = Affine3A::from_rotation_translation(rot, Vec3::new(1.0, 2.0, 3.0))
        * Affine3A::from_scale(Vec3::new(-(a as f32), b as f32, c as f32));
    let g =
        SceneGeometry::build_with_instances(Vec::new(), Vec::new(), vec![object], &[(0, to_world)]);
    let inv_rot = rot.inverse().as_dquat();
    let center = DVec3::new(1.0, 2.0, 3.0);
    let mut rng = Rng(3);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = Vec3::new(1.0, 2.0, 3.0) + rand_vec(&mut rng, -4.0, 4.0);
        let target = Vec3::new(1.0, 2.0, 3.0) + rand_vec(&mut rng, -1.0, 1.0);
        let d = target - o;
        // The ellipsoid frame: x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 after the inverse rotation.
        let lo = inv_rot * (o.as_dvec3() - center);
        let ld = inv_rot * d.as_dvec3();
        let s = DVec3::new(1.0 / a, 1.0 / b, 1.0 / c);
        let (po, pd) = (lo * s, ld * s);
        let (qa, qb, qc) = (pd.dot(pd), 2.0 * po.dot(pd), po.dot(po) - 1.0);
        let disc = qb * qb - 4.0 * qa * qc;
        let (t, prim, b1, b2) = closest(&g, &[o], &[d], 0.0);
        if disc <= 0.0 || qc < 0.0 {
            // A miss, or the origin inside: no claim but for misses well away.
            if disc < -1e-3 {
                assert_eq!(prim[0], NO_HIT);
            }
            continue;
        }
        let t0 = (-qb - disc.sqrt()) / (2.0 * qa);
        if t0 <= 0.0 || disc < 1e-3 {
            continue;
        }
        hits += 1;
        assert_eq!(prim[0], 0);
        assert_eq!(g.instance_of(0), Some((0, 0)));
        // Relative to t, and to the rounding of the origin's coordinates (a few units).
        let tol = 1e-5 * t0 + 2e-6 * (o.length() as f64 + 1.0) / d.length() as f64;
        assert!((t[0] as f64 - t0).abs() < tol, "t {} vs {t0}", t[0]);
        let s_at = g.surface_at(prim[0], o, d, t[0], b1[0], b2[0]);
        let local = lo + ld * t0;
        let n_local = DVec3::new(local.x / (a * a), local.y / (b * b), local.z / (c * c));
        let n_world = (rot.as_dquat() * n_local).normalize();
        assert!(
            s_at.ng.as_dvec3().dot(n_world) > 0.99999,
            "ng {} vs {n_world}",
            s_at.ng
        );
        assert!(g.hit_is_front(prim[0], o, d, t[0], b1[0]));
        // The exact point is within p_error of p (plus the ulps t's own rounding moves it).
        let exact = o.as_dvec3() + d.as_dvec3() * t0;
        let slack = d.as_dvec3().abs() * 1e-6 * t0;
        let err = (s_at.p.as_dvec3() - exact).abs();
        assert!(
            err.cmple(s_at.p_error.as_dvec3() + slack).all(),
            "p {} vs {exact}, bound {}",
            s_at.p,
            s_at.p_error
        );
        // The tangent is orthogonal to the normal and along the mapped phi direction.
        let tan = g.tangent_at(prim[0], s_at.ng);
        assert!(tan.dot(s_at.ng).abs() < 1e-5 && (tan.length() - 1.0).abs() < 1e-5);
        assert!(g.is_sphere(prim[0]));
        let uv = g.surface_uv(prim[0], o, d, t[0], b1[0], b2[0]);
        let h = local * s;
        let phi = h.y.atan2(-h.x).rem_euclid(std::f64::consts::TAU);
        assert!(
            ((uv.x as f64) - phi / std::f64::consts::TAU).abs() < 1e-4
                || (uv.x as f64 - phi / std::f64::consts::TAU).abs() > 0.9999
        );
    }
    assert!(hits > 200, "{hits} hits");
}

/// Mesh attributes of an object reach its instances: normals as normals map (inverse
/// transpose), uvs unchanged, tangents as the map moves `dp/du`, and the shadow-terminator
/// triangles, as the same mesh written out flat with its normals mapped gives them.
#[test]
fn instanced_mesh_attributes_match_the_flat_mesh() {
    let tris = octahedron();
    // One tilted normal for every corner of a triangle (so interpolation is exact in both
    // spaces), uvs that vary.
    let normals: Vec<Vec3> = tris
        .iter()
        .map(|t| {
            ((t[1] - t[0]).cross(t[2] - t[0]).normalize() + Vec3::new(0.1, 0.2, -0.1)).normalize()
        })
        .collect();
    let corners: Vec<[u32; 3]> = (0..tris.len() as u32).map(|i| [i, i, i]).collect();
    let uv_corners: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let uvs: Vec<Vec2> = (0..3 * tris.len())
        .map(|k| Vec2::new(k as f32 * 0.1, (k % 3) as f32 * 0.3))
        .collect();
    // Normals index per triangle, uvs per corner: two meshes' worth of attribute layouts
    // are not needed, so the normals are repeated per corner instead.
    let normals_per_corner: Vec<Vec3> = normals.iter().flat_map(|&n| [n, n, n]).collect();
    let _ = corners;
    let attrs = VertexAttributes {
        normals: normals_per_corner.clone(),
        uvs: uvs.clone(),
        corners: uv_corners.clone(),
        shadow_terminator_offset: true,
    };
    let m = placements()[1];
    let mut object = SceneGeometry::build(tris.clone(), Vec::new());
    let mut a = MeshAttributes::default();
    a.push(0, attrs);
    object.set_attributes(a);
    let inst = SceneGeometry::build_with_instances(Vec::new(), Vec::new(), vec![object], &[(0, m)]);
    assert!(inst.has_attributes() && inst.attributes().is_empty());

    let normal_map = m.matrix3.inverse().transpose();
    let flat_tris: Vec<[Vec3; 3]> = tris
        .iter()
        .map(|t| t.map(|v| m.transform_point3(v)))
        .collect();
    let mut flat = SceneGeometry::build(flat_tris, Vec::new());
    let mut fa = MeshAttributes::default();
    fa.push(
        0,
        VertexAttributes {
            normals: normals_per_corner
                .iter()
                .map(|&n| Vec3::from(normal_map * Vec3A::from(n)).normalize())
                .collect(),
            uvs,
            corners: uv_corners,
            shadow_terminator_offset: true,
        },
    );
    flat.set_attributes(fa);

    let mut rng = Rng(11);
    let mut checked = 0;
    for _ in 0..1000 {
        let o = rand_vec(&mut rng, -6.0, 6.0);
        let d = (m.transform_point3(rand_vec(&mut rng, -0.5, 0.5)) - o).normalize();
        let (ti, pi, b1i, b2i) = closest(&inst, &[o], &[d], 0.0);
        let (tf, pf, b1f, b2f) = closest(&flat, &[o], &[d], 0.0);
        if pi[0] == NO_HIT {
            continue;
        }
        assert_eq!(pf[0], pi[0]);
        let si = inst.surface_at(pi[0], o, d, ti[0], b1i[0], b2i[0]);
        let sf = flat.surface_at(pf[0], o, d, tf[0], b1f[0], b2f[0]);
        let ai = inst
            .mesh_shading(pi[0], b1i[0], b2i[0], si.ng)
            .expect("attributes");
        let af = flat
            .mesh_shading(pf[0], b1f[0], b2f[0], sf.ng)
            .expect("attributes");
        assert!(ai.nn.dot(af.nn) > 0.9999, "nn {} vs {}", ai.nn, af.nn);
        assert!((ai.uv.unwrap() - af.uv.unwrap()).abs().max_element() < 1e-4);
        assert!(
            ai.tangent.dot(af.tangent) > 0.999,
            "tangent {} vs {}",
            ai.tangent,
            af.tangent
        );
        // The shadow-terminator data: vertices placed, normals mapped like the flat mesh's.
        let (vi, ni) = inst.terminator_triangle(pi[0]).expect("offset asked for");
        let (vf, nf) = flat.terminator_triangle(pf[0]).expect("offset asked for");
        for k in 0..3 {
            assert!((vi[k] - vf[k]).length() < 1e-4, "v {} vs {}", vi[k], vf[k]);
            assert!(ni[k].dot(nf[k]) > 0.9999, "n {} vs {}", ni[k], nf[k]);
        }
        checked += 1;
    }
    assert!(checked > 100);
}

/// Memory scales with the object, not with the instances: a thousand instances of a mesh
/// cost the object once plus a few hundred bytes each.
#[test]
fn instances_share_their_object() {
    let mut tris = Vec::new();
    for i in 0..2000 {
        let c = Vec3::new((i % 50) as f32, (i / 50) as f32, 0.0);
        tris.push([c, c + Vec3::X, c + Vec3::Y]);
    }
    let object = SceneGeometry::build(tris.clone(), Vec::new());
    let one = SceneGeometry::build(tris, Vec::new()).memory_bytes();
    let instances: Vec<(u32, Affine3A)> = (0..1000)
        .map(|k| {
            (
                0,
                Affine3A::from_translation(Vec3::new(0.0, 0.0, k as f32 * 2.0)),
            )
        })
        .collect();
    let g = SceneGeometry::build_with_instances(Vec::new(), Vec::new(), vec![object], &instances);
    assert_eq!(g.num_prims(), 2_000_000);
    let per_instance = (g.memory_bytes() - one) / 1000;
    assert!(per_instance < 600, "{per_instance} bytes per instance");
    // A flat copy would hold at least the 64-byte triangle records of every copy.
    assert!(g.memory_bytes() * 50 < 2_000_000 * 64);
    let (k, j) = g.instance_of(1_234_567).unwrap();
    assert_eq!((k, j), (617, 567));
}

/// Clearance through instances is a lower bound of the true distance: at most the flat
/// copy's clearance, and for rigid placements at least that over `sqrt(3)` (the Frobenius
/// norm of a rotation, which the bound divides by).
#[test]
fn instanced_clearance_bounds_the_flat_clearance() {
    let tris = octahedron();
    let object = SceneGeometry::build(tris.clone(), Vec::new());
    let rigid = [
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(2.0, 0.0, 0.0)),
        Affine3A::from_rotation_translation(Quat::from_rotation_x(1.2), Vec3::new(-2.0, 1.0, 0.0)),
    ];
    let placements: Vec<(u32, Affine3A)> = rigid.iter().map(|&m| (0, m)).collect();
    let inst =
        SceneGeometry::build_with_instances(Vec::new(), Vec::new(), vec![object], &placements);
    let flat_tris: Vec<[Vec3; 3]> = rigid
        .iter()
        .flat_map(|m| tris.iter().map(move |t| t.map(|v| m.transform_point3(v))))
        .collect();
    let flat = SceneGeometry::build(flat_tris, Vec::new());
    let mut rng = Rng(5);
    for _ in 0..500 {
        let p = rand_vec(&mut rng, -5.0, 5.0);
        let ci = crate::clearance::clearance(&inst, p, 100.0);
        let cf = crate::clearance::clearance(&flat, p, 100.0);
        assert!(ci <= cf * (1.0 + 1e-5) + 1e-6, "at {p}: {ci} vs flat {cf}");
        assert!(
            ci >= cf / 3f32.sqrt() * (1.0 - 1e-5) - 1e-6,
            "at {p}: {ci} vs flat {cf}"
        );
    }
}
