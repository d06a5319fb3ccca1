//! Instances: an object's geometry, built once in object space, placed in the world by an
//! affine map, as many times as a scene asks (pbrt-v4's `ObjectInstance`, Mitsuba 3's
//! `instance` of a `shapegroup`).
//!
//! A hit on an instanced primitive is found in object space (the traversal maps the ray
//! there, see [`ray_to_object`]) and everything a hit gives downstream is computed there
//! by the object's own [`SceneGeometry`] and mapped back: the point (with its rounding
//! bound grown through the map, pbrt-v4 sec. 6.8.6), normals by the inverse transpose,
//! tangents by the map itself. Memory: one [`Instance`] per instance, nothing per
//! instanced primitive.

use glam::{Affine3A, DAffine3, DVec3, Mat3A, Vec2, Vec3, Vec3A};

use super::{gamma, SceneGeometry, SurfaceSample, UNDERFLOW};
use crate::mesh_attributes::{arbitrary_tangent, sphere_tangent, MeshShading};

/// One placement of an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index of the object (into the objects given to
    /// [`SceneGeometry::build_with_instances`]).
    pub object: u32,
    /// Object to world.
    pub to_world: Affine3A,
    /// World to object: the inverse of `to_world`, inverted in double precision.
    pub to_object: Affine3A,
    /// Primitive index of the object's primitive 0 in this instance.
    pub prim_base: u32,
}

/// The instances of a build and their world boxes.
pub(super) struct Placed {
    pub(super) instances: Vec<Instance>,
    /// World box of each instance (its object's box mapped by `to_world`, unpadded).
    pub(super) boxes: Vec<(Vec3, Vec3)>,
}

/// Numbers the instances' primitives from `first` and bounds them (see
/// [`SceneGeometry::build_with_instances`] for the panics).
pub(super) fn place(
    objects: &[SceneGeometry],
    placements: &[(u32, Affine3A)],
    first: u32,
) -> Placed {
    for o in objects {
        assert!(o.instances.is_empty(), "an object holds instances");
        assert!(o.bvh8.is_some(), "an object is empty");
    }
    let mut next = u64::from(first);
    let mut instances = Vec::with_capacity(placements.len());
    let mut boxes = Vec::with_capacity(placements.len());
    for &(object, to_world) in placements {
        let o = &objects[object as usize];
        let d = DAffine3::from_mat3_translation(
            glam::Mat3::from(to_world.matrix3).as_dmat3(),
            Vec3::from(to_world.translation).as_dvec3(),
        );
        let det = d.matrix3.determinant();
        assert!(det.is_finite() && det != 0.0, "a singular instance map");
        let inv = d.inverse();
        let to_object =
            Affine3A::from_mat3_translation(inv.matrix3.as_mat3(), inv.translation.as_vec3());
        assert!(next < u64::from(u32::MAX), "too many primitives: {next}");
        instances.push(Instance {
            object,
            to_world,
            to_object,
            prim_base: next as u32,
        });
        next += o.num_prims() as u64;
        assert!(next < u64::from(u32::MAX), "too many primitives: {next}");
        // The box's eight corners through the map, in double precision, rounded outwards
        // by the caller's padding.
        let (lo, hi) = o.bounds();
        let (mut blo, mut bhi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for c in 0..8 {
            let pick = |bit: usize, a: f32, b: f32| if c & bit == 0 { a } else { b };
            let corner = DVec3::new(
                pick(1, lo.x, hi.x) as f64,
                pick(2, lo.y, hi.y) as f64,
                pick(4, lo.z, hi.z) as f64,
            );
            let w = d.transform_point3(corner);
            blo = blo.min(w);
            bhi = bhi.max(w);
        }
        boxes.push((blo.as_vec3(), bhi.as_vec3()));
    }
    Placed { instances, boxes }
}

/// The ray `origin + t direction` in an instance's object space (`to_object` its world to
/// object map): the direction is mapped as a vector and not renormalised, so a point at
/// parameter `t` maps to the object-space point at the same `t`. The traversal and
/// [`SceneGeometry::surface_at`] both map rays with this function, so the object-space
/// ray a hit was found with is recomputed bit for bit.
#[inline(always)]
pub(crate) fn ray_to_object(to_object: &Affine3A, origin: Vec3, direction: Vec3) -> (Vec3, Vec3) {
    (
        to_object.transform_point3(origin),
        to_object.transform_vector3(direction),
    )
}

impl Instance {
    /// `|to_world|` entry by entry: the error terms of mapped points use it.
    fn abs_matrix(&self) -> Mat3A {
        let m = self.to_world.matrix3;
        Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
    }

    /// A unit object-space normal mapped to the world: by the inverse transpose (the
    /// transpose of `to_object`'s linear part), normalised. This keeps outward normals
    /// outward under mirroring (a surface's side is `d . n`, and `d_w . M^-T n = (M^-1
    /// d_w) . n`).
    #[inline]
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        (self.to_object.matrix3.transpose() * Vec3A::from(n))
            .normalize_or_zero()
            .into()
    }

    /// An object-space surface sample mapped to the world. The point's error bound grows
    /// through the map as pbrt-v4 sec. 6.8.6 ("Transforming points with error bounds")
    /// derives it: with `M` the linear part, `T` the translation and `e` the object-space
    /// bound, `(1 + gamma(3)) |M| e + gamma(3) (|M| |p| + |T|)` per component; here with
    /// `gamma(4)` (glam's sum of three products and the translation is four roundings) and
    /// a subnormal for products that underflow.
    #[inline]
    pub fn surface_to_world(&self, s: SurfaceSample) -> SurfaceSample {
        let abs_m = self.abs_matrix();
        let g = gamma(4.0);
        let p_error = abs_m * Vec3A::from(s.p_error) * (1.0 + g)
            + (abs_m * Vec3A::from(s.p.abs()) + self.to_world.translation.abs()) * g
            + Vec3A::splat(UNDERFLOW);
        SurfaceSample {
            p: self.to_world.transform_point3(s.p),
            ng: self.normal_to_world(s.ng),
            uv: s.uv,
            p_error: p_error.into(),
        }
    }

    /// An object-space tangent mapped to the world (by the map itself: tangents are
    /// differences of points) and made orthogonal to the world shading normal `nn`;
    /// [`arbitrary_tangent`] of `nn` if that degenerates.
    #[inline]
    pub fn tangent_to_world(&self, tangent: Vec3, nn: Vec3) -> Vec3 {
        let t = self.to_world.transform_vector3(tangent);
        let ortho = t - nn * nn.dot(t);
        let len2 = ortho.length_squared();
        if len2 > 1e-20 * t.length_squared() && len2.is_finite() {
            ortho / len2.sqrt()
        } else {
            arbitrary_tangent(nn)
        }
    }
}

