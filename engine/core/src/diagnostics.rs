//! Diagnostics: [`SceneError`], a scene-file error located by file, line and column with a
//! source excerpt; the scene text it points into ([`Source`]); a value's place in it
//! ([`Location`]), for checks that run after parsing; and the files a scene reads
//! ([`ReferencedFiles`]). Any scene-file reader (the TOML loader, a user's own format) builds
//! its errors with these, and the scene world keeps them to report late errors where the
//! value was written.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What went wrong, for callers that react to the category (the message says it all).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneErrorKind {
    /// The scene file itself could not be read.
    Io,
    /// The text is not valid TOML.
    Syntax,
    /// A key the entity does not accept (usually a typo).
    UnknownField,
    /// A required key is absent.
    MissingField,
    /// A value of the wrong TOML type (e.g. a string where a number is expected).
    WrongType,
    /// A value of the right type outside its valid range (negative radiance, fov 190, ...).
    InvalidValue,
    /// A name that refers to nothing (a shape's material, a camera volume shape).
    UnknownReference,
    /// Two entities with the same name.
    Duplicate,
    /// A referenced file (OBJ mesh, environment map) is missing or cannot be parsed.
    ExternalFile,
}

/// An error in a scene file. Its `Display` is a complete message: the file, line and
/// column, the entity (`shapes[3] "tall_box"`, `materials.glass`, `camera`), the field, what
/// is wrong with the offending value, then the offending source line with a caret marker.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{}", .0.rendered)]
pub struct SceneError(Box<ErrorData>);

/// The parts of a [`SceneError`] (boxed: errors are rare, `Result`s are everywhere).
#[derive(Debug, Clone)]
struct ErrorData {
    kind: SceneErrorKind,
    file: PathBuf,
    line_col: Option<(usize, usize)>,
    entity: Option<String>,
    field: Option<String>,
    message: String,
    rendered: String,
}

impl SceneError {
    /// The category.
    pub fn kind(&self) -> SceneErrorKind {
        self.0.kind
    }
    /// The scene file the error is in.
    pub fn file(&self) -> &Path {
        &self.0.file
    }
    /// 1-based line of the offending text (`None` only when the file could not be read).
    pub fn line(&self) -> Option<usize> {
        self.0.line_col.map(|(l, _)| l)
    }
    /// 1-based column (in characters) of the offending text.
    pub fn column(&self) -> Option<usize> {
        self.0.line_col.map(|(_, c)| c)
    }
    /// The entity, e.g. `shapes[3] "tall_box"` or `materials.glass`.
    pub fn entity(&self) -> Option<&str> {
        self.0.entity.as_deref()
    }
    /// The field (key) within the entity, e.g. `radius`.
    pub fn field(&self) -> Option<&str> {
        self.0.field.as_deref()
    }
    /// The bare description without location, entity and excerpt.
    pub fn message(&self) -> &str {
        &self.0.message
    }

    /// An error about `file` with no line to name (a scene description built in code rather
    /// than parsed).
    pub fn unlocated(file: &Path, kind: SceneErrorKind, message: &str) -> SceneError {
        SceneError(Box::new(ErrorData {
            kind,
            file: file.to_path_buf(),
            line_col: None,
            entity: None,
            field: None,
            rendered: format!("{}: {message}", file.display()),
            message: message.to_owned(),
        }))
    }

    /// An error reading the scene file itself.
    pub fn io(file: &Path, err: &std::io::Error) -> SceneError {
        let message = format!("cannot read scene file: {err}");
        SceneError(Box::new(ErrorData {
            kind: SceneErrorKind::Io,
            file: file.to_path_buf(),
            line_col: None,
            entity: None,
            field: None,
            rendered: format!("{}: {message}", file.display()),
            message,
        }))
    }
}

