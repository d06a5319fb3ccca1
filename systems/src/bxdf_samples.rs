//! The output table of Bxdf (and phase-function) sampling: one row per shading point.

use crate::bxdf::{BxdfSample, Frame};
use glam::Vec3;
use risotto_components::{LobeSampled, Rgb};

/// Output columns of a Bxdf's `generate_samples`, one row per point of the shading context.
#[derive(Clone, Debug, Default)]
pub struct BxdfSamples {
    /// Sampled incident direction (world space, unit). Ignored where `pdf == 0`.
    pub wi: Vec<Vec3>,
    /// `f * |cos| / pdf` (for specular lobes: the lobe weight; for phase functions `p / pdf`
    /// times the single-scattering albedo).
    pub weight: Vec<Rgb>,
    /// Solid-angle pdf of `wi`; for specular lobes the discrete lobe probability. 0 = no sample
    /// (the path ends, counted as absorbed).
    pub pdf: Vec<f32>,
    /// Lobe bits of each sample (`TRANSMIT` marks a crossing into the opposite volume).
    pub lobe: Vec<LobeSampled>,
    /// Relative index of refraction crossed (1 when none).
    pub eta: Vec<f32>,
}

impl BxdfSamples {
    /// Writes the sample `s` drawn in the local frame `frame` as row `i` (direction turned to
    /// world space).
    #[inline]
    pub fn set_local(&mut self, i: usize, frame: &Frame, s: BxdfSample) {
        self.wi[i] = frame.to_world(s.wi);
        self.weight[i] = s.weight;
        self.pdf[i] = s.pdf;
        self.lobe[i] = s.lobe;
        self.eta[i] = s.eta;
    }

    /// Resizes every column to `n` rows of "no sample".
    pub fn reset(&mut self, n: usize) {
        self.wi.clear();
        self.wi.resize(n, Vec3::Z);
        self.weight.clear();
        self.weight.resize(n, Rgb::BLACK);
        self.pdf.clear();
        self.pdf.resize(n, 0.0);
        self.lobe.clear();
        self.lobe.resize(n, LobeSampled::NONE);
        self.eta.clear();
        self.eta.resize(n, 1.0);
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.wi.len()
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.wi.is_empty()
    }
}
