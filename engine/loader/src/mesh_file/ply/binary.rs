//! Binary PLY bodies (little and big endian) decoded straight from the header's layout.
//!
//! `ply-rs-bw` reads an element by looking each property up by name and handing it over as
//! an enum (`Property`), with a list allocated per element; on a 2-million-triangle mesh that
//! was most of the load (issue 36's "serial stretches": 0.47-0.56 s before this decoder,
//! 0.32-0.42 s with it, `benches/README.md`). Here the header is
//! still `ply-rs-bw`'s, but each property's place in the element, its type and the record
//! field it fills are worked out once ([`ElementLayout`]); an element is then read from the
//! buffered file's bytes in place, with no lookup and no allocation. The values are the ones
//! the generic path makes (every scalar type widened to `f64` exactly, lists to `i64`), so a
//! file loads to the same mesh either way (the `tests` module compares them on every type).

use std::io::{BufRead, ErrorKind};

use ply_rs_bw::ply::{ElementDef, PropertyType, ScalarType};

use super::{scalar_size, vertex_slot};

/// The byte order of a binary body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ByteOrder {
    Little,
    Big,
}

/// Where a property's value goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    /// [`super::VertexRecord`]'s `values` entry (x, y, z, nx, ny, nz, then the texture
    /// names' pairs).
    Vertex(usize),
    /// The face's index list (under the name the loader chose).
    Indices,
    /// Read past.
    Ignored,
}

/// One property of an element: its type and the field it fills.
#[derive(Clone, Debug)]
struct Field {
    data: PropertyType,
    slot: Slot,
}

/// A scalar of a list-free element that fills a vertex value.
#[derive(Clone, Debug)]
struct VertexScalar {
    data: ScalarType,
    /// Its byte offset in the element.
    offset: usize,
    /// Its [`super::VertexRecord`]'s `values` entry.
    slot: usize,
}

/// The properties of one element in file order, with where each goes.
pub(super) struct ElementLayout {
    /// The face list the mesh takes (the `face` element's; `None` elsewhere).
    pub(super) index_name: Option<&'static str>,
    fields: Vec<Field>,
    /// The element's size in bytes when it has no list.
    fixed: Option<usize>,
    /// When `fixed`: the scalars that fill vertex values (the rest is read past).
    vertex_scalars: Vec<VertexScalar>,
    /// When `fixed`: the index list's name is taken by a scalar.
    scalar_in_index_slot: bool,
}

impl ElementLayout {
    /// The layout of `def`; `index_name` is the face list the mesh takes (for the `face`
    /// element; `None` elsewhere).
    pub(super) fn of(def: &ElementDef, index_name: Option<&'static str>) -> Self {
        let vertex = def.name == "vertex";
        let mut layout = ElementLayout {
            index_name,
            fields: Vec::with_capacity(def.properties.len()),
            fixed: Some(0),
            vertex_scalars: Vec::new(),
            scalar_in_index_slot: false,
        };
        for p in def.properties.values() {
            let slot = if vertex {
                vertex_slot(&p.name).map_or(Slot::Ignored, Slot::Vertex)
            } else if Some(p.name.as_str()) == index_name {
                Slot::Indices
            } else {
                Slot::Ignored
            };
            match (&p.data_type, layout.fixed) {
                (PropertyType::Scalar(s), Some(offset)) => {
                    if let Slot::Vertex(slot) = slot {
                        let (data, offset) = (s.clone(), offset);
                        layout
                            .vertex_scalars
                            .push(VertexScalar { data, offset, slot });
                    }
                    layout.scalar_in_index_slot |= slot == Slot::Indices;
                    layout.fixed = Some(offset + scalar_size(s));
                }
                (PropertyType::List(..), _) => layout.fixed = None,
                (PropertyType::Scalar(_), None) => {}
            }
            let data = p.data_type.clone();
            layout.fields.push(Field { data, slot });
        }
        layout
    }
}

/// Reads a binary body element by element.
pub(super) struct BinaryDecoder {
    order: ByteOrder,
    /// An element (or a list) that straddles the reader's buffer, copied out whole.
    straddling: Vec<u8>,
}

/// One element as the mesh sees it.
pub(super) struct Element {
    /// [`super::VertexRecord`]'s `values`: NaN where the element has no such scalar.
    pub(super) values: [f64; 12],
    /// The index list (empty where there is none).
    pub(super) indices: Vec<i64>,
    /// False when the index slot holds no integer list (a scalar or a float list).
    pub(super) integer_list: bool,
}

