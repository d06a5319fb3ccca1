//! Opacity on any material (issue 32; the seed's opacity shaders "in addition to
//! `GetTransmission`"): path rays pass a surface of opacity `a` with probability `1 - a`,
//! shadow rays are attenuated by `1 - a`, the two estimate the same transport, a fully
//! transparent stack cannot loop forever, scenes without opacity run no opacity stage, and a
//! plug-in's opacity may depend on the direction (`BxdfFactory::opacity`).

mod common;
use common::*;
use risotto::engine::stats::Termination;
use risotto_components::Rgb;

/// Render settings and camera of the test scenes: `from` looking at `to` with a 40-degree
/// field of view, `n` x `n` pixels, `spp` samples.
fn header(n: u32, spp: u32, from: &str, to: &str) -> String {
    format!(
        "[render]\nwidth = {n}\nheight = {n}\nspp = {spp}\nmax_depth = 8\nseed = 3\n\n\
         [camera]\nfov = 40\nfrom = {from}\nto = {to}\nup = [0, 0, -1]\n\n"
    )
}

/// A unit-radiance emitter filling the view, seen through a black sheet of opacity
/// `opacity` (none: no sheet).
fn emitter_behind_sheet(opacity: Option<f32>) -> String {
    let mut s = header(16, 64, "[0, 3, 0]", "[0, 0, 0]");
    s += "[materials.black]\ntype = \"diffuse\"\nreflectance = 0\n\n";
    // Emits upwards (+y, towards the camera): edge1 x edge2 = z x x = +y.
    s += "[[shapes]]\nname = \"lamp\"\ntype = \"quad\"\nmaterial = \"black\"\n\
          corner = [-5, 0, -5]\nedge1 = [0, 0, 10]\nedge2 = [10, 0, 0]\nemission = 1\n\n";
    if let Some(a) = opacity {
        s += &format!(
            "[materials.sheet]\ntype = \"diffuse\"\nreflectance = 0\nopacity = {a}\n\n\
             [[shapes]]\nname = \"sheet\"\ntype = \"quad\"\nmaterial = \"sheet\"\n\
             corner = [-5, 1, -5]\nedge1 = [0, 0, 10]\nedge2 = [10, 0, 0]\n\n"
        );
    }
    s
}

#[test]
fn camera_rays_see_seventy_percent_of_an_emitter_through_opacity_0_3() {
    let dir = scratch_dir("opacity", "camera");
    let out = render_scene_text(&dir, &emitter_behind_sheet(Some(0.3)));
    assert_finite("sheet", &out);
    let (mean, _) = image_mean(&out);
    // Each camera sample is 0 or 1: iid standard error sqrt(0.21 / 16384) = 0.0036 (the
    // sampler does better); a sheet that passed with probability a (0.3) would be 40 sigma
    // off.
    for c in [mean.r, mean.g, mean.b] {
        assert!((c - 0.7).abs() < 0.015, "mean {mean:?}, expected 0.7");
    }
    let c = &out.stats.counters;
    assert!(c.opacity_tests > 0 && c.opacity_passes > 0);
    let pass_rate = c.opacity_passes as f64 / c.opacity_tests as f64;
    assert!((pass_rate - 0.7).abs() < 0.015, "pass rate {pass_rate}");
}

/// A grey floor lit by the sun only (a delta light: shadow rays are its only estimator),
/// seen from below a black roof of opacity `opacity` that covers the whole scene.
fn sunlit_floor_under_roof(opacity: f32) -> String {
    let mut s = header(16, 4, "[0, 1, 0]", "[0, 0, 0]");
    s += &format!(
        "[materials.grey]\ntype = \"diffuse\"\nreflectance = 0.5\n\n\
         [materials.roof]\ntype = \"diffuse\"\nreflectance = 0\nopacity = {opacity}\n\n\
         [[shapes]]\nname = \"floor\"\ntype = \"quad\"\nmaterial = \"grey\"\n\
         corner = [-50, 0, -50]\nedge1 = [0, 0, 100]\nedge2 = [100, 0, 0]\n\n\
         [[shapes]]\nname = \"roof\"\ntype = \"quad\"\nmaterial = \"roof\"\n\
         corner = [-50, 2, -50]\nedge1 = [0, 0, 100]\nedge2 = [100, 0, 0]\n\n\
         [[lights]]\ntype = \"distant\"\ndirection = [0.2, -1, 0.1]\nirradiance = 3\n"
    );
    s
}

