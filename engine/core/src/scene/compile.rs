//! [`Scene::compile`]: the world flattened into a [`CompiledScene`], with the checks that
//! need every entity at once (coincident shapes, the camera's volume stack).

use super::*;
use risotto_systems::geometry::TriangleSet;
use risotto_systems::mesh_attributes::MeshAttributes;

/// A triangle shape's vertex attributes, pushed after the build in primitive order.
struct ShapeAttributes {
    /// The shape's first primitive.
    first: u32,
    attributes: VertexAttributes,
    /// Set when the attributes' corners are the mesh's own triangles' indices: the mesh
    /// lends them to the build rather than holding two copies while the tree is built, and
    /// gets them back after it (issue 36: 24 MB of the 2M-triangle mesh's peak).
    lent: Option<LentCorners>,
}

/// Where a mesh's lent corners are in the build's indices.
struct LentCorners {
    /// The mesh's triangles.
    count: usize,
    /// The set's number of the mesh's first vertex.
    base: u32,
}

impl Scene {
    /// Flattens the world into a [`CompiledScene`].
    pub fn compile(self) -> Result<CompiledScene, CompileError> {
        self.settings.check(&self.camera)?;
        // What loading freed (a mesh file's parse tables and its f64 data) is handed back
        // before the build allocates its boxes and tree (issue 36, peak memory).
        crate::memory::release_freed_pages();
        let Scene {
            files,
            warnings: read_warnings,
            mut world,
            materials,
            camera,
            settings,
            camera_volume,
            camera_volume_at,
            within_checks,
            objects,
            source: _,
        } = self;
        // Shapes in spawn order (hecs iteration order is by archetype; sort by entity id so
        // primitive numbering is stable).
        let mut shape_entities: Vec<(hecs::Entity, String, ShapeGeometry, u32, Option<Rgb>)> =
            Vec::new();
        // The geometry is moved out of the world, not copied: a mesh's triangles are the
        // largest thing a scene holds, and the world is dropped with the compiled scene's
        // build (issue 36, peak memory).
        for (e, (name, geom, mat, emission)) in
            world.query_mut::<(&Name, &mut ShapeGeometry, &MaterialRef, Option<&Emission>)>()
        {
            let geom = std::mem::replace(geom, ShapeGeometry::Triangles(Vec::new()));
            shape_entities.push((e, name.0.clone(), geom, mat.0, emission.map(|em| em.0)));
        }
        shape_entities.sort_by_key(|s| s.0.id());
        let mut transforms: Vec<Option<glam::Affine3A>> = shape_entities
            .iter()
            .map(|s| world.get::<&ObjectTransform>(s.0).ok().map(|t| t.0))
            .collect();
        let mut warnings = read_warnings;
        let hidden = hidden_coincident_shapes(&shape_entities, &materials, &mut warnings)?;

        let mut triangles = TriangleSet::default();
        // Each shape's triangle count, expanded to one shape per triangle after the build:
        // 4 bytes a triangle fewer at the build's peak (issue 36).
        let mut tri_shape_runs: Vec<(u32, usize)> = Vec::new();
        let mut spheres = Vec::new();
        let mut sphere_shape = Vec::new();
        let mut shapes = Vec::new();
        let mut attributes = MeshAttributes::default();
        // Each triangle shape's vertex attributes, pushed after the build in primitive order.
        let mut shape_attributes: Vec<ShapeAttributes> = Vec::new();
        for (i, (entity, name, geom, mat, emission)) in shape_entities.into_iter().enumerate() {
            if mat as usize >= materials.len() {
                return Err(CompileError::MissingMaterial {
                    shape: name,
                    index: mat,
                });
            }
            match geom {
                // A hidden shape keeps its index and name, but has no primitive to hit.
                _ if hidden[i] => {}
                ShapeGeometry::Sphere(s) => {
                    spheres.push(s);
                    sphere_shape.push(i as u32);
                }
                ShapeGeometry::Triangles(_) | ShapeGeometry::Mesh(_) => {
                    let first = triangles.len() as u32;
                    let count = geom.num_triangles();
                    let mut attrs = world.remove_one::<VertexAttributes>(entity).ok();
                    tri_shape_runs.push((i as u32, count));
                    // The first shape's vectors are moved, not copied (issue 36, peak memory).
                    let lent = match geom {
                        ShapeGeometry::Mesh(m) => {
                            let lends = attrs.as_ref().is_some_and(|a| a.corners == m.triangles);
                            if let (Some(a), true) = (&mut attrs, lends) {
                                a.corners = Vec::new();
                            }
                            let base = triangles.push_mesh(m);
                            lends.then_some(LentCorners { count, base })
                        }
                        ShapeGeometry::Triangles(t) => {
                            triangles.push_soup(t);
                            None
                        }
                        ShapeGeometry::Sphere(_) => unreachable!("matched above"),
                    };
                    if let Some(attributes) = attrs {
                        shape_attributes.push(ShapeAttributes {
                            first,
                            attributes,
                            lent,
                        });
                    }
                }
            }
            shapes.push(ShapeInfo {
                name,
                material: mat,
                emission,
            });
        }
        let num_tris = triangles.len();
        let num_flat_shapes = shapes.len();
        let objects = instances::compile_objects(
            objects,
            &world,
            &materials,
            num_flat_shapes,
            triangles.len() + spheres.len(),
        )?;
        shapes.extend(objects.shapes);
        transforms.resize(shapes.len(), None);
        let (mut geometry, mut indices) = SceneGeometry::build_set_keeping_indices(
            triangles,
            spheres,
            objects.geometries,
            &objects.placements,
        );
        // The meshes that lent their corners to the build get them back (their own vertex
        // numbers: the set numbered a mesh's vertices from `base`).
        for ShapeAttributes {
            first,
            attributes: mut a,
            lent,
        } in shape_attributes
        {
            if let Some(LentCorners { count, base }) = lent {
                let start = first as usize;
                a.corners = if start == 0 && base == 0 && count == indices.len() {
                    std::mem::take(&mut indices)
                } else {
                    let own = &indices[start..start + count];
                    own.iter().map(|t| t.map(|k| k - base)).collect()
                };
            }
            attributes.push(first, a);
        }
        drop(indices);
        // The build's inputs (a mesh's vertices and indices, the primitives' boxes) are freed;
        // the tables compiled next would otherwise sit on top of their retained pages, and the
        // peak be theirs and the tree's together (2M-triangle mesh: 243 -> 234 MB, issue 36).
        crate::memory::release_freed_pages();
        let mut features = Features {
            vertex_normals: attributes.any_normals() || objects.any_normals,
            terminator_offset: attributes.any_terminator_offset() || objects.any_terminator_offset,
            ..Features::default()
        };
        geometry.set_attributes(attributes);
        let mut prim_shape = Vec::with_capacity(num_tris + sphere_shape.len());
        for (shape, count) in tri_shape_runs {
            prim_shape.extend(std::iter::repeat_n(shape, count));
        }
        prim_shape.extend(sphere_shape);

        let (lo, hi) = geometry.bounds();
        let (center, radius) = if lo.cmple(hi).all() {
            // No absolute floor beyond keeping radius^2 a normal f32: the lights at infinity
            // are priced by pi radius^2 (systems::lights), and a floor of 1e-3 made the sky
            // of a scene 1e-6 across a million times brighter than its point light, which
            // was then almost never selected (issue 14 item 8).
            ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-18))
        } else {
            (Vec3::ZERO, 1.0)
        };

        let mut lights = Vec::new();
        for (prim, &s) in prim_shape.iter().enumerate() {
            if let Some(radiance) = shapes[s as usize].emission {
                if !radiance.is_black() {
                    lights.push(Light::Area {
                        prim: prim as u32,
                        radiance,
                    });
                    features.area_lights = true;
                }
            }
        }
        let mut light_entities: Vec<(hecs::Entity, LightComponent)> = world
            .query::<&LightComponent>()
            .iter()
            .map(|(e, l)| (e, l.clone()))
            .collect();
        light_entities.sort_by_key(|l| l.0.id());
        for (_, l) in light_entities {
            lights.push(match l {
                LightComponent::Distant {
                    direction,
                    irradiance,
                } => {
                    features.distant_lights = true;
                    Light::Distant {
                        direction,
                        irradiance,
                    }
                }
                LightComponent::Point {
                    position,
                    intensity,
                } => {
                    features.point_lights = true;
                    Light::Point {
                        position,
                        intensity,
                    }
                }
                LightComponent::Spot {
                    position,
                    direction,
                    intensity,
                    cutoff_angle,
                    beam_width,
                    texture,
                } => {
                    features.spot_lights = true;
                    let direction = direction.normalize();
                    let texture = match texture {
                        None => None,
                        Some((image, up)) => Some(Arc::new(
                            SpotTexture::new(
                                (*image).clone(),
                                direction,
                                up,
                                cutoff_angle.to_radians(),
                            )
                            .ok_or_else(|| CompileError::Invalid {
                                entity: "spot light".into(),
                                message: format!(
                                    "`up` {up} is parallel to the direction {direction}: it \
                                     cannot orient the texture"
                                ),
                            })?,
                        )),
                    };
                    Light::Spot {
                        position,
                        direction,
                        intensity,
                        falloff: SpotFalloff::from_degrees(cutoff_angle, beam_width),
                        texture,
                    }
                }
                LightComponent::Environment { radiance, map } => {
                    features.environment = true;
                    Light::Environment {
                        radiance,
                        map: map.map(|m| Box::new((*m).clone())),
                    }
                }
            });
        }
        let mis_lights =
            LightSet::with_environment_sampling(lights.clone(), &geometry, radius, false);
        let lights = LightSet::new(lights, &geometry, radius);

        let material_info: Vec<MaterialInfo> = materials
            .iter()
            .map(|m| MaterialInfo {
                hints: m.factory.instance_hints(),
                priority: m.priority,
                ior: m.factory.ior(),
                shadow_transmittance: m.factory.shadow_transmittance(),
            })
            .collect();
        // Only materials some shape uses decide the features.
        let mut used = vec![false; materials.len()];
        for s in &shapes {
            used[s.material as usize] = true;
        }
        for (info, _) in material_info.iter().zip(&used).filter(|(_, &u)| u) {
            let h = info.hints;
            features.volumes |= h.contains(InstanceHints::COMPUTES_INTERIOR);
            features.transmissive |=
                h.contains(InstanceHints::TRANSMITS) || h.contains(InstanceHints::INDEX_MATCHED);
            features.scattering_media |= h.contains(InstanceHints::INTERIOR_SCATTERS);
            features.heterogeneous |= h.contains(InstanceHints::INTERIOR_HETEROGENEOUS);
            features.subsurface |= h.contains(InstanceHints::INTERIOR_SUBSURFACE);
            features.emissive_media |= h.contains(InstanceHints::INTERIOR_EMITS);
            features.transmission_shadows |= h.contains(InstanceHints::TRANSMISSION_SHADOWS);
            features.surface_uv |= h.contains(InstanceHints::READS_SURFACE_UV);
            features.opacity |= h.contains(InstanceHints::OPACITY);
        }

        let prim_material = prim_shape
            .iter()
            .map(|&s| shapes[s as usize].material)
            .collect();
        let mut compiled = CompiledScene {
            files: files.paths(),
            geometry,
            prim_shape,
            prim_material,
            instanced: objects.numbering,
            shapes,
            materials,
            material_info,
            lights,
            mis_lights,
            lights_with_volumes: None,
            camera,
            settings,
            features,
            camera_stack: VolumeStack::new(),
            radius,
            center,
            shape_tracked: Vec::new(),
            shape_entry: Vec::new(),
            shape_bounds: Vec::new(),
            shape_space: Vec::new(),
            volume_light: Vec::new(),
            warnings,
        };
        let empty = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut bounds = vec![empty; num_flat_shapes];
        // Instances' shapes: their object-space bounds mapped (they hold no volumes).
        bounds.extend(objects.bounds);
        let mut object_bounds = bounds.clone();
        // The inverse transforms in double precision: object bounds as exact as the f32
        // vertices allow (a unit box turned 90 degrees maps back to [0, 1], not 0.99999994).
        let inverses: Vec<Option<glam::DAffine3>> = transforms
            .iter()
            .map(|t| t.map(|t| to_daffine(t).inverse()))
            .collect();
        let g = &compiled.geometry;
        for (p, &shape) in compiled.prim_shape.iter().enumerate() {
            let inverse = inverses[shape as usize].as_ref();
            let ((lo, hi), (olo, ohi)) = if p < g.num_triangles() {
                let v = g.triangle(p);
                let world = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
                let object = match inverse {
                    None => world,
                    Some(m) => {
                        let o = v.map(|q| m.transform_point3(q.as_dvec3()));
                        let (a, b) = (o[0].min(o[1]).min(o[2]), o[0].max(o[1]).max(o[2]));
                        (a.as_vec3(), b.as_vec3())
                    }
                };
                (world, object)
            } else {
                let s = g.sphere(p - g.num_triangles());
                let world = (
                    s.center - Vec3::splat(s.radius),
                    s.center + Vec3::splat(s.radius),
                );
                let object = match inverse {
                    None => world,
                    Some(m) => {
                        // The ball maps to an ellipsoid, whose half extent along object
                        // axis i is the radius times the length of row i of the linear part.
                        let c = m.transform_point3(s.center.as_dvec3());
                        let rows = m.matrix3.transpose();
                        let half = glam::DVec3::new(
                            rows.x_axis.length(),
                            rows.y_axis.length(),
                            rows.z_axis.length(),
                        ) * f64::from(s.radius);
                        ((c - half).as_vec3(), (c + half).as_vec3())
                    }
                };
                (world, object)
            };
            let b = &mut bounds[shape as usize];
            *b = (b.0.min(lo), b.1.max(hi));
            let b = &mut object_bounds[shape as usize];
            *b = (b.0.min(olo), b.1.max(ohi));
        }
        compiled.shape_space = (0..bounds.len())
            .map(|s| match transforms[s] {
                None => crate::plugin::VolumeSpace::world(bounds[s].0, bounds[s].1),
                Some(t) => crate::plugin::VolumeSpace::new(object_bounds[s], bounds[s], t),
            })
            .collect();
        compiled.shape_bounds = bounds;
        compiled.add_volume_lights();
        let shapes = 0..compiled.shapes.len() as u32;
        compiled.shape_tracked = shapes
            .clone()
            .map(|s| compiled.tracks_interior(s))
            .collect();
        compiled.shape_entry = shapes.map(|s| compiled.volume_entry(s)).collect();
        let probed = compiled.probe_stack(camera.from, camera.forward);
        compiled.camera_stack = match camera_volume {
            Some(names) => {
                let fail = |message: String| match &camera_volume_at {
                    Some(at) => CompileError::Scene(
                        at.error(crate::diagnostics::SceneErrorKind::InvalidValue, message),
                    ),
                    None => CompileError::CameraVolume(message),
                };
                let given = compiled.explicit_stack(&names).map_err(fail)?;
                // A stated stack only states what probing finds (issue 14: a wrong one, say
                // `inside = []` for a camera in fog, rendered every camera ray without the
                // fog and said nothing). The probe is exact for closed shapes; a shape that
                // is not closed cannot be listed meaningfully anyway.
                if given != probed {
                    let list = |s: &VolumeStack| {
                        let names: Vec<String> = s
                            .entries()
                            .iter()
                            .map(|e| format!("\"{}\"", compiled.shapes[e.shape as usize].name))
                            .collect();
                        format!("[{}]", names.join(", "))
                    };
                    return Err(fail(format!(
                        "the camera is stated to be inside {} (outermost first), but the camera \
                         at {} looking along {} is inside {}; remove `inside` to let the \
                         engine find it, or correct it",
                        list(&given),
                        fmt_point(camera.from),
                        fmt_point(camera.forward),
                        list(&probed)
                    )));
                }
                given
            }
            None => probed,
        };
        for check in &within_checks {
            compiled
                .check_within(check)
                .map_err(|message| match &check.at {
                    Some(at) => CompileError::Scene(
                        at.error(crate::diagnostics::SceneErrorKind::InvalidValue, message),
                    ),
                    None => CompileError::Within(message),
                })?;
        }
        Ok(compiled)
    }
}

