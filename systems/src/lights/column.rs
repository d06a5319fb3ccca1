//! Light sampling over a column of shading points, eight lanes at a time: the hot path of
//! next-event estimation, bit for bit [`LightSet::sample`] per point.

use super::*;

impl LightSet {
    /// [`Self::sample`] for a column of points: row `i` of `out` is the light sample from
    /// `p[i]` with position sample `(u[i][0], u[i][1])` and selection sample `u[i][2]` (a
    /// vertex's four-dimension set; `u[i][3]` is not used) where `active[i]`, no sample
    /// elsewhere. `geometry` must be the geometry the set was built with.
    ///
    /// Bit for bit `sample`'s results (tested). Points are taken eight at a time
    /// (`simd8` lanes): the selection, and for lanes whose selected light is a
    /// triangle area light (the common case) the point on the triangle, direction, distance
    /// and solid-angle pdf, with one square root and two divisions for the eight. Lanes of
    /// other lights go through `sample` one by one. The columns (rather than
    /// `Option<LightSample>` rows) let the caller hand `out.wi` straight to the Bxdf.
    ///
    /// # Panics
    /// When the columns differ in length.
    pub fn sample_column(
        &self,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        self.sample_column_on(Backend::best(), geometry, p, u, active, out);
    }

    /// [`Self::sample_column`] on the lanes of `backend`.
    pub(super) fn sample_column_on(
        &self,
        backend: Backend,
        geometry: &SceneGeometry,
        p: &[Vec3],
        u: &[[f32; 4]],
        active: &[bool],
        out: &mut LightSampleColumns<'_>,
    ) {
        let len = p.len();
        assert!(
            u.len() == len && active.len() == len && out.len() == len,
            "sample_column: column lengths"
        );
        assert!(out.columns_equally_long(), "sample_column: column lengths");
        let Some(selection) = self.selection.as_ref() else {
            for i in 0..len {
                out.set(i, None);
            }
            return;
        };
        backend.run(LightColumns {
            set: self,
            selection,
            geometry,
            p,
            u,
            active,
            out,
        });
    }

    /// The lights `selection.sample_discrete(u)` chooses for eight lanes of `u`, as lanes
    /// of whole numbers. With few lights, the same count of CDF entries `<= u` (after the
    /// same clamp into `[0, 1)`), eight lanes per compare.
    #[inline(always)]
    fn select_eight<S: Simd>(&self, s: S, selection: &Distribution1D, u: S::F) -> S::F {
        match &self.selection_cdf {
            Some(cdf) => {
                // clamp_unit: NaN and negatives to 0 (the compare is false for NaN).
                let zero = s.splat(0.0);
                let u = S::F::select(zero.le(u), u.min(s.splat(ONE_MINUS_EPSILON)), zero);
                let (mut count, one) = (zero, s.splat(1.0));
                for &c in cdf {
                    count = count + S::F::select(s.splat(c).le(u), one, zero);
                }
                count
            }
            None => {
                let index = u.to_array().map(|u| selection.sample_discrete(u).0 as f32);
                s.load(&Row8(index))
            }
        }
    }

