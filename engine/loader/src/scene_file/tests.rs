//! Tests of the scene file loader: located error messages for every kind of mistake,
//! robustness against garbage, transforms and geometry against independent values
//! (Mitsuba README coordinates, analytic shapes), and every scene in `scenes/`.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec2, Vec3};
use risotto_components::Rgb;

use super::*;

mod disk;
mod environment;
mod integrator;
mod objects;
mod pixel_filter;
mod shading_normals;
mod triangles;

/// The file name used for inline scenes (it must show up in every message).
const FILE: &str = "test-scenes/inline_scene.toml";

fn parse(text: &str) -> Result<SceneDesc, SceneError> {
    parse_scene(text, Path::new(FILE))
}

fn parse_err(text: &str) -> SceneError {
    match parse(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

/// 1-based line of the first occurrence of `needle` in `text` (found independently of the
/// loader's span bookkeeping).
fn line_of(text: &str, needle: &str) -> usize {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("`{needle}` not in the text"));
    text[..at].matches('\n').count() + 1
}

/// Asserts the message names the file, `file:LINE:`, and contains every fragment.
fn assert_message(e: &SceneError, line: usize, fragments: &[&str]) {
    let msg = e.to_string();
    let location = format!("{FILE}:{line}:");
    assert!(
        msg.contains(&location),
        "message lacks `{location}`:\n{msg}"
    );
    assert_eq!(e.line(), Some(line), "{msg}");
    for f in fragments {
        assert!(msg.contains(f), "message lacks `{f}`:\n{msg}");
    }
}

/// A scene using every section; small, valid.
const BASE: &str = r#"[render]
width = 64
height = 48
spp = 4

[materials.white]
type = "diffuse"
reflectance = [0.8, 0.8, 0.8]

[materials.glass]
type = "dielectric"
ior = 1.5
priority = 2
interior = { type = "beer", sigma_a = [0.1, 0.2, 0.3] }

[[shapes]]
name = "ball"
type = "sphere"
material = "glass"
center = [0, 1, 0]
radius = 1

[[shapes]]
name = "floor"
type = "quad"
material = "white"
corner = [-5, 0, -5]
edge1 = [0, 0, 10]
edge2 = [10, 0, 0]
emission = [0.1, 0.1, 0.1]

[[shapes]]
name = "crate"
type = "box"
material = "white"
transform = [{ scale = 0.5 }, { rotate = { axis = [0, 1, 0], angle = 30 } }, { translate = [2, 0.5, 0] }]

[[lights]]
name = "sun"
type = "distant"
direction = [0, -2, 0]
irradiance = [1, 1, 1]

[[lights]]
name = "bulb"
type = "point"
position = [0, 4, 0]
intensity = 10

[[lights]]
type = "environment"
radiance = [0.1, 0.2, 0.3]

[camera]
fov = 40
up = [0, 1, 0]
from = [0, 2, 6]
to = [0, 0.5, 0]
"#;

/// Replaces exactly one occurrence of `from` in `BASE`.
fn base_with(from: &str, to: &str) -> String {
    assert_eq!(
        BASE.matches(from).count(),
        1,
        "`{from}` must occur once in BASE"
    );
    BASE.replacen(from, to, 1)
}

/// Unit normal `(v1 - v0) x (v2 - v0)` of a triangle.
fn normal(t: &[Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize()
}

/// The world-space triangles of a shape (of a mesh, its triangles over its vertices).
fn triangles(shape: &ShapeDesc) -> Vec<[Vec3; 3]> {
    match &shape.geometry {
        ShapeGeometry::Sphere { .. } => panic!("{} is a sphere", shape.name),
        g => g.world_triangles(),
    }
}

fn shape<'a>(scene: &'a SceneDesc, name: &str) -> &'a ShapeDesc {
    scene
        .shapes
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no shape {name}"))
}

/// The distinct vertices of a triangle set (merged within 1e-5).
fn distinct_vertices(tris: &[[Vec3; 3]]) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::new();
    for v in tris.iter().flatten() {
        if !out.iter().any(|u| u.distance(*v) < 1e-5) {
            out.push(*v);
        }
    }
    out
}

/// Every point of `a` has a partner in `b` within `tol` and the counts agree.
fn same_point_set(a: &[Vec3], b: &[Vec3], tol: f32) -> bool {
    a.len() == b.len() && a.iter().all(|p| b.iter().any(|q| p.distance(*q) < tol))
}

/// Every triangle's normal points away from the centroid of the closed shape.
fn assert_outward(tris: &[[Vec3; 3]], what: &str) {
    let verts = distinct_vertices(tris);
    let center = verts.iter().copied().sum::<Vec3>() / verts.len() as f32;
    for t in tris {
        let c = (t[0] + t[1] + t[2]) / 3.0;
        assert!(
            normal(t).dot(c - center) > 0.0,
            "{what}: triangle {t:?} faces inwards"
        );
    }
}

/// A fresh scratch directory for files a test needs.
fn scratch_dir(test: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("risotto-scene-file-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

// ---------------------------------------------------------------------------------------
// The valid base scene.

#[test]
fn base_scene_loads_with_resolved_values() {
    let s = parse(BASE).expect("BASE is valid");
    assert_eq!(
        s.render,
        RenderSettings {
            width: 64,
            height: 48,
            spp: 4,
            ..RenderSettings::default()
        }
    );
    assert_eq!(s.render.max_depth, 8);
    assert_eq!(s.render.rr_depth, 5);
    assert_eq!(
        s.camera.projection,
        Projection::Perspective { fov_deg: 40.0 }
    );
    assert_eq!(s.camera.from, Vec3::new(0.0, 2.0, 6.0));
    assert_eq!(s.materials.len(), 2);
    assert_eq!(s.materials[1].name, "glass");
    assert_eq!(s.materials[1].type_name, "dielectric");
    assert_eq!(s.materials[1].priority, 2);
    assert_eq!(s.materials[0].priority, 0);
    assert_eq!(s.shapes[0].material, 1);
    assert_eq!(
        s.shapes[0].geometry,
        ShapeGeometry::Sphere {
            center: Vec3::Y,
            radius: 1.0
        }
    );
    assert_eq!(s.shapes[1].emission, Some(Rgb::splat(0.1)));
    assert_eq!(s.shapes[0].emission, None);
    // The floor quad: normal = normalize(edge1 x edge2) = z x x = +y.
    for t in triangles(&s.shapes[1]) {
        assert!(normal(&t).distance(Vec3::Y) < 1e-6);
    }
    // The crate: cube [-1,1]^3 scaled 0.5, turned, centred at (2, 0.5, 0).
    let crate_tris = triangles(&s.shapes[2]);
    assert_eq!(crate_tris.len(), 12);
    assert_outward(&crate_tris, "crate");
    for v in distinct_vertices(&crate_tris) {
        let local = v - Vec3::new(2.0, 0.5, 0.0);
        assert!((local.y.abs() - 0.5).abs() < 1e-6);
        // Rotation about y preserves the horizontal distance sqrt(0.5^2 + 0.5^2).
        assert!((local.x.hypot(local.z) - 0.5f32.hypot(0.5)).abs() < 1e-6);
    }
    // Lights: the direction is normalised; a lone number is a grey colour.
    assert_eq!(
        s.lights[0],
        LightDesc::Distant {
            name: "sun".into(),
            direction: Vec3::NEG_Y,
            irradiance: Rgb::WHITE
        }
    );
    assert_eq!(
        s.lights[1],
        LightDesc::Point {
            name: "bulb".into(),
            position: Vec3::new(0.0, 4.0, 0.0),
            intensity: Rgb::splat(10.0)
        }
    );
    assert_eq!(s.lights[2].name(), "lights[2]");
    assert_eq!(s.camera_volume, None);
}

#[test]
fn defaults_when_render_section_is_absent() {
    let text = "[camera]\nfov = 30\nfrom = [0, 0, 1]\nto = [0, 0, 0]\n";
    let s = parse(text).expect("minimal scene");
    assert_eq!(
        s.render,
        RenderSettings {
            width: 512,
            height: 512,
            spp: 64,
            max_depth: 8,
            seed: 0,
            rr_depth: 5,
            filter: PixelFilter::PIXEL_BOX,
            integrator: risotto_engine::integrator::GlobalIntegrator::Path,
            shading_normals: risotto_engine::scene::ShadingNormals::Consistent,
        }
    );
    assert_eq!(s.camera.up, Vec3::Y);
    assert!(s.shapes.is_empty() && s.lights.is_empty() && s.materials.is_empty());
}

#[test]
fn max_depth_minus_one_is_unbounded() {
    let s = parse(&base_with("spp = 4", "spp = 4\nmax_depth = -1\nseed = 77")).unwrap();
    assert_eq!(s.render.max_depth, RenderSettings::UNBOUNDED_DEPTH);
    assert_eq!(s.render.seed, 77);
    let text = base_with("spp = 4", "spp = 4\nmax_depth = 0");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "max_depth"),
        &["render", "max_depth", "`0`"],
    );
}

