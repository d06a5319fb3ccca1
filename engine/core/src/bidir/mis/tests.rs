//! The recursive weights against the power heuristic computed from every strategy's full
//! path pdf (Veach 1997, eq. 10.9), on random paths.

use super::*;
use glam::Vec3;

/// A random path: vertex 0 the camera, 1..=m scattering vertices, m + 1 a point on an area
/// light; directional pdfs at each scattering vertex towards its camera-side (`rev`) and
/// light-side (`fwd`) neighbours.
struct TestPath {
    z: Vec<Vec3>,
    n: Vec<Vec3>,
    /// `fwd[i]`: pdf of sampling `z[i] -> z[i+1]` given `z[i-1]` (camera subpath direction).
    fwd: Vec<f32>,
    /// `rev[i]`: pdf of sampling `z[i] -> z[i-1]` given `z[i+1]` (light subpath direction).
    rev: Vec<f32>,
    camera_pdf_w: f32,
    emit_pos: f32,
    emit_dir: f32,
    direct_pdf_a: f32,
    /// Scattering vertices with a Dirac lobe.
    specular: Vec<bool>,
    /// Scattering vertices inside a medium (no surface: cosines 1).
    medium: Vec<bool>,
}

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }
    fn vec(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0
    }
}

impl TestPath {
    fn random(m: usize, rng: &mut Lcg, specular_at: Option<usize>) -> TestPath {
        let z: Vec<Vec3> = (0..m + 2).map(|_| rng.vec() * 3.0).collect();
        let n: Vec<Vec3> = (0..m + 2).map(|_| rng.vec().normalize()).collect();
        let mut fwd: Vec<f32> = (0..m + 2).map(|_| 0.05 + rng.next() * 2.0).collect();
        let mut rev: Vec<f32> = (0..m + 2).map(|_| 0.05 + rng.next() * 2.0).collect();
        let mut specular = vec![false; m + 2];
        if let Some(i) = specular_at {
            specular[i] = true;
            // A Dirac lobe's pdfs cancel between directions (the recursion's assumption).
            rev[i] = fwd[i];
        }
        fwd[0] = 0.0;
        rev[0] = 0.0;
        let mut medium: Vec<bool> = (0..m + 2).map(|_| rng.next() < 0.3).collect();
        medium[0] = false;
        medium[m + 1] = false;
        TestPath {
            medium,
            z,
            n,
            fwd,
            rev,
            camera_pdf_w: 0.1 + rng.next(),
            emit_pos: 0.1 + rng.next(),
            emit_dir: 0.1 + rng.next(),
            direct_pdf_a: 0.1 + rng.next(),
            specular,
        }
    }
    fn m(&self) -> usize {
        self.z.len() - 2
    }
    fn d(&self, a: usize, b: usize) -> f32 {
        (self.z[a] - self.z[b]).length()
    }
    /// `|cos|` at vertex `a` towards vertex `b` (1 in a medium).
    fn cos(&self, a: usize, b: usize) -> f32 {
        if self.medium[a] {
            return 1.0;
        }
        self.n[a].dot((self.z[b] - self.z[a]).normalize()).abs()
    }
    /// Area pdf of `z[b]` sampled from `z[a]` with solid-angle pdf `pdf_w`.
    fn to_area(&self, pdf_w: f32, a: usize, b: usize) -> f32 {
        pdf_w * self.cos(b, a) / (self.d(a, b) * self.d(a, b))
    }
    /// The camera subpath's area pdf of `z[i]`, i >= 1.
    fn p_cam(&self, i: usize) -> f32 {
        if i == 1 {
            self.to_area(self.camera_pdf_w, 0, 1)
        } else {
            self.to_area(self.fwd[i - 1], i - 1, i)
        }
    }
    /// The light subpath's area pdf of `z[j]`, j <= m.
    fn p_light(&self, j: usize) -> f32 {
        let m = self.m();
        if j == m {
            self.to_area(self.emit_dir, m + 1, m)
        } else {
            self.to_area(self.rev[j + 1], j + 1, j)
        }
    }
    /// Full path pdf of the strategy with `s` light vertices (0: the camera hits the light;
    /// 1: a light sample; m + 1: light tracing), or 0 when it cannot make the path (it
    /// connects at a Dirac vertex).
    fn strategy_pdf(&self, s: usize) -> f32 {
        let m = self.m();
        let t = m + 2 - s;
        // Connection endpoints: camera vertex t - 1, light vertex t (for 1 <= s <= m + 1).
        if s >= 1 && (self.specular[t - 1] || (t <= m && self.specular[t])) {
            return 0.0;
        }
        let mut p = 1.0;
        for i in 1..t {
            p *= self.p_cam(i);
        }
        if s == 1 {
            p *= self.direct_pdf_a;
        } else if s >= 2 {
            p *= self.emit_pos;
            for j in t..=m {
                p *= self.p_light(j);
            }
        }
        p
    }

