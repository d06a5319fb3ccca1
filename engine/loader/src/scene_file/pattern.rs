//! Pattern tables in material parameters: a colour key may be a table
//! `{ pattern = "noise", frequency = 4, ... }`, nested for combinators, read into a
//! [`PatternGraph`] with located errors (see `docs/scene-format.md`, Patterns).

use super::params::MaterialParams;
use super::SceneError;
use glam::Vec3;
use risotto_components::Rgb;
use risotto_systems::grid::DensityGrid;
use risotto_systems::pattern::{
    self, Axis, Fbm, GridBorder, ImageLookup, Node, NodeId, PatternGraph, Space, TextureFilter,
    Wrap, MAX_OCTAVES,
};
use std::sync::Arc;

/// A colour parameter as written: a constant or a pattern graph.
#[derive(Clone, Debug, PartialEq)]
pub enum ColourParam {
    /// `[r, g, b]` or one number.
    Constant(Rgb),
    /// `{ pattern = "...", ... }`.
    Pattern(PatternGraph),
}

/// The pattern types, in the order messages list them.
const PATTERNS: [&str; 13] = [
    "constant", "noise", "checker", "gradient", "image", "grid", "mix", "multiply", "add",
    "fraction", "scale", "remap", "power",
];

/// The `uv_transform`, `wrap` and `filter` keys of an `image` table `t`.
fn image_lookup(t: &MaterialParams) -> Result<ImageLookup, SceneError> {
    let choice = |key: &str, names: &[&str]| -> Result<usize, SceneError> {
        let name = t.string(key, Some(names[0]))?;
        names.iter().position(|n| *n == name).ok_or_else(|| {
            t.error(
                Some(key),
                format!("must be one of {}, got \"{name}\"", names.join(", ")),
            )
        })
    };
    let wrap =
        [Wrap::Repeat, Wrap::Mirror, Wrap::Clamp][choice("wrap", &["repeat", "mirror", "clamp"])?];
    let filter = [TextureFilter::Bilinear, TextureFilter::Nearest]
        [choice("filter", &["bilinear", "nearest"])?];
    // `uv_transform = { u = [a, b, c], v = [d, e, f] }`: u' = a u + b v + c, v' = d u + e v + f.
    let uv_transform = match t.table("uv_transform")? {
        None => None,
        Some(m) => {
            m.deny_unknown(&["u", "v"])?;
            let (u, v) = (m.vec3("u", Some(Vec3::X))?, m.vec3("v", Some(Vec3::Y))?);
            let affine = glam::Affine2::from_cols(
                glam::Vec2::new(u.x, v.x),
                glam::Vec2::new(u.y, v.y),
                glam::Vec2::new(u.z, v.z),
            );
            if !affine.is_finite() {
                return Err(m.error(Some("u"), "the transform's entries must be finite"));
            }
            Some(affine)
        }
    };
    Ok(ImageLookup {
        uv_transform,
        wrap,
        filter,
    })
}

/// Nesting deeper than this is refused (no scene needs it; it bounds the recursion).
const MAX_DEPTH: usize = 32;

impl MaterialParams {
    /// A colour that may also be a pattern table. A constant must have every channel in
    /// `[range[0], range[1]]` (the message says "every channel in [lo, hi]"); a pattern must
    /// be bounded within the range everywhere, by its interval bounds over all of space
    /// ([`pattern::bounds`]): wrap it in `remap` or `scale` otherwise.
    pub fn colour_or_pattern(
        &self,
        key: &str,
        default: Rgb,
        range: [f32; 2],
    ) -> Result<ColourParam, SceneError> {
        let requirement = format!("every channel in [{}, {}]", range[0], range[1]);
        let in_range = |c: Rgb| c.min_channel() >= range[0] && c.max_channel() <= range[1];
        if !self.is_table(key) {
            let c = self.rgb_where(key, Some(default), &requirement, in_range)?;
            return Ok(ColourParam::Constant(c));
        }
        let graph = self.pattern(key)?.expect("checked: a table");
        let everywhere = (Vec3::NEG_INFINITY, Vec3::INFINITY);
        let (lo, hi) = pattern::bounds(&graph, everywhere.0, everywhere.1);
        if !(in_range(lo) && in_range(hi)) {
            return Err(self.error(
                Some(key),
                format!(
                    "the pattern must keep {requirement}, but its values may reach \
                     [{}, {}, {}] .. [{}, {}, {}] (interval bounds over all of space): \
                     wrap it in `remap` or `scale`",
                    lo.r, lo.g, lo.b, hi.r, hi.g, hi.b
                ),
            ));
        }
        Ok(ColourParam::Pattern(graph))
    }

