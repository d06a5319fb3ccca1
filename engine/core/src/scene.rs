//! The scene world (hecs) and its compilation into the flat data the systems read.
//!
//! A scene is an [`hecs::World`] of entities: shapes ([`ShapeGeometry`] + [`MaterialRef`],
//! optionally [`Emission`] and an [`ObjectTransform`]) and lights ([`LightComponent`]), each with a [`Name`]. Materials
//! are factories registered in the [`Scene`] by name. [`Scene::compile`] flattens the world:
//! one BVH over every primitive, a light set, a per-material table of hints, and the
//! [`Features`] that decide which stages the scheduler runs.

pub use crate::features::Features;
use crate::plugin::{BxdfFactory, InstanceHints};
use glam::{Affine3A, Vec3};
use risotto_components::{Rgb, VolumeStack};
use risotto_systems::camera::Camera;
use risotto_systems::environment_map::EnvironmentMap;
pub use risotto_systems::geometry::TriangleMesh;
use risotto_systems::geometry::{SceneGeometry, Sphere};
use risotto_systems::lights::{Light, LightSet, SpotFalloff, SpotTexture};
/// Per-vertex normals and texture coordinates of a [`ShapeGeometry::Triangles`] or
/// [`ShapeGeometry::Mesh`] shape (an optional component of its entity;
/// [`Scene::set_vertex_attributes`]).
pub use risotto_systems::mesh_attributes::VertexAttributes;
use std::sync::Arc;

mod compile;
mod instances;
mod volume_lights;
mod within;

pub use instances::{InstanceOf, InstancedShapes, ObjectDef, ObjectShape};
pub use within::{WithinCheck, NO_MEDIUM};

/// Name of an entity (shape or light), used in messages and stats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Name(pub String);

/// Geometry of a shape entity, in world space.
#[derive(Clone, Debug)]
pub enum ShapeGeometry {
    /// An analytic sphere.
    Sphere(Sphere),
    /// Triangles, one `[Vec3; 3]` each (quads, boxes, disks; any triangles built in code),
    /// wound so `(v1-v0)x(v2-v0)` is the outward (front) normal.
    Triangles(Vec<[Vec3; 3]>),
    /// Triangles over shared vertices, wound as [`Self::Triangles`]: what a mesh file holds.
    /// The same surface as the [`Self::Triangles`] of its triangles, stored once and built
    /// without a weld (issue 36).
    Mesh(TriangleMesh),
}

impl ShapeGeometry {
    /// Number of triangles (0 for a sphere).
    pub fn num_triangles(&self) -> usize {
        match self {
            ShapeGeometry::Sphere(_) => 0,
            ShapeGeometry::Triangles(t) => t.len(),
            ShapeGeometry::Mesh(m) => m.len(),
        }
    }

    /// The vertices of each triangle, in order (none for a sphere).
    pub fn triangles(&self) -> Box<dyn Iterator<Item = [Vec3; 3]> + '_> {
        match self {
            ShapeGeometry::Sphere(_) => Box::new(std::iter::empty()),
            ShapeGeometry::Triangles(t) => Box::new(t.iter().copied()),
            ShapeGeometry::Mesh(m) => Box::new((0..m.len()).map(|i| m.triangle(i))),
        }
    }
}

/// The object-to-world transform of a shape entity: its geometry (always stored in world
/// space) was written in an object space that this maps to the world (a scene file's
/// `transform`). A volume's `u, v, w` and grids are measured in object space
/// ([`crate::plugin::VolumeSpace`]). A shape without this component is written in world
/// coordinates (the identity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectTransform(pub Affine3A);

/// The material (index into [`Scene::materials`]) of a shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialRef(pub u32);

/// Emitted radiance of a shape (an area light, front side only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission(pub Rgb);