/// `t` in double precision.
fn to_daffine(t: glam::Affine3A) -> glam::DAffine3 {
    glam::DAffine3::from_mat3_translation(
        glam::Mat3::from(t.matrix3).as_dmat3(),
        glam::Vec3::from(t.translation).as_dvec3(),
    )
}

/// A point or direction for messages: `(x, y, z)` with the shortest exact digits.
fn fmt_point(p: Vec3) -> String {
    format!("({}, {}, {})", p.x, p.y, p.z)
}

/// The shapes compiling leaves out because an identical one takes their place: among shapes
/// with exactly the same geometry (same sphere, or the same triangles in the same order)
/// whose materials track an interior (glass, media), without emission, only the one of
/// highest priority is built; ties go to the first in file order when the tied shapes share
/// a material, and are an error otherwise.
///
/// Why: crossing one of two coincident surfaces moves the new ray's origin past both (the
/// spawn offset), so the other's crossing is never seen and the volume stacks go wrong. Two
/// identical glass balls rendered visibly unlike one (issue 14 item 10), with warnings of
/// rays leaving shapes they never entered. By the priority rule (Schmidt and Budge 2002) a
/// volume inside one of higher priority never shows, so leaving it out is exact; for equal
/// priorities and one material the shapes are the same solid. Equal priorities with
/// different materials leave undefined which one fills the shape: an error naming both.
/// Emissive shapes are kept (their emission would be lost), as are shapes that track no
/// interior (an opaque surface hides what coincides with it either way).
fn hidden_coincident_shapes(
    shapes: &[(hecs::Entity, String, ShapeGeometry, u32, Option<Rgb>)],
    materials: &[Material],
    warnings: &mut Vec<String>,
) -> Result<Vec<bool>, CompileError> {
    use std::collections::HashMap;
    use std::hash::{Hash, Hasher};
    let mut hidden = vec![false; shapes.len()];
    let candidate = |(_, _, _, mat, emission): &(_, _, _, u32, Option<Rgb>)| {
        let Some(m) = materials.get(*mat as usize) else {
            // Reported as a missing material by the caller.
            return false;
        };
        let h = m.factory.instance_hints();
        emission.is_none_or(|e| e.is_black())
            && (h.contains(InstanceHints::COMPUTES_INTERIOR)
                || h.contains(InstanceHints::TRANSMITS))
    };
    // Group by a hash of the geometry's bits, then compare exactly within a group.
    let bits = |g: &ShapeGeometry, h: &mut std::collections::hash_map::DefaultHasher| match g {
        ShapeGeometry::Sphere(s) => {
            0u8.hash(h);
            s.center.to_array().map(f32::to_bits).hash(h);
            s.radius.to_bits().hash(h);
        }
        // A mesh and the soup of its triangles are the same surface.
        triangles => {
            1u8.hash(h);
            triangles.num_triangles().hash(h);
            for v in triangles.triangles().flatten() {
                v.to_array().map(f32::to_bits).hash(h);
            }
        }
    };
    let same = |a: &ShapeGeometry, b: &ShapeGeometry| match (a, b) {
        (ShapeGeometry::Sphere(a), ShapeGeometry::Sphere(b)) => a == b,
        (ShapeGeometry::Sphere(_), _) | (_, ShapeGeometry::Sphere(_)) => false,
        (a, b) => a.num_triangles() == b.num_triangles() && a.triangles().eq(b.triangles()),
    };
    let mut groups: HashMap<u64, Vec<usize>> = HashMap::new();
    for (i, s) in shapes.iter().enumerate().filter(|(_, s)| candidate(s)) {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        bits(&s.2, &mut h);
        groups.entry(h.finish()).or_default().push(i);
    }
    let mut groups: Vec<Vec<usize>> = groups.into_values().filter(|g| g.len() > 1).collect();
    groups.sort();
    for group in groups {
        // Split a (improbable) hash collision into classes of equal geometry.
        let mut rest = group;
        while let Some(&first) = rest.first() {
            let (class, others): (Vec<usize>, Vec<usize>) = rest
                .iter()
                .partition(|&&j| same(&shapes[j].2, &shapes[first].2));
            rest = others;
            if class.len() < 2 {
                continue;
            }
            let priority = |j: usize| materials[shapes[j].3 as usize].priority;
            let top = class.iter().map(|&j| priority(j)).max().unwrap_or(0);
            let tied: Vec<usize> = class
                .iter()
                .copied()
                .filter(|&j| priority(j) == top)
                .collect();
            let winner = tied[0];
            if let Some(&other) = tied.iter().find(|&&j| shapes[j].3 != shapes[winner].3) {
                return Err(CompileError::Invalid {
                    entity: format!("shape \"{}\"", shapes[other].1),
                    message: format!(
                        "has the same geometry as shape \"{}\" and the same priority ({top}) \
                         but another material (\"{}\" against \"{}\"): which one fills the \
                         shape is undefined; give one material a higher `priority`",
                        shapes[winner].1,
                        materials[shapes[other].3 as usize].name,
                        materials[shapes[winner].3 as usize].name,
                    ),
                });
            }
            for &j in class.iter().filter(|&&j| j != winner) {
                hidden[j] = true;
                warnings.push(format!(
                    "shape \"{}\" has the same geometry as shape \"{}\" and {}: it is left \
                     out (its surface is \"{}\"'s)",
                    shapes[j].1,
                    shapes[winner].1,
                    if priority(j) < top {
                        "a lower priority"
                    } else {
                        "the same material and priority"
                    },
                    shapes[winner].1,
                ));
            }
        }
    }
    Ok(hidden)
}
