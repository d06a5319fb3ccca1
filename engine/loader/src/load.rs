//! From scene files to scenes: the material registry (type name -> factory constructor) and
//! the conversion of a [`SceneDesc`] into a [`Scene`] world.
//!
//! Users register their own material types so that a scene file can say
//! `type = "my_glass"`:
//!
//! ```
//! use risotto_loader::load::MaterialRegistry;
//! use risotto_builtins::builtin::{BuiltinMaterial, Interior, Opacity, OpacityMask, Surface};
//! use risotto_components::Rgb;
//!
//! let mut registry = MaterialRegistry::with_builtins();
//! registry.register("grey", |params| {
//!     let level = params.f32_in("level", Some(0.5), 0.0, 1.0)?;
//!     Ok(Box::new(BuiltinMaterial {
//!         surface: Surface::Diffuse { reflectance: Rgb::splat(level) },
//!         interior: Interior::None,
//!     }))
//! });
//! assert!(registry.contains("grey") && registry.contains("diffuse"));
//! ```

use crate::scene_file::{
    load_scene, load_scene_with, ColourParam, LightDesc, MaterialDesc, MaterialParams,
    Projection as DescProjection, SceneDesc, SceneError, SceneErrorKind,
    ShapeGeometry as DescGeometry,
};
use crate::surface_params;
use risotto_builtins::builtin::{BuiltinMaterial, Interior, Opacity, OpacityMask, Surface};
use risotto_builtins::media::{HomogeneousMedium, Scattering};
use risotto_components::Rgb;
use risotto_engine::output::{read_exr_rgb_within, Image, OutputError};
use risotto_engine::plugin::BxdfFactory;
use risotto_engine::scene::{CompileError, LightComponent, RenderSettings, Scene, ShapeGeometry};
use risotto_systems::camera::{Camera, Projection};
use risotto_systems::environment_map::{EnvProjection, EnvironmentMap};
use risotto_systems::geometry::Sphere;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Builds a factory from a material's parameters.
pub type MaterialConstructor =
    Box<dyn Fn(&MaterialParams) -> Result<Box<dyn BxdfFactory>, SceneError> + Send + Sync>;

/// Material types by name.
pub struct MaterialRegistry {
    constructors: BTreeMap<String, MaterialConstructor>,
}

/// Errors turning a scene file into a scene.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file itself (syntax, values, missing meshes, material parameters).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The camera is degenerate.
    #[error("{scene}: camera: `from` and `to` coincide or `up` is parallel to the view direction")]
    Camera {
        /// Scene file.
        scene: PathBuf,
    },
    /// Compilation failed.
    #[error("{scene}: {cause}")]
    Compile {
        /// Scene file.
        scene: PathBuf,
        /// Cause (part of the message, so not also `source()`, which would repeat it).
        cause: CompileError,
    },
}

impl MaterialRegistry {
    /// An empty registry.
    pub fn new() -> Self {
        MaterialRegistry {
            constructors: BTreeMap::new(),
        }
    }