/// A light that is not a shape.
#[derive(Clone, Debug)]
pub enum LightComponent {
    /// Distant light.
    Distant {
        /// Direction the light travels (unit).
        direction: Vec3,
        /// Irradiance.
        irradiance: Rgb,
    },
    /// Point light.
    Point {
        /// Position.
        position: Vec3,
        /// Intensity.
        intensity: Rgb,
    },
    /// Spot light (Mitsuba 3's `spot`): a point light whose intensity falls off away from
    /// its axis, linearly in the angle from `beam_width` to `cutoff_angle`
    /// ([`SpotFalloff`]).
    Spot {
        /// Position.
        position: Vec3,
        /// Unit direction of the axis (where the light points).
        direction: Vec3,
        /// Intensity on the axis (W/sr per channel).
        intensity: Rgb,
        /// Half-angle of the lit cone, degrees, in `(0, 90]`.
        cutoff_angle: f32,
        /// Half-angle of the fully lit beam, degrees, in `(0, cutoff_angle]`.
        beam_width: f32,
        /// A projection texture and the `up` that orients it (Mitsuba's `lookat` up; not
        /// parallel to `direction`), if any ([`risotto_systems::lights::SpotTexture`]).
        texture: Option<(Arc<risotto_systems::pattern::Texture>, Vec3)>,
    },
    /// Environment.
    Environment {
        /// Constant radiance (scales the map).
        radiance: Rgb,
        /// Optional equirectangular map.
        map: Option<Arc<EnvironmentMap>>,
    },
}

/// A registered material.
pub struct Material {
    /// Name used by shapes and messages.
    pub name: String,
    /// Priority for nested dielectrics (higher wins); defaults to 0.
    pub priority: i32,
    /// The factory.
    pub factory: Box<dyn BxdfFactory>,
}

/// Render settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum number of path segments (Mitsuba's `max_depth`: 1 = directly visible emitters
    /// only, 2 = direct lighting); `u32::MAX` = unbounded.
    pub max_depth: u32,
    /// Scattering vertices after which Russian roulette starts.
    pub rr_depth: u32,
    /// Seed of the sampler.
    pub seed: u64,
    /// Pass-throughs (index-matched or false boundaries) one path may make before it is
    /// stopped; a generous guard against infinite loops. Defaults to 1024.
    pub max_passes: u32,
    /// The global integrator the scene asks for (`[render] integrator`); a render's
    /// [`RenderOptions::integrator`](crate::render::RenderOptions::integrator) overrides it.
    /// Defaults to the path tracer.
    pub integrator: crate::global_integrator::GlobalIntegrator,
    /// How shading normals that differ from the geometric normal are treated
    /// (`[render] shading_normals`); defaults to [`ShadingNormals::Consistent`].
    pub shading_normals: ShadingNormals,
}

/// How directions are treated where a shading normal `Nn` (vertex normals) and the geometric
/// normal `Ng` disagree on whether they are reflection or transmission.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadingNormals {
    /// Directions the two normals classify differently are discarded, so light neither leaks
    /// through a surface nor is reflected from below it (Veach 1997, sec. 5.3.2; pbrt-v3's
    /// `BSDF::f`): `crate::path_tracer::shading_normals`. The default.
    #[default]
    Consistent,
    /// The Bxdf is evaluated and sampled in the shading frame alone and every direction is
    /// kept, as Mitsuba 3 and pbrt-v4 do; a ray crosses the surface (and changes medium)
    /// when its direction and the viewer lie on different sides of `Ng`, whatever lobe
    /// sampled it (Mitsuba's `SurfaceInteraction::target_medium`). Light can leak near the
    /// silhouettes of coarse meshes; the importers of Mitsuba and pbrt files choose it so
    /// that their scenes render as there.
    ShadingFrame,
}

impl ShadingNormals {
    /// Both treatments, in listing order.
    pub const ALL: [ShadingNormals; 2] = [ShadingNormals::Consistent, ShadingNormals::ShadingFrame];

    /// The name scene files use (`[render] shading_normals`).
    pub fn name(self) -> &'static str {
        match self {
            ShadingNormals::Consistent => "consistent",
            ShadingNormals::ShadingFrame => "shading_frame",
        }
    }

    /// The treatment called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 512,
            height: 512,
            spp: 64,
            max_depth: 8,
            rr_depth: 5,
            seed: 0,
            max_passes: 1024,
            integrator: crate::global_integrator::GlobalIntegrator::Path,
            shading_normals: ShadingNormals::Consistent,
        }
    }
}

