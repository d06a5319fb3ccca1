//! The XML document of a Mitsuba 3 scene, read into an owned tree with Mitsuba's
//! preprocessing done: `<default>` and `$name` substitution (command-line `-D` first),
//! `<include>` (relative to the including file, cycles and depth bounded), `<path>` (extra
//! directories to find files in) and `id` registration for `<ref>`.
//!
//! Parsing is `roxmltree`'s (a read-only DOM that keeps byte positions, so every node can
//! be reported at its file, line and column). DTDs are refused (no entity expansion).

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use risotto_engine::diagnostics::{SceneError, SceneErrorKind, Source};

/// Deepest `<include>` nesting accepted (deeper is almost surely a mistake).
const MAX_INCLUDE_DEPTH: usize = 32;
/// Largest XML file read (scene or include), bytes.
const MAX_XML_BYTES: u64 = 256 << 20;
/// Most elements in one XML file (bounds the work on hostile input).
const MAX_XML_NODES: u32 = 1 << 24;
/// Longest attribute value after `$name` substitution, bytes.
const MAX_VALUE_BYTES: usize = 1 << 20;

/// An attribute of an element, after substitution.
#[derive(Debug)]
pub struct Attr {
    /// Attribute name.
    pub name: String,
    /// Value with every `$name` replaced.
    pub value: String,
    /// Byte range of the value in its file.
    pub span: Range<usize>,
}

/// An element of the scene (owned; `<include>`, `<default>` and `<path>` already applied).
#[derive(Debug)]
pub struct Node {
    /// Tag name (`shape`, `float`, ...).
    pub tag: String,
    /// Attributes in document order.
    pub attrs: Vec<Attr>,
    /// Child elements in document order.
    pub children: Vec<Rc<Node>>,
    /// Index of the file in [`Document::sources`].
    pub file: usize,
    /// Byte range of the start tag in its file.
    pub span: Range<usize>,
}

impl Node {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|a| a.name == name)
            .map(|a| a.value.as_str())
    }

    /// The attribute `name` itself.
    pub fn attr_full(&self, name: &str) -> Option<&Attr> {
        self.attrs.iter().find(|a| a.name == name)
    }
}

/// A loaded scene document.
#[derive(Debug)]
pub struct Document {
    /// Every file read (index 0 is the scene file), for located errors.
    pub sources: Vec<Source>,
    /// The `<scene>` element with includes spliced in.
    pub root: Rc<Node>,
    /// Elements by `id`.
    pub ids: HashMap<String, Rc<Node>>,
    /// Directories named by `<path>`, in the order given.
    pub search_paths: Vec<PathBuf>,
}

impl Document {
    /// A located error at `node`.
    pub fn error(
        &self,
        node: &Node,
        kind: SceneErrorKind,
        entity: Option<&str>,
        field: Option<&str>,
        message: impl Into<String>,
    ) -> SceneError {
        self.sources[node.file].error(kind, &node.span, entity, field, message)
    }

    /// The file and line of `node` (for the origin of a converted part).
    pub fn origin(&self, node: &Node) -> (PathBuf, usize) {
        let src = &self.sources[node.file];
        (src.path.clone(), src.line_col(node.span.start).0)
    }

    /// The file `name` given in `node`'s file: relative names are looked up next to that
    /// file, then in each `<path>` directory (the last given first, as Mitsuba's file
    /// resolver prepends them), then next to the scene file; the first that exists wins,
    /// else the name next to the file that wrote it.
    pub fn resolve(&self, node: &Node, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        let own = self.sources[node.file].dir.join(p);
        let candidates = std::iter::once(own.clone())
            .chain(self.search_paths.iter().rev().map(|d| d.join(p)))
            .chain(std::iter::once(self.sources[0].dir.join(p)));
        for c in candidates {
            if c.exists() {
                return c;
            }
        }
        own
    }
}