    /// Eight points of [`Self::sample_column`]: `LightSet::sample`'s `Light::Area` branch with
    /// `SceneGeometry::sample_prim`'s triangle branch on the lanes of `s`, operation for
    /// operation the same float arithmetic (no fused multiply-add), so the same bits; lanes
    /// whose light is not a triangle light through `LightSet::sample`.
    #[inline(always)]
    fn sample_eight<S: Simd>(
        &self,
        s: S,
        selection: &Distribution1D,
        geometry: &SceneGeometry,
        (p, u, active): (&[Vec3; 8], &[[f32; 4]; 8], &[bool; 8]),
        out: Out8<'_>,
    ) {
        let [px, py, pz] = s.load_xyz(p);
        // No closures over lane operations here: a closure's body is compiled without the
        // kernel's target features.
        let ux = s.load(&Row8(u.map(|u| u[0])));
        let uy = s.load(&Row8(u.map(|u| u[1])));
        let index = self.select_eight(s, selection, s.load(&Row8(u.map(|u| u[2]))));
        // The attribute table and each lane's column in it: the set's own, by light, or
        // the lanes' lights gathered, by lane.
        let gathered;
        let (l8, column) = match self.lights8.as_deref() {
            Some(l8) => (l8, index),
            None => {
                let index = index
                    .to_array()
                    .map(|i| self.triangle_lights[i as usize].as_ref());
                gathered = Lights8::new(index);
                let lane = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
                (&gathered, s.load(&Row8(lane)))
            }
        };
        let (zero, one, inf) = (s.splat(0.0), s.splat(1.0), s.splat(f32::INFINITY));
        // Heitz 2019 (see SceneGeometry::sample_prim): fold the square onto the triangle.
        let below = ux.lt(uy);
        let half = s.splat(0.5);
        let (hx, hy) = (ux * half, uy * half);
        let b0 = S::F::select(below, hx, ux - hy);
        let b1 = S::F::select(below, uy - hx, hy);
        let b2 = one - b0 - b1;
        let [x0, y0, z0, x1, y1, z1, x2, y2, z2, nx, ny, nz, pmf_over_area, r, g, b, triangle] =
            &l8.attr;
        let triangle = s.lookup(triangle, column).gt(zero).bits();
        let (x0, y0, z0) = (
            s.lookup(x0, column),
            s.lookup(y0, column),
            s.lookup(z0, column),
        );
        let (x1, y1, z1) = (
            s.lookup(x1, column),
            s.lookup(y1, column),
            s.lookup(z1, column),
        );
        let (x2, y2, z2) = (
            s.lookup(x2, column),
            s.lookup(y2, column),
            s.lookup(z2, column),
        );
        let qx = x0 * b0 + x1 * b1 + x2 * b2;
        let qy = y0 * b0 + y1 * b1 + y2 * b2;
        let qz = z0 * b0 + z1 * b1 + z2 * b2;
        let (dx, dy, dz) = (qx - px, qy - py, qz - pz);
        let dist2 = dx * dx + dy * dy + dz * dz;
        // dist2 > 0 and finite (false for NaN), like sample's early return.
        let ok = dist2.gt(zero) & dist2.lt(inf);
        let dist = dist2.sqrt();
        let inv = one / dist;
        let (wx, wy, wz) = (dx * inv, dy * inv, dz * inv);
        // One-sided emitter: cos_light = -n . wi > 0.
        let (nx, ny, nz) = (
            s.lookup(nx, column),
            s.lookup(ny, column),
            s.lookup(nz, column),
        );
        let cos_light = (nx * wx + ny * wy + nz * wz).neg();
        // `light_margin` of `sample_surface`'s bound, `triangle_point_error([v2, v1, v0],
        // b2, b1, b0)`, operation for operation.
        let (ab0, ab1, ab2) = (b0.abs(), b1.abs(), b2.abs());
        let (g3, g4, g5) = (
            s.splat(gamma(3.0)),
            s.splat(gamma(4.0)),
            s.splat(gamma(5.0)),
        );
        let tiny = s.splat(UNDERFLOW);
        let lever = g3 * ((one + ab1) + ab0);
        let ex = (x2.abs() * ab2 + x1.abs() * ab1 + x0.abs() * ab0) * g4 + x2.abs() * lever + tiny;
        let ey = (y2.abs() * ab2 + y1.abs() * ab1 + y0.abs() * ab0) * g4 + y2.abs() * lever + tiny;
        let ez = (z2.abs() * ab2 + z1.abs() * ab1 + z0.abs() * ab0) * g4 + z2.abs() * lever + tiny;
        let ex = ex + g5 * (dx.abs() + qx.abs());
        let ey = ey + g5 * (dy.abs() + qy.abs());
        let ez = ez + g5 * (dz.abs() + qz.abs());
        let along_n = nx.abs() * ex + ny.abs() * ey + nz.abs() * ez;
        let margin = along_n * s.splat(1.0 + gamma(4.0)) / cos_light;
        let pdf = s.lookup(pmf_over_area, column) * dist2 / cos_light;
        let act = s.load(&Row8(active.map(|a| if a { 1.0 } else { 0.0 })));
        let ok = ok & cos_light.gt(zero) & pdf.gt(zero) & pdf.lt(inf) & act.gt(zero);
        // Rows without a sample: pdf 0 and wi +z.
        let wx = S::F::select(ok, wx, zero).to_array();
        let wy = S::F::select(ok, wy, zero).to_array();
        let wz = S::F::select(ok, wz, one).to_array();
        let (r, g, b) = (
            s.lookup(r, column).to_array(),
            s.lookup(g, column).to_array(),
            s.lookup(b, column).to_array(),
        );
        for j in 0..8 {
            out.wi[j] = Vec3::new(wx[j], wy[j], wz[j]);
            out.radiance[j] = Rgb::new(r[j], g[j], b[j]);
        }
        *out.distance = dist.to_array();
        *out.pdf = S::F::select(ok, pdf, zero).to_array();
        *out.delta = [false; 8];
        *out.margin = S::F::select(ok, margin, zero).to_array();
        if triangle != 0xff {
            self.other_lanes(geometry, triangle, p, u, active, out);
        }
    }