// ---------------------------------------------------------------------------------------
// Located errors, one per kind of mistake.

#[test]
fn syntax_error_names_file_line_and_text() {
    let text = base_with("radius = 1", "radius = = 1");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::Syntax);
    assert_message(
        &e,
        line_of(&text, "radius = = 1"),
        &["TOML syntax error", "radius = = 1"],
    );
    // An unclosed array at the end of the file.
    let text = "[camera]\nfov = 40\nfrom = [0, 0,\n";
    let e = parse_err(text);
    assert_eq!(e.kind(), SceneErrorKind::Syntax);
    assert!(e.to_string().starts_with(FILE), "{e}");
}

#[test]
fn unknown_camera_field_is_rejected_with_suggestion() {
    let text = base_with("fov = 40", "fov = 40\nfocal_lenght = 35");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::UnknownField);
    assert_message(
        &e,
        line_of(&text, "focal_lenght"),
        &["camera", "`focal_lenght`", "`fov`"],
    );
    // A near miss gets a suggestion.
    let text = base_with("up = [0, 1, 0]", "upp = [0, 1, 0]");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "upp"), &["camera", "did you mean `up`?"]);
    // A field of the other projection.
    let text = base_with(
        "fov = 40",
        "projection = \"orthographic\"\nwidth = 4\nfov = 40",
    );
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "fov = 40"),
        &["camera", "unknown field `fov`"],
    );
}

#[test]
fn unknown_fields_elsewhere_are_rejected() {
    let text = base_with("radius = 1", "radius = 1\nradious = 2");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "radious"),
        &["shapes[0] \"ball\"", "`radious`"],
    );
    let text = format!("{BASE}\n[integrator]\ntype = \"path\"\n");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "[integrator]"), &["`integrator`"]);
    let text = base_with("spp = 4", "spp = 4\nsamples = 3");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "samples"), &["render", "`samples`"]);
}

#[test]
fn missing_required_field_points_at_the_entity() {
    let text = base_with("radius = 1\n", "");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::MissingField);
    // Located at the [[shapes]] header of the ball.
    let ball_header = text[..text.find("name = \"ball\"").unwrap()]
        .matches('\n')
        .count(); // the line before `name = "ball"` is `[[shapes]]`
    assert_message(
        &e,
        ball_header,
        &["shapes[0] \"ball\"", "`radius`", "missing"],
    );
    assert_eq!(e.field(), Some("radius"));
    assert_eq!(e.entity(), Some("shapes[0] \"ball\""));

    let text = BASE.replace(
        "[camera]\nfov = 40\nup = [0, 1, 0]\nfrom = [0, 2, 6]\nto = [0, 0.5, 0]\n",
        "",
    );
    let e = parse_err(&text);
    assert_message(&e, 1, &["[camera]"]);
}

#[test]
fn negative_emission_and_radiance_are_rejected() {
    let text = base_with("emission = [0.1, 0.1, 0.1]", "emission = [0.1, -0.5, 0.1]");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::InvalidValue);
    assert_message(
        &e,
        line_of(&text, "emission"),
        &[
            "shapes[1] \"floor\"",
            "`emission`",
            "[0.1, -0.5, 0.1]",
            ">= 0",
        ],
    );
    let text = base_with("radiance = [0.1, 0.2, 0.3]", "radiance = -2");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "radiance = -2"),
        &["lights[2]", "`radiance`", "`-2`"],
    );
}

#[test]
fn ior_at_most_zero_is_rejected_through_material_params() {
    let text = base_with("ior = 1.5", "ior = -1.5");
    let s = parse(&text).expect("the scene layer leaves material params to factories");
    let glass = &s.materials[1].params;
    let e = glass
        .f32_where("ior", Some(1.5), "must be > 0", |v| v > 0.0)
        .unwrap_err();
    assert_message(
        &e,
        line_of(&text, "ior"),
        &["materials.glass", "`ior`", "`-1.5`", "> 0"],
    );
    let text = base_with("ior = 1.5", "ior = 0");
    let s = parse(&text).unwrap();
    let e = s.materials[1]
        .params
        .f32_in("ior", None, 1e-3, 10.0)
        .unwrap_err();
    assert_message(
        &e,
        line_of(&text, "ior"),
        &["materials.glass", "`0`", "[0.001, 10]"],
    );
}

#[test]
fn zero_light_direction_is_rejected() {
    let text = base_with("direction = [0, -2, 0]", "direction = [0, 0, 0]");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "direction"),
        &["lights[0] \"sun\"", "`direction`", "[0, 0, 0]", "non-zero"],
    );
}

#[test]
fn fov_outside_open_interval_is_rejected() {
    for bad in ["0", "180", "-5", "200.5"] {
        let text = base_with("fov = 40", &format!("fov = {bad}"));
        let e = parse_err(&text);
        assert_message(
            &e,
            line_of(&text, "fov ="),
            &["camera", "`fov`", &format!("`{bad}`"), "(0, 180)"],
        );
    }
    let s = parse(&base_with("fov = 40", "fov = 179.5")).unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Perspective { fov_deg: 179.5 }
    );
}

#[test]
fn non_positive_sphere_radius_is_rejected() {
    for bad in ["0", "-0.25", "0.0"] {
        let text = base_with("radius = 1", &format!("radius = {bad}"));
        let e = parse_err(&text);
        assert_message(
            &e,
            line_of(&text, "radius"),
            &["shapes[0] \"ball\"", "`radius`", &format!("`{bad}`"), "> 0"],
        );
    }
}

#[test]
fn wrong_types_are_reported_with_the_value() {
    let text = base_with("radius = 1", "radius = \"big\"");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::WrongType);
    assert_message(
        &e,
        line_of(&text, "radius"),
        &["`radius`", "expected a number", "\"big\""],
    );
    let text = base_with("center = [0, 1, 0]", "center = [0, 1]");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "center"),
        &["`center`", "2 elements", "[0, 1]"],
    );
    let text = base_with("spp = 4", "spp = 4.5");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "spp"),
        &["render", "`spp`", "an integer", "4.5"],
    );
}

#[test]
fn missing_obj_names_the_full_path() {
    let dir = scratch_dir("missing_obj");
    let scene_path = dir.join("scene.toml");
    let text = base_with(
        "[[lights]]\nname = \"sun\"",
        "[[shapes]]\nname = \"bunny\"\ntype = \"mesh\"\nmaterial = \"white\"\npath = \"meshes/nope.obj\"\n\n[[lights]]\nname = \"sun\"",
    );
    let e = parse_scene(&text, &scene_path).unwrap_err();
    let full = dir.join("meshes").join("nope.obj");
    let msg = e.to_string();
    assert_eq!(e.kind(), SceneErrorKind::ExternalFile);
    assert!(msg.contains(&full.display().to_string()), "{msg}");
    assert!(msg.contains(&scene_path.display().to_string()), "{msg}");
    assert!(msg.contains("shapes[3] \"bunny\""), "{msg}");
    assert!(msg.contains("`path`"), "{msg}");
    assert_eq!(e.line(), Some(line_of(&text, "meshes/nope.obj")));
    let _ = std::fs::remove_dir_all(&dir);
}

