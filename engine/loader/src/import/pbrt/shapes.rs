//! pbrt-v4 shapes and area lights.
//!
//! Orientation (which side an area light emits from): pbrt-v4's triangle faces along
//! `(p1 - p0) x (p2 - p0)` transformed as a normal, flipped by `ReverseOrientation`; when
//! the mesh has normals `N`, its face turns towards them (pbrt-v4 `Triangle`,
//! `FaceForward(n, ns)`; `ReverseOrientation` flips `N` too). risotto's front is the
//! winding's, so each triangle is wound to face where pbrt's faces.

use glam::{DMat4, DVec3};
use risotto_engine::diagnostics::SceneError;

use super::convert::{AreaLight, Converter};
use super::lexer::At;
use super::params::{Colour, Params};
use crate::import::{path_for_toml, Entity};

impl Converter<'_> {
    /// `AreaLightSource "diffuse"`.
    pub(super) fn area_light(&mut self, ty: &str, p: &Params, at: &At) -> Result<(), SceneError> {
        if ty != "diffuse" {
            return Err(self.error(
                at,
                &p.entity,
                format!("area light \"{ty}\" is not supported (only \"diffuse\")"),
            ));
        }
        let lx = &self.lx;
        let l = match p.colour(lx, "L", false, &|q| self.spectrum_colour(p, q))? {
            Some(Colour::Rgb(c)) => c,
            None => [1.0; 3],
            Some(_) => unreachable!("textures and names are refused above"),
        };
        let scale = p.float(lx, "scale", 1.0)?;
        if p.bool(lx, "twosided", false)? {
            let q = p.list.iter().find(|q| q.name == "twosided").expect("given");
            return Err(p.error(
                lx,
                q,
                "two-sided area lights are not supported (risotto's emit from the front)",
            ));
        }
        for k in ["filename", "power"] {
            if let Some(q) = p.ignore(k) {
                return Err(p.error(lx, q, "is not supported (give L and scale)"));
            }
        }
        self.gs.area_light = Some(AreaLight {
            radiance: l.map(|c| c * scale),
            at: at.clone(),
        });
        Ok(())
    }

    /// `Shape "..."`.
    pub(super) fn shape(&mut self, ty: &str, p: &Params, at: &At) -> Result<(), SceneError> {
        let entity = p.entity.clone();
        // pbrt-v4's `alpha` (a float or a float texture: 1 opaque, 0 absent, stochastic in
        // between) is risotto's `opacity`, which lives on materials: the shape gets its
        // material with `opacity` set (one such copy per material and alpha).
        self.shape_opacity = match self.colour_value(p, "alpha", true)? {
            Some(toml::Value::Array(c)) => {
                let a = c.first().and_then(|v| v.as_float()).unwrap_or(1.0);
                if !(0.0..=1.0).contains(&a) {
                    let q = p.list.iter().find(|q| q.name == "alpha").expect("given");
                    return Err(p.error(&self.lx, q, format!("alpha {a} must be in [0, 1]")));
                }
                (a < 1.0).then_some(toml::Value::Float(a))
            }
            other => other,
        };
        for k in ["emissionfilename", "displacement", "edgelength"] {
            if let Some(q) = p.ignore(k) {
                return Err(p.error(&self.lx, q, "is not supported"));
            }
        }
        let ctm = self.gs.ctm;
        let mut e = Entity::new(Some(self.origin(at)));
        let mut local = DMat4::IDENTITY;
        match ty {
            "trianglemesh" | "bilinearmesh" => self.triangles(ty, p, at, &mut e)?,
            "loopsubdiv" => self.loop_subdiv(p, at, &mut e)?,
            "plymesh" => {
                let Some((file, _)) = p.string(&self.lx, "filename")? else {
                    return Err(self.error(at, &entity, "needs \"string filename\""));
                };
                let path = self.lx.resolve(at, file);
                if self.gs.reverse && self.gs.area_light.is_some() {
                    return Err(self.error(at, &entity, "ReverseOrientation on an emitting PLY mesh is not supported"));
                }
                e.set("type", "mesh");
                e.set("path", path_for_toml(&path, self.options.toml_dir));
                // pbrt has no shadow-terminator offset: render as it does.
                e.set("shadow_terminator_offset", false);
            }
            "sphere" => {
                let r = p.float_where(&self.lx, "radius", 1.0, "> 0", |r| r > 0.0)?;
                let zmin = p.float(&self.lx, "zmin", -r)?;
                let zmax = p.float(&self.lx, "zmax", r)?;
                let phimax = p.float(&self.lx, "phimax", 360.0)?;
                if zmin > -r || zmax < r || phimax < 360.0 {
                    return Err(self.error(at, &entity, "partial spheres (zmin, zmax, phimax) are not supported"));
                }
                if self.gs.reverse && self.gs.area_light.is_some() {
                    return Err(self.error(at, &entity, "ReverseOrientation on an emitting sphere is not supported (risotto's spheres emit outwards)"));
                }
                // risotto's sphere is a centre and a radius: the transform must be a
                // similarity (rotation, mirror, uniform scale, translation).
                let m = if self.object.is_some() { ctm } else { self.world_root * ctm };
                let a = glam::DMat3::from_mat4(m);
                let s = a.x_axis.length();
                let similar = (a.y_axis.length() - s).abs() <= 1e-9 * s
                    && (a.z_axis.length() - s).abs() <= 1e-9 * s
                    && a.x_axis.dot(a.y_axis).abs() <= 1e-9 * s * s
                    && a.x_axis.dot(a.z_axis).abs() <= 1e-9 * s * s
                    && a.y_axis.dot(a.z_axis).abs() <= 1e-9 * s * s;
                if !similar || s == 0.0 {
                    return Err(self.error(at, &entity, "a sphere under a non-uniform scale or shear is not supported (risotto's spheres are round)"));
                }
                let c = m.transform_point3(DVec3::ZERO);
                e.set("type", "sphere");
                e.set("center", vec![c.x, c.y, c.z]);
                e.set("radius", r * s);
                return self.finish_shape(e, None, at, &entity);
            }
            "disk" => {
                let r = p.float_where(&self.lx, "radius", 1.0, "> 0", |r| r > 0.0)?;
                let ri = p.float_where(&self.lx, "innerradius", 0.0, "in [0, radius)", |x| x >= 0.0 && x < r)?;
                let h = p.float(&self.lx, "height", 0.0)?;
                if p.float(&self.lx, "phimax", 360.0)? < 360.0 {
                    return Err(self.error(at, &entity, "partial disks (phimax) are not supported"));
                }
                e.set("type", "disk");
                e.set("radius", r);
                if ri > 0.0 {
                    e.set("inner_radius", ri);
                }
                local = DMat4::from_translation(DVec3::new(0.0, 0.0, h));
                if self.gs.reverse {
                    // The disk faces +z; a mirror of z turns it (normals follow mirrors).
                    local *= DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0));
                }
            }
            _ => {
                return Err(self.error(at, &entity, format!("shape \"{ty}\" is not supported (trianglemesh, bilinearmesh, loopsubdiv, plymesh, sphere, disk)")))
            }
        }
        let m = if self.object.is_some() {
            ctm * local
        } else {
            self.world_root * ctm * local
        };
        let t = self.transform_value(&m, at, &entity)?;
        self.finish_shape(e, Some(t), at, &entity)
    }

    /// Adds the material, emission and transform, and files the shape in the scene or the
    /// open object.
    fn finish_shape(
        &mut self,
        mut e: Entity,
        transform: Option<toml::Value>,
        at: &At,
        entity: &str,
    ) -> Result<(), SceneError> {
        if let Some(t) = transform {
            if !is_identity(&t) {
                e.set("transform", t);
            }
        }
        let material = self.material_for_shape(at, entity)?;
        e.set("material", material.as_str());
        if let Some(light) = self.gs.area_light.clone() {
            if self.object.is_some() {
                return Err(self.error(&light.at, entity, "area lights inside an object (ObjectBegin) are not supported (pbrt-v4 refuses them too)"));
            }
            e.set("emission", light.radiance.to_vec());
        }
        let (inside, outside) = (self.gs.inside.clone(), self.gs.outside.clone());
        let holds = !inside.is_empty() && inside != outside;
        let borders = !outside.is_empty() && inside != outside;
        match &mut self.object {
            Some((_, shapes, _)) => {
                if borders {
                    return Err(self.error(at, entity, format!("a shape in an object (ObjectBegin) cannot have an outside medium (\"{outside}\"): its instances may sit anywhere")));
                }
                shapes.push(toml::Value::Table(e.table))
            }
            None => {
                // pbrt-v4 switches media only at shapes whose inside and outside differ
                // (leaving to the outside, "" = vacuum) and keeps the medium across any
                // other; risotto nests volumes. They agree where no medium surrounds a
                // shape that bounds a volume but states no outside medium (a medium's
                // boundary, a glass, an interface): checked (`within = "no medium"`) when
                // the scene has media (finish).
                let bounds_volume = holds || self.scene.bounds_clear_volume(&material);
                let vacuum_outside = bounds_volume && !borders;
                // A shape holding or bordering a medium is named for `within` checks.
                if holds || borders || vacuum_outside {
                    let line = self.lx.line(at);
                    let kind = entity.trim_start_matches("Shape ").trim_matches('"');
                    let name = self.unique(&format!("{kind} at line {line}"));
                    e.set("name", name.as_str());
                    if holds {
                        self.medium_holders.push((inside, name));
                    }
                    if borders {
                        self.outsides
                            .push((outside, self.scene.shapes.len(), at.clone()));
                    }
                    if vacuum_outside {
                        self.no_medium_outside.push(self.scene.shapes.len());
                    }
                }
                self.scene.shapes.push(e)
            }
        }
        Ok(())
    }

    /// `trianglemesh` (P, indices, N, uv) and `bilinearmesh` (P, indices in fours, each quad
    /// split into two triangles), as a `triangles` shape.
    fn triangles(
        &mut self,
        ty: &str,
        p: &Params,
        at: &At,
        e: &mut Entity,
    ) -> Result<(), SceneError> {
        let lx = &self.lx;
        let entity = p.entity.clone();
        let Some((pos, pq)) = p.nums(lx, "P", &["point3", "point"], 3)? else {
            return Err(self.error(at, &entity, "needs \"point3 P\""));
        };
        let nv = pos.len() / 3;
        let per = if ty == "bilinearmesh" { 4 } else { 3 };
        let indices: Vec<u32> = match p.ints(lx, "indices")? {
            Some((i, q)) => {
                if i.len() % per != 0 {
                    return Err(p.error(
                        lx,
                        q,
                        format!("expected a multiple of {per} indices, got {}", i.len()),
                    ));
                }
                if let Some(bad) = i.iter().find(|&&x| x as usize >= nv) {
                    return Err(p.error(
                        lx,
                        q,
                        format!("index {bad} is out of range (P has {nv} points)"),
                    ));
                }
                i
            }
            None if nv == per => (0..per as u32).collect(),
            None => {
                return Err(p.error(
                    lx,
                    pq,
                    format!(
                        "without \"integer indices\", P must hold exactly {per} points, got {nv}"
                    ),
                ))
            }
        };
        let normals = match p.nums(lx, "N", &["normal", "normal3"], 3)? {
            Some((n, q)) if n.len() != pos.len() => {
                return Err(p.error(
                    lx,
                    q,
                    format!("expected one normal per point ({nv}), got {}", n.len() / 3),
                ))
            }
            n => n.map(|(n, _)| n),
        };
        let uv = match p.nums(lx, "uv", &["point2", "float"], 2)? {
            Some((u, q)) if u.len() / 2 != nv => {
                return Err(p.error(
                    lx,
                    q,
                    format!("expected one uv per point ({nv}), got {}", u.len() / 2),
                ))
            }
            u => u.map(|(u, _)| u),
        };
        for k in ["S", "faceIndices"] {
            if let Some(q) = p.ignore(k) {
                return Err(p.error(lx, q, "is not supported"));
            }
        }
        let point = |i: u32| {
            DVec3::new(
                pos[3 * i as usize],
                pos[3 * i as usize + 1],
                pos[3 * i as usize + 2],
            )
        };
        let mut tris: Vec<[u32; 3]> = Vec::with_capacity(indices.len() / per * (per - 2));
        if per == 4 {
            let mut warned = false;
            for q in indices.chunks_exact(4) {
                // pbrt's patch corners are p00, p10, p01, p11; its normal is along
                // (p10 - p00) x (p01 - p00). Split along p00-p11.
                let [a, b, c, d] = [q[0], q[1], q[2], q[3]];
                let n = (point(b) - point(a)).cross(point(c) - point(a));
                let off = (point(d) - point(a)).dot(n.normalize_or_zero());
                let size = (point(d) - point(a)).length();
                if !warned && off.abs() > 1e-6 * size {
                    warned = true;
                    self.warnings.push(format!(
                        "{}:{}: a bilinear patch is not planar; it is split into two flat triangles (pbrt renders it curved)",
                        lx.path(at).display(),
                        lx.line(at)
                    ));
                }
                tris.push([a, b, d]);
                tris.push([a, d, c]);
            }
        } else {
            tris.extend(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
        }
        let pos = pos.to_vec();
        let normals = normals.map(<[f64]>::to_vec);
        let uv = uv.map(<[f64]>::to_vec);
        self.emit_triangles(pos, &tris, normals, uv, e);
        Ok(())
    }

    /// `loopsubdiv` (`levels`, default 3; `P`, `indices`): subdivided here
    /// ([`super::loop_subdiv`]) and written as a `triangles` shape with the limit normals.
    fn loop_subdiv(&mut self, p: &Params, at: &At, e: &mut Entity) -> Result<(), SceneError> {
        let lx = &self.lx;
        let entity = p.entity.clone();
        let levels = p.int(lx, "levels", 3)?;
        let Some((pos, _)) = p.nums(lx, "P", &["point3", "point"], 3)? else {
            return Err(self.error(at, &entity, "needs \"point3 P\""));
        };
        let Some((indices, iq)) = p.ints(lx, "indices")? else {
            return Err(self.error(at, &entity, "needs \"integer indices\""));
        };
        let nv = pos.len() / 3;
        if indices.len() % 3 != 0 {
            return Err(p.error(
                lx,
                iq,
                format!("expected a multiple of 3 indices, got {}", indices.len()),
            ));
        }
        if let Some(bad) = indices.iter().find(|&&x| x as usize >= nv) {
            return Err(p.error(
                lx,
                iq,
                format!("index {bad} is out of range (P has {nv} points)"),
            ));
        }
        if !(0..=16).contains(&levels) {
            let q = p.list.iter().find(|q| q.name == "levels").expect("given");
            return Err(p.error(lx, q, format!("must be in [0, 16], got {levels}")));
        }
        let points: Vec<DVec3> = pos
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect();
        let tris: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let s = super::loop_subdiv::loop_subdivide(&points, &tris, levels as u32)
            .map_err(|m| self.error(at, &entity, m))?;
        let flat = |v: &[DVec3]| v.iter().flat_map(|q| q.to_array()).collect::<Vec<f64>>();
        self.emit_triangles(
            flat(&s.positions),
            &s.triangles,
            Some(flat(&s.normals)),
            None,
            e,
        );
        Ok(())
    }

    /// Writes a `triangles` shape, each triangle wound so its front is pbrt's (see the
    /// module documentation).
    fn emit_triangles(
        &mut self,
        pos: Vec<f64>,
        tris: &[[u32; 3]],
        normals: Option<Vec<f64>>,
        uv: Option<Vec<f64>>,
        e: &mut Entity,
    ) {
        let point = |i: u32| {
            DVec3::new(
                pos[3 * i as usize],
                pos[3 * i as usize + 1],
                pos[3 * i as usize + 2],
            )
        };
        let reverse = self.gs.reverse;
        let normals = normals.as_deref();
        let normal_at = |i: u32| {
            normals.map_or(DVec3::ZERO, |n| {
                DVec3::new(
                    n[3 * i as usize],
                    n[3 * i as usize + 1],
                    n[3 * i as usize + 2],
                )
            })
        };
        let mut flat = Vec::with_capacity(tris.len() * 3);
        for &[a, b, c] in tris {
            let winding = (point(b) - point(a)).cross(point(c) - point(a));
            let flip = match normals {
                Some(_) => {
                    (winding.dot(normal_at(a) + normal_at(b) + normal_at(c)) < 0.0) ^ reverse
                }
                None => reverse,
            };
            let t = if flip { [a, c, b] } else { [a, b, c] };
            flat.extend(t.map(|i| toml::Value::Integer(i64::from(i))));
        }
        e.set("type", "triangles");
        e.set("indices", toml::Value::Array(flat));
        if let Some(n) = normals {
            e.set("normals", n.to_vec());
            // pbrt has no shadow-terminator offset: render as it does.
            e.set("shadow_terminator_offset", false);
        }
        e.set("positions", pos);
        if let Some(u) = uv {
            e.set("uv", u);
        }
    }
}

/// Whether a transform list is the identity matrix.
fn is_identity(t: &toml::Value) -> bool {
    let Some(step) = t
        .as_array()
        .and_then(|a| a.first())
        .and_then(|s| s.get("matrix"))
    else {
        return false;
    };
    let want = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    step.as_array().is_some_and(|rows| {
        rows.iter().zip(want).all(|(r, w)| {
            r.as_array()
                .is_some_and(|c| c.iter().zip(w).all(|(x, y)| x.as_float() == Some(y)))
        })
    })
}
