//! Mesh vertex attributes in images: a tessellated sphere with vertex normals renders within
//! noise of the analytic sphere (and the same mesh shaded flat does not), OBJ and PLY files
//! of one mesh render identically, a coarse mesh with bent normals leaks no light from
//! behind, smooth normals do not darken a white furnace, and a coarse smooth mesh shows no
//! faceted shadow terminator (rays leave from the smooth surface, Hanika 2021).

mod common;

use common::*;
use std::f32::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

/// A UV sphere of radius 1 at the origin: `nu` segments in `phi`, `nv` rings in `theta`
/// (from `+z`), the seam and pole vertices duplicated so that `uv = (phi / 2pi, theta /
/// pi)` is continuous on every triangle (the renderer's own sphere parameterisation);
/// triangles wound outwards, the degenerate ones at the poles left out.
struct UvSphere {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    triangles: Vec<[u32; 3]>,
}

fn uv_sphere(nu: u32, nv: u32) -> UvSphere {
    let mut s = UvSphere {
        positions: Vec::new(),
        uvs: Vec::new(),
        triangles: Vec::new(),
    };
    for i in 0..=nv {
        for j in 0..=nu {
            let (u, v) = (j as f32 / nu as f32, i as f32 / nv as f32);
            let (theta, phi) = (v * PI, u * 2.0 * PI);
            s.positions.push([
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]);
            s.uvs.push([u, v]);
        }
    }
    let at = |i: u32, j: u32| i * (nu + 1) + j;
    for i in 0..nv {
        for j in 0..nu {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if i + 1 < nv {
                s.triangles.push([a, b, c]);
            }
            if i > 0 {
                s.triangles.push([a, c, d]);
            }
        }
    }
    s
}