/// The scene text being read, for turning byte spans into line:column and excerpts.
#[derive(Debug)]
pub struct Source {
    /// The scene file's path as given (used in messages).
    pub path: PathBuf,
    /// The directory relative paths in the scene are resolved against.
    pub dir: PathBuf,
    /// The whole text.
    pub text: String,
    /// Every file path resolved from the text (and noted by factories).
    pub files: ReferencedFiles,
    /// The side files decoded so far, shared by every entity that names them
    /// ([`crate::side_files`]).
    pub side_files: crate::side_files::SideFiles,
    /// What reading the scene and its files found that a user should know without it being
    /// an error (an OBJ's points and lines skipped); every render's stats repeat them.
    pub warnings: SceneWarnings,
    /// Where the command-line overrides begin in `text`, if there are any
    /// ([`Source::with_overrides`]): errors in them name the `-D` argument, not a line of the
    /// file.
    overrides_at: Option<usize>,
    /// When `text` is the TOML a scene of another format was converted to
    /// ([`Source::converted`]): where each part of it came from, by byte range in `text`
    /// (ascending, disjoint), so errors name the original file and line.
    origins: Option<Vec<(Range<usize>, Origin)>>,
}

/// Where a part of a converted scene was written in its original file (a Mitsuba XML
/// element, a pbrt directive): errors found in the converted TOML are reported here.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Origin {
    /// The original file (an `<include>`d or `Import`ed file where the part was written).
    pub file: PathBuf,
    /// 1-based line in `file`.
    pub line: usize,
}

/// Characters of a source line shown on each side of an error's caret.
const EXCERPT_CONTEXT: usize = 60;

/// `text` safe to print on a terminal: control characters (an escape sequence in a file
/// name or a scene, which a terminal would obey) shown escaped as `\u{1b}`, except line
/// breaks and tabs.
pub fn terminal_safe(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() && c != '\n' && c != '\t' {
            out.extend(c.escape_unicode());
        } else {
            out.push(c);
        }
    }
    out
}

/// Longest excerpt of a value quoted in a message.
const MAX_QUOTE: usize = 60;

impl Source {
    /// The text `text` of the file `path`.
    pub fn new(path: &Path, text: &str) -> Source {
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        Source {
            path: path.to_path_buf(),
            dir,
            text: text.to_owned(),
            files: ReferencedFiles::default(),
            side_files: Default::default(),
            warnings: SceneWarnings::default(),
            overrides_at: None,
            origins: None,
        }
    }

    /// The TOML text `toml` that the scene file `path` (Mitsuba XML, pbrt) was converted to,
    /// with the origin of each part: `origins[i] = (range, origin)` says that the bytes
    /// `range` of `toml` were converted from `origin`. Errors in such a part are reported at
    /// the original file and line, others at `path` without a line; the converted TOML line
    /// is quoted below either. Relative paths in `toml` resolve against `path`'s directory.
    pub fn converted(path: &Path, toml: &str, mut origins: Vec<(Range<usize>, Origin)>) -> Source {
        let mut src = Source::new(path, toml);
        origins.sort_by_key(|(r, _)| r.start);
        src.origins = Some(origins);
        src
    }

    /// The origin of the converted text at byte `offset`, if this is a converted scene and
    /// the offset lies in a part with one.
    fn origin_at(&self, offset: usize) -> Option<&Origin> {
        let origins = self.origins.as_ref()?;
        let i = origins.partition_point(|(r, _)| r.start <= offset);
        let (range, origin) = origins.get(i.checked_sub(1)?)?;
        range.contains(&offset).then_some(origin)
    }

    /// The text `text` of the file `path` followed by command-line overrides (`-D KEY=VALUE`),
    /// one per line after the file's text, so that values parsed from them carry spans into
    /// this text and their errors quote the argument. Returns the source and the byte offset
    /// of each override's line (it starts with `-D `).
    pub fn with_overrides(path: &Path, text: &str, overrides: &[String]) -> (Source, Vec<usize>) {
        let mut src = Source::new(path, text);
        let starts = src.append_overrides(overrides);
        (src, starts)
    }

    /// Appends command-line overrides after the text as [`Source::with_overrides`] does
    /// (also to a [`Source::converted`] scene) and returns the byte offset of each one's line.
    pub fn append_overrides(&mut self, overrides: &[String]) -> Vec<usize> {
        if overrides.is_empty() {
            return Vec::new();
        }
        if !self.text.ends_with('\n') {
            self.text.push('\n');
        }
        self.overrides_at = Some(self.text.len());
        overrides
            .iter()
            .map(|o| {
                let start = self.text.len();
                // One line each: a line break inside an argument would split it.
                self.text.push_str("-D ");
                self.text.push_str(&o.replace(['\n', '\r'], " "));
                self.text.push('\n');
                start
            })
            .collect()
    }