impl SceneGeometry {
    /// The instance (index into [`Self::instances`]) and the object's primitive that
    /// primitive `prim` is, or `None` for a primitive outside instances. A binary search
    /// over the instances' first primitives.
    #[inline]
    pub fn instance_of(&self, prim: u32) -> Option<(usize, u32)> {
        if (prim as usize) < self.num_flat_prims() || self.instances.is_empty() {
            return None;
        }
        let k = self.instances.partition_point(|i| i.prim_base <= prim) - 1;
        Some((k, prim - self.instances[k].prim_base))
    }

    /// Number of instances.
    pub fn num_instances(&self) -> usize {
        self.instances.len()
    }

    /// The instances, in primitive order.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// The objects instances place (empty without instances).
    pub fn objects(&self) -> &[SceneGeometry] {
        &self.objects
    }

    /// Number of primitives `instances` would add to a scene with these `objects` (each
    /// `(object, _)` adds its object's [`Self::num_prims`]): what a caller checks against
    /// the `u32` primitive index before [`Self::build_with_instances`].
    pub fn count_instanced_prims(objects: &[SceneGeometry], instances: &[(u32, Affine3A)]) -> u64 {
        instances
            .iter()
            .map(|(o, _)| objects[*o as usize].num_prims() as u64)
            .sum()
    }

    /// Instance, object and object-space ray of a hit on instanced primitive `prim`.
    #[inline]
    fn instanced(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
    ) -> (&Instance, &SceneGeometry, u32, Vec3, Vec3) {
        let (k, local) = self.instance_of(prim).expect("a primitive of an instance");
        let inst = &self.instances[k];
        let (o, d) = ray_to_object(&inst.to_object, origin, direction);
        (inst, &self.objects[inst.object as usize], local, o, d)
    }