    /// Full path pdf of merging at scattering vertex `i` (the camera subpath's vertex `i`
    /// and the light subpath's own sample of it within the kernel, `eta` of the vertex's
    /// kind): 0 at a Dirac vertex.
    fn merge_pdf(&self, i: usize, radius: f32, light_paths: f32) -> f32 {
        if self.specular[i] {
            return 0.0;
        }
        let pi = std::f32::consts::PI;
        let eta = if self.medium[i] {
            4.0 / 3.0 * pi * radius.powi(3) * light_paths
        } else {
            pi * radius * radius * light_paths
        };
        let mut p = eta * self.emit_pos;
        for k in 1..=i {
            p *= self.p_cam(k);
        }
        for j in i..=self.m() {
            p *= self.p_light(j);
        }
        p
    }
}

/// The recursion's weight of merging at scattering vertex `i` of `path`.
fn recursive_merge_weight(path: &TestPath, i: usize, f: &MisFactors) -> f32 {
    let m = path.m();
    let mut cam = SubpathMis::camera_start(path.camera_pdf_w, f.light_paths_per_pixel);
    for k in 1..=i {
        cam.arrive(path.d(k - 1, k), path.cos(k, k - 1), false);
        if k < i {
            let v = f.at(path.medium[k]);
            cam.scatter(
                path.fwd[k],
                path.rev[k],
                path.cos(k, k + 1),
                path.specular[k],
                v,
            );
        }
    }
    let emission_pdf = path.emit_pos * path.emit_dir;
    let cos_light = path.cos(m + 1, m);
    let mut light = SubpathMis::light_start(path.direct_pdf_a, emission_pdf, cos_light, false);
    for j in (i..=m).rev() {
        light.arrive(path.d(j + 1, j), path.cos(j, j + 1), false);
        if j > i {
            let v = f.at(path.medium[j]);
            light.scatter(
                path.rev[j],
                path.fwd[j],
                path.cos(j, j - 1),
                path.specular[j],
                v,
            );
        }
    }
    // The camera vertex's Bxdf towards the light vertex's incident direction (the light
    // vertex sits where the camera vertex is).
    merge_weight(&cam, &light, path.fwd[i], path.rev[i], f.at(path.medium[i]))
}

