//! `<transform>`: Mitsuba's `translate`, `rotate` (axis and angle, or `x`/`y`/`z` as the
//! axis), `scale`, `matrix` and `lookat` operations, each applied after the ones before
//! it (p_world = T_n ... T_1 p_local, as Mitsuba composes them). They are kept as the same
//! steps of risotto's TOML `transform` (which composes the same way), so a conversion
//! places things exactly as a hand port does; the composed matrix is kept too, for the
//! conversions that read positions from it (spheres, cameras, lights, grids).

use glam::{DMat4, DVec3, DVec4};

use super::values::{parse_list, parse_number, xyz, Cx};
use super::xml::Node;
use risotto_engine::diagnostics::{SceneError, SceneErrorKind};

/// A composed transform.
#[derive(Clone, Debug, PartialEq)]
pub struct Transform {
    /// risotto TOML transform steps, in order.
    pub steps: Vec<toml::Value>,
    /// The composed matrix (object to world).
    pub matrix: DMat4,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            steps: Vec::new(),
            matrix: DMat4::IDENTITY,
        }
    }
}

fn table(key: &str, value: toml::Value) -> toml::Value {
    let mut t = toml::Table::new();
    t.insert(key.into(), value);
    toml::Value::Table(t)
}

fn vec3(v: [f64; 3]) -> toml::Value {
    toml::Value::Array(v.iter().map(|x| toml::Value::Float(*x)).collect())
}

impl Transform {
    /// The operations of the `<transform>` element `node` (of plugin `entity`).
    pub fn read(cx: &Cx, node: &Node, entity: &str) -> Result<Transform, SceneError> {
        let mut t = Transform::default();
        for op in &node.children {
            let err = |m: String| {
                cx.doc.error(
                    op,
                    SceneErrorKind::InvalidValue,
                    Some(entity),
                    Some(&op.tag),
                    m,
                )
            };
            let (step, m) = match op.tag.as_str() {
                "translate" => {
                    let v = xyz(op, 0.0).map_err(err)?;
                    (
                        table("translate", vec3(v)),
                        DMat4::from_translation(DVec3::from(v)),
                    )
                }
                "scale" => {
                    let v = xyz(op, 1.0).map_err(err)?;
                    let step = if op.attr("value").is_some() && v[0] == v[1] && v[1] == v[2] {
                        table("scale", toml::Value::Float(v[0]))
                    } else {
                        table("scale", vec3(v))
                    };
                    (step, DMat4::from_scale(DVec3::from(v)))
                }
                "rotate" => {
                    let axis = xyz(op, 0.0).map_err(err)?;
                    let angle = op
                        .attr("angle")
                        .ok_or_else(|| err("<rotate> needs an `angle` (degrees)".into()))
                        .and_then(|a| parse_number(a).map_err(err))?;
                    let a = DVec3::from(axis);
                    // Mitsuba 3.9.1 does not normalise the axis (its matrix is then not a
                    // rotation); risotto does. A unit axis means the same in both.
                    if (a.length() - 1.0).abs() > 1e-6 {
                        return Err(err(format!(
                            "the rotation axis {axis:?} is not of unit length: Mitsuba 3 does \
                             not normalise it (its result is then not a rotation), so give a \
                             unit axis"
                        )));
                    }
                    let mut r = toml::Table::new();
                    r.insert("axis".into(), vec3(axis));
                    r.insert("angle".into(), toml::Value::Float(angle));
                    (
                        table("rotate", toml::Value::Table(r)),
                        DMat4::from_axis_angle(a.normalize(), angle.to_radians()),
                    )
                }
                "matrix" => {
                    let v = op
                        .attr("value")
                        .ok_or_else(|| err("<matrix> needs a `value`".into()))?;
                    let n = parse_list(v).map_err(err)?;
                    let rows: Vec<[f64; 4]> = match n.len() {
                        16 => {
                            if n[12..] != [0.0, 0.0, 0.0, 1.0] {
                                return Err(err(format!(
                                    "the last row of the matrix must be 0 0 0 1 (a projective \
                                     transform cannot place a shape), got {:?}",
                                    &n[12..]
                                )));
                            }
                            (0..3)
                                .map(|r| [n[4 * r], n[4 * r + 1], n[4 * r + 2], n[4 * r + 3]])
                                .collect()
                        }
                        9 => (0..3)
                            .map(|r| [n[3 * r], n[3 * r + 1], n[3 * r + 2], 0.0])
                            .collect(),
                        k => {
                            return Err(err(format!(
                                "a <matrix> has 16 (4 x 4) or 9 (3 x 3) numbers, got {k}"
                            )))
                        }
                    };
                    let m = DMat4::from_cols(
                        DVec4::new(rows[0][0], rows[1][0], rows[2][0], 0.0),
                        DVec4::new(rows[0][1], rows[1][1], rows[2][1], 0.0),
                        DVec4::new(rows[0][2], rows[1][2], rows[2][2], 0.0),
                        DVec4::new(rows[0][3], rows[1][3], rows[2][3], 1.0),
                    );
                    let value = toml::Value::Array(
                        rows.iter()
                            .map(|r| {
                                toml::Value::Array(
                                    r.iter().map(|x| toml::Value::Float(*x)).collect(),
                                )
                            })
                            .collect(),
                    );
                    (table("matrix", value), m)
                }
                "lookat" => {
                    let point = |name: &str| -> Result<DVec3, SceneError> {
                        let v = op.attr(name).ok_or_else(|| {
                            err(format!("<lookat> needs `{name}` (origin, target and up)"))
                        })?;
                        match parse_list(v).map_err(err)?[..] {
                            [x, y, z] => Ok(DVec3::new(x, y, z)),
                            _ => Err(err(format!("`{name}=\"{v}\"` needs 3 numbers"))),
                        }
                    };
                    let (o, target, up) = (point("origin")?, point("target")?, point("up")?);
                    let dir = (target - o).normalize_or_zero();
                    let left = up.cross(dir).normalize_or_zero();
                    if dir == DVec3::ZERO || left == DVec3::ZERO {
                        return Err(err(format!(
                            "<lookat>: origin {o} and target {target} coincide, or up {up} is \
                             parallel to the view direction"
                        )));
                    }
                    // Mitsuba's look-at: local +x -> left, +y -> the new up, +z -> dir.
                    let new_up = dir.cross(left);
                    let m = DMat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        o.extend(1.0),
                    );
                    let mut l = toml::Table::new();
                    l.insert("from".into(), vec3(o.to_array()));
                    l.insert("to".into(), vec3(target.to_array()));
                    l.insert("up".into(), vec3(up.to_array()));
                    (table("look_at", toml::Value::Table(l)), m)
                }
                other => {
                    return Err(err(format!(
                        "<{other}> is not a transform operation (translate, rotate, scale, \
                         matrix, lookat)"
                    )))
                }
            };
            t.steps.push(step);
            t.matrix = m * t.matrix;
        }
        Ok(t)
    }

    /// The steps as a TOML value.
    pub fn toml(&self) -> toml::Value {
        toml::Value::Array(self.steps.clone())
    }

    /// The transform followed by `other` (`other` applied last).
    pub fn then(&self, other: &Transform) -> Transform {
        Transform {
            steps: self.steps.iter().chain(&other.steps).cloned().collect(),
            matrix: other.matrix * self.matrix,
        }
    }
}
