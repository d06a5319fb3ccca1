//! Unit tests of the pbrt-v4 importer: each convention against the value pbrt-v4 gives,
//! and every error located at its file, line and column.

use std::path::{Path, PathBuf};

use crate::import::{import_scene, ImportOptions, SceneFormat, TomlScene};

/// A fresh directory for a test's files.
fn dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("risotto-pbrt-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The camera, film and filter every test scene starts with (the box filter of radius
/// 1/2 is risotto's default, so no filter key is written).
const HEAD: &str = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 30\nPixelFilter \"box\"\n";

fn convert_in(d: &Path, text: &str) -> Result<TomlScene, String> {
    let path = d.join("scene.pbrt");
    std::fs::write(&path, text).unwrap();
    let options = ImportOptions {
        defines: &[],
        toml_dir: d,
    };
    import_scene(SceneFormat::Pbrt, &path, text, &options)
        .map(|s| s.scene)
        .map_err(|e| e.to_string())
}

fn convert(test: &str, text: &str) -> TomlScene {
    convert_in(&dir(test), text).unwrap_or_else(|e| panic!("{e}"))
}

fn error(test: &str, text: &str) -> String {
    match convert_in(&dir(test), text) {
        Ok(s) => panic!("converted: {s:?}"),
        Err(e) => e,
    }
}

fn floats(v: &toml::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)).unwrap())
        .collect()
}

fn matrix(shape: &toml::Table) -> Vec<Vec<f64>> {
    shape["transform"][0]["matrix"]
        .as_array()
        .unwrap()
        .iter()
        .map(floats)
        .collect()
}

#[test]
fn the_transform_stack_composes_and_restores_as_pbrt() {
    // With `Scale -1 1 1` before LookAt the camera is already right-handed: no mirror.
    let s = convert(
        "stack",
        "Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nPixelFilter \"box\"\n\
         WorldBegin\nAttributeBegin\nTranslate 1 0 0\nScale 2 2 2\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\nAttributeEnd\n\
         TransformBegin\nTranslate 0 5 0\nTransformEnd\nRotate 90 0 0 1\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n",
    );
    // ctm = T(1,0,0) S(2): p_world = 2 p + (1, 0, 0).
    assert_eq!(
        matrix(&s.shapes[0].table),
        vec![
            vec![2.0, 0.0, 0.0, 1.0],
            vec![0.0, 2.0, 0.0, 0.0],
            vec![0.0, 0.0, 2.0, 0.0]
        ]
    );
    // After AttributeEnd and TransformEnd only the rotation applies: x -> y.
    let m = matrix(&s.shapes[1].table);
    assert!(
        (m[1][0] - 1.0).abs() < 1e-12 && m[0][0].abs() < 1e-12,
        "{m:?}"
    );
    assert!(m.iter().all(|r| r[3] == 0.0), "{m:?}");
}

#[test]
fn a_plain_look_at_mirrors_the_world_so_the_image_matches_pbrt() {
    // pbrt's LookAt makes camera +x = cross(up, dir): looking down -z with +y up, pbrt's
    // image right is world -x, while risotto's (cross(dir, up)) is +x. The world is
    // mirrored across the plane x = 0 (through the eye, containing dir and up).
    let text = format!("{HEAD}WorldBegin\nLightSource \"point\" \"point3 from\" [2 1 0]\n");
    let s = convert("mirror", &text);
    assert_eq!(floats(&s.lights[0].table["position"]), vec![-2.0, 1.0, 0.0]);
    assert_eq!(floats(&s.camera.table["from"]), vec![0.0, 0.0, 5.0]);
    // With `Scale -1 1 1` (pbrt's exporters' idiom) nothing is mirrored.
    let s = convert("mirror-scaled", &format!("Scale -1 1 1\n{text}"));
    assert_eq!(floats(&s.lights[0].table["position"]), vec![2.0, 1.0, 0.0]);
}

