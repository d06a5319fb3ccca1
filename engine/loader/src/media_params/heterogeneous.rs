//! Reading `interior = { type = "heterogeneous", ... }` (see `docs/scene-format.md`).

use super::patterns::{parse_albedo, parse_phase};
use crate::grid_file::{is_vdb, read_grid_channels, GridChannels};
use crate::scene_file::{MaterialParams, SceneError};
use glam::Vec3;
use risotto_builtins::heterogeneous::{
    HeterogeneousMedium, Tracking, DEFAULT_MAJORANT_CELLS, TRACKINGS,
};
use risotto_components::Rgb;
use risotto_systems::grid::{DensityChannels, DensityGrid};
use risotto_systems::pattern::{self, PatternGraph};
use risotto_systems::phase::PhaseFunction;
use std::path::Path;
use std::sync::Arc;

/// Reads `interior = { type = "heterogeneous", ... }` (see `docs/scene-format.md`).
pub(crate) fn parse(t: &MaterialParams) -> Result<HeterogeneousMedium, SceneError> {
    t.deny_unknown(&[
        "type",
        "density",
        "scale",
        "albedo",
        "phase",
        "tracking",
        "march_step",
        "majorant_grid",
        "emission",
    ])?;
    let d = t
        .table("density")?
        .ok_or_else(|| t.error(None, "a heterogeneous interior needs `density = { grid = \"file.vol\" }` (or `{ constant = .. }`, or a pattern table)"))?;
    if d.has("pattern") {
        return parse_pattern_density(t);
    }
    d.deny_unknown(&["grid", "header", "name", "constant"])?;
    let density = match (d.path("grid")?, d.has("constant")) {
        (Some(path), false) => {
            let header = d.path("header")?;
            let name = if d.has("name") {
                Some(d.string("name", None)?)
            } else {
                None
            };
            match grid_file_channels(&d, &path, header, name)? {
                SharedGrid::One(g) => g,
                // The per-voxel maximum the medium derives is its own; the channels are
                // copied (only one-channel grids are shared).
                SharedGrid::Three(c) => return parse_channel_density(t, (*c).clone()),
            }
        }
        (None, true) => {
            if d.has("header") {
                return Err(d.error(Some("header"), "`header` belongs to a raw `grid` file"));
            }
            let c = d.f32_where("constant", None, "must be >= 0", |v| v >= 0.0)?;
            Arc::new(
                DensityGrid::constant([1, 1, 1], c)
                    .map_err(|e| d.error(Some("constant"), e.to_string()))?,
            )
        }
        (Some(_), true) => {
            return Err(d.error(
                Some("constant"),
                "give either `grid` or `constant`, not both",
            ))
        }
        (None, false) => {
            return Err(d.error(
                None,
                "`density` needs `grid = \"file\"` or `constant = number`",
            ))
        }
    };
    // A number (grey) or a colour (chromatic: spectral tracking), like every colour key.
    let scale = scale(t)?;
    if !(scale * density.max()).is_finite() {
        let shown = if scale.r == scale.g && scale.g == scale.b {
            format!("{}", scale.r)
        } else {
            format!("[{}, {}, {}]", scale.r, scale.g, scale.b)
        };
        return Err(t.error(
            Some("scale"),
            format!(
                "scale {shown} times the grid's max {} overflows",
                density.max()
            ),
        ));
    }
    let c = common(t)?;
    let medium = HeterogeneousMedium::new(density, c.cells, 1.0, c.albedo, c.phase, c.tracking)
        .with_scale(scale);
    with_emission(t, c.apply(medium))
}

/// `density = { grid = "rgb.vol" }` with 3 channels: `sigma_t,c = scale_c density_c`
/// (per-channel density; `scale` a number or a colour as for one channel). A colour
/// `emission` (`j = colour * density`) is refused: which channel's density it would follow
/// is not defined; an emission grid or pattern is accepted.
fn parse_channel_density(
    t: &MaterialParams,
    channels: DensityChannels,
) -> Result<HeterogeneousMedium, SceneError> {
    let scale = scale(t)?;
    let max = channels.max();
    if !(scale * max).is_finite() {
        return Err(t.error(
            Some("scale"),
            format!(
                "scale [{}, {}, {}] times the grid's channel maxima [{}, {}, {}] overflows",
                scale.r, scale.g, scale.b, max.r, max.g, max.b
            ),
        ));
    }
    if t.has("emission") && !t.is_table("emission") {
        return Err(t.error(
            Some("emission"),
            "a colour emission follows the density, but this grid has 3 channels (a density \
             per RGB channel): give `emission = { grid = \"file\" }` or a pattern table",
        ));
    }
    let c = common(t)?;
    let first = channels.channel(0).clone();
    let medium = HeterogeneousMedium::new(first, c.cells, 1.0, c.albedo, c.phase, c.tracking)
        .with_scale(scale)
        .with_density_channels(channels, c.cells);
    with_emission(t, c.apply(medium))
}