    /// The lanes of [`Self::sample_eight`] whose light is not a triangle light (bit clear
    /// in `triangle`), through `LightSet::sample`.
    #[cold]
    #[inline(never)]
    fn other_lanes(
        &self,
        geometry: &SceneGeometry,
        triangle: u32,
        p: &[Vec3; 8],
        u: &[[f32; 4]; 8],
        active: &[bool; 8],
        out: Out8<'_>,
    ) {
        let mut cols = LightSampleColumns {
            wi: out.wi,
            distance: out.distance,
            radiance: out.radiance,
            pdf: out.pdf,
            delta: out.delta,
            margin: out.margin,
        };
        for j in (0..8).filter(|&j| triangle & (1 << j) == 0) {
            let s = active[j]
                .then(|| self.sample(geometry, p[j], u[j][2], Vec2::new(u[j][0], u[j][1])))
                .flatten();
            cols.set(j, s);
        }
    }
}

/// Eight rows of the output columns.
struct Out8<'a> {
    wi: &'a mut [Vec3; 8],
    distance: &'a mut [f32; 8],
    radiance: &'a mut [Rgb; 8],
    pdf: &'a mut [f32; 8],
    delta: &'a mut [bool; 8],
    margin: &'a mut [f32; 8],
}

/// The arguments of [`LightSet::sample_column`] (columns of equal length, a selection
/// exists), as a [`Kernel8`].
struct LightColumns<'a, 'o> {
    set: &'a LightSet,
    selection: &'a Distribution1D,
    geometry: &'a SceneGeometry,
    p: &'a [Vec3],
    u: &'a [[f32; 4]],
    active: &'a [bool],
    out: &'a mut LightSampleColumns<'o>,
}

impl Kernel8 for LightColumns<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        let (set, selection, geometry) = (self.set, self.selection, self.geometry);
        let (p8, p_rest) = self.p.as_chunks::<8>();
        let (u8, u_rest) = self.u.as_chunks::<8>();
        let (a8, a_rest) = self.active.as_chunks::<8>();
        let out = &mut *self.out;
        let (wi8, wi_rest) = out.wi.as_chunks_mut::<8>();
        let (distance8, distance_rest) = out.distance.as_chunks_mut::<8>();
        let (radiance8, radiance_rest) = out.radiance.as_chunks_mut::<8>();
        let (pdf8, pdf_rest) = out.pdf.as_chunks_mut::<8>();
        let (delta8, delta_rest) = out.delta.as_chunks_mut::<8>();
        let (margin8, margin_rest) = out.margin.as_chunks_mut::<8>();
        let outs = wi8
            .iter_mut()
            .zip(distance8)
            .zip(radiance8)
            .zip(pdf8)
            .zip(delta8)
            .zip(margin8);
        for (((p, u), a), o) in p8.iter().zip(u8).zip(a8).zip(outs) {
            let (((((wi, distance), radiance), pdf), delta), margin) = o;
            let o = Out8 {
                wi,
                distance,
                radiance,
                pdf,
                delta,
                margin,
            };
            set.sample_eight(s, selection, geometry, (p, u, a), o);
        }
        if !p_rest.is_empty() {
            // The last partial block, padded with inactive copies of its first point.
            // Element loops rather than `copy_from_slice`: a `memcpy` call of a varying
            // small length mispredicts inside.
            let (mut p, mut u, mut a) = ([p_rest[0]; 8], [u_rest[0]; 8], [false; 8]);
            for (j, ((&pr, &ur), &ar)) in p_rest.iter().zip(u_rest).zip(a_rest).enumerate() {
                (p[j], u[j], a[j]) = (pr, ur, ar);
            }
            let (mut wi, mut distance, mut radiance) = ([Vec3::Z; 8], [0.0; 8], [Rgb::BLACK; 8]);
            let (mut pdf, mut delta, mut margin) = ([0.0; 8], [false; 8], [0.0; 8]);
            let o = Out8 {
                wi: &mut wi,
                distance: &mut distance,
                radiance: &mut radiance,
                pdf: &mut pdf,
                delta: &mut delta,
                margin: &mut margin,
            };
            set.sample_eight(s, selection, geometry, (&p, &u, &a), o);
            let rest = wi_rest
                .iter_mut()
                .zip(distance_rest)
                .zip(radiance_rest)
                .zip(pdf_rest)
                .zip(delta_rest)
                .zip(margin_rest);
            for (j, (((((w, d), r), p), de), mg)) in rest.enumerate() {
                (*w, *d, *r, *p, *de) = (wi[j], distance[j], radiance[j], pdf[j], delta[j]);
                *mg = margin[j];
            }
        }
    }
}