#[test]
fn fov_is_the_shorter_axis_and_becomes_horizontal() {
    let landscape = convert("fov", &format!("{HEAD}WorldBegin\n"));
    let want = 2.0
        * ((20f64.to_radians()).tan() * 40.0 / 30.0)
            .atan()
            .to_degrees();
    let got = landscape.camera.table["fov"].as_float().unwrap();
    assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    let portrait = convert(
        "fov-portrait",
        &format!(
            "{}WorldBegin\n",
            HEAD.replace("xresolution\" 40", "xresolution\" 20")
        ),
    );
    assert_eq!(portrait.camera.table["fov"].as_float(), Some(40.0));
}

#[test]
fn maxdepth_counts_bounces_and_max_depth_segments() {
    let s = convert(
        "depth",
        &format!("{HEAD}Integrator \"volpath\" \"integer maxdepth\" 3\nWorldBegin\n"),
    );
    assert_eq!(s.render.table["max_depth"].as_integer(), Some(4));
    // pbrt's default is 5.
    let s = convert("depth-default", &format!("{HEAD}WorldBegin\n"));
    assert_eq!(s.render.table["max_depth"].as_integer(), Some(6));
    assert_eq!(s.render.table["spp"].as_integer(), Some(16));
}

#[test]
fn diffuse_is_two_sided_and_rough_metals_remap_roughness() {
    let s = convert(
        "materials",
        &format!(
            "{HEAD}WorldBegin\nMaterial \"conductor\" \"float roughness\" 0.04 \
             \"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.2]\n\
             Shape \"sphere\"\nMaterial \"diffuse\"\nShape \"sphere\"\n\
             Material \"conductor\" \"float roughness\" 0.04 \"bool remaproughness\" false\n\
             Shape \"sphere\"\n"
        ),
    );
    let (_, metal) = &s.materials[0];
    assert_eq!(metal.table["type"].as_str(), Some("rough_conductor"));
    assert!((metal.table["alpha"].as_float().unwrap() - 0.2).abs() < 1e-12);
    assert_eq!(metal.table["energy_compensation"].as_bool(), Some(false));
    let (_, diffuse) = &s.materials[1];
    assert_eq!(diffuse.table["two_sided"].as_bool(), Some(true));
    assert_eq!(diffuse.table["reflectance"].as_float(), Some(0.5));
    let (_, copper) = &s.materials[2];
    assert_eq!(copper.table["material"].as_str(), Some("Cu"));
    assert_eq!(copper.table["alpha"].as_float(), Some(0.04));
}

#[test]
fn objects_are_emitted_once_and_instanced() {
    let s = convert(
        "objects",
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\nObjectBegin \"tri\"\n\
             Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\nObjectEnd\n\
             Translate 3 0 0\nObjectInstance \"tri\"\nTranslate 0 2 0\nObjectInstance \"tri\"\n"
        ),
    );
    assert_eq!(s.objects.len(), 1);
    let shapes = s.objects[0].1.table["shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 1);
    assert_eq!(shapes[0]["type"].as_str(), Some("triangles"));
    assert_eq!(s.shapes.len(), 2);
    for (shape, t) in s.shapes.iter().zip([[3.0, 0.0], [3.0, 2.0]]) {
        assert_eq!(shape.table["type"].as_str(), Some("instance"));
        assert_eq!(shape.table["object"].as_str(), Some("tri"));
        let m = matrix(&shape.table);
        assert_eq!((m[0][3], m[1][3]), (t[0], t[1]));
    }
}