impl RenderSettings {
    /// Checks the settings of a scene built in code as the scene file's are checked: the
    /// image size agrees with `camera`'s (the camera, which makes the rays, holds the size
    /// too: a `settings.width` changed alone would be ignored), each side at least 1, the
    /// pixel count at most [`MAX_PIXELS`](risotto_systems::film::MAX_PIXELS), and `spp` from
    /// 1 to [`MAX_SPP`](risotto_systems::sampler::MAX_SPP). [`Scene::compile`] calls it.
    pub fn check(&self, camera: &Camera) -> Result<(), CompileError> {
        let invalid = |message: String| CompileError::Invalid {
            entity: "settings".into(),
            message,
        };
        let (w, h) = (self.width, self.height);
        if (camera.width, camera.height) != (w, h) {
            return Err(invalid(format!(
                "image size {w}x{h} differs from the camera's {}x{}: set both (the camera's \
                 is the size given to Camera::look_at)",
                camera.width, camera.height
            )));
        }
        if w == 0 || h == 0 || u64::from(w) * u64::from(h) > risotto_systems::film::MAX_PIXELS {
            return Err(invalid(format!(
                "image size {w}x{h}: each side must be at least 1 and the image at most {} \
                 pixels",
                risotto_systems::film::MAX_PIXELS
            )));
        }
        let max_spp = risotto_systems::sampler::MAX_SPP;
        if !(1..=max_spp).contains(&self.spp) {
            return Err(invalid(format!(
                "spp {}: must be from 1 to {max_spp}",
                self.spp
            )));
        }
        Ok(())
    }
}

/// A scene being assembled: the world, the materials, the camera and the settings.
pub struct Scene {
    /// The files a scene file made it from reads (empty for a scene built in code).
    pub files: crate::diagnostics::ReferencedFiles,
    /// Warnings from reading the scene (its files' skipped content); compiling adds its own,
    /// and every render's stats repeat them.
    pub warnings: Vec<String>,
    /// The file the scene was read from, which compile errors without a line of their own
    /// name (`None`: built in code).
    pub source: Option<std::path::PathBuf>,
    /// The entities.
    pub world: hecs::World,
    /// Materials by index.
    pub materials: Vec<Material>,
    /// The camera.
    pub camera: Camera,
    /// Render settings.
    pub settings: RenderSettings,
    /// Volume stack at the camera, by shape name (outermost first); `None` = found by probing.
    /// When given, it must agree with what probing finds: compiling checks it (a stated
    /// stack that is wrong would render every camera ray with the wrong media, silently).
    pub camera_volume: Option<Vec<String>>,
    /// Where [`Self::camera_volume`] was written (`camera.inside` in a scene file), so its
    /// errors name the file and line; `None` for scenes built in code.
    pub camera_volume_at: Option<crate::diagnostics::Location>,
    /// Statements of the volume the camera or a shape sits in, checked when compiling
    /// ([`WithinCheck`]; `within` in scene files, written by importers of formats that name
    /// media explicitly).
    pub within_checks: Vec<WithinCheck>,
    /// Objects: shapes defined once and placed by instance entities ([`InstanceOf`];
    /// [`Self::add_object`], [`Self::add_instance`]).
    pub objects: Vec<ObjectDef>,
}

/// Per-shape data of a compiled scene.
#[derive(Clone, Debug)]
pub struct ShapeInfo {
    /// Name.
    pub name: String,
    /// Material index.
    pub material: u32,
    /// Emitted radiance, if an area light.
    pub emission: Option<Rgb>,
}

/// Per-material data of a compiled scene.
#[derive(Clone, Copy, Debug)]
pub struct MaterialInfo {
    /// Instance hints of the factory.
    pub hints: InstanceHints,
    /// Priority.
    pub priority: i32,
    /// IOR of the interior.
    pub ior: f32,
    /// Shadow-ray transmittance of the surface.
    pub shadow_transmittance: Rgb,
}