    /// The pattern table at `key` as a graph; `None` if the key is absent, an error if it is
    /// not a table or the table is not a valid pattern.
    pub fn pattern(&self, key: &str) -> Result<Option<PatternGraph>, SceneError> {
        let Some(t) = self.table(key)? else {
            return Ok(None);
        };
        let mut nodes = Vec::new();
        node(&t, &mut nodes, 0)?;
        // Children are pushed before their parents, so the order is valid by construction;
        // a parameter error left unchecked above would surface here.
        PatternGraph::new(nodes)
            .map(Some)
            .map_err(|e| self.error(Some(key), e.to_string()))
    }
}

/// Pushes the nodes of pattern table `t` (children first) and returns its root's index.
fn node(t: &MaterialParams, nodes: &mut Vec<Node>, depth: usize) -> Result<NodeId, SceneError> {
    if depth > MAX_DEPTH {
        return Err(t.error(None, format!("patterns nest at most {MAX_DEPTH} deep")));
    }
    let kind = t.string("pattern", None)?;
    let n = match kind.as_str() {
        "constant" => {
            t.deny_unknown(&["pattern", "value"])?;
            Node::Constant(t.rgb("value", None)?)
        }
        "noise" => {
            t.deny_unknown(&[
                "pattern",
                "frequency",
                "octaves",
                "lacunarity",
                "gain",
                "seed",
            ])?;
            let frequency = t.f32_where("frequency", Some(1.0), "must be >= 0", |v| v >= 0.0)?;
            let octaves = t.u32("octaves", Some(4))?;
            if !(1..=MAX_OCTAVES).contains(&octaves) {
                return Err(t.error(
                    Some("octaves"),
                    format!("must be in [1, {MAX_OCTAVES}], got `{octaves}`"),
                ));
            }
            let lacunarity = t.f32_where("lacunarity", Some(2.0), "must be > 0", |v| v > 0.0)?;
            let gain = t.f32_where("gain", Some(0.5), "must be >= 0", |v| v >= 0.0)?;
            let seed = t.u32("seed", Some(0))?;
            Node::Noise(
                Fbm::new(frequency, octaves, lacunarity, gain, seed)
                    .map_err(|e| t.error(None, e.to_string()))?,
            )
        }
        "checker" => {
            t.deny_unknown(&["pattern", "scale", "a", "b", "space"])?;
            let space = match t.string("space", Some("p"))?.as_str() {
                "p" | "P" => Space::P,
                "uv" => Space::Uv,
                other => {
                    return Err(t.error(
                        Some("space"),
                        format!("must be \"p\" or \"uv\", got \"{other}\""),
                    ))
                }
            };
            Node::Checker {
                scale: t.f32_where("scale", Some(1.0), "must be > 0", |v| v > 0.0)?,
                a: t.rgb("a", Some(Rgb::BLACK))?,
                b: t.rgb("b", Some(Rgb::WHITE))?,
                space,
            }
        }
        "gradient" => {
            t.deny_unknown(&["pattern", "axis", "from", "to", "a", "b"])?;
            let axis = match t.string("axis", Some("y"))?.as_str() {
                "x" => Axis::X,
                "y" => Axis::Y,
                "z" => Axis::Z,
                "u" => Axis::U,
                "v" => Axis::V,
                other => {
                    return Err(t.error(
                        Some("axis"),
                        format!("must be \"x\", \"y\", \"z\", \"u\" or \"v\", got \"{other}\""),
                    ))
                }
            };
            let from = t.f32("from", Some(0.0))?;
            let to = t.f32("to", Some(1.0))?;
            if from == to {
                return Err(t.error(
                    Some("to"),
                    format!("must differ from `from`, got `{to}` for both"),
                ));
            }
            Node::Gradient {
                axis,
                from,
                to,
                a: t.rgb("a", Some(Rgb::BLACK))?,
                b: t.rgb("b", Some(Rgb::WHITE))?,
            }
        }
        "image" => {
            use crate::texture_file::{
                read_texture_channels, read_texture_channels_top_down, TextureChannels,
            };
            t.deny_unknown(&[
                "pattern",
                "path",
                "channel",
                "raw",
                "v_origin",
                "uv_transform",
                "wrap",
                "filter",
            ])?;
            let path = t
                .path("path")?
                .ok_or_else(|| t.error(None, "an image pattern needs `path = \"file.png\"`"))?;
            let channels = match t.string("channel", Some("rgb"))?.as_str() {
                "rgb" => TextureChannels::Rgb,
                "a" => TextureChannels::Alpha,
                other => {
                    return Err(t.error(
                        Some("channel"),
                        format!("must be \"rgb\" or \"a\", got \"{other}\""),
                    ))
                }
            };
            // `raw = true`: a PNG's colour values as stored, not decoded from sRGB (alpha is
            // linear either way).
            let channels = match (channels, t.bool("raw", Some(false))?) {
                (TextureChannels::Rgb, true) => TextureChannels::RawRgb,
                (c, _) => c,
            };
            // Where `v = 0` is: the bottom row (risotto's and pbrt's convention) or the top
            // row (Mitsuba's bitmaps).
            let top_down = match t.string("v_origin", Some("bottom"))?.as_str() {
                "bottom" => false,
                "top" => true,
                other => {
                    return Err(t.error(
                        Some("v_origin"),
                        format!("must be \"bottom\" or \"top\", got \"{other}\""),
                    ))
                }
            };
            // Decoded once per scene load, shared by every pattern naming the file.
            let texture = t
                .side_files()
                .get_or_load(
                    &path,
                    &format!("texture {channels:?} top-down {top_down}"),
                    || {
                        if top_down {
                            read_texture_channels_top_down(&path, channels)
                        } else {
                            read_texture_channels(&path, channels)
                        }
                    },
                )
                .map_err(|e| t.error(Some("path"), e))?;
            Node::Image(texture, image_lookup(t)?)
        }
        "grid" => grid(t)?,
        "mix" => {
            t.deny_unknown(&["pattern", "a", "b", "t"])?;
            let a = input(t, "a", Some(Rgb::BLACK), nodes, depth)?;
            let b = input(t, "b", Some(Rgb::WHITE), nodes, depth)?;
            let tt = input(t, "t", None, nodes, depth)?;
            Node::Mix { a, b, t: tt }
        }
        "multiply" => {
            t.deny_unknown(&["pattern", "a", "b"])?;
            let a = input(t, "a", None, nodes, depth)?;
            let b = input(t, "b", None, nodes, depth)?;
            Node::Multiply { a, b }
        }
        "add" => {
            t.deny_unknown(&["pattern", "a", "b"])?;
            let a = input(t, "a", None, nodes, depth)?;
            let b = input(t, "b", None, nodes, depth)?;
            Node::Add { a, b }
        }
        "fraction" => {
            t.deny_unknown(&["pattern", "a", "b"])?;
            let a = input(t, "a", None, nodes, depth)?;
            let b = input(t, "b", None, nodes, depth)?;
            Node::Fraction { a, b }
        }
        "scale" => {
            t.deny_unknown(&["pattern", "a", "factor"])?;
            let a = input(t, "a", None, nodes, depth)?;
            Node::Scale {
                a,
                factor: t.rgb("factor", None)?,
            }
        }
        "remap" => {
            t.deny_unknown(&["pattern", "a", "from", "to"])?;
            let a = input(t, "a", None, nodes, depth)?;
            let from = pair(t, "from", [0.0, 1.0])?;
            if from[0] == from[1] {
                return Err(t.error(
                    Some("from"),
                    format!(
                        "the input range must not be empty, got `[{}, {}]`",
                        from[0], from[1]
                    ),
                ));
            }
            Node::Remap {
                a,
                from,
                to: pair(t, "to", [0.0, 1.0])?,
            }
        }
        "power" => {
            t.deny_unknown(&["pattern", "a", "exponent"])?;
            let a = input(t, "a", None, nodes, depth)?;
            let exponent = t.f32_where("exponent", None, "must be > 0", |e| e > 0.0)?;
            Node::Power { a, exponent }
        }
        other => {
            return Err(t.error(
                Some("pattern"),
                format!(
                    "unknown pattern \"{other}\" (known: {})",
                    PATTERNS.join(", ")
                ),
            ))
        }
    };
    nodes.push(n);
    Ok((nodes.len() - 1) as NodeId)
}