#[test]
fn includes_resolve_against_the_including_file() {
    let d = dir("include");
    std::fs::create_dir_all(d.join("geo/more")).unwrap();
    std::fs::write(
        d.join("geo/a.pbrt"),
        "Translate 0 1 0\nInclude \"more/b.pbrt\"\n",
    )
    .unwrap();
    std::fs::write(
        d.join("geo/more/b.pbrt"),
        "Shape \"plymesh\" \"string filename\" \"m.ply\"\n",
    )
    .unwrap();
    std::fs::write(
        d.join("geo/c.pbrt"),
        "Shape \"sphere\" \"float radius\" 2\n",
    )
    .unwrap();
    let s = convert_in(
        &d,
        &format!("Scale -1 1 1\n{HEAD}WorldBegin\nInclude \"geo/a.pbrt\"\nImport \"geo/c.pbrt\"\n"),
    )
    .unwrap();
    assert_eq!(s.shapes[0].table["path"].as_str(), Some("geo/more/m.ply"));
    // Include is textual: the Translate in a.pbrt applies to what follows it.
    assert_eq!(floats(&s.shapes[1].table["center"]), vec![0.0, 1.0, 0.0]);
    assert_eq!(s.shapes[1].table["radius"].as_float(), Some(2.0));
    // The origin names the included file and its line.
    let o = s.shapes[0].origin.as_ref().unwrap();
    assert!(o.file.ends_with("geo/more/b.pbrt") && o.line == 1, "{o:?}");
}

#[test]
fn reverse_orientation_and_normals_decide_the_emitting_side() {
    let tri = "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]";
    let with_n = "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 -1 0 0 -1 0 0 -1]";
    let s = convert(
        "orientation",
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\n{tri}\nAttributeBegin\nReverseOrientation\n{tri}\n\
             AttributeEnd\n{with_n}\nReverseOrientation\n{with_n}\n"
        ),
    );
    let idx: Vec<Vec<f64>> = s
        .shapes
        .iter()
        .map(|e| floats(&e.table["indices"]))
        .collect();
    assert_eq!(idx[0], vec![0.0, 1.0, 2.0]);
    assert_eq!(idx[1], vec![0.0, 2.0, 1.0], "ReverseOrientation flips");
    assert_eq!(idx[2], vec![0.0, 2.0, 1.0], "faces the normals");
    assert_eq!(idx[3], vec![0.0, 1.0, 2.0], "reversed normals");
}

#[test]
fn bilinear_patches_split_into_two_triangles_facing_the_same_way() {
    let s = convert(
        "bilinear",
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\nShape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n"
        ),
    );
    // Corners p00 p10 p01 p11: triangles (p00, p10, p11) and (p00, p11, p01), both with
    // normal +z, pbrt's (p10 - p00) x (p01 - p00).
    assert_eq!(
        floats(&s.shapes[0].table["indices"]),
        vec![0.0, 1.0, 3.0, 0.0, 3.0, 2.0]
    );
}

#[test]
fn media_become_interiors_of_their_shapes() {
    let s = convert(
        "media",
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \
             \"rgb sigma_a\" [0.1 0.2 0.3] \"rgb sigma_s\" [1 1 1] \"float scale\" 2 \"float g\" 0.5\n\
             Material \"interface\"\nMediumInterface \"fog\" \"\"\nShape \"sphere\"\n"
        ),
    );
    let (_, m) = &s.materials[0];
    let interior = m.table["interior"].as_table().unwrap();
    assert_eq!(floats(&interior["sigma_a"]), vec![0.2, 0.4, 0.6]);
    assert_eq!(floats(&interior["sigma_s"]), vec![2.0, 2.0, 2.0]);
    assert_eq!(interior["phase"]["g"].as_float(), Some(0.5));
}