impl Element {
    pub(super) fn new() -> Self {
        Element {
            values: [f64::NAN; 12],
            indices: Vec::new(),
            integer_list: true,
        }
    }
}

/// Why an element could not be read: the file ends before it or inside it.
fn ends(started: bool) -> String {
    if started {
        "the file ends inside it".into()
    } else {
        "the file ends before it".into()
    }
}

impl BinaryDecoder {
    pub(super) fn new(order: ByteOrder) -> Self {
        BinaryDecoder {
            order,
            straddling: Vec::new(),
        }
    }

    /// Reads `count` elements laid out as `layout` from `reader`, handing each to `f` with
    /// its number. Elements are decoded where they lie in the reader's buffer; one that
    /// straddles its end is gathered in `straddling` first. A read error is returned as
    /// `cannot(number, reason)`.
    pub(super) fn for_each(
        &mut self,
        reader: &mut impl BufRead,
        layout: &ElementLayout,
        count: usize,
        cannot: impl Fn(usize, String) -> String,
        mut f: impl FnMut(usize, &Element) -> Result<(), String>,
    ) -> Result<(), String> {
        let mut element = Element::new();
        let mut i = 0;
        while i < count {
            let buf = reader
                .fill_buf()
                .map_err(|e| cannot(i, io_error(e, false)))?;
            let mut at = 0;
            while i < count {
                match self.decode_element(&buf[at..], layout, &mut element) {
                    Ok(Some(n)) => at += n,
                    Ok(None) => break,
                    Err(e) => return Err(cannot(i, e)),
                }
                f(i, &element)?;
                i += 1;
            }
            reader.consume(at);
            if i < count {
                self.straddle(reader, layout, &mut element)
                    .map_err(|e| cannot(i, e))?;
                f(i, &element)?;
                i += 1;
            }
        }
        Ok(())
    }

    /// The element that starts at what is left of `reader`'s buffer and ends beyond it,
    /// gathered buffer by buffer into `straddling` until it decodes.
    fn straddle(
        &mut self,
        reader: &mut impl BufRead,
        layout: &ElementLayout,
        element: &mut Element,
    ) -> Result<(), String> {
        let mut gathered = std::mem::take(&mut self.straddling);
        gathered.clear();
        let result = loop {
            let buf = match reader.fill_buf() {
                Ok(buf) => buf,
                Err(e) => break Err(io_error(e, !gathered.is_empty())),
            };
            if buf.is_empty() {
                break Err(ends(!gathered.is_empty()));
            }
            // A piece as long as what is gathered (at least 64 bytes): an element costs
            // copies of about its own size, not of the reader's whole buffer.
            let old = gathered.len();
            let take = buf.len().min(old.max(64));
            gathered.extend_from_slice(&buf[..take]);
            match self.decode_element(&gathered, layout, element) {
                // The element needed more than the `old` bytes that did not decode.
                Ok(Some(n)) => {
                    reader.consume(n - old);
                    break Ok(());
                }
                Ok(None) => reader.consume(take),
                Err(e) => break Err(e),
            }
        };
        self.straddling = gathered;
        result
    }

