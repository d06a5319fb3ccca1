//! `within` on the camera and on shapes (the statements Mitsuba's sensor medium and shape
//! `exterior` become): checked against the volumes the geometry puts them in when the scene
//! is compiled, so a statement the geometry contradicts is a located error, never a render
//! with the wrong medium around the camera or the shape.

use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::parse_scene;
use std::path::Path;

/// A haze box (-4..4) around the camera and a glass ball in it; a second ball outside the
/// box; `camera` and `ball` / `far` keys added by the caller.
fn scene(camera: &str, ball: &str, far: &str) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
spp = 1

[camera]
from = [0, 0, 3]
to = [0, 0, 0]
fov = 40
{camera}

[materials.haze]
type = "interface"
interior = {{ type = "beer", sigma_a = 0.1 }}

[materials.glass]
type = "dielectric"
ior = 1.5
interior = {{ type = "beer", sigma_a = 0.5 }}

[materials.white]
type = "diffuse"

[[shapes]]
name = "haze"
type = "box"
min = [-4, -4, -4]
max = [4, 4, 4]
material = "haze"

[[shapes]]
name = "ball"
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "glass"
{ball}

[[shapes]]
name = "far"
type = "sphere"
center = [10, 0, 0]
radius = 1
material = "white"
{far}
"#
    )
}

/// Loads and compiles `text`; the error's text if either fails.
fn compile(text: &str) -> Result<(), String> {
    compile_as(text, "scene.toml")
}