/// The keys every form of density shares.
struct Common {
    albedo: Rgb,
    albedo_pattern: Option<Arc<PatternGraph>>,
    phase: PhaseFunction,
    g_pattern: Option<Arc<PatternGraph>>,
    tracking: Tracking,
    march_step: Option<f32>,
    cells: usize,
}

impl Common {
    /// `medium` with these keys' values (its own density and scale kept).
    fn apply(self, medium: HeterogeneousMedium) -> HeterogeneousMedium {
        HeterogeneousMedium {
            albedo: self.albedo,
            albedo_pattern: self.albedo_pattern,
            phase: self.phase,
            g_pattern: self.g_pattern,
            tracking: self.tracking,
            march_step: self.march_step,
            ..medium
        }
    }
}

/// Reads the keys every form of density shares: `albedo` and `phase` (either may hold
/// patterns, [`risotto_builtins::scatter_patterns`]), `tracking`, `march_step`, `majorant_grid`.
fn common(t: &MaterialParams) -> Result<Common, SceneError> {
    let (albedo, albedo_pattern) = parse_albedo(t)?;
    let (phase, g_pattern) = parse_phase(t)?;
    let name = t.string("tracking", Some("ratio"))?;
    let tracking = Tracking::from_name(&name).ok_or_else(|| {
        t.error(
            Some("tracking"),
            format!(
                "unknown tracking \"{name}\" (known: {})",
                TRACKINGS.map(Tracking::name).join(", ")
            ),
        )
    })?;
    let march_step = if t.has("march_step") {
        Some(t.f32_where("march_step", None, "must be > 0 (world units)", |v| v > 0.0)?)
    } else {
        None
    };
    let cells = t.u32("majorant_grid", Some(DEFAULT_MAJORANT_CELLS as u32))?;
    if cells == 0 || cells > 256 {
        return Err(t.error(
            Some("majorant_grid"),
            format!("must be in [1, 256] cells per axis, got {cells}"),
        ));
    }
    Ok(Common {
        albedo,
        albedo_pattern,
        phase,
        g_pattern,
        tracking,
        march_step,
        cells: cells as usize,
    })
}

/// `scale`: a number (grey) or a colour (chromatic: spectral tracking), like every colour
/// key.
fn scale(t: &MaterialParams) -> Result<Rgb, SceneError> {
    t.rgb_where(
        "scale",
        Some(Rgb::WHITE),
        "must be >= 0 and finite in every channel",
        |c| c.min_channel() >= 0.0 && c.is_finite(),
    )
}

/// `density = { pattern = .., .. }`: a pattern of the world position `P`, grey (one density)
/// or a colour graph (a density per channel), bounded in `[0, inf)` by its interval bounds
/// over all of space (module docs).
fn parse_pattern_density(t: &MaterialParams) -> Result<HeterogeneousMedium, SceneError> {
    let scale = scale(t)?;
    let graph = density_pattern(t, "density", scale.max_channel())?;
    let c = common(t)?;
    let unit = DensityGrid::constant([1, 1, 1], 1.0).expect("a valid constant");
    let medium = HeterogeneousMedium::new(unit, 1, 1.0, c.albedo, c.phase, c.tracking)
        .with_density_pattern(graph, c.cells)
        .with_scale(scale);
    // A colour (not a table: a grid or a pattern) follows the density.
    if medium.per_channel_density() && t.has("emission") && !t.is_table("emission") {
        return Err(t.error(
            Some("emission"),
            "a colour emission follows the density, and a colour density pattern is one \
             density per channel: write the emission as a pattern instead (e.g. `emission = \
             { pattern = \"multiply\", a = <the density pattern>, b = { pattern = \"constant\", \
             value = [r, g, b] } }`)",
        ));
    }
    with_emission(t, c.apply(medium))
}