/// A combinator's input `key`: a colour (a constant node), a pattern table, or the default.
fn input(
    t: &MaterialParams,
    key: &str,
    default: Option<Rgb>,
    nodes: &mut Vec<Node>,
    depth: usize,
) -> Result<NodeId, SceneError> {
    if let Some(sub) = t.table(key).ok().flatten() {
        return node(&sub, nodes, depth + 1);
    }
    nodes.push(Node::Constant(t.rgb(key, default)?));
    Ok((nodes.len() - 1) as NodeId)
}

/// `{ pattern = "grid", path = "file", header = .., name = .., min = [..], max = [..],
/// transform = [..] }`, or with the values inline: `values = [..], dims = [nx, ny, nz]`.
fn grid(t: &MaterialParams) -> Result<Node, SceneError> {
    t.deny_unknown(&[
        "pattern",
        "path",
        "header",
        "name",
        "values",
        "dims",
        "min",
        "max",
        "transform",
        "border",
        "channel",
    ])?;
    if t.has("channel") && !t.has("path") {
        return Err(t.error(
            Some("channel"),
            "belongs to a 3-channel grid file (`path`), not to `values`",
        ));
    }
    let grid = match (t.has("path"), t.has("values")) {
        (true, false) => grid_file(t)?,
        (false, true) => inline_grid(t)?,
        (true, true) => return Err(t.error(Some("values"), "give `path` or `values`, not both")),
        (false, false) => {
            return Err(t.error(
                None,
                "a grid pattern needs `path = \"file.vol\"` or `values = [..]` with `dims`",
            ))
        }
    };
    let min = t.vec3("min", Some(Vec3::splat(-1.0)))?;
    let max = t.vec3("max", Some(Vec3::ONE))?;
    if !min.cmplt(max).all() {
        return Err(t.error(
            Some("max"),
            format!("must be > `min` on every axis, got {max} and {min}"),
        ));
    }
    // The box's placement (box space to world), read as a shape's; the node keeps its
    // inverse. Absent: the box is in world space and no transform is applied.
    let to_box = if t.has("transform") {
        let m = super::geometry::read_transform(&t.reader())?.inverse();
        Some(glam::Affine3A::from_mat3_translation(
            m.matrix3.as_mat3(),
            m.translation.as_vec3(),
        ))
    } else {
        None
    };
    let (grid, border) = match t.string("border", Some("clamp"))?.as_str() {
        "clamp" => (grid, GridBorder::Clamp),
        "zero" => (Arc::new(grid.padded_with_zeros()), GridBorder::Zero),
        "box" => (grid, GridBorder::ClampInBox),
        other => {
            return Err(t.error(
                Some("border"),
                format!("unknown border `{other}`; expected `clamp`, `zero` or `box`"),
            ))
        }
    };
    Ok(Node::Grid {
        grid,
        min,
        max,
        to_box,
        border,
    })
}