/// An OBJ with a UTF-8 byte-order mark and a Latin-1 comment (common in files from other
/// tools) loads: the mark made its first vertex unreadable ("face vertex index out of
/// bounds") and the comment the whole file ("read error").
#[test]
fn obj_with_a_byte_order_mark_and_a_latin1_comment_loads() {
    let dir = scratch_dir("bom_obj");
    std::fs::write(
        dir.join("tri.obj"),
        b"\xef\xbb\xbfv 0 0 0\nv 1 0 0\n# caf\xe9\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let text = "[materials.m]\ntype = \"diffuse\"\n\n[[shapes]]\nname = \"tri\"\ntype = \"mesh\"\nmaterial = \"m\"\npath = \"tri.obj\"\n\n[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n";
    let s = parse_scene(text, &dir.join("scene.toml")).unwrap();
    let tris = triangles(shape(&s, "tri"));
    assert_eq!(tris.len(), 1);
    assert_eq!(tris[0][1], Vec3::X);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unparsable_obj_is_reported() {
    let dir = scratch_dir("bad_obj");
    let scene_path = dir.join("scene.toml");
    let bad_objs: &[(&str, &[u8])] = &[
        ("letters", b"v 0 0 0\nv 1 0 0\nv a b c\nf 1 2 3\n"),
        ("short_vertex", b"v 1 2\nf 1 2 3\n"),
        ("no_vertices", b"f 1 2 3\n"),
        (
            "index_out_of_range",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
        ),
        (
            "negative_out_of_range",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -7 1 2\n",
        ),
        ("empty", b""),
        ("only_comments", b"# nothing\no thing\n"),
        ("nan", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        (
            "binary",
            &[
                0xff, 0xfe, 0x00, 0x01, b'v', b' ', 0x80, b'\n', b'f', b' ', b'1',
            ],
        ),
    ];
    for (name, bytes) in bad_objs {
        let obj = dir.join(format!("{name}.obj"));
        std::fs::write(&obj, bytes).unwrap();
        let text = format!(
            "[materials.m]\ntype = \"diffuse\"\n\n[[shapes]]\ntype = \"mesh\"\nmaterial = \"m\"\npath = \"{name}.obj\"\n\n[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n"
        );
        let e = parse_scene(&text, &scene_path)
            .err()
            .unwrap_or_else(|| panic!("{name}.obj should be rejected"));
        let msg = e.to_string();
        assert_eq!(e.kind(), SceneErrorKind::ExternalFile, "{name}: {msg}");
        assert!(msg.contains(&obj.display().to_string()), "{name}: {msg}");
        assert!(msg.contains("shapes[0]"), "{name}: {msg}");
        assert_eq!(e.line(), Some(7), "{name}: {msg}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad vertex attributes and bad PLY files: each a located error (the shape's `path`)
/// naming the file and what is wrong with which value.
#[test]
fn bad_mesh_attributes_and_ply_files_are_reported() {
    let dir = scratch_dir("bad_mesh_attributes");
    let scene_path = dir.join("scene.toml");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let ply_head = |vertex_props: &str, count: usize, faces: &str| {
        format!("ply\nformat ascii 1.0\nelement vertex {count}\n{vertex_props}{faces}end_header\n")
    };
    let xyz = "property float x\nproperty float y\nproperty float z\n";
    let face = "element face 1\nproperty list uchar int vertex_indices\n";
    // Binary (ascii PLY readers reject `nan` before it reaches the check).
    let mut nan_normal_ply = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\n{xyz}property float nx\n\
         property float ny\nproperty float nz\n{face}end_header\n"
    )
    .into_bytes();
    for v in [
        [0.0, 0.0, 0.0, 0.0, 0.0, f32::NAN],
        [1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    ] {
        nan_normal_ply.extend(v.iter().flat_map(|x: &f32| x.to_le_bytes()));
    }
    nan_normal_ply.push(3);
    nan_normal_ply.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "bad_vn.obj",
            format!("{tri}vn 0 0 1\nf 1//1 2//1 3//2\n").into_bytes(),
            "line 5: face corner `3//2` refers to vn 2 but the file has 1",
        ),
        (
            "bad_vt.obj",
            format!("{tri}vt 0 0\nvt 1 0\nf 1/1 2/2 3/7\n").into_bytes(),
            "line 6: face corner `3/7` refers to vt 7 but the file has 2",
        ),
        (
            "nan_vn.obj",
            format!("{tri}vn 0 nan 1\nf 1//1 2//1 3//1\n").into_bytes(),
            "normal 1 is not finite (0, NaN, 1)",
        ),
        (
            "no_z.ply",
            format!(
                "{}0 0\n1 0\n0 1\n3 0 1 2\n",
                ply_head("property float x\nproperty float y\n", 3, face)
            )
            .into_bytes(),
            "the `vertex` element has no `z` property",
        ),
        (
            "no_faces.ply",
            format!("{}0 0 0\n1 0 0\n0 1 0\n", ply_head(xyz, 3, "")).into_bytes(),
            "the header declares no `face` element",
        ),
        (
            "too_many.ply",
            format!(
                "{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                ply_head(xyz, 4_000_000_000, face)
            )
            .into_bytes(),
            "the header declares 4000000000 `vertex` elements, more than the file's",
        ),
        ("nan_normal.ply", nan_normal_ply, "normal 1 is not finite"),
        (
            "bad_index.ply",
            format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", ply_head(xyz, 3, face)).into_bytes(),
            "face 0 refers to vertex 5 but the file has 3",
        ),
    ];
    for (name, bytes, want) in cases {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let text = format!(
            "[materials.m]\ntype = \"diffuse\"\n\n[[shapes]]\ntype = \"mesh\"\nmaterial = \"m\"\npath = \"{name}\"\n\n[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n"
        );
        let e = parse_scene(&text, &scene_path)
            .err()
            .unwrap_or_else(|| panic!("{name} should be rejected"));
        let msg = e.to_string();
        assert_eq!(e.kind(), SceneErrorKind::ExternalFile, "{name}: {msg}");
        assert!(msg.contains(&file.display().to_string()), "{name}: {msg}");
        assert!(msg.contains(want), "{name}: {msg}");
        assert_eq!(e.line(), Some(7), "{name}: {msg}");
    }
    // `face_normals` must be a boolean.
    std::fs::write(dir.join("ok.obj"), format!("{tri}f 1 2 3\n")).unwrap();
    let text = "[materials.m]\ntype = \"diffuse\"\n\n[[shapes]]\ntype = \"mesh\"\nmaterial = \"m\"\npath = \"ok.obj\"\nface_normals = 1\n\n[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n";
    let Err(e) = parse_scene(text, &scene_path) else {
        panic!("a number is not a switch");
    };
    assert_eq!(e.line(), Some(8), "{e}");
    // `flip_normals` reverses each triangle: its normal (v1 - v0) x (v2 - v0) turns over.
    let normal_z = |extra: &str| {
        let text = format!("[materials.m]\ntype = \"diffuse\"\n\n[[shapes]]\ntype = \"mesh\"\nmaterial = \"m\"\npath = \"ok.obj\"\n{extra}\n\n[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n");
        let desc = parse_scene(&text, &scene_path).unwrap();
        let [a, b, c] = desc.shapes[0].geometry.world_triangles()[0];
        (b - a).cross(c - a).z
    };
    let (plain, flipped) = (normal_z(""), normal_z("flip_normals = true"));
    assert!(plain != 0.0 && flipped == -plain, "{plain} {flipped}");
    assert_eq!(normal_z("flip_normals = false"), plain);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_material_reference_lists_the_known_ones() {
    let text = base_with("material = \"glass\"", "material = \"glas\"");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::UnknownReference);
    assert_message(
        &e,
        line_of(&text, "\"glas\""),
        &["shapes[0] \"ball\"", "`material`", "`glas`", "white, glass"],
    );
}

#[test]
fn duplicate_names_are_rejected() {
    let text = base_with("name = \"floor\"", "name = \"ball\"");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::Duplicate);
    let second = text.match_indices("name = \"ball\"").nth(1).unwrap().0;
    let line = text[..second].matches('\n').count() + 1;
    let first_line = line_of(&text, "name = \"ball\"");
    assert_message(
        &e,
        line,
        &[
            "shapes[1] \"ball\"",
            "`ball`",
            &format!("first defined at line {first_line}"),
        ],
    );
    let text = base_with("name = \"bulb\"", "name = \"sun\"");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "name = \"sun\"\ntype = \"point\""),
        &["lights[1]", "`sun`"],
    );
    // Materials are table keys: TOML itself forbids duplicates.
    let text = format!("{BASE}\n[materials.white]\ntype = \"diffuse\"\n");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::Syntax);
    assert!(e.to_string().contains("white"), "{e}");
}

#[test]
fn zero_spp_and_zero_resolution_are_rejected() {
    let text = base_with("spp = 4", "spp = 0");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "spp"),
        &["render", "`spp`", "`0`", "[1, "],
    );
    for key in ["width", "height"] {
        let text = base_with(&format!("{key} = "), &format!("{key} = 0\n# was "));
        let e = parse_err(&text);
        assert_message(
            &e,
            line_of(&text, &format!("{key} = 0")),
            &["render", key, "`0`"],
        );
    }
    let text = base_with("width = 64", "width = -64");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "width"), &["`-64`"]);
}

#[test]
fn camera_geometry_errors() {
    let text = base_with("to = [0, 0.5, 0]", "to = [0, 2, 6]");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "to = "),
        &["camera", "`to`", "[0, 2, 6]", "differ"],
    );
    // forward = to - from = (0, -1.5, -6).
    let text = base_with("up = [0, 1, 0]", "up = [0, -1.5, -6]");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "up = "), &["camera", "`up`", "parallel"]);
    let text = base_with("fov = 40", "projection = \"fisheye\"\nfov = 40");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "fisheye"), &["camera", "`fisheye`"]);
    let s = parse(&base_with(
        "fov = 40",
        "projection = \"orthographic\"\nwidth = 4",
    ))
    .unwrap();
    assert_eq!(s.camera.projection, Projection::Orthographic { width: 4.0 });
}

