//! pbrt-v4 media (`MakeNamedMedium`) as risotto interiors: `homogeneous` as the homogeneous
//! interior, `uniformgrid` (`GridMedium`) and `rgbgrid` (`RGBGridMedium`) as heterogeneous
//! interiors whose density (and for `rgbgrid` albedo) are inline grid patterns.
//!
//! pbrt looks the density up in the box `[p0, p1]` of medium space (the CTM at
//! `MakeNamedMedium`) with `SampledGrid::Lookup`: voxel `i` sits at `(i + 1/2) / n` of the
//! box, trilinear between voxel centres, and indices outside the grid read 0, so the field
//! falls to 0 over the half voxel next to each face and is 0 outside the box (pbrt-v4,
//! `util/containers.h` `SampledGrid`, `media.h` `GridMedium`). That is risotto's grid
//! pattern with `border = "zero"` on the box `[p0, p1]`, placed by the medium's CTM
//! (`transform`).
//! `sigma_t = (sigma_a + sigma_s) scale density` and the albedo `sigma_s / (sigma_a +
//! sigma_s)` are constant colours, as risotto's heterogeneous `scale` and `albedo`.

use glam::{DMat4, DVec3};
use risotto_engine::diagnostics::SceneError;

use super::convert::Converter;
use super::lexer::At;
use super::params::{Colour, Params};
use crate::import::Entity;

/// The largest grid converted: risotto's grid limit (the TOML holds every value as text).
const MAX_VALUES: usize = crate::grid_file::MAX_VOXELS;