    /// Decodes the element at the start of `b` into `element`: `Ok(Some(bytes it took))`,
    /// or `Ok(None)` when `b` ends before it does.
    #[inline]
    fn decode_element(
        &self,
        b: &[u8],
        layout: &ElementLayout,
        element: &mut Element,
    ) -> Result<Option<usize>, String> {
        let order = self.order;
        if let Some(size) = layout.fixed {
            // No list: each vertex scalar at its offset.
            if b.len() < size {
                return Ok(None);
            }
            for s in &layout.vertex_scalars {
                element.values[s.slot] = decode(&s.data, &b[s.offset..], order);
            }
            element.integer_list = !layout.scalar_in_index_slot;
            return Ok(Some(size));
        }
        element.indices.clear();
        element.integer_list = true;
        let mut at = 0;
        for field in &layout.fields {
            match &field.data {
                PropertyType::Scalar(s) => {
                    let n = scalar_size(s);
                    let Some(v) = b.get(at..at + n) else {
                        return Ok(None);
                    };
                    match field.slot {
                        Slot::Vertex(k) => element.values[k] = decode(s, v, order),
                        // A scalar where the index list should be.
                        Slot::Indices => element.integer_list = false,
                        Slot::Ignored => {}
                    }
                    at += n;
                }
                PropertyType::List(count_type, item) => {
                    let n = scalar_size(count_type);
                    let Some(v) = b.get(at..at + n) else {
                        return Ok(None);
                    };
                    at += n;
                    let count = list_length(decode(count_type, v, order), count_type)?;
                    let size = scalar_size(item);
                    let end = count.checked_mul(size).and_then(|n| at.checked_add(n));
                    let Some(items) = end.and_then(|end| b.get(at..end)) else {
                        return Ok(None);
                    };
                    at += items.len();
                    let is_integer = !matches!(item, ScalarType::Float | ScalarType::Double);
                    match field.slot {
                        Slot::Indices if is_integer => {
                            extend_ints(&mut element.indices, items, item, order)
                        }
                        Slot::Indices => element.integer_list = false,
                        // A list where a vertex scalar should be: NaN, as the ascii path.
                        Slot::Vertex(k) => element.values[k] = f64::NAN,
                        Slot::Ignored => {}
                    }
                }
            }
        }
        Ok(Some(at))
    }
}

/// A list's length from its count property, which must be a non-negative integer.
fn list_length(count: f64, count_type: &ScalarType) -> Result<usize, String> {
    if matches!(count_type, ScalarType::Float | ScalarType::Double) {
        return Err(format!(
            "a list's length is a {count_type:?}, not an integer"
        ));
    }
    if count < 0.0 {
        return Err(format!("a list has a negative length ({count})"));
    }
    Ok(count as usize)
}

fn io_error(e: std::io::Error, started: bool) -> String {
    if e.kind() == ErrorKind::UnexpectedEof {
        ends(started)
    } else {
        e.to_string()
    }
}

/// `N` bytes of `b` in `order` as an array for `from_le_bytes` / `from_be_bytes`.
#[inline(always)]
fn array<const N: usize>(b: &[u8], order: ByteOrder) -> [u8; N] {
    let mut a: [u8; N] = b[..N].try_into().expect("N bytes");
    if order == ByteOrder::Big {
        a.reverse();
    }
    a
}

/// A scalar of type `s` as `f64` (exact for every PLY type).
#[inline(always)]
fn decode(s: &ScalarType, b: &[u8], order: ByteOrder) -> f64 {
    match s {
        ScalarType::Float => f64::from(f32::from_le_bytes(array(b, order))),
        ScalarType::Double => f64::from_le_bytes(array(b, order)),
        _ => decode_int(s, b, order) as f64,
    }
}

/// Appends the integers of type `item` in `items` to `out`, with the type's match outside
/// the loop for the usual 32-bit little-endian indices.
#[inline(always)]
fn extend_ints(out: &mut Vec<i64>, items: &[u8], item: &ScalarType, order: ByteOrder) {
    let words = items
        .chunks_exact(4)
        .map(|c| <[u8; 4]>::try_from(c).expect("4 bytes"));
    match (item, order) {
        (ScalarType::Int, ByteOrder::Little) => {
            out.extend(words.map(|w| i64::from(i32::from_le_bytes(w))))
        }
        (ScalarType::UInt, ByteOrder::Little) => {
            out.extend(words.map(|w| i64::from(u32::from_le_bytes(w))))
        }
        _ => {
            let size = scalar_size(item);
            out.extend(items.chunks_exact(size).map(|c| decode_int(item, c, order)))
        }
    }
}

/// An integer scalar of type `s` as `i64` (0 for the float types, which callers exclude).
#[inline(always)]
fn decode_int(s: &ScalarType, b: &[u8], order: ByteOrder) -> i64 {
    match s {
        ScalarType::Char => i64::from(b[0] as i8),
        ScalarType::UChar => i64::from(b[0]),
        ScalarType::Short => i64::from(i16::from_le_bytes(array(b, order))),
        ScalarType::UShort => i64::from(u16::from_le_bytes(array(b, order))),
        ScalarType::Int => i64::from(i32::from_le_bytes(array(b, order))),
        ScalarType::UInt => i64::from(u32::from_le_bytes(array(b, order))),
        ScalarType::Float | ScalarType::Double => 0,
    }
}

#[cfg(test)]
mod tests;