#[test]
fn a_uniformgrid_becomes_a_zero_border_grid_pattern_in_its_box() {
    let s = convert(
        "uniformgrid",
        &format!(
            "{HEAD}WorldBegin\nTranslate 1 2 3\nMakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \
             \"rgb sigma_a\" [1 2 0] \"rgb sigma_s\" [3 2 0] \"float scale\" 2 \
             \"integer nx\" 2 \"integer ny\" 1 \"integer nz\" 1 \"float density\" [0.25 4] \
             \"point3 p0\" [0 0 0] \"point3 p1\" [2 1 1]\n\
             Material \"interface\"\nMediumInterface \"g\" \"\"\nShape \"sphere\" \"float radius\" 5\n"
        ),
    );
    let interior = s.materials[0].1.table["interior"].as_table().unwrap();
    assert_eq!(interior["type"].as_str(), Some("heterogeneous"));
    // sigma_t = (sigma_a + sigma_s) scale; albedo sigma_s / sigma_t (0 where sigma_t is 0).
    assert_eq!(floats(&interior["scale"]), vec![8.0, 8.0, 0.0]);
    assert_eq!(floats(&interior["albedo"]), vec![0.75, 0.5, 0.0]);
    let d = interior["density"].as_table().unwrap();
    assert_eq!(d["pattern"].as_str(), Some("grid"));
    assert_eq!(d["border"].as_str(), Some("zero"));
    assert_eq!(floats(&d["dims"]), vec![2.0, 1.0, 1.0]);
    assert_eq!(floats(&d["values"]), vec![0.25, 4.0]);
    assert_eq!(floats(&d["max"]), vec![2.0, 1.0, 1.0]);
    // Placed by the CTM at MakeNamedMedium: the translation is in the transform's matrix.
    let t = d["transform"][0]["matrix"].as_array().unwrap();
    assert_eq!(floats(&t[1])[3], 2.0);
}

#[test]
fn mix_materials_blend_their_named_components() {
    let s = convert(
        "mix",
        &format!(
            "{HEAD}WorldBegin\nMakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.8 0.1 0.1]\n\
             MakeNamedMaterial \"gold\" \"string type\" \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"\n\
             Material \"mix\" \"string materials\" [\"red\" \"gold\"] \"float amount\" 0.3\nShape \"sphere\"\n\
             NamedMaterial \"red\"\nShape \"sphere\"\n"
        ),
    );
    // The components are written once (the plain red sphere shares its material) and
    // the mix names them; pbrt's `amount` is the weight of `materials[1]`.
    let names: Vec<&str> = s.materials.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 3, "{names:?}");
    let (_, mix) = s
        .materials
        .iter()
        .find(|(_, m)| m.table["type"].as_str() == Some("mix"))
        .unwrap();
    assert_eq!(mix.table["a"].as_str(), Some("red"));
    assert_eq!(mix.table["b"].as_str(), Some("gold"));
    assert_eq!(floats(&mix.table["amount"]), vec![0.3; 3]);
    assert_eq!(s.shapes[1].table["material"].as_str(), Some("red"));
}

#[test]
fn the_camera_medium_and_outside_media_become_within_checks() {
    let s = convert(
        "within",
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         MediumInterface \"\" \"fog\"\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n\
         WorldBegin\n\
         AttributeBegin\nMaterial \"interface\"\nMediumInterface \"fog\" \"\"\n\
         Shape \"sphere\" \"float radius\" 10\nAttributeEnd\n\
         MediumInterface \"\" \"fog\"\nShape \"sphere\"\n",
    );
    let name = |i: usize| s.shapes[i].table["name"].as_str().unwrap().to_owned();
    assert_eq!(name(0), "sphere at line 9");
    let within = |t: &toml::Table| t["within"].as_array().unwrap().clone();
    assert_eq!(within(&s.camera.table), vec![toml::Value::from(name(0))]);
    assert_eq!(within(&s.shapes[1].table), vec![toml::Value::from(name(0))]);
    // The fog sphere's outside is unset (vacuum in pbrt): stated as "no medium".
    assert_eq!(s.shapes[0].table["within"].as_str(), Some("no medium"));
}

