//! `[render] shading_normals`: the default, every name, and located errors.

use super::*;
use risotto_engine::scene::ShadingNormals;

fn with_shading_normals(line: &str) -> String {
    base_with("spp = 4", &format!("spp = 4\n{line}"))
}

#[test]
fn shading_normals_default_to_consistent_and_read_every_name() {
    assert_eq!(
        parse(BASE).unwrap().render.shading_normals,
        ShadingNormals::Consistent
    );
    for t in ShadingNormals::ALL {
        let text = with_shading_normals(&format!("shading_normals = \"{}\"", t.name()));
        assert_eq!(
            parse(&text).unwrap().render.shading_normals,
            t,
            "{}",
            t.name()
        );
    }
}

#[test]
fn unknown_shading_normals_are_a_located_error_naming_the_value_and_the_choices() {
    let text = with_shading_normals("shading_normals = \"mitsuba\"");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "shading_normals = \"mitsuba\""),
        &[
            "shading_normals",
            "`\"mitsuba\"`",
            "consistent",
            "shading_frame",
        ],
    );
    let text = with_shading_normals("shading_normals = true");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "shading_normals = true"),
        &["shading_normals"],
    );
}