    /// A registry with the built-in types: `diffuse`, `dielectric`, `conductor`, `mirror`,
    /// `rough_conductor`, `rough_dielectric`, `interface`, `subsurface`, `plastic`,
    /// `rough_plastic`, `thin_dielectric`, `coated_diffuse`, `coated_conductor`.
    pub fn with_builtins() -> Self {
        let mut r = Self::new();
        r.register("diffuse", |p| {
            // A colour, or a pattern table (evaluated per point through the context's cache).
            let surface = match p.colour_or_pattern("reflectance", Rgb::splat(0.5), [0.0, 1.0])? {
                ColourParam::Constant(reflectance) => Surface::Diffuse { reflectance },
                ColourParam::Pattern(graph) => Surface::DiffusePattern {
                    reflectance: Arc::new(graph),
                },
            };
            let surface = surface_params::two_sided(p, surface)?;
            builtin(p, surface, &["reflectance", "two_sided"])
        });
        r.register("plastic", |p| {
            let surface = surface_params::two_sided(p, surface_params::plastic(p)?)?;
            let mut keys = surface_params::PLASTIC_KEYS.to_vec();
            keys.push("two_sided");
            builtin(p, surface, &keys)
        });
        r.register("rough_plastic", |p| {
            let surface = crate::rough_params::rough_plastic(p)?;
            let surface = surface_params::two_sided(p, surface)?;
            let mut keys = crate::rough_params::ROUGH_PLASTIC_KEYS.to_vec();
            keys.push("two_sided");
            builtin(p, surface, &keys)
        });
        r.register("thin_dielectric", |p| {
            let keys = ["ior", "null_transmission"];
            builtin(p, surface_params::thin_dielectric(p)?, &keys)
        });
        r.register("dielectric", |p| {
            surface_params::reject_two_sided(p, "dielectric")?;
            let ior = p.f32_where("ior", Some(1.5), "must be > 0", |v| v > 0.0)?;
            let cheap_shadows = p.bool("cheap_shadows", Some(false))?;
            // A colour, or a pattern table (as the diffuse reflectance).
            let surface = match p.colour_or_pattern("tint", Rgb::WHITE, [0.0, 1.0])? {
                ColourParam::Constant(tint) => Surface::Dielectric {
                    ior,
                    tint,
                    cheap_shadows,
                },
                // Cheap shadows attenuate a shadow ray by one colour per surface, which a
                // pattern does not have.
                ColourParam::Pattern(_) if cheap_shadows => {
                    return Err(p.error(
                        Some("cheap_shadows"),
                        "cheap shadows attenuate by one tint colour: give `tint` as a colour, \
                         or drop `cheap_shadows` for a tint pattern",
                    ))
                }
                ColourParam::Pattern(graph) => Surface::DielectricPattern {
                    ior,
                    tint: Arc::new(graph),
                },
            };
            builtin(p, surface, &["ior", "tint", "cheap_shadows"])
        });
        for name in ["conductor", "mirror"] {
            r.register(name, |p| {
                // A colour, or a pattern table (as the diffuse reflectance).
                let surface = match p.colour_or_pattern("reflectance", Rgb::WHITE, [0.0, 1.0])? {
                    ColourParam::Constant(reflectance) => Surface::Mirror { reflectance },
                    ColourParam::Pattern(graph) => Surface::MirrorPattern {
                        reflectance: Arc::new(graph),
                    },
                };
                builtin(p, surface, &["reflectance"])
            });
        }
        r.register("rough_conductor", |p| {
            let (surface, mut keys) = crate::rough_params::rough_conductor(p)?;
            // One-sided as Mitsuba's `roughconductor`; `two_sided = true` as its `twosided`.
            let surface = surface_params::two_sided(p, surface)?;
            keys.push("two_sided");
            builtin(p, surface, &keys)
        });
        r.register("coated_diffuse", |p| {
            let (surface, keys) = crate::coated_params::coated_diffuse(p)?;
            builtin(p, surface, &keys)
        });
        r.register("coated_conductor", |p| {
            let (surface, keys) = crate::coated_params::coated_conductor(p)?;
            builtin(p, surface, &keys)
        });
        r.register("rough_dielectric", |p| {
            surface_params::reject_two_sided(p, "rough_dielectric")?;
            let (surface, keys) = crate::rough_params::rough_dielectric(p)?;
            builtin(p, surface, &keys)
        });
        r.register("interface", |p| {
            surface_params::reject_two_sided(p, "interface")?;
            builtin(p, Surface::Interface, &[])
        });
        r.register("subsurface", |p| {
            surface_params::reject_two_sided(p, "subsurface")?;
            crate::media_params::subsurface::construct(p)
        });
        r
    }

    /// Registers (or replaces) a material type.
    pub fn register(
        &mut self,
        type_name: &str,
        constructor: impl Fn(&MaterialParams) -> Result<Box<dyn BxdfFactory>, SceneError>
            + Send
            + Sync
            + 'static,
    ) {
        self.constructors
            .insert(type_name.to_string(), Box::new(constructor));
    }