/// Each error names the file, line and column of what is wrong.
#[test]
fn errors_are_located() {
    let cases: &[(&str, &str, &str)] = &[
        ("Shape \"hair\"", "6:1", "shape \"hair\" is not supported"),
        ("Frobnicate 1", "6:1", "unknown or unsupported directive `Frobnicate`"),
        ("Shape \"sphere\" \"float radius\" [ 1", "6:16", "no closing `]`"),
        ("Shape \"sphere\" \"float radius\" -1", "6:16", "must be > 0"),
        ("Shape \"sphere\" \"float radios\" 1", "6:16", "`float radios` is not supported"),
        ("Shape \"sphere\" \"floot radius\" 1", "6:16", "unknown parameter type `floot`"),
        ("Material \"mix\"", "6:1", "a mix needs \"string materials\""),
        ("Material \"mix\" \"string materials\" [\"x\" \"y\"]", "6:16", "no material named \"x\""),
        ("Material \"mix\" \"string materials\" [\"x\"]", "6:16", "expected two material names"),
        ("Material \"hair\"", "6:1", "material \"hair\" is not supported"),
        ("NamedMaterial \"nope\"\nShape \"sphere\"", "6:1", "no material named \"nope\""),
        ("Include \"missing.pbrt\"", "6:1", "missing.pbrt"),
        ("Shape \"sphere\" \"string x\" \"abc", "6:27", "unterminated string"),
        ("LightSource \"goniometric\"", "6:1", "light \"goniometric\" is not supported"),
        ("LightSource \"infinite\" \"string filename\" \"sky.exr\" \"rgb L\" [1 1 1]", "6:24", "either L or a filename"),
        ("Shape \"curve\"", "6:1", "shape \"curve\" is not supported"),
        ("Shape \"loopsubdiv\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"integer indices\" [0 1 2 0 1 3 1 0 2]", "6:1", "more than two triangles"),
        ("AttributeEnd", "6:1", "has no matching Begin"),
        ("ObjectInstance \"x\"", "6:1", "no object named \"x\""),
        ("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]", "6:53", "index 3 is out of range"),
        ("Scale 1 0 1\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]", "7:1", "singular"),
        ("Shape \"sphere\" \"float radius\" 1e999", "6:31", "not a finite number"),
        ("Material \"conductor\" \"spectrum eta\" \"metal-Zz-eta\" \"spectrum k\" \"metal-Zz-k\"", "6:1", "not a metal risotto knows"),
        ("MakeNamedMedium \"g\" \"string type\" \"nanovdb\"", "6:21", "NanoVDB files are not read"),
        ("MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"float density\" [1]", "6:64", "has 1 values; nx * ny * nz = 2"),
        ("MakeNamedMedium \"g\" \"string type\" \"uniformgrid\"", "6:1", "needs \"float density\""),
        ("MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"float density\" [-1]", "6:49", "value 0 is -1"),
        ("MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"float density\" [1] \"point3 p1\" [1 0 1]", "6:69", "p1 > p0"),
        ("MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"float density\" [1] \"rgb Le\" [1 1 1]", "6:69", "emission of a grid medium"),
        ("MakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nz\" 0 \"float density\" [1]", "6:49", "must be in [1,"),
        ("MakeNamedMedium \"g\" \"string type\" \"rgbgrid\" \"rgb sigma_a\" [1 1 1]", "6:1", "needs \"rgb sigma_s\""),
        ("MakeNamedMedium \"g\" \"string type\" \"rgbgrid\" \"integer nx\" 2 \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [1 1 1 1 1 1]", "6:60", "has 1 values; nx * ny * nz = 2 colours"),
    ];
    for (i, (body, at, message)) in cases.iter().enumerate() {
        let e = error(&format!("err{i}"), &format!("{HEAD}WorldBegin\n{body}\n"));
        assert!(
            e.contains(&format!("scene.pbrt:{at}:")) && e.contains(message),
            "case {i} `{body}`: expected scene.pbrt:{at}: ... {message}; got\n{e}"
        );
    }
    // Before WorldBegin.
    let e = error("err-film", "Film \"spectral\"\nWorldBegin\n");
    assert!(
        e.contains("scene.pbrt:1:1:") && e.contains("film \"spectral\""),
        "{e}"
    );
    let e = error("err-filter", "PixelFilter \"mitchell\"\nWorldBegin\n");
    assert!(
        e.contains("scene.pbrt:1:1:") && e.contains("negative lobes"),
        "{e}"
    );
    let e = error("err-order", "Shape \"sphere\"\nWorldBegin\n");
    assert!(
        e.contains("scene.pbrt:1:1:") && e.contains("after WorldBegin"),
        "{e}"
    );
    let e = error("err-order2", "WorldBegin\nCamera \"perspective\"\n");
    assert!(
        e.contains("scene.pbrt:2:1:") && e.contains("before WorldBegin"),
        "{e}"
    );
    let e = error("err-world", "LookAt 0 0 1 0 0 0 0 1 0\n");
    assert!(e.contains("no WorldBegin"), "{e}");
    // An error in an included file names that file.
    let d = dir("err-include");
    std::fs::write(d.join("inc.pbrt"), "\n  Shape \"cone\"\n").unwrap();
    let e = convert_in(&d, &format!("{HEAD}WorldBegin\nInclude \"inc.pbrt\"\n")).unwrap_err();
    assert!(
        e.contains("inc.pbrt:2:3:") && e.contains("shape \"cone\""),
        "{e}"
    );
    // A file including itself stops at the nesting limit.
    let d = dir("err-recursive");
    std::fs::write(d.join("self.pbrt"), "Include \"self.pbrt\"\n").unwrap();
    let e = convert_in(&d, &format!("{HEAD}WorldBegin\nInclude \"self.pbrt\"\n")).unwrap_err();
    assert!(e.contains("nested more than"), "{e}");
}

