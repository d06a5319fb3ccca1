//! Denoising a render with Intel Open Image Denoise (OIDN), the denoiser Cycles, Arnold and
//! others ship; cargo feature `denoise` (README, "Denoising").
//!
//! OIDN's `RT` filter (a U-Net trained on path-traced images; Áfra, "Intel Open Image
//! Denoise", 2019-2025) takes the noisy HDR beauty with two auxiliary layers the render
//! already makes: the first-hit albedo and the first-hit shading normal, per-pixel means of
//! every sample. They let it keep texture and geometric edges the noise would blur. Where
//! the camera sees a medium rather than a surface (smoke, fog, the inside of a volume) these
//! layers hold the surface behind it, or nothing, so there the filter has only the beauty
//! and blurs more: a denoised volume is smoother than its converged image, not equal to it.

use crate::components::Rgb;
use crate::engine::output::Image;

/// Why a denoise failed: OIDN's own message.
#[derive(Debug)]
pub struct DenoiseError(String);

impl std::fmt::Display for DenoiseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "denoising (Open Image Denoise): {}", self.0)
    }
}

impl std::error::Error for DenoiseError {}

/// `beauty` denoised by OIDN's `RT` filter in HDR mode, guided by `albedo` and `normal` (each
/// `beauty`'s size; the render's first-hit AOV means). The images stay linear; `beauty` is not
/// changed.
pub fn denoise(beauty: &Image, albedo: &Image, normal: &Image) -> Result<Image, DenoiseError> {
    let (w, h) = (beauty.width, beauty.height);
    for (name, aux) in [("albedo", albedo), ("normal", normal)] {
        if (aux.width, aux.height) != (w, h) || aux.pixels.len() != beauty.pixels.len() {
            return Err(DenoiseError(format!(
                "the {name} layer is {}x{}, the beauty {w}x{h}",
                aux.width, aux.height
            )));
        }
    }
    let flat = |img: &Image| -> Vec<f32> { img.pixels.iter().flat_map(|p| p.to_array()).collect() };
    let color = flat(beauty);
    // OIDN wants albedo in [0, 1] and normals in [-1, 1]: the means already are, except for
    // estimator noise and rounding, which clamping removes.
    let albedo: Vec<f32> = flat(albedo).iter().map(|a| a.clamp(0.0, 1.0)).collect();
    let normal: Vec<f32> = flat(normal).iter().map(|n| n.clamp(-1.0, 1.0)).collect();
    let mut output = vec![0.0f32; color.len()];
    let device = oidn::Device::new().map_err(|e| DenoiseError(format!("no device: {e}")))?;
    let mut filter = oidn::RayTracing::try_new(&device)
        .map_err(|e| DenoiseError(format!("no RT filter: {e}")))?;
    filter
        .hdr(true)
        .image_dimensions(w, h)
        .albedo_normal(&albedo, &normal);
    filter
        .filter(&color, &mut output)
        .map_err(|e| DenoiseError(e.to_string()))?;
    device
        .get_error()
        .map_err(|e| DenoiseError(e.to_string()))?;
    // OIDN's output is finite for finite input; a pixel that is not (a library fault) keeps
    // the noisy value rather than putting a NaN on the film.
    let pixels = output
        .chunks_exact(3)
        .zip(&beauty.pixels)
        .map(|(d, &noisy)| {
            let p = Rgb::new(d[0].max(0.0), d[1].max(0.0), d[2].max(0.0));
            if p.to_array().iter().all(|c| c.is_finite()) {
                p
            } else {
                noisy
            }
        })
        .collect();
    Ok(Image::from_pixels(w, h, pixels))
}