/// Reads the scene `text` of `path`.
pub fn load(path: &Path, text: &str, defines: &[(String, String)]) -> Result<Document, SceneError> {
    let mut loader = Loader {
        sources: Vec::new(),
        params: defines.iter().cloned().collect(),
        search_paths: Vec::new(),
        stack: Vec::new(),
    };
    let (children, span) = loader.file(path, text, 0)?;
    let root = Rc::new(Node {
        tag: "scene".into(),
        attrs: Vec::new(),
        children,
        file: 0,
        span,
    });
    let mut ids = HashMap::new();
    register_ids(&loader.sources, &root, &mut ids)?;
    Ok(Document {
        sources: loader.sources,
        root,
        ids,
        search_paths: loader.search_paths,
    })
}

/// Every element with an `id` (but `<ref>`, which names one) into `ids`; a second
/// element with the same id is an error at it.
fn register_ids(
    sources: &[Source],
    node: &Rc<Node>,
    ids: &mut HashMap<String, Rc<Node>>,
) -> Result<(), SceneError> {
    for child in &node.children {
        if child.tag != "ref" {
            if let Some(id) = child.attr_full("id") {
                if let Some(first) = ids.get(&id.value) {
                    let (line, _) = sources[first.file].line_col(first.span.start);
                    return Err(sources[child.file].error(
                        SceneErrorKind::Duplicate,
                        &id.span,
                        None,
                        Some("id"),
                        format!(
                            "id \"{}\" is already used by the <{}> at {}:{line}",
                            id.value,
                            first.tag,
                            sources[first.file].path.display()
                        ),
                    ));
                }
                ids.insert(id.value.clone(), child.clone());
            }
        }
        register_ids(sources, child, ids)?;
    }
    Ok(())
}

struct Loader {
    sources: Vec<Source>,
    /// `$name` values: `-D` definitions, then `<default>`s not already defined.
    params: HashMap<String, String>,
    search_paths: Vec<PathBuf>,
    /// Canonical paths of the files being read (include cycle detection).
    stack: Vec<PathBuf>,
}

