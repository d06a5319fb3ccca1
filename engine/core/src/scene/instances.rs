//! Objects (shapes defined once, in object space) and their instances (placements by an
//! affine map) in the scene world, and what compiling makes of them: one object geometry
//! per used object, shared by its instances ([`SceneGeometry::build_with_instances`]), and
//! one shape per (instance, object shape) so that the volume stack, false boundaries and
//! per-shape materials work on instances as on any shape. Nothing is stored per instanced
//! primitive: a primitive's shape is its instance's first shape plus its object's shape
//! of the primitive ([`InstancedShapes`]).

use super::*;
use risotto_systems::geometry::TriangleSet;
use risotto_systems::mesh_attributes::MeshAttributes;

/// A shape of an object: its geometry in the object's space.
#[derive(Clone, Debug)]
pub struct ObjectShape {
    /// Name (instances' shapes are named `instance/shape`).
    pub name: String,
    /// Geometry in object space.
    pub geometry: ShapeGeometry,
    /// Material index.
    pub material: u32,
    /// Vertex normals and texture coordinates of a triangle shape (object space; empty for
    /// none).
    pub attributes: VertexAttributes,
}

/// An object: shapes defined once, rendered only where an instance places them.
#[derive(Clone, Debug)]
pub struct ObjectDef {
    /// Name, for messages.
    pub name: String,
    /// Its shapes (at least one).
    pub shapes: Vec<ObjectShape>,
}

/// The component of an instance entity: the index of the object it places (into
/// [`Scene::objects`]); its [`ObjectTransform`] maps object space to the world (absent:
/// the identity).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InstanceOf(pub u32);

/// Shape numbering of the instances' primitives in a compiled scene.
#[derive(Clone, Debug, Default)]
pub struct InstancedShapes {
    /// Per instance (in primitive order): the shape index of its object's shape 0.
    shape_base: Vec<u32>,
    /// Per built object: the object's shape of each of its primitives (memory scales with
    /// the objects, not the instances).
    object_prim_shape: Vec<Vec<u32>>,
}

impl InstancedShapes {
    /// The shape of primitive `prim` of `geometry`, a primitive of an instance.
    ///
    /// # Panics
    /// If `prim` is not a primitive of an instance.
    #[inline(never)]
    pub fn shape_of(&self, geometry: &SceneGeometry, prim: u32) -> u32 {
        let (k, local) = geometry
            .instance_of(prim)
            .expect("a primitive of an instance");
        let object = geometry.instances()[k].object as usize;
        self.shape_base[k] + self.object_prim_shape[object][local as usize]
    }
}

impl Scene {
    /// Adds an object (shapes in object space, not rendered by themselves) and returns its
    /// index for [`Self::add_instance`].
    pub fn add_object(&mut self, name: &str, shapes: Vec<ObjectShape>) -> u32 {
        self.objects.push(ObjectDef {
            name: name.to_string(),
            shapes,
        });
        (self.objects.len() - 1) as u32
    }

    /// Adds an instance entity placing object `object` by `to_world` (any invertible affine
    /// map).
    pub fn add_instance(&mut self, name: &str, object: u32, to_world: Affine3A) -> hecs::Entity {
        let e = self
            .world
            .spawn((Name(name.to_string()), InstanceOf(object)));
        if to_world != Affine3A::IDENTITY {
            self.world
                .insert_one(e, ObjectTransform(to_world))
                .expect("entity was just spawned");
        }
        e
    }
}

/// The objects and instances of a world, compiled.
pub(super) struct CompiledObjects {
    /// The used objects' geometries, in object space.
    pub(super) geometries: Vec<SceneGeometry>,
    /// Per instance: (index into `geometries`, object to world).
    pub(super) placements: Vec<(u32, Affine3A)>,
    /// The instances' shapes, numbered from the `first_shape` given.
    pub(super) shapes: Vec<ShapeInfo>,
    /// World bounds of each of `shapes`.
    pub(super) bounds: Vec<(Vec3, Vec3)>,
    /// Whether some object mesh has vertex normals.
    pub(super) any_normals: bool,
    /// Whether some object mesh with vertex normals asks for the shadow-terminator offset.
    pub(super) any_terminator_offset: bool,
    pub(super) numbering: InstancedShapes,
}

