//! pbrt-v4's tokens and parameter lists, read from a stack of files (`Include` and
//! `Import` read their file in place), every token remembering its file and byte span so
//! that any error names `file:line:col`.
//!
//! The grammar (pbrt-v4 `src/pbrt/parser.cpp`, "File format" in the pbrt-v4 user's
//! guide): `#` comments to the end of the line; double-quoted strings (`\"`, `\\`, `\n`,
//! `\t` escapes, no newline inside); numbers; `[` and `]`; bare words (directives and
//! `true` / `false`). A parameter is a string `"type name"` followed by one value or a
//! bracketed list of values of one kind. Tokenizing is one pass over the bytes, so a
//! mesh of millions of numbers costs time and memory in proportion to the file.

use std::ops::Range;
use std::path::{Path, PathBuf};

use risotto_engine::diagnostics::{SceneError, SceneErrorKind, Source};

/// One file being read.
pub(super) struct File {
    /// The path as given (joined to the including file's directory).
    pub path: PathBuf,
    /// Its text and line table, for located errors.
    pub src: Source,
}

/// Where a token is: file index and byte span in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct At {
    /// Index into the converter's files.
    pub file: usize,
    /// Byte span in that file.
    pub span: Range<usize>,
}

/// The kinds of token.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    /// A bare word (a directive, `true`, `false`).
    Word(String),
    /// A quoted string, unescaped.
    Str(String),
    /// A number.
    Num(f64),
    /// `[`.
    Open,
    /// `]`.
    Close,
}

/// A token and where it is.
#[derive(Clone, Debug)]
pub(super) struct Token {
    /// What it is.
    pub tok: Tok,
    /// Where it is.
    pub at: At,
}

/// The deepest nesting of `Include` / `Import` (a file including itself ends here).
pub(super) const MAX_INCLUDE_DEPTH: usize = 32;

/// The files being read and the read position in each, innermost last.
pub(super) struct Lexer {
    /// Every file read so far (errors refer to them by index).
    pub files: Vec<File>,
    /// `(file, byte offset)` of each open file, the including ones first.
    stack: Vec<(usize, usize)>,
    peeked: Option<Token>,
}

impl Lexer {
    /// A lexer over the top-level file.
    pub fn new(path: &Path, text: &str) -> Lexer {
        Lexer {
            files: vec![File {
                path: path.to_path_buf(),
                src: Source::new(path, text),
            }],
            stack: vec![(0, 0)],
            peeked: None,
        }
    }

    /// A located error.
    pub fn error(
        &self,
        kind: SceneErrorKind,
        at: &At,
        entity: &str,
        message: impl Into<String>,
    ) -> SceneError {
        self.files[at.file]
            .src
            .error(kind, &at.span, Some(entity), None, message)
    }

    /// The 1-based line of `at`.
    pub fn line(&self, at: &At) -> usize {
        self.files[at.file].src.line_col(at.span.start).0
    }

    /// The file of `at`.
    pub fn path(&self, at: &At) -> &Path {
        &self.files[at.file].path
    }

    /// Starts reading `path` (already resolved) in place of the rest of the current file,
    /// which resumes when it ends. `at` is the directive that asked for it.
    pub fn push_file(&mut self, path: &Path, at: &At, directive: &str) -> Result<(), SceneError> {
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(self.error(
                SceneErrorKind::InvalidValue,
                at,
                directive,
                format!(
                    "files nested more than {MAX_INCLUDE_DEPTH} deep (does `{}` include itself?)",
                    path.display()
                ),
            ));
        }
        let fail = |m: String| self.error(SceneErrorKind::ExternalFile, at, directive, m);
        std::fs::metadata(path)
            .map_err(|e| fail(format!("cannot read `{}`: {e}", path.display())))?;
        crate::side_file::check(path).map_err(fail)?;
        let text = std::fs::read_to_string(path)
            .map_err(|e| fail(format!("cannot read `{}`: {e}", path.display())))?;
        self.files.push(File {
            path: path.to_path_buf(),
            src: Source::new(path, &text),
        });
        self.stack.push((self.files.len() - 1, 0));
        Ok(())
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Result<Option<&Token>, SceneError> {
        if self.peeked.is_none() {
            self.peeked = self.scan()?;
        }
        Ok(self.peeked.as_ref())
    }

