//! Objects and instances: what they read to, and every error they can give.

use super::*;

/// `BASE` with `extra` appended (objects and instance shapes).
fn with(extra: &str) -> String {
    format!("{BASE}\n{extra}")
}

const OBJECT: &str = r#"
[objects.pebble]
shapes = [
  { name = "stone", type = "box", material = "white", transform = [ { scale = 2 } ] },
  { type = "sphere", center = [0, 1, 0], radius = 0.5, material = "white" },
]
"#;

#[test]
fn objects_and_instances_are_read() {
    let text = with(&format!(
        "{OBJECT}\n[[shapes]]\nname = \"p1\"\ntype = \"instance\"\nobject = \"pebble\"\n\
         transform = [ {{ scale = [1, 2, -1] }}, {{ translate = [4, 0, 0] }} ]\n\n\
         [[shapes]]\ntype = \"instance\"\nobject = \"pebble\"\n"
    ));
    let s = parse(&text).unwrap();
    assert_eq!(s.objects.len(), 1);
    let o = &s.objects[0];
    assert_eq!(o.name, "pebble");
    assert_eq!(o.shapes.len(), 2);
    assert_eq!(o.shapes[0].name, "stone");
    assert_eq!(o.shapes[1].name, "objects.pebble.shapes[1]");
    // The box in object space: its own transform only (a unit box scaled by 2).
    let ShapeGeometry::Triangles { triangles, .. } = &o.shapes[0].geometry else {
        panic!("a box is triangles");
    };
    let hi = triangles.iter().flatten().fold(Vec3::MIN, |a, v| a.max(*v));
    assert_eq!(hi, Vec3::splat(2.0));
    // Instances are not shapes; they keep their names and transforms.
    assert_eq!(s.shapes.len(), 3);
    assert_eq!(s.instances.len(), 2);
    assert_eq!(s.instances[0].name, "p1");
    assert_eq!(s.instances[0].object, 0);
    let p = s.instances[0]
        .transform
        .transform_point3(Vec3::new(1.0, 1.0, 1.0));
    assert_eq!(p, Vec3::new(5.0, 2.0, -1.0));
    assert_eq!(s.instances[1].name, "shapes[4]");
    assert_eq!(s.instances[1].transform, Affine3A::IDENTITY);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn unknown_object_is_located_with_a_suggestion() {
    let text = with(&format!(
        "{OBJECT}\n[[shapes]]\nname = \"p1\"\ntype = \"instance\"\nobject = \"pebbel\"\n"
    ));
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "object = \"pebbel\""),
        &[
            "shapes[3] \"p1\"",
            "unknown object `pebbel`",
            "did you mean `pebble`?",
        ],
    );
    let text = with("[[shapes]]\ntype = \"instance\"\nobject = \"tree\"\n");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "object = \"tree\""),
        &["unknown object `tree`", "no objects are defined"],
    );
}

#[test]
fn unused_object_is_a_warning() {
    let s = parse(&with(OBJECT)).unwrap();
    let line = line_of(&with(OBJECT), "[objects.pebble]");
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(w.contains(&format!("{FILE}:{line}:")), "{w}");
    assert!(w.contains("objects.pebble is never instanced"), "{w}");
}

#[test]
fn empty_object_is_an_error() {
    for body in ["shapes = []", ""] {
        let text = with(&format!("[objects.nothing]\n{body}\n"));
        let e = parse_err(&text);
        assert_message(
            &e,
            line_of(&text, "[objects.nothing]"),
            &["objects.nothing", "an object needs at least one shape"],
        );
    }
}

#[test]
fn nested_instances_are_an_error() {
    let text = with(&format!(
        "{OBJECT}\n[objects.pile]\nshapes = [ {{ type = \"instance\", object = \"pebble\" }} ]\n"
    ));
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "type = \"instance\", object"),
        &[
            "objects.pile.shapes[0]",
            "nested instances are not supported",
        ],
    );
}

#[test]
fn emission_inside_an_object_is_an_error() {
    let text = with(
        "[objects.lamp]\nshapes = [ { type = \"sphere\", center = [0, 0, 0], radius = 1, \
         material = \"white\", emission = 5 } ]\n",
    );
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "[objects.lamp]") + 1,
        &[
            "objects.lamp.shapes[0]",
            "emission",
            "area lights / volumes inside objects are not supported",
            "pbrt-v4 does not support area lights in instances either",
        ],
    );
}

#[test]
fn interior_inside_an_object_is_an_error() {
    // BASE's `glass` has a Beer interior.
    let text = with(
        "[objects.marble]\nshapes = [ { type = \"sphere\", center = [0, 0, 0], radius = 1, \
         material = \"glass\" } ]\n",
    );
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "[objects.marble]") + 1,
        &[
            "objects.marble.shapes[0]",
            "material `glass` has an interior",
            "volumes inside objects are not supported",
        ],
    );
}

#[test]
fn instance_keys_and_object_shape_names_are_checked() {
    let text = with(&format!(
        "{OBJECT}\n[[shapes]]\ntype = \"instance\"\nobject = \"pebble\"\nmaterial = \"white\"\n"
    ));
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "pebble\"\nmaterial = \"white\"") + 1,
        &["unknown field `material`"],
    );
    let text = with(
        "[objects.twins]\nshapes = [\n  { name = \"a\", type = \"sphere\", center = [0, 0, 0], radius = 1, material = \"white\" },\n  { name = \"a\", type = \"sphere\", center = [0, 3, 0], radius = 1, material = \"white\" },\n]\n",
    );
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "[objects.twins]") + 3,
        &["duplicate object shape name `a`"],
    );
    // A singular instance transform.
    let text = with(&format!(
        "{OBJECT}\n[[shapes]]\ntype = \"instance\"\nobject = \"pebble\"\ntransform = [ {{ scale = [1, 0, 1] }} ]\n"
    ));
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "transform = [ { scale = [1, 0, 1]"),
        &["singular"],
    );
}

/// `[[objects.NAME.shapes]]` tables are the same as the inline array.
#[test]
fn object_shapes_as_arrays_of_tables() {
    let text = with(
        "[[objects.rock.shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"white\"\n\n\
         [[objects.rock.shapes]]\ntype = \"box\"\nmaterial = \"white\"\n\n\
         [[shapes]]\ntype = \"instance\"\nobject = \"rock\"\n",
    );
    let s = parse(&text).unwrap();
    assert_eq!(s.objects[0].shapes.len(), 2);
    assert_eq!(s.instances.len(), 1);
}
