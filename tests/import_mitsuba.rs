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
