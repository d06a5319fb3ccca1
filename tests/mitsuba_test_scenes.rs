//! Scenes of Mitsuba 3's own test data (`mitsuba-renderer/mitsuba-data`, `tests/scenes/`):
//! every one whose features risotto reads (20), read from their unchanged XML and judged by Mitsuba's own render z-test
//! (`risotto::tools::z_test`: per pixel and XYZ channel against the reference's per-sample
//! variance, Sidak-corrected, 99.75 % of the pixels must pass), at Mitsuba's test budget of
//! 2e6 samples per image.
//!
//! The files sit under `tests/data/mitsuba-data/` in the repository's own layout
//! (`tests/scenes/...` and the `common/` meshes and textures their `<path>` names), copied
//! from commit 01100fa. The references (`tests/data/mitsuba-data/refs/`) were made with the
//! Mitsuba harness as Mitsuba's `test_render.py` makes its own (the scene's `moment` wrapper
//! gives the mean and the per-sample variance), Mitsuba 3.9.1 `llvm_ad_rgb`, 16384 spp:
//!
//! ```text
//! cd tests/data/mitsuba-data/tests/scenes
//! ../../../../../../shared/refs/mitsuba/run.sh ../../make_refs.py ../../refs DIR/SCENE.xml \
//!     --spp 16384 --pass-spp 1024
//! ```
//!
//! What the test found and what was fixed: a `rectangle`'s texture coordinates were the
//! triangles' barycentrics (`orthographic_sensor`: 85 % of the pixels passed; now Mitsuba's
//! `(x + 1) / 2, (y + 1) / 2`); an OBJ's `v` was not flipped as Mitsuba flips it
//! (`surf_area_light`, the checkerboard background: 58 %; now `flip_tex_coords`); the rough
//! plastic's coat tables weighed the refracted direction by the height-correlated `G2`
//! where Mitsuba's use `G1` (up to 2x in the diffuse lobe at alpha 1; now Mitsuba's); and
//! Mitsuba's microfacet lobes use the separable masking-shadowing `G1(wo) G1(wi)` where
//! risotto's default is height-correlated, brighter at grazing angles (the roughplastic
//! grids passed 99.71 % of their pixels, 99.75 % are needed): now `masking = "separable"`,
//! which the importer writes. `participating_media/test_homo_dielectric_envmap_volpath` (two
//! water spheres with vertex normals) passed 91 % of its pixels: risotto's smooth dielectric
//! refracted about the geometric normal where Mitsuba's (and risotto's other materials) use
//! the shading normal (fixed), and Mitsuba keeps the directions the two normals classify
//! differently where risotto's default discards them (0.5 % darker with the dielectric
//! fixed): now `[render] shading_normals = "shading_frame"`, which the importer writes.

mod common;

use risotto::engine::output::read_exr_rgb;
use risotto::loader::load::{scene_from_desc, MaterialRegistry};
use risotto::loader::scene_file::load_scene;
use risotto::tools::z_test::{mitsuba_test_spp, mitsuba_z_test};
use std::path::Path;

/// Renders `tests/scenes/{scene}.xml` at its own size with Mitsuba's test budget and runs
/// Mitsuba's z-test against `refs/{stem}_ref_rgb.exr` and its `_var` image.
fn z_test(scene: &str) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba-data");
    let xml = data.join("tests/scenes").join(format!("{scene}.xml"));
    let mut desc = load_scene(&xml).unwrap_or_else(|e| panic!("{}: {e}", xml.display()));
    let spp = mitsuba_test_spp(desc.render.width as usize, desc.render.height as usize);
    desc.render.spp = spp;
    let compiled = scene_from_desc(desc, &MaterialRegistry::with_builtins())
        .unwrap()
        .compile()
        .unwrap();
    let out = common::render_default(&compiled);
    assert_eq!(out.stats.counters.nan_dropped, 0, "{scene}: NaN samples");
    let stem = Path::new(scene).file_name().unwrap().to_str().unwrap();
    let reference = read_exr_rgb(&data.join(format!("refs/{stem}_ref_rgb.exr"))).unwrap();
    let variance = read_exr_rgb(&data.join(format!("refs/{stem}_ref_rgb_var.exr"))).unwrap();
    let outcome = mitsuba_z_test(&out.beauty, spp, &reference, &variance).unwrap();
    eprintln!("{scene} ({spp} spp): {outcome}");
    assert!(outcome.accepted, "{scene} ({spp} spp): {outcome}");
}

macro_rules! mitsuba_test_scene {
    ($($name:ident => $scene:literal,)*) => {
        $(
            #[test]
            fn $name() {
                z_test($scene);
            }
        )*
    };
}

mitsuba_test_scene! {
    bsdf_spheres_arealight => "bsdf_spheres/test_arealight_path",
    bsdf_spheres_constant => "bsdf_spheres/test_constant_path",
    bsdf_spheres_envmap => "bsdf_spheres/test_envmap_path",
    bsdf_spheres_pointlight => "bsdf_spheres/test_pointlight_path",
    bsdf_spheres_textured_diffuse => "bsdf_spheres/test_textured_diffuse_path",
    bsdf_spheres_roughdielectric => "bsdf_spheres/test_roughdielectric_path",
    bsdf_spheres_roughplastic_linear => "bsdf_spheres/test_roughplastic_linear_path",
    bsdf_spheres_roughplastic_nonlinear => "bsdf_spheres/test_roughplastic_nonlinear_path",
    bsdf_spheres_textured_roughconductor => "bsdf_spheres/test_textured_roughconductor_path",
    floating_sphere_directional_direct => "floating_sphere/test_directional_direct",
    infinite_mirrors => "infinite_mirrors/scene_path",
    instancing => "instancing/test_instancing_path",
    orthographic_sensor => "orthographic_sensor/test_orthographic_path",
    hetero_sigmat => "participating_media/test_hetero_sigmat_volpath",
    homo_dielectric_envmap => "participating_media/test_homo_dielectric_envmap_volpath",
    homo_null_envmap => "participating_media/test_homo_null_envmap_volpath",
    homo_roughdielectric_spot => "participating_media/test_homo_roughdielectric_spot_volpath",
    homo_spectral_sigmat => "participating_media/test_homo_spectral_sigmat_volpathmis",
    surf_area_light => "participating_media/test_surf_area_light_volpath",
    spot_direct => "spot_light/test_spot_direct",
    texture_interp_direct => "texture_interp/test_texture_interp_direct",
}