    /// The factory of material `m` of `materials` (with its opacity): the registered
    /// constructor of its type, or a [`crate::mix_params`] mix (`depth`: how many mixes
    /// contain this one).
    pub(crate) fn build(
        &self,
        m: &MaterialDesc,
        materials: &[MaterialDesc],
        depth: usize,
    ) -> Result<Box<dyn BxdfFactory>, SceneError> {
        let factory = match self.constructors.get(&m.type_name) {
            Some(ctor) => ctor(&m.params)?,
            None if m.type_name == crate::mix_params::MIX => {
                let build = |c: &MaterialDesc, d: usize| self.build(c, materials, d);
                crate::mix_params::mix(m, materials, &build, depth)?
            }
            // Located at the `type` value: the registry is only known here, after parsing.
            None => {
                return Err(m.params.location(Some("type")).error(
                    SceneErrorKind::UnknownReference,
                    format!(
                        "unknown material type \"{}\" (known: {}, {})",
                        m.type_name,
                        self.types().collect::<Vec<_>>().join(", "),
                        crate::mix_params::MIX
                    ),
                ))
            }
        };
        with_opacity(&m.params, factory)
    }

    /// True when `type_name` is registered.
    pub fn contains(&self, type_name: &str) -> bool {
        self.constructors.contains_key(type_name)
    }

    /// Registered type names.
    pub fn types(&self) -> impl Iterator<Item = &str> {
        self.constructors.keys().map(String::as_str)
    }
}

impl Default for MaterialRegistry {
    fn default() -> Self {
        Self::with_builtins()
    }
}

/// Reads the optional `interior` table of a built-in material.
fn interior(p: &MaterialParams) -> Result<Interior, SceneError> {
    let Some(t) = p.table("interior")? else {
        return Ok(Interior::None);
    };
    let kind = t.string("type", None)?;
    match kind.as_str() {
        "null" => {
            t.deny_unknown(&["type"])?;
            Ok(Interior::Null)
        }
        "beer" => {
            t.deny_unknown(&["type", "sigma_a"])?;
            let sigma_a = t.rgb_where("sigma_a", None, "every channel >= 0 and finite", |c| {
                c.min_channel() >= 0.0 && c.is_finite()
            })?;
            Ok(Interior::Beer { sigma_a })
        }
        "homogeneous" => homogeneous(&t),
        "heterogeneous" => Ok(Interior::Heterogeneous(std::sync::Arc::new(
            crate::media_params::heterogeneous::parse(&t)?,
        ))),
        other => Err(t.error(
            Some("type"),
            format!(
                "unknown interior type \"{other}\" (known: null, beer, homogeneous, heterogeneous)"
            ),
        )),
    }
}