    /// [`Self::surface_at`] on a primitive of an instance.
    pub(super) fn instance_surface_at(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> SurfaceSample {
        let (inst, object, local, o, d) = self.instanced(prim, origin, direction);
        inst.surface_to_world(object.surface_at(local, o, d, t, b1, b2))
    }

    /// [`Self::hit_is_front`] on a primitive of an instance: the object-space test, since
    /// `d_w . M^-T n = d_o . n` has the same sign.
    pub(super) fn instance_hit_is_front(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
    ) -> bool {
        let (_, object, local, o, d) = self.instanced(prim, origin, direction);
        object.hit_is_front(local, o, d, t, b1)
    }

    /// [`Self::surface_uv`] on a primitive of an instance: its object's parameters.
    pub(super) fn instance_surface_uv(
        &self,
        prim: u32,
        origin: Vec3,
        direction: Vec3,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> Vec2 {
        let (_, object, local, o, d) = self.instanced(prim, origin, direction);
        object.surface_uv(local, o, d, t, b1, b2)
    }

    /// Whether some mesh, outside instances or in an object, has vertex normals or texture
    /// coordinates ([`Self::mesh_shading`] is `None` everywhere otherwise).
    #[inline]
    pub fn has_attributes(&self) -> bool {
        self.any_attributes
    }

    /// What a mesh's vertex attributes give at a hit on primitive `prim` with barycentrics
    /// `(b1, b2)` and world geometric normal `ng` ([`crate::mesh_attributes::MeshAttributes::shading`]),
    /// or `None` when `prim` is not a triangle of a mesh with attributes. On an instance the
    /// object's normals are mapped as normals are (by the inverse transpose, before they
    /// are normalised and turned to `ng`'s side) and the tangent is `dpdu` of the mapped
    /// triangle ([`crate::mesh_attributes::MeshAttributes::shading_mapped`]); uvs are the
    /// object's.
    #[inline]
    pub fn mesh_shading(&self, prim: u32, b1: f32, b2: f32, ng: Vec3) -> Option<MeshShading> {
        if (prim as usize) < self.tri_slots.len() {
            return self
                .attributes
                .shading(prim, b1, b2, self.triangle(prim as usize), ng);
        }
        let (k, local) = self.instance_of(prim)?;
        let inst = &self.instances[k];
        let object = &self.objects[inst.object as usize];
        if local as usize >= object.tri_slots.len() {
            return None;
        }
        let v = object
            .triangle(local as usize)
            .map(|p| inst.to_world.transform_point3(p));
        let normal_map = inst.to_object.matrix3.transpose();
        object.attributes.shading_mapped(local, b1, b2, v, ng, |n| {
            (normal_map * Vec3A::from(n)).into()
        })
    }

    /// The world-space vertices and unit vertex normals (the stored ones mapped as normals
    /// are, by the inverse transpose on an instance, and normalised; zero where a stored
    /// normal is zero) of triangle `prim` when its mesh has vertex normals and asks for the
    /// shadow-terminator offset ([`crate::terminator`]); `None` for every other primitive.
    /// Normals keep the file's orientation: [`crate::terminator::terminator_lift`] turns
    /// them to the side it needs.
    #[inline]
    pub fn terminator_triangle(&self, prim: u32) -> Option<([Vec3; 3], [Vec3; 3])> {
        if (prim as usize) < self.tri_slots.len() {
            let n = self.attributes.terminator_normals(prim)?;
            return Some((self.triangle(prim as usize), n));
        }
        let (k, local) = self.instance_of(prim)?;
        let inst = &self.instances[k];
        let object = &self.objects[inst.object as usize];
        if local as usize >= object.tri_slots.len() {
            return None;
        }
        let n = object.attributes.terminator_normals(local)?;
        let v = object
            .triangle(local as usize)
            .map(|p| inst.to_world.transform_point3(p));
        let normal_map = inst.to_object.matrix3.transpose();
        let n = n.map(|n| Vec3::from(normal_map * Vec3A::from(n)).normalize_or_zero());
        Some((v, n))
    }

    /// The tangent of a hit on primitive `prim` that is not a triangle outside instances
    /// (a sphere, or any primitive of an instance), with world normal `ng`: a sphere's
    /// direction of increasing `phi` ([`sphere_tangent`], mapped to the world on an
    /// instance), [`arbitrary_tangent`] of `ng` on an instanced triangle.
    #[inline]
    pub fn tangent_at(&self, prim: u32, ng: Vec3) -> Vec3 {
        let Some((k, local)) = self.instance_of(prim) else {
            return sphere_tangent(ng);
        };
        let inst = &self.instances[k];
        let object = &self.objects[inst.object as usize];
        if (local as usize) < object.tri_slots.len() {
            return arbitrary_tangent(ng);
        }
        // The object-space normal: normals map back by the transpose of `to_world`.
        let n_obj = (inst.to_world.matrix3.transpose() * Vec3A::from(ng)).normalize_or_zero();
        inst.tangent_to_world(sphere_tangent(n_obj.into()), ng)
    }

    /// Whether primitive `prim` is a sphere (outside instances or in one).
    #[inline]
    pub fn is_sphere(&self, prim: u32) -> bool {
        match self.instance_of(prim) {
            None => prim as usize >= self.tri_slots.len(),
            Some((k, local)) => {
                let object = &self.objects[self.instances[k].object as usize];
                local as usize >= object.tri_slots.len()
            }
        }
    }

    /// Bytes the objects hold (each once: its triangles, spheres, attributes and BVH); the
    /// rest of [`Self::memory_bytes`] is the flat geometry, the top-level BVH and the
    /// instances.
    pub fn object_bytes(&self) -> usize {
        self.objects.iter().map(Self::memory_bytes).sum::<usize>()
    }

    /// Bytes this geometry holds: triangles, spheres, the BVH, mesh attributes, and the
    /// objects and instances (an object counted once, however many instances place it).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        size_of::<Self>()
            + self.tri_slots.capacity() * size_of::<u32>()
            + self.spheres.capacity() * size_of::<super::Sphere>()
            + self.bvh8.as_ref().map_or(0, |b| b.bytes())
            + self.attributes.bytes()
            + self.objects.iter().map(Self::memory_bytes).sum::<usize>()
            + self.instances.capacity() * size_of::<Instance>()
    }
}