    /// Whether a byte offset lies in the command-line overrides.
    fn in_overrides(&self, offset: usize) -> bool {
        self.overrides_at.is_some_and(|at| offset >= at)
    }

    /// Clamps a byte offset into the text, onto a char boundary.
    fn clamp(&self, mut offset: usize) -> usize {
        offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        offset
    }

    /// 1-based line and column (in chars) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = self.clamp(offset);
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let col = self.text[line_start..offset].chars().count() + 1;
        (line, col)
    }

    /// The source text of a span, shortened for quoting in a message.
    pub fn quote(&self, span: &Range<usize>) -> String {
        let (s, e) = (self.clamp(span.start), self.clamp(span.end));
        let text = self.text[s..e.max(s)].trim();
        // A table's span covers whole lines; quote only its first line.
        let first = text.lines().next().unwrap_or("");
        let shortened: String = first.chars().take(MAX_QUOTE).collect();
        if shortened.len() < text.len() {
            format!("{shortened} ...")
        } else {
            shortened
        }
    }

    /// The line containing `span.start` and a caret line under the span (clipped to that
    /// line), indented like rustc's excerpts.
    fn excerpt(&self, span: &Range<usize>) -> String {
        let start = self.clamp(span.start);
        let end = self.clamp(span.end).max(start);
        let line_start = self.text[..start].rfind('\n').map_or(0, |i| i + 1);
        let line_end = self.text[start..]
            .find('\n')
            .map_or(self.text.len(), |i| start + i);
        let line_text = self.text[line_start..line_end].trim_end_matches('\r');
        let (line, col) = self.line_col(start);
        // A command-line override is labelled `-D`, not with a line number past the file's end.
        let label = if self.in_overrides(start) {
            "-D".to_string()
        } else {
            line.to_string()
        };
        let width = self.text[start..end.min(line_end)].chars().count().max(1);
        // A long line (a minified file, a hostile one: 100 000 brackets) is shown as a
        // window around the caret, each cut marked, so a message stays a few lines long.
        let chars: Vec<char> = line_text.chars().collect();
        let first = (col - 1).saturating_sub(EXCERPT_CONTEXT);
        let last = (col - 1 + width.min(EXCERPT_CONTEXT) + EXCERPT_CONTEXT).min(chars.len());
        let mut shown: String =
            terminal_safe(&chars[first..last.max(first)].iter().collect::<String>());
        let mut caret_col = col - 1 - first;
        if first > 0 {
            shown.insert_str(0, "... ");
            caret_col += 4;
        }
        if last < chars.len() {
            shown.push_str(" ...");
        }
        let gutter = label.len();
        let mut out = String::new();
        let _ = writeln!(out, "{:gutter$} |", "");
        let _ = writeln!(out, "{label} | {shown}");
        let _ = write!(
            out,
            "{:gutter$} | {}{}",
            "",
            " ".repeat(caret_col),
            "^".repeat(width.min(EXCERPT_CONTEXT))
        );
        out
    }

    /// Builds a located error.
    pub fn error(
        &self,
        kind: SceneErrorKind,
        span: &Range<usize>,
        entity: Option<&str>,
        field: Option<&str>,
        message: impl Into<String>,
    ) -> SceneError {
        let message = message.into();
        let (line, col) = self.line_col(span.start);
        let origin = self
            .origin_at(span.start)
            .filter(|_| !self.in_overrides(span.start));
        let converted = self.origins.is_some() && !self.in_overrides(span.start);
        let mut head = if let Some(o) = origin {
            format!("{}:{}: ", o.file.display(), o.line)
        } else if converted {
            format!("{}: ", self.path.display())
        } else if self.in_overrides(span.start) {
            let start = self.clamp(span.start);
            let line_start = self.text[..start].rfind('\n').map_or(0, |i| i + 1);
            let line_end = self.text[start..]
                .find('\n')
                .map_or(self.text.len(), |i| start + i);
            let arg: String = self.text[line_start..line_end]
                .chars()
                .take(MAX_QUOTE)
                .collect();
            format!(
                "{}: command-line override `{}`: ",
                self.path.display(),
                terminal_safe(&arg)
            )
        } else {
            format!("{}:{line}:{col}: ", self.path.display())
        };
        match (entity, field) {
            (Some(e), Some(f)) => {
                let _ = write!(head, "{e}, field `{f}`: ");
            }
            (Some(e), None) => {
                let _ = write!(head, "{e}: ");
            }
            (None, Some(f)) => {
                let _ = write!(head, "field `{f}`: ");
            }
            (None, None) => {}
        }
        let rendered = match converted {
            true => format!(
                "{head}{message}\n  in the scene's TOML conversion (`risotto convert`), line \
                 {line}:\n{}",
                self.excerpt(span)
            ),
            false => format!("{head}{message}\n{}", self.excerpt(span)),
        };
        let (file, line_col) = match origin {
            Some(o) => (o.file.clone(), Some((o.line, 1))),
            None if converted => (self.path.clone(), None),
            None => (
                self.path.clone(),
                (!self.in_overrides(span.start)).then_some((line, col)),
            ),
        };
        SceneError(Box::new(ErrorData {
            kind,
            file,
            line_col,
            entity: entity.map(str::to_owned),
            field: field.map(str::to_owned),
            message,
            rendered,
        }))
    }
}