/// The pattern table at `key` as a density: of `P` only, bounded in `[0, inf)` in every
/// channel with a finite upper bound (times `scale`) by its interval bounds over all of
/// space; each a located error. A colour graph is a density per channel.
fn density_pattern(t: &MaterialParams, key: &str, scale: f32) -> Result<PatternGraph, SceneError> {
    let graph = t.pattern(key)?.expect("checked: a table");
    if graph.reads_uv() {
        return Err(t.error(
            Some(key),
            "a medium's pattern sees the world position P only (u and v belong to surfaces): \
             use `space = \"P\"` and an axis x, y or z",
        ));
    }
    let (lo, hi) = pattern::bounds(&graph, Vec3::NEG_INFINITY, Vec3::INFINITY);
    // NaN reads as not >= 0; the lowest channel (every channel of a grey graph is equal).
    let low =
        [lo.r, lo.g, lo.b].into_iter().fold(
            f32::INFINITY,
            |m, v| if v.is_nan() || v < m { v } else { m },
        );
    if low.is_nan() || low < 0.0 {
        return Err(t.error(
            Some(key),
            format!(
                "the {key} pattern may reach {low} (interval bounds over all of space), but it \
                 must be >= 0: wrap it in `remap` (e.g. from = [-1, 1], to = [0, 1])",
            ),
        ));
    }
    let high = hi.max_channel();
    if !([hi.r, hi.g, hi.b].iter().all(|v| v.is_finite()) && (scale * high).is_finite()) {
        return Err(t.error(
            Some(key),
            format!(
                "the {key} pattern's upper bound {high} (times scale {scale}) is not finite: \
                 the trackers need a finite majorant",
            ),
        ));
    }
    if scale * high > MAX_PATTERN_EXTINCTION {
        return Err(t.error(
            Some(key),
            format!(
                "the {key} pattern's upper bound {high} times scale {scale} is an extinction \
                 of up to {:e} per unit of length: a pattern density is tracked one tentative \
                 collision at a time, about that many per unit of path (a grid's dense \
                 stretches are integrated exactly instead), so at most {:e} is accepted: lower \
                 the scale, or bake the pattern into a grid",
                scale * high,
                MAX_PATTERN_EXTINCTION
            ),
        ));
    }
    Ok(graph)
}

/// The largest extinction bound (`scale` times the density pattern's upper bound, per unit
/// of length) a pattern density may have. Null-collision trackers take about `majorant x
/// length` tentative collisions along a path, each a pattern evaluation; a grid's dense
/// stretches are integrated exactly past `risotto_systems::tracking::dense::TRACKING_CAP`,
/// but a pattern's optical depth has no closed form. At this bound a unit of path costs a
/// million evaluations (tens of milliseconds); media meant to be seen through are below a
/// few thousand. Without it a mistyped scale (`1e30`) renders for ever.
const MAX_PATTERN_EXTINCTION: f32 = 1e6;

/// Why a homogeneous interior refuses an emission grid.
const HOMOGENEOUS_EMISSION: &str = "a homogeneous interior's emission is a colour or a \
     pattern table; an emission grid belongs to `type = \"heterogeneous\"`";