#[test]
fn shadow_rays_are_attenuated_by_one_minus_opacity() {
    let dir = scratch_dir("opacity", "shadow");
    // Opacity 1 leaves the material opaque (no mask): the sun is blocked.
    let blocked = render_scene_text(&dir, &sunlit_floor_under_roof(1.0));
    let half = render_scene_text(&dir, &sunlit_floor_under_roof(0.3));
    let open = render_scene_text(&dir, &sunlit_floor_under_roof(0.0));
    let (b, _) = image_mean(&blocked);
    assert!(b.is_black(), "an opaque roof blocks the sun: {b:?}");
    assert_eq!(blocked.stats.counters.opacity_shadow_crossings, 0);
    // The floor sees the sun through the roof only; the black roof reflects nothing and
    // the camera under it never meets it, so each pixel is its direct light times 0.7,
    // exactly: the shadow rays' attenuation is deterministic, and the opacity choices
    // draw from their own sequence, so both renders take the same camera samples.
    assert!(half.stats.counters.opacity_shadow_crossings > 0);
    for (h, o) in half.beauty.pixels.iter().zip(&open.beauty.pixels) {
        for (h, o) in [(h.r, o.r), (h.g, o.g), (h.b, o.b)] {
            assert!(o > 0.0, "lit floor");
            assert!(
                (h / o - 0.7).abs() < 1e-4,
                "pixel {h} vs {o} without the roof's opacity"
            );
        }
    }
}

/// A grey floor under a large area light, seen from below a black sheet of opacity
/// `opacity` between them: light reaches the floor both by light samples (shadow rays
/// through the sheet) and by Bxdf samples (path rays passing it), weighted by MIS.
fn lamp_over_sheet(opacity: Option<f32>) -> String {
    let mut s = header(16, 256, "[0, 0.5, 0]", "[0, 0, 0]");
    s += "[materials.grey]\ntype = \"diffuse\"\nreflectance = 0.5\n\n\
          [materials.black]\ntype = \"diffuse\"\nreflectance = 0\n\n\
          [[shapes]]\nname = \"floor\"\ntype = \"quad\"\nmaterial = \"grey\"\n\
          corner = [-20, 0, -20]\nedge1 = [0, 0, 40]\nedge2 = [40, 0, 0]\n\n\
          [[shapes]]\nname = \"lamp\"\ntype = \"quad\"\nmaterial = \"black\"\n\
          corner = [-2, 2, -2]\nedge1 = [4, 0, 0]\nedge2 = [0, 0, 4]\nemission = 2\n\n";
    if let Some(a) = opacity {
        s += &format!(
            "[materials.sheet]\ntype = \"diffuse\"\nreflectance = 0\nopacity = {a}\n\n\
             [[shapes]]\nname = \"sheet\"\ntype = \"quad\"\nmaterial = \"sheet\"\n\
             corner = [-20, 1, -20]\nedge1 = [0, 0, 40]\nedge2 = [40, 0, 0]\n\n"
        );
    }
    s
}

