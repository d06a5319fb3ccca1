//! A directive's parameter list (`"float radius" [ 3 ]`), read once and then looked up by
//! name; every parameter a conversion does not read is an error, as pbrt-v4 reports
//! unused parameters, so nothing in the file is dropped silently.

use std::cell::Cell;

use risotto_engine::diagnostics::{SceneError, SceneErrorKind};

use super::lexer::{At, Lexer, Tok};

/// The values of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Values {
    /// Numbers (`integer`, `float`, `point*`, `vector*`, `normal*`, `rgb`, `blackbody`,
    /// a sampled `spectrum`).
    Nums(Vec<f64>),
    /// Strings (`string`, `texture`, a named or file `spectrum`, `bool` written quoted).
    Strs(Vec<String>),
    /// `true` / `false` words.
    Bools(Vec<bool>),
}

/// One parameter.
#[derive(Clone, Debug)]
pub(super) struct Param {
    /// Its type (`float`, `rgb`, ...).
    pub ty: String,
    /// Its name.
    pub name: String,
    /// Where `"type name"` is.
    pub at: At,
    /// Its values.
    pub values: Values,
    /// Whether the conversion read it.
    used: Cell<bool>,
}

/// The parameter types of pbrt-v4 (and `color`, pbrt-v3's `rgb`; `point` / `vector` /
/// `normal`, the short forms of the 3-D ones).
const TYPES: &[&str] = &[
    "integer",
    "float",
    "point2",
    "vector2",
    "point3",
    "vector3",
    "point",
    "vector",
    "normal",
    "normal3",
    "rgb",
    "color",
    "spectrum",
    "blackbody",
    "bool",
    "string",
    "texture",
];

/// A directive's parameters.
#[derive(Debug, Default)]
pub(super) struct Params {
    /// In file order.
    pub list: Vec<Param>,
    /// The directive (`Shape "sphere"`), for messages.
    pub entity: String,
}

/// A colour-valued parameter's value.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Colour {
    /// Linear Rec.709 RGB.
    Rgb([f64; 3]),
    /// A named texture.
    Texture(String),
    /// A named spectrum (`metal-Au-eta`, `glass-BK7`).
    Named(String),
}