#[test]
fn thin_lens_camera_keys_defaults_and_errors() {
    let lens = "projection = \"thin_lens\"\nfov = 40\naperture_radius = 0.25";
    let s = parse(&base_with("fov = 40", lens)).unwrap();
    // Default focus distance: |to - from| = |(0, -1.5, -6)|, so `to` is in focus.
    assert_eq!(
        s.camera.projection,
        Projection::ThinLens {
            fov_deg: 40.0,
            aperture_radius: 0.25,
            focus_distance: 38.25f32.sqrt(),
        }
    );
    let s = parse(&base_with(
        "fov = 40",
        &format!("{lens}\nfocus_distance = 2"),
    ))
    .unwrap();
    assert!(matches!(
        s.camera.projection,
        Projection::ThinLens { focus_distance, .. } if focus_distance == 2.0
    ));
    // Located errors: file, line, key, value.
    for (bad, key, value) in [
        ("aperture_radius = -0.1", "`aperture_radius`", "-0.1"),
        ("aperture_radius = inf", "`aperture_radius`", "inf"),
        ("aperture_radius = nan", "`aperture_radius`", "nan"),
    ] {
        let text = base_with(
            "fov = 40",
            &format!("projection = \"thin_lens\"\nfov = 40\n{bad}"),
        );
        let e = parse_err(&text);
        assert_message(&e, line_of(&text, bad), &["camera", key, value]);
    }
    for (bad, value) in [
        ("focus_distance = 0", "0"),
        ("focus_distance = -3", "-3"),
        ("focus_distance = inf", "inf"),
    ] {
        let text = base_with("fov = 40", &format!("{lens}\n{bad}"));
        let e = parse_err(&text);
        assert_message(
            &e,
            line_of(&text, bad),
            &["camera", "`focus_distance`", value],
        );
    }
    // The aperture is required; lens keys belong to the thin lens only.
    let text = base_with("fov = 40", "projection = \"thin_lens\"\nfov = 40");
    assert!(parse_err(&text).to_string().contains("aperture_radius"));
    let text = base_with("fov = 40", "fov = 40\naperture_radius = 0.1");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "aperture_radius"), &["aperture_radius"]);
}

#[test]
fn camera_inside_resolves_closed_shapes() {
    let s = parse(&base_with(
        "fov = 40",
        "fov = 40\ninside = [\"crate\", \"ball\"]",
    ))
    .unwrap();
    assert_eq!(
        s.camera_volume,
        Some(vec!["crate".to_owned(), "ball".to_owned()])
    );
    let text = base_with("fov = 40", "fov = 40\ninside = [\"floor\"]");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "inside"),
        &["camera", "`floor`", "no inside"],
    );
    let text = base_with("fov = 40", "fov = 40\ninside = [\"nothing\"]");
    let e = parse_err(&text);
    assert_eq!(e.kind(), SceneErrorKind::UnknownReference);
    assert_message(&e, line_of(&text, "inside"), &["`nothing`"]);
}

#[test]
fn unknown_shape_and_light_types() {
    let text = base_with("type = \"sphere\"", "type = \"cone\"");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "cone"),
        &["shapes[0] \"ball\"", "`cone`", "sphere, quad"],
    );
    let text = base_with("type = \"point\"", "type = \"laser\"");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "laser"),
        &["lights[1] \"bulb\"", "`laser`", "point, spot, environment"],
    );
    // Array-of-tables headers are absolute: this is lights[3], a second environment.
    let text = format!("{BASE}\n[[lights]]\ntype = \"environment\"\nradiance = 1\n");
    let e = parse_err(&text);
    assert!(e.to_string().contains("at most one environment"), "{e}");
}

/// Singularity is a property of shape, not of size (issue 14 item 10): a uniform scale of
/// 1e-4 (determinant 1e-12) or 1e-9 is a valid transform; a matrix that flattens space, at
/// any size, is not.
#[test]
fn tiny_uniform_scales_are_not_singular() {
    for scale in ["1e-4", "1e-9", "[1e-4, 2e-4, 1e-4]"] {
        let text = base_with("{ scale = 0.5 }", &format!("{{ scale = {scale} }}"));
        if let Err(e) = parse(&text) {
            panic!("scale {scale}: {e}");
        }
    }
    for scale in ["[1, 1e-13, 1]", "[1e-4, 1e-4, 1e-17]"] {
        let text = base_with("{ scale = 0.5 }", &format!("{{ scale = {scale} }}"));
        let e = parse_err(&text);
        assert_message(&e, line_of(&text, "transform"), &["\"crate\"", "singular"]);
    }
    // Rows (1e-3, 0, 0), (0, 1e-3, 0), (1e-3, 1e-3, 1e-17): the third axis nearly in the
    // plane of the first two, at a small size.
    let flat =
        "{ matrix = [[1e-3, 0, 0, 0], [0, 1e-3, 0, 0], [1e-3, 1e-3, 1e-17, 0], [0, 0, 0, 1]] }";
    let text = base_with("{ scale = 0.5 }", flat);
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "transform"), &["\"crate\"", "singular"]);
}

#[test]
fn degenerate_quad_and_singular_transform_are_rejected() {
    let text = base_with("edge2 = [10, 0, 0]", "edge2 = [0, 0, -3]");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "edge2"),
        &["shapes[1] \"floor\"", "no area"],
    );
    let text = base_with("{ scale = 0.5 }", "{ scale = [1, 0, 1] }");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "transform"),
        &["shapes[2] \"crate\"", "singular"],
    );
    let text = base_with("{ scale = 0.5 }", "{ scale = 3e38 }");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "transform"),
        &["shapes[2] \"crate\"", "overflow"],
    );
    let text = base_with("{ scale = 0.5 }", "{ scale = 0.5, translate = [1, 2, 3] }");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "transform"),
        &["transform[0]", "exactly one"],
    );
    let text = base_with("{ scale = 0.5 }", "{ shear = 0.5 }");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "transform"),
        &["transform[0]", "`shear`"],
    );
    let text = base_with("angle = 30", "angle = \"thirty\"");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "thirty"),
        &["transform[1] rotate", "`angle`"],
    );
}

#[test]
fn environment_map_is_resolved_and_must_exist() {
    let dir = scratch_dir("env_map");
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    std::fs::write(dir.join("maps/sky.exr"), b"not really an exr").unwrap();
    let scene_path = dir.join("scene.toml");
    let ok = base_with("radiance = [0.1, 0.2, 0.3]", "map = \"maps/sky.exr\"");
    let s = parse_scene(&ok, &scene_path).unwrap();
    let LightDesc::Environment {
        name,
        radiance,
        map,
        map_at,
        ..
    } = &s.lights[2]
    else {
        panic!("{:?}", s.lights[2]);
    };
    assert_eq!(name, "lights[2]");
    assert_eq!(*radiance, Rgb::WHITE);
    assert_eq!(
        map,
        &Some(std::path::absolute(dir.join("maps/sky.exr")).unwrap())
    );
    // The map's location is kept for the errors of reading it, at the `map` value.
    let e = map_at
        .as_ref()
        .unwrap()
        .error(SceneErrorKind::ExternalFile, "x");
    assert_eq!(e.line(), Some(line_of(&ok, "map =")));
    assert_eq!(e.field(), Some("map"));
    let bad = base_with("radiance = [0.1, 0.2, 0.3]", "map = \"maps/cloudy.exr\"");
    let e = parse_scene(&bad, &scene_path).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains(&dir.join("maps/cloudy.exr").display().to_string()),
        "{msg}"
    );
    assert_eq!(e.line(), Some(line_of(&bad, "cloudy")));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unreadable_scene_file_names_it() {
    let e = load_scene(Path::new("/nonexistent/dir/scene.toml")).unwrap_err();
    assert_eq!(e.kind(), SceneErrorKind::Io);
    assert!(e.to_string().contains("/nonexistent/dir/scene.toml"), "{e}");
}

// ---------------------------------------------------------------------------------------
// Spans: line and column, implicit tables, the excerpt.

#[test]
fn line_and_column_count_characters() {
    // Column counts characters, not bytes: "é" is 2 bytes.
    let text = "# é é\n[camera]\nfov = 40\nfrom = [0, 0, 1]\nto = [0, 0, 1] # héhé\n";
    let e = parse_err(text);
    assert_eq!((e.line(), e.column()), (Some(5), Some(6)), "{e}");
    // The excerpt repeats the line and marks the value.
    let msg = e.to_string();
    assert!(msg.contains("5 | to = [0, 0, 1] # héhé"), "{msg}");
    assert!(msg.contains("  |      ^^^^^^^^^"), "{msg}");
}

#[test]
fn implicit_tables_and_dotted_keys_keep_spans() {
    // `materials` and `materials.glass` are implicit (no header of their own), and
    // `interior.sigma_a` is a dotted key: toml gives these no span.
    let text = r#"[materials.glass.interior]
type = "beer"
sigma_a = [1, -2, 3]

[materials.glass]
type = "dielectric"
tint.r = 1

[camera]
fov = 40
from = [0, 0, 1]
to = [0, 0, 0]
"#;
    let s = parse(text).expect("valid");
    let glass = &s.materials[0].params;
    assert_eq!(glass.keys(), vec!["interior", "tint"]);
    let interior = glass.table("interior").unwrap().expect("nested table");
    assert_eq!(interior.entity(), "materials.glass.interior");
    assert_eq!(interior.string("type", None).unwrap(), "beer");
    let e = interior.rgb("sigma_a", None).unwrap_err();
    assert_message(
        &e,
        3,
        &["materials.glass.interior", "`sigma_a`", "[1, -2, 3]"],
    );
    // A dotted key makes an implicit table; reading it as a colour names its line.
    let e = glass.rgb("tint", None).unwrap_err();
    assert_message(&e, 7, &["materials.glass", "`tint`", "a table"]);
}