#[test]
fn light_samples_and_bxdf_samples_through_opacity_agree() {
    let dir = scratch_dir("opacity", "mis");
    let open = render_scene_text(&dir, &lamp_over_sheet(None));
    let sheet = render_scene_text(&dir, &lamp_over_sheet(Some(0.3)));
    assert_finite("sheet", &sheet);
    let ((o, oe), (s, se)) = (image_mean(&open), image_mean(&sheet));
    // Floor radiance through the sheet: 0.7 of it, whether the light arrives by a shadow
    // ray (attenuated) or a Bxdf sample (passing with probability 0.7). Counting emission
    // behind a pass twice, or attenuating Bxdf-sampled light as well, would be 0.49 or
    // 1.4 of the open value, many standard errors off.
    let ratio = s.r / o.r;
    let err = 0.7 * ((se.r / s.r).powi(2) + (oe.r / o.r).powi(2)).sqrt();
    assert!(
        (ratio - 0.7).abs() < 4.0 * err.max(0.002),
        "ratio {ratio} (expected 0.7 +- {err})"
    );
}

#[test]
fn fully_transparent_layers_are_bounded_and_finite() {
    // Forty stacked sheets of opacity 0 over an emitter: every camera ray passes them all.
    // With the pass budget at 8, every path stops at the ninth sheet (counted as
    // `pass_limit`), and nothing is NaN; with the default budget (1024) they reach the lamp.
    let mut s = emitter_behind_sheet(None);
    s += "[materials.clear]\ntype = \"diffuse\"\nreflectance = 0.5\nopacity = 0\n\n";
    for k in 0..40 {
        let y = 0.5 + 0.05 * k as f32;
        s += &format!(
            "[[shapes]]\nname = \"sheet{k}\"\ntype = \"quad\"\nmaterial = \"clear\"\n\
             corner = [-5, {y}, -5]\nedge1 = [0, 0, 10]\nedge2 = [10, 0, 0]\n\n"
        );
    }
    let dir = scratch_dir("opacity", "bounded");
    let mut scene = load_scene_text(&dir, &s).unwrap();
    let full = render_default(&scene);
    assert_finite("clear sheets", &full);
    let (mean, _) = image_mean(&full);
    // Opacity 0: the sheets are not there (only rounding of the restarted rays differs).
    assert!((mean.r - 1.0).abs() < 1e-4, "{mean:?}");
    scene.settings.max_passes = 8;
    let cut = render_default(&scene);
    assert_finite("clear sheets, budget 8", &cut);
    let c = &cut.stats.counters;
    let pixels = 16 * 16 * 64;
    assert_eq!(c.terminated[Termination::PassLimit as usize], pixels);
    assert_eq!(image_mean(&cut).0, Rgb::BLACK);
}

#[test]
fn only_scenes_with_opacity_run_the_opacity_stage() {
    let dir = scratch_dir("opacity", "stage");
    let without = render_scene_text(&dir, &emitter_behind_sheet(None));
    assert!(!without.stats.features.iter().any(|f| f == "opacity"));
    let c = &without.stats.counters;
    assert_eq!(
        (c.opacity_tests, c.opacity_shadow_crossings),
        (0, 0),
        "no opacity, no opacity stage"
    );
    let json = serde_json::to_string(&without.stats).unwrap();
    assert!(!json.contains("opacity_tests"), "{json}");
    assert!(!without.stats.to_string().contains("opacity:"));
    // Opacity 1 is the opaque default: still no opacity stage.
    let opaque = render_scene_text(&dir, &emitter_behind_sheet(Some(1.0)));
    assert!(!opaque.stats.features.iter().any(|f| f == "opacity"));
    assert_eq!(opaque.stats.counters.opacity_tests, 0);
    let with = render_scene_text(&dir, &emitter_behind_sheet(Some(0.5)));
    assert!(with.stats.features.iter().any(|f| f == "opacity"));
    assert!(with.stats.counters.opacity_tests > 0);
    let json = serde_json::to_string(&with.stats).unwrap();
    assert!(json.contains("\"opacity_tests\""), "{json}");
    let shown = with.stats.to_string();
    assert!(
        shown.contains("opacity: ") && shown.contains("path-ray tests"),
        "{shown}"
    );
}