/// Writes the sphere as OBJ (`v`, `vt`, `vn` with the position as the normal).
fn write_obj(s: &UvSphere, path: &Path) {
    let mut t = String::new();
    for p in &s.positions {
        writeln!(t, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for uv in &s.uvs {
        writeln!(t, "vt {} {}", uv[0], uv[1]).unwrap();
    }
    for p in &s.positions {
        writeln!(t, "vn {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for tri in &s.triangles {
        let [a, b, c] = tri.map(|i| i + 1);
        writeln!(t, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}").unwrap();
    }
    std::fs::write(path, t).unwrap();
}

/// Writes the sphere as PLY in `format` (`ascii`, `binary_little_endian` or
/// `binary_big_endian`), pairs of triangles that share an edge as one quad where `quads`.
fn write_ply(s: &UvSphere, path: &Path, format: &str) {
    let mut head = format!(
        "ply\nformat {format} 1.0\ncomment risotto test\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property float u\nproperty float v\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        s.positions.len(),
        s.triangles.len()
    );
    let mut body: Vec<u8> = Vec::new();
    let f = |x: f32, out: &mut Vec<u8>| match format {
        "binary_little_endian" => out.extend(x.to_le_bytes()),
        _ => out.extend(x.to_be_bytes()),
    };
    let i = |x: i32, out: &mut Vec<u8>| match format {
        "binary_little_endian" => out.extend(x.to_le_bytes()),
        _ => out.extend(x.to_be_bytes()),
    };
    for (p, uv) in s.positions.iter().zip(&s.uvs) {
        if format == "ascii" {
            writeln!(
                head,
                "{} {} {} {} {} {} {} {}",
                p[0], p[1], p[2], p[0], p[1], p[2], uv[0], uv[1]
            )
            .unwrap();
        } else {
            for x in [p[0], p[1], p[2], p[0], p[1], p[2], uv[0], uv[1]] {
                f(x, &mut body);
            }
        }
    }
    for t in &s.triangles {
        if format == "ascii" {
            writeln!(head, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
        } else {
            body.push(3);
            for &v in t {
                i(v as i32, &mut body);
            }
        }
    }
    let mut bytes = head.into_bytes();
    bytes.extend(body);
    std::fs::write(path, bytes).unwrap();
}

/// A scene text: the shape `shape` (a table body) seen by a 64 x 64 camera, diffuse
/// `material` (a table body), lit by a sun from the side and a dim environment.
fn sphere_scene(shape: &str, material: &str, spp: u32) -> String {
    format!(
        r#"
[render]
width = 64
height = 64
spp = {spp}
max_depth = 4
seed = 7

[camera]
fov = 30
from = [0, 0, 5]
to = [0, 0, 0]

[materials.m]
{material}

[[shapes]]
name = "s"
material = "m"
{shape}

[[lights]]
type = "distant"
direction = [-1, -0.3, -0.4]
irradiance = 3

[[lights]]
type = "environment"
radiance = 0.2
"#
    )
}

/// Block z-scores of the difference of two renders (8 x 8 blocks of pixels, channels
/// summed): `(mean_a - mean_b) / sqrt(var_a + var_b)` per block, from the films'
/// variances of the pixel means.
fn block_z(
    a: &risotto::engine::render::RenderOutput,
    b: &risotto::engine::render::RenderOutput,
) -> Vec<f64> {
    let (w, h) = (64usize, 64usize);
    let mut z = Vec::new();
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            let (mut d, mut v) = (0.0f64, 0.0f64);
            for y in by..by + 8 {
                for x in bx..bx + 8 {
                    let k = y * w + x;
                    let (pa, pb) = (a.beauty.pixels[k], b.beauty.pixels[k]);
                    let (va, vb) = (a.variance.pixels[k], b.variance.pixels[k]);
                    d += (pa.r + pa.g + pa.b) as f64 - (pb.r + pb.g + pb.b) as f64;
                    // Channels are equal here (grey material, white lights).
                    v += 9.0 * (va.r as f64 + vb.r as f64);
                }
            }
            z.push(if v > 0.0 {
                d / v.sqrt()
            } else if d == 0.0 {
                0.0
            } else {
                f64::INFINITY
            });
        }
    }
    z
}

#[test]
fn smooth_tessellated_sphere_matches_the_analytic_sphere_and_flat_does_not() {
    let dir = scratch_dir("mesh_attributes", "smooth_vs_analytic");
    // Facets 3.75 degrees apart: flat shading shows them in the sun; the interpolated
    // normals and the polygonal silhouette are within noise of the sphere's. (Coarser
    // meshes differ near the sun's terminator unless rays leave from the smooth surface:
    // `coarse_smooth_sphere_has_no_faceted_terminator`.)
    write_obj(&uv_sphere(96, 48), &dir.join("sphere.obj"));
    let material = "type = \"diffuse\"\nreflectance = 0.7";
    let render = |shape: &str| render_scene_text(&dir, &sphere_scene(shape, material, 256));
    let analytic = render("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1");
    let smooth = render("type = \"mesh\"\npath = \"sphere.obj\"");
    let flat = render("type = \"mesh\"\npath = \"sphere.obj\"\nface_normals = true");
    let z_smooth = block_z(&smooth, &analytic);
    let z_flat = block_z(&flat, &analytic);
    let max = |z: &[f64]| z.iter().fold(0.0f64, |m, &v| m.max(v.abs()));
    // 64 blocks: |z| > 4.5 has probability ~5e-4 under pure noise.
    assert!(
        max(&z_smooth) < 4.5,
        "smooth mesh differs from the sphere: {z_smooth:?}"
    );
    assert!(
        max(&z_flat) > 6.0,
        "flat shading should show its facets: {z_flat:?}"
    );
}

#[test]
fn obj_and_ply_of_the_same_mesh_render_identically() {
    let dir = scratch_dir("mesh_attributes", "obj_vs_ply");
    let s = uv_sphere(24, 12);
    write_obj(&s, &dir.join("sphere.obj"));
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        write_ply(&s, &dir.join(format!("{format}.ply")), format);
    }
    // A checker on uv: the texture coordinates must agree too, not only the normals.
    let material = "type = \"diffuse\"\nreflectance = { pattern = \"checker\", scale = 8, \
                    space = \"uv\", a = 0.2, b = 0.8 }";
    let render = |file: &str| {
        let shape = format!("type = \"mesh\"\npath = \"{file}\"");
        render_scene_text(&dir, &sphere_scene(&shape, material, 4))
    };
    let obj = render("sphere.obj");
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let ply = render(&format!("{format}.ply"));
        assert!(
            obj.beauty.pixels == ply.beauty.pixels,
            "{format} PLY renders differently from the OBJ"
        );
    }
}