/// `interior = { type = "homogeneous", ... }`: `sigma_t` and `albedo`, or `sigma_a` and
/// `sigma_s` (colours or numbers, per world unit); `phase`; `scattering`; `emission` (the
/// emission coefficient, radiance per unit length). `albedo` and the HG `g` may be patterns
/// read at the scattering points ([`risotto_builtins::scatter_patterns`]); a pattern `sigma_t` or
/// `emission` makes the medium heterogeneous
/// ([`crate::media_params::heterogeneous::homogeneous_with_patterns`]).
fn homogeneous(t: &MaterialParams) -> Result<Interior, SceneError> {
    t.deny_unknown(&[
        "type",
        "sigma_t",
        "albedo",
        "sigma_a",
        "sigma_s",
        "phase",
        "scattering",
        "emission",
    ])?;
    let non_negative = "every channel >= 0 and finite";
    let ok = |c: Rgb| c.min_channel() >= 0.0 && c.is_finite();
    let by_extinction = t.has("sigma_t") || t.has("albedo");
    let by_coefficients = t.has("sigma_a") || t.has("sigma_s");
    let (sigma_t, sigma_s, albedo_pattern) = match (by_extinction, by_coefficients) {
        (true, true) => {
            let key = if t.has("sigma_a") {
                "sigma_a"
            } else {
                "sigma_s"
            };
            return Err(t.error(
                Some(key),
                "give either sigma_t and albedo, or sigma_a and sigma_s, not both",
            ));
        }
        (false, false) => {
            return Err(t.error(
                None,
                "a homogeneous interior needs sigma_t (and albedo) or sigma_a and sigma_s",
            ))
        }
        (false, true) if t.is_table("sigma_a") || t.is_table("sigma_s") => {
            let key = if t.is_table("sigma_a") {
                "sigma_a"
            } else {
                "sigma_s"
            };
            return Err(t.error(
                Some(key),
                "sigma_a and sigma_s take no pattern: give sigma_t (a grey pattern) and \
                 albedo (a colour or a pattern) instead",
            ));
        }
        (true, false) if t.is_table("sigma_t") => {
            let medium = crate::media_params::heterogeneous::homogeneous_with_patterns(t, None)?;
            return Ok(Interior::Heterogeneous(std::sync::Arc::new(medium)));
        }
        (true, false) => {
            let sigma_t = t.rgb_where("sigma_t", None, non_negative, ok)?;
            // With a pattern the flights run at albedo 1 and each collision's weight is
            // scaled by the pattern there.
            let (albedo, pattern) = crate::media_params::patterns::parse_albedo(t)?;
            (sigma_t, sigma_t * albedo, pattern)
        }
        (false, true) => {
            let sigma_a = t.rgb_where("sigma_a", Some(Rgb::BLACK), non_negative, ok)?;
            let sigma_s = t.rgb_where("sigma_s", Some(Rgb::BLACK), non_negative, ok)?;
            let sigma_t = sigma_a + sigma_s;
            if !sigma_t.is_finite() {
                return Err(t.error(Some("sigma_a"), "sigma_a + sigma_s overflows"));
            }
            (sigma_t, sigma_s, None)
        }
    };
    if t.is_table("emission") {
        // A constant extinction with an emission pattern: heterogeneous too.
        let albedo = risotto_builtins::media::albedo_of(sigma_s, sigma_t);
        let constant = Some((sigma_t, albedo, albedo_pattern));
        let medium = crate::media_params::heterogeneous::homogeneous_with_patterns(t, constant)?;
        return Ok(Interior::Heterogeneous(std::sync::Arc::new(medium)));
    }
    let (phase, g_pattern) = crate::media_params::patterns::parse_phase(t)?;
    let scattering = match t.string("scattering", Some("multiple"))?.as_str() {
        "multiple" => Scattering::Multiple,
        "walk" => Scattering::Walk,
        "bounce" => Scattering::Bounce,
        "single" => Scattering::Single,
        other => {
            return Err(t.error(
                Some("scattering"),
                format!("unknown scattering \"{other}\" (known: multiple, walk, bounce, single)"),
            ))
        }
    };
    let emission = t.rgb_where(
        "emission",
        Some(Rgb::BLACK),
        "every channel in [0, 1e30] (radiance per unit length; MAX_RADIANCE)",
        |c| ok(c) && c.max_channel() <= crate::scene_file::MAX_RADIANCE,
    )?;
    Ok(Interior::Homogeneous(HomogeneousMedium {
        sigma_t,
        sigma_s,
        phase,
        scattering,
        emission,
        albedo_pattern,
        g_pattern,
    }))
}

fn builtin(
    p: &MaterialParams,
    surface: Surface,
    keys: &[&str],
) -> Result<Box<dyn BxdfFactory>, SceneError> {
    let mut known = keys.to_vec();
    known.push("interior");
    p.deny_unknown(&known)?;
    Ok(Box::new(BuiltinMaterial {
        surface,
        interior: interior(p)?,
    }))
}

/// Wraps `factory` in an [`OpacityMask`] when its material has an `opacity` (a key of every
/// material, whatever its type: a number in [0, 1] or a pattern kept in [0, 1] by its
/// bounds) other than 1; an opaque material stays as it is, so it renders as before.
fn with_opacity(
    p: &MaterialParams,
    factory: Box<dyn BxdfFactory>,
) -> Result<Box<dyn BxdfFactory>, SceneError> {
    let p = p.with_common_keys();
    let opacity = if p.is_table("opacity") {
        match p.colour_or_pattern("opacity", Rgb::WHITE, [0.0, 1.0])? {
            ColourParam::Pattern(graph) => Opacity::Pattern(Arc::new(graph)),
            ColourParam::Constant(c) => Opacity::Constant(c.average()),
        }
    } else {
        Opacity::Constant(p.f32_in("opacity", Some(1.0), 0.0, 1.0)?)
    };
    Ok(match opacity {
        Opacity::Constant(1.0) => factory,
        opacity => Box::new(OpacityMask {
            inner: factory,
            opacity,
        }),
    })
}