impl Params {
    /// Reads `"type name" value` pairs while the next token is a string.
    pub fn read(lx: &mut Lexer, entity: &str) -> Result<Params, SceneError> {
        let mut list: Vec<Param> = Vec::new();
        while let Some(tok) = lx.peek()? {
            let Tok::Str(decl) = &tok.tok else { break };
            let decl = decl.clone();
            let at = tok.at.clone();
            lx.next()?;
            let mut words = decl.split_whitespace();
            let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
                return Err(lx.error(
                    SceneErrorKind::Syntax,
                    &at,
                    entity,
                    format!(
                        "expected a parameter declaration \"type name\" (such as \"float radius\"), got \"{decl}\""
                    ),
                ));
            };
            if !TYPES.contains(&ty) {
                return Err(lx.error(
                    SceneErrorKind::InvalidValue,
                    &at,
                    entity,
                    format!(
                        "unknown parameter type `{ty}` in \"{decl}\"; expected one of {}",
                        TYPES.join(", ")
                    ),
                ));
            }
            if list.iter().any(|p| p.name == name) {
                return Err(lx.error(
                    SceneErrorKind::Duplicate,
                    &at,
                    entity,
                    format!("parameter `{name}` is given twice"),
                ));
            }
            let values = read_values(lx, &at, entity, &decl)?;
            list.push(Param {
                ty: ty.to_owned(),
                name: name.to_owned(),
                at,
                values,
                used: Cell::new(false),
            });
        }
        Ok(Params {
            list,
            entity: entity.to_owned(),
        })
    }

    /// Adds the `Attribute` defaults not given here (pbrt-v4: a parameter on the directive
    /// wins over the default).
    pub fn with_defaults(mut self, defaults: Option<&Vec<Param>>) -> Params {
        for d in defaults.into_iter().flatten() {
            if !self.list.iter().any(|p| p.name == d.name) {
                self.list.push(d.clone());
            }
        }
        self
    }

    fn find(&self, name: &str) -> Option<&Param> {
        let p = self.list.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// A located error at parameter `p`.
    pub fn error(&self, lx: &Lexer, p: &Param, message: impl Into<String>) -> SceneError {
        lx.error(
            SceneErrorKind::InvalidValue,
            &p.at,
            &self.entity,
            format!("parameter `{} {}`: {}", p.ty, p.name, message.into()),
        )
    }

    /// Marks `name` as read without reading it (a parameter with no effect on the image,
    /// such as the film's file name); returns it if present.
    pub fn ignore(&self, name: &str) -> Option<&Param> {
        self.find(name)
    }

    /// Whether `name` is given (marking it read).
    pub fn has(&self, name: &str) -> bool {
        self.list.iter().any(|p| p.name == name)
    }

    /// The numbers of `name`, checking its type is one of `types` and the count is a
    /// multiple of `per` (and non-zero).
    pub fn nums(
        &self,
        lx: &Lexer,
        name: &str,
        types: &[&str],
        per: usize,
    ) -> Result<Option<(&[f64], &Param)>, SceneError> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        if !types.contains(&p.ty.as_str()) {
            return Err(self.error(lx, p, format!("expected type {}", types.join(" or "))));
        }
        match &p.values {
            Values::Nums(v) if !v.is_empty() && v.len() % per == 0 => Ok(Some((v, p))),
            Values::Nums(v) => Err(self.error(
                lx,
                p,
                format!(
                    "expected a multiple of {per} numbers (at least {per}), got {}",
                    v.len()
                ),
            )),
            _ => Err(self.error(lx, p, "expected numbers")),
        }
    }

    /// One `float` (or `integer`) `name`, or `default`.
    pub fn float(&self, lx: &Lexer, name: &str, default: f64) -> Result<f64, SceneError> {
        match self.nums(lx, name, &["float", "integer"], 1)? {
            None => Ok(default),
            Some((v, _)) if v.len() == 1 => Ok(v[0]),
            Some((_, p)) => Err(self.error(lx, p, "expected one number")),
        }
    }

    /// A `float` that must satisfy `ok` (described by `what`).
    pub fn float_where(
        &self,
        lx: &Lexer,
        name: &str,
        default: f64,
        what: &str,
        ok: impl Fn(f64) -> bool,
    ) -> Result<f64, SceneError> {
        let v = self.float(lx, name, default)?;
        // Only a given value is checked: a default that does not fit (pbrt's `conedelta`
        // of 5 under a `coneangle` of 3) is left to the TOML loader's check of the result.
        match self.list.iter().find(|p| p.name == name) {
            Some(p) if !ok(v) => Err(self.error(lx, p, format!("must be {what}, got {v}"))),
            _ => Ok(v),
        }
    }

    /// One `integer` `name`, or `default`.
    pub fn int(&self, lx: &Lexer, name: &str, default: i64) -> Result<i64, SceneError> {
        match self.nums(lx, name, &["integer"], 1)? {
            None => Ok(default),
            Some((v, _)) if v.len() == 1 && v[0].fract() == 0.0 && v[0].abs() < 9e15 => {
                Ok(v[0] as i64)
            }
            Some((_, p)) => Err(self.error(lx, p, "expected one integer")),
        }
    }

    /// Integers of `name` (each within `0..limit`).
    pub fn ints(&self, lx: &Lexer, name: &str) -> Result<Option<(Vec<u32>, &Param)>, SceneError> {
        let Some((v, p)) = self.nums(lx, name, &["integer"], 1)? else {
            return Ok(None);
        };
        let mut out = Vec::with_capacity(v.len());
        for (i, &x) in v.iter().enumerate() {
            if x.fract() != 0.0 || !(0.0..=f64::from(u32::MAX)).contains(&x) {
                return Err(self.error(
                    lx,
                    p,
                    format!("value {i} ({x}) is not an integer in [0, {}]", u32::MAX),
                ));
            }
            out.push(x as u32);
        }
        Ok(Some((out, p)))
    }

    /// One `string` `name`.
    pub fn string(&self, lx: &Lexer, name: &str) -> Result<Option<(&str, &Param)>, SceneError> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        match &p.values {
            Values::Strs(v) if v.len() == 1 && (p.ty == "string" || p.ty == "texture") => {
                Ok(Some((&v[0], p)))
            }
            _ => Err(self.error(lx, p, "expected one string")),
        }
    }

    /// One `bool` `name`, or `default`.
    pub fn bool(&self, lx: &Lexer, name: &str, default: bool) -> Result<bool, SceneError> {
        let Some(p) = self.find(name) else {
            return Ok(default);
        };
        match &p.values {
            Values::Bools(v) if v.len() == 1 && p.ty == "bool" => Ok(v[0]),
            Values::Strs(v)
                if v.len() == 1 && p.ty == "bool" && (v[0] == "true" || v[0] == "false") =>
            {
                Ok(v[0] == "true")
            }
            _ => Err(self.error(lx, p, "expected one bool (true or false)")),
        }
    }

    /// One 3-vector (`point3`, `vector3`, `normal`, ...) `name`.
    pub fn vec3(&self, lx: &Lexer, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        let types = ["point3", "point", "vector3", "vector", "normal", "normal3"];
        match self.nums(lx, name, &types, 3)? {
            None => Ok(None),
            Some((v, _)) if v.len() == 3 => Ok(Some([v[0], v[1], v[2]])),
            Some((_, p)) => Err(self.error(lx, p, "expected one 3-vector")),
        }
    }

    /// A colour `name`: `rgb`, a `spectrum` given by one constant or by a name, or a
    /// `texture` when `textures` allows one. Sampled spectra and blackbody emitters are
    /// converted by the caller's `spectrum` function (`None`: a located error).
    pub fn colour(
        &self,
        lx: &Lexer,
        name: &str,
        textures: bool,
        spectrum: &dyn Fn(&Param) -> Result<Colour, SceneError>,
    ) -> Result<Option<Colour>, SceneError> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        let c = match (p.ty.as_str(), &p.values) {
            ("rgb" | "color", Values::Nums(v)) if v.len() == 3 => Colour::Rgb([v[0], v[1], v[2]]),
            ("rgb" | "color", _) => return Err(self.error(lx, p, "expected 3 numbers")),
            ("float", Values::Nums(v)) if v.len() == 1 => Colour::Rgb([v[0]; 3]),
            ("spectrum", Values::Nums(v)) if v.len() == 1 => Colour::Rgb([v[0]; 3]),
            ("texture", Values::Strs(v)) if textures && v.len() == 1 => {
                Colour::Texture(v[0].clone())
            }
            ("texture", _) if !textures => {
                return Err(self.error(lx, p, "a texture is not supported here (give a value)"))
            }
            ("spectrum" | "blackbody", _) => spectrum(p)?,
            _ => return Err(self.error(lx, p, "expected a colour (rgb, spectrum or texture)")),
        };
        if let Colour::Rgb(c) = &c {
            if c.iter().any(|x| !x.is_finite()) {
                return Err(self.error(lx, p, "must be finite"));
            }
        }
        Ok(Some(c))
    }

    /// Errors on the first parameter not read (pbrt-v4 reports unused parameters too).
    pub fn finish(&self, lx: &Lexer) -> Result<(), SceneError> {
        match self.list.iter().find(|p| !p.used.get()) {
            None => Ok(()),
            Some(p) => Err(lx.error(
                SceneErrorKind::UnknownField,
                &p.at,
                &self.entity,
                format!(
                    "parameter `{} {}` is not supported here (see docs/import-pbrt.md)",
                    p.ty, p.name
                ),
            )),
        }
    }
}