/// The error loading `material` (the lines of one material table, named `m`) in a small
/// scene, checked to name the scene file, the line of `needle` and every fragment.
fn assert_material_error(dir: &std::path::Path, material: &str, needle: &str, fragments: &[&str]) {
    let text = format!(
        "{}[materials.m]\n{material}\n\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"m\"\n\
         center = [0, 0, 0]\nradius = 1\n",
        header(8, 1, "[0, 3, 0]", "[0, 0, 0]")
    );
    let line = text[..text.find(needle).expect("needle in text")]
        .matches('\n')
        .count()
        + 1;
    let e = match load_scene_text(dir, &text) {
        Ok(_) => panic!("expected an error for:\n{material}"),
        Err(risotto::loader::load::LoadError::Scene(e)) => e,
        Err(e) => panic!("not a scene error: {e}"),
    };
    let msg = e.to_string();
    assert!(msg.contains("scene.toml"), "no file in: {msg}");
    assert_eq!(e.line(), Some(line), "{msg}");
    for f in fragments {
        assert!(msg.contains(f), "message lacks `{f}`: {msg}");
    }
}

#[test]
fn bad_opacity_is_a_located_error() {
    let dir = scratch_dir("opacity", "errors");
    // Outside [0, 1], or not a number, on any material type.
    let cases = [
        (
            "type = \"diffuse\"\nopacity = 1.5",
            "opacity",
            &["opacity", "1.5", "[0, 1]"][..],
        ),
        (
            "type = \"dielectric\"\nopacity = -0.25",
            "opacity",
            &["opacity", "-0.25"][..],
        ),
        (
            "type = \"interface\"\nopacity = nan",
            "opacity",
            &["opacity", "nan"][..],
        ),
        (
            "type = \"subsurface\"\nopacity = \"half\"",
            "opacity",
            &["opacity", "half"][..],
        ),
        // A pattern whose bounds leave [0, 1] (a checker with a = 2).
        (
            "type = \"diffuse\"\nopacity = { pattern = \"checker\", a = 2 }",
            "opacity",
            &["opacity", "[2, 2, 2]", "remap"][..],
        ),
    ];
    for (material, needle, fragments) in cases {
        assert_material_error(&dir, material, needle, fragments);
    }
    // An image without alpha asked for its alpha; an unknown channel.
    let rgb = dir.join("rgb.png");
    let file = std::fs::File::create(&rgb).unwrap();
    let mut e = png::Encoder::new(file, 1, 1);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header()
        .unwrap()
        .write_image_data(&[1, 2, 3])
        .unwrap();
    assert_material_error(
        &dir,
        "type = \"diffuse\"\nopacity = { pattern = \"image\", path = \"rgb.png\", channel = \"a\" }",
        "opacity",
        &["rgb.png", "alpha", "Rgb"],
    );
    assert_material_error(
        &dir,
        "type = \"diffuse\"\nopacity = { pattern = \"image\", path = \"rgb.png\", channel = \"alpha\" }",
        "opacity",
        &["channel", "\"alpha\"", "\"a\""],
    );
}

/// A plug-in's direction-dependent opacity (`BxdfFactory::opacity`, which a user's factory
/// overrides as the built-in null pane does): a black veil present with probability
/// `1 - |cos|` of the hit's angle to its normal, so it lets through `|cos|` of the light
/// crossing it, by path rays and by shadow rays alike.
struct Veil;

impl risotto::engine::plugin::BxdfFactory for Veil {
    fn instance_hints(&self) -> risotto::engine::plugin::InstanceHints {
        risotto::engine::plugin::InstanceHints::OPACITY
    }
    fn begin_scatter<'a>(
        &'a self,
        _ctx: &'a risotto::engine::plugin::ShadingContext<'a>,
        _mode: risotto::engine::plugin::ShadingMode,
        arena: &'a bumpalo::Bump,
    ) -> &'a mut (dyn risotto::engine::plugin::Bxdf + 'a) {
        arena.alloc(risotto::engine::plugin::NullBxdf)
    }
    fn opacity(&self, ctx: &risotto::engine::plugin::ShadingContext<'_>, out: &mut [f32]) {
        for (a, (n, v)) in out.iter_mut().zip(ctx.nn().iter().zip(ctx.vn())) {
            *a = 1.0 - n.dot(*v).abs();
        }
    }
}

