//! Mitsuba 3 XML scenes through the driver (issue 33): `risotto convert X.xml OUT.toml`
//! then `risotto render OUT.toml` gives the same bits as `risotto render X.xml`, with the
//! conversion beside the scene or in another directory (paths rewritten), and `-D`
//! definitions reach the XML. The images against Mitsuba's own renders are checked in
//! `tests/mitsuba_reference.rs` (the `*_xml_*` tests).

use std::path::{Path, PathBuf};

mod common;
use common::cli::{assert_fails, ok, risotto};
use risotto::engine::output::read_exr_rgb;

fn setup(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("import-mitsuba-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The beauty's pixels as bits.
fn bits(path: &Path) -> Vec<[u32; 3]> {
    let img = read_exr_rgb(path).unwrap();
    let mut v = Vec::new();
    for y in 0..img.height {
        for x in 0..img.width {
            v.push(img.get(x, y).to_array().map(f32::to_bits));
        }
    }
    v
}

fn render(scene: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
        "-t",
        "1",
        "--size",
        "24x24",
        "--spp",
        "2",
        "--no-preview",
    ];
    args.extend_from_slice(extra);
    ok(&format!("render {}", scene.display()), risotto(&args));
}

fn suite(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/mitsuba-suite")
        .join(name)
}

#[test]
fn convert_then_render_is_render_of_the_xml_bit_for_bit() {
    let dir = setup("roundtrip");
    // hetero_grid names a grid file, spot_texture a texture: their paths must be
    // rewritten for a conversion in another directory.
    for scene in ["cornell.xml", "hetero_grid.xml", "spot_texture.xml"] {
        let xml = suite(scene);
        let direct = dir.join(format!("{scene}.exr"));
        render(&xml, &direct, &[]);
        let toml = dir.join(format!("{scene}.toml"));
        ok(
            "convert",
            risotto(&["convert", xml.to_str().unwrap(), toml.to_str().unwrap()]),
        );
        let converted = dir.join(format!("{scene}-converted.exr"));
        render(&toml, &converted, &[]);
        assert!(bits(&direct) == bits(&converted), "{scene}: images differ");
    }
}

#[test]
fn definitions_reach_the_xml_and_dotted_ones_the_conversion() {
    let dir = setup("defines");
    let xml = suite("cornell.xml");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    // `max_depth` is the XML's <default>; `render.max_depth` overrides the converted TOML.
    render(&xml, &a, &["-D", "max_depth=2"]);
    render(&xml, &b, &["-D", "render.max_depth=2"]);
    assert!(bits(&a) == bits(&b));
    let c = dir.join("c.exr");
    render(&xml, &c, &[]);
    assert!(bits(&a) != bits(&c), "max_depth 2 and 8 rendered the same");
    // An error in the XML names the XML file and line.
    let bad = dir.join("bad.xml");
    std::fs::write(
        &bad,
        std::fs::read_to_string(&xml)
            .unwrap()
            .replace("type=\"diffuse\" id=\"red\"", "type=\"hair\" id=\"red\""),
    )
    .unwrap();
    let out = risotto(&["render", bad.to_str().unwrap(), "-o", c.to_str().unwrap()]);
    assert_fails(
        "hair",
        &out,
        &["bad.xml:39:5:", "bsdf type \"hair\" is not supported"],
    );
}

/// `shapegroup` / `instance` become a TOML object and its instances: the instanced scene
/// renders as the same shapes written out in place (block z-test, independent seeds), and
/// its conversion holds one object and three instances.
#[test]
fn shapegroups_render_as_their_copies() {
    let dir = setup("shapegroups");
    let head = r#"<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 2, 8" target="0, 0.5, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/>
      <rfilter type="box"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
  <emitter type="directional"><vector name="direction" value="-1, -3, -2"/><rgb name="irradiance" value="2"/></emitter>
  <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7"/></bsdf>
"#;
    let shapes = r#"<shape type="cube"><transform name="to_world"><scale value="0.4"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><translate y="-0.4"/></transform><ref id="white"/></shape>"#;
    let placements = [
        r#"<translate x="-1.5"/>"#,
        r#"<rotate y="1" angle="30"/><translate z="-1"/>"#,
        r#"<scale x="1" y="1.5" z="1"/><translate x="1.5"/>"#,
    ];
    let mut instanced =
        format!("{head}  <shape type=\"shapegroup\" id=\"thing\">{shapes}</shape>\n");
    let mut copies = head.to_string();
    for p in placements {
        instanced.push_str(&format!(
            "  <shape type=\"instance\"><ref id=\"thing\"/><transform name=\"to_world\">{p}</transform></shape>\n"
        ));
        // The same shapes with the placement appended to each one's own to_world.
        copies.push_str(&shapes.replace("</transform>", &format!("{p}</transform>")));
        copies.push('\n');
    }
    instanced.push_str("</scene>\n");
    copies.push_str("</scene>\n");
    let (a, b) = (dir.join("instanced.xml"), dir.join("copies.xml"));
    std::fs::write(&a, instanced).unwrap();
    std::fs::write(&b, copies).unwrap();

    let converted = dir.join("instanced.toml");
    ok(
        "convert",
        risotto(&["convert", a.to_str().unwrap(), converted.to_str().unwrap()]),
    );
    let toml = std::fs::read_to_string(&converted).unwrap();
    assert_eq!(toml.matches("[objects.thing]").count(), 1, "{toml}");
    assert_eq!(toml.matches("type = \"instance\"").count(), 3, "{toml}");

    let render = |path: &Path, seed: u64| {
        let mut desc = risotto::loader::scene_file::load_scene(path).unwrap();
        desc.render.seed = seed;
        let scene = risotto::loader::load::scene_from_desc(
            desc,
            &risotto::loader::load::MaterialRegistry::with_builtins(),
        )
        .unwrap()
        .compile()
        .unwrap();
        let options = risotto::engine::render::RenderOptions {
            threads: Some(2),
            ..Default::default()
        };
        risotto::engine::render::render(&scene, &options, &|_| {}).unwrap()
    };
    let z = common::images::block_z(&render(&a, 1), &render(&b, 2));
    let max = z.iter().fold(0.0f64, |m, &v| m.max(v.abs()));
    assert!(max < 4.5, "max |z| = {max}");
}

/// A group may not hold what an object cannot: an area light inside is a located error.
#[test]
fn an_emitting_shape_in_a_shapegroup_is_an_error() {
    let dir = setup("shapegroup-emitter");
    let xml = dir.join("s.xml");
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/></sensor>
  <shape type="shapegroup" id="g">
    <shape type="cube"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
  </shape>
  <shape type="instance"><ref id="g"/></shape>
</scene>
"#,
    )
    .unwrap();
    let o = risotto(&[
        "convert",
        xml.to_str().unwrap(),
        dir.join("o.toml").to_str().unwrap(),
    ]);
    assert_fails("emitter in a group", &o, &["s.xml:3", "emission"]);
}
