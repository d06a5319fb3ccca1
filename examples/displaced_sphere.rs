//! Writes the load and memory benchmark's mesh (issue 36): a displaced unit sphere as an OBJ
//! file with `v` positions, `vn` vertex normals and `f v//vn` faces, as a scanned or
//! sculpted mesh from a user would come; or, for an `OUT` ending in `.ply`, the same mesh
//! as a binary little-endian PLY (float `x y z nx ny nz`, `list uchar int vertex_indices`),
//! the positions and normals rounded to the OBJ's six decimals so both files hold the same
//! mesh.
//!
//! ```text
//! cargo run --release --example displaced_sphere -- TRIANGLES OUT.obj
//! cargo run --release --example displaced_sphere -- TRIANGLES OUT.ply
//! ```
//!
//! A latitude-longitude grid of `rings` rings of `2 rings` vertices each plus the two poles
//! (`4 rings^2` triangles: `rings` is the largest with at most `TRIANGLES`), every vertex
//! moved along the radius by a sum of three sines, so neighbouring triangles are not
//! coplanar and the BVH sees a realistic surface rather than a perfect sphere. The normals
//! are the area-weighted means of the faces around each vertex (what modelling tools
//! write). Deterministic: no random numbers, so the same arguments give the same bytes.
//! `benches/displaced_sphere.toml` renders it (README "Benches", the load and memory row).

use std::io::Write;

use glam::DVec3;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [count, out] = args.as_slice() else {
        return Err("usage: displaced_sphere TRIANGLES OUT.obj|OUT.ply".into());
    };
    let triangles: u64 = count
        .parse()
        .map_err(|e| format!("TRIANGLES `{count}` is not a count: {e}"))?;
    // 4 rings^2 triangles: 2 x (2 rings) per band between rings, (rings - 1) bands, plus
    // the two pole fans of 2 rings each.
    let rings = ((triangles as f64 / 4.0).sqrt().floor() as usize).max(2);
    let (positions, faces) = sphere(rings);
    let normals = vertex_normals(&positions, &faces);
    let file = std::fs::File::create(out).map_err(|e| format!("cannot create `{out}`: {e}"))?;
    let mut w = std::io::BufWriter::new(file);
    let write = |w: &mut std::io::BufWriter<std::fs::File>| -> std::io::Result<()> {
        writeln!(w, "# displaced sphere: {} triangles", faces.len())?;
        for p in &positions {
            writeln!(w, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z)?;
        }
        for n in &normals {
            writeln!(w, "vn {:.6} {:.6} {:.6}", n.x, n.y, n.z)?;
        }
        for f in &faces {
            let [a, b, c] = f.map(|i| i + 1);
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
        w.flush()
    };
    let ply = out.to_ascii_lowercase().ends_with(".ply");
    let written = if ply {
        write_ply(&mut w, &positions, &normals, &faces)
    } else {
        write(&mut w)
    };
    written.map_err(|e| format!("cannot write `{out}`: {e}"))?;
    println!(
        "{out}: {} vertices, {} triangles",
        positions.len(),
        faces.len()
    );
    Ok(())
}

/// The mesh as a binary little-endian PLY, each coordinate rounded as the OBJ prints it.
fn write_ply(
    w: &mut impl Write,
    positions: &[DVec3],
    normals: &[DVec3],
    faces: &[[usize; 3]],
) -> std::io::Result<()> {
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\nelement face {}\nproperty list uchar int vertex_indices\n\
         end_header\n",
        positions.len(),
        faces.len()
    )?;
    let six = |x: f64| -> f32 { format!("{x:.6}").parse().unwrap_or(0.0) };
    for (p, n) in positions.iter().zip(normals) {
        for c in [p.x, p.y, p.z, n.x, n.y, n.z] {
            w.write_all(&six(c).to_le_bytes())?;
        }
    }
    for f in faces {
        w.write_all(&[3])?;
        for &i in f {
            w.write_all(&(i as i32).to_le_bytes())?;
        }
    }
    w.flush()
}

/// The displaced grid: vertex 0 the north pole, then `rings` rings of `2 rings` vertices
/// from north to south, then the south pole; faces wound counter-clockwise seen from outside.
fn sphere(rings: usize) -> (Vec<DVec3>, Vec<[usize; 3]>) {
    let around = 2 * rings;
    let radius = |theta: f64, phi: f64| {
        1.0 + 0.04 * (7.0 * theta).sin() * (9.0 * phi).cos()
            + 0.02 * (23.0 * theta + 1.0).sin() * (17.0 * phi).sin()
            + 0.005 * (97.0 * theta).cos() * (101.0 * phi + 2.0).sin()
    };
    let point = |theta: f64, phi: f64| {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        radius(theta, phi) * DVec3::new(st * cp, ct, -st * sp)
    };
    let mut positions = vec![point(0.0, 0.0)];
    for r in 0..rings {
        let theta = std::f64::consts::PI * (r as f64 + 1.0) / (rings as f64 + 1.0);
        for k in 0..around {
            let phi = std::f64::consts::TAU * k as f64 / around as f64;
            positions.push(point(theta, phi));
        }
    }
    let south = positions.len();
    positions.push(point(std::f64::consts::PI, 0.0));
    let at = |r: usize, k: usize| 1 + r * around + k % around;
    let mut faces = Vec::with_capacity(4 * rings * rings);
    for k in 0..around {
        faces.push([0, at(0, k), at(0, k + 1)]);
    }
    for r in 0..rings - 1 {
        for k in 0..around {
            let (a, b, c, d) = (at(r, k), at(r + 1, k), at(r + 1, k + 1), at(r, k + 1));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    for k in 0..around {
        faces.push([south, at(rings - 1, k + 1), at(rings - 1, k)]);
    }
    (positions, faces)
}

/// Area-weighted vertex normals: the sum of the (unnormalised) face normals around each
/// vertex, normalised.
fn vertex_normals(positions: &[DVec3], faces: &[[usize; 3]]) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for &[a, b, c] in faces {
        let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for i in [a, b, c] {
            normals[i] += n;
        }
    }
    normals.iter().map(|n| n.normalize()).collect()
}