/// The largest environment map accepted, in pixels: 2^27 (16384 x 8192; about 30 bytes
/// a pixel while it is read and its sampling distribution built). Checked in the EXR's
/// header before anything is decoded.
pub const MAX_ENVIRONMENT_PIXELS: u64 = 1 << 27;

/// Loads a scene file and builds its world with the materials of `registry`.
pub fn load_scene_file(path: &Path, registry: &MaterialRegistry) -> Result<Scene, LoadError> {
    let desc = load_scene(path)?;
    scene_from_desc(desc, registry)
}

/// [`load_scene_file`] with command-line overrides `KEY.PATH=VALUE` applied to the file's
/// values before they are read ([`crate::scene_file::parse_scene_with`]).
pub fn load_scene_file_with(
    path: &Path,
    overrides: &[String],
    registry: &MaterialRegistry,
) -> Result<Scene, LoadError> {
    let desc = load_scene_with(path, overrides)?;
    scene_from_desc(desc, registry)
}

/// Builds a scene world from a parsed description.
pub fn scene_from_desc(desc: SceneDesc, registry: &MaterialRegistry) -> Result<Scene, LoadError> {
    let r = desc.render;
    let settings = RenderSettings {
        width: r.width,
        height: r.height,
        spp: r.spp,
        max_depth: r.max_depth,
        rr_depth: r.rr_depth,
        seed: r.seed,
        integrator: r.integrator,
        shading_normals: r.shading_normals,
        ..RenderSettings::default()
    };
    let c = desc.camera;
    let projection = match c.projection {
        DescProjection::Perspective { fov_deg } => Projection::Perspective { fov_deg },
        DescProjection::Orthographic { width } => Projection::Orthographic { width },
        DescProjection::ThinLens {
            fov_deg,
            aperture_radius,
            focus_distance,
        } => Projection::ThinLens {
            fov_deg,
            aperture_radius,
            focus_distance,
        },
    };
    let camera = Camera::look_at(projection, c.from, c.to, c.up, r.width, r.height)
        .ok_or_else(|| LoadError::Camera {
            scene: desc.path.clone(),
        })?
        .with_filter(r.filter);
    let mut scene = Scene::new(camera, settings);
    scene.files = desc.files.clone();
    scene.warnings = desc.warnings.clone();
    scene.source = Some(desc.path.clone());
    scene.camera_volume = desc.camera_volume.clone();
    scene.camera_volume_at = desc.camera_volume_at.clone();
    scene.within_checks = desc.within.clone();
    for m in &desc.materials {
        let factory = registry.build(m, &desc.materials, 0)?;
        scene.add_material(&m.name, m.priority, factory);
    }
    for s in desc.shapes {
        let geometry = match s.geometry {
            DescGeometry::Sphere { center, radius } => {
                ShapeGeometry::Sphere(Sphere { center, radius })
            }
            DescGeometry::Triangles { triangles, .. } => ShapeGeometry::Triangles(triangles),
            DescGeometry::Mesh(mesh) => ShapeGeometry::Mesh(mesh),
        };
        let e = scene.add_shape_with_transform(
            &s.name,
            geometry,
            s.material as u32,
            s.emission,
            s.transform,
        );
        if !s.attributes.is_empty() {
            scene.set_vertex_attributes(e, s.attributes);
        }
    }
    // Objects in file order (their index is the instances' `object`), then instances.
    for o in desc.objects {
        let shapes = o
            .shapes
            .into_iter()
            .map(|s| risotto_engine::scene::ObjectShape {
                name: s.name,
                geometry: match s.geometry {
                    DescGeometry::Sphere { center, radius } => {
                        ShapeGeometry::Sphere(Sphere { center, radius })
                    }
                    DescGeometry::Triangles { triangles, .. } => {
                        ShapeGeometry::Triangles(triangles)
                    }
                    DescGeometry::Mesh(mesh) => ShapeGeometry::Mesh(mesh),
                },
                material: s.material as u32,
                attributes: s.attributes,
            })
            .collect();
        scene.add_object(&o.name, shapes);
    }
    for i in desc.instances {
        scene.add_instance(&i.name, i.object as u32, i.transform);
    }
    for l in desc.lights {
        let name = l.name().to_string();
        let light = match l {
            LightDesc::Distant {
                direction,
                irradiance,
                ..
            } => LightComponent::Distant {
                direction,
                irradiance,
            },
            LightDesc::Point {
                position,
                intensity,
                ..
            } => LightComponent::Point {
                position,
                intensity,
            },
            LightDesc::Spot {
                position,
                direction,
                intensity,
                cutoff_angle,
                beam_width,
                texture,
                ..
            } => LightComponent::Spot {
                position,
                direction,
                intensity,
                cutoff_angle,
                beam_width,
                texture,
            },
            LightDesc::Environment {
                radiance,
                map,
                map_at,
                filter,
                projection,
                to_world,
                ..
            } => {
                let map = match map {
                    Some(p) => {
                        let img = read_exr_rgb_within(&p, MAX_ENVIRONMENT_PIXELS)
                            .and_then(|img| check_radiance_map(&p, img))
                            .and_then(|img| check_projection(&p, img, projection))
                            .map_err(|e| {
                                let message = format!("cannot read environment map: {e}");
                                match &map_at {
                                    Some(at) => at.error(SceneErrorKind::ExternalFile, message),
                                    // A description built in code, not parsed: no line to name.
                                    None => SceneError::unlocated(
                                        &desc.path,
                                        SceneErrorKind::ExternalFile,
                                        &format!("light \"{name}\": {message}"),
                                    ),
                                }
                            })?;
                        Some(Arc::new(EnvironmentMap::with_projection(
                            img.pixels, img.width, img.height, projection, filter, to_world,
                        )))
                    }
                    None => None,
                };
                LightComponent::Environment { radiance, map }
            }
        };
        scene.add_light(&name, light);
    }
    Ok(scene)
}