impl Converter<'_> {
    /// `MakeNamedMedium` at `at` in medium space `m` (the CTM there): an `interior` table.
    pub(super) fn medium(
        &mut self,
        p: &Params,
        at: &At,
        m: &glam::DMat4,
    ) -> Result<toml::Table, SceneError> {
        let lx = &self.lx;
        let Some((ty, q)) = p.string(lx, "type")? else {
            return Err(lx.error(
                risotto_engine::diagnostics::SceneErrorKind::MissingField,
                &p.list.first().map_or_else(
                    || super::lexer::At {
                        file: 0,
                        span: 0..0,
                    },
                    |q| q.at.clone(),
                ),
                &p.entity,
                "needs \"string type\"",
            ));
        };
        if ty == "nanovdb" {
            return Err(p.error(lx, q, "medium \"nanovdb\": NanoVDB files are not read (there is no maintained Rust NanoVDB reader); convert the grid to OpenVDB (.vdb) or Mitsuba's .vol and give it to a risotto heterogeneous medium"));
        }
        if !["homogeneous", "uniformgrid", "rgbgrid"].contains(&ty) {
            return Err(p.error(
                lx,
                q,
                format!("medium \"{ty}\" is not supported (\"homogeneous\", \"uniformgrid\", \"rgbgrid\")"),
            ));
        }
        if let Some(q) = p.ignore("preset") {
            return Err(p.error(
                lx,
                q,
                "named scattering presets are not supported; give sigma_a and sigma_s",
            ));
        }
        let rgb = |name: &str| -> Result<[f64; 3], SceneError> {
            match p.colour(lx, name, false, &|q| self.spectrum_colour(p, q))? {
                None => Ok([1.0; 3]),
                Some(Colour::Rgb(c)) => Ok(c),
                Some(_) => {
                    let q = p.list.iter().find(|q| q.name == name).expect("given");
                    Err(p.error(lx, q, "give an rgb value"))
                }
            }
        };
        let scale = p.float(lx, "scale", 1.0)?;
        let g = p.float_where(lx, "g", 0.0, "in (-1, 1)", |g| g.abs() < 1.0)?;
        let phase = (g != 0.0).then(|| {
            let mut phase = toml::Table::new();
            phase.insert("type".into(), "hg".into());
            phase.insert("g".into(), g.into());
            phase
        });
        if ty == "rgbgrid" {
            return self.rgb_grid_medium(p, at, m, scale, phase);
        }
        let sa = rgb("sigma_a")?.map(|c| c * scale);
        let ss = rgb("sigma_s")?.map(|c| c * scale);
        if ty == "uniformgrid" {
            return self.grid_medium(p, at, m, sa, ss, phase);
        }
        let mut t = Entity::new(None)
            .with("type", "homogeneous")
            .with("sigma_a", sa.to_vec())
            .with("sigma_s", ss.to_vec());
        if let Some(phase) = phase {
            t.set("phase", phase);
        }
        if p.has("Le") {
            let le = match p.colour(lx, "Le", false, &|q| self.spectrum_colour(p, q))? {
                Some(Colour::Rgb(c)) => c,
                _ => [0.0; 3],
            };
            let ls = p.float(lx, "Lescale", 1.0)?;
            // pbrt's source term is sigma_a Le (`HomogeneousMedium`); risotto's is the
            // emission coefficient itself.
            let j: Vec<f64> = (0..3).map(|i| sa[i] * le[i] * ls).collect();
            if j.iter().any(|&x| x > 0.0) {
                t.set("emission", j);
            }
        }
        Ok(t.table)
    }

    /// The grid's voxel counts (`nx`, `ny`, `nz`), checked, and its box and placement as the
    /// keys of a grid pattern (`dims`, `min`, `max`, `border = "zero"`, `transform`).
    fn grid_box(&self, p: &Params, at: &At, m: &DMat4) -> Result<GridBox, SceneError> {
        let lx = &self.lx;
        for key in [
            "temperature",
            "Le",
            "Lescale",
            "temperaturecutoff",
            "temperaturescale",
        ] {
            if let Some(q) = p.ignore(key) {
                return Err(p.error(lx, q, "emission of a grid medium is not converted"));
            }
        }
        let mut dims = [0usize; 3];
        for (d, k) in dims.iter_mut().zip(["nx", "ny", "nz"]) {
            let v = p.int(lx, k, 1)?;
            if !(1..=1 << 20).contains(&v) {
                let q = p
                    .list
                    .iter()
                    .find(|q| q.name == k)
                    .expect("given: default 1 fits");
                return Err(p.error(lx, q, format!("must be in [1, {}], got {v}", 1 << 20)));
            }
            *d = v as usize;
        }
        let p0 = DVec3::from(p.vec3(lx, "p0")?.unwrap_or([0.0; 3]));
        let p1 = DVec3::from(p.vec3(lx, "p1")?.unwrap_or([1.0; 3]));
        if !((p1 - p0).cmpgt(DVec3::ZERO).all() && (p1 - p0).is_finite()) {
            let q = p
                .list
                .iter()
                .find(|q| q.name == "p1")
                .or_else(|| p.list.iter().find(|q| q.name == "p0"));
            let message = format!("the box p0 = {p0} .. p1 = {p1} must have p1 > p0 on every axis");
            return Err(match q {
                Some(q) => p.error(lx, q, message),
                None => self.error(at, &p.entity, message),
            });
        }
        let mut keys = Entity::new(None)
            .with("dims", dims.iter().map(|&d| d as i64).collect::<Vec<_>>())
            .with("border", "zero")
            .with("min", p0.to_array().to_vec())
            .with("max", p1.to_array().to_vec());
        if *m != DMat4::IDENTITY {
            keys.set("transform", self.transform_value(m, at, &p.entity)?);
        }
        Ok(GridBox {
            count: dims.iter().product(),
            padded: dims.iter().map(|d| d + 2).product(),
            keys: keys.table,
        })
    }

    /// The values of `name` (`per` numbers per voxel, finite and >= 0), as many as `grid`
    /// has voxels.
    fn grid_values<'p>(
        &self,
        p: &'p Params,
        at: &At,
        grid: &GridBox,
        name: &str,
        per: usize,
    ) -> Result<&'p [f64], SceneError> {
        let lx = &self.lx;
        let types: &[&str] = if per == 1 { &["float"] } else { &["rgb"] };
        let Some((values, q)) = p.nums(lx, name, types, per)? else {
            return Err(self.error(
                at,
                &p.entity,
                format!("needs \"{} {name}\" (nx * ny * nz values)", types[0]),
            ));
        };
        if values.len() != grid.count * per {
            return Err(p.error(
                lx,
                q,
                format!(
                    "has {} values; nx * ny * nz = {} {}",
                    values.len() / per,
                    grid.count,
                    if per == 1 { "" } else { "colours" }
                )
                .trim_end()
                .to_owned(),
            ));
        }
        if grid.padded > MAX_VALUES {
            return Err(p.error(lx, q, format!("a grid of {} voxels is larger than risotto reads ({MAX_VALUES} with its border)", grid.count)));
        }
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(p.error(
                lx,
                q,
                format!("value {i} is {v}: densities must be finite and >= 0"),
            ));
        }
        Ok(values)
    }

    /// `MakeNamedMedium "name" "string type" "uniformgrid"` in medium space `m`, with the
    /// scaled coefficients and phase the caller read: a heterogeneous `interior` table.
    pub(super) fn grid_medium(
        &self,
        p: &Params,
        at: &At,
        m: &DMat4,
        sigma_a: [f64; 3],
        sigma_s: [f64; 3],
        phase: Option<toml::Table>,
    ) -> Result<toml::Table, SceneError> {
        let grid = self.grid_box(p, at, m)?;
        let density = self.grid_values(p, at, &grid, "density", 1)?;
        let sigma_t: Vec<f64> = (0..3).map(|c| sigma_a[c] + sigma_s[c]).collect();
        let albedo: Vec<f64> = (0..3)
            .map(|c| {
                if sigma_t[c] > 0.0 {
                    sigma_s[c] / sigma_t[c]
                } else {
                    0.0
                }
            })
            .collect();
        let mut t = Entity::new(None)
            .with("type", "heterogeneous")
            .with("density", grid.pattern(density.iter().copied()))
            .with("scale", sigma_t)
            .with("albedo", albedo);
        if let Some(phase) = phase {
            t.set("phase", phase);
        }
        Ok(t.table)
    }

    /// `MakeNamedMedium "name" "string type" "rgbgrid"` in medium space `m`: a colour
    /// `sigma_a` and `sigma_s` per voxel (pbrt-v4's `RGBGridMedium`, both looked up by the
    /// same `SampledGrid` as `uniformgrid`'s density), times `scale`. risotto's heterogeneous
    /// interior with a density per channel, `sigma_t = sigma_a + sigma_s` (trilinear, so the
    /// sum of the two looked-up fields is the lookup of the summed voxels), and the albedo
    /// `sigma_s / (sigma_s + sigma_a)` of the two looked-up fields (a `fraction` pattern),
    /// as pbrt evaluates them.
    fn rgb_grid_medium(
        &self,
        p: &Params,
        at: &At,
        m: &DMat4,
        scale: f64,
        phase: Option<toml::Table>,
    ) -> Result<toml::Table, SceneError> {
        let grid = self.grid_box(p, at, m)?;
        let sa = self.grid_values(p, at, &grid, "sigma_a", 3)?;
        let ss = self.grid_values(p, at, &grid, "sigma_s", 3)?;
        let colour = |f: &dyn Fn(usize) -> f64| {
            let channel = |c: usize| {
                let mut factor = [0.0; 3];
                factor[c] = 1.0;
                let mut t = toml::Table::new();
                t.insert("pattern".into(), "scale".into());
                t.insert(
                    "a".into(),
                    grid.pattern((0..grid.count).map(|i| f(3 * i + c))),
                );
                t.insert("factor".into(), factor.to_vec().into());
                toml::Value::Table(t)
            };
            let add = |a: toml::Value, b: toml::Value| {
                let mut t = toml::Table::new();
                t.insert("pattern".into(), "add".into());
                t.insert("a".into(), a);
                t.insert("b".into(), b);
                toml::Value::Table(t)
            };
            add(add(channel(0), channel(1)), channel(2))
        };
        let sigma_t = colour(&|k| (sa[k] + ss[k]) * scale);
        let mut albedo = toml::Table::new();
        albedo.insert("pattern".into(), "fraction".into());
        albedo.insert("a".into(), colour(&|k| ss[k]));
        albedo.insert("b".into(), colour(&|k| sa[k]));
        let mut t = Entity::new(None)
            .with("type", "heterogeneous")
            .with("density", sigma_t)
            .with("albedo", albedo);
        if let Some(phase) = phase {
            t.set("phase", phase);
        }
        Ok(t.table)
    }
}

/// A grid medium's voxel counts and the placement keys of its grid patterns.
struct GridBox {
    /// `nx ny nz`.
    count: usize,
    /// `(nx + 2) (ny + 2) (nz + 2)`: with the zero border.
    padded: usize,
    /// `dims`, `border`, `min`, `max` and `transform` of its grid patterns.
    keys: toml::Table,
}

impl GridBox {
    /// A grey grid pattern of `values` (one per voxel, x fastest) in the box.
    fn pattern(&self, values: impl Iterator<Item = f64>) -> toml::Value {
        let mut t = self.keys.clone();
        t.insert("pattern".into(), "grid".into());
        t.insert(
            "values".into(),
            values.map(toml::Value::from).collect::<Vec<_>>().into(),
        );
        toml::Value::Table(t)
    }
}