#[test]
fn textured_mesh_maps_uv_like_the_analytic_sphere() {
    // The mesh's `vt` reach the pattern: a gradient over v on the tessellated sphere looks
    // like the same gradient on the analytic sphere (same parameterisation), within noise.
    let dir = scratch_dir("mesh_attributes", "textured");
    write_obj(&uv_sphere(96, 48), &dir.join("sphere.obj"));
    let material = "type = \"diffuse\"\nreflectance = { pattern = \"gradient\", axis = \"v\", \
                    a = 0.1, b = 0.9 }";
    let render = |shape: &str| render_scene_text(&dir, &sphere_scene(shape, material, 256));
    let analytic = render("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1");
    let mesh = render("type = \"mesh\"\npath = \"sphere.obj\"");
    let z = block_z(&mesh, &analytic);
    assert!(z.iter().all(|z| z.abs() < 4.5), "{z:?}");
    // Barycentrics instead of the file's uv would not match (the test can fail).
    let mut no_uv = String::new();
    for line in std::fs::read_to_string(dir.join("sphere.obj"))
        .unwrap()
        .lines()
    {
        if !line.starts_with("vt") {
            let line = line.replace("f ", "F ");
            let line = line
                .split_whitespace()
                .map(|w| match w.split('/').collect::<Vec<_>>()[..] {
                    [v, _, n] => format!("{v}//{n}"),
                    _ => w.to_string(),
                })
                .collect::<Vec<_>>()
                .join(" ")
                .replace("F ", "f ");
            writeln!(no_uv, "{line}").unwrap();
        }
    }
    std::fs::write(dir.join("no_uv.obj"), no_uv).unwrap();
    let bary = render("type = \"mesh\"\npath = \"no_uv.obj\"");
    let z = block_z(&bary, &analytic);
    assert!(z.iter().any(|z| z.abs() > 8.0), "{z:?}");
}

/// The bent-normal quad of [`bent_normals_leak_no_light_from_behind`] under a sun from
/// behind it; `render_line` is added to `[render]`. Returns the brightest pixel and the
/// largest cosine between the sun's direction and a shading normal of the quad.
fn bent_quad_under_a_sun_from_behind(test: &str, render_line: &str) -> (f32, f32) {
    // One quad facing +z (the camera) whose vertex normals lean 50 degrees outwards, lit
    // only by a sun from behind it at 30 degrees below its plane: the light is behind every
    // facet, though the shading normals face the light near the edge the light comes from.
    let dir = scratch_dir("mesh_attributes", test);
    let lean = 50f32.to_radians();
    let (s, c) = (lean.sin(), lean.cos());
    let obj = format!(
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
         vn {} 0 {c}\nvn {s} 0 {c}\nvn {s} 0 {c}\nvn {} 0 {c}\n\
         f 1//1 2//2 3//3\nf 1//1 3//3 4//4\n",
        -s, -s
    );
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    // The sun travels from +x, below the plane, towards -x and +z: wi = (cos 30, 0, -sin 30).
    let wi = glam::Vec3::new(30f32.to_radians().cos(), 0.0, -30f32.to_radians().sin());
    let nn_at_edge = glam::Vec3::new(s, 0.0, c);
    assert!(wi.dot(nn_at_edge) > 0.3, "the setup must be able to leak");
    let text = format!(
        r#"
[render]
width = 32
height = 32
spp = 16
max_depth = 4
{render_line}

[camera]
fov = 40
from = [0, 0, 4]
to = [0, 0, 0]

[materials.m]
type = "diffuse"
reflectance = 1

[[shapes]]
name = "q"
type = "mesh"
path = "quad.obj"
material = "m"

[[lights]]
type = "distant"
direction = [{}, 0, {}]
irradiance = 10
"#,
        -wi.x, -wi.z
    );
    let out = render_scene_text(&dir, &text);
    let max = out
        .beauty
        .pixels
        .iter()
        .fold(0.0f32, |m, p| m.max(p.r).max(p.g).max(p.b));
    (max, wi.dot(nn_at_edge))
}

