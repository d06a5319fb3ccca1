//! Lobe bits: what kind of scattering produced a ray.

/// Which lobe a Bxdf sampled (RIS `lobeSampled`). The `TRANSMIT` bit is the contract with the
/// renderer: a ray carrying it crossed the surface and will travel in the surface's *opposite*
/// volume; without it the ray stays in the *incident* volume.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LobeSampled(pub u8);

impl LobeSampled {
    /// No lobe (camera rays, invalid samples).
    pub const NONE: LobeSampled = LobeSampled(0);
    /// The ray left on the incident side of the surface.
    pub const REFLECT: LobeSampled = LobeSampled(1);
    /// The ray crossed the surface into the opposite volume.
    pub const TRANSMIT: LobeSampled = LobeSampled(2);
    /// Diffuse lobe (a pdf exists; light sampling and MIS apply).
    pub const DIFFUSE: LobeSampled = LobeSampled(4);
    /// Specular (Dirac) lobe: no light sampling, no MIS.
    pub const SPECULAR: LobeSampled = LobeSampled(8);
    /// A volume scattering event (phase function).
    pub const SCATTER: LobeSampled = LobeSampled(16);
    /// A pass-through: index-matched or false boundary; not a scattering bounce.
    pub const PASS: LobeSampled = LobeSampled(32);

    /// True when every bit of `other` is set in `self`.
    pub const fn contains(self, other: LobeSampled) -> bool {
        self.0 & other.0 == other.0
    }
    /// True when any bit of `other` is set in `self`.
    pub const fn intersects(self, other: LobeSampled) -> bool {
        self.0 & other.0 != 0
    }
    /// The transmit bit.
    pub const fn is_transmit(self) -> bool {
        self.contains(Self::TRANSMIT)
    }
    /// The specular bit.
    pub const fn is_specular(self) -> bool {
        self.contains(Self::SPECULAR)
    }
}

impl std::ops::BitOr for LobeSampled {
    type Output = LobeSampled;
    fn bitor(self, o: LobeSampled) -> LobeSampled {
        LobeSampled(self.0 | o.0)
    }
}
impl std::ops::BitOrAssign for LobeSampled {
    fn bitor_assign(&mut self, o: LobeSampled) {
        self.0 |= o.0;
    }
}