/// The flat, read-only data the renderer works from.
pub struct CompiledScene {
    /// The files the scene reads besides its own text, sorted
    /// ([`ReferencedFiles`](crate::diagnostics::ReferencedFiles)).
    pub files: Vec<std::path::PathBuf>,
    /// All primitives and the BVH.
    pub geometry: SceneGeometry,
    /// Shape index of every primitive outside instances (of any primitive:
    /// [`Self::shape_of_prim`]).
    pub prim_shape: Vec<u32>,
    /// Material index of every primitive outside instances (its shape's material; what
    /// grouping hits by material reads, one lookup instead of two; of any primitive:
    /// [`Self::material_of_prim`]).
    pub prim_material: Vec<u32>,
    /// The shapes of the instances' primitives.
    pub instanced: InstancedShapes,
    /// Shapes: those of the scene, then one per (instance, object shape).
    pub shapes: Vec<ShapeInfo>,
    /// Materials (factories).
    pub materials: Vec<Material>,
    /// Material data the hot loops read.
    pub material_info: Vec<MaterialInfo>,
    /// Lights, every one sampled (light sampling without MIS: `--lighting nee`, the lighting
    /// delegate).
    pub lights: LightSet,
    /// The same lights as sampled under MIS with Bxdf sampling (the path tracer's default):
    /// a constant environment is left to Bxdf sampling
    /// ([`LightSet::with_environment_sampling`]).
    pub mis_lights: LightSet,
    /// With emissive media: [`Self::lights`] and the volume lights
    /// ([`Self::bidirectional_lights`]).
    pub lights_with_volumes: Option<LightSet>,
    /// Camera.
    pub camera: Camera,
    /// Settings.
    pub settings: RenderSettings,
    /// Features.
    pub features: Features,
    /// Volume stack rays start with at the camera.
    pub camera_stack: VolumeStack,
    /// Radius of the scene's bounding sphere.
    pub radius: f32,
    /// Centre of the scene's bounding sphere.
    pub center: Vec3,
    /// Per shape: whether rays crossing it enter or leave a tracked volume
    /// ([`Self::tracks_interior`]).
    pub shape_tracked: Vec<bool>,
    /// Per shape: its volume-stack entry ([`Self::volume_entry`]).
    pub shape_entry: Vec<risotto_components::VolumeEntry>,
    /// Per shape: its world-space bounding box `(min, max)`.
    pub shape_bounds: Vec<(Vec3, Vec3)>,
    /// Per shape: its object space ([`ObjectTransform`]) and its bounds there, what a
    /// volume's `u, v, w` and grids are measured in.
    pub shape_space: Vec<crate::plugin::VolumeSpace>,
    /// Per shape: the index (in `mis_lights`) of the volume light its emissive interior
    /// offered ([`crate::plugin::volume_light`]), or `u32::MAX`.
    pub volume_light: Vec<u32>,
    /// What compiling changed about the scene as written that a user should know (shapes
    /// hidden by a coincident shape); every render's stats repeat them.
    pub warnings: Vec<String>,
}

/// Errors found while compiling a scene.
#[derive(Debug, thiserror::Error)]
pub enum CompileError {
    /// A shape names a material index that does not exist.
    #[error("shape \"{shape}\": material index {index} does not exist")]
    MissingMaterial {
        /// Shape name.
        shape: String,
        /// Index.
        index: u32,
    },
    /// The camera volume (`camera.inside`) names an unknown shape or a shape without
    /// interior, or differs from the volumes the camera is in; for a scene built in code
    /// (no file to name).
    #[error("camera_volume: {0}")]
    CameraVolume(String),
    /// A [`WithinCheck`] of a scene built in code failed (the camera or a shape is not in
    /// the volume stated).
    #[error("within: {0}")]
    Within(String),
    /// An error located in the scene file (`camera.inside`).
    #[error(transparent)]
    Scene(#[from] crate::diagnostics::SceneError),
    /// A value is invalid.
    #[error("{entity}: {message}")]
    Invalid {
        /// Entity name.
        entity: String,
        /// What is wrong.
        message: String,
    },
}

impl Scene {
    /// An empty scene with the given camera and settings. The image size is the camera's
    /// (it makes the rays): `settings.width` and `settings.height` are set to it here, and
    /// [`compile`](Self::compile) refuses a scene whose two sizes were changed apart later
    /// ([`RenderSettings::check`]).
    pub fn new(camera: Camera, mut settings: RenderSettings) -> Self {
        (settings.width, settings.height) = (camera.width, camera.height);
        Scene {
            files: Default::default(),
            warnings: Vec::new(),
            source: None,
            world: hecs::World::new(),
            materials: Vec::new(),
            camera,
            settings,
            camera_volume: None,
            camera_volume_at: None,
            within_checks: Vec::new(),
            objects: Vec::new(),
        }
    }

    /// Registers a material and returns its index.
    pub fn add_material(
        &mut self,
        name: &str,
        priority: i32,
        factory: Box<dyn BxdfFactory>,
    ) -> u32 {
        self.materials.push(Material {
            name: name.to_string(),
            priority,
            factory,
        });
        (self.materials.len() - 1) as u32
    }

    /// Adds a shape entity written in world coordinates (no [`ObjectTransform`]).
    pub fn add_shape(
        &mut self,
        name: &str,
        geometry: ShapeGeometry,
        material: u32,
        emission: Option<Rgb>,
    ) -> hecs::Entity {
        let e = self
            .world
            .spawn((Name(name.to_string()), geometry, MaterialRef(material)));
        if let Some(l) = emission {
            self.world
                .insert_one(e, Emission(l))
                .expect("entity was just spawned");
        }
        e
    }