#[test]
fn attribute_defaults_apply_within_their_attribute_block() {
    let s = convert(
        "attribute",
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\nAttributeBegin\nAttribute \"shape\" \"float radius\" 2\n\
             Shape \"sphere\"\nShape \"sphere\" \"float radius\" 3\nAttributeEnd\nShape \"sphere\"\n"
        ),
    );
    let radii: Vec<f64> = s
        .shapes
        .iter()
        .map(|e| e.table["radius"].as_float().unwrap())
        .collect();
    assert_eq!(radii, vec![2.0, 3.0, 1.0]);
}

#[test]
fn loop_subdivision_surfaces_become_triangles_with_normals() {
    let s = convert(
        "loop",
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\nShape \"loopsubdiv\" \"integer levels\" 2 \
             \"point3 P\" [1 1 1 1 -1 -1 -1 1 -1 -1 -1 1] \"integer indices\" [0 1 2 0 3 1 0 2 3 1 3 2]\n"
        ),
    );
    let t = &s.shapes[0].table;
    assert_eq!(t["type"].as_str(), Some("triangles"));
    assert_eq!(t["indices"].as_array().unwrap().len(), 3 * 64);
    assert_eq!(
        t["shadow_terminator_offset"].as_bool(),
        Some(false),
        "as pbrt"
    );
    assert_eq!(
        t["normals"].as_array().unwrap().len(),
        t["positions"].as_array().unwrap().len()
    );
}

#[test]
fn spectra_become_rgb_and_light_spectra_have_unit_luminance() {
    let d = dir("spectra");
    std::fs::write(
        d.join("flat.spd"),
        "# a flat spectrum\n360 0.25\n830 0.25\n",
    )
    .unwrap();
    let s = convert_in(
        &d,
        &format!(
            "Scale -1 1 1\n{HEAD}WorldBegin\n\
             LightSource \"point\" \"blackbody I\" 3000 \"float scale\" 2\n\
             LightSource \"distant\" \"spectrum L\" [ 400 1 700 1 ]\n\
             Material \"diffuse\" \"spectrum reflectance\" [ 300 0.5 800 0.5 ]\nShape \"sphere\"\n\
             Material \"conductor\" \"spectrum eta\" \"flat.spd\" \"spectrum k\" \"flat.spd\"\nShape \"sphere\"\n"
        ),
    )
    .unwrap();
    let lum = |c: &[f64]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let warm = floats(&s.lights[0].table["intensity"]);
    // pbrt divides a light's spectrum by its photometric value: luminance = scale.
    assert!((lum(&warm) - 2.0).abs() < 1e-9, "{warm:?}");
    // 3000 K is reddish.
    assert!(warm[0] > warm[1] && warm[1] > warm[2], "{warm:?}");
    assert!((lum(&floats(&s.lights[1].table["irradiance"])) - 1.0).abs() < 1e-9);
    // A flat reflectance is grey of its value (D65-weighted, as Mitsuba's RGB modes).
    let grey = floats(&s.materials[0].1.table["reflectance"]);
    assert!(grey.iter().all(|c| (c - 0.5).abs() < 2e-3), "{grey:?}");
    let eta = floats(&s.materials[1].1.table["eta"]);
    assert!(eta.iter().all(|c| (c - 0.25).abs() < 2e-3), "{eta:?}");
    // A bad .spd is a located error naming the file.
    std::fs::write(d.join("bad.spd"), "400 1\n500 x\n").unwrap();
    let e = convert_in(
        &d,
        &format!("{HEAD}WorldBegin\nMaterial \"diffuse\" \"spectrum reflectance\" \"bad.spd\"\n"),
    )
    .unwrap_err();
    assert!(
        e.contains("scene.pbrt:6:20:") && e.contains("bad.spd` line 2: `x`"),
        "{e}"
    );
}

