//! Comparing two renders of the same scene.

use risotto::engine::render::RenderOutput;

/// Per-channel z-scores of the difference of two renders over 8 x 8-pixel blocks:
/// `(mean_a - mean_b) / sqrt(var_a + var_b)`, from the films' variances of the pixel means.
pub fn block_z(a: &RenderOutput, b: &RenderOutput) -> Vec<f64> {
    let (w, h) = (a.beauty.width, a.beauty.height);
    let mut z = Vec::new();
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            for c in 0..3 {
                let (mut d, mut v) = (0.0f64, 0.0f64);
                for y in by..(by + 8).min(h) {
                    for x in bx..(bx + 8).min(w) {
                        let k = y * w + x;
                        let pa = a.beauty.pixels[k].to_array()[c] as f64;
                        let pb = b.beauty.pixels[k].to_array()[c] as f64;
                        d += pa - pb;
                        v += (a.variance.pixels[k].to_array()[c]
                            + b.variance.pixels[k].to_array()[c])
                            as f64;
                    }
                }
                z.push(if v > 0.0 {
                    d / v.sqrt()
                } else if d.abs() < 1e-6 {
                    0.0
                } else {
                    f64::INFINITY
                });
            }
        }
    }
    z
}