/// A grid pattern's file (`path`, with `header` and `name`), shared with every graph and
/// medium naming it.
fn grid_file(t: &MaterialParams) -> Result<Arc<DensityGrid>, SceneError> {
    use crate::grid_file::{is_vdb, read_grid_channels, read_grid_named, GridChannels};
    let path = t
        .path("path")?
        .ok_or_else(|| t.error(Some("path"), "expected a file name"))?;
    let header = t.path("header")?;
    let name = t.has("name").then(|| t.string("name", None)).transpose()?;
    let vol = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vol"));
    if header.is_none() && !vol && !is_vdb(&path) {
        // A raw grid's header beside it is read too.
        t.note_file(&path.with_extension("json"));
    }
    // `channel = "r" | "g" | "b"`: one channel of a 3-channel file (a pattern is grey).
    let channel = match t
        .has("channel")
        .then(|| t.string("channel", None))
        .transpose()?
    {
        None => None,
        Some(c) => Some(
            ["r", "g", "b"]
                .iter()
                .position(|n| *n == c)
                .ok_or_else(|| {
                    t.error(
                        Some("channel"),
                        format!("must be \"r\", \"g\" or \"b\", got \"{c}\""),
                    )
                })?,
        ),
    };
    let Some(k) = channel else {
        return t
            .side_files()
            .get_or_load(
                &path,
                &format!("grid header={header:?} name={name:?}"),
                || read_grid_named(&path, header.as_deref(), name.as_deref()),
            )
            .map_err(|e| t.error(Some("path"), e.to_string()));
    };
    t.side_files()
        .get_or_load(
            &path,
            &format!("grid header={header:?} name={name:?} channel={k}"),
            || match read_grid_channels(&path, header.as_deref(), name.as_deref())? {
                GridChannels::Three(c) => Ok(c.channel(k).clone()),
                GridChannels::One(_) => Err(crate::grid_file::GridFileError::Format {
                    path: path.clone(),
                    message: "1 channel: `channel` picks one of a 3-channel file's".into(),
                }),
            },
        )
        .map_err(|e| t.error(Some("path"), e.to_string()))
}

