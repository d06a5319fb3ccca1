//! Per-channel density grids: a colour-varying extinction `sigma_t,c(x) = scale_c
//! density_c(x)` (Mitsuba 3's `gridvolume` with three channels as a `heterogeneous` medium's
//! `sigma_t`), and the one grey majorant grid its trackers share.
//!
//! The three channels are kept as three [`DensityGrid`]s (planar, each checked and looked up
//! exactly as a one-channel grid), so that a channel reads the same field a one-channel grid
//! of its values would.
//!
//! ```
//! use risotto_systems::grid::DensityChannels;
//! use risotto_components::Rgb;
//! use glam::Vec3;
//! // Two voxels along x, RGB interleaved per voxel (as a 3-channel Mitsuba .vol).
//! let g = DensityChannels::new([2, 1, 1], &[0.0, 1.0, 2.0, 1.0, 1.0, 4.0]).unwrap();
//! assert_eq!(g.lookup(Vec3::splat(0.5)), Rgb::new(0.5, 1.0, 3.0));
//! ```

use super::{DensityGrid, GridValueError, MajorantGrid};
use glam::Vec3;
use risotto_components::Rgb;

/// Three density grids of the same dimensions, one per RGB channel (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct DensityChannels {
    channels: [DensityGrid; 3],
}

impl DensityChannels {
    /// The grids of `dims` voxels from `interleaved` values (`3 (ix + nx (iy + ny iz)) + c`:
    /// x fastest, the channel fastest of all, as Mitsuba's `.vol`). The length must be
    /// `3 nx ny nz` and every value finite and >= 0; a bad value is reported with its
    /// index into `interleaved` and its voxel.
    pub fn new(dims: [usize; 3], interleaved: &[f32]) -> Result<Self, GridValueError> {
        let n = dims
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .unwrap_or(usize::MAX);
        if dims.contains(&0) || n.checked_mul(3) != Some(interleaved.len()) {
            return Err(GridValueError::Size {
                dims,
                expected: n.saturating_mul(3),
                got: interleaved.len(),
            });
        }
        // Located on the interleaved data (the file's order), before splitting.
        if let Some(index) = interleaved
            .iter()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            return Err(GridValueError::Value {
                index,
                voxel: super::voxel_of(dims, index / 3),
                value: interleaved[index],
            });
        }
        let plane = |c: usize| {
            let data = interleaved.iter().skip(c).step_by(3).copied().collect();
            DensityGrid::new(dims, data)
        };
        Ok(DensityChannels {
            channels: [plane(0)?, plane(1)?, plane(2)?],
        })
    }

    /// The channels given as three grids of the same dimensions (`None` if they differ).
    pub fn from_grids(channels: [DensityGrid; 3]) -> Option<Self> {
        let d = channels[0].dims();
        channels
            .iter()
            .all(|g| g.dims() == d)
            .then_some(DensityChannels { channels })
    }

    /// `[nx, ny, nz]` (every channel's).
    pub fn dims(&self) -> [usize; 3] {
        self.channels[0].dims()
    }

    /// Channel `c` (0 red, 1 green, 2 blue).
    pub fn channel(&self, c: usize) -> &DensityGrid {
        &self.channels[c]
    }

    /// The largest voxel value of each channel.
    pub fn max(&self) -> Rgb {
        Rgb::new(
            self.channels[0].max(),
            self.channels[1].max(),
            self.channels[2].max(),
        )
    }

    /// The trilinearly interpolated densities at `uvw` ([`DensityGrid::lookup`] per channel).
    #[inline]
    pub fn lookup(&self, uvw: Vec3) -> Rgb {
        Rgb::new(
            self.channels[0].lookup(uvw),
            self.channels[1].lookup(uvw),
            self.channels[2].lookup(uvw),
        )
    }

    /// The grey majorant grid of the extinction `scale_c density_c` over `res` cells per
    /// axis, in **extinction** units: each cell's upper bound is the largest channel's
    /// (`max_c scale_c max_c(cell)`), its lower bound the smallest channel's (`min_c scale_c
    /// min_c(cell)`), each from the channel's own [`MajorantGrid`]. So every channel's
    /// extinction lies between the two in the cell: one sequence of tentative collisions
    /// serves all three (the spectral trackers' convention,
    /// [`crate::spectral_tracking`]), and the lower bound is a control every channel's
    /// residual stays non-negative against.
    pub fn majorants(&self, scale: Rgb, res: [usize; 3]) -> MajorantGrid {
        let grids = self.channels.each_ref().map(|g| MajorantGrid::new(g, res));
        let s = scale.to_array();
        MajorantGrid::from_cell_bounds(res, |[x, y, z]| {
            let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
            for (g, sc) in grids.iter().zip(s) {
                lo = lo.min(sc * g.min_at(x, y, z));
                hi = hi.max(sc * g.max_at(x, y, z));
            }
            (lo, hi)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::SplitMix64;

    #[test]
    fn each_channel_reads_as_its_own_grid() {
        let dims = [3, 2, 4];
        let mut rng = SplitMix64(7);
        let values: Vec<f32> = (0..72).map(|_| rng.f32() * 5.0).collect();
        let g = DensityChannels::new(dims, &values).unwrap();
        for c in 0..3 {
            let plane: Vec<f32> = values.iter().skip(c).step_by(3).copied().collect();
            let one = DensityGrid::new(dims, plane).unwrap();
            assert_eq!(g.channel(c), &one);
            for _ in 0..100 {
                let p = Vec3::new(rng.f32(), rng.f32(), rng.f32());
                assert_eq!(g.lookup(p).to_array()[c], one.lookup(p));
            }
        }
    }

    #[test]
    fn bad_values_name_the_interleaved_index_and_voxel() {
        let mut v = vec![1.0f32; 12];
        v[7] = -0.5; // voxel 2 (x = 0, y = 1), green
        let e = DensityChannels::new([2, 2, 1], &v).unwrap_err();
        assert_eq!(
            e,
            GridValueError::Value {
                index: 7,
                voxel: [0, 1, 0],
                value: -0.5
            }
        );
        v[7] = f32::NAN;
        assert!(DensityChannels::new([2, 2, 1], &v).is_err());
        let e = DensityChannels::new([2, 2, 1], &[1.0; 4]).unwrap_err();
        assert!(matches!(
            e,
            GridValueError::Size {
                expected: 12,
                got: 4,
                ..
            }
        ));
    }

    #[test]
    fn the_shared_majorant_bounds_every_scaled_channel() {
        let dims = [9, 7, 5];
        let mut rng = SplitMix64(3);
        let values: Vec<f32> = (0..dims.iter().product::<usize>() * 3)
            .map(|_| rng.f32() * rng.f32() * 4.0)
            .collect();
        let g = DensityChannels::new(dims, &values).unwrap();
        let scale = Rgb::new(0.5, 3.0, 1.25);
        let m = g.majorants(scale, [4, 3, 2]);
        let mut tight = 0;
        for _ in 0..20000 {
            let p = Vec3::new(rng.f32(), rng.f32(), rng.f32());
            let [x, y, z] = m.cell_of(p);
            let sigma = scale * g.lookup(p);
            assert!(sigma.max_channel() <= m.max_at(x, y, z), "{p}");
            assert!(sigma.min_channel() >= m.min_at(x, y, z), "{p}");
            // The bound is the densest channel's: some points come close to it.
            tight += (sigma.max_channel() > 0.5 * m.max_at(x, y, z)) as u32;
        }
        assert!(tight > 1000, "{tight}");
    }
}