// ---------------------------------------------------------------------------------------
// MaterialParams.

#[test]
fn material_params_typed_reads() {
    let text = r#"[materials.custom]
type = "my_plugin"
priority = -3
roughness = 0.25
albedo = [0.5, 0.6, 0.7]
grey = 0.4
flag = true
mode = "fast"
count = 7
offset = [-1, 0, 2.5]
texture = "textures/wood.png"
albedoo = 1

[camera]
fov = 40
from = [0, 0, 1]
to = [0, 0, 0]
"#;
    let s = parse(text).unwrap();
    let m = &s.materials[0];
    assert_eq!((m.type_name.as_str(), m.priority), ("my_plugin", -3));
    let p = &m.params;
    assert!(!p.has("type") && !p.has("priority") && p.has("grey"));
    assert_eq!(p.keys()[0], "roughness");
    assert_eq!(p.f32("roughness", None).unwrap(), 0.25);
    assert_eq!(p.f32("missing", Some(2.0)).unwrap(), 2.0);
    assert_eq!(p.rgb("albedo", None).unwrap(), Rgb::new(0.5, 0.6, 0.7));
    assert_eq!(p.rgb("grey", None).unwrap(), Rgb::splat(0.4));
    assert!(p.bool("flag", None).unwrap());
    assert_eq!(p.string("mode", None).unwrap(), "fast");
    assert_eq!(p.u32("count", None).unwrap(), 7);
    assert_eq!(p.vec3("offset", None).unwrap(), Vec3::new(-1.0, 0.0, 2.5));
    let tex = p.path("texture").unwrap().unwrap();
    assert!(
        tex.is_absolute() && tex.ends_with("test-scenes/textures/wood.png"),
        "{tex:?}"
    );
    assert!(p.table("mode").is_err());
    assert!(p.table("nothing").unwrap().is_none());

    let e = p.f32("missing", None).unwrap_err();
    assert_message(
        &e,
        1,
        &["materials.custom", "`missing`", "missing required field"],
    );
    let e = p
        .rgb_where("albedo", None, "every channel must be <= 0.55", |c| {
            c.max_channel() <= 0.55
        })
        .unwrap_err();
    assert_message(&e, 5, &["`albedo`", "[0.5, 0.6, 0.7]", "<= 0.55"]);
    let e = p.deny_unknown(&[
        "roughness",
        "albedo",
        "grey",
        "flag",
        "mode",
        "count",
        "offset",
        "texture",
    ]);
    let e = e.unwrap_err();
    assert_eq!(e.kind(), SceneErrorKind::UnknownField);
    assert_message(
        &e,
        12,
        &["materials.custom", "`albedoo`", "did you mean `albedo`?"],
    );
    let e = p.error(Some("mode"), "`fast` needs `count` >= 8");
    assert_message(&e, 8, &["materials.custom", "`mode`", "needs `count`"]);
    let e = p.u32("offset", None).unwrap_err();
    assert_eq!(e.kind(), SceneErrorKind::WrongType);
}

#[test]
fn material_type_is_required_but_not_checked() {
    let text =
        "[materials.m]\nreflectance = 1\n[camera]\nfov = 40\nfrom = [0, 0, 1]\nto = [0, 0, 0]\n";
    let e = parse_err(text);
    assert_message(&e, 1, &["materials.m", "`type`"]);
    let text = text.replace("reflectance", "type = \"anything_goes\"\nwhatever");
    let s = parse(&text).unwrap();
    assert_eq!(s.materials[0].type_name, "anything_goes");
    assert_eq!(s.materials[0].params.keys(), vec!["whatever"]);
}

// ---------------------------------------------------------------------------------------
// Robustness: garbage never panics.

#[test]
fn every_truncation_is_an_error() {
    let text = BASE.trim_end();
    for (cut, _) in text.char_indices() {
        let prefix = &text[..cut];
        assert!(
            parse(prefix).is_err(),
            "the prefix of {cut} bytes parsed without error:\n{prefix}"
        );
    }
    assert!(parse(text).is_ok());
}

/// xorshift64*: a tiny deterministic generator for the mutation test.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// The fuzzer's budget: `RISOTTO_FUZZ_CASES` cases (default `default`) from stream
/// `RISOTTO_FUZZ_SEED` (default 0), so anyone can run it longer or elsewhere:
/// `RISOTTO_FUZZ_CASES=100000 RISOTTO_FUZZ_SEED=7 cargo test --release ...`.
fn fuzz_budget(default: usize) -> (usize, u64) {
    let read = |name: &str| {
        std::env::var(name).ok().map(|v| {
            v.trim()
                .parse::<u64>()
                .unwrap_or_else(|_| panic!("{name}={v:?} is not a whole number"))
        })
    };
    (
        read("RISOTTO_FUZZ_CASES").map_or(default, |n| n as usize),
        read("RISOTTO_FUZZ_SEED").unwrap_or(0),
    )
}