/// An equal-area map is square (pbrt-v4's octahedral layout has no other shape): anything
/// else is an error naming the map and its size.
fn check_projection(
    path: &Path,
    img: Image,
    projection: EnvProjection,
) -> Result<Image, OutputError> {
    if projection == EnvProjection::EqualArea && img.width != img.height {
        return Err(OutputError::Invalid {
            path: path.to_path_buf(),
            reason: format!(
                "an equal_area map is square, this one is {} x {}",
                img.width, img.height
            ),
        });
    }
    Ok(img)
}

/// An environment map's texels are radiance: every channel finite and `>= 0`. The first
/// texel that is not is an error naming the map, the pixel `(x, y)` (from the top left), the
/// channel and the value (a NaN texel would drop every sample that sees it; a negative one
/// would make a negative image).
fn check_radiance_map(path: &Path, img: Image) -> Result<Image, OutputError> {
    for (i, p) in img.pixels.iter().enumerate() {
        for (c, v) in ["R", "G", "B"].into_iter().zip(p.to_array()) {
            if !(v.is_finite() && v >= 0.0) {
                return Err(OutputError::Invalid {
                    path: path.to_path_buf(),
                    reason: format!(
                        "pixel ({}, {}) channel {c} is {v}; environment map texels must be \
                         finite and >= 0",
                        i % img.width,
                        i / img.width
                    ),
                });
            }
        }
    }
    Ok(img)
}

/// Compiles a scene, attributing errors to the file it was read from
/// ([`Scene::source`]; `<scene>` for one built in code).
pub fn compile_scene(scene: Scene) -> Result<risotto_engine::scene::CompiledScene, LoadError> {
    let path = scene
        .source
        .clone()
        .unwrap_or_else(|| std::path::PathBuf::from("<scene>"));
    scene.compile().map_err(|source| match source {
        // Already names the file (and line).
        CompileError::Scene(e) => LoadError::Scene(e),
        cause => LoadError::Compile { scene: path, cause },
    })
}