/// `values = [..]` (x fastest, then y, then z; each finite and >= 0) of `dims = [nx, ny,
/// nz]` voxels, as a grid file's (what importers write for grids given in the scene file
/// itself, such as pbrt-v4's `uniformgrid`).
fn inline_grid(t: &MaterialParams) -> Result<Arc<DensityGrid>, SceneError> {
    for key in ["header", "name"] {
        if t.has(key) {
            return Err(t.error(
                Some(key),
                "belongs to a grid file (`path`), not to `values`",
            ));
        }
    }
    let r = t.reader();
    let items = r
        .array_opt("dims")?
        .ok_or_else(|| t.error(Some("dims"), "inline `values` need `dims = [nx, ny, nz]`"))?;
    let node = r.get("dims").expect("present: an array");
    if items.len() != 3 {
        return Err(r.invalid("dims", node, "expected 3 integers [nx, ny, nz]"));
    }
    let mut dims = [0usize; 3];
    for (d, item) in dims.iter_mut().zip(items) {
        match item.value {
            super::raw::Value::Integer(n) if n >= 1 => *d = n as usize,
            _ => return Err(r.invalid("dims", item, "each must be an integer >= 1")),
        }
    }
    let values = r
        .array_opt("values")?
        .expect("present: checked by the caller");
    let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    if count != Some(values.len()) {
        return Err(r.invalid(
            "values",
            r.get("values").expect("present"),
            &format!(
                "has {} numbers; dims {dims:?} need {}",
                values.len(),
                count.map_or_else(|| "more than can be counted".to_owned(), |n| n.to_string())
            ),
        ));
    }
    let data = values
        .iter()
        .map(|v| r.f32_of("values", v))
        .collect::<Result<Vec<f32>, _>>()?;
    DensityGrid::new(dims, data)
        .map(Arc::new)
        .map_err(|e| t.error(Some("values"), e.to_string()))
}

/// Two finite numbers `[a, b]`.
fn pair(t: &MaterialParams, key: &str, default: [f32; 2]) -> Result<[f32; 2], SceneError> {
    let r = t.reader();
    let Some(items) = r.array_opt(key)? else {
        return Ok(default);
    };
    let node = r.get(key).expect("present: an array");
    if items.len() != 2 {
        return Err(r.invalid(key, node, "expected 2 numbers [lo, hi]"));
    }
    Ok([r.f32_of(key, &items[0])?, r.f32_of(key, &items[1])?])
}
