//! The spot light's projection texture (issue 32): located errors for what cannot orient or
//! read it. Its image is checked against Mitsuba in `tests/mitsuba_reference.rs`.

use std::path::Path;

mod common;
use common::cli::{assert_fails, risotto, SCENE};

#[test]
fn bad_spot_textures_are_located_errors() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("spot-texture");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let png = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba-suite/spot_texture.png");
    let spot = |extra: &str| {
        format!(
            "[[lights]]\nname = \"spot\"\ntype = \"spot\"\nposition = [0, 3, 0]\n\
             direction = [0, -1, 0]\nintensity = 10\n{extra}\n"
        )
    };
    let cases = [
        (
            spot(&format!(
                "texture = {:?}\nup = [0, 2, 0]",
                png.to_str().unwrap()
            )),
            "must not be parallel",
        ),
        (spot("up = [1, 0, 0]"), "only orients a `texture`"),
        (spot("texture = \"missing.png\""), "missing.png"),
    ];
    for (i, (extra, needle)) in cases.iter().enumerate() {
        let scene = dir.join(format!("case{i}.toml"));
        std::fs::write(&scene, format!("{SCENE}\n{extra}")).unwrap();
        let out = dir.join(format!("case{i}.exr"));
        let result = risotto(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert_fails(
            &format!("case {i}"),
            &result,
            &[needle, &format!("case{i}.toml:")],
        );
    }
}