#[test]
fn mutated_scenes_never_panic() {
    let dir = scratch_dir("mutations");
    std::fs::write(
        dir.join("ico.obj"),
        include_str!("../../../../scenes/meshes/icosphere.obj"),
    )
    .unwrap();
    let scene_path = dir.join("scene.toml");
    let base = base_with(
        "[[lights]]\nname = \"sun\"",
        "[[shapes]]\nname = \"ico\"\ntype = \"mesh\"\nmaterial = \"white\"\npath = \"ico.obj\"\ntransform = [{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]] }]\n\n[[lights]]\nname = \"sun\"",
    );
    assert!(parse_scene(&base, &scene_path).is_ok());
    let tokens = [
        "[",
        "]",
        "{",
        "}",
        "=",
        "\"",
        "'",
        ",",
        ".",
        "-",
        "e",
        "9",
        "\n",
        "#",
        "\\",
        " ",
        "é",
        "nan",
        "inf",
        "-1",
        "0",
        "1e39",
        "99999999999999999999",
        "[[shapes]]",
        "[camera]",
        "\"\"\"",
        "true",
        "1979-05-27",
        "{}",
        "[]",
    ];
    let (cases, seed) = fuzz_budget(3000);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ seed.wrapping_mul(0xD1B5_4A32_D192_ED03));
    let (mut ok, mut err) = (0, 0);
    for _ in 0..cases {
        let mut chars: Vec<char> = base.chars().collect();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(chars.len() + 1);
            match rng.below(4) {
                0 => {
                    let end = (at + 1 + rng.below(12)).min(chars.len());
                    chars.drain(at.min(end)..end);
                }
                1 | 2 => {
                    let t = tokens[rng.below(tokens.len())];
                    chars.splice(at..at, t.chars());
                }
                _ => {
                    if at < chars.len() {
                        let t = tokens[rng.below(tokens.len())];
                        let end = (at + t.chars().count()).min(chars.len());
                        chars.splice(at..end, t.chars());
                    }
                }
            }
        }
        let text: String = chars.into_iter().collect();
        let result = std::panic::catch_unwind(|| parse_scene(&text, &scene_path));
        match result {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(e)) => {
                err += 1;
                // Every located error names the file and a line within the text.
                let line = e.line().expect("located");
                assert!(line >= 1 && line <= text.lines().count() + 1, "{e}");
                assert!(e.to_string().starts_with(&scene_path.display().to_string()));
            }
            Err(_) => panic!("the loader panicked on:\n{text}"),
        }
    }
    // Most mutations must break the scene (an ineffective mutator would test nothing).
    assert!(err > ok, "ok {ok}, err {err}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------
// Transforms against independent values.

#[test]
fn look_at_rectangle_matches_mitsuba_readme_corners() {
    // Mitsuba reference README, scene b: "square side 4 centred at (-3, 6, 3) facing the
    // origin (normal (0.4082, -0.8165, -0.4082))" with its four corners listed.
    let text = r#"[materials.black]
type = "diffuse"
[[shapes]]
type = "rectangle"
material = "black"
transform = [{ scale = 2 }, { look_at = { from = [-3, 6, 3], to = [0, 0, 0], up = [0, 1, 0] } }]
[camera]
fov = 40
from = [0, 0, 1]
to = [0, 0, 0]
"#;
    let s = parse(text).unwrap();
    let tris = triangles(&s.shapes[0]);
    let corners = [
        Vec3::new(-2.7405, 4.8453, 5.5689),
        Vec3::new(-5.5689, 4.8453, 2.7405),
        Vec3::new(-3.2595, 7.1547, 0.4311),
        Vec3::new(-0.4311, 7.1547, 3.2595),
    ];
    assert!(same_point_set(&distinct_vertices(&tris), &corners, 1e-4));
    for t in tris {
        assert!(normal(&t).distance(Vec3::new(0.4082, -0.8165, -0.4082)) < 1e-4);
    }
}

#[test]
fn mirroring_transform_keeps_boxes_and_meshes_outward() {
    let text = r#"[materials.m]
type = "diffuse"
[[shapes]]
name = "mirrored_box"
type = "box"
material = "m"
min = [0, 0, 0]
max = [1, 2, 3]
transform = [{ scale = [-1, 1, 1] }, { translate = [5, 0, 0] }]
[[shapes]]
name = "mirrored_rect"
type = "rectangle"
material = "m"
transform = [{ scale = [1, 1, -1] }]
[camera]
fov = 40
from = [0, 0, 1]
to = [0, 0, 0]
"#;
    let s = parse(text).unwrap();
    let tris = triangles(&s.shapes[0]);
    assert_outward(&tris, "mirrored box");
    let expected: Vec<Vec3> = (0..8)
        .map(|i| {
            let c = Vec3::new(
                (i & 1) as f32,
                ((i >> 1) & 1) as f32 * 2.0,
                ((i >> 2) & 1) as f32 * 3.0,
            );
            Vec3::new(5.0 - c.x, c.y, c.z)
        })
        .collect();
    assert!(same_point_set(&distinct_vertices(&tris), &expected, 1e-6));
    // A rectangle's normal is carried like a normal (inverse transpose): +z -> -z.
    for t in triangles(&s.shapes[1]) {
        assert!(normal(&t).distance(Vec3::NEG_Z) < 1e-6);
    }
}

/// `flip_tex_coords` reads a mesh file's `v` as `1 - v`; without it the file's values stand.
#[test]
fn flip_tex_coords_turns_v_upside_down() {
    let dir = scratch_dir("flip_tex_coords");
    std::fs::write(
        dir.join("t.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.75\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    let uvs = |flip: bool| {
        let text = format!(
            "[materials.m]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"mesh\"\npath = \"t.obj\"\n\
             material = \"m\"\nflip_tex_coords = {flip}\n[camera]\nfov = 40\n\
             from = [0, 0, 5]\nto = [0, 0, 0]\n"
        );
        let path = dir.join("s.toml");
        std::fs::write(&path, text).unwrap();
        let s = load_scene(&path).unwrap();
        let a = &s.shapes[0].attributes;
        a.corners[0].map(|c| a.uvs[c as usize])
    };
    let stored = uvs(false);
    assert_eq!(
        stored,
        [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.3, 0.4),
            Vec2::new(0.5, 0.75)
        ]
    );
    let flipped = uvs(true);
    for (f, s) in flipped.iter().zip(&stored) {
        assert_eq!((f.x, f.y), (s.x, 1.0 - s.y));
    }
}

/// A rectangle's texture coordinates are Mitsuba's `((x + 1) / 2, (y + 1) / 2)` of the local
/// point (mitsuba3 `rectangle.cpp`): checked at every world-space corner, also under a
/// mirroring transform (which swaps the triangles' corners along with their vertices).
#[test]
fn rectangle_uv_is_mitsubas_local_parameterisation() {
    for (transform, local_of) in [
        (
            "[{ scale = [2, 3, 1] }, { translate = [0, 0, 1] }]",
            (|p: Vec3| Vec3::new(p.x / 2.0, p.y / 3.0, p.z - 1.0)) as fn(Vec3) -> Vec3,
        ),
        ("[{ scale = [-1, 1, 1] }]", |p: Vec3| {
            Vec3::new(-p.x, p.y, p.z)
        }),
    ] {
        let text = format!(
            "[materials.m]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"rectangle\"\n\
             material = \"m\"\ntransform = {transform}\n[camera]\nfov = 40\n\
             from = [0, 0, 5]\nto = [0, 0, 0]\n"
        );
        let s = parse(&text).unwrap();
        let shape = &s.shapes[0];
        let tris = triangles(shape);
        let a = &shape.attributes;
        assert_eq!((a.corners.len(), a.uvs.len()), (2, 4), "{transform}");
        for (t, corners) in tris.iter().zip(&a.corners) {
            for k in 0..3 {
                let local = local_of(t[k]);
                let uv = a.uvs[corners[k] as usize];
                let want = Vec2::new((local.x + 1.0) / 2.0, (local.y + 1.0) / 2.0);
                assert!(uv.distance(want) < 1e-6, "{transform}: {uv} at {local}");
            }
        }
    }
}

#[test]
fn matrix_step_equals_the_step_list_it_was_computed_from() {
    let rows = |angle: f64| {
        // R_y(a) from the README: x' = x cos a + z sin a, z' = -x sin a + z cos a.
        let (s, c) = angle.to_radians().sin_cos();
        (s, c)
    };
    let (s, c) = rows(18.0);
    let matrix = format!(
        "[[{}, 0, {}, -0.33], [0, 0.6, 0, -0.4], [{}, 0, {}, -0.28], [0, 0, 0, 1]]",
        0.3 * c,
        0.3 * s,
        -0.3 * s,
        0.3 * c
    );
    let scene = |transform: &str| {
        format!(
            "[materials.m]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"box\"\nmaterial = \"m\"\ntransform = {transform}\n[camera]\nfov = 40\nfrom = [0, 0, 5]\nto = [0, 0, 0]\n"
        )
    };
    let a = parse(&scene(&format!("[{{ matrix = {matrix} }}]"))).unwrap();
    let b = parse(&scene(
        "[{ scale = [0.3, 0.6, 0.3] }, { rotate = { axis = [0, 1, 0], angle = 18 } }, { translate = [-0.33, -0.4, -0.28] }]",
    ))
    .unwrap();
    let (ta, tb) = (triangles(&a.shapes[0]), triangles(&b.shapes[0]));
    for (x, y) in ta.iter().flatten().zip(tb.iter().flatten()) {
        assert!(x.distance(*y) < 1e-6, "{x} vs {y}");
    }
}

// ---------------------------------------------------------------------------------------
// The scenes shipped in scenes/.

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

fn toml_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("scenes dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            toml_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "toml") {
            out.push(path);
        }
    }
}

fn load(rel: &str) -> SceneDesc {
    let path = scenes_dir().join(rel);
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_shipped_scene_loads_and_is_well_formed() {
    let mut files = Vec::new();
    toml_files(&scenes_dir(), &mut files);
    assert!(files.len() >= 6, "found only {files:?}");
    for file in files {
        let s = load_scene(&file).unwrap_or_else(|e| panic!("{e}"));
        let what = file.display();
        for shape in &s.shapes {
            match &shape.geometry {
                ShapeGeometry::Triangles {
                    kind: "quad",
                    triangles,
                } => {
                    assert_eq!(triangles.len(), 2, "{what} {}", shape.name);
                    assert!(normal(&triangles[0]).distance(normal(&triangles[1])) < 1e-6);
                }
                ShapeGeometry::Triangles {
                    kind: "box",
                    triangles,
                } => {
                    assert_eq!(triangles.len(), 12);
                    assert_outward(triangles, &format!("{what} {}", shape.name));
                }
                ShapeGeometry::Triangles { triangles, .. } => assert!(!triangles.is_empty()),
                ShapeGeometry::Mesh(m) => assert!(!m.is_empty() && m.indices_in_range()),
                ShapeGeometry::Sphere { radius, .. } => assert!(*radius > 0.0),
            }
        }
        // Every material parses the parameters its built-in type needs.
        for m in &s.materials {
            let p = &m.params;
            match m.type_name.as_str() {
                "diffuse" => {
                    // A colour or a pattern table (scenes/patterns.toml).
                    p.colour_or_pattern("reflectance", Rgb::splat(0.5), [0.0, 1.0])
                        .unwrap();
                }
                "mirror" | "conductor" => {
                    p.rgb("reflectance", Some(Rgb::splat(0.5))).unwrap();
                }
                "dielectric" => {
                    p.f32_where("ior", Some(1.5), "must be > 0", |v| v > 0.0)
                        .unwrap();
                }
                // Index-matched boundaries take no surface parameters.
                "interface" => {}
                // Read by `media_params::subsurface` (whose test parses every shipped one).
                "subsurface" => {}
                // Read by their own parsers (`surface_params`, `rough_params`, which build on
                // this module): `tests/scenes.rs` builds every shipped scene with the
                // built-in registry.
                "plastic" | "rough_plastic" | "thin_dielectric" | "rough_conductor"
                | "rough_dielectric" | "coated_diffuse" | "coated_conductor" => {}
                other => panic!("{what}: unexpected material type {other}"),
            }
            if let Some(interior) = p.table("interior").unwrap() {
                match interior.string("type", None).unwrap().as_str() {
                    "null" => {}
                    "beer" => {
                        interior.rgb("sigma_a", None).unwrap();
                    }
                    "homogeneous" => {
                        assert!(
                            interior.has("sigma_t") || interior.has("sigma_s"),
                            "{what}: a homogeneous interior without coefficients"
                        );
                    }
                    "heterogeneous" => {
                        let density = interior.table("density").unwrap().unwrap();
                        // A pattern density needs no file; a grid density's file is shipped.
                        if density.has("pattern") {
                            interior.pattern("density").unwrap();
                        } else {
                            let grid = density.path("grid").unwrap();
                            assert!(
                                grid.as_ref().is_some_and(|g| g.exists()),
                                "{what}: a heterogeneous interior's grid file is shipped: {grid:?}"
                            );
                        }
                    }
                    other => panic!("{what}: unexpected interior type {other}"),
                }
            }
        }
    }
}

/// The README's box matrices (rows, 6 digits) applied to the cube's corners.
fn readme_box(rows: [[f64; 4]; 3]) -> Vec<Vec3> {
    let mut out = Vec::new();
    for i in 0..8 {
        let c = DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        );
        let p = |r: [f64; 4]| r[0] * c.x + r[1] * c.y + r[2] * c.z + r[3];
        out.push(DVec3::new(p(rows[0]), p(rows[1]), p(rows[2])).as_vec3());
    }
    out
}