impl Loader {
    /// Reads one file: the children of its `<scene>` and the span of that element.
    fn file(
        &mut self,
        path: &Path,
        text: &str,
        depth: usize,
    ) -> Result<(Vec<Rc<Node>>, Range<usize>), SceneError> {
        let index = self.sources.len();
        self.sources.push(Source::new(path, text));
        self.stack
            .push(std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()));
        let options = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: MAX_XML_NODES,
            ..roxmltree::ParsingOptions::default()
        };
        let lenient = blank_double_hyphens_in_comments(text);
        let doc = roxmltree::Document::parse_with_options(&lenient, options).map_err(|e| {
            let pos = e.pos();
            let offset = offset_of(text, pos.row as usize, pos.col as usize);
            self.sources[index].error(
                SceneErrorKind::Syntax,
                &(offset..offset + 1),
                None,
                None,
                format!("XML syntax error: {e}"),
            )
        })?;
        let root = doc.root_element();
        let span = start_tag(&root);
        if root.tag_name().name() != "scene" {
            return Err(self.sources[index].error(
                SceneErrorKind::Syntax,
                &span,
                None,
                None,
                format!(
                    "the root element is <{}>; a Mitsuba scene file has <scene version=\"3.0.0\">",
                    root.tag_name().name()
                ),
            ));
        }
        self.check_version(index, &root)?;
        let children = self.children(index, &root, depth)?;
        self.stack.pop();
        Ok((children, span))
    }

    /// The `version` attribute: 2.x and 3.x are Mitsuba 3's XML; older versions (0.x, 1.x:
    /// Mitsuba 0.6) name parameters differently.
    fn check_version(&self, file: usize, root: &roxmltree::Node) -> Result<(), SceneError> {
        let src = &self.sources[file];
        let Some(v) = root.attribute_node("version") else {
            return Err(src.error(
                SceneErrorKind::MissingField,
                &start_tag(root),
                None,
                Some("version"),
                "<scene> has no version attribute (write version=\"3.0.0\")",
            ));
        };
        let major = v.value().split('.').next().unwrap_or("");
        match major.trim().parse::<u32>() {
            Ok(2 | 3) => Ok(()),
            Ok(m) if m < 2 => Err(src.error(
                SceneErrorKind::InvalidValue,
                &v.range_value(),
                None,
                Some("version"),
                format!(
                    "version {} is a Mitsuba 0.6 scene, whose parameter names differ; upgrade \
                     it with Mitsuba 3's `mitsuba.xml.upgrade` rules (or Mitsuba 3 itself) first",
                    v.value()
                ),
            )),
            _ => Err(src.error(
                SceneErrorKind::InvalidValue,
                &v.range_value(),
                None,
                Some("version"),
                format!(
                    "version \"{}\" is not a Mitsuba 3 scene version (2.x or 3.x)",
                    v.value()
                ),
            )),
        }
    }

    /// The element children of `node`, preprocessed.
    fn children(
        &mut self,
        file: usize,
        node: &roxmltree::Node,
        depth: usize,
    ) -> Result<Vec<Rc<Node>>, SceneError> {
        let mut out = Vec::new();
        for child in node.children().filter(|c| c.is_element()) {
            match child.tag_name().name() {
                "default" => {
                    let name = self.required(file, &child, "name")?;
                    let value = self.required(file, &child, "value")?;
                    let value = self.substitute(file, &value, child.range())?;
                    self.params.entry(name).or_insert(value);
                }
                "path" => {
                    let value = self.required(file, &child, "value")?;
                    let dir = self.sources[file].dir.join(value);
                    self.search_paths.push(dir);
                }
                "include" => {
                    let name = self.required(file, &child, "filename")?;
                    out.extend(self.include(file, &child, &name, depth)?);
                }
                _ => out.push(Rc::new(self.element(file, &child, depth)?)),
            }
        }
        Ok(out)
    }

    /// An element with substituted attributes and preprocessed children.
    fn element(
        &mut self,
        file: usize,
        node: &roxmltree::Node,
        depth: usize,
    ) -> Result<Node, SceneError> {
        let mut attrs = Vec::new();
        for a in node.attributes() {
            attrs.push(Attr {
                name: a.name().to_owned(),
                value: self.substitute(file, a.value(), a.range_value())?,
                span: a.range_value(),
            });
        }
        Ok(Node {
            tag: node.tag_name().name().to_owned(),
            attrs,
            children: self.children(file, node, depth)?,
            file,
            span: start_tag(node),
        })
    }

    /// The attribute `name` of a preprocessing element, substituted.
    fn required(
        &self,
        file: usize,
        node: &roxmltree::Node,
        name: &str,
    ) -> Result<String, SceneError> {
        match node.attribute_node(name) {
            Some(a) => self.substitute(file, a.value(), a.range_value()),
            None => Err(self.sources[file].error(
                SceneErrorKind::MissingField,
                &start_tag(node),
                None,
                Some(name),
                format!("<{}> needs a `{name}` attribute", node.tag_name().name()),
            )),
        }
    }

    /// `<include filename="...">`: the included file's `<scene>` children, read relative
    /// to the including file.
    fn include(
        &mut self,
        file: usize,
        node: &roxmltree::Node,
        name: &str,
        depth: usize,
    ) -> Result<Vec<Rc<Node>>, SceneError> {
        let err = |this: &Self, msg: String| {
            this.sources[file].error(
                SceneErrorKind::ExternalFile,
                &start_tag(node),
                None,
                Some("filename"),
                msg,
            )
        };
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(err(
                self,
                format!("includes are nested more than {MAX_INCLUDE_DEPTH} deep"),
            ));
        }
        // Next to the including file, else (Mitsuba's file resolver) in the <path>
        // directories and next to the scene file.
        let mut path = self.sources[file].dir.join(name);
        if !path.exists() {
            if let Some(p) = self
                .search_paths
                .iter()
                .rev()
                .chain(std::iter::once(&self.sources[0].dir))
                .map(|d| d.join(name))
                .find(|p| p.exists())
            {
                path = p;
            }
        }
        let canonical = std::fs::canonicalize(&path)
            .map_err(|e| err(self, format!("cannot read `{}`: {e}", path.display())))?;
        if let Some(i) = self.stack.iter().position(|p| *p == canonical) {
            let chain: Vec<String> = self.stack[i..]
                .iter()
                .chain(std::iter::once(&canonical))
                .map(|p| p.display().to_string())
                .collect();
            return Err(err(
                self,
                format!("include loop: {}", chain.join(" includes ")),
            ));
        }
        let meta = std::fs::metadata(&canonical)
            .map_err(|e| err(self, format!("cannot read `{}`: {e}", path.display())))?;
        if !meta.is_file() || meta.len() > MAX_XML_BYTES {
            return Err(err(
                self,
                format!(
                    "`{}` is not a regular file of at most {MAX_XML_BYTES} bytes",
                    path.display()
                ),
            ));
        }
        let text = std::fs::read_to_string(&canonical)
            .map_err(|e| err(self, format!("cannot read `{}`: {e}", path.display())))?;
        Ok(self.file(&path, &text, depth + 1)?.0)
    }

    /// `value` with each `$name` replaced by its parameter; an unknown name is an error.
    fn substitute(
        &self,
        file: usize,
        value: &str,
        span: Range<usize>,
    ) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_owned());
        }
        let mut out = String::new();
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..len];
            match self.params.get(name) {
                Some(v) if !name.is_empty() => out.push_str(v),
                _ => {
                    return Err(self.sources[file].error(
                        SceneErrorKind::UnknownReference,
                        &span,
                        None,
                        None,
                        format!(
                            "`${name}` is not defined (give it with `-D {name}=...` or a \
                             <default name=\"{name}\" value=\"...\"/>)"
                        ),
                    ))
                }
            }
            if out.len() > MAX_VALUE_BYTES {
                return Err(self.sources[file].error(
                    SceneErrorKind::InvalidValue,
                    &span,
                    None,
                    None,
                    format!("the value is longer than {MAX_VALUE_BYTES} bytes after substitution"),
                ));
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

/// `text` with `--` inside comments (and a `-` just before their `-->`) blanked out to
/// spaces, byte for byte (so positions stay): XML 1.0 forbids them, but pugixml, Mitsuba's
/// parser, accepts them and scenes written for Mitsuba use them (`<!-- a -- b -->`).
fn blank_double_hyphens_in_comments(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.contains("<!--") {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut bytes = text.as_bytes().to_vec();
    let mut at = 0;
    while let Some(open) = text[at..].find("<!--").map(|i| at + i + 4) {
        let Some(close) = text[open..].find("-->").map(|i| open + i) else {
            break;
        };
        for i in open..close {
            let next_is_hyphen = i + 1 < close && bytes[i + 1] == b'-';
            if bytes[i] == b'-' && (next_is_hyphen || i + 1 == close) {
                bytes[i] = b' ';
            }
        }
        at = close + 3;
    }
    // Only ASCII hyphens became ASCII spaces: still UTF-8.
    std::borrow::Cow::Owned(String::from_utf8(bytes).unwrap_or_else(|_| text.to_owned()))
}

/// Byte range of `node`'s start tag (its whole range when it has no children: `<a/>`).
fn start_tag(node: &roxmltree::Node) -> Range<usize> {
    let r = node.range();
    match node.first_child() {
        Some(c) => r.start..c.range().start.max(r.start),
        None => r,
    }
}

/// Byte offset of 1-based `row`, `col` (characters) in `text`.
fn offset_of(text: &str, row: usize, col: usize) -> usize {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(row.saturating_sub(1))
        .map(str::len)
        .sum();
    let line = &text[line_start.min(text.len())..];
    line_start
        + line
            .char_indices()
            .nth(col.saturating_sub(1))
            .map_or(line.len(), |(i, _)| i)
}
