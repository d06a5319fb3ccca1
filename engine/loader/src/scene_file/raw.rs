//! A TOML document as a tree in which every value and key carries its byte span.
//!
//! Why not `toml::Value` or `toml::Spanned<toml::Value>`: `toml::Value` has no spans, and
//! `toml::Spanned<T>` fails outright on *implicit* tables (e.g. `materials` in
//! `[materials.white]`, or `a` in the dotted key `a.b = 1`), because toml 0.8 has no span
//! for them and `Spanned`'s visitor then sees a plain map. [`Node`] speaks the same serde
//! protocol as `toml::Spanned` (the struct name and field names below, shared by toml and
//! serde_spanned since toml 0.5) but falls back to an unspanned value when the deserializer
//! offers none; [`Node::fill_spans`] then gives such nodes the span of their contents. The
//! protocol is exercised by every located-error test, so a toml upgrade that changes it
//! fails loudly.

use std::fmt;
use std::ops::Range;

use serde::de::{Deserialize, Deserializer, Error as _, MapAccess, SeqAccess, Visitor};

/// `serde_spanned::Spanned`'s serde protocol (identical in toml 0.5 ... 0.8).
const SPANNED_NAME: &str = "$__serde_spanned_private_Spanned";
const SPANNED_START: &str = "$__serde_spanned_private_start";
const SPANNED_END: &str = "$__serde_spanned_private_end";
const SPANNED_VALUE: &str = "$__serde_spanned_private_value";
const SPANNED_FIELDS: &[&str] = &[SPANNED_START, SPANNED_END, SPANNED_VALUE];
/// toml's private encoding of a datetime (a one-entry map with this key).
const DATETIME_KEY: &str = "$__toml_private_datetime";

/// A TOML value.
#[derive(Clone, Debug)]
pub(crate) enum Value {
    String(String),
    Integer(i64),
    Float(f64),
    Boolean(bool),
    /// Kept only to report it as a wrong type.
    Datetime,
    Array(Vec<Node>),
    /// Entries in document order.
    Table(Vec<(Key, Node)>),
}

impl Value {
    /// The TOML type name, for "expected X, got Y" messages.
    pub(crate) fn type_name(&self) -> &'static str {
        match self {
            Value::String(_) => "a string",
            Value::Integer(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Boolean(_) => "a boolean",
            Value::Datetime => "a datetime",
            Value::Array(_) => "an array",
            Value::Table(_) => "a table",
        }
    }
}

/// A value and the byte range of its text in the document.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    pub(crate) span: Option<Range<usize>>,
    pub(crate) value: Value,
}

/// A table key and the byte range of its text (toml gives spans for header keys only;
/// [`Node::fill_spans`] uses the value's span for the others).
#[derive(Clone, Debug)]
pub(crate) struct Key {
    pub(crate) span: Option<Range<usize>>,
    pub(crate) name: String,
}

impl Node {
    fn bare(value: Value) -> Node {
        Node { span: None, value }
    }

    /// The span, which [`Node::fill_spans`] guarantees to exist.
    pub(crate) fn span(&self) -> Range<usize> {
        self.span.clone().unwrap_or(0..0)
    }

    /// The entries if this is a table.
    pub(crate) fn as_table(&self) -> Option<&[(Key, Node)]> {
        match &self.value {
            Value::Table(t) => Some(t),
            _ => None,
        }
    }

    /// Looks a key up in a table (first occurrence; TOML forbids duplicates anyway).
    pub(crate) fn get(&self, key: &str) -> Option<(&Key, &Node)> {
        self.as_table()?
            .iter()
            .find(|(k, _)| k.name == key)
            .map(|(k, v)| (k, v))
    }

    /// Gives every node and key without a span one: a container gets the hull of its
    /// children's spans, anything else (an empty implicit table) its parent's span; a key
    /// without a span gets its value's.
    pub(crate) fn fill_spans(&mut self, parent: Range<usize>) {
        let own = self.span.clone();
        let fallback = own.clone().unwrap_or(parent);
        let mut hull: Option<Range<usize>> = None;
        let mut widen = |r: &Range<usize>| {
            hull = Some(match hull.take() {
                None => r.clone(),
                Some(h) => h.start.min(r.start)..h.end.max(r.end),
            });
        };
        match &mut self.value {
            Value::Array(items) => {
                for item in items.iter_mut() {
                    item.fill_spans(fallback.clone());
                    widen(&item.span());
                }
            }
            Value::Table(entries) => {
                for (key, item) in entries.iter_mut() {
                    item.fill_spans(key.span.clone().unwrap_or(fallback.clone()));
                    if key.span.is_none() {
                        key.span = item.span.clone();
                    }
                    if let Some(k) = &key.span {
                        widen(k);
                    }
                    widen(&item.span());
                }
            }
            _ => {}
        }
        if self.span.is_none() {
            self.span = Some(hull.unwrap_or(fallback));
        }
    }
}