/// Renders `text` with the built-in materials and the plug-in type `veil`.
fn render_with_veil(dir: &std::path::Path, text: &str) -> risotto::engine::render::RenderOutput {
    use risotto::loader::load::{scene_from_desc, MaterialRegistry};
    let mut registry = MaterialRegistry::with_builtins();
    registry.register("veil", |_| Ok(Box::new(Veil)));
    let desc = risotto::loader::scene_file::parse_scene(text, &dir.join("scene.toml")).unwrap();
    let scene = scene_from_desc(desc, &registry).unwrap().compile().unwrap();
    render_default(&scene)
}

#[test]
fn a_plug_in_opacity_may_depend_on_the_direction() {
    let dir = scratch_dir("opacity", "veil");
    // The veil turned by `angle` about z between the camera (or the sun) and what it
    // looks at (or lights).
    let veil = |angle: f32| {
        format!(
            "[materials.veil]\ntype = \"veil\"\n\n\
             [[shapes]]\nname = \"veil\"\ntype = \"quad\"\nmaterial = \"veil\"\n\
             corner = [-50, 0, -50]\nedge1 = [0, 0, 100]\nedge2 = [100, 0, 0]\n\
             transform = [{{ rotate = {{ axis = [0, 0, 1], angle = {angle} }} }}, \
             {{ translate = [0, 1.5, 0] }}]\n\n"
        )
    };
    // Path rays: a unit emitter seen through the veil at 60 degrees by parallel camera rays
    // passes cos 60 = 0.5 of each camera sample (0 or 1: standard error
    // sqrt(0.25 / 16384) = 0.004).
    let mut emitter = header(16, 64, "[0, 3, 0]", "[0, 0, 0]")
        .replace("fov = 40", "projection = \"orthographic\"\nwidth = 1");
    emitter += "[materials.black]\ntype = \"diffuse\"\nreflectance = 0\n\n\
                [[shapes]]\nname = \"lamp\"\ntype = \"quad\"\nmaterial = \"black\"\n\
                corner = [-50, 0, -50]\nedge1 = [0, 0, 100]\nedge2 = [100, 0, 0]\nemission = 1\n\n";
    let out = render_with_veil(&dir, &(emitter + &veil(60.0)));
    assert_finite("veil", &out);
    let (mean, _) = image_mean(&out);
    assert!((mean.g - 0.5).abs() < 0.02, "mean {mean:?}, expected 0.5");
    // Shadow rays: the sun straight down through the veil at `angle` onto a grey floor seen
    // from below the veil is `cos(angle)` of the open floor's light, exactly (deterministic
    // attenuation, the same camera samples).
    let floor = |veiled: Option<f32>| {
        let mut s = header(8, 4, "[0, 1, 0]", "[0, 0, 0]");
        s += "[materials.grey]\ntype = \"diffuse\"\nreflectance = 0.5\n\n\
              [[shapes]]\nname = \"floor\"\ntype = \"quad\"\nmaterial = \"grey\"\n\
              corner = [-50, 0, -50]\nedge1 = [0, 0, 100]\nedge2 = [100, 0, 0]\n\n\
              [[lights]]\ntype = \"distant\"\ndirection = [0, -1, 0]\nirradiance = 3\n\n";
        if let Some(angle) = veiled {
            s += &veil(angle);
        }
        render_with_veil(&dir, &s)
    };
    let open = floor(None);
    for angle in [30.0f32, 75.0] {
        let veiled = floor(Some(angle));
        let expected = angle.to_radians().cos();
        for (v, o) in veiled.beauty.pixels.iter().zip(&open.beauty.pixels) {
            assert!(o.g > 0.0, "lit floor");
            assert!(
                (v.g / o.g - expected).abs() < 1e-4,
                "angle {angle}: {} of the open floor, expected {expected}",
                v.g / o.g
            );
        }
    }
}
