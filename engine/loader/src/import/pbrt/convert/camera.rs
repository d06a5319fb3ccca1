//! The camera and the render settings: `Camera`, `Film`, `Sampler`, `Integrator`,
//! `PixelFilter`, and the camera placed from pbrt's camera transform.

use super::*;

impl Converter<'_> {
    /// `Film`, `Sampler`, `Integrator`, `PixelFilter`, `Accelerator`.
    pub(super) fn render_setting(
        &mut self,
        name: &str,
        ty: &str,
        p: &Params,
        at: &At,
        render: &mut Entity,
    ) -> Result<(), SceneError> {
        let lx = &self.lx;
        let entity = p.entity.clone();
        render
            .origin
            .get_or_insert_with(|| origin(lx.path(at), lx.line(at)));
        match name {
            "Film" => {
                if ty != "rgb" && ty != "gbuffer" {
                    return Err(self.error(
                        at,
                        &entity,
                        format!(
                            "film \"{ty}\" is not supported (only \"rgb\"; risotto renders RGB)"
                        ),
                    ));
                }
                let w = p.int(lx, "xresolution", 1280)?;
                let h = p.int(lx, "yresolution", 720)?;
                for (k, v) in [("xresolution", w), ("yresolution", h)] {
                    if !(1..=65536).contains(&v) {
                        let at = p
                            .list
                            .iter()
                            .find(|q| q.name == k)
                            .map(|q| q.at.clone())
                            .unwrap_or(at.clone());
                        return Err(self.error(
                            &at,
                            &entity,
                            format!("`{k}` must be in [1, 65536], got {v}"),
                        ));
                    }
                }
                render.set("width", w);
                render.set("height", h);
                p.ignore("filename");
                p.ignore("savefp16");
                p.ignore("diagonal");
                if let Some((c, q)) = p.nums(lx, "cropwindow", &["float"], 4)? {
                    if c != [0.0, 1.0, 0.0, 1.0] {
                        return Err(p.error(
                            lx,
                            q,
                            "a crop window is not supported (render the whole image)",
                        ));
                    }
                }
                if let Some((_, q)) = p.nums(lx, "pixelbounds", &["integer"], 4)? {
                    return Err(p.error(
                        lx,
                        q,
                        "pixel bounds are not supported (render the whole image)",
                    ));
                }
                let iso = p.float(lx, "iso", 100.0)?;
                let wb = p.float(lx, "whitebalance", 0.0)?;
                if iso != 100.0 || wb != 0.0 {
                    let q = p
                        .list
                        .iter()
                        .find(|q| q.name == "iso" || q.name == "whitebalance")
                        .expect("given");
                    return Err(p.error(lx, q, "iso and white balance are not supported (risotto writes the radiance: iso 100, no white balance)"));
                }
                if let Some((s, q)) = p.string(lx, "sensor")? {
                    if s != "cie1931" {
                        return Err(p.error(lx, q, "only the \"cie1931\" sensor is supported"));
                    }
                }
                if let Some(q) = p.ignore("maxcomponentvalue") {
                    let v = p.float(lx, "maxcomponentvalue", f64::INFINITY)?;
                    if v.is_finite() {
                        return Err(p.error(lx, q, "clamping sample values is not supported"));
                    }
                }
            }
            "Sampler" => {
                p.ignore("seed");
                p.ignore("randomization");
                p.ignore("dimension");
                let spp = p.int(lx, "pixelsamples", 16)?;
                if !(1..=1 << 24).contains(&spp) {
                    let q = p
                        .list
                        .iter()
                        .find(|q| q.name == "pixelsamples")
                        .expect("given");
                    return Err(p.error(lx, q, format!("must be in [1, 16777216], got {spp}")));
                }
                render.set("spp", spp);
            }
            "Integrator" => {
                match ty {
                    "path" | "volpath" => {}
                    "bdpt" | "mlt" | "sppm" | "simplepath" | "simplevolpath" | "randomwalk" => {
                        self.warnings.push(format!(
                            "{}:{}: integrator \"{ty}\" is rendered with risotto's path tracer (the same image in expectation, different noise)",
                            self.lx.path(at).display(),
                            self.lx.line(at)
                        ));
                        for k in ["mutationsperpixel", "chains", "bootstrapsamples", "largestepprobability", "sigma", "iterations", "photonsperiteration", "radius", "seed", "visualizestrategies", "visualizeweights"] {
                            p.ignore(k);
                        }
                    }
                    _ => return Err(self.error(at, &entity, format!("integrator \"{ty}\" is not supported (it renders a different image than a path tracer)"))),
                }
                let lx = &self.lx;
                let depth = p.int(lx, "maxdepth", 5)?;
                if !(0..i64::from(u32::MAX)).contains(&depth) {
                    let q = p.list.iter().find(|q| q.name == "maxdepth").expect("given");
                    return Err(p.error(lx, q, format!("must be >= 0, got {depth}")));
                }
                // pbrt's maxdepth counts scattering events; risotto's max_depth counts
                // path segments (Mitsuba's convention): one more.
                render.set("max_depth", depth + 1);
                if p.bool(lx, "regularize", false)? {
                    let q = p
                        .list
                        .iter()
                        .find(|q| q.name == "regularize")
                        .expect("given");
                    return Err(p.error(lx, q, "path regularization is not supported"));
                }
                p.ignore("lightsampler");
            }
            "PixelFilter" => {
                let xr = p.float(lx, "xradius", f64::NAN)?;
                let yr = p.float(lx, "yradius", f64::NAN)?;
                if !(xr.is_nan() && yr.is_nan()) && xr != yr {
                    let q = p
                        .list
                        .iter()
                        .find(|q| q.name == "xradius" || q.name == "yradius")
                        .expect("given");
                    return Err(p.error(lx, q, "xradius and yradius must be equal (risotto's filters are the same along x and y)"));
                }
                let r = if xr.is_nan() { yr } else { xr };
                let (kind, default_r) = match ty {
                    "box" => ("box", 0.5),
                    "triangle" => ("tent", 2.0),
                    "gaussian" => ("gaussian", 1.5),
                    _ => return Err(self.error(at, &entity, format!("filter \"{ty}\" is not supported (box, triangle, gaussian; filters with negative lobes cannot be importance sampled)"))),
                };
                let r = if r.is_nan() { default_r } else { r };
                if !(r > 0.0 && r.is_finite()) {
                    return Err(self.error(
                        at,
                        &entity,
                        format!("the filter radius must be > 0, got {r}"),
                    ));
                }
                render.table.remove("filter_stddev");
                render.set("filter", kind);
                render.set("filter_radius", r);
                if kind == "gaussian" {
                    let s = p.float_where(lx, "sigma", 0.5, "> 0", |s| s > 0.0)?;
                    render.set("filter_stddev", s);
                }
                if kind == "box" && r == 0.5 {
                    // The default filter: written as nothing, so such scenes need no filter support.
                    render.table.remove("filter");
                    render.table.remove("filter_radius");
                }
            }
            _ => {
                // Accelerator: how rays are traced, not what they see.
                for q in &p.list {
                    p.ignore(&q.name);
                }
            }
        }
        Ok(())
    }

    /// The risotto camera from pbrt's `Camera` (after the whole file: the film's aspect
    /// ratio is needed for the field of view).
    pub(super) fn camera(
        &mut self,
        ty: &str,
        p: &Params,
        at: &At,
        render: &Entity,
    ) -> Result<(), SceneError> {
        let world_from_camera = self.named_coords["camera"];
        let (pos, fwd, up, _) = camera_frame(&world_from_camera);
        let (pos, fwd, up) = (
            self.world_root.transform_point3(pos),
            self.world_root.transform_vector3(fwd),
            self.world_root.transform_vector3(up),
        );
        let w = render.table["width"].as_integer().unwrap_or(1280) as f64;
        let h = render.table["height"].as_integer().unwrap_or(720) as f64;
        let lx = &self.lx;
        let entity = p.entity.clone();
        let mut cam = Entity::new(Some(self.origin(at)))
            .with("from", vec![pos.x, pos.y, pos.z])
            .with("to", vec![pos.x + fwd.x, pos.y + fwd.y, pos.z + fwd.z])
            .with("up", vec![up.x, up.y, up.z]);
        for k in ["frameaspectratio", "screenwindow"] {
            if let Some(q) = p.ignore(k) {
                return Err(p.error(
                    lx,
                    q,
                    "is not supported (the image's aspect ratio decides the screen window)",
                ));
            }
        }
        let open = p.float(lx, "shutteropen", 0.0)?;
        let close = p.float(lx, "shutterclose", 1.0)?;
        if close - open != 1.0 {
            let q = p
                .list
                .iter()
                .find(|q| q.name.starts_with("shutter"))
                .expect("given");
            return Err(p.error(
                lx,
                q,
                "an exposure time other than 1 scales pbrt's image; not supported",
            ));
        }
        match ty {
            "perspective" => {
                let fov =
                    p.float_where(lx, "fov", 90.0, "in (0, 180)", |f| f > 0.0 && f < 180.0)?;
                // pbrt's fov spans the shorter image axis; risotto's is horizontal.
                let hfov = if w >= h {
                    2.0 * ((fov.to_radians() / 2.0).tan() * w / h).atan().to_degrees()
                } else {
                    fov
                };
                cam.set("fov", hfov);
                let lens = p.float_where(lx, "lensradius", 0.0, ">= 0", |r| r >= 0.0)?;
                let focus = p.float_where(lx, "focaldistance", 1e6, "> 0", |d| d > 0.0)?;
                if lens > 0.0 {
                    cam.set("projection", "thin_lens");
                    cam.set("aperture_radius", lens);
                    cam.set("focus_distance", focus);
                }
            }
            "orthographic" => {
                cam.set("projection", "orthographic");
                // pbrt's default screen window spans [-1, 1] along the shorter axis.
                cam.set("width", if w >= h { 2.0 * w / h } else { 2.0 });
                if p.float(lx, "lensradius", 0.0)? != 0.0 {
                    let q = p
                        .list
                        .iter()
                        .find(|q| q.name == "lensradius")
                        .expect("given");
                    return Err(p.error(
                        lx,
                        q,
                        "an orthographic camera with a lens is not supported",
                    ));
                }
                p.ignore("focaldistance");
            }
            _ => {
                return Err(self.error(
                    at,
                    &entity,
                    format!("camera \"{ty}\" is not supported (perspective, orthographic)"),
                ))
            }
        }
        self.scene.camera = cam;
        Ok(())
    }

    /// pbrt's camera when the file has none: at the origin looking along +z, fov 90.
    pub(super) fn default_camera(&mut self, render: &Entity) {
        let w = render.table["width"].as_integer().unwrap_or(1280) as f64;
        let h = render.table["height"].as_integer().unwrap_or(720) as f64;
        let (pos, fwd, up) = (
            self.world_root.transform_point3(DVec3::ZERO),
            self.world_root.transform_vector3(DVec3::Z),
            self.world_root.transform_vector3(DVec3::Y),
        );
        let fov = 90f64;
        let hfov = if w >= h {
            2.0 * ((fov.to_radians() / 2.0).tan() * w / h).atan().to_degrees()
        } else {
            fov
        };
        self.scene.camera = Entity::new(None)
            .with("from", vec![pos.x, pos.y, pos.z])
            .with("to", vec![pos.x + fwd.x, pos.y + fwd.y, pos.z + fwd.z])
            .with("up", vec![up.x, up.y, up.z])
            .with("fov", hfov);
    }
}