const TALL_ROWS: [[f64; 4]; 3] = [
    [0.285317, 0.0, 0.092705, -0.33],
    [0.0, 0.6, 0.0, -0.4],
    [-0.092705, 0.0, 0.285317, -0.28],
];
const SHORT_ROWS: [[f64; 4]; 3] = [
    [0.286891, 0.0, -0.087712, 0.335],
    [0.0, 0.3, 0.0, -0.7],
    [0.087712, 0.0, 0.286891, 0.38],
];

/// The footprint (x, z) corners and y range of a box against the README's list.
fn assert_box(s: &SceneDesc, name: &str, footprint: [(f32, f32); 4], y: (f32, f32)) {
    let verts = distinct_vertices(&triangles(shape(s, name)));
    assert_eq!(verts.len(), 8, "{name}");
    for (lo_hi, yv) in [("bottom", y.0), ("top", y.1)] {
        let layer: Vec<Vec3> = verts
            .iter()
            .filter(|v| (v.y - yv).abs() < 1e-4)
            .map(|v| Vec3::new(v.x, 0.0, v.z))
            .collect();
        let expected: Vec<Vec3> = footprint
            .iter()
            .map(|&(x, z)| Vec3::new(x, 0.0, z))
            .collect();
        assert!(
            same_point_set(&layer, &expected, 1e-4),
            "{name} {lo_hi}: {layer:?} vs {expected:?}"
        );
    }
}

#[test]
fn mitsuba_suite_cornell_matches_the_readme() {
    let s = load("mitsuba-suite/cornell.toml");
    assert_eq!(
        s.render,
        RenderSettings {
            width: 256,
            height: 256,
            spp: 64,
            max_depth: 8,
            seed: 0,
            rr_depth: 5,
            filter: PixelFilter::PIXEL_BOX,
            integrator: risotto_engine::integrator::GlobalIntegrator::Path,
            shading_normals: risotto_engine::scene::ShadingNormals::Consistent,
        }
    );
    assert_eq!(
        s.camera,
        CameraDesc {
            projection: Projection::Perspective { fov_deg: 40.0 },
            from: Vec3::new(0.0, 0.0, 3.9),
            to: Vec3::ZERO,
            up: Vec3::Y
        }
    );
    assert!(s.lights.is_empty());
    // Boxes: README footprint corners and y ranges, and the README matrices.
    assert_box(
        &s,
        "tall_box",
        [
            (-0.708022, -0.472612),
            (-0.137388, -0.658022),
            (0.048022, -0.087388),
            (-0.522612, 0.098022),
        ],
        (-1.0, 0.2),
    );
    assert_box(
        &s,
        "short_box",
        [
            (0.13582, 0.005397),
            (0.709603, 0.18082),
            (0.53418, 0.754603),
            (-0.039603, 0.57918),
        ],
        (-1.0, -0.4),
    );
    for (name, rows) in [("tall_box", TALL_ROWS), ("short_box", SHORT_ROWS)] {
        let tris = triangles(shape(&s, name));
        assert!(
            same_point_set(&distinct_vertices(&tris), &readme_box(rows), 1e-5),
            "{name}"
        );
        assert_outward(&tris, name);
    }
    // Walls: 2 x 2, inward normals as listed in the README.
    let walls = [
        ("floor", Vec3::Y, "white"),
        ("ceiling", Vec3::NEG_Y, "white"),
        ("back", Vec3::Z, "white"),
        ("left_red", Vec3::X, "red"),
        ("right_green", Vec3::NEG_X, "green"),
    ];
    for (name, n, material) in walls {
        let sh = shape(&s, name);
        assert_eq!(s.materials[sh.material].name, material);
        assert_eq!(sh.emission, None);
        let tris = triangles(sh);
        for &t in &tris {
            assert!(normal(&t).distance(n) < 1e-6, "{name}");
        }
        // The wall lies in the plane -n . p = 1 (the cube face opposite its normal).
        let verts = distinct_vertices(&tris);
        assert_eq!(verts.len(), 4);
        for v in &verts {
            assert!((v.dot(n) + 1.0).abs() < 1e-6, "{name} {v}");
            assert!(v.abs().max_element() <= 1.0 + 1e-6);
        }
        let area: f32 = tris
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length())
            .sum();
        assert!((area - 4.0).abs() < 1e-5, "{name} area {area}");
    }
    // Light: 0.5 x 0.5 at y = 0.99 facing down, radiance (17, 12, 4), black material.
    let light = shape(&s, "light");
    assert_eq!(light.emission, Some(Rgb::new(17.0, 12.0, 4.0)));
    let black = &s.materials[light.material];
    assert_eq!(
        (black.name.as_str(), black.type_name.as_str()),
        ("black", "diffuse")
    );
    assert_eq!(black.params.rgb("reflectance", None).unwrap(), Rgb::BLACK);
    let corners: Vec<Vec3> = [(-0.25, -0.25), (0.25, -0.25), (0.25, 0.25), (-0.25, 0.25)]
        .iter()
        .map(|&(x, z)| Vec3::new(x, 0.99, z))
        .collect();
    assert!(same_point_set(
        &distinct_vertices(&triangles(light)),
        &corners,
        1e-6
    ));
    for t in triangles(light) {
        assert!(normal(&t).distance(Vec3::NEG_Y) < 1e-6);
    }
    // Materials as in the XML.
    let refl = |n: &str| {
        let m = s.materials.iter().find(|m| m.name == n).unwrap();
        m.params.rgb("reflectance", None).unwrap()
    };
    assert_eq!(refl("white"), Rgb::new(0.725, 0.71, 0.68));
    assert_eq!(refl("red"), Rgb::new(0.63, 0.065, 0.05));
    assert_eq!(refl("green"), Rgb::new(0.14, 0.45, 0.091));
}

#[test]
fn cornell_box_has_the_suite_geometry() {
    let suite = load("mitsuba-suite/cornell.toml");
    let classic = load("cornell-box.toml");
    assert_eq!((classic.render.width, classic.render.height), (512, 512));
    assert_eq!(classic.render.spp, 64);
    assert_eq!(classic.camera, suite.camera);
    let pairs = [
        ("floor", "floor"),
        ("ceiling", "ceiling"),
        ("back", "back"),
        ("left", "left_red"),
        ("right", "right_green"),
        ("tall_box", "tall_box"),
        ("short_box", "short_box"),
        ("light", "light"),
    ];
    for (a, b) in pairs {
        let (sa, sb) = (shape(&classic, a), shape(&suite, b));
        let (ta, tb) = (triangles(sa), triangles(sb));
        assert!(
            same_point_set(&distinct_vertices(&ta), &distinct_vertices(&tb), 1e-5),
            "{a} vs {b}"
        );
        // Same orientation: compare the (uniform) normal of the first triangles.
        assert!(normal(&ta[0]).distance(normal(&tb[0])) < 1e-5 || sa.name.ends_with("box"));
        assert_eq!(sa.emission, sb.emission);
        assert_eq!(
            classic.materials[sa.material].name,
            suite.materials[sb.material].name
        );
    }
}

#[test]
fn mesh_scene_icosphere_is_a_closed_outward_sphere() {
    let s = load("mesh.toml");
    let ico = shape(&s, "icosphere");
    let tris = triangles(ico);
    assert_eq!(tris.len(), 320);
    let center = Vec3::new(-0.9, 0.7, 0.0);
    let verts = distinct_vertices(&tris);
    assert_eq!(verts.len(), 162);
    for v in &verts {
        assert!((v.distance(center) - 0.7).abs() < 1e-5, "{v}");
    }
    for &t in &tris {
        let c = (t[0] + t[1] + t[2]) / 3.0;
        assert!(normal(&t).dot(c - center) > 0.0);
    }
    // Closed: every edge is shared by exactly two triangles, in opposite directions.
    let key = |v: Vec3| verts.iter().position(|u| u.distance(v) < 1e-5).unwrap();
    let mut edges = std::collections::HashMap::new();
    for t in tris {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((key(a), key(b))).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1);
        assert_eq!(edges.get(&(b, a)), Some(&1));
    }
}