/// An image infinite light becomes an equal-area environment map whose frame is carried
/// into the world exactly as the scene's geometry is (the same CTM and world mirror): the
/// map's `transform` takes the light frame's axes where a point light placed on them under
/// the same CTM lands, and its radiance is the `scale`.
#[test]
fn image_infinite_lights_are_equal_area_maps_in_the_light_frame() {
    let text = format!(
        "{HEAD}WorldBegin\nAttributeBegin\nRotate -90 1 0 0\nRotate 30 0 0 1\n\
         LightSource \"infinite\" \"string filename\" \"sky.exr\" \"float scale\" 2.5\n\
         LightSource \"point\" \"point3 from\" [1 0 0]\n\
         LightSource \"point\" \"point3 from\" [0 1 0]\n\
         LightSource \"point\" \"point3 from\" [0 0 1]\n\
         AttributeEnd\n"
    );
    let scene = convert("infinite-image", &text);
    let lights: Vec<&toml::Table> = scene.lights.iter().map(|e| &e.table).collect();
    let env = lights[0];
    assert_eq!(env["type"].as_str(), Some("environment"));
    assert_eq!(env["projection"].as_str(), Some("equal_area"));
    assert!(env["map"].as_str().unwrap().ends_with("sky.exr"), "{env:?}");
    assert_eq!(env["radiance"].as_float(), Some(2.5));
    let m = matrix(env);
    for (axis, light) in lights[1..].iter().enumerate() {
        let landed = floats(&light["position"]);
        let column: Vec<f64> = (0..3).map(|row| m[row][axis]).collect();
        for k in 0..3 {
            assert!(
                (landed[k] - m[k][3] - column[k]).abs() < 1e-9,
                "axis {axis}: the map's frame takes it to {column:?}, the point light lands at {landed:?}"
            );
        }
    }
}

/// A shape's `alpha` (pbrt-v4's cut-out: 1 opaque, 0 absent) becomes its material's
/// `opacity`, on a copy of the material made once per material and alpha; a shape without
/// alpha keeps the plain material; a float texture alpha becomes the texture's pattern.
#[test]
fn shape_alpha_becomes_the_materials_opacity() {
    let text = format!(
        "{HEAD}WorldBegin\nTexture \"mask\" \"float\" \"checkerboard\"\n\
         Material \"diffuse\"\n\
         Shape \"sphere\" \"float alpha\" 0.25\n\
         Shape \"sphere\" \"float alpha\" 0.25 \"float radius\" 2\n\
         Shape \"sphere\"\n\
         Shape \"sphere\" \"texture alpha\" \"mask\"\n\
         Shape \"sphere\" \"float alpha\" 1\n"
    );
    let scene = convert("shape-alpha", &text);
    let material = |i: usize| {
        scene.shapes[i].table["material"]
            .as_str()
            .unwrap()
            .to_string()
    };
    let opacity = |name: &str| {
        let (_, m) = scene.materials.iter().find(|(n, _)| n == name).unwrap();
        m.table.get("opacity").cloned()
    };
    assert_eq!(opacity(&material(0)), Some(toml::Value::Float(0.25)));
    assert_eq!(material(0), material(1), "one copy per material and alpha");
    assert_eq!(opacity(&material(2)), None);
    assert_ne!(material(0), material(2));
    let pattern = opacity(&material(3)).expect("a texture alpha");
    assert_eq!(pattern["pattern"].as_str(), Some("checker"), "{pattern:?}");
    assert_eq!(material(4), material(2), "alpha 1 is opaque");
    let e = error(
        "shape-alpha-range",
        &format!("{HEAD}WorldBegin\nShape \"sphere\" \"float alpha\" 1.5\n"),
    );
    assert!(
        e.contains("scene.pbrt:6:16:") && e.contains("alpha 1.5 must be in [0, 1]"),
        "{e}"
    );
}

