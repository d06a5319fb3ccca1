//! `[render] filter`, `filter_radius`, `filter_stddev`: the pixel reconstruction filter
//! (`docs/scene-format.md`, "render"). Defaults are Mitsuba 3's (`box` of radius 1/2, `tent`
//! of radius 1, `gaussian` of standard deviation 1/2 truncated at 4 standard deviations).

use super::params::Reader;
use risotto_engine::diagnostics::{SceneError, SceneErrorKind};
use risotto_systems::pixel_filter::{GaussianFilter, PixelFilter};

/// The filter keys of `[render]`.
pub(crate) const FILTER_KEYS: [&str; 3] = ["filter", "filter_radius", "filter_stddev"];

/// The largest `filter_radius`, in pixels: a filter wider than this blurs more than any
/// film's reconstruction asks for, and a wild value is more likely a unit mix-up.
const MAX_RADIUS: f32 = 16.0;

/// The largest `filter_radius / filter_stddev` of a Gaussian: 64 standard deviations is far
/// beyond where the Gaussian is 0 in f32, and the bound keeps the sampler's quadrature (a
/// piece per quarter standard deviation) short.
const MAX_RADIUS_IN_STDDEVS: f32 = 64.0;

/// Reads the pixel filter of the `[render]` table `r`.
pub(crate) fn read_pixel_filter(r: &Reader<'_>) -> Result<PixelFilter, SceneError> {
    let name = r.str_opt("filter")?.unwrap_or("box");
    let radius = |default: f32| {
        r.f32_where(
            "filter_radius",
            Some(default),
            &format!("must be finite, > 0 and <= {MAX_RADIUS} (pixels)"),
            |v| v.is_finite() && v > 0.0 && v <= MAX_RADIUS,
        )
    };
    let no_stddev = |name: &str| match r.get("filter_stddev") {
        Some(node) => Err(r.invalid(
            "filter_stddev",
            node,
            &format!("applies to `filter = \"gaussian\"` only, not to `{name}`"),
        )),
        None => Ok(()),
    };
    match name {
        "box" => {
            no_stddev(name)?;
            Ok(PixelFilter::Box {
                radius: radius(0.5)?,
            })
        }
        "tent" => {
            no_stddev(name)?;
            Ok(PixelFilter::Tent {
                radius: radius(1.0)?,
            })
        }
        "gaussian" => {
            let stddev = r.f32_where(
                "filter_stddev",
                Some(0.5),
                "must be finite and > 0 (pixels)",
                |v| v.is_finite() && v > 0.0,
            )?;
            let radius = radius((4.0 * stddev).min(MAX_RADIUS))?;
            if radius > MAX_RADIUS_IN_STDDEVS * stddev {
                let key = if r.has("filter_radius") {
                    "filter_radius"
                } else {
                    "filter_stddev"
                };
                return Err(r.invalid(
                    key,
                    r.get(key).unwrap_or(r.node),
                    &format!(
                        "filter_radius {radius} is {} standard deviations of {stddev}; at \
                         most {MAX_RADIUS_IN_STDDEVS} are allowed",
                        radius / stddev
                    ),
                ));
            }
            GaussianFilter::new(stddev, radius)
                .map(PixelFilter::Gaussian)
                .ok_or_else(|| {
                    r.invalid(
                        "filter_stddev",
                        r.get("filter_stddev").unwrap_or(r.node),
                        "gives a filter of zero integral",
                    )
                })
        }
        other => {
            let why = if matches!(other, "mitchell" | "lanczos" | "catmullrom") {
                format!(
                    "filter `{other}` has negative lobes, which filter importance sampling \
                     cannot sample; "
                )
            } else {
                format!("unknown filter `{other}`; ")
            };
            Err(r.error(
                SceneErrorKind::InvalidValue,
                &r.get("filter").unwrap_or(r.node).span(),
                Some("filter"),
                format!("{why}expected `box`, `tent` or `gaussian`"),
            ))
        }
    }
}
