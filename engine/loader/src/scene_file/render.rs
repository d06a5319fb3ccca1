//! The `[render]` section: image size, samples, path length, seed, pixel filter, global
//! integrator and shading-normal treatment, read with located errors.

use super::params::Reader;
use super::{pixel_filter, section, SceneError};
use risotto_engine::integrator::GlobalIntegrator;
use risotto_systems::pixel_filter::PixelFilter;
use risotto_systems::sampler::MAX_SPP;

/// The `[render]` section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels (default 512).
    pub width: u32,
    /// Image height in pixels (default 512).
    pub height: u32,
    /// Samples per pixel (default 64), at most [`MAX_SPP`] (65536, the driver's `--spp`
    /// limit too).
    pub spp: u32,
    /// Maximum number of path *segments*, Mitsuba's convention: 1 = only directly visible
    /// emitters, 2 = direct lighting, n = at most n - 1 scattering vertices (default 8).
    /// `max_depth = -1` in the file (unbounded) is stored as `u32::MAX`.
    pub max_depth: u32,
    /// Seed of the random number streams (default 0).
    pub seed: u64,
    /// Russian roulette starts after this many scattering vertices (default 5).
    pub rr_depth: u32,
    /// The pixel reconstruction filter (`filter`, `filter_radius`, `filter_stddev`;
    /// default the box of radius 1/2, uniform over each pixel).
    pub filter: PixelFilter,
    /// The global integrator (`integrator = "path" | "light" | "bdpt" | "vcm"`, default
    /// `"path"`).
    pub integrator: GlobalIntegrator,
    /// How directions are treated where shading normals and geometric normals disagree
    /// (`shading_normals = "consistent" | "shading_frame"`, default `"consistent"`;
    /// [`ShadingNormals`](risotto_engine::scene::ShadingNormals)).
    pub shading_normals: risotto_engine::scene::ShadingNormals,
}

impl RenderSettings {
    /// `max_depth` value meaning "unbounded" (`-1` in the file).
    pub const UNBOUNDED_DEPTH: u32 = u32::MAX;
    /// Largest `width * height` a scene file may ask for
    /// ([`MAX_FILM_PIXELS`](risotto_engine::render::MAX_FILM_PIXELS)). Larger resolutions
    /// are an error naming the key and the value rather than an allocation abort.
    pub const MAX_PIXELS: u64 = risotto_engine::render::MAX_FILM_PIXELS;
}

impl Default for RenderSettings {
    /// The engine's defaults ([`risotto_engine::scene::RenderSettings::default`]), stated once.
    fn default() -> Self {
        let d = risotto_engine::scene::RenderSettings::default();
        RenderSettings {
            width: d.width,
            height: d.height,
            spp: d.spp,
            max_depth: d.max_depth,
            seed: d.seed,
            rr_depth: d.rr_depth,
            filter: PixelFilter::PIXEL_BOX,
            integrator: d.integrator,
            shading_normals: d.shading_normals,
        }
    }
}

pub(super) fn read_render(top: &Reader<'_>) -> Result<RenderSettings, SceneError> {
    let d = RenderSettings::default();
    let Some(node) = section(top, "render")? else {
        return Ok(d);
    };
    let r = Reader::new(top.src, node, "render");
    let keys = [
        "width",
        "height",
        "spp",
        "max_depth",
        "seed",
        "rr_depth",
        "integrator",
        "shading_normals",
    ];
    r.deny_unknown(&[&keys[..], &pixel_filter::FILTER_KEYS].concat())?;
    // Each side bounded so that width * height stays far from overflow; the product is
    // bounded below.
    let max_res = 1 << 16;
    let u32_max = i64::from(u32::MAX);
    let max_depth = match r.int_opt("max_depth")? {
        None => d.max_depth,
        Some((-1, _)) => RenderSettings::UNBOUNDED_DEPTH,
        Some((v, _)) if (1..u32_max).contains(&v) => v as u32,
        Some((_, n)) => {
            return Err(r.invalid(
                "max_depth",
                n,
                "must be >= 1 (path segments; 1 = directly visible emitters only) or -1 \
                 (unbounded)",
            ))
        }
    };
    let width = r.int_in("width", Some(d.width.into()), 1, max_res)? as u32;
    let height = r.int_in("height", Some(d.height.into()), 1, max_res)? as u32;
    // The film and the output layers are allocated up front: a bound on the pixel count
    // turns an allocation abort into an error naming the resolution.
    if u64::from(width) * u64::from(height) > RenderSettings::MAX_PIXELS {
        let key = if r.int_opt("height")?.is_some() {
            "height"
        } else {
            "width"
        };
        let (_, node) = r.int_opt(key)?.expect("one of width and height is given");
        return Err(r.invalid(
            key,
            node,
            &format!(
                "{width} x {height} = {} pixels exceeds the limit of {} (8192 x 8192; a \
                 render takes about {} bytes a pixel)",
                u64::from(width) * u64::from(height),
                RenderSettings::MAX_PIXELS,
                risotto_engine::render::FILM_BYTES_PER_PIXEL
            ),
        ));
    }
    Ok(RenderSettings {
        width,
        height,
        // The one spp limit, shared with the driver's `--spp`: samples past it would repeat
        // the first ones exactly.
        spp: r.int_in("spp", Some(d.spp.into()), 1, MAX_SPP.into())? as u32,
        max_depth,
        seed: r.int_in("seed", Some(d.seed as i64), 0, i64::MAX)? as u64,
        rr_depth: r.int_in("rr_depth", Some(d.rr_depth.into()), 1, u32_max)? as u32,
        filter: pixel_filter::read_pixel_filter(&r)?,
        integrator: read_integrator(&r)?,
        shading_normals: read_shading_normals(&r)?,
    })
}

/// The key `key` of the `[render]` table `r`, one of the names `name` gives the values of
/// `all` (the first is the default when the key is absent).
fn read_choice<T: Copy>(
    r: &Reader<'_>,
    key: &str,
    all: &[T],
    name: fn(T) -> &'static str,
) -> Result<T, SceneError> {
    let Some(given) = r.str_opt(key)? else {
        return Ok(all[0]);
    };
    all.iter()
        .copied()
        .find(|&v| name(v) == given)
        .ok_or_else(|| {
            let names: Vec<&str> = all.iter().map(|&v| name(v)).collect();
            let node = r.get(key).unwrap_or(r.node);
            r.invalid(key, node, &format!("must be one of {}", names.join(", ")))
        })
}

/// The `shading_normals` key of the `[render]` table `r`.
fn read_shading_normals(
    r: &Reader<'_>,
) -> Result<risotto_engine::scene::ShadingNormals, SceneError> {
    use risotto_engine::scene::ShadingNormals;
    let all = ShadingNormals::ALL;
    debug_assert_eq!(all[0], ShadingNormals::default());
    read_choice(r, "shading_normals", &all, ShadingNormals::name)
}

/// The `integrator` key of the `[render]` table `r`.
fn read_integrator(r: &Reader<'_>) -> Result<GlobalIntegrator, SceneError> {
    let all = GlobalIntegrator::ALL;
    debug_assert_eq!(all[0], GlobalIntegrator::default());
    read_choice(r, "integrator", &all, GlobalIntegrator::name)
}