/// A `homogeneous` interior whose `sigma_t` or `emission` is a pattern table: such a medium
/// is heterogeneous, and is built as one (see `docs/scene-format.md`).
/// - `sigma_t = { pattern = .. }` (grey): the density pattern, scale 1, ratio tracking,
///   the default majorant grid; a colour `emission` is then `j = emission` everywhere.
/// - a constant `sigma_t` (or `sigma_a` + `sigma_s`) with `emission = { pattern = .. }`:
///   density 1 with `scale = sigma_t` (chromatic as the colour says), tracked by residual
///   ratio tracking, which integrates the constant cell exactly (no tentative collisions).
///
/// `constant`: the constant extinction the homogeneous reader parsed, as `(sigma_t, albedo,
/// albedo pattern)`, or `None` for a pattern `sigma_t` (read here, with `albedo`). `phase`
/// reads as for any medium, and `scattering` must be `"multiple"` or `"bounce"` (a
/// heterogeneous medium's points always go back to the path tracer).
pub(crate) fn homogeneous_with_patterns(
    t: &MaterialParams,
    constant: Option<(Rgb, Rgb, Option<Arc<PatternGraph>>)>,
) -> Result<HeterogeneousMedium, SceneError> {
    let scattering = t.string("scattering", Some("multiple"))?;
    if scattering != "multiple" && scattering != "bounce" {
        return Err(t.error(
            Some("scattering"),
            format!(
                "scattering = \"{scattering}\" needs a constant sigma_t and emission: with a \
                 pattern the medium is heterogeneous, whose scattering points go back to the \
                 path tracer (\"multiple\" or \"bounce\")"
            ),
        ));
    }
    if t.is_table("emission") && !t.table("emission")?.is_some_and(|e| e.has("pattern")) {
        return Err(t.error(Some("emission"), HOMOGENEOUS_EMISSION));
    }
    let unit = DensityGrid::constant([1, 1, 1], 1.0).expect("a valid constant");
    let (phase, g_pattern) = parse_phase(t)?;
    let (medium, albedo, albedo_pattern) = match constant {
        None => {
            let graph = density_pattern(t, "sigma_t", 1.0)?;
            let (albedo, albedo_pattern) = parse_albedo(t)?;
            let m = HeterogeneousMedium::new(unit, 1, 1.0, albedo, phase, Tracking::Ratio)
                .with_density_pattern(graph, DEFAULT_MAJORANT_CELLS);
            (m, albedo, albedo_pattern)
        }
        Some((sigma_t, albedo, albedo_pattern)) => {
            let m = HeterogeneousMedium::new(unit, 1, 1.0, albedo, phase, Tracking::Residual)
                .with_scale(sigma_t);
            (m, albedo, albedo_pattern)
        }
    };
    let medium = HeterogeneousMedium {
        albedo,
        albedo_pattern,
        g_pattern,
        ..medium
    };
    Ok(match parse_emission(t)? {
        None => medium,
        Some(EmissionKey::Pattern(graph)) => medium.with_emission_pattern(graph),
        // The density is 1 here: j = colour.
        Some(EmissionKey::Colour(c)) if medium.density_pattern.is_none() => {
            medium.with_emission_following_density(c)
        }
        Some(EmissionKey::Colour(c)) => {
            let constant = PatternGraph::new(vec![pattern::Node::Constant(c)])
                .expect("one constant node is a graph");
            medium.with_emission_pattern(constant)
        }
        Some(EmissionKey::Grid(..)) => return Err(t.error(Some("emission"), HOMOGENEOUS_EMISSION)),
    })
}

/// `medium` with the interior's `emission` key, if any.
fn with_emission(
    t: &MaterialParams,
    medium: HeterogeneousMedium,
) -> Result<HeterogeneousMedium, SceneError> {
    Ok(match parse_emission(t)? {
        None => medium,
        Some(EmissionKey::Colour(c)) => {
            let max = medium.density.max();
            if !(c * max).is_finite() {
                return Err(t.error(
                    Some("emission"),
                    format!("emission {c:?} times the density grid's max {max} overflows"),
                ));
            }
            medium.with_emission_following_density(c)
        }
        Some(EmissionKey::Grid(grid, scale)) => medium.with_emission_grid(grid, scale),
        Some(EmissionKey::Pattern(graph)) => medium.with_emission_pattern(graph),
    })
}

/// Reads the one-channel grid file of a `{ grid = .., header = .., name = .. }` table `t`
/// (an emission grid), as [`grid_file_channels`]; 3 channels are an error.
fn grid_file(
    t: &MaterialParams,
    path: &std::path::Path,
    header: Option<std::path::PathBuf>,
    name: Option<String>,
) -> Result<Arc<DensityGrid>, SceneError> {
    match grid_file_channels(t, path, header, name)? {
        SharedGrid::One(g) => Ok(g),
        SharedGrid::Three(_) => Err(t.error(
            Some("grid"),
            format!(
                "{}: 3 channels, but this grid needs one value per voxel (a density per RGB \
                 channel belongs to a heterogeneous interior's `density`)",
                path.display()
            ),
        )),
    }
}

/// A grid file's values, shared by every medium of the scene that names the file with the
/// same `header` and `name` ([`risotto_engine::side_files`]).
enum SharedGrid {
    One(Arc<DensityGrid>),
    Three(Arc<DensityChannels>),
}

