//! Reading a conversion back as TOML (`scene_file::parse_imported`): errors in the
//! converted text are reported at the original file and line, dotted `-D` overrides apply
//! to the conversion, and a pbrt conversion reads back. (Integration tests: they use the
//! importers and the TOML loader together, which the modules' own tests must not, lest the
//! modules depend on each other both ways.)

use std::path::Path;

use risotto_engine::scratch_dir::ScratchDir;
use risotto_loader::import::{
    import_scene, origin, Entity, ImportOptions, ImportedScene, SceneFormat, TomlScene,
};
use risotto_loader::scene_file::parse_imported;

fn scene_with_radius(radius: f64) -> ImportedScene {
    let xml = Path::new("dir/scene.xml");
    let mut scene = TomlScene {
        camera: Entity::new(Some(origin(xml, 2)))
            .with("from", vec![0.0, 0.0, 5.0])
            .with("to", vec![0.0, 0.0, 0.0])
            .with("fov", 40.0),
        ..TomlScene::default()
    };
    scene.materials.push((
        "white".into(),
        Entity::new(Some(origin(xml, 4)))
            .with("type", "diffuse")
            .with("reflectance", 0.5),
    ));
    scene.shapes.push(
        Entity::new(Some(origin(Path::new("dir/inc.xml"), 12)))
            .with("type", "sphere")
            .with("material", "white")
            .with("center", vec![0.0, 0.0, 0.0])
            .with("radius", radius),
    );
    ImportedScene {
        scene,
        warnings: vec!["an aov integrator was unwrapped".into()],
    }
}

#[test]
fn errors_in_a_conversion_name_the_original_file_and_line() {
    let e = parse_imported(scene_with_radius(-1.0), Path::new("dir/scene.xml"), &[]).unwrap_err();
    assert_eq!(e.file(), Path::new("dir/inc.xml"));
    assert_eq!(e.line(), Some(12));
    let text = e.to_string();
    assert!(
        text.starts_with("dir/inc.xml:12: shapes[0], field `radius`"),
        "{text}"
    );
    assert!(text.contains("radius = -1.0"), "{text}");
}

#[test]
fn dotted_overrides_apply_to_the_conversion_and_warnings_carry_through() {
    let desc = parse_imported(
        scene_with_radius(1.0),
        Path::new("dir/scene.xml"),
        &["shapes.0.radius=2".into()],
    )
    .unwrap();
    match &desc.shapes[0].geometry {
        risotto_loader::scene_file::ShapeGeometry::Sphere { radius, .. } => {
            assert_eq!(*radius, 2.0)
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(desc.warnings, vec!["an aov integrator was unwrapped"]);
    // An error in an override names the override, not an origin.
    let e = parse_imported(
        scene_with_radius(1.0),
        Path::new("dir/scene.xml"),
        &["shapes.0.radius=-3".into()],
    )
    .unwrap_err();
    assert!(e.to_string().contains("command-line override"), "{e}");
    // An error outside every converted part names the scene without a line.
    let mut no_camera = scene_with_radius(1.0);
    no_camera.scene.camera = Entity::default();
    let e = parse_imported(no_camera, Path::new("dir/scene.xml"), &[]).unwrap_err();
    assert_eq!((e.file(), e.line()), (Path::new("dir/scene.xml"), None));
    assert!(
        e.to_string()
            .starts_with("dir/scene.xml: scene, field `camera`"),
        "{e}"
    );
}

#[test]
fn the_conversion_reads_back_as_toml() {
    let d = ScratchDir::new("pbrt-readback");
    let text: String = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 30\nPixelFilter \"box\"\nSampler \"halton\" \"integer pixelsamples\" 4\nWorldBegin\n\
         LightSource \"spot\" \"point3 from\" [0 4 0] \"point3 to\" [0 0 0] \"float coneangle\" 30\n\
         LightSource \"distant\" \"rgb L\" [1 1 1]\nLightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n\
         Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 \
         \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1]\n\
         Material \"diffuse\" \"texture reflectance\" \"c\"\n\
         Shape \"trianglemesh\" \"point3 P\" [-1 0 -1 1 0 -1 1 0 1 -1 0 1] \
         \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n\
         Material \"dielectric\" \"float eta\" 1.33 \"float roughness\" 0.1\nShape \"sphere\"\n".into();
    let path = d.join("s.pbrt");
    std::fs::write(&path, &text).unwrap();
    let options = ImportOptions {
        defines: &[],
        toml_dir: &d,
    };
    let imported = import_scene(SceneFormat::Pbrt, &path, &text, &options).unwrap();
    assert!(
        !imported.warnings.is_empty(),
        "the spot's falloff is warned about"
    );
    let desc = parse_imported(imported, &path, &[]).unwrap();
    assert_eq!(desc.shapes.len(), 2);
    assert_eq!(desc.lights.len(), 3);
}
