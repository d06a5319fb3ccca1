//! Scenes of Mitsuba 3's own test data (`mitsuba-renderer/mitsuba-data`, `tests/scenes/`):
//! the 27 whose features risotto reads, read from their unchanged XML and judged by Mitsuba's own render z-test
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
//! `texture_interp` needed the image pattern's `wrap`, `filter` and `uv_transform` (Mitsuba's
//! `wrap_mode`, `filter_type`, `to_uv`); the scenes with a `thindielectric` around a medium
//! needed panes that bound a volume, and Mitsuba's volumetric path tracers count a
//! `thindielectric`'s transmission as a null event, not a bounce (its component is flagged
//! `Null`; measured: 5 % of a pane-covered scene's light at `max_depth = 6`), now the
//! pane's `null_transmission`; and `hetero_spectral_sigmat_no_scattering` showed that a
//! `constvolume` bounds Mitsuba's heterogeneous medium to its box (`[0, 1]^3` without a
//! `to_world`), which the importer now writes as a box-bordered grid pattern.
//!
//! `participating_media/test_homo_area_light_volpath` and `test_homo_obj_inside_medium_volpath`
//! (media inside thin panes, lit from outside) agreed in the mean (channels within 0.25 %
//! of Mitsuba's) but were 2-5x noisier than the reference's per-sample variance allows
//! (99.740 % and 97.9 % of the pixels passed): Mitsuba's volumetric path tracers sample
//! lights through a `thindielectric` (a shadow ray passes a null pane attenuated by its
//! `1 - R'(theta)`), while risotto's shadow rays stopped at a pane. A null pane is now a
//! surface whose opacity is its reflectance `R'(theta)` (`BxdfFactory::opacity`, which may
//! read the direction), so light samples pass it as Mitsuba's do: 99.957 % and 100 %.
//!
//! Scenes of the directory left out, each a located error of the importer: `bumpmap`,
//! `normalmap` (3), `principled` (3), `mesh_attribute` (3), `projector` (2), the particle
//! tracer (`ptracer`) and a sphere with a non-uniform `to_world` (`various_shapes`). A
//! chromatic (3-channel) density grid in a mesh (`hetero_spectral_sigmat_volpathmis`) is
//! read as the sum of its channels' box-bordered grid patterns (a density per channel), as
//! a 3-channel albedo grid is (`hetero_sigmat_albedo`).

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
    hetero_sigmat_albedo => "participating_media/test_hetero_sigmat_albedo_volpath",
    homo_dielectric_envmap => "participating_media/test_homo_dielectric_envmap_volpath",
    homo_area_light => "participating_media/test_homo_area_light_volpath",
    homo_emitter_inside_medium => "participating_media/test_homo_emitter_inside_medium_volpath",
    homo_obj_inside_medium => "participating_media/test_homo_obj_inside_medium_volpath",
    hetero_spectral_sigmat_no_scattering => "participating_media/test_hetero_spectral_sigmat_no_scattering_volpath",
    homo_null_envmap => "participating_media/test_homo_null_envmap_volpath",
    homo_roughdielectric_spot => "participating_media/test_homo_roughdielectric_spot_volpath",
    homo_spectral_sigmat => "participating_media/test_homo_spectral_sigmat_volpathmis",
    hetero_spectral_sigmat => "participating_media/test_hetero_spectral_sigmat_volpathmis",
    surf_area_light => "participating_media/test_surf_area_light_volpath",
    spot_direct => "spot_light/test_spot_direct",
    texture_interp_direct => "texture_interp/test_texture_interp_direct",
}