/// Compiles the instances of `world` (entities with [`InstanceOf`], in spawn order) and
/// the objects they place; the instances' shapes are numbered from `first_shape`, their
/// primitives from `first_prim`.
pub(super) fn compile_objects(
    objects: Vec<ObjectDef>,
    world: &hecs::World,
    materials: &[Material],
    first_shape: usize,
    first_prim: usize,
) -> Result<CompiledObjects, CompileError> {
    let invalid = |entity: String, message: String| CompileError::Invalid { entity, message };
    let mut instances: Vec<(hecs::Entity, String, u32, Affine3A)> = world
        .query::<(&Name, &InstanceOf)>()
        .iter()
        .map(|(e, (n, i))| {
            let t = world
                .get::<&ObjectTransform>(e)
                .map_or(Affine3A::IDENTITY, |t| t.0);
            (e, n.0.clone(), i.0, t)
        })
        .collect();
    instances.sort_by_key(|i| i.0.id());
    // Objects are built in index order, unused ones not at all.
    let mut built = vec![u32::MAX; objects.len()];
    for (_, name, object, _) in &instances {
        let b = built.get_mut(*object as usize).ok_or_else(|| {
            invalid(
                format!("instance \"{name}\""),
                format!("object index {object} does not exist"),
            )
        })?;
        *b = 0;
    }
    let mut geometries = Vec::new();
    let mut object_prim_shape = Vec::new();
    let mut object_shape_bounds = Vec::new();
    let mut any_normals = false;
    let mut any_terminator_offset = false;
    for (o, def) in objects.iter().enumerate() {
        if built[o] == u32::MAX {
            continue;
        }
        built[o] = geometries.len() as u32;
        let entity = format!("object \"{}\"", def.name);
        if def.shapes.is_empty() {
            return Err(invalid(entity, "has no shapes".into()));
        }
        let (mut tris, mut tri_shape) = (TriangleSet::default(), Vec::new());
        let (mut spheres, mut sphere_shape) = (Vec::new(), Vec::new());
        let mut attributes = MeshAttributes::default();
        let mut shape_bounds = Vec::with_capacity(def.shapes.len());
        for (s, shape) in def.shapes.iter().enumerate() {
            let Some(m) = materials.get(shape.material as usize) else {
                return Err(CompileError::MissingMaterial {
                    shape: format!("{}/{}", def.name, shape.name),
                    index: shape.material,
                });
            };
            if m.factory
                .instance_hints()
                .contains(InstanceHints::COMPUTES_INTERIOR)
            {
                return Err(invalid(
                    format!("object \"{}\" shape \"{}\"", def.name, shape.name),
                    format!(
                        "material \"{}\" has an interior: area lights / volumes inside objects \
                         are not supported; pbrt-v4 does not support area lights in instances \
                         either (place the shape directly in `shapes`)",
                        m.name
                    ),
                ));
            }
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            match &shape.geometry {
                ShapeGeometry::Sphere(sp) => {
                    spheres.push(*sp);
                    sphere_shape.push(s as u32);
                    (lo, hi) = (
                        sp.center - Vec3::splat(sp.radius),
                        sp.center + Vec3::splat(sp.radius),
                    );
                }
                triangles => {
                    if !shape.attributes.is_empty() {
                        any_normals |= !shape.attributes.normals.is_empty();
                        any_terminator_offset |= !shape.attributes.normals.is_empty()
                            && shape.attributes.shadow_terminator_offset;
                        attributes.push(tris.len() as u32, shape.attributes.clone());
                    }
                    for v in triangles.triangles().flatten() {
                        (lo, hi) = (lo.min(v), hi.max(v));
                    }
                    tri_shape.extend(std::iter::repeat_n(s as u32, triangles.num_triangles()));
                    match triangles {
                        ShapeGeometry::Mesh(m) => {
                            tris.push_mesh(m.clone());
                        }
                        ShapeGeometry::Triangles(t) => tris.push_soup(t.clone()),
                        ShapeGeometry::Sphere(_) => unreachable!("matched above"),
                    }
                }
            }
            shape_bounds.push((lo, hi));
        }
        if tris.is_empty() && spheres.is_empty() {
            return Err(invalid(
                entity,
                "has no primitives (its meshes are empty)".into(),
            ));
        }
        tri_shape.extend(sphere_shape);
        let mut g = SceneGeometry::build_set_with_instances(tris, spheres, Vec::new(), &[]);
        g.set_attributes(attributes);
        geometries.push(g);
        object_prim_shape.push(tri_shape);
        object_shape_bounds.push(shape_bounds);
    }
    let placements: Vec<(u32, Affine3A)> = instances
        .iter()
        .map(|(_, _, o, t)| (built[*o as usize], *t))
        .collect();
    let total = first_prim as u64 + SceneGeometry::count_instanced_prims(&geometries, &placements);
    if total >= u64::from(u32::MAX) {
        return Err(invalid(
            "instances".into(),
            format!(
                "the scene has {total} primitives counting every instance's; at most {} are \
                 supported",
                u32::MAX - 1
            ),
        ));
    }
    let mut shapes = Vec::new();
    let mut bounds = Vec::new();
    let mut shape_base = Vec::with_capacity(instances.len());
    for (_, name, object, to_world) in &instances {
        let def = &objects[*object as usize];
        shape_base.push((first_shape + shapes.len()) as u32);
        for (shape, &(lo, hi)) in def
            .shapes
            .iter()
            .zip(&object_shape_bounds[built[*object as usize] as usize])
        {
            shapes.push(ShapeInfo {
                name: format!("{name}/{}", shape.name),
                material: shape.material,
                emission: None,
            });
            bounds.push(map_box(to_world, lo, hi));
        }
    }
    Ok(CompiledObjects {
        geometries,
        placements,
        shapes,
        bounds,
        any_normals,
        any_terminator_offset,
        numbering: InstancedShapes {
            shape_base,
            object_prim_shape,
        },
    })
}

/// The box `lo..hi` mapped by `m`: the bounds of its eight mapped corners (an empty box,
/// as a shape of no primitive has, stays empty).
fn map_box(m: &Affine3A, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    if !lo.cmple(hi).all() {
        return (lo, hi);
    }
    let (mut a, mut b) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for c in 0..8 {
        let pick = |bit: usize, x: f32, y: f32| if c & bit == 0 { x } else { y };
        let p = m.transform_point3(Vec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        ));
        (a, b) = (a.min(p), b.max(p));
    }
    (a, b)
}
