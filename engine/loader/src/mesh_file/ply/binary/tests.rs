use super::super::load_ply;
use super::super::tests::write;
use super::*;
use std::io::BufReader;

/// One value of a property in a body of `format`: ascii text or bytes in the byte order.
fn value(format: &str, ty: &str, v: f64) -> Vec<u8> {
    let big = format == "binary_big_endian";
    macro_rules! bytes {
        ($t:ty) => {{
            let x = v as $t;
            if big {
                x.to_be_bytes().to_vec()
            } else {
                x.to_le_bytes().to_vec()
            }
        }};
    }
    if format == "ascii" {
        return format!("{v} ").into_bytes();
    }
    match ty {
        "char" => bytes!(i8),
        "uchar" => bytes!(u8),
        "short" => bytes!(i16),
        "ushort" => bytes!(u16),
        "int" => bytes!(i32),
        "uint" => bytes!(u32),
        "float" => bytes!(f32),
        "double" => bytes!(f64),
        _ => unreachable!("{ty}"),
    }
}

/// A mesh with every PLY type somewhere: positions as `float`, `double` and `short`, normals,
/// `texture_u, texture_v`, unused scalars and a list before and after the used ones, a quad
/// and a triangle with an `int` count and `ushort` indices, and an element after the faces
/// with a list of its own.
fn mesh_file(format: &str) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat {format} 1.0\nelement vertex 4\nproperty uchar red\nproperty float x\n\
         property double y\nproperty short z\nproperty list uchar float weights\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty float texture_u\n\
         property double texture_v\nproperty char flag\nelement face 2\nproperty uint id\n\
         property list int ushort vertex_indices\nproperty list uchar char tags\n\
         element edge 1\nproperty list uchar uint ends\nend_header\n"
    )
    .into_bytes();
    let positions = [
        [0.5, -1.25, 3.0],
        [1.0, 0.0, -2.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 7.0],
    ];
    for (i, p) in positions.iter().enumerate() {
        let i = i as f64;
        b.extend(value(format, "uchar", 200.0 + i));
        b.extend(value(format, "float", p[0]));
        b.extend(value(format, "double", p[1]));
        b.extend(value(format, "short", p[2]));
        b.extend(value(format, "uchar", 2.0));
        b.extend(value(format, "float", 0.25));
        b.extend(value(format, "float", -4.0));
        for n in [0.0, 0.6, 0.8] {
            b.extend(value(format, "float", n));
        }
        b.extend(value(format, "float", 0.125 * i));
        b.extend(value(format, "double", 1.0 - 0.1 * i));
        b.extend(value(format, "char", -3.0));
        if format == "ascii" {
            b.push(b'\n');
        }
    }
    for (id, face) in [(7.0, vec![0.0, 1.0, 2.0, 3.0]), (9.0, vec![3.0, 2.0, 1.0])] {
        b.extend(value(format, "uint", id));
        b.extend(value(format, "int", face.len() as f64));
        for i in face {
            b.extend(value(format, "ushort", i));
        }
        b.extend(value(format, "uchar", 1.0));
        b.extend(value(format, "char", -100.0));
        if format == "ascii" {
            b.push(b'\n');
        }
    }
    b.extend(value(format, "uchar", 2.0));
    b.extend(value(format, "uint", 0.0));
    b.extend(value(format, "uint", 3.0));
    b
}

/// The binary decoder gives, in either byte order, the mesh `ply-rs-bw` parses from the
/// same file in ascii.
#[test]
fn binary_bodies_load_as_their_ascii_twin() {
    let ascii = load_ply(&write("twin-ascii.ply", &mesh_file("ascii"))).unwrap();
    assert_eq!(ascii.positions[0], glam::DVec3::new(0.5, -1.25, 3.0));
    assert_eq!(ascii.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
    assert_eq!(ascii.normals.len(), 4);
    assert_eq!(ascii.uvs[3], glam::Vec2::new(0.375, 0.7));
    for format in ["binary_little_endian", "binary_big_endian"] {
        let binary = load_ply(&write(&format!("twin-{format}.ply"), &mesh_file(format))).unwrap();
        assert_eq!(binary.positions, ascii.positions, "{format}");
        assert_eq!(binary.normals, ascii.normals, "{format}");
        assert_eq!(binary.uvs, ascii.uvs, "{format}");
        assert_eq!(binary.triangles, ascii.triangles, "{format}");
    }
}

/// Every element read through buffers of every size from 1 byte to past the body (so that
/// elements straddle the buffer's end at every offset) is the element read in one piece.
#[test]
fn elements_straddling_the_buffer_decode_whole() {
    let file = mesh_file("binary_little_endian");
    let body_at = file.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let body = &file[body_at..];
    let header = {
        let mut reader = ply_rs_bw::parser::Reader::new(BufReader::new(&file[..]));
        ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new()
            .read_header(&mut reader)
            .unwrap()
    };
    let read_all = |capacity: usize| {
        let mut reader = BufReader::with_capacity(capacity, body);
        let mut decoder = BinaryDecoder::new(ByteOrder::Little);
        let mut seen = Vec::new();
        for (name, def) in &header.elements {
            let layout = ElementLayout::of(def, (name == "face").then_some("vertex_indices"));
            let cannot = |i: usize, e: String| format!("{name} {i}: {e}");
            decoder
                .for_each(&mut reader, &layout, def.count, cannot, |i, e| {
                    let values = e.values.map(f64::to_bits);
                    seen.push((name.clone(), i, values, e.indices.clone(), e.integer_list));
                    Ok(())
                })
                .unwrap();
        }
        assert!(
            reader.fill_buf().unwrap().is_empty(),
            "the whole body is read"
        );
        seen
    };
    let whole = read_all(1 << 16);
    assert_eq!(whole.len(), 4 + 2 + 1);
    assert_eq!(whole[4].3, vec![0, 1, 2, 3]);
    for capacity in 1..body.len() + 2 {
        assert_eq!(read_all(capacity), whole, "buffer of {capacity} bytes");
    }
}

/// A body cut short, a list of negative length and a list whose length is a float are errors
/// naming the file, the element and the value.
#[test]
fn bad_binary_bodies_are_errors() {
    let file = mesh_file("binary_little_endian");
    // Cut inside the second face (the edge's 9 bytes and 3 of the face's end removed).
    let cut = &file[..file.len() - 12];
    let e = load_ply(&write("cut.ply", cut)).unwrap_err();
    assert!(
        e.contains("cut.ply") && e.contains("`face` element 1 (of 2): the file ends inside it"),
        "{e}"
    );
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                property float y\nproperty float z\nelement face 1\n";
    let mut negative =
        format!("{head}property list char int vertex_indices\nend_header\n").into_bytes();
    negative.extend([0u8; 36]);
    negative.extend([0xff, 0, 0, 0, 0]);
    negative.extend([0u8; 8]);
    let e = load_ply(&write("negative.ply", &negative)).unwrap_err();
    assert!(
        e.contains("negative.ply")
            && e.contains("`face` element 0 (of 1): a list has a negative length (-1)"),
        "{e}"
    );
    let mut float_count =
        format!("{head}property list float int vertex_indices\nend_header\n").into_bytes();
    float_count.extend([0u8; 36]);
    float_count.extend(3f32.to_le_bytes());
    float_count.extend([0u8; 12]);
    let e = load_ply(&write("float_count.ply", &float_count)).unwrap_err();
    assert!(
        e.contains("`face` element 0 (of 1): a list's length is a Float"),
        "{e}"
    );
}