#[test]
fn furnace_and_glass_scenes_have_their_lights() {
    let f = load("furnace.toml");
    assert_eq!(f.render.max_depth, RenderSettings::UNBOUNDED_DEPTH);
    assert!(matches!(
        &f.lights[..],
        [LightDesc::Environment { radiance, map: None, .. }] if *radiance == Rgb::WHITE
    ));
    assert_eq!(
        f.materials[0].params.rgb("reflectance", None).unwrap(),
        Rgb::WHITE
    );
    let g = load("glass-sphere.toml");
    let glass = g.materials.iter().find(|m| m.name == "glass").unwrap();
    assert_eq!(glass.params.f32("ior", None).unwrap(), 1.5);
    match &g.lights[0] {
        LightDesc::Distant { direction, .. } => {
            assert!((direction.length() - 1.0).abs() < 1e-6);
            assert!(direction.distance(Vec3::new(1.0, -2.0, -1.0).normalize()) < 1e-6);
        }
        other => panic!("expected the sun, got {other:?}"),
    }
    let m = load("mirror-spheres.toml");
    assert!(matches!(m.lights[0], LightDesc::Point { .. }));
    assert!(m.shapes.iter().any(|s| s.emission.is_some()));
}

#[test]
fn documented_complete_example_parses() {
    let doc = include_str!("../../../../docs/scene-format.md");
    let section = &doc[doc.find("## Complete example").expect("section")..];
    let start = section.find("```toml\n").expect("toml block") + "```toml\n".len();
    let end = start + section[start..].find("```").expect("closing fence");
    // Parsed as if it lived in scenes/, so its mesh path resolves to the shipped OBJ.
    let path = scenes_dir().join("doc-example.toml");
    let s = parse_scene(&section[start..end], &path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.render.max_depth, RenderSettings::UNBOUNDED_DEPTH);
    assert_eq!(s.shapes.len(), 6);
    assert_eq!(s.lights.len(), 2);
    let glass = s.materials.iter().find(|m| m.name == "glass").unwrap();
    let interior = glass.params.table("interior").unwrap().unwrap();
    assert_eq!(interior.string("type", None).unwrap(), "beer");
    assert_eq!(
        interior.rgb("sigma_a", None).unwrap(),
        Rgb::new(0.1, 0.8, 1.5)
    );
    // The lamp: side 4 centred at (-3, 6, 3) facing the origin.
    let lamp = triangles(shape(&s, "lamp"));
    let centre = distinct_vertices(&lamp).iter().copied().sum::<Vec3>() / 4.0;
    assert!(centre.distance(Vec3::new(-3.0, 6.0, 3.0)) < 1e-5);
    assert!(normal(&lamp[0]).dot(-centre.normalize()) > 0.9999);
}

/// Issue 14 item 6: `spp` above the driver's limit (65536) was accepted, the extra samples
/// repeating the first ones exactly, and `spp = 4294967295` ran forever.
#[test]
fn spp_above_the_sampler_limit_is_rejected() {
    assert_eq!(
        parse(&base_with("spp = 4", "spp = 65536"))
            .unwrap()
            .render
            .spp,
        65536
    );
    for v in ["65537", "4294967295"] {
        let text = base_with("spp = 4", &format!("spp = {v}"));
        let e = parse_err(&text);
        assert_message(&e, line_of(&text, "spp ="), &["spp", "65536"]);
    }
}

/// Issue 14 item 6: 65536 x 65536 was accepted and aborted allocating the film (~730 GB).
/// A resolution past `MAX_PIXELS` is an error at the key, naming the value.
#[test]
fn resolution_past_the_film_bound_is_rejected() {
    let ok = base_with("width = 64\nheight = 48", "width = 8192\nheight = 8192");
    assert_eq!(parse(&ok).unwrap().render.width, 8192);
    let text = base_with("width = 64\nheight = 48", "width = 65536\nheight = 65536");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "height ="),
        &["height", "65536 x 65536", "67108864"],
    );
    let text = base_with("width = 64\nheight = 48", "height = 2048\nwidth = 65536");
    let e = parse_err(&text);
    assert_message(&e, line_of(&text, "height ="), &["height", "65536 x 2048"]);
}

/// `BASE` with a spot light `lamp` (lights[3]) whose body is `body`.
fn with_spot(body: &str) -> String {
    format!("{BASE}\n[[lights]]\nname = \"lamp\"\ntype = \"spot\"\n{body}\n")
}

#[test]
fn spot_light_parses_with_mitsubas_defaults() {
    let s = parse(&with_spot(
        "position = [0, 4, 0]\ndirection = [0, -3, 0]\nintensity = 5",
    ))
    .unwrap();
    assert_eq!(
        s.lights[3],
        LightDesc::Spot {
            name: "lamp".into(),
            position: Vec3::new(0.0, 4.0, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Rgb::splat(5.0),
            cutoff_angle: 20.0,
            beam_width: 15.0,
            texture: None,
        }
    );
    // The axis as a target point; explicit angles (beam = cutoff allowed).
    let s = parse(&with_spot(
        "position = [1, 2, 3]\nto = [1, 2, 5]\nintensity = [1, 2, 3]\ncutoff_angle = 90\nbeam_width = 90",
    ))
    .unwrap();
    assert_eq!(
        s.lights[3],
        LightDesc::Spot {
            name: "lamp".into(),
            position: Vec3::new(1.0, 2.0, 3.0),
            direction: Vec3::Z,
            intensity: Rgb::new(1.0, 2.0, 3.0),
            cutoff_angle: 90.0,
            beam_width: 90.0,
            texture: None,
        }
    );
    assert_eq!(s.lights[3].name(), "lamp");
}

#[test]
fn spot_light_errors_name_file_entity_and_value() {
    let ok = "position = [0, 4, 0]\ndirection = [0, -1, 0]\nintensity = 5";
    // (replacement of one line of `ok` or an added line, the line's key, fragments)
    let cases: &[(&str, &str, &str, &[&str])] = &[
        ("", "cutoff_angle = 0", "cutoff_angle", &["`0`", "(0, 90]"]),
        (
            "",
            "cutoff_angle = 90.5",
            "cutoff_angle",
            &["`90.5`", "(0, 90]"],
        ),
        (
            "",
            "cutoff_angle = -10",
            "cutoff_angle",
            &["`-10`", "(0, 90]"],
        ),
        ("", "beam_width = 0", "beam_width", &["`0`", "(0, 20]"]),
        ("", "beam_width = 25", "beam_width", &["`25`", "(0, 20]"]),
        (
            "",
            "cutoff_angle = 40\nbeam_width = 41",
            "beam_width",
            &["`41`", "(0, 40]"],
        ),
        (
            "direction = [0, -1, 0]",
            "direction = [0, 0, 0]",
            "direction",
            &["[0, 0, 0]", "non-zero"],
        ),
        (
            "direction = [0, -1, 0]",
            "to = [0, 4, 0]",
            "to",
            &["[0, 4, 0]", "differ from `position`"],
        ),
        ("", "to = [0, 0, 0]", "to", &["not both"]),
        (
            "intensity = 5",
            "intensity = [1, -1, 1]",
            "intensity",
            &["[1, -1, 1]", ">= 0"],
        ),
        (
            "intensity = 5",
            "intensity = nan",
            "intensity",
            &["`nan`", "finite"],
        ),
        (
            "intensity = 5",
            "intensity = inf",
            "intensity",
            &["`inf`", "finite"],
        ),
        (
            "intensity = 5",
            "intensity = 2e30",
            "intensity",
            &["`2e30`", "at most 1e30"],
        ),
    ];
    for (from, to, key, fragments) in cases {
        let body = if from.is_empty() {
            format!("{ok}\n{to}")
        } else {
            ok.replace(from, to)
        };
        let text = with_spot(&body);
        let e = parse_err(&text);
        assert_eq!(e.kind(), SceneErrorKind::InvalidValue, "{e}");
        let at = text.rfind(&format!("{key} =")).unwrap();
        let line = text[..at].matches('\n').count() + 1;
        let mut all = vec!["lights[3] \"lamp\"", key];
        all.extend_from_slice(fragments);
        assert_message(&e, line, &all);
    }
    // No axis at all.
    let e = parse_err(&with_spot("position = [0, 4, 0]\nintensity = 5"));
    assert_eq!(e.kind(), SceneErrorKind::MissingField);
    assert!(e.to_string().contains("`direction`"), "{e}");
}