    /// The next token.
    pub fn next(&mut self) -> Result<Option<Token>, SceneError> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.scan(),
        }
    }

    /// Reads one token, leaving files that end.
    fn scan(&mut self) -> Result<Option<Token>, SceneError> {
        loop {
            let Some(&(file, pos)) = self.stack.last() else {
                return Ok(None);
            };
            let bytes = self.files[file].src.text.as_bytes();
            let mut i = pos;
            // Whitespace and comments.
            while i < bytes.len() {
                match bytes[i] {
                    b' ' | b'\t' | b'\r' | b'\n' => i += 1,
                    b'#' => {
                        while i < bytes.len() && bytes[i] != b'\n' {
                            i += 1;
                        }
                    }
                    _ => break,
                }
            }
            if i >= bytes.len() {
                self.stack.pop();
                continue;
            }
            let start = i;
            let at = |end: usize| At {
                file,
                span: start..end,
            };
            let (tok, end) = match bytes[i] {
                b'[' => (Tok::Open, i + 1),
                b']' => (Tok::Close, i + 1),
                b'"' => {
                    let mut s = Vec::new();
                    i += 1;
                    loop {
                        match bytes.get(i) {
                            None | Some(b'\n') => {
                                return Err(self.error(
                                    SceneErrorKind::Syntax,
                                    &at(start + 1),
                                    "string",
                                    "unterminated string (no closing `\"` on this line)",
                                ))
                            }
                            Some(b'"') => break,
                            Some(b'\\') => {
                                let c = match bytes.get(i + 1) {
                                    Some(b'n') => b'\n',
                                    Some(b't') => b'\t',
                                    Some(&c) => c,
                                    None => b'\\',
                                };
                                s.push(c);
                                i += 2;
                            }
                            Some(&c) => {
                                s.push(c);
                                i += 1;
                            }
                        }
                    }
                    // The bytes came from a `str` and were split only at ASCII, so they
                    // are UTF-8.
                    (Tok::Str(String::from_utf8_lossy(&s).into_owned()), i + 1)
                }
                c if c.is_ascii_alphabetic() || c == b'_' => {
                    while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_')
                    {
                        i += 1;
                    }
                    let w = &self.files[file].src.text[start..i];
                    (Tok::Word(w.to_owned()), i)
                }
                _ => {
                    while i < bytes.len()
                        && !matches!(
                            bytes[i],
                            b' ' | b'\t' | b'\r' | b'\n' | b'[' | b']' | b'"' | b'#'
                        )
                    {
                        i += 1;
                    }
                    let w = &self.files[file].src.text[start..i];
                    // Only digits, signs, a point and an exponent: Rust would also read
                    // `inf` and `nan`, which pbrt does not.
                    let numeric = w
                        .bytes()
                        .all(|c| c.is_ascii_digit() || b"+-.eE".contains(&c));
                    match w.parse::<f64>() {
                        Ok(v) if numeric && v.is_finite() => (Tok::Num(v), i),
                        Ok(_) if numeric => {
                            return Err(self.error(
                                SceneErrorKind::InvalidValue,
                                &at(i),
                                "number",
                                format!("`{w}` is not a finite number"),
                            ))
                        }
                        _ => {
                            return Err(self.error(
                                SceneErrorKind::Syntax,
                                &at(i.max(start + 1)),
                                "token",
                                format!("unexpected `{w}` (expected a directive, a string, a number or a bracket)"),
                            ))
                        }
                    }
                }
            };
            self.stack.last_mut().expect("a file is open").1 = end;
            return Ok(Some(Token { tok, at: at(end) }));
        }
    }

    /// The file `name` names: relative to the directory of the file `at` is in, or, when
    /// nothing is there, to the top-level file's (pbrt-v4 resolves every name against the
    /// directory of the scene it was given, which is the same for files in that
    /// directory).
    pub fn resolve(&self, at: &At, name: &str) -> PathBuf {
        let dir_of = |f: usize| {
            self.files[f]
                .path
                .parent()
                .unwrap_or(Path::new(""))
                .to_path_buf()
        };
        let here = dir_of(at.file).join(name);
        if at.file == 0 || here.exists() {
            return here;
        }
        let top = dir_of(0).join(name);
        if top.exists() {
            top
        } else {
            here
        }
    }
}