/// The recursion's weight of strategy `s` on `path`.
fn recursive_weight(path: &TestPath, s: usize, f: &MisFactors) -> f32 {
    let m = path.m();
    let t = m + 2 - s;
    // The camera subpath up to camera vertex t - 1 (or to the light for s = 0).
    let last_camera = if s == 0 { m + 1 } else { t - 1 };
    let mut cam = SubpathMis::camera_start(path.camera_pdf_w, f.light_paths_per_pixel);
    for i in 1..=last_camera {
        cam.arrive(path.d(i - 1, i), path.cos(i, i - 1), false);
        if i < last_camera {
            let (fw, rv) = (path.fwd[i], path.rev[i]);
            cam.scatter(
                fw,
                rv,
                path.cos(i, i + 1),
                path.specular[i],
                f.at(path.medium[i]),
            );
        }
    }
    let emission_pdf = path.emit_pos * path.emit_dir;
    let cos_light = path.cos(m + 1, m);
    match s {
        0 => emitter_hit_weight(&cam, path.direct_pdf_a, emission_pdf, false),
        1 => {
            let d = path.d(m, m + 1);
            let direct_w = path.direct_pdf_a * d * d / cos_light;
            light_sample_weight(
                &cam,
                direct_w,
                emission_pdf,
                path.fwd[m],
                path.rev[m],
                path.cos(m, m + 1),
                cos_light,
                false,
                f.at(path.medium[m]),
            )
        }
        _ => {
            // The light subpath down to light vertex t.
            let mut light =
                SubpathMis::light_start(path.direct_pdf_a, emission_pdf, cos_light, false);
            for j in (t..=m).rev() {
                light.arrive(path.d(j + 1, j), path.cos(j, j + 1), false);
                if j > t {
                    let (fw, rv) = (path.rev[j], path.fwd[j]);
                    let v = f.at(path.medium[j]);
                    light.scatter(fw, rv, path.cos(j, j - 1), path.specular[j], v);
                }
            }
            if t == 1 {
                let camera_pdf_a = path.to_area(path.camera_pdf_w, 0, 1);
                let v = f.at(path.medium[1]);
                camera_connection_weight(&light, camera_pdf_a, path.fwd[1], v, 1.0)
            } else {
                let (c, l) = (t - 1, t);
                let d = path.d(c, l);
                let pdfs = ConnectionPdfs {
                    camera_pdf_a: pdf_w_to_a(path.fwd[c], d, path.cos(l, c)),
                    camera_rev_pdf_w: path.rev[c],
                    light_pdf_a: pdf_w_to_a(path.rev[l], d, path.cos(c, l)),
                    light_rev_pdf_w: path.fwd[l],
                };
                connection_weight(
                    &cam,
                    &light,
                    &pdfs,
                    f.at(path.medium[c]),
                    f.at(path.medium[l]),
                )
            }
        }
    }
}

/// Merging off (`merge = None`) or on with `(radius, light paths)`.
fn check(path: &TestPath, merge: Option<(f32, f32)>, what: &str) {
    let f = match merge {
        None => MisFactors::connections_only(1.0),
        Some((r, n)) => MisFactors::vcm(r, n, 1.0),
    };
    let m = path.m();
    let pdfs: Vec<f32> = (0..=m + 1).map(|s| path.strategy_pdf(s)).collect();
    let merges: Vec<f32> = match merge {
        None => Vec::new(),
        Some((r, n)) => (1..=m).map(|i| path.merge_pdf(i, r, n)).collect(),
    };
    let total: f64 = pdfs.iter().chain(&merges).map(|&p| f64::from(mis(p))).sum();
    let mut sum = 0.0;
    let mut compare = |got: f32, p: f32, name: String| {
        let want = f64::from(mis(p)) / total;
        let got = f64::from(got);
        sum += got;
        assert!(
            (got - want).abs() <= 2e-3 * want.max(1e-3),
            "{what}: {name} of a path of {} segments: recursive weight {got}, power \
             heuristic of the full pdfs {want} (connections {pdfs:?}, merges {merges:?})",
            m + 1
        );
    };
    for s in 0..=m + 1 {
        if pdfs[s] > 0.0 {
            compare(
                recursive_weight(path, s, &f),
                pdfs[s],
                format!("strategy s = {s}"),
            );
        }
    }
    for (k, &p) in merges.iter().enumerate() {
        if p > 0.0 {
            let i = k + 1;
            compare(
                recursive_merge_weight(path, i, &f),
                p,
                format!("merge at {i}"),
            );
        }
    }
    assert!((sum - 1.0).abs() < 2e-3, "{what}: weights sum to {sum}");
}

#[test]
fn recursive_weights_are_the_power_heuristic_of_full_path_pdfs() {
    let mut rng = Lcg(7);
    for m in 1..6 {
        for trial in 0..20 {
            let path = TestPath::random(m, &mut rng, None);
            check(&path, None, &format!("m = {m}, trial {trial}"));
            check(
                &path,
                Some((0.05, 1000.0)),
                &format!("VCM, m = {m}, trial {trial}"),
            );
        }
    }
}

#[test]
fn dirac_vertices_drop_the_strategies_that_connect_there() {
    let mut rng = Lcg(11);
    for m in 2..6 {
        for at in 1..=m {
            for trial in 0..10 {
                let path = TestPath::random(m, &mut rng, Some(at));
                check(
                    &path,
                    None,
                    &format!("m = {m}, Dirac vertex {at}, trial {trial}"),
                );
                let what = format!("VCM, m = {m}, Dirac vertex {at}, trial {trial}");
                check(&path, Some((0.05, 1000.0)), &what);
            }
        }
    }
}
