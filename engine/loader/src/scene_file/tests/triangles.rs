//! The `triangles` shape: an indexed mesh written in the scene, checked as mesh files are.

use super::*;

/// A scene with one `triangles` shape whose body is `body`.
fn scene(body: &str) -> String {
    format!(
        "[camera]\nfrom = [0, 0, 5]\nto = [0, 0, 0]\nfov = 40\n\n[materials.m]\ntype = \"diffuse\"\n\n\
         [[shapes]]\ntype = \"triangles\"\nmaterial = \"m\"\n{body}\n"
    )
}

#[test]
fn triangles_are_placed_with_their_attributes() {
    let text = scene(
        "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0]\nindices = [0, 1, 2, 1, 3, 2]\n\
         normals = [0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1]\nuv = [0, 0, 1, 0, 0, 1, 1, 1]\n\
         transform = [{ translate = [0, 0, 2] }]",
    );
    let desc = parse(&text).unwrap();
    let tris = triangles(&desc.shapes[0]);
    assert_eq!(tris.len(), 2);
    assert_eq!(tris[1][1], Vec3::new(1.0, 1.0, 2.0));
    assert!(normal(&tris[0]).z > 0.0);
    let a = &desc.shapes[0].attributes;
    assert_eq!((a.normals.len(), a.uvs.len(), a.corners.len()), (4, 4, 2));
    // A mirror keeps the front: winding swapped, corners too.
    let text = scene(
        "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 2]\n\
         normals = [0, 0, 1, 0, 0, 1, 0, 0, 1]\ntransform = [{ scale = [-1, 1, 1] }]",
    );
    let desc = parse(&text).unwrap();
    assert!(normal(&triangles(&desc.shapes[0])[0]).z > 0.0);
    assert_eq!(desc.shapes[0].attributes.corners[0], [0, 2, 1]);
}

#[test]
fn bad_triangles_are_located_errors() {
    let cases = [
        (
            "positions = [0, 0, 0, 1, 0]\nindices = [0, 0, 0]",
            "positions",
            "multiple of 3",
        ),
        (
            "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 3]",
            "indices",
            "index 3 is not a vertex",
        ),
        (
            "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, -1]",
            "indices",
            "index -1",
        ),
        (
            "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 1.5]",
            "indices",
            "index 1.5",
        ),
        (
            "positions = [0, 0, nan, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 2]",
            "positions",
            "finite",
        ),
        (
            "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 2]\nnormals = [0, 0, 1]",
            "normals",
            "one normal per vertex",
        ),
        (
            "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 2]\nuv = [0, 0]",
            "uv",
            "one (u, v) pair",
        ),
        ("positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]", "type", "indices"),
        (
            "positions = \"many\"\nindices = [0, 1, 2]",
            "positions",
            "flat array",
        ),
        (
            "positions = [0, 0, 0, 1, 0, 0, 0, 1, 0]\nindices = [0, 1, 2]\nradius = 1",
            "radius",
            "radius",
        ),
    ];
    for (body, at, fragment) in cases {
        let text = scene(body);
        let e = parse_err(&text);
        let line = if at == "type" {
            line_of(&text, "[[shapes]]")
        } else {
            line_of(&text, at)
        };
        assert_message(&e, line, &[fragment]);
    }
}
