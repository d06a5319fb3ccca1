//! `type = "disk"`: area under transforms, orientation under mirroring, texture
//! coordinates, located errors.

use super::*;

/// A scene with one disk shape of the given extra keys.
fn disk_scene(keys: &str) -> String {
    format!(
        "[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n\n[materials.m]\ntype = \
         \"diffuse\"\n\n[[shapes]]\nname = \"d\"\ntype = \"disk\"\nmaterial = \"m\"\n{keys}\n"
    )
}

fn triangles(s: &SceneDesc) -> &[[Vec3; 3]] {
    match &s.shapes[0].geometry {
        ShapeGeometry::Triangles { kind, triangles } => {
            assert_eq!(*kind, "disk");
            triangles
        }
        other => panic!("not triangles: {other:?}"),
    }
}

/// Sum of the world-space triangle areas against `pi (R^2 - ri^2) sx sy` (the disk's area
/// under a scale of `sx`, `sy` in its plane), to the tessellation's 1e-4.
#[test]
fn disk_area_follows_radius_inner_radius_and_scale() {
    let cases = [
        ("", 1.0, 0.0, 1.0, 1.0),
        ("radius = 2", 2.0, 0.0, 1.0, 1.0),
        ("inner_radius = 0.5", 1.0, 0.5, 1.0, 1.0),
        (
            "radius = 0.5\ninner_radius = 0.1\ntransform = [{ scale = [3, 2, 7] }, { rotate = \
             { axis = [1, 1, 0], angle = 40 } }, { translate = [1, 2, 3] }]",
            0.5,
            0.1,
            3.0,
            2.0,
        ),
    ];
    for (keys, radius, inner, sx, sy) in cases {
        let s = parse(&disk_scene(keys)).unwrap();
        let area: f64 = triangles(&s)
            .iter()
            .map(|[a, b, c]| 0.5 * f64::from((*b - *a).cross(*c - *a).length()))
            .sum();
        let exact = std::f64::consts::PI * (radius * radius - inner * inner) * sx * sy;
        let error = (area - exact).abs() / exact;
        assert!(error < 1e-4, "{keys}: area {area} vs {exact} ({error:e})");
        // And not by luck: the tessellation is a polygon, slightly inside the circle.
        assert!(area < exact, "{keys}");
    }
}

/// The geometric normal of every triangle is the transformed plane normal (the inverse
/// transpose of the transform applied to +z), also under mirroring transforms, which swap
/// the winding; the texture coordinates are swapped with the vertices.
#[test]
fn disk_normals_follow_mirroring_transforms() {
    for (transform, normal) in [
        ("[]", Vec3::Z),
        ("[{ scale = [1, 1, -1] }]", -Vec3::Z),
        ("[{ scale = [-1, 1, 1] }]", Vec3::Z),
        ("[{ rotate = { axis = [1, 0, 0], angle = -90 } }]", Vec3::Y),
        (
            "[{ scale = [1, -2, 1] }, { rotate = { axis = [1, 0, 0], angle = -90 } }]",
            Vec3::Y,
        ),
    ] {
        let s = parse(&disk_scene(&format!("transform = {transform}"))).unwrap();
        let tris = triangles(&s);
        assert_eq!(tris.len(), 1520);
        for [a, b, c] in tris {
            let n = (*b - *a).cross(*c - *a).normalize();
            assert!(
                (n - normal).length() < 1e-4,
                "{transform}: normal {n}, want {normal}"
            );
        }
        let attrs = &s.shapes[0].attributes;
        assert!(
            attrs.normals.is_empty(),
            "the plane's normal, not vertex normals"
        );
        assert_eq!(attrs.corners.len(), tris.len());
        // Each corner's uv is the polar coordinate of its world vertex mapped back to the
        // object disk: u = r, v = phi / 2 pi (v = 1 allowed at the seam).
        let inverse = s.shapes[0].transform.inverse();
        for (t, corners) in tris.iter().zip(&attrs.corners) {
            for (p, &k) in t.iter().zip(corners) {
                let q = inverse.transform_point3(*p);
                let uv = attrs.uvs[k as usize];
                assert!(
                    (q.truncate().length() - uv.x).abs() < 1e-4,
                    "{transform}: u"
                );
                if uv.x > 0.0 {
                    let phi = q.y.atan2(q.x).rem_euclid(std::f32::consts::TAU);
                    let d = (uv.y - phi / std::f32::consts::TAU).abs();
                    assert!(d < 1e-4 || (d - 1.0).abs() < 1e-4, "{transform}: v");
                }
            }
        }
    }
}

#[test]
fn bad_disks_are_located_errors() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "inner_radius = 1",
            "inner_radius",
            &[
                "shapes[0] \"d\"",
                "inner_radius",
                "`1`",
                "below the radius (1)",
            ],
        ),
        (
            "radius = 0.5\ninner_radius = 0.7",
            "inner_radius",
            &["inner_radius", "`0.7`", "below the radius (0.5)"],
        ),
        (
            "inner_radius = -0.1",
            "inner_radius",
            &["inner_radius", "`-0.1`", ">= 0"],
        ),
        ("radius = 0", "radius", &["radius", "`0`", "> 0"]),
        ("center = [0, 0, 0]", "center", &["center"]),
        (
            "transform = [{ scale = [1, 1, 0] }]",
            "transform",
            &["transform", "singular"],
        ),
    ];
    for (keys, at, fragments) in cases {
        let text = disk_scene(keys);
        let e = parse_err(&text);
        assert_message(&e, line_of(&text, at), fragments);
    }
    // A disk has no inside for the camera to be in.
    let text = disk_scene("") + "";
    let text = text.replace("to = [0, 0, 0]\n", "to = [0, 0, 0]\ninside = [\"d\"]\n");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "inside"),
        &["`d` is a disk, which has no inside"],
    );
}
