//! The importer's features and errors, each on a small scene.

use std::path::{Path, PathBuf};

use super::import;
use crate::import::{ImportOptions, ImportedScene};

mod media;

/// A scene of `body` (inside `<scene>`) with a camera, as text.
fn scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="16"/><rfilter type="box"/></film>
    </sensor>
{body}
</scene>"#
    )
}

fn convert_in(
    dir: &Path,
    name: &str,
    text: &str,
    defines: &[(&str, &str)],
) -> Result<ImportedScene, String> {
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let options = ImportOptions {
        defines: &defines,
        toml_dir: dir,
    };
    import(&dir.join(name), text, &options).map_err(|e| e.to_string())
}

fn convert(text: &str) -> Result<ImportedScene, String> {
    convert_in(Path::new("dir"), "s.xml", text, &[])
}

/// A fresh directory for files of `test`.
fn temp(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("risotto-mitsuba-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn floats(v: &toml::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_float().unwrap())
        .collect()
}

#[test]
fn defaults_are_substituted_and_command_line_definitions_win() {
    let text = r#"<scene version="3.0.0">
    <default name="spp" value="16"/>
    <default name="res" value="24"/>
    <default name="w" value="$res"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="$w"/><integer name="height" value="1$res"/><rfilter type="box"/></film>
    </sensor>
</scene>"#;
    let s = convert(text).unwrap().scene;
    assert_eq!(s.render.table["spp"].as_integer(), Some(16));
    assert_eq!(s.render.table["width"].as_integer(), Some(24));
    assert_eq!(s.render.table["height"].as_integer(), Some(124));
    let s = convert_in(
        Path::new("dir"),
        "s.xml",
        text,
        &[("spp", "3"), ("res", "8")],
    )
    .unwrap()
    .scene;
    assert_eq!(s.render.table["spp"].as_integer(), Some(3));
    assert_eq!(s.render.table["width"].as_integer(), Some(8));
    // An undefined parameter is an error at its attribute.
    let e = convert(&text.replace("$spp", "$nope")).unwrap_err();
    assert!(e.starts_with("dir/s.xml:7:"), "{e}");
    assert!(e.contains("`$nope` is not defined"), "{e}");
}

#[test]
fn includes_are_relative_to_the_including_file_and_loops_are_errors() {
    let d = temp("include");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    std::fs::write(
        d.join("sub/materials.xml"),
        r#"<scene version="3.0.0"><include filename="more.xml"/></scene>"#,
    )
    .unwrap();
    std::fs::write(
        d.join("sub/more.xml"),
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf></scene>"#,
    )
    .unwrap();
    let text = scene(
        r#"<include filename="sub/materials.xml"/>
    <shape type="sphere"><ref id="red"/></shape>"#,
    );
    let s = convert_in(&d, "s.xml", &text, &[]).unwrap().scene;
    assert_eq!(s.materials[0].0, "red");
    assert_eq!(
        floats(&s.materials[0].1.table["reflectance"]),
        [0.8, 0.1, 0.1]
    );
    // The material's origin is the included file.
    let origin = s.materials[0].1.origin.clone().unwrap();
    assert!(origin.file.ends_with("sub/more.xml"), "{origin:?}");
    // A loop: more.xml includes materials.xml again.
    std::fs::write(
        d.join("sub/more.xml"),
        r#"<scene version="3.0.0"><include filename="materials.xml"/></scene>"#,
    )
    .unwrap();
    let e = convert_in(&d, "s.xml", &text, &[]).unwrap_err();
    assert!(e.contains("include loop"), "{e}");
    assert!(e.contains("more.xml:1:"), "{e}");
    // A missing file.
    let e = convert_in(
        &d,
        "s.xml",
        &scene(r#"<include filename="nope.xml"/>"#),
        &[],
    )
    .unwrap_err();
    assert!(e.contains("s.xml:7:") && e.contains("nope.xml"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn references_nested_objects_and_missing_references() {
    let s = convert(&scene(
        r#"<bsdf type="diffuse" id="grey"/>
    <shape type="sphere" id="a"><ref id="grey"/></shape>
    <shape type="sphere" id="b"><ref id="grey"/><float name="radius" value="2"/></shape>
    <shape type="sphere" id="c"><bsdf type="dielectric"/></shape>
    <shape type="sphere" id="d"/>"#,
    ))
    .unwrap()
    .scene;
    let names: Vec<&str> = s.materials.iter().map(|(n, _)| n.as_str()).collect();
    // One material per distinct BSDF; a shape without one gets Mitsuba's default diffuse.
    assert_eq!(names, ["grey", "c", "default"]);
    assert_eq!(s.shapes[1].table["material"].as_str(), Some("grey"));
    assert_eq!(s.shapes[1].table["radius"].as_float(), Some(2.0));
    assert_eq!(s.materials[0].1.table["reflectance"].as_float(), Some(0.5));
    assert_eq!(
        s.materials[1].1.table["ior"].as_float(),
        Some(1.5046 / 1.000277)
    );
    let e = convert(&scene(
        r#"<shape type="sphere"><ref id="nothing"/></shape>"#,
    ))
    .unwrap_err();
    assert!(
        e.starts_with("dir/s.xml:7:") && e.contains("<ref id=\"nothing\"> names no element"),
        "{e}"
    );
    let e = convert(&scene(
        r#"<bsdf type="diffuse" id="x"/><bsdf type="diffuse" id="x"/>"#,
    ))
    .unwrap_err();
    assert!(e.contains("id \"x\" is already used"), "{e}");
}

#[test]
fn transforms_compose_in_document_order_as_hand_computed() {
    use glam::{DMat4, DVec3};
    let s = convert(&scene(
        r#"<shape type="sphere">
        <float name="radius" value="0.5"/>
        <point name="center" x="1" y="0" z="0"/>
        <transform name="to_world">
            <scale value="2"/>
            <translate x="1" y="2" z="3"/>
        </transform>
    </shape>
    <emitter type="directional">
        <transform name="to_world"><rotate y="1" angle="90"/><rotate x="1" angle="90"/></transform>
    </emitter>"#,
    ))
    .unwrap()
    .scene;
    // center (1, 0, 0) -> scale 2 -> (2, 0, 0) -> + (1, 2, 3) -> (3, 2, 3); radius 0.5 * 2.
    assert_eq!(floats(&s.shapes[0].table["center"]), [3.0, 2.0, 3.0]);
    assert_eq!(s.shapes[0].table["radius"].as_float(), Some(1.0));
    // +z -> R_y(90) (x' = x cos a + z sin a, z' = -x sin a + z cos a) -> +x -> R_x(90) -> +x;
    // in the other order it would be -y.
    let d = floats(&s.lights[0].table["direction"]);
    for (a, b) in d.iter().zip([1.0, 0.0, 0.0]) {
        assert!((a - b).abs() < 1e-12, "{d:?}");
    }
    // Each operation by itself, against its matrix.
    let read = |ops: &str| {
        let s = convert(&scene(&format!(
            r#"<shape type="cube"><transform name="to_world">{ops}</transform></shape>"#
        )))
        .unwrap()
        .scene;
        s.shapes[0].table["transform"].clone()
    };
    let t = read(r#"<matrix value="1 0 0 4  0 2 0 5  0 0 3 6  0 0 0 1"/>"#);
    assert_eq!(
        t.to_string(),
        "[{ matrix = [[1.0, 0.0, 0.0, 4.0], [0.0, 2.0, 0.0, 5.0], [0.0, 0.0, 3.0, 6.0]] }]"
    );
    let t = read(r#"<lookat origin="1, 2, 3" target="1, 2, 4" up="0, 1, 0"/><scale x="2"/>"#);
    assert_eq!(
        t.to_string(),
        "[{ look_at = { from = [1.0, 2.0, 3.0], to = [1.0, 2.0, 4.0], up = [0.0, 1.0, 0.0] } }, { scale = [2.0, 1.0, 1.0] }]"
    );
    // The composed matrix of a look-at: +x to up x dir (the left), +z to dir, origin to origin.
    let cx = super::values::Cx {
        doc: super::xml::load(
            Path::new("t.xml"),
            r#"<scene version="3.0.0"><transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 4" up="0, 1, 0"/><translate x="1"/></transform></scene>"#,
            &[],
        )
        .unwrap(),
        warnings: Default::default(),
    };
    let node = cx.doc.root.children[0].clone();
    let t = super::transform::Transform::read(&cx, &node, "t").unwrap();
    let expected = DMat4::from_translation(DVec3::X)
        * DMat4::from_cols(
            glam::DVec4::new(1.0, 0.0, 0.0, 0.0),
            glam::DVec4::new(0.0, 1.0, 0.0, 0.0),
            glam::DVec4::new(0.0, 0.0, 1.0, 0.0),
            glam::DVec4::new(1.0, 2.0, 3.0, 1.0),
        );
    assert!(t.matrix.abs_diff_eq(expected, 1e-12), "{}", t.matrix);
    // Errors: a non-unit axis, a projective matrix, an unknown operation.
    for (ops, msg) in [
        (r#"<rotate x="1" y="1" angle="3"/>"#, "not of unit length"),
        (
            r#"<matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1"/>"#,
            "last row",
        ),
        (r#"<shear value="1"/>"#, "not a transform operation"),
        (r#"<rotate x="1"/>"#, "needs an `angle`"),
    ] {
        let e = convert(&scene(&format!(
            r#"<shape type="cube"><transform name="to_world">{ops}</transform></shape>"#
        )))
        .unwrap_err();
        assert!(
            e.starts_with("dir/s.xml:7:") && e.contains(msg),
            "{ops}: {e}"
        );
    }
    // A sphere turned or stretched cannot be written.
    let e = convert(&scene(
        r#"<shape type="sphere"><transform name="to_world"><scale x="2"/></transform></shape>"#,
    ))
    .unwrap_err();
    assert!(e.contains("uniform scale and translation"), "{e}");
}

#[test]
fn field_of_view_follows_fov_axis_and_the_50mm_default_as_mitsuba() {
    // Values printed by Mitsuba 3.9.1 (`mi.traverse(sensor)['x_fov']`).
    let fov = |params: &str, w: u32, h: u32| {
        let text = format!(
            r#"<scene version="3.0.0"><sensor type="perspective">{params}
            <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/><rfilter type="box"/></film>
            </sensor></scene>"#
        );
        convert(&text).unwrap().scene.camera.table["fov"]
            .as_float()
            .unwrap()
    };
    for (axis, w, h, expected) in [
        ("x", 200, 100, 40.0),
        ("y", 200, 100, 72.10477447509766),
        ("y", 100, 200, 20.628210067749023),
        ("diagonal", 200, 100, 36.064788818359375),
        ("diagonal", 100, 200, 18.49018669128418),
        ("smaller", 200, 100, 72.10477447509766),
        ("smaller", 100, 200, 40.0),
        ("larger", 200, 100, 40.0),
        ("larger", 100, 200, 20.628210067749023),
    ] {
        let p =
            format!(r#"<float name="fov" value="40"/><string name="fov_axis" value="{axis}"/>"#);
        let f = fov(&p, w, h);
        assert!(
            (f - expected).abs() < 1e-4,
            "{axis} {w}x{h}: {f} vs {expected}"
        );
    }
    assert!((fov("", 200, 100) - 42.31171417236328).abs() < 1e-4);
    let f = fov(r#"<string name="focal_length" value="28mm"/>"#, 100, 100);
    assert!((f - 57.29763412475586).abs() < 1e-4, "{f}");
}

#[test]
fn spectra_in_a_scene_convert_by_their_use() {
    let s = convert(&scene(
        r#"<shape type="sphere">
        <bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1, 500:0.5, 700:0.9"/></bsdf>
        <emitter type="area"><spectrum name="radiance" value="400:0.1, 500:0.5, 700:0.9"/></emitter>
    </shape>
    <emitter type="point"><spectrum name="intensity" value="0.5"/><point name="position" x="0" y="3" z="0"/></emitter>"#,
    ))
    .unwrap()
    .scene;
    // Mitsuba 3.9.1's values (see spectrum.rs).
    let close_within = |v: &toml::Value, e: [f64; 3], tol: f64| {
        floats(v)
            .iter()
            .zip(e)
            .all(|(a, b)| (a - b).abs() < tol * b)
    };
    let close = |v: &toml::Value, e: [f64; 3]| close_within(v, e, 5e-5);
    assert!(close(
        &s.materials[0].1.table["reflectance"],
        [0.775405, 0.593508, 0.277033]
    ));
    assert!(close(
        &s.shapes[0].table["emission"],
        [0.917922, 0.565488, 0.241605]
    ));
    // Mitsuba turns a uniform emitted spectrum into RGB by another route than a sampled
    // one (we use the sampled route for both): they agree within 4e-4.
    let i = &s.lights[0].table["intensity"];
    assert!(close_within(i, [0.602397, 0.474146, 0.454458], 5e-4), "{i}");
}

#[test]
fn unsupported_plugins_values_and_parameters_are_located_errors() {
    for (body, line, msg) in [
        (r#"<shape type="sphere"><bsdf type="hair"/></shape>"#, 7, "bsdf type \"hair\" is not supported"),
        (r#"<shape type="teapot"/>"#, 7, "shape type \"teapot\" is not supported"),
        (r#"<emitter type="sunsky"/>"#, 7, "emitter type \"sunsky\" is not supported"),
        (r#"<shape type="sphere"><float name="radius" value="big"/></shape>"#, 7, "`big` is not a finite number"),
        (r#"<shape type="sphere"><float name="radios" value="1"/></shape>"#, 7, "parameter `radios` of shape (sphere) is not supported"),
        (r#"<shape type="sphere"><string name="radius" value="1"/></shape>"#, 7, "must be a <float>"),
        ("<shape type=\"sphere\">\n<bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"glass\"/></bsdf></shape>", 8, "one of Mitsuba's named indices"),
        (r#"<shape type="cube"><medium type="homogeneous" name="exterior"/></shape>"#, 7, "this exterior medium is not the interior of any shape"),
        (r#"<integrator type="bdpt"/>"#, 7, "integrator type \"bdpt\" is not supported"),
        (r#"<shape type="rectangle"><bsdf type="twosided"><bsdf type="dielectric"/></bsdf></shape>"#, 7, "twosided around"),
    ] {
        let e = convert(&scene(body)).unwrap_err();
        assert!(e.starts_with(&format!("dir/s.xml:{line}:")), "{body}: {e}");
        assert!(e.contains(msg), "{body}: {e}");
    }
    // Old (Mitsuba 0.6) and missing versions, syntax errors.
    let e = convert(r#"<scene version="0.6.0"/>"#).unwrap_err();
    assert!(e.contains("Mitsuba 0.6 scene"), "{e}");
    let e = convert("<scene>").unwrap_err();
    assert!(e.contains("XML syntax error"), "{e}");
    let e = convert("<scene/>").unwrap_err();
    assert!(e.contains("no version attribute"), "{e}");
}

#[test]
fn bsdfs_map_to_risotto_materials() {
    let s = convert(&scene(
        r#"<shape type="sphere"><bsdf type="roughconductor"><string name="material" value="Au"/><float name="alpha" value="0.2"/></bsdf></shape>
    <shape type="sphere"><bsdf type="twosided"><bsdf type="roughplastic"><string name="distribution" value="ggx"/></bsdf></bsdf></shape>
    <shape type="rectangle"><bsdf type="mask"><float name="opacity" value="0.25"/><bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf></bsdf></shape>
    <shape type="sphere"><bsdf type="conductor"/></shape>
    <shape type="sphere"><bsdf type="plastic"><string name="int_ior" value="water"/></bsdf></shape>"#,
    ))
    .unwrap()
    .scene;
    let t = |i: usize| &s.materials[i].1.table;
    assert_eq!(t(0)["type"].as_str(), Some("rough_conductor"));
    assert_eq!(
        t(0)["distribution"].as_str(),
        Some("beckmann"),
        "Mitsuba's default"
    );
    assert_eq!(t(0)["energy_compensation"].as_bool(), Some(false));
    assert_eq!(t(1)["type"].as_str(), Some("rough_plastic"));
    assert!(!t(1).contains_key("distribution"));
    assert_eq!(t(1)["two_sided"].as_bool(), Some(true));
    assert_eq!(t(2)["opacity"].as_float(), Some(0.25));
    let checker = t(2)["reflectance"].as_table().unwrap();
    assert_eq!(checker["pattern"].as_str(), Some("checker"));
    assert_eq!(checker["scale"].as_float(), Some(2.0));
    assert_eq!(floats(&checker["a"]), [0.4; 3]);
    assert_eq!(t(3)["type"].as_str(), Some("conductor"));
    assert_eq!(t(4)["int_ior"].as_float(), Some(1.333));
    assert_eq!(t(4)["ext_ior"].as_float(), Some(1.000277));
}

#[test]
fn blendbsdf_becomes_a_mix_of_its_two_bsdfs() {
    let s = convert(&scene(
        r#"<bsdf type="diffuse" id="matte"><rgb name="reflectance" value="0.8"/></bsdf>
    <shape type="sphere"><bsdf type="blendbsdf" id="blend"><float name="weight" value="0.3"/>
        <ref id="matte"/><bsdf type="conductor"/></bsdf></shape>
    <shape type="sphere"><ref id="matte"/></shape>"#,
    ))
    .unwrap()
    .scene;
    let by_name = |n: &str| &s.materials.iter().find(|(m, _)| m == n).unwrap().1.table;
    let mix = &s.shapes[0].table["material"];
    let mix = by_name(mix.as_str().unwrap());
    assert_eq!(mix["type"].as_str(), Some("mix"));
    assert_eq!(mix["amount"].as_float(), Some(0.3));
    assert_eq!(mix["a"].as_str(), Some("matte"));
    assert_eq!(
        by_name(mix["b"].as_str().unwrap())["type"].as_str(),
        Some("conductor")
    );
    // The plain use of the first BSDF shares its material.
    assert_eq!(s.shapes[1].table["material"].as_str(), Some("matte"));
    let e = convert(&scene(
        r#"<shape type="sphere"><bsdf type="blendbsdf"><float name="weight" value="0.3"/><bsdf type="diffuse"/></bsdf></shape>"#,
    ))
    .unwrap_err();
    assert!(e.contains("blends two nested BSDFs"), "{e}");
}

#[test]
fn aov_wrappers_are_unwrapped_with_a_warning_and_path_with_media_warns() {
    let out = convert(&scene(
        r#"<integrator type="aov"><string name="aovs" value="dd.y:depth"/><integrator type="path"><integer name="max_depth" value="4"/></integrator></integrator>
    <shape type="sphere"><bsdf type="null"/><medium type="homogeneous" name="interior"><float name="sigma_t" value="1"/></medium></shape>"#,
    ))
    .unwrap();
    assert_eq!(out.scene.render.table["max_depth"].as_integer(), Some(4));
    assert!(
        out.warnings.iter().any(|w| w.contains("only adds outputs")),
        "{:?}",
        out.warnings
    );
    assert!(
        out.warnings.iter().any(|w| w.contains("ignores media")),
        "{:?}",
        out.warnings
    );
    let interior = out.scene.materials[0].1.table["interior"]
        .as_table()
        .unwrap();
    assert_eq!(interior["sigma_t"].as_float(), Some(1.0));
    assert_eq!(
        interior["albedo"].as_float(),
        Some(0.75),
        "Mitsuba's default albedo"
    );
}

#[test]
fn comments_with_double_hyphens_are_read_as_mitsuba_reads_them() {
    let s = convert(&scene("<!-- a -- b --->\n<shape type=\"sphere\"/>"))
        .unwrap()
        .scene;
    assert_eq!(s.shapes.len(), 1);
}

#[test]
fn clip_planes_filters_and_sensor_media_are_stated() {
    // A shape nearer than near_clip: Mitsuba cuts it, risotto does not: a warning.
    let text = scene(r#"<shape type="sphere"><point name="center" x="0" y="0" z="4.5"/><float name="radius" value="0.2"/></shape>"#)
        .replace(r#"<float name="fov" value="40"/>"#, r#"<float name="fov" value="40"/><float name="near_clip" value="0.5"/>"#);
    let out = convert(&text).unwrap();
    assert!(
        out.warnings
            .iter()
            .any(|w| w.contains("closer to the camera than near_clip")),
        "{:?}",
        out.warnings
    );
    // Far enough: no warning.
    let out = convert(&text.replace(r#"z="4.5""#, r#"z="0""#)).unwrap();
    assert!(out.warnings.is_empty(), "{:?}", out.warnings);
    // No rfilter is Mitsuba's Gaussian; a tent keeps its radius.
    let gaussian = convert(&scene("").replace(r#"<rfilter type="box"/>"#, ""))
        .unwrap()
        .scene;
    assert_eq!(gaussian.render.table["filter"].as_str(), Some("gaussian"));
    let tent = convert(&scene("").replace(
        r#"<rfilter type="box"/>"#,
        r#"<rfilter type="tent"><float name="radius" value="1.5"/></rfilter>"#,
    ))
    .unwrap()
    .scene;
    assert_eq!(tent.render.table["filter"].as_str(), Some("tent"));
    assert_eq!(tent.render.table["filter_radius"].as_float(), Some(1.5));
    let box_ = convert(&scene("")).unwrap().scene;
    assert!(!box_.render.table.contains_key("filter"));
    // A camera in a medium no shape bounds: an error saying what to do.
    let e = convert(&scene("").replace(
        "</sensor>",
        r#"<medium type="homogeneous" name="medium"/></sensor>"#,
    ))
    .unwrap_err();
    assert!(
        e.contains("the sensor's medium is not the interior of any shape"),
        "{e}"
    );
    // A cropped film is an error.
    let e = convert(&scene("").replace(
        r#"<rfilter type="box"/>"#,
        r#"<rfilter type="box"/><integer name="crop_width" value="4"/>"#,
    ))
    .unwrap_err();
    assert!(e.contains("cropped film"), "{e}");
}

#[test]
fn sensor_and_exterior_media_become_within_checks() {
    // A fog box holding the camera (by reference) and a glass ball bordered by the fog; the
    // second box holds the same medium; the ball without an id gets a name.
    let body = r#"
<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="0.1"/></medium>
<shape type="cube" id="box"><bsdf type="null"/><ref id="fog" name="interior"/>
    <transform name="to_world"><scale value="8"/></transform></shape>
<shape type="cube" id="box2"><bsdf type="null"/><ref id="fog" name="interior"/>
    <transform name="to_world"><translate value="30, 0, 0"/></transform></shape>
<shape type="sphere"><bsdf type="dielectric"/><ref id="fog" name="exterior"/></shape>"#;
    let text = scene(body).replace("</sensor>", r#"<ref id="fog" name="medium"/></sensor>"#);
    let s = convert(&text).unwrap().scene;
    let names = |v: &toml::Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap().to_owned())
            .collect()
    };
    assert_eq!(names(&s.camera.table["within"]), ["box", "box2"]);
    let ball = &s.shapes[2].table;
    assert_eq!(ball["name"].as_str(), Some("sphere at line 13"));
    assert_eq!(names(&ball["within"]), ["box", "box2"]);
    // A shape that holds the medium but states no exterior is stated to be in no medium
    // (Mitsuba: vacuum outside it); so is a camera without a sensor medium, when the scene
    // has media (tests/within.rs has the checks themselves).
    assert_eq!(s.shapes[0].table["within"].as_str(), Some("no medium"));
    let unset = convert(&scene(body)).unwrap().scene;
    assert_eq!(unset.camera.table["within"].as_str(), Some("no medium"));
    // An exterior in a shapegroup cannot be placed.
    let group = r#"
<medium type="homogeneous" id="fog"/>
<shape type="cube"><bsdf type="null"/><ref id="fog" name="interior"/></shape>
<shape type="shapegroup" id="g"><shape type="sphere"><ref id="fog" name="exterior"/></shape></shape>"#;
    let e = convert(&scene(group)).unwrap_err();
    assert!(
        e.contains("shapegroup cannot state an exterior medium"),
        "{e}"
    );
}

#[test]
fn roughness_textures_become_roughness_patterns() {
    let s = convert(&scene(
        r#"<shape type="sphere"><bsdf type="roughconductor"><texture type="checkerboard" name="alpha"><float name="color0" value="0.1"/><float name="color1" value="0.4"/></texture></bsdf></shape>
    <shape type="sphere"><bsdf type="roughdielectric"><float name="alpha_u" value="0.3"/><texture type="bitmap" name="alpha_v"><string name="filename" value="rough.png"/></texture></bsdf></shape>
    <shape type="sphere"><bsdf type="roughplastic"><texture type="checkerboard" name="alpha"/></bsdf></shape>"#,
    ))
    .unwrap()
    .scene;
    let t = |i: usize| &s.materials[i].1.table;
    let checker = t(0)["alpha"].as_table().unwrap();
    assert_eq!(checker["pattern"].as_str(), Some("checker"));
    // Read as a float (Mitsuba's `eval_1`), a checkerboard's colours are the other way
    // round from a colour checkerboard's (`float_texture`).
    assert_eq!(floats(&checker["a"]), [0.4; 3]);
    assert_eq!(floats(&checker["b"]), [0.1; 3]);
    assert_eq!(t(1)["alpha_u"].as_float(), Some(0.3));
    let image = t(1)["alpha_v"].as_table().unwrap();
    assert_eq!(image["pattern"].as_str(), Some("image"));
    assert!(image["path"].as_str().unwrap().ends_with("rough.png"));
    assert_eq!(t(2)["alpha"]["pattern"].as_str(), Some("checker"));
    // Every Mitsuba microfacet lobe uses the separable masking-shadowing function.
    for i in 0..3 {
        assert_eq!(t(i)["masking"].as_str(), Some("separable"));
    }
}

#[test]
fn meshes_are_imported_without_the_shadow_terminator_offset() {
    let s = convert(&scene(
        r#"<shape type="obj"><string name="filename" value="m.obj"/></shape>"#,
    ))
    .unwrap()
    .scene;
    let t = &s.shapes[0].table;
    assert_eq!(t["type"].as_str(), Some("mesh"));
    assert_eq!(
        t["shadow_terminator_offset"].as_bool(),
        Some(false),
        "as Mitsuba"
    );
}

/// Mitsuba reads an OBJ's texture coordinates as `(u, 1 - v)` unless `flip_tex_coords` is
/// false, a PLY's as stored unless it is true (checked with Mitsuba 3.9.1's own loaders).
#[test]
fn obj_texture_coordinates_are_flipped_as_mitsuba_flips_them() {
    let body = r#"
<shape type="obj"><string name="filename" value="a.obj"/></shape>
<shape type="obj"><string name="filename" value="b.obj"/><boolean name="flip_tex_coords" value="false"/></shape>
<shape type="ply"><string name="filename" value="c.ply"/></shape>
<shape type="ply"><string name="filename" value="d.ply"/><boolean name="flip_tex_coords" value="true"/></shape>"#;
    let s = convert(&scene(body)).unwrap().scene;
    let flipped: Vec<bool> = s
        .shapes
        .iter()
        .map(|shape| shape.table.get("flip_tex_coords").and_then(|v| v.as_bool()) == Some(true))
        .collect();
    assert_eq!(flipped, [true, false, false, true]);
}

#[test]
fn bitmap_to_uv_wrap_and_filter_become_the_image_lookup() {
    // Mitsuba composes `scale` then `translate`: u' = 2 u - 0.5 (its texture_interp scene).
    let s = convert(&scene(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><transform name="to_uv"><scale value="2"/><translate value="-.5,-.5, 0"/></transform><string name="filename" value="c.png"/><string name="wrap_mode" value="mirror"/><string name="filter_type" value="nearest"/></texture></bsdf></shape>"#,
    ))
    .unwrap()
    .scene;
    let image = s.materials[0].1.table["reflectance"].as_table().unwrap();
    assert_eq!(image["wrap"].as_str(), Some("mirror"));
    assert_eq!(image["filter"].as_str(), Some("nearest"));
    let uv = image["uv_transform"].as_table().unwrap();
    assert_eq!(floats(&uv["u"]), [2.0, 0.0, -0.5]);
    assert_eq!(floats(&uv["v"]), [0.0, 2.0, -0.5]);
    // A checkerboard takes a uniform scale only; an unknown wrap mode is an error.
    for bad in [
        r#"<texture type="checkerboard" name="reflectance"><transform name="to_uv"><translate x="0.5"/></transform></texture>"#,
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="c.png"/><string name="wrap_mode" value="zero"/></texture>"#,
    ] {
        let text = format!(r#"<shape type="sphere"><bsdf type="diffuse">{bad}</bsdf></shape>"#);
        let e = convert(&scene(&text)).unwrap_err();
        assert!(e.contains("to_uv") || e.contains("wrap_mode"), "{e}");
    }
}

#[test]
fn thin_dielectrics_pass_as_null_events_under_the_volumetric_integrators() {
    // Mitsuba flags a thindielectric's transmission `Null`: volpath and volpathmis (also
    // inside a moment wrapper) do not count it as a bounce, path does.
    let pane = r#"<shape type="rectangle"><bsdf type="thindielectric"/></shape>"#;
    for (integrator, null) in [
        ("", false),
        (r#"<integrator type="path"/>"#, false),
        (r#"<integrator type="volpath"/>"#, true),
        (
            r#"<integrator type="moment"><integrator type="volpathmis"/></integrator>"#,
            true,
        ),
    ] {
        let s = convert(&scene(&format!("{integrator}{pane}")))
            .unwrap()
            .scene;
        let t = &s.materials[0].1.table;
        assert_eq!(t["type"].as_str(), Some("thin_dielectric"));
        assert_eq!(
            t.get("null_transmission").and_then(|v| v.as_bool()),
            null.then_some(true),
            "{integrator}"
        );
    }
}