    /// Adds a shape entity whose world-space `geometry` was written in an object space that
    /// `object_to_world` maps to the world ([`ObjectTransform`]; the identity is the same as
    /// [`add_shape`](Self::add_shape)).
    pub fn add_shape_with_transform(
        &mut self,
        name: &str,
        geometry: ShapeGeometry,
        material: u32,
        emission: Option<Rgb>,
        object_to_world: Affine3A,
    ) -> hecs::Entity {
        let e = self.add_shape(name, geometry, material, emission);
        if object_to_world != Affine3A::IDENTITY {
            self.world
                .insert_one(e, ObjectTransform(object_to_world))
                .expect("entity was just spawned");
        }
        e
    }

    /// Gives the triangle shape `shape` per-vertex normals and texture coordinates (world
    /// space; `attributes.corners` has one entry per triangle of the shape, in its order).
    /// Attributes with neither normals nor uvs are not stored.
    ///
    /// # Panics
    /// When `shape` is not a triangle shape of this scene, the corners are not one per
    /// triangle, or a corner indexes past the normals or uvs.
    pub fn set_vertex_attributes(&mut self, shape: hecs::Entity, attributes: VertexAttributes) {
        let triangles = match &*self
            .world
            .get::<&ShapeGeometry>(shape)
            .expect("a shape of this scene")
        {
            ShapeGeometry::Sphere(_) => panic!("vertex attributes on a sphere"),
            g => g.num_triangles(),
        };
        assert_eq!(
            attributes.corners.len(),
            triangles,
            "one corner triple per triangle"
        );
        let max = attributes.corners.iter().flatten().copied().max();
        for len in [attributes.normals.len(), attributes.uvs.len()] {
            assert!(
                len == 0 || max.is_none_or(|m| (m as usize) < len),
                "corner out of range"
            );
        }
        if !attributes.is_empty() {
            self.world
                .insert_one(shape, attributes)
                .expect("a shape of this scene");
        }
    }

    /// Adds a light entity.
    pub fn add_light(&mut self, name: &str, light: LightComponent) -> hecs::Entity {
        self.world.spawn((Name(name.to_string()), light))
    }
}

impl CompiledScene {
    /// Whether sampled and light directions that the shading and geometric normals classify
    /// differently are discarded: the scene has shading normals and
    /// [`ShadingNormals::Consistent`] treatment.
    #[inline]
    pub fn discards_disagreeing_directions(&self) -> bool {
        self.features.vertex_normals && self.settings.shading_normals == ShadingNormals::Consistent
    }

    /// The shape of primitive `prim` (any, instanced or not).
    #[inline(always)]
    pub fn shape_of_prim(&self, prim: u32) -> u32 {
        match self.prim_shape.get(prim as usize) {
            Some(&s) => s,
            None => self.instanced.shape_of(&self.geometry, prim),
        }
    }

    /// The material of primitive `prim` (any, instanced or not).
    #[inline(always)]
    pub fn material_of_prim(&self, prim: u32) -> u32 {
        match self.prim_material.get(prim as usize) {
            Some(&m) => m,
            None => self.shapes[self.instanced.shape_of(&self.geometry, prim) as usize].material,
        }
    }

    /// The volume entry for crossing into `shape`'s interior, if its material has one.
    pub fn volume_entry(&self, shape: u32) -> risotto_components::VolumeEntry {
        let material = self.shapes[shape as usize].material;
        risotto_components::VolumeEntry {
            material,
            shape,
            priority: self.material_info[material as usize].priority,
        }
    }

    /// The per-shape boundary data the ray-spawning systems read.
    pub fn boundaries(&self) -> risotto_systems::ray::InteriorBoundaries<'_> {
        risotto_systems::ray::InteriorBoundaries {
            tracked: &self.shape_tracked,
            entry: &self.shape_entry,
            by_geometric_side: self.settings.shading_normals == ShadingNormals::ShadingFrame,
        }
    }

    /// True when a hit on `shape` by a ray whose volume stack is `stack` is a false boundary
    /// (Schmidt and Budge 2002): `shape` bounds a tracked volume whose priority is below that
    /// of a volume the ray is inside, so it is crossed without shading. A shape that bounds
    /// no volume (an opaque floor a glass stands on) is never false: priorities order
    /// volumes, and a surface without one is always real. (Treating such a floor as false
    /// let rays inside the glass of `scenes/liquid-in-glass.toml` pass through the floor
    /// under it, skip the coincident bottom of the glass and leave the scene still inside
    /// the glass.)
    #[inline]
    pub fn is_false_boundary(&self, stack: &VolumeStack, shape: u32) -> bool {
        let s = shape as usize;
        self.shape_tracked[s] && stack.is_false_boundary(shape, self.shape_entry[s].priority)
    }