#[test]
fn roughness_textures_become_alpha_patterns() {
    let s = convert(
        "rough_textures",
        &format!(
            "{HEAD}WorldBegin\nTexture \"rough\" \"float\" \"checkerboard\" \
             \"float tex1\" 0.04 \"float tex2\" 0.25\n\
             Material \"conductor\" \"texture roughness\" \"rough\"\nShape \"sphere\"\n\
             Material \"dielectric\" \"texture uroughness\" \"rough\" \"float vroughness\" 0.09 \
             \"bool remaproughness\" false\nShape \"sphere\"\n"
        ),
    );
    // remaproughness (the default): alpha = sqrt(roughness), clamped to [1e-4, 1].
    let alpha = s.materials[0].1.table["alpha"].as_table().unwrap();
    assert_eq!(alpha["pattern"].as_str(), Some("remap"));
    assert_eq!(floats(&alpha["to"]), [1e-4, 1.0]);
    let sqrt = alpha["a"].as_table().unwrap();
    assert_eq!(sqrt["pattern"].as_str(), Some("power"));
    assert_eq!(sqrt["exponent"].as_float(), Some(0.5));
    assert_eq!(sqrt["a"]["pattern"].as_str(), Some("checker"));
    // No remap: the texture as it is; a number beside it stays a number.
    let glass = &s.materials[1].1.table;
    assert_eq!(glass["type"].as_str(), Some("rough_dielectric"));
    assert_eq!(glass["alpha_u"]["a"]["pattern"].as_str(), Some("checker"));
    assert_eq!(glass["alpha_v"].as_float(), Some(0.09));
}

#[test]
fn imagemap_scales_offsets_wrap_and_point_filter_become_the_image_lookup() {
    let s = convert(
        "imagemap",
        &format!(
            "{HEAD}WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \
             \"float uscale\" 2 \"float vscale\" 3 \"float udelta\" 0.25 \"float vdelta\" -0.5 \
             \"string wrap\" \"clamp\" \"string filter\" \"point\"\n\
             Material \"diffuse\" \"texture reflectance\" \"t\"\nShape \"sphere\"\n"
        ),
    );
    let (_, m) = &s.materials[0];
    let image = m.table["reflectance"].as_table().unwrap();
    assert_eq!(image["pattern"].as_str(), Some("image"));
    assert_eq!(image["wrap"].as_str(), Some("clamp"));
    assert_eq!(image["filter"].as_str(), Some("nearest"));
    let uv = image["uv_transform"].as_table().unwrap();
    assert_eq!(floats(&uv["u"]), [2.0, 0.0, 0.25]);
    assert_eq!(floats(&uv["v"]), [0.0, 3.0, -0.5]);
    // pbrt's "black" wrap and MIP-mapped filters are located errors.
    for (key, value) in [("wrap", "black"), ("filter", "ewa")] {
        let e = error(
            "imagemap-errors",
            &format!(
                "{HEAD}WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \
                 \"string {key}\" \"{value}\"\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\n\
                 Shape \"sphere\"\n"
            ),
        );
        assert!(e.contains(key) && e.contains("scene.pbrt:6:"), "{e}");
    }
}