/// The eye, view direction, up and right (pbrt's camera +x) of a world-from-camera
/// matrix, unit length.
pub(super) fn camera_frame(world_from_camera: &DMat4) -> (DVec3, DVec3, DVec3, DVec3) {
    let pos = world_from_camera.transform_point3(DVec3::ZERO);
    let fwd = world_from_camera.transform_vector3(DVec3::Z).normalize();
    let up = world_from_camera.transform_vector3(DVec3::Y).normalize();
    let right = world_from_camera.transform_vector3(DVec3::X).normalize();
    (pos, fwd, up, right)
}

/// pbrt's `LookAt ex ey ez  lx ly lz  ux uy uz`: the camera-from-world matrix of a camera
/// at `e` looking at `l`, camera +x = normalize(cross(up, dir)), +y = cross(dir, +x), +z =
/// dir (pbrt-v4 `LookAt`, a left-handed camera space); `None` when degenerate.
pub(super) fn look_at(v: &[f64]) -> Option<DMat4> {
    let eye = DVec3::new(v[0], v[1], v[2]);
    let look = DVec3::new(v[3], v[4], v[5]);
    let up = DVec3::new(v[6], v[7], v[8]);
    let dir = (look - eye).try_normalize()?;
    let right = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    );
    Some(world_from_camera.inverse())
}