    /// True when rays crossing `shape` enter a volume the renderer must track (its material
    /// computes an interior or takes part in priorities / IOR nesting).
    pub fn tracks_interior(&self, shape: u32) -> bool {
        let info = &self.material_info[self.shapes[shape as usize].material as usize];
        info.hints.contains(InstanceHints::COMPUTES_INTERIOR)
            || info.hints.contains(InstanceHints::TRANSMITS)
    }

    fn explicit_stack(&self, names: &[String]) -> Result<VolumeStack, String> {
        let mut stack = VolumeStack::new();
        for n in names {
            let s = self
                .shapes
                .iter()
                .position(|s| &s.name == n)
                .ok_or_else(|| format!("shape \"{n}\" does not exist"))?;
            if !self.tracks_interior(s as u32) {
                return Err(format!(
                    "shape \"{n}\" has no interior (its material neither transmits nor \
                     computes a volume), so no camera is inside it"
                ));
            }
            stack.enter(self.volume_entry(s as u32));
        }
        Ok(stack)
    }

    /// Finds the volumes a ray leaving `point` along `forward` (the camera's view axis)
    /// starts in: a walk from `point` backwards, out of the scene, collects every crossing
    /// of a tracked shape, and they are applied from the outside in (front face, as seen
    /// along `forward`: enter; back face: leave).
    ///
    /// The walk starts `delta` (4 ulps of the point's coordinates) ahead of the point, so a
    /// surface through the point itself, which camera rays cannot hit (they accept `t > 0`
    /// only), counts as crossed: a camera on a glass surface looking into it is inside the
    /// glass (issue 14 item 4). The probe used to come from outside along one fixed
    /// direction and stop at the point, where its f32 `t`, tens of scene units long, could
    /// not tell which side of such a surface the point was on: a camera on the bottom face
    /// of a slab looking up was outside the slab and saw no absorption. Walking from the
    /// point, the crossings are measured from it, to the triangle test's double-precision
    /// accuracy near the origin.
    pub fn probe_stack(&self, point: Vec3, forward: Vec3) -> VolumeStack {
        self.probe_stack_excluding(point, forward, None)
    }

    /// [`Self::probe_stack`] with the crossings of shape `exclude` left out (the volumes
    /// around a point on that shape).
    fn probe_stack_excluding(
        &self,
        point: Vec3,
        forward: Vec3,
        exclude: Option<u32>,
    ) -> VolumeStack {
        let mut stack = VolumeStack::new();
        if !self.features.volumes && !self.features.transmissive {
            return stack;
        }
        let forward = forward.normalize();
        let delta = point.abs().max_element().max(self.radius * 1e-3) * 5e-7;
        let origin = point + forward * delta;
        let d = -forward;
        let mut crossings = Vec::new();
        // The first query starts at `origin`, no surface point.
        let mut t0 = risotto_systems::intersect::FREE_ORIGIN;
        for _ in 0..10_000 {
            let mut t = [0.0f32];
            let mut prim = [0u32];
            let (mut b1, mut b2) = ([0.0f32], [0.0f32]);
            risotto_systems::intersect::intersect_closest(
                &self.geometry,
                &[origin],
                &[d],
                &[t0],
                &[f32::INFINITY],
                &mut t,
                &mut prim,
                &mut b1,
                &mut b2,
            );
            if prim[0] == risotto_components::NO_HIT {
                break;
            }
            let shape = self.shape_of_prim(prim[0]);
            let s = self
                .geometry
                .surface_at(prim[0], origin, d, t[0], b1[0], b2[0]);
            if self.tracks_interior(shape) && exclude != Some(shape) {
                // Seen along `forward`, the opposite of the walk's direction.
                crossings.push((shape, forward.dot(s.ng) < 0.0));
            }
            // Past this hit by its surface's error offset along the ray (coincident hits,
            // such as an edge two triangles share, count once).
            t0 = risotto_systems::ray::tmin_past_hit(t[0], s.offset(), s.ng, d);
        }
        for &(shape, front) in crossings.iter().rev() {
            stack.cross(self.volume_entry(shape), front);
        }
        stack
    }
}
