//! The light vertices of a batch's light subpaths: a table the camera subpaths connect to.
//!
//! Only vertices a connection can use are stored: those whose closure has a non-Dirac lobe.
//! Each light subpath has at most one vertex per bounce, so the table is filled bounce by
//! bounce and `by_bounce[b][path]` finds path `path`'s vertex of bounce `b` (or
//! [`NO_VERTEX`]). Memory: one row (the shading point, about 120 bytes, plus 40 bytes of
//! path state and the volume stack) per stored vertex, at most `max_depth - 1` per light
//! subpath, so at most `batch size x (max_depth - 1)` rows per batch. `vcm` keeps the tables
//! of every batch of an iteration until its camera pass (at most
//! [`ITERATION_LIGHT_PATHS`](super::ITERATION_LIGHT_PATHS) light subpaths).

use super::mis::SubpathMis;
use risotto_components::{Rgb, ShadingPoints, VolumeStack};

/// No vertex at this bounce of this path.
pub const NO_VERTEX: u32 = u32::MAX;

/// Stored light vertices.
#[derive(Default)]
pub struct LightVertices {
    /// The shading point of each vertex; `vn` points back along the light subpath.
    pub points: ShadingPoints,
    /// Light subpath throughput arriving at the vertex (importance transport: light's
    /// radiance from the start times every Bxdf and transmittance since, over the pdfs).
    pub throughput: Vec<Rgb>,
    /// The subpath's MIS sums at the vertex (after arriving).
    pub mis: Vec<SubpathMis>,
    /// Segments from the light to the vertex.
    pub segments: Vec<u32>,
    /// The volumes the arriving ray travelled in.
    pub stack: Vec<VolumeStack>,
    /// Per bounce, per light subpath: the vertex of that bounce.
    pub by_bounce: Vec<Vec<u32>>,
    /// Per bounce: its vertices' rows (contiguous: a bounce's groups are stored one after
    /// the other), as runs of one material and mode each.
    pub runs: Vec<Vec<LightRun>>,
}

/// Rows of [`LightVertices::points`] of one material and mode.
#[derive(Clone, Debug)]
pub struct LightRun {
    /// The material.
    pub material: u32,
    /// Surface or medium points.
    pub mode: crate::shade_groups::ShadingMode,
    /// The rows.
    pub rows: std::ops::Range<usize>,
}

impl LightVertices {
    /// Empties the table for a batch of `paths` light subpaths.
    pub fn clear(&mut self) {
        self.points.clear();
        self.throughput.clear();
        self.mis.clear();
        self.segments.clear();
        self.stack.clear();
        for b in &mut self.by_bounce {
            b.clear();
        }
        for r in &mut self.runs {
            r.clear();
        }
    }

    /// Records that rows `rows` (just stored) of bounce `bounce` are of `material`, `mode`.
    pub fn push_run(
        &mut self,
        bounce: usize,
        material: u32,
        mode: crate::shade_groups::ShadingMode,
        rows: std::ops::Range<usize>,
    ) {
        while self.runs.len() <= bounce {
            self.runs.push(Vec::new());
        }
        self.runs[bounce].push(LightRun {
            material,
            mode,
            rows,
        });
    }

    /// The rows of bounce `bounce`'s vertices.
    pub fn bounce_rows(&self, bounce: usize) -> std::ops::Range<usize> {
        match self.runs.get(bounce).map(|r| (r.first(), r.last())) {
            Some((Some(a), Some(b))) => a.rows.start..b.rows.end,
            _ => 0..0,
        }
    }

    /// Number of stored vertices.
    pub fn len(&self) -> usize {
        self.throughput.len()
    }

    /// True when no vertex is stored.
    pub fn is_empty(&self) -> bool {
        self.throughput.is_empty()
    }

    /// The per-path index of bounce `bounce`, made (all [`NO_VERTEX`]) when new.
    pub fn bounce_mut(&mut self, bounce: usize, paths: usize) -> &mut [u32] {
        while self.by_bounce.len() <= bounce {
            self.by_bounce.push(Vec::new());
        }
        let b = &mut self.by_bounce[bounce];
        if b.len() != paths {
            b.clear();
            b.resize(paths, NO_VERTEX);
        }
        b
    }

    /// Bounces that hold some vertex.
    pub fn bounces(&self) -> usize {
        self.by_bounce.iter().take_while(|b| !b.is_empty()).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use risotto_components::ShadingPointRow;
    use std::mem::size_of;

    /// The per-vertex memory the README states (at most 200 bytes a stored vertex), from
    /// the columns' element sizes.
    #[test]
    fn a_stored_vertex_takes_at_most_200_bytes() {
        let row = size_of::<ShadingPointRow>()
            + size_of::<Rgb>()
            + size_of::<SubpathMis>()
            + size_of::<u32>()
            + size_of::<VolumeStack>();
        assert!(row <= 200, "{row} bytes a vertex");
    }

    #[test]
    fn bounces_index_their_paths_vertices() {
        let mut v = LightVertices::default();
        v.bounce_mut(0, 3)[1] = 0;
        v.bounce_mut(1, 3)[2] = 1;
        assert_eq!(v.bounces(), 2);
        assert_eq!(v.by_bounce[0], [NO_VERTEX, 0, NO_VERTEX]);
        v.clear();
        assert_eq!(v.bounces(), 0, "a cleared table has no bounce");
    }
}