/// [`compile`] of a scene read as the file `name` (its extension picks the format).
fn compile_as(text: &str, name: &str) -> Result<(), String> {
    let desc = parse_scene(text, Path::new(name)).map_err(|e| e.to_string())?;
    scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .map_err(|e| e.to_string())?
        .compile()
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn statements_the_geometry_agrees_with_load() {
    compile(&scene(
        r#"within = ["haze"]"#,
        r#"within = ["haze"]"#,
        "within = []",
    ))
    .unwrap();
    // One of several shapes is enough (Mitsuba's medium may be the interior of several).
    compile(&scene(r#"within = ["ball", "haze"]"#, "", "")).unwrap();
}

#[test]
fn statements_the_geometry_contradicts_are_located_errors() {
    for (camera, ball, far, want) in [
        // The camera is in the haze, not in no volume.
        (
            "within = []",
            "",
            "",
            "the camera is stated to be in no volume, but the innermost volume around it is the interior of \"haze\"",
        ),
        // The camera is not inside the glass ball.
        ("within = [\"ball\"]", "", "", "the interior of \"ball\", but"),
        // The ball sits in the haze.
        ("", "within = []", "", "shape \"ball\" is stated to be in no volume"),
        // The far ball is outside the haze box.
        (
            "",
            "",
            "within = [\"haze\"]",
            "shape \"far\" is stated to be within the interior of \"haze\", but it is in no volume",
        ),
    ] {
        let e = compile(&scene(camera, ball, far)).expect_err(want);
        assert!(e.contains(want) && e.contains("scene.toml"), "{e}");
        assert!(e.contains("within"), "{e}");
    }
    // Names are checked when read, and a shape without an interior is no volume.
    let e = compile(&scene("within = [\"fog\"]", "", "")).unwrap_err();
    assert!(
        e.contains("unknown shape `fog`") && e.contains("scene.toml:"),
        "{e}"
    );
    let e = compile(&scene("within = [\"far\"]", "", "")).unwrap_err();
    assert!(e.contains("\"far\" has no interior"), "{e}");
    let e = compile(&scene("within = [\"haze\", \"haze\"]", "", "")).unwrap_err();
    assert!(e.contains("listed twice"), "{e}");
}

/// A Mitsuba scene: the camera at z = 5 with the sensor in `fog` (if `sensor`), a fog box of
/// half size `half` at the origin and a glass ball bordered by the fog.
fn mitsuba(half: f32, sensor: bool) -> String {
    let medium = if sensor {
        r#"<ref id="fog" name="medium"/>"#
    } else {
        ""
    };
    format!(
        r#"<scene version="3.0.0">
    <medium type="homogeneous" id="fog"><rgb name="sigma_t" value="0.1"/></medium>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
        {medium}
    </sensor>
    <shape type="cube" id="box"><bsdf type="null"/><ref id="fog" name="interior"/>
        <transform name="to_world"><scale value="{half}"/></transform></shape>
    <shape type="sphere" id="ball"><bsdf type="dielectric"/><ref id="fog" name="exterior"/></shape>
</scene>"#
    )
}

#[test]
fn mitsuba_sensor_and_exterior_media_are_checked_against_the_geometry() {
    let load = |text: &str| compile_as(text, "scene.xml");
    // The fog box encloses camera and ball: as Mitsuba states.
    load(&mitsuba(8.0, true)).unwrap();
    // A box of half size 3 leaves the camera (at z = 5) outside: Mitsuba would render the
    // camera rays in fog up to the box, risotto in vacuum; refused, at the sensor's medium.
    let e = load(&mitsuba(3.0, true)).unwrap_err();
    assert!(
        e.contains("the camera is stated to be within the interior of \"box\"")
            && e.contains("in no volume")
            && e.contains("scene.xml:3"),
        "{e}"
    );
    // A box of half size 0.5 sits inside the ball: the ball's outside is no volume, refused
    // at the ball.
    let e = load(&mitsuba(0.5, false)).unwrap_err();
    assert!(
        e.contains("shape \"ball\" is stated to be within the interior of \"box\"")
            && e.contains("scene.xml:11"),
        "{e}"
    );
    load(&mitsuba(3.0, false)).unwrap();
}

/// Where Mitsuba leaves a medium unset it means vacuum: the sensor without a medium, a
/// medium's boundary without an exterior (leaving it puts the ray in vacuum), a glass or
/// null boundary without media (Mitsuba keeps the medium across it; risotto's volume would
/// be empty). The importer states "no medium" around each when the scene has media, so a
/// scene where Mitsuba's and risotto's media differ is an error, not another image.
#[test]
fn mitsuba_unset_media_are_checked_to_be_vacuum() {
    let load = |text: &str| compile_as(text, "scene.xml");
    // The camera inside the fog box without a sensor medium: Mitsuba renders it in vacuum.
    let e = load(&mitsuba(8.0, false)).unwrap_err();
    assert!(
        e.contains("the camera is stated to be in no medium") && e.contains("\"box\""),
        "{e}"
    );
    let body = |shapes: &str| {
        format!(
            r#"<scene version="3.0.0">
    <medium type="homogeneous" id="fog"><rgb name="sigma_t" value="0.1"/></medium>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <shape type="sphere" id="outer"><float name="radius" value="3"/><bsdf type="null"/><ref id="fog" name="interior"/></shape>
{shapes}
</scene>"#
        )
    };
    // A fog ball nested in the fog ball with no exterior: leaving it, Mitsuba's ray is in
    // vacuum; risotto's back in the outer fog.
    let e = load(&body(
        r#"<shape type="sphere" id="inner"><bsdf type="null"/><ref id="fog" name="interior"/></shape>"#,
    ))
    .unwrap_err();
    assert!(
        e.contains("shape \"inner\" is stated to be in no medium")
            && e.contains("\"outer\", which holds a medium"),
        "{e}"
    );
    // Stated as Mitsuba needs it (the exterior is the fog), it loads.
    load(&body(
        r#"<shape type="sphere" id="inner"><bsdf type="null"/><ref id="fog" name="interior"/><ref id="fog" name="exterior"/></shape>"#,
    ))
    .unwrap();
    // A clear glass ball in the fog: Mitsuba keeps the fog inside it, risotto's glass
    // volume would be empty.
    let e = load(&body(
        r#"<shape type="sphere" id="glass"><bsdf type="dielectric"/></shape>"#,
    ))
    .unwrap_err();
    assert!(
        e.contains("shape \"glass\" is stated to be in no medium"),
        "{e}"
    );
    // A fog ball reaching into the outer one with a part of its surface only (its first
    // primitives outside): found by the probes spread over its surface.
    let e = load(&body(
        r#"<shape type="sphere" id="part"><point name="center" x="0" y="0" z="3.5"/><bsdf type="null"/><ref id="fog" name="interior"/></shape>"#,
    ))
    .unwrap_err();
    assert!(
        e.contains("shape \"part\" is stated to be in no medium"),
        "{e}"
    );
    // A diffuse ball in the fog bounds no volume: nothing to check, it loads.
    load(&body(
        r#"<shape type="sphere" id="white"><bsdf type="diffuse"/></shape>"#,
    ))
    .unwrap();
}

#[test]
fn pbrt_camera_and_outside_media_are_checked_against_the_geometry() {
    // The camera at z = 5 in fog, a fog ball of radius `r` at the origin, and a small ball
    // at z = `z` whose outside is the fog.
    let pbrt = |r: f32, z: f32| {
        format!(
            "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         MediumInterface \"\" \"fog\"\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n\
             Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
             WorldBegin\n\
             AttributeBegin\nMaterial \"interface\"\nMediumInterface \"fog\" \"\"\n\
             Shape \"sphere\" \"float radius\" {r}\nAttributeEnd\n\
             MediumInterface \"\" \"fog\"\nTranslate 0 0 {z}\nShape \"sphere\" \"float radius\" 0.5\n"
        )
    };
    compile_as(&pbrt(10.0, 2.0), "scene.pbrt").unwrap();
    // Radius 4: the camera is outside the fog, the small ball inside it.
    let e = compile_as(&pbrt(4.0, 2.0), "scene.pbrt").unwrap_err();
    assert!(
        e.contains("the camera is stated to be within the interior of \"sphere at line 10\"")
            && e.contains("scene.pbrt:4"),
        "{e}"
    );
    // The small ball at z = -20, outside the fog the camera is in.
    let e = compile_as(&pbrt(10.0, -20.0), "scene.pbrt").unwrap_err();
    assert!(
        e.contains("shape \"sphere at line 14\" is stated to be within")
            && e.contains("in no volume")
            && e.contains("scene.pbrt:14"),
        "{e}"
    );
}

/// pbrt-v4 switches media only where a shape's inside and outside differ and keeps the
/// medium across any other shape, as Mitsuba does: where it leaves a medium unset (no camera
/// medium, a medium's boundary with an empty outside, a glass without an interface in a
/// medium) risotto's nested volumes agree only if no medium surrounds it, which the importer
/// states and the compile checks.
#[test]
fn pbrt_unset_media_are_checked_to_be_vacuum() {
    let head = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
                LookAt 0 0 9  0 0 0  0 1 0\nCamera \"perspective\"\n\
                Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
                WorldBegin\n\
                AttributeBegin\nMaterial \"interface\"\nMediumInterface \"fog\" \"\"\n\
                Shape \"sphere\" \"float radius\" 3\nAttributeEnd\n";
    let load = |rest: &str| compile_as(&format!("{head}{rest}"), "scene.pbrt");
    // A diffuse ball in the fog: nothing to check.
    load("Material \"diffuse\"\nShape \"sphere\" \"float radius\" 1\n").unwrap();
    // A glass ball in the fog without an interface: pbrt keeps the fog inside it.
    let e = load("Material \"dielectric\"\nShape \"sphere\" \"float radius\" 1\n").unwrap_err();
    assert!(
        e.contains("is stated to be in no medium") && e.contains("scene.pbrt:12"),
        "{e}"
    );
    // Stated inside the fog on both sides, it is still no transition in pbrt: the same.
    let e = load(
        "AttributeBegin\nMediumInterface \"fog\" \"fog\"\nMaterial \"dielectric\"\n\
         Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
    )
    .unwrap_err();
    assert!(e.contains("is stated to be in no medium"), "{e}");
    // A fog ball nested in the fog with an empty outside: vacuum around it in pbrt.
    let e = load(
        "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"fog\" \"\"\n\
         Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
    )
    .unwrap_err();
    assert!(e.contains("is stated to be in no medium"), "{e}");
    // A fog ball with the fog outside too is no transition in pbrt (the fog continues
    // across it), but risotto's interface makes a volume of it: refused as well.
    load(
        "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"fog\" \"fog\"\n\
         Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
    )
    .unwrap_err();
    // Outside the fog, a glass ball loads.
    load("Translate 0 0 -20\nMaterial \"dielectric\"\nShape \"sphere\" \"float radius\" 1\n")
        .unwrap();
}
