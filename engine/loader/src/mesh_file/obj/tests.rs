//! The OBJ reader against hand-checked meshes and errors (each case was also read by tobj
//! 4.0.5, the reader this one replaced: the same mesh or a rejection, except for `l 1 2 3`,
//! a polyline tobj made a triangle of).

use glam::{DVec3, Vec2};

use super::{load_obj, load_obj_in_blocks};
use crate::mesh_file::MeshData;

/// `text` written to a scratch file and read; also read a line at a time and in blocks of
/// 16 bytes (the lines parsed in parallel per block, then applied in order), which must
/// give the same mesh or the same error.
fn read(name: &str, text: &str) -> Result<MeshData, String> {
    let dir = std::env::temp_dir().join(format!("risotto-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, text).unwrap();
    let whole = load_obj(&path);
    for block_bytes in [1, 16] {
        assert_eq!(
            load_obj_in_blocks(&path, block_bytes),
            whole,
            "{name} in blocks of {block_bytes} bytes"
        );
    }
    whole
}

/// A corner names a position before its `v` line (checked at the object's end, as tobj
/// did) and relative indices count back from the entries read so far; a position used
/// with two texture coordinates is two vertices, in order of first use.
#[test]
fn forward_relative_and_seam_corners_make_vertices_in_first_use_order() {
    let m = read(
        "seam",
        "v 0 0 0\nv 1 0 0\nvt 0 0\nvt 1 0\nf 1/1 2/2 3/1\nv 0 1 0\nf -1/-2 -3/-1 -2/-2\n",
    )
    .unwrap();
    let p = |x, y| DVec3::new(x, y, 0.0);
    assert_eq!(
        m.positions,
        [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(0.0, 1.0),
            p(0.0, 0.0),
            p(1.0, 0.0)
        ]
    );
    let (a, b) = (Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0));
    assert_eq!(m.uvs, [a, b, a, b, a]);
    assert_eq!(m.triangles, [[0, 1, 2], [2, 3, 4]]);
    assert!(m.normals.is_empty());
}

/// Polygons are fans from their first corner; `v x y z w` is divided by `w`; each object
/// (`o`, `g`) has its own vertices; faces of one or two corners, `p` and `l` are skipped.
#[test]
fn fans_weights_objects_and_skipped_statements() {
    let m = read(
        "fan",
        "v 0 0 0 2\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0 0\nvn 0 0 1\n\
         f 1//1 2//1 3//1 4//1 5//1\nf 1 2\np 1\nl 1 2 3\no second\nf 1//1 2//1 3//1\n",
    )
    .unwrap();
    assert_eq!(m.positions.len(), 8);
    assert_eq!(m.positions[0], DVec3::ZERO);
    assert_eq!(m.positions[5], DVec3::ZERO);
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 6, 7]]);
    assert_eq!(m.normals, vec![DVec3::Z; 8]);
    assert_eq!((m.skipped.points, m.skipped.lines), (1, 1));
    let half = read("half", "v 2 4 6 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(half.positions[0], DVec3::new(1.0, 2.0, 3.0));
}

/// Malformed statements and bad indices are errors naming the line and its text (or the
/// face corner); problems with an object's vertices name the vertex or the object.
#[test]
fn errors_name_the_line_and_the_value() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: [(&str, String, &str); 16] = [
        (
            "short",
            "v 1 2\n".to_owned(),
            "line 1: a position needs three numbers in `v 1 2`",
        ),
        (
            "zero_w",
            "v 0 0 0 0\n".to_owned(),
            "line 1: the weight `w` is 0",
        ),
        (
            "two_extra",
            "v 0 0 0 1 1\n".to_owned(),
            "line 1: a position is followed by",
        ),
        (
            "bad_vt",
            "vt 0\n".to_owned(),
            "line 1: a texture coordinate needs two numbers",
        ),
        (
            "no_corners",
            format!("{tri}f\n"),
            "line 4: a face has no corners in `f`",
        ),
        (
            "four_slots",
            format!("{tri}f 1/1/1/1 2 3\n"),
            "face corner `1/1/1/1` is not",
        ),
        (
            "letters",
            format!("{tri}f 1 2 x\n"),
            "face corner `x` is not",
        ),
        (
            "usemtl",
            format!("{tri}usemtl\n"),
            "line 4: `usemtl` names no material",
        ),
        (
            "v_range",
            format!("{tri}f 1 2 9\n"),
            "line 4: face corner `9` refers to v 9 but the file has 3",
        ),
        (
            "v_zero",
            format!("{tri}f 0 1 2\n"),
            "line 4: face corner `0` refers to v 0",
        ),
        (
            "v_range_at_o",
            format!("{tri}f 1 2 -7\no next\nf 1 2 3\n"),
            "line 4: face corner `-7` refers to v -7",
        ),
        (
            "vn_range",
            format!("{tri}vn 0 0 1\nf 1//1 2//1 3//2\n"),
            "line 5: face corner `3//2` refers to vn 2",
        ),
        (
            "some_normals",
            format!("{tri}vn 0 0 1\no part\nf 1//1 2//1 3\n"),
            "object `part` gives normals (`vn`) on some faces but not on others",
        ),
        (
            "not_finite",
            "v 0 0 0\nv 1 0 0\nv inf 1 0\nf 1 2 3\n".to_owned(),
            "vertex 3 is not finite",
        ),
        (
            "colour",
            "v 0 0 0 1 1 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_owned(),
            "a face uses a vertex without a colour",
        ),
        ("no_faces", format!("{tri}f 1 2\n"), "contains no faces"),
    ];
    for (name, text, want) in cases {
        let e = read(name, &text).expect_err(name);
        assert!(e.contains(&format!("{name}.obj")), "{name}: {e}");
        assert!(e.contains(want), "{name}: {e}");
    }
}

/// A byte-order mark, CRLF line ends and a Latin-1 comment (not UTF-8): the same mesh read
/// whole or a line at a time (the first line and lines that are not UTF-8 are left to the
/// in-order pass, the others parsed in parallel).
#[test]
fn byte_order_mark_crlf_and_latin1_comments_read_alike_in_any_block() {
    let dir = std::env::temp_dir().join(format!("risotto-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bom_crlf.obj");
    let mut bytes = b"\xef\xbb\xbfv 0 0 0\r\n# caf\xe9\r\nv 1 0 0\r\nv 0 1 0\r\n".to_vec();
    bytes.extend_from_slice(b"vn 0 0 1\r\nvt 0.5 0.25\r\nf 1/1/1 2/1/1 3/1/1\r\n");
    std::fs::write(&path, &bytes).unwrap();
    let whole = load_obj(&path).unwrap();
    assert_eq!(whole.positions.len(), 3);
    assert_eq!(whole.positions[1], DVec3::new(1.0, 0.0, 0.0));
    assert_eq!(whole.uvs, [Vec2::new(0.5, 0.25); 3]);
    assert_eq!(whole.normals, [DVec3::Z; 3]);
    for block_bytes in [1, 7, 1 << 20] {
        assert_eq!(load_obj_in_blocks(&path, block_bytes).unwrap(), whole);
    }
}