/// Reads the grid file of a `{ grid = .., header = .., name = .. }` table `t` (density or
/// emission), of 1 or 3 channels: `header` only for raw files, `name` only for `.vdb` ones.
/// The file is decoded once per scene load and shared ([`SharedGrid`]).
fn grid_file_channels(
    t: &MaterialParams,
    path: &Path,
    header: Option<std::path::PathBuf>,
    name: Option<String>,
) -> Result<SharedGrid, SceneError> {
    if is_vdb(path) && header.is_some() {
        return Err(t.error(
            Some("header"),
            "`header` belongs to a raw `grid` file, not a .vdb",
        ));
    }
    if !is_vdb(path) && name.is_some() {
        return Err(t.error(Some("name"), "`name` picks a grid of a .vdb file"));
    }
    let vol = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vol"));
    if header.is_none() && !vol && !is_vdb(path) {
        // A raw grid's header beside it is read too.
        t.note_file(&path.with_extension("json"));
    }
    let params = format!("grid header={header:?} name={name:?}");
    let shared = t
        .side_files()
        .get_or_load(path, &params, || {
            read_grid_channels(path, header.as_deref(), name.as_deref()).map(|c| match c {
                GridChannels::One(g) => SharedGrid::One(Arc::new(g)),
                GridChannels::Three(c) => SharedGrid::Three(Arc::new(c)),
            })
        })
        .map_err(|e| t.error(Some("grid"), e.to_string()))?;
    Ok(match &*shared {
        SharedGrid::One(g) => SharedGrid::One(Arc::clone(g)),
        SharedGrid::Three(c) => SharedGrid::Three(Arc::clone(c)),
    })
}

/// The two forms of a heterogeneous interior's `emission` key.
enum EmissionKey {
    /// `emission = colour`.
    Colour(Rgb),
    /// `emission = { grid = "file", scale = colour }`.
    Grid(Arc<DensityGrid>, Rgb),
    /// `emission = { pattern = .., .. }`.
    Pattern(PatternGraph),
}

/// Reads `emission` (absent: none): a colour (`j = colour * density`) or a table
/// `{ grid = "file.vol" | "file.raw", header = "file.json", scale = colour }`
/// (`j = scale * grid`).
fn parse_emission(t: &MaterialParams) -> Result<Option<EmissionKey>, SceneError> {
    let coefficient = "every channel in [0, 1e30] (radiance per unit length; MAX_RADIANCE)";
    let ok = |c: Rgb| {
        c.min_channel() >= 0.0
            && c.is_finite()
            && c.max_channel() <= crate::scene_file::MAX_RADIANCE
    };
    if !t.has("emission") {
        return Ok(None);
    }
    if !t.is_table("emission") {
        return Ok(Some(EmissionKey::Colour(t.rgb_where(
            "emission",
            None,
            coefficient,
            ok,
        )?)));
    }
    let e = t.table("emission")?.expect("checked: a table");
    if e.has("pattern") {
        let graph = t.pattern("emission")?.expect("checked: a table");
        if graph.reads_uv() {
            return Err(t.error(
                Some("emission"),
                "a medium's pattern sees the world position P only (u and v belong to \
                 surfaces)",
            ));
        }
        let (lo, hi) = pattern::bounds(&graph, Vec3::NEG_INFINITY, Vec3::INFINITY);
        if !(lo.min_channel() >= 0.0 && ok(hi)) {
            return Err(t.error(
                Some("emission"),
                format!(
                    "the emission pattern must keep {coefficient}, but its values may reach \
                     [{}, {}, {}] .. [{}, {}, {}] (interval bounds over all of space): wrap it \
                     in `remap` or `scale`",
                    lo.r, lo.g, lo.b, hi.r, hi.g, hi.b
                ),
            ));
        }
        return Ok(Some(EmissionKey::Pattern(graph)));
    }
    e.deny_unknown(&["grid", "header", "name", "scale"])?;
    let Some(path) = e.path("grid")? else {
        return Err(e.error(
            None,
            "an emission table needs `grid = \"file.vol\"` (or give `emission` as a colour: \
             j = colour * density)",
        ));
    };
    let header = e.path("header")?;
    let name = if e.has("name") {
        Some(e.string("name", None)?)
    } else {
        None
    };
    let grid = grid_file(&e, &path, header, name)?;
    let scale = e.rgb_where("scale", Some(Rgb::WHITE), coefficient, ok)?;
    if !(scale * grid.max()).is_finite() {
        return Err(e.error(
            Some("scale"),
            format!(
                "scale {scale:?} times the emission grid's max {} overflows",
                grid.max()
            ),
        ));
    }
    Ok(Some(EmissionKey::Grid(grid, scale)))
}