/// One value or a bracketed list of values of one kind.
fn read_values(lx: &mut Lexer, at: &At, entity: &str, decl: &str) -> Result<Values, SceneError> {
    let missing = |lx: &Lexer| {
        lx.error(
            SceneErrorKind::Syntax,
            at,
            entity,
            format!("parameter \"{decl}\" has no value"),
        )
    };
    let Some(first) = lx.next()? else {
        return Err(missing(lx));
    };
    let bracketed = first.tok == Tok::Open;
    let mut values: Option<Values> = None;
    let mut pending = if bracketed { None } else { Some(first) };
    loop {
        let tok = match pending.take() {
            Some(t) => t,
            None => match lx.next()? {
                Some(t) => t,
                None => {
                    return Err(lx.error(
                        SceneErrorKind::Syntax,
                        at,
                        entity,
                        format!("the values of \"{decl}\" have no closing `]`"),
                    ))
                }
            },
        };
        let kind_error = |lx: &Lexer, t: &super::lexer::Token| {
            lx.error(
                SceneErrorKind::Syntax,
                &t.at,
                entity,
                format!("the values of \"{decl}\" must all be numbers, all strings or all bools"),
            )
        };
        match (&tok.tok, &mut values) {
            (Tok::Close, _) if bracketed => break,
            (Tok::Num(v), None) => values = Some(Values::Nums(vec![*v])),
            (Tok::Num(v), Some(Values::Nums(list))) => list.push(*v),
            (Tok::Str(s), None) => values = Some(Values::Strs(vec![s.clone()])),
            (Tok::Str(s), Some(Values::Strs(list))) => list.push(s.clone()),
            (Tok::Word(w), None) if w == "true" || w == "false" => {
                values = Some(Values::Bools(vec![w == "true"]))
            }
            (Tok::Word(w), Some(Values::Bools(list))) if w == "true" || w == "false" => {
                list.push(w == "true")
            }
            (Tok::Num(_) | Tok::Str(_), Some(_)) => return Err(kind_error(lx, &tok)),
            _ => {
                return Err(lx.error(
                    SceneErrorKind::Syntax,
                    &tok.at,
                    entity,
                    format!("unexpected token in the values of \"{decl}\""),
                ))
            }
        }
        if !bracketed {
            break;
        }
    }
    values.ok_or_else(|| missing(lx))
}
