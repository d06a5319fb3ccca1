//! Microfacet parameters given as patterns (`alpha`, `alpha_u`, `alpha_v` of the rough
//! materials; `eta`, `k` of `rough_conductor`), end to end: a constant pattern renders as
//! its number, a pattern splitting a sphere in two renders each half as the material with
//! that half's value, white furnaces stay white with energy compensation between the
//! roughness grid's points, and bad patterns are located errors.

mod common;

use risotto::engine::render::RenderOutput;

/// A unit sphere of material `body` under a sun from the upper left and a dim sky, filling
/// a 48x48 view; `x = 0` (where the split patterns below switch) is the image's centre
/// column boundary. Paths bounce up to 8 times.
fn sphere_scene(body: &str, spp: u32) -> String {
    sphere_scene_depth(body, spp, 8)
}

/// [`sphere_scene`] with paths of at most `max_depth` bounces.
fn sphere_scene_depth(body: &str, spp: u32, max_depth: u32) -> String {
    let lights = "[[lights]]\ntype = \"distant\"\ndirection = [0.4, -0.5, -1]\nirradiance = 3\n\n\
                  [[lights]]\ntype = \"environment\"\nradiance = 0.2";
    common::sphere_scene(body, 48, 28.0, spp, max_depth, lights)
}

fn render(test: &str, text: &str) -> RenderOutput {
    let d = common::scratch_dir("rough_patterns", test);
    let out = common::render_scene_text(&d, text);
    assert_eq!(out.stats.counters.nan_dropped, 0, "{text}");
    out
}

/// A pattern switching from `a` (at `x < 0`) to `b` (at `x > 0`) within 0.002 of `x = 0`.
fn split(a: &str, b: &str) -> String {
    format!(
        "{{ pattern = \"gradient\", axis = \"x\", from = -0.001, to = 0.001, a = {a}, b = {b} }}"
    )
}

/// Block z-scores (8x8 blocks of a 48-wide image, 6 block columns, 3 channels) of `a`
/// against `b`, kept for the block columns `columns` (the two outermost on a side: the
/// centre's blocks straddle the switch through the pixel filter).
fn z_in_columns(a: &RenderOutput, b: &RenderOutput, columns: [usize; 2]) -> Vec<f64> {
    common::images::block_z(a, b)
        .chunks(3)
        .enumerate()
        .filter(|(k, _)| columns.contains(&(k % 6)))
        .flat_map(|(_, z)| z.to_vec())
        .collect()
}

const LEFT: [usize; 2] = [0, 1];
const RIGHT: [usize; 2] = [4, 5];

/// `what`'s left and right halves agree with `left` and `right` (every block |z| < 4.5),
/// and `left` and `right` themselves differ on the left (some |z| > 6), so that the test
/// could tell a half rendered with the wrong value.
fn assert_halves(what: &str, split: &RenderOutput, left: &RenderOutput, right: &RenderOutput) {
    for (side, reference, columns) in [("left", left, LEFT), ("right", right, RIGHT)] {
        let z = z_in_columns(split, reference, columns);
        let worst = z.iter().fold(0.0f64, |m, z| m.max(z.abs()));
        assert!(worst < 4.5, "{what}, {side} half: worst block |z| {worst}");
    }
    let apart = z_in_columns(left, right, LEFT);
    let most = apart.iter().fold(0.0f64, |m, z| m.max(z.abs()));
    assert!(
        most > 6.0,
        "{what}: the two values are not told apart ({most})"
    );
}

/// A roughness or index written as a `constant` pattern takes the pattern path (per-point
/// lobes, a one-point table grid) and renders bit for bit as the number, for the three
/// microfacet materials.
#[test]
fn a_constant_roughness_or_index_pattern_renders_as_the_number() {
    let number = render(
        "constant",
        &sphere_scene(
            "type = \"rough_conductor\"\nmaterial = \"Au\"\nalpha = 0.3",
            4,
        ),
    );
    let pattern = render(
        "constant",
        &sphere_scene(
            "type = \"rough_conductor\"\nmaterial = \"Au\"\n\
             alpha = { pattern = \"constant\", value = 0.3 }",
            4,
        ),
    );
    assert_eq!(number.beauty.pixels, pattern.beauty.pixels);
    let index = render(
        "constant",
        &sphere_scene(
            "type = \"rough_conductor\"\nalpha = 0.3\n\
             eta = { pattern = \"constant\", value = [0.14304, 0.37531, 1.442] }\n\
             k = [3.983, 2.3856, 1.6034]",
            4,
        ),
    );
    assert_eq!(number.beauty.pixels, index.beauty.pixels);
    for base in ["type = \"rough_dielectric\"", "type = \"rough_plastic\""] {
        let number = render(
            "constant",
            &sphere_scene(&format!("{base}\nalpha = 0.3"), 4),
        );
        let body = format!("{base}\nalpha = {{ pattern = \"constant\", value = 0.3 }}");
        let pattern = render("constant", &sphere_scene(&body, 4));
        assert_eq!(number.beauty.pixels, pattern.beauty.pixels, "{base}");
    }
}

