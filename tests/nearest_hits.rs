//! `IntegratorContext::nearest_hits` against a per-ray reference: the shading points it
//! builds, their grouping by material and the misses, for rays in vacuum and inside a glass
//! ball (the outside IOR from the volume stack).

use glam::Vec3;
use risotto::builtins::builtin::{BuiltinMaterial, Interior, Surface};
use risotto::components::{Hits, Rays, Rgb, VolumeStack, NO_HIT};
use risotto::components::{RayRow, VolumeEntry};
use risotto::engine::context::RenderContext;
use risotto::engine::plugin::IntegratorContext;
use risotto::engine::scene::{RenderSettings, Scene, ShapeGeometry};
use risotto::engine::shade_groups::{ShadeGroups, ShadingMode};
use risotto::engine::stats::SystemStats;
use risotto::systems::camera::{Camera, Projection};
use risotto::systems::geometry::Sphere;
use risotto::systems::intersect::intersect_closest;
use risotto::systems::sampler::SplitMix64;

fn material(surface: Surface) -> Box<BuiltinMaterial> {
    Box::new(BuiltinMaterial {
        surface,
        interior: Interior::None,
    })
}

fn quad(corner: Vec3, e1: Vec3, e2: Vec3) -> ShapeGeometry {
    let (a, b, c, d) = (corner, corner + e1, corner + e1 + e2, corner + e2);
    ShapeGeometry::Triangles(vec![[a, b, c], [a, c, d]])
}