/// Where a value sits in its scene file, kept for the checks that can only run after
/// parsing (reading an environment map, comparing `camera.inside` with the volumes the
/// camera is really in, resolving a material type against the registry), so that their
/// errors name the file, line and column like the parser's own.
#[derive(Clone, Debug)]
pub struct Location {
    src: std::sync::Arc<Source>,
    span: Range<usize>,
    entity: String,
    field: Option<String>,
}

impl Location {
    /// The place `span` (bytes) of `src`, the value of `field` (if any) of `entity`.
    pub fn new(
        src: &std::sync::Arc<Source>,
        span: Range<usize>,
        entity: &str,
        field: Option<&str>,
    ) -> Location {
        Location {
            src: std::sync::Arc::clone(src),
            span,
            entity: entity.to_owned(),
            field: field.map(str::to_owned),
        }
    }

    /// A located error at this value: `file:line:col: entity, field `f`: message` and the
    /// source excerpt.
    pub fn error(&self, kind: SceneErrorKind, message: impl Into<String>) -> SceneError {
        self.src.error(
            kind,
            &self.span,
            Some(&self.entity),
            self.field.as_deref(),
            message,
        )
    }
}

/// Two locations are equal when they name the same place: the same file, span, entity and
/// field (the text itself is not compared).
impl PartialEq for Location {
    fn eq(&self, other: &Location) -> bool {
        self.src.path == other.src.path
            && self.span == other.span
            && self.entity == other.entity
            && self.field == other.field
    }
}

/// Warnings found while reading a scene (a shared handle, like [`ReferencedFiles`]: readers
/// deep in the loader add to it; the scene and its compiled form carry them to the stats).
#[derive(Clone, Debug, Default)]
pub struct SceneWarnings(Arc<std::sync::Mutex<Vec<String>>>);

impl SceneWarnings {
    /// Adds a warning (once: the same text twice is one warning).
    pub fn add(&self, warning: String) {
        let mut w = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if !w.contains(&warning) {
            w.push(warning);
        }
    }

    /// The warnings, in the order they were found.
    pub fn list(&self) -> Vec<String> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// The files a scene reads besides its own text: every path resolved from the scene file
/// (meshes, grids, environment maps, any path a material factory reads) and those factories
/// note. A shared handle: the description, the [`Scene`](crate::scene::Scene) built from it
/// and the compiled scene see the same list, which grows while factories parse their
/// parameters. Split renders hash the files' contents into their scene hash.
#[derive(Clone, Debug, Default)]
pub struct ReferencedFiles(Arc<std::sync::Mutex<Vec<PathBuf>>>);

impl ReferencedFiles {
    /// Adds a path.
    pub fn add(&self, path: &Path) {
        let mut files = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if !files.iter().any(|p| p == path) {
            files.push(path.to_path_buf());
        }
    }

    /// The paths, sorted.
    pub fn paths(&self) -> Vec<PathBuf> {
        let mut v = self.0.lock().unwrap_or_else(|e| e.into_inner()).clone();
        v.sort();
        v
    }
}