/// A roughness switching from 0.08 to 0.6 across the sphere renders each half as the
/// material with that roughness, for the conductor, the dielectric and the plastic. Light refracted into
/// the glass crosses to the other half, so the glass's paths stop after their second
/// bounce (what each half reflects and transmits there is its own).
#[test]
fn a_roughness_split_renders_each_half_as_its_constant() {
    for (base, depth) in [
        ("type = \"rough_conductor\"\nmaterial = \"Cu\"", 8),
        ("type = \"rough_dielectric\"\nior = 1.5", 2),
        (
            "type = \"rough_plastic\"\ndiffuse_reflectance = [0.6, 0.2, 0.2]",
            8,
        ),
    ] {
        let with = |alpha: &str| {
            let body = format!("{base}\nalpha = {alpha}");
            render("split", &sphere_scene_depth(&body, 64, depth))
        };
        let split = with(&split("0.08", "0.6"));
        assert_halves(base, &split, &with("0.08"), &with("0.6"));
    }
}

/// A complex index switching from gold's to silver's across the sphere renders each half
/// as `material = "Au"` and `"Ag"`.
#[test]
fn an_index_split_renders_gold_and_silver_halves() {
    let (au_eta, au_k) = ("[0.14304, 0.37531, 1.442]", "[3.983, 2.3856, 1.6034]");
    let (ag_eta, ag_k) = ("[0.15528, 0.11673, 0.13839]", "[4.8284, 3.1222, 2.1469]");
    let body = format!(
        "type = \"rough_conductor\"\nalpha = 0.2\neta = {}\nk = {}",
        split(au_eta, ag_eta),
        split(au_k, ag_k)
    );
    let split = render("metals", &sphere_scene(&body, 64));
    let metal = |m: &str| {
        render(
            "metals",
            &sphere_scene(
                &format!("type = \"rough_conductor\"\nalpha = 0.2\nmaterial = \"{m}\""),
                64,
            ),
        )
    };
    assert_halves("Au | Ag", &split, &metal("Au"), &metal("Ag"));
}

/// The image's mean, per channel averaged.
fn furnace_mean(body: &str) -> f64 {
    let out = render("furnace", &common::sphere_furnace_scene(body, 64));
    let px = &out.beauty.pixels;
    px.iter().map(|c| c.average() as f64).sum::<f64>() / px.len() as f64
}

/// White rough materials whose roughness varies continuously over the sphere (so almost
/// every point lies between the table grid's roughnesses) stay white in a furnace with
/// energy compensation, within 1% (1.5% anisotropic, as the constant case's test), and
/// lose energy without it.
#[test]
fn varying_roughness_stays_white_in_a_furnace() {
    let ramp = "{ pattern = \"gradient\", axis = \"x\", from = -1, to = 1, a = 0.05, b = 1 }";
    let noise = "{ pattern = \"remap\", a = { pattern = \"noise\", frequency = 3 }, \
                 from = [-0.6, 0.6], to = [0.3, 1] }";
    for (body, tolerance) in [
        (format!("type = \"rough_conductor\"\nalpha = {ramp}"), 0.01),
        (
            format!("type = \"rough_conductor\"\nalpha = {noise}\ndistribution = \"beckmann\""),
            0.01,
        ),
        (
            format!("type = \"rough_dielectric\"\nalpha = {ramp}\nior = 1.5"),
            0.01,
        ),
        (
            format!("type = \"rough_conductor\"\nalpha_u = {ramp}\nalpha_v = 0.3"),
            0.015,
        ),
        (
            format!("type = \"rough_conductor\"\nalpha_u = {ramp}\nalpha_v = {noise}"),
            0.015,
        ),
    ] {
        let on = furnace_mean(&body);
        println!("{body}: furnace mean {on:.4}");
        assert!((on - 1.0).abs() < tolerance, "{body}: compensated {on}");
    }
    let off = furnace_mean(&format!(
        "type = \"rough_conductor\"\nalpha = {ramp}\nenergy_compensation = false"
    ));
    println!("uncompensated ramp: furnace mean {off:.4}");
    assert!(off < 0.9, "uncompensated: {off}");
}

/// Roughness and index patterns that may leave their range, or are coloured where one
/// number is needed, are located errors naming the key and the bounds.
#[test]
fn bad_roughness_and_index_patterns_are_located_errors() {
    let d = common::scratch_dir("rough_patterns", "errors");
    let cases: [(&str, &[&str]); 5] = [
        (
            "type = \"rough_conductor\"\nalpha = { pattern = \"noise\" }",
            &["alpha", "(0, 1]", "-2.8", "remap"],
        ),
        (
            "type = \"rough_dielectric\"\nalpha = { pattern = \"constant\", value = [0.1, 0.2, 0.3] }",
            &["alpha", "grey"],
        ),
        (
            "type = \"rough_conductor\"\nalpha_u = 0.2\nalpha_v = { pattern = \"gradient\", a = 0, b = 0.5 }",
            &["alpha_v", "(0, 1]", "0 .. 0.5"],
        ),
        (
            "type = \"rough_conductor\"\neta = 1\nk = { pattern = \"noise\", frequency = 2 }",
            &["`k`", ">= 0", "-2.8", "remap"],
        ),
        (
            "type = \"rough_plastic\"\nalpha = { pattern = \"checker\", a = 0.2, b = 1.2 }",
            &["alpha", "(0, 1]", "1.2"],
        ),
    ];
    common::assert_located_errors(&d, &cases);
}
