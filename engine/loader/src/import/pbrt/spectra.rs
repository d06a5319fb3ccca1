//! pbrt-v4's spectra as RGB: sampled (`"spectrum Kd" [ 400 0.3  500 0.6 ... ]`), `.spd`
//! files, `blackbody` temperatures and named spectra, converted by
//! [`crate::import::spectrum`] (Mitsuba 3's RGB conventions) with pbrt's normalisation of
//! light spectra.
//!
//! pbrt-v4 divides every light's spectrum by its photometric value,
//! `scale /= SpectrumToPhotometric(spectrum)` (`lights.cpp`; for an RGB value only the
//! colour space's illuminant counts, so RGB lights keep their values): a `blackbody` or
//! sampled light spectrum has luminance 1 times `scale`. So a light's spectrum is
//! converted as an emission and divided by its luminance `Y = 0.2126 R + 0.7152 G +
//! 0.0722 B` (Rec.709).

use risotto_engine::diagnostics::{SceneError, SceneErrorKind};

use super::convert::Converter;
use super::params::{Colour, Param, Params, Values};
use crate::import::spectrum::{blackbody_rgb, sampled_to_rgb, SpectrumUse};

/// How a parameter's spectrum is converted, by the parameter's name.
enum Use {
    /// Converted with this use.
    Plain(SpectrumUse),
    /// A light's: an emission normalised to unit luminance.
    Light,
}

fn use_of(name: &str) -> Use {
    match name {
        "L" | "I" => Use::Light,
        "Le" => Use::Plain(SpectrumUse::Emission),
        n if n == "eta" || n == "k" || n.ends_with(".eta") || n.ends_with(".k") => {
            Use::Plain(SpectrumUse::Unbounded)
        }
        n if n.starts_with("sigma_") => Use::Plain(SpectrumUse::Unbounded),
        _ => Use::Plain(SpectrumUse::Reflectance),
    }
}

impl Converter<'_> {
    /// A `spectrum` or `blackbody` parameter (other than a single constant) as a colour:
    /// named spectra are returned by name (the caller maps the ones it knows).
    pub(super) fn spectrum_colour(&self, p: &Params, q: &Param) -> Result<Colour, SceneError> {
        let lx = &self.lx;
        let samples: Vec<(f64, f64)> = match (&q.ty[..], &q.values) {
            ("blackbody", Values::Nums(v)) if v.len() == 1 => {
                let u = match use_of(&q.name) {
                    Use::Light => SpectrumUse::Emission,
                    Use::Plain(u) => u,
                };
                let rgb = blackbody_rgb(v[0], u).map_err(|m| p.error(lx, q, m))?;
                return self.finish_spectrum(p, q, rgb);
            }
            ("blackbody", _) => return Err(p.error(lx, q, "expected one temperature in kelvin")),
            (_, Values::Nums(v)) if v.len() % 2 == 0 => {
                v.chunks_exact(2).map(|c| (c[0], c[1])).collect()
            }
            (_, Values::Nums(_)) => {
                return Err(p.error(lx, q, "expected wavelength (nm) and value pairs"))
            }
            (_, Values::Strs(v)) if v.len() == 1 && v[0].to_ascii_lowercase().ends_with(".spd") => {
                self.read_spd(p, q, &v[0])?
            }
            (_, Values::Strs(v)) if v.len() == 1 => return Ok(Colour::Named(v[0].clone())),
            _ => return Err(p.error(lx, q, "expected a spectrum")),
        };
        let u = match use_of(&q.name) {
            Use::Light => SpectrumUse::Emission,
            Use::Plain(u) => u,
        };
        let rgb = sampled_to_rgb(&samples, u).map_err(|m| p.error(lx, q, m))?;
        self.finish_spectrum(p, q, rgb)
    }

    /// Normalises a light's spectrum to unit luminance (see the module documentation).
    fn finish_spectrum(&self, p: &Params, q: &Param, rgb: [f64; 3]) -> Result<Colour, SceneError> {
        if let Use::Light = use_of(&q.name) {
            let y = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
            if !(y > 0.0 && y.is_finite()) {
                return Err(p.error(&self.lx, q, "the light's spectrum has no luminance"));
            }
            return Ok(Colour::Rgb(rgb.map(|c| c / y)));
        }
        Ok(Colour::Rgb(rgb))
    }

    /// The `(wavelength, value)` pairs of a `.spd` file (numbers separated by white space,
    /// `#` comments), resolved as pbrt resolves file names.
    fn read_spd(&self, p: &Params, q: &Param, name: &str) -> Result<Vec<(f64, f64)>, SceneError> {
        let lx = &self.lx;
        let path = lx.resolve(&q.at, name);
        let fail = |m: String| {
            lx.error(
                SceneErrorKind::ExternalFile,
                &q.at,
                &p.entity,
                format!("parameter `{} {}`: {m}", q.ty, q.name),
            )
        };
        crate::side_file::check(&path).map_err(fail)?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| fail(format!("cannot read `{}`: {e}", path.display())))?;
        let mut values = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("");
            for w in line.split_whitespace() {
                match w.parse::<f64>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    _ => {
                        return Err(fail(format!(
                            "`{}` line {}: `{w}` is not a finite number",
                            path.display(),
                            i + 1
                        )))
                    }
                }
            }
        }
        if values.len() % 2 != 0 || values.is_empty() {
            return Err(fail(format!(
                "`{}` must hold wavelength and value pairs (it has {} numbers)",
                path.display(),
                values.len()
            )));
        }
        Ok(values.chunks_exact(2).map(|c| (c[0], c[1])).collect())
    }
}