struct NodeVisitor;

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a TOML value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Node, E> {
        Ok(Node::bare(Value::Boolean(v)))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Node, E> {
        Ok(Node::bare(Value::Integer(v)))
    }
    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Node, E> {
        i64::try_from(v)
            .map(|v| Node::bare(Value::Integer(v)))
            .map_err(|_| E::custom("integer out of range"))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Node, E> {
        Ok(Node::bare(Value::Float(v)))
    }
    fn visit_str<E>(self, v: &str) -> Result<Node, E> {
        Ok(Node::bare(Value::String(v.to_owned())))
    }
    fn visit_string<E>(self, v: String) -> Result<Node, E> {
        Ok(Node::bare(Value::String(v)))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element::<Node>()? {
            items.push(item);
        }
        Ok(Node::bare(Value::Array(items)))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
        let Some(first) = map.next_key::<Key>()? else {
            return Ok(Node::bare(Value::Table(Vec::new())));
        };
        if first.name == SPANNED_START {
            // The spanned protocol: start, end, then the value itself. The value must be
            // read with `deserialize_any` (`Unspanned`): asking for a span again would
            // recurse forever on the same table.
            let start: usize = map.next_value()?;
            let end = match map.next_key::<Key>()? {
                Some(k) if k.name == SPANNED_END => map.next_value::<usize>()?,
                _ => return Err(A::Error::custom("malformed spanned value")),
            };
            let Unspanned(mut node) = match map.next_key::<Key>()? {
                Some(k) if k.name == SPANNED_VALUE => map.next_value::<Unspanned>()?,
                _ => return Err(A::Error::custom("malformed spanned value")),
            };
            node.span = Some(start..end.max(start));
            return Ok(node);
        }
        if first.name == DATETIME_KEY {
            let _text: String = map.next_value()?;
            return Ok(Node::bare(Value::Datetime));
        }
        let mut entries = vec![(first, map.next_value::<Node>()?)];
        while let Some(key) = map.next_key::<Key>()? {
            let value = map.next_value::<Node>()?;
            entries.push((key, value));
        }
        Ok(Node::bare(Value::Table(entries)))
    }
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Node, D::Error> {
        d.deserialize_struct(SPANNED_NAME, SPANNED_FIELDS, NodeVisitor)
    }
}

/// A node read without asking for its span (the inner value of a spanned value).
struct Unspanned(Node);

impl<'de> Deserialize<'de> for Unspanned {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Unspanned, D::Error> {
        d.deserialize_any(NodeVisitor).map(Unspanned)
    }
}

struct KeyVisitor;

impl<'de> Visitor<'de> for KeyVisitor {
    type Value = Key;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a TOML key")
    }
    fn visit_str<E>(self, v: &str) -> Result<Key, E> {
        Ok(Key {
            span: None,
            name: v.to_owned(),
        })
    }
    fn visit_string<E>(self, v: String) -> Result<Key, E> {
        Ok(Key {
            span: None,
            name: v,
        })
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Key, A::Error> {
        let mut start = None;
        let mut end = None;
        let mut name = None;
        while let Some(field) = map.next_key::<String>()? {
            match field.as_str() {
                SPANNED_START => start = Some(map.next_value::<usize>()?),
                SPANNED_END => end = Some(map.next_value::<usize>()?),
                SPANNED_VALUE => name = Some(map.next_value::<String>()?),
                _ => return Err(A::Error::custom("malformed spanned key")),
            }
        }
        match (start, end, name) {
            (Some(s), Some(e), Some(name)) => Ok(Key {
                span: Some(s..e.max(s)),
                name,
            }),
            _ => Err(A::Error::custom("malformed spanned key")),
        }
    }
}

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Key, D::Error> {
        d.deserialize_struct(SPANNED_NAME, SPANNED_FIELDS, KeyVisitor)
    }
}

/// Parses a TOML document into a fully spanned tree (root span = the whole text), or
/// returns toml's syntax error (message and byte span).
pub(crate) fn parse_document(text: &str) -> Result<Node, toml::de::Error> {
    // The root table: `deserialize_any` so the whole document is the root's span.
    let Unspanned(mut root) = toml::from_str::<Unspanned>(text)?;
    root.span = Some(0..text.len());
    root.fill_spans(0..text.len());
    Ok(root)
}
