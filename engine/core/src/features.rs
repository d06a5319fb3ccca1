//! What a scene contains, as far as the scheduler and the techniques care: derived at
//! compilation from the materials' instance hints and the lights.

/// What a scene contains, as far as the scheduler cares.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Features {
    /// Some material computes an interior (volume stages run).
    pub volumes: bool,
    /// Some material lets rays cross its surface (partitioning by transmit bit runs).
    pub transmissive: bool,
    /// Some interior scatters.
    pub scattering_media: bool,
    /// Some interior is heterogeneous.
    pub heterogeneous: bool,
    /// Some interior is subsurface.
    pub subsurface: bool,
    /// Some interior emits.
    pub emissive_media: bool,
    /// Some emissive medium is light-sampled (`crate::plugin::volume_light`).
    pub emissive_volume_lights: bool,
    /// Some emissive interior offers no volume light (behind a dielectric, in a turned
    /// shape or one no emitter covers, `crate::plugin::volume_light`): only the rays that
    /// cross it gather its emission, and no light subpath starts in it.
    pub emissive_media_without_lights: bool,
    /// Some surface passes shadow rays (transmission system must walk through surfaces).
    pub transmission_shadows: bool,
    /// Some material reads surface `u`, `v` (sphere hits compute theirs,
    /// [`InstanceHints::READS_SURFACE_UV`](crate::plugin::InstanceHints::READS_SURFACE_UV)).
    pub surface_uv: bool,
    /// Some surface is partly present ([`InstanceHints::OPACITY`](crate::plugin::InstanceHints::OPACITY)):
    /// path rays test it in the pass-through stage, shadow rays walk through it.
    pub opacity: bool,
    /// Some mesh has vertex normals: shading normals differ from geometric ones, and the
    /// directions where the two disagree are discarded (`path_tracer::shading_normals`).
    pub vertex_normals: bool,
    /// Some mesh with vertex normals asks for the shadow-terminator offset: hits on it get
    /// their `terminator_lift` and rays leaving to the viewer's side start from the smooth
    /// surface (`risotto_systems::terminator`).
    pub terminator_offset: bool,
    /// Emissive shapes.
    pub area_lights: bool,
    /// Distant lights.
    pub distant_lights: bool,
    /// Point lights.
    pub point_lights: bool,
    /// Spot lights.
    pub spot_lights: bool,
    /// An environment.
    pub environment: bool,
}

impl Features {
    /// Feature names for the stats' `features` list.
    pub fn names(&self) -> Vec<String> {
        let all = [
            (self.volumes, "volumes"),
            (self.transmissive, "transmissive_surfaces"),
            (self.scattering_media, "scattering_media"),
            (self.heterogeneous, "heterogeneous_media"),
            (self.subsurface, "subsurface"),
            (self.emissive_media, "emissive_media"),
            (self.emissive_volume_lights, "emissive_volume_lights"),
            (
                self.emissive_media_without_lights,
                "emissive_media_without_lights",
            ),
            (self.transmission_shadows, "transmission_shadows"),
            (self.surface_uv, "surface_uv"),
            (self.opacity, "opacity"),
            (self.vertex_normals, "vertex_normals"),
            (self.terminator_offset, "terminator_offset"),
            (self.area_lights, "area_lights"),
            (self.distant_lights, "distant_lights"),
            (self.point_lights, "point_lights"),
            (self.spot_lights, "spot_lights"),
            (self.environment, "environment"),
        ];
        all.iter()
            .filter(|(on, _)| *on)
            .map(|(_, n)| n.to_string())
            .collect()
    }
}