#[test]
fn bent_normals_leak_no_light_from_behind() {
    let (max, _) = bent_quad_under_a_sun_from_behind("leak", "");
    assert_eq!(max, 0.0, "light leaked through the quad");
}

#[test]
fn shading_frame_normals_keep_the_directions_consistent_ones_discard() {
    // Mitsuba's and pbrt-v4's treatment: the Lambertian lobe in the shading frame alone, so
    // the edge facing the sun is lit by `E cos(wi, nn) / pi` (the sun's direct light only:
    // the quad sees nothing else) where the consistent rule keeps it black.
    let (max, cos_edge) =
        bent_quad_under_a_sun_from_behind("shading-frame", r#"shading_normals = "shading_frame""#);
    let at_edge = 10.0 * cos_edge / std::f32::consts::PI;
    assert!(
        max > 0.8 * at_edge && max <= 1.001 * at_edge,
        "brightest pixel {max}, the lit edge's radiance {at_edge}"
    );
}

#[test]
fn smooth_normals_do_not_darken_a_white_furnace() {
    // A white diffuse tessellated sphere in a uniform environment of radiance 1: every
    // pixel is 1 (energy conservation at albedo 1, any geometry). Discarding the directions
    // on which the normals disagree costs energy only where they disagree much; on this
    // mesh the image mean stays within 1 % of 1.
    let dir = scratch_dir("mesh_attributes", "furnace");
    write_obj(&uv_sphere(48, 24), &dir.join("sphere.obj"));
    let text = r#"
[render]
width = 32
height = 32
spp = 64
max_depth = 64

[camera]
fov = 30
from = [0, 0, 5]
to = [0, 0, 0]

[materials.m]
type = "diffuse"
reflectance = 1

[[shapes]]
name = "s"
type = "mesh"
path = "sphere.obj"
material = "m"

[[lights]]
type = "environment"
radiance = 1
"#;
    let out = render_scene_text(&dir, text);
    let (mean, err) = image_mean(&out);
    for (m, e) in [(mean.r, err.r), (mean.g, err.g), (mean.b, err.b)] {
        assert!((m - 1.0).abs() < 0.01 + 4.0 * e, "furnace mean {m} +- {e}");
    }
    // And no pixel is much darker: the silhouette pixels are the worst.
    let min = out.beauty.pixels.iter().fold(f32::MAX, |m, p| m.min(p.r));
    assert!(min > 0.8, "darkest pixel {min}");
}

#[test]
fn only_scenes_with_vertex_normals_run_the_shading_normal_checks() {
    let dir = scratch_dir("mesh_attributes", "features");
    let s = uv_sphere(8, 4);
    write_obj(&s, &dir.join("smooth.obj"));
    let material = "type = \"diffuse\"\nreflectance = 0.5";
    let compile = |shape: &str| load_scene_text(&dir, &sphere_scene(shape, material, 1)).unwrap();
    let smooth = compile("type = \"mesh\"\npath = \"smooth.obj\"");
    assert!(smooth.features.vertex_normals);
    assert!(smooth.geometry.attributes().has_normals(0));
    // Flat: the normals are dropped, the uvs kept (no shading-normal stage, uv still read).
    let flat = compile("type = \"mesh\"\npath = \"smooth.obj\"\nface_normals = true");
    assert!(!flat.features.vertex_normals);
    assert!(!flat.geometry.attributes().is_empty());
    let sphere = compile("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1");
    assert!(!sphere.features.vertex_normals && sphere.geometry.attributes().is_empty());
    assert!(!sphere
        .features
        .names()
        .contains(&"vertex_normals".to_string()));
}

/// The sun-lit diffuse sphere, no environment: every pixel is direct light only (a convex
/// shape never sees itself), noiseless but for the pixel filter's jitter.
fn sunlit_scene(shape: &str) -> String {
    let text = sphere_scene(shape, "type = \"diffuse\"\nreflectance = 0.7", 16);
    let env = "\n[[lights]]\ntype = \"environment\"\nradiance = 0.2\n";
    assert!(text.contains(env));
    text.replace(env, "\n")
}

/// Mean absolute difference (channels summed) of `a` from `reference` over `band`.
fn band_error(
    a: &risotto::engine::render::RenderOutput,
    reference: &risotto::engine::render::RenderOutput,
    band: &[usize],
) -> f64 {
    let sum = |p: risotto::components::Rgb| (p.r + p.g + p.b) as f64;
    let total: f64 = band
        .iter()
        .map(|&k| (sum(a.beauty.pixels[k]) - sum(reference.beauty.pixels[k])).abs())
        .sum();
    total / band.len() as f64
}

/// A 224-triangle UV sphere (16 x 8) with vertex normals under a sun: near the terminator
/// the flat facets' shadow rays hit their neighbours and the lit side ends in dark steps;
/// leaving from the smooth surface (the default `shadow_terminator_offset`) brings the band
/// close to the analytic sphere. Band: pixels lit at a grazing angle on the analytic
/// sphere (below 30 % of its brightest), well inside its silhouette.
#[test]
fn coarse_smooth_sphere_has_no_faceted_terminator() {
    let dir = scratch_dir("mesh_attributes", "terminator");
    write_obj(&uv_sphere(16, 8), &dir.join("sphere.obj"));
    let render = |shape: &str| render_scene_text(&dir, &sunlit_scene(shape));
    let analytic = render("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1");
    let lifted = render("type = \"mesh\"\npath = \"sphere.obj\"");
    let flat_origins =
        render("type = \"mesh\"\npath = \"sphere.obj\"\nshadow_terminator_offset = false");
    let value = |k: usize| {
        let p = analytic.beauty.pixels[k];
        (p.r + p.g + p.b) as f64
    };
    let brightest = (0..64 * 64).map(value).fold(0.0, f64::max);
    // The sphere's silhouette is about 24 pixels from the centre (asin(1/5) against the
    // 15 degree half field of view); 20 keeps the band off it.
    let band: Vec<usize> = (0..64 * 64)
        .filter(|&k| {
            let (x, y) = ((k % 64) as f64 - 31.5, (k / 64) as f64 - 31.5);
            x.hypot(y) < 20.0 && value(k) > 0.0 && value(k) < 0.3 * brightest
        })
        .collect();
    assert!(band.len() > 50, "{} pixels in the band", band.len());
    let with = band_error(&lifted, &analytic, &band);
    let without = band_error(&flat_origins, &analytic, &band);
    let mean = band.iter().map(|&k| value(k)).sum::<f64>() / band.len() as f64;
    eprintln!(
        "terminator band ({} px, mean {mean:.4}): error with offset {with:.4}, without {without:.4}",
        band.len()
    );
    assert!(
        without > 0.05 * mean,
        "the flat origins should show the terminator: {without} against mean {mean}"
    );
    assert!(
        with < 0.6 * without,
        "the offset should bring the band near the sphere: {with} against {without}"
    );
    // The offset runs only where asked, and is counted only there.
    assert!(lifted.stats.counters.terminator_lifts > 0);
    assert!(lifted
        .stats
        .features
        .contains(&"terminator_offset".to_string()));
    assert_eq!(flat_origins.stats.counters.terminator_lifts, 0);
    assert!(!flat_origins
        .stats
        .features
        .contains(&"terminator_offset".to_string()));
    // Away from the terminator nothing changes: the fully lit pixels well inside agree.
    let lit: Vec<usize> = (0..64 * 64)
        .filter(|&k| {
            let (x, y) = ((k % 64) as f64 - 31.5, (k / 64) as f64 - 31.5);
            x.hypot(y) < 20.0 && value(k) > 0.6 * brightest
        })
        .collect();
    eprintln!(
        "lit ({} px): error {:.4}",
        lit.len(),
        band_error(&lifted, &analytic, &lit)
    );
    let same = lit
        .iter()
        .filter(|&&k| lifted.beauty.pixels[k] == flat_origins.beauty.pixels[k])
        .count();
    assert_eq!(same, lit.len(), "the offset changed fully lit pixels");
    // No leak through the closed mesh: where the analytic sphere's normal (its normal AOV)
    // faces well away from the sun, past the coarse normals' spread (a facet is 22.5
    // degrees wide), the lifted mesh receives no light either.
    let l = glam::Vec3::new(1.0, 0.3, 0.4).normalize();
    let dark: Vec<usize> = (0..64 * 64)
        .filter(|&k| {
            let n = analytic.normal.pixels[k];
            let n = glam::Vec3::new(n.r, n.g, n.b);
            n.length() > 0.99 && n.dot(l) < -0.3
        })
        .collect();
    assert!(dark.len() > 50, "{} dark pixels", dark.len());
    for &k in &dark {
        let p = lifted.beauty.pixels[k];
        assert_eq!(
            (p.r, p.g, p.b),
            (0.0, 0.0, 0.0),
            "light leaked at pixel {k}"
        );
    }
}

/// A flat mesh whose vertex normals all equal its face normal (a box written with normals)
/// renders the same with and without the offset, bit for bit, and is never lifted.
#[test]
fn flat_meshes_with_normals_are_not_lifted() {
    let dir = scratch_dir("mesh_attributes", "terminator_flat");
    // A unit box with one vertex per face corner, each with its face's normal.
    let mut t = String::new();
    let faces: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
        ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
    ];
    for (f, (n, a, b)) in faces.iter().enumerate() {
        for (s, r) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let p: Vec<f32> = (0..3).map(|i| 0.6 * (n[i] + s * a[i] + r * b[i])).collect();
            writeln!(t, "v {} {} {}", p[0], p[1], p[2]).unwrap();
            writeln!(t, "vn {} {} {}", n[0], n[1], n[2]).unwrap();
        }
        let o = 4 * f + 1;
        writeln!(t, "f {0}//{0} {1}//{1} {2}//{2}", o, o + 1, o + 2).unwrap();
        writeln!(t, "f {0}//{0} {1}//{1} {2}//{2}", o, o + 2, o + 3).unwrap();
    }
    std::fs::write(dir.join("box.obj"), t).unwrap();
    let shape = "type = \"mesh\"\npath = \"box.obj\"\ntransform = [{ rotate = { axis = [1, 1, 0], angle = 30 } }]";
    let material = "type = \"diffuse\"\nreflectance = 0.7";
    let on = render_scene_text(&dir, &sphere_scene(shape, material, 4));
    let off_shape = format!("{shape}\nshadow_terminator_offset = false");
    let off = render_scene_text(&dir, &sphere_scene(&off_shape, material, 4));
    assert!(on.stats.features.contains(&"terminator_offset".to_string()));
    assert_eq!(on.stats.counters.terminator_lifts, 0);
    assert!(
        on.beauty.pixels == off.beauty.pixels,
        "a flat mesh renders differently with the offset"
    );
}
