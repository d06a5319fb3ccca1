//! Structure-of-arrays tables. Each table is a set of equally long columns; row `i` of every
//! column describes item `i`. Systems take the columns they need as slices, so their hot loops
//! run over contiguous memory.

use crate::{LobeSampled, Rgb, VolumeStack};
use glam::Vec3;

/// Marks a miss in [`Hits::prim`].
pub const NO_HIT: u32 = u32::MAX;

/// Declares an SoA table `$name` with its columns, a row type `$row` holding one item and a
/// view `$cols` of some rows' columns as mutable slices.
macro_rules! soa_table {
    (
        $(#[$meta:meta])* $name:ident, $(#[$rmeta:meta])* $row:ident,
        $(#[$cmeta:meta])* $cols:ident {
            $( $(#[$fmeta:meta])* $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, Default)]
        pub struct $name {
            $( $(#[$fmeta])* pub $field: Vec<$ty>, )*
        }

        $(#[$rmeta])*
        #[derive(Clone, Debug, Default)]
        pub struct $row {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }

        $(#[$cmeta])*
        #[derive(Debug)]
        pub struct $cols<'a> {
            $( $(#[$fmeta])* pub $field: &'a mut [$ty], )*
        }

        impl $name {
            /// An empty table with room for `n` rows in every column.
            #[inline]
            pub fn with_capacity(n: usize) -> Self {
                Self { $( $field: Vec::with_capacity(n), )* }
            }
            /// Number of rows.
            #[inline]
            pub fn len(&self) -> usize {
                self.first_len()
            }
            /// True when the table has no rows.
            #[inline]
            pub fn is_empty(&self) -> bool {
                self.len() == 0
            }
            /// Removes every row, keeping the columns' allocations.
            #[inline]
            pub fn clear(&mut self) {
                $( self.$field.clear(); )*
            }
            /// Appends one row. Every column checks its capacity and stores its length; to
            /// write many rows, [`append_default`](Self::append_default) or
            /// [`reuse_rows`](Self::reuse_rows) and writing the returned slices avoids that.
            #[inline]
            pub fn push(&mut self, row: $row) {
                $( self.$field.push(row.$field); )*
            }
            /// Appends `n` rows of default values and returns the new rows' columns, each
            /// exactly `n` long. A loop that writes row `j < n` of every slice needs no
            /// capacity checks and (since all slices have the same, known length) at most one
            /// bounds check per row, where per-row [`push`](Self::push) pays a capacity check
            /// and a length update per column. Rows not written keep their defaults; drop
            /// unused ones with [`truncate`](Self::truncate).
            #[inline]
            pub fn append_default(&mut self, n: usize) -> $cols<'_> {
                let start = self.len();
                $( self.$field.resize(start + n, Default::default()); )*
                $cols { $( $field: &mut self.$field[start..start + n], )* }
            }
            /// Sets the table to `n` rows and returns every column, for a caller that
            /// overwrites every column of every row it keeps: rows that existed keep their old
            /// values, only rows beyond the old length are defaults. A table whose rows are
            /// dead can so be refilled without first writing defaults into every column as
            /// [`append_default`](Self::append_default) does.
            #[inline]
            pub fn reuse_rows(&mut self, n: usize) -> $cols<'_> {
                $( self.$field.resize(n, Default::default()); )*
                $cols { $( $field: &mut self.$field[..n], )* }
            }
            /// Keeps the first `n` rows (no effect when the table is not longer).
            #[inline]
            pub fn truncate(&mut self, n: usize) {
                $( self.$field.truncate(n); )*
            }
            /// Copies row `i` out.
            #[inline]
            pub fn row(&self, i: usize) -> $row {
                $row { $( $field: self.$field[i].clone(), )* }
            }
            /// Appends a copy of row `i` of `other`.
            #[inline]
            pub fn push_from(&mut self, other: &Self, i: usize) {
                $( self.$field.push(other.$field[i].clone()); )*
            }
            /// Keeps the rows `i` with `keep[i]` (in order) and removes the others, in place.
            ///
            /// # Panics
            /// When `keep` is not as long as the table.
            pub fn retain_rows(&mut self, keep: &[bool]) {
                self.retain_rows_from(0, keep);
            }
            /// Keeps the rows `start + i` with `keep[i]` (in order) and removes the others
            /// of that tail, in place; rows before `start` are not touched, so a caller that
            /// filters only the rows it appended pays for those alone.
            ///
            /// # Panics
            /// When `keep` is not as long as the tail from `start`.
            pub fn retain_rows_from(&mut self, start: usize, keep: &[bool]) {
                assert_eq!(
                    keep.len(),
                    self.len().saturating_sub(start),
                    "one flag per row"
                );
                // The kept rows up to the first removed one stay where they are; the kept
                // rows after it are listed once, so each column moves just those, without a
                // branch per row and column.
                let first = keep.iter().position(|&k| !k).unwrap_or(keep.len());
                let later: Vec<usize> = (first..keep.len())
                    .filter(|&k| keep[k])
                    .map(|k| start + k)
                    .collect();
                let at = start + first;
                $( {
                    let column = &mut self.$field[..];
                    for (j, &src) in later.iter().enumerate() {
                        column.swap(at + j, src);
                    }
                    self.$field.truncate(at + later.len());
                } )*
            }
            /// Appends copies of the rows `rows` of `other`, in that order: one gather per
            /// column, where [`push_from`](Self::push_from) per row checks the capacity and
            /// stores the length of every column for every row.
            ///
            /// # Panics
            /// When a row index is out of `other`'s range.
            pub fn extend_gather(&mut self, other: &Self, rows: &[u32]) {
                $( {
                    let src = &other.$field[..];
                    self.$field.extend(rows.iter().map(|&i| src[i as usize].clone()));
                } )*
            }
            /// Appends a copy of the rows `range` of `other`, in order.
            ///
            /// # Panics
            /// When `range` is out of `other`'s range.
            pub fn extend_from_range(&mut self, other: &Self, range: std::ops::Range<usize>) {
                $( self.$field.extend_from_slice(&other.$field[range.clone()]); )*
            }
            /// Appends a copy of every row of `other`.
            #[inline]
            pub fn extend_from(&mut self, other: &Self) {
                $( self.$field.extend_from_slice(&other.$field); )*
            }
            /// Debug check that every column has the same length.
            pub fn is_consistent(&self) -> bool {
                let n = self.len();
                true $( && self.$field.len() == n )*
            }
            fn first_len(&self) -> usize {
                soa_table!(@first self $( $field )*)
            }
        }
    };
    (@first $self:ident $first:ident $( $rest:ident )*) => { $self.$first.len() };
}

soa_table! {
    /// A batch of rays in flight (camera rays or the next bounce of paths).
    Rays,
    /// One ray of a [`Rays`] table.
    RayRow,
    /// Mutable column slices of some rows of a [`Rays`] table (from `append_default`
    /// or `reuse_rows`).
    RayColumns {
        /// World-space origin.
        origin: Vec3,
        /// Unit direction.
        direction: Vec3,
        /// Smallest accepted hit distance.
        tmin: f32,
        /// Largest accepted hit distance (`f32::INFINITY` for unbounded rays).
        tmax: f32,
        /// Index of the path (camera sample) this ray belongs to, in the batch's [`Paths`].
        path: u32,
        /// Path throughput carried by this ray (includes Russian-roulette `1/q` factors).
        throughput: Rgb,
        /// Lobe that produced the ray ([`LobeSampled::NONE`] for camera rays).
        lobe: LobeSampled,
        /// Scattering bounces so far (camera rays: 0). Pass-throughs do not count.
        depth: u16,
        /// Pass-throughs (index-matched and false boundaries) so far; bounded separately.
        passes: u16,
        /// Solid-angle pdf of the direction sampling that produced the ray (for MIS when it
        /// hits an emitter); 0 for specular lobes and camera rays.
        pdf: f32,
        /// Product of squared relative IORs crossed (for Russian roulette, as pbrt-v4's
        /// `etaScale`).
        eta_scale: f32,
        /// Next sampler dimension of this path.
        dimension: u32,
        /// Index of the shading point this ray left from, in the group that produced it
        /// (RIS `shadingCtxIndex`); `u32::MAX` for camera rays.
        shading_ctx_index: u32,
        /// Position of the last scattering vertex (the camera for camera rays). Pass-throughs
        /// keep it, so the light pdf of an emitter hit after them is measured from the vertex
        /// that sampled the direction (for MIS).
        prev_p: Vec3,
        /// Volumes the ray travels in.
        volume_stack: VolumeStack,
    }
}

soa_table! {
    /// The state of every camera sample (path) of a batch.
    Paths,
    /// One path of a [`Paths`] table.
    PathRow,
    /// Mutable column slices of some rows of a [`Paths`] table (from `append_default`
    /// or `reuse_rows`).
    PathColumns {
        /// Pixel index `y * width + x` in the film.
        pixel: u32,
        /// Sample index within the pixel (the Sobol index).
        sample: u32,
        /// Radiance gathered so far; splatted when the path ends.
        radiance: Rgb,
        /// First-hit albedo (AOV).
        albedo: Rgb,
        /// First-hit shading normal (AOV).
        normal: Vec3,
        /// First-hit distance from the camera (AOV); infinity on a miss.
        depth: f32,
    }
}

soa_table! {
    /// Nearest-hit results, one row per ray of the [`Rays`] table they answer.
    Hits,
    /// One row of a [`Hits`] table.
    HitRow,
    /// Mutable column slices of some rows of a [`Hits`] table (from `append_default`
    /// or `reuse_rows`).
    HitColumns {
        /// Hit distance along the ray.
        t: f32,
        /// Primitive index in the compiled scene, or [`NO_HIT`].
        prim: u32,
        /// First barycentric (triangles) or surface parameter (spheres).
        b1: f32,
        /// Second barycentric (triangles) or surface parameter (spheres).
        b2: f32,
    }
}

soa_table! {
    /// Shading points (RIS shading-context builtins), grouped so that points of one shading
    /// context are contiguous.
    ShadingPoints,
    /// One row of a [`ShadingPoints`] table.
    ShadingPointRow,
    /// Mutable column slices of some rows of a [`ShadingPoints`] table (from `append_default`
    /// or `reuse_rows`).
    ShadingPointColumns {
        /// Position `P`.
        p: Vec3,
        /// Geometric normal `Ng` (outward for closed shapes).
        ng: Vec3,
        /// How far along `ng` the exact surface can be from `p`: `dot(|ng|, p_error)` of
        /// the point's per-component rounding-error bound (0 inside a volume). Rays spawned
        /// here move off the surface by it (`risotto_systems::ray`); one `f32` rather than
        /// the `Vec3` bound because every use is along `ng`.
        p_offset: f32,
        /// Where rays leaving to the viewer's side of a triangle start, relative to `p`:
        /// the displacement to the smooth surface the mesh's vertex normals imply
        /// (`risotto_systems::terminator`, Hanika 2021), written only for meshes that ask
        /// for the shadow-terminator offset; zero elsewhere.
        terminator_lift: Vec3,
        /// Shading normal `Nn`, on the same side as `ng`.
        nn: Vec3,
        /// Unit tangent orthogonal to `nn` (`dPdu` made orthogonal to `nn` on meshes with
        /// texture coordinates; the direction of increasing `phi` on spheres; elsewhere, and
        /// inside volumes, some unit vector orthogonal to `nn` that varies continuously with
        /// it): with `nn` it fixes the frame of anisotropic Bxdfs.
        tangent: Vec3,
        /// Unit vector towards the viewer `Vn` (`-ray direction`).
        vn: Vec3,
        /// Length of the incident ray segment `VLen`.
        vlen: f32,
        /// Surface (or volume) parameter `u`.
        u: f32,
        /// Surface (or volume) parameter `v`.
        v: f32,
        /// Volume parameter `w` (0 on surfaces).
        w: f32,
        /// Transmission over the incident segment, written by the volume integrator that
        /// returned this point; the global integrator multiplies it into the path.
        transmission: Rgb,
        /// Index of the ray (in the table passed to `nearest_hits`) that produced the point.
        ray_id: u32,
        /// Material (Bxdf factory) index.
        material: u32,
        /// Shape index (`u32::MAX` for points inside a volume).
        shape: u32,
        /// The ray arrived against `ng` (from outside a closed shape).
        front_face: bool,
        /// Index of refraction of the medium outside this shape's interior at the point (the
        /// renderer derives it from the ray's volume stack; 1 in vacuum). Dielectrics refract
        /// with `eta = ior_inside / ior_outside`, so liquid in glass gets the right ratio.
        ior_outside: f32,
    }
}

soa_table! {
    /// Shadow (transmission) rays: straight, never bending segments towards light samples.
    ShadowRays,
    /// One row of a [`ShadowRays`] table.
    ShadowRayRow,
    /// Mutable column slices of some rows of a [`ShadowRays`] table (from `append_default`
    /// or `reuse_rows`).
    ShadowRayColumns {
        /// Origin (already offset from the surface).
        origin: Vec3,
        /// Unit direction.
        direction: Vec3,
        /// Distance to the light sample (slightly shortened); infinity for distant lights.
        tmax: f32,
        /// Unoccluded contribution `throughput * f * Le * mis / pdf`.
        contribution: Rgb,
        /// The contribution's factor without the light's radiance, `throughput * f * mis /
        /// pdf`: what multiplies radiance emitted by volumes along the shadow ray.
        weight: Rgb,
        /// Path the contribution is added to.
        path: u32,
        /// First sampler dimension of the shadow ray's own sequence (the vertex's first
        /// dimension; the sequence is decorrelated from the camera path's by its seed).
        dimension: u32,
        /// Volumes the shadow ray starts in.
        volume_stack: VolumeStack,
    }
}

impl ShadingPointRow {
    /// A shading point at the start of a segment inside a volume (no surface: normals face
    /// the viewer, transmission 1, no shape). Binds volume integrators to the rays or shadow
    /// segments they answer.
    pub fn in_volume(p: Vec3, direction: Vec3, ray_id: u32, material: u32) -> Self {
        ShadingPointRow {
            p,
            ng: -direction,
            p_offset: 0.0,
            terminator_lift: Vec3::ZERO,
            nn: -direction,
            tangent: (-direction).any_orthonormal_vector(),
            vn: -direction,
            vlen: 0.0,
            u: 0.0,
            v: 0.0,
            w: 0.0,
            transmission: Rgb::WHITE,
            ray_id,
            material,
            shape: u32::MAX,
            front_face: true,
            ior_outside: 1.0,
        }
    }
}

impl ShadingPoints {
    /// Appends one [`ShadingPointRow::in_volume`] row per `(p[i], direction[i])`, with
    /// `ray_id = i`, column by column (a per-row [`push`](Self::push) checks the capacity of
    /// every column for every row).
    ///
    /// # Panics
    /// When `p` and `direction` differ in length.
    pub fn extend_in_volume(&mut self, p: &[Vec3], direction: &[Vec3], material: u32) {
        assert_eq!(p.len(), direction.len(), "one direction per point");
        let (start, m) = (self.len(), p.len());
        let row = ShadingPointRow::in_volume(Vec3::ZERO, Vec3::Z, 0, material);
        let facing = || direction.iter().map(|&d| -d);
        self.p.extend_from_slice(p);
        self.ng.extend(facing());
        self.p_offset.resize(start + m, row.p_offset);
        self.terminator_lift.resize(start + m, row.terminator_lift);
        self.nn.extend(facing());
        self.tangent
            .extend(facing().map(Vec3::any_orthonormal_vector));
        self.vn.extend(facing());
        self.vlen.resize(start + m, row.vlen);
        self.u.resize(start + m, row.u);
        self.v.resize(start + m, row.v);
        self.w.resize(start + m, row.w);
        self.transmission.resize(start + m, row.transmission);
        self.ray_id.extend(0..m as u32);
        self.material.resize(start + m, row.material);
        self.shape.resize(start + m, row.shape);
        self.front_face.resize(start + m, row.front_face);
        self.ior_outside.resize(start + m, row.ior_outside);
        assert!(
            self.is_consistent(),
            "a shading-point column was not filled"
        );
    }
}

impl Rays {
    /// Asserts the table invariants in debug builds.
    pub fn debug_check(&self) {
        debug_assert!(self.is_consistent());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_and_row_round_trip() {
        let mut h = Hits::default();
        h.push(HitRow {
            t: 2.0,
            prim: 3,
            b1: 0.25,
            b2: 0.5,
        });
        assert_eq!(h.len(), 1);
        assert!(h.is_consistent());
        assert_eq!(h.row(0).prim, 3);
        h.clear();
        assert!(h.is_empty());
    }

    fn hit(t: f32, prim: u32) -> HitRow {
        HitRow {
            t,
            prim,
            b1: t * 0.5,
            b2: t * 0.25,
        }
    }

    fn prims(h: &Hits) -> Vec<u32> {
        h.prim.clone()
    }

    #[test]
    fn append_default_returns_exactly_the_new_rows() {
        let mut h = Hits::default();
        h.push(hit(1.0, 10));
        h.push(hit(2.0, 20));
        let cols = h.append_default(3);
        assert_eq!((cols.t.len(), cols.prim.len(), cols.b1.len()), (3, 3, 3));
        assert!(cols.prim.iter().all(|&p| p == 0) && cols.t.iter().all(|&t| t == 0.0));
        cols.prim[0] = 30;
        cols.t[2] = 5.0;
        assert_eq!(h.len(), 5);
        assert!(h.is_consistent());
        assert_eq!(prims(&h), vec![10, 20, 30, 0, 0]);
        assert_eq!(h.t[4], 5.0);
        assert_eq!(h.row(1).b1, 1.0, "existing rows untouched");
        h.truncate(3);
        assert_eq!(prims(&h), vec![10, 20, 30]);
        h.truncate(7);
        assert_eq!(h.len(), 3, "truncate never grows");
        assert!(h.is_consistent());
    }

    #[test]
    fn reuse_rows_keeps_existing_rows_and_defaults_new_ones() {
        let mut h = Hits::default();
        for i in 0..3 {
            h.push(hit(i as f32 + 1.0, i));
        }
        let cols = h.reuse_rows(2);
        assert_eq!(cols.prim, &[0, 1], "old values, not defaults");
        assert_eq!(h.len(), 2);
        let cols = h.reuse_rows(4);
        assert_eq!(cols.prim.len(), 4);
        assert_eq!(cols.prim, &[0, 1, 0, 0]);
        assert_eq!(cols.t, &[1.0, 2.0, 0.0, 0.0]);
        assert!(h.is_consistent());
    }

    #[test]
    fn retain_rows_keeps_flagged_rows_in_order() {
        let mut h = Hits::default();
        for i in 0..5 {
            h.push(hit(i as f32, i));
        }
        h.retain_rows(&[true, false, false, true, true]);
        assert_eq!(prims(&h), vec![0, 3, 4]);
        assert_eq!(h.t, vec![0.0, 3.0, 4.0]);
        assert_eq!(h.row(1).b1, 1.5, "rows move whole");
        assert!(h.is_consistent());
    }

    #[test]
    fn extend_in_volume_equals_rows_pushed_one_by_one() {
        let p = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, 0.5, 0.0)];
        let d = [Vec3::X, Vec3::new(0.0, -0.6, 0.8)];
        let mut bulk = ShadingPoints::default();
        bulk.push(ShadingPointRow::in_volume(Vec3::ONE, Vec3::Y, 9, 1));
        bulk.extend_in_volume(&p, &d, 7);
        let mut rows = ShadingPoints::default();
        rows.push(ShadingPointRow::in_volume(Vec3::ONE, Vec3::Y, 9, 1));
        for i in 0..2 {
            rows.push(ShadingPointRow::in_volume(p[i], d[i], i as u32, 7));
        }
        assert_eq!(bulk.len(), 3);
        for k in 0..3 {
            assert_eq!(format!("{:?}", bulk.row(k)), format!("{:?}", rows.row(k)));
        }
    }

    #[test]
    fn retain_rows_from_filters_only_the_tail() {
        let mut h = Hits::default();
        for i in 0..6 {
            h.push(hit(i as f32, i));
        }
        h.retain_rows_from(2, &[false, true, false, true]);
        assert_eq!(prims(&h), vec![0, 1, 3, 5]);
        assert_eq!(h.t, vec![0.0, 1.0, 3.0, 5.0]);
        assert!(h.is_consistent());
        h.retain_rows_from(4, &[]);
        assert_eq!(prims(&h), vec![0, 1, 3, 5]);
    }

    #[test]
    #[should_panic(expected = "one flag per row")]
    fn retain_rows_wants_one_flag_per_row() {
        let mut h = Hits::default();
        h.push(hit(1.0, 1));
        h.retain_rows(&[]);
    }

    #[test]
    fn extend_gather_and_range_match_push_from() {
        let mut src = Hits::default();
        for i in 0..6 {
            src.push(hit(i as f32 + 0.5, 100 + i));
        }
        let rows = [4u32, 0, 4, 2];
        let (mut a, mut b) = (Hits::default(), Hits::default());
        a.push(hit(9.0, 9));
        b.push(hit(9.0, 9));
        a.extend_gather(&src, &rows);
        for &i in &rows {
            b.push_from(&src, i as usize);
        }
        assert_eq!(prims(&a), vec![9, 104, 100, 104, 102]);
        assert_eq!(prims(&a), prims(&b));
        assert_eq!((a.t.clone(), a.b1.clone(), a.b2.clone()), (b.t, b.b1, b.b2));
        a.extend_from_range(&src, 1..3);
        assert_eq!(prims(&a)[5..], [101, 102]);
        assert_eq!(a.t[5..], [1.5, 2.5]);
        assert!(a.is_consistent());
    }

    #[test]
    fn extend_from_appends_every_row_in_order() {
        let mut a = Hits::default();
        a.push(hit(1.0, 1));
        let mut b = Hits::default();
        b.push(hit(2.0, 2));
        b.push(hit(3.0, 3));
        a.extend_from(&b);
        assert_eq!(prims(&a), vec![1, 2, 3]);
        assert_eq!(a.row(2).b2, 0.75);
        assert!(a.is_consistent());
    }
}