/// Rays from random points in a box towards random directions, so some escape; a third
/// of them travel inside the glass ball's interior. The second batch goes into the same
/// output, so its rows start after the first batch's; it is the smaller, so the context's
/// hit buffers still hold rows of the first batch past its rays, which it must not read.
#[test]
fn nearest_hits_matches_a_per_ray_reference() {
    let cam = Camera::look_at(
        Projection::Perspective { fov_deg: 40.0 },
        Vec3::new(0.0, 1.0, 5.0),
        Vec3::ZERO,
        Vec3::Y,
        8,
        8,
    )
    .unwrap();
    let mut scene = Scene::new(cam, RenderSettings::default());
    let grey = Surface::Diffuse {
        reflectance: Rgb::splat(0.5),
    };
    // Material 0 is used by no shape (an empty group must not appear).
    scene.add_material("unused", 0, material(grey.clone()));
    let m_floor = scene.add_material("floor", 0, material(grey.clone()));
    let m_glass = scene.add_material(
        "glass",
        1,
        Box::new(BuiltinMaterial {
            surface: Surface::Dielectric {
                ior: 1.5,
                tint: Rgb::WHITE,
                cheap_shadows: false,
            },
            interior: Interior::Null,
        }),
    );
    let m_wall = scene.add_material("wall", 0, material(grey));
    let c = Vec3::new(-2.0, -1.0, -2.0);
    scene.add_shape(
        "floor",
        quad(c, 4.0 * Vec3::Z, 4.0 * Vec3::X),
        m_floor,
        None,
    );
    scene.add_shape("wall", quad(c, 4.0 * Vec3::X, 3.0 * Vec3::Y), m_wall, None);
    let ball = Sphere {
        center: Vec3::new(0.3, 0.0, 0.1),
        radius: 0.7,
    };
    scene.add_shape("ball", ShapeGeometry::Sphere(ball), m_glass, None);
    scene.add_shape(
        "pebble",
        ShapeGeometry::Sphere(Sphere {
            center: Vec3::new(-1.0, -0.6, 1.0),
            radius: 0.4,
        }),
        m_wall,
        None,
    );
    let scene = scene.compile().unwrap();
    let ball_shape = 2;
    assert_eq!(scene.shapes[ball_shape].material, m_glass);

    let mut rng = SplitMix64(7);
    let mut batches = Vec::new();
    for size in [300, 200] {
        let mut rays = Rays::default();
        for i in 0..size {
            let o = Vec3::new(
                4.0 * rng.f32() - 2.0,
                3.0 * rng.f32() - 1.0,
                4.0 * rng.f32() - 2.0,
            );
            let d = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3::ONE)
                .normalize_or(Vec3::Y);
            let mut volume_stack = VolumeStack::new();
            if i % 3 == 0 {
                volume_stack.enter(VolumeEntry {
                    material: m_glass,
                    shape: ball_shape as u32,
                    priority: 1,
                });
            }
            rays.push(RayRow {
                origin: o,
                direction: d,
                tmin: 0.0,
                tmax: f32::INFINITY,
                volume_stack,
                ..Default::default()
            });
        }
        batches.push(rays);
    }

    let mut stats = SystemStats::default();
    let mut ictx = RenderContext::new(&scene, &mut stats);
    let mut out = ShadeGroups::default();
    let mut bases = Vec::new();
    for rays in &batches {
        bases.push((out.points.len(), out.groups.len(), out.misses.len()));
        ictx.nearest_hits(rays, &mut out);
    }
    assert!(out.points.is_consistent());
    assert_eq!(out.misses.len(), out.miss_transmission.len());

    for (b, rays) in batches.iter().enumerate() {
        let n = rays.len();
        let mut hits = Hits::default();
        hits.append_default(n);
        intersect_closest(
            &scene.geometry,
            &rays.origin,
            &rays.direction,
            &rays.tmin,
            &rays.tmax,
            &mut hits.t,
            &mut hits.prim,
            &mut hits.b1,
            &mut hits.b2,
        );
        let (p0, g0, m0) = bases[b];
        let (p1, g1, m1) = bases.get(b + 1).copied().unwrap_or((
            out.points.len(),
            out.groups.len(),
            out.misses.len(),
        ));
        // Misses: every escaping ray once, in ray order, untouched.
        let misses: Vec<u32> = (0..n as u32)
            .filter(|&i| hits.prim[i as usize] == NO_HIT)
            .collect();
        assert!(!misses.is_empty() && misses.len() < n);
        assert_eq!(out.misses[m0..m1], misses[..]);
        assert!(out.miss_transmission[m0..m1]
            .iter()
            .all(|&t| t == Rgb::WHITE));
        // Groups: one per material that was hit, in material order, tiling the rows.
        let groups = &out.groups[g0..g1];
        let mut hit_materials: Vec<u32> = (0..n)
            .filter(|&i| hits.prim[i] != NO_HIT)
            .map(|i| {
                let shape = scene.prim_shape[hits.prim[i] as usize];
                scene.shapes[shape as usize].material
            })
            .collect();
        hit_materials.sort();
        hit_materials.dedup();
        assert_eq!(
            groups.iter().map(|g| g.material).collect::<Vec<_>>(),
            hit_materials
        );
        assert_eq!(hit_materials, [m_floor, m_glass, m_wall]);
        let mut next = p0;
        for g in groups {
            assert_eq!(g.mode, ShadingMode::Scatter);
            assert_eq!(g.range.start, next);
            assert!(!g.range.is_empty());
            next = g.range.end;
            // Rays in ray order within a group.
            let ids = &out.points.ray_id[g.range.clone()];
            assert!(ids.windows(2).all(|w| w[0] < w[1]));
        }
        assert_eq!(next, p1);
        assert_eq!(p1 - p0 + misses.len(), n);
        // Every row against the ray it came from.
        let pts = &out.points;
        for g in groups {
            for k in g.range.clone() {
                let i = pts.ray_id[k] as usize;
                let prim = hits.prim[i];
                assert_ne!(prim, NO_HIT);
                let shape = scene.prim_shape[prim as usize];
                assert_eq!(scene.shapes[shape as usize].material, g.material);
                assert_eq!(pts.material[k], g.material);
                assert_eq!(pts.shape[k], shape);
                let (o, d, t) = (rays.origin[i], rays.direction[i], hits.t[i]);
                let surf = scene
                    .geometry
                    .surface_at(prim, o, d, t, hits.b1[i], hits.b2[i]);
                assert_eq!(pts.p[k], surf.p);
                assert_eq!(pts.ng[k], surf.ng);
                assert_eq!(pts.p_offset[k], surf.offset());
                assert_eq!(pts.nn[k], surf.ng);
                assert_eq!((pts.u[k], pts.v[k]), (surf.uv.x, surf.uv.y));
                assert!((pts.p[k] - (o + t * d)).length() < 1e-4);
                assert_eq!(pts.vn[k], -d);
                assert_eq!(pts.vlen[k], t);
                assert_eq!(pts.w[k], 0.0);
                assert_eq!(pts.transmission[k], Rgb::WHITE);
                assert_eq!(pts.front_face[k], d.dot(surf.ng) < 0.0);
                // Inside the ball, the medium outside every other shape is glass; the
                // ball's own boundary has vacuum outside.
                let inside = !rays.volume_stack[i].is_empty();
                let ior = if inside && shape != ball_shape as u32 {
                    1.5
                } else {
                    1.0
                };
                assert_eq!(pts.ior_outside[k], ior, "ray {i} shape {shape}");
            }
        }
    }
}
