//! Conductors' optics: the Fresnel reflectance of an interface with a complex index of
//! refraction `eta + i k`, and the table of common metals by name (Mitsuba 3's `material`
//! parameter of `conductor` / `roughconductor`).

use risotto_components::Rgb;

/// Unpolarized Fresnel reflectance of a conductor, `(R_s + R_p) / 2`, for the cosine
/// `cos_theta_i` (clamped to `[0, 1]`) between the incident direction and the normal and the
/// relative complex index `eta + i k` (conductor over outside medium).
///
/// The closed form for real `cos_theta_i` of Born & Wolf's complex Fresnel equations in
/// terms of `a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2)` and
/// `a^2 = (a^2 + b^2 + eta^2 - k^2 - sin^2) / 2` (as in pbrt-v3's `FrConductor` and
/// Mitsuba 3's `fresnel_conductor`; tested against complex arithmetic in f64). `eta = 0`,
/// `k = 1` is a perfect reflector (Mitsuba's `material = "none"`).
pub fn fresnel_conductor(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let c = cos_theta_i.clamp(0.0, 1.0);
    let cos2 = c * c;
    let sin2 = 1.0 - cos2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - sin2;
    let a2pb2 = (t0 * t0 + 4.0 * eta2 * k2).max(0.0).sqrt();
    let a = (0.5 * (a2pb2 + t0)).max(0.0).sqrt();
    let t1 = a2pb2 + cos2;
    let t2 = 2.0 * c * a;
    // t1 + t2 > 0 unless a2pb2 = cos2 = 0: grazing incidence on a lossless index of 1,
    // which reflects fully, as every grazing ray does.
    let rs = if t1 + t2 > 0.0 {
        (t1 - t2) / (t1 + t2)
    } else {
        1.0
    };
    let t3 = cos2 * a2pb2 + sin2 * sin2;
    let t4 = t2 * sin2;
    let rp = if t3 + t4 > 0.0 {
        rs * (t3 - t4) / (t3 + t4)
    } else {
        rs
    };
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

/// [`fresnel_conductor`] per RGB channel.
pub fn fresnel_conductor_rgb(cos_theta_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    Rgb::new(
        fresnel_conductor(cos_theta_i, eta.r, k.r),
        fresnel_conductor(cos_theta_i, eta.g, k.g),
        fresnel_conductor(cos_theta_i, eta.b, k.b),
    )
}

/// A named metal's complex index of refraction in RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metal {
    /// The name (Mitsuba 3's, e.g. `"Au"`).
    pub name: &'static str,
    /// Real part of the index per RGB channel.
    pub eta: [f32; 3],
    /// Imaginary part (extinction coefficient) per RGB channel.
    pub k: [f32; 3],
}

/// Mitsuba 3's conductor presets as its RGB variants see them, plus `none` (a perfect
/// reflector, `eta = 0, k = 1`).
///
/// Mitsuba stores each material as measured spectra (`data/ior/<name>.{eta,k}.spd`) and in
/// its RGB variants turns each into an sRGB triple with `spectrum_list_to_srgb` (the
/// spectrum integrated against the CIE 1931 matching functions, then XYZ to linear sRGB,
/// negative channels clamped; `render/ior.h`, `complex_ior_from_file`). The values below are
/// exactly those: read from Mitsuba 3.9.1 (`scalar_rgb`) by loading
/// `{"type": "roughconductor", "material": NAME}` and reading `eta.value` and `k.value`
/// through `mi.traverse`, rounded to 5 significant digits.
pub const METALS: &[Metal] = &[
    Metal {
        name: "none",
        eta: [0.0, 0.0, 0.0],
        k: [1.0, 1.0, 1.0],
    },
    Metal {
        name: "a-C",
        eta: [2.944, 2.2271, 1.9682],
        k: [0.88746, 0.7993, 0.81529],
    },
    Metal {
        name: "Ag",
        eta: [0.15528, 0.11673, 0.13839],
        k: [4.8284, 3.1222, 2.1469],
    },
    Metal {
        name: "Al",
        eta: [1.6575, 0.8804, 0.52124],
        k: [9.2238, 6.2695, 4.837],
    },
    Metal {
        name: "AlAs",
        eta: [3.6053, 3.2329, 2.2163],
        k: [0.00067944, 0.0, 0.0075127],
    },
    Metal {
        name: "AlSb",
        eta: [0.0, 4.1394, 4.6693],
        k: [0.0, 0.094009, 1.3006],
    },
    Metal {
        name: "Au",
        eta: [0.14304, 0.37531, 1.442],
        k: [3.983, 2.3856, 1.6034],
    },
    Metal {
        name: "Be",
        eta: [4.185, 3.185, 2.7841],
        k: [3.8355, 3.0101, 2.869],
    },
    Metal {
        name: "Cr",
        eta: [4.3697, 2.9165, 1.6549],
        k: [5.2065, 4.2313, 3.7547],
    },
    Metal {
        name: "CsI",
        eta: [2.1449, 1.7023, 1.6624],
        k: [0.0, 0.0, 0.0],
    },
    Metal {
        name: "Cu",
        eta: [0.20101, 0.92375, 1.1022],
        k: [3.9133, 2.453, 2.1421],
    },
    Metal {
        name: "Cu2O",
        eta: [3.5518, 2.9499, 2.7519],
        k: [0.11421, 0.1939, 0.60613],
    },
    Metal {
        name: "CuO",
        eta: [3.2475, 2.4478, 2.2102],
        k: [0.52109, 0.57003, 0.72218],
    },
    Metal {
        name: "d-C",
        eta: [2.7087, 2.3188, 2.2289],
        k: [0.0, 0.0, 0.0],
    },
    Metal {
        name: "Hg",
        eta: [2.3989, 1.44, 0.90957],
        k: [6.3276, 4.3719, 3.4218],
    },
    Metal {
        name: "HgTe",
        eta: [4.779, 3.2312, 2.6599],
        k: [1.6316, 1.5808, 1.7293],
    },
    Metal {
        name: "Ir",
        eta: [3.0863, 2.0822, 1.6179],
        k: [5.5922, 4.0671, 3.2673],
    },
    Metal {
        name: "K",
        eta: [0.064043, 0.04641, 0.038185],
        k: [2.1042, 1.3489, 0.91313],
    },
    Metal {
        name: "Li",
        eta: [0.26579, 0.19562, 0.22095],
        k: [3.5402, 2.3111, 1.6686],
    },
    Metal {
        name: "MgO",
        eta: [2.0896, 1.6507, 1.5949],
        k: [0.000000, 0.0, 0.000000],
    },
    Metal {
        name: "Mo",
        eta: [4.484, 3.5251, 2.7763],
        k: [4.1114, 3.4208, 3.1506],
    },
    Metal {
        name: "Na_palik",
        eta: [0.060269, 0.056141, 0.061988],
        k: [3.1793, 2.1125, 1.579],
    },
    Metal {
        name: "Nb",
        eta: [3.4201, 2.7901, 2.3956],
        k: [3.4414, 2.7377, 2.5797],
    },
    Metal {
        name: "Ni_palik",
        eta: [2.3673, 1.6634, 1.4671],
        k: [4.4988, 3.0502, 2.3454],
    },
    Metal {
        name: "Rh",
        eta: [2.5858, 1.8602, 1.5543],
        k: [6.7823, 4.703, 3.9761],
    },
    Metal {
        name: "Se",
        eta: [4.0583, 2.8429, 2.8209],
        k: [0.75405, 0.63844, 0.52181],
    },
    Metal {
        name: "SiC",
        eta: [3.1723, 2.526, 2.4794],
        k: [0.000001, 0.0, 0.000010],
    },
    Metal {
        name: "SnTe",
        eta: [4.5242, 1.9816, 1.2816],
        k: [0.0, 0.0, 0.0],
    },
    Metal {
        name: "Ta",
        eta: [2.0627, 2.3929, 2.6279],
        k: [2.4084, 1.7415, 1.947],
    },
    Metal {
        name: "Te",
        eta: [7.3902, 4.4821, 2.6371],
        k: [3.256, 3.5271, 3.2921],
    },
    Metal {
        name: "ThF4",
        eta: [1.8307, 1.4422, 1.3876],
        k: [0.0, 0.0, 0.0],
    },
    Metal {
        name: "TiC",
        eta: [3.7005, 2.8374, 2.5823],
        k: [3.2656, 2.3516, 2.1728],
    },
    Metal {
        name: "TiN",
        eta: [1.6484, 1.1505, 1.3798],
        k: [3.3683, 1.9435, 1.1021],
    },
    Metal {
        name: "TiO2",
        eta: [3.4566, 2.8017, 2.9052],
        k: [0.00010526, 0.0, 0.00065289],
    },
    Metal {
        name: "VC",
        eta: [3.6576, 2.7527, 2.5327],
        k: [3.0683, 2.1987, 1.9632],
    },
    Metal {
        name: "V_palik",
        eta: [4.2776, 3.5129, 2.7611],
        k: [3.4913, 2.8895, 3.1115],
    },
    Metal {
        name: "VN",
        eta: [2.8656, 2.1192, 1.9401],
        k: [3.0322, 2.0561, 1.6163],
    },
    Metal {
        name: "W",
        eta: [4.3708, 3.3002, 2.9984],
        k: [3.5006, 2.6049, 2.2732],
    },
];

/// The metal called `name` in [`METALS`] (case-sensitive, as Mitsuba's names).
pub fn metal(name: &str) -> Option<&'static Metal> {
    METALS.iter().find(|m| m.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(R_s + R_p) / 2` from complex arithmetic in f64 (Born & Wolf sec. 14.2): with
    /// `n = eta + i k`, `cos_t = sqrt(1 - sin^2 / n^2)`,
    /// `r_s = (cos_i - n cos_t) / (cos_i + n cos_t)`, `r_p = (n cos_i - cos_t) / (n cos_i + cos_t)`.
    fn fresnel_complex(cos_i: f64, eta: f64, k: f64) -> f64 {
        #[derive(Clone, Copy)]
        struct C(f64, f64);
        let mul = |a: C, b: C| C(a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let div = |a: C, b: C| {
            let d = b.0 * b.0 + b.1 * b.1;
            C((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
        };
        let sqrt = |a: C| {
            let r = (a.0 * a.0 + a.1 * a.1).sqrt();
            let re = ((r + a.0) / 2.0).sqrt();
            let im = ((r - a.0) / 2.0).sqrt().copysign(a.1);
            C(re, im)
        };
        let n = C(eta, k);
        let sin2 = 1.0 - cos_i * cos_i;
        let n2 = mul(n, n);
        let s = div(C(sin2, 0.0), n2);
        let cos_t = sqrt(C(1.0 - s.0, -s.1));
        let ncos_t = mul(n, cos_t);
        let rs = div(
            C(cos_i - ncos_t.0, -ncos_t.1),
            C(cos_i + ncos_t.0, ncos_t.1),
        );
        let ncos_i = C(n.0 * cos_i, n.1 * cos_i);
        let rp = div(
            C(ncos_i.0 - cos_t.0, ncos_i.1 - cos_t.1),
            C(ncos_i.0 + cos_t.0, ncos_i.1 + cos_t.1),
        );
        let abs2 = |a: C| a.0 * a.0 + a.1 * a.1;
        0.5 * (abs2(rs) + abs2(rp))
    }

    #[test]
    fn conductor_fresnel_matches_complex_arithmetic() {
        for &(eta, k) in &[
            (0.143, 3.98),
            (1.6575, 9.2238),
            (0.2, 0.0),
            (2.5, 0.5),
            (1.5, 0.0),
        ] {
            for i in 0..=100 {
                let c = i as f64 / 100.0;
                let want = fresnel_complex(c.max(1e-9), eta, k);
                let got = fresnel_conductor(c as f32, eta as f32, k as f32) as f64;
                assert!(
                    (got - want).abs() < 2e-5,
                    "eta {eta} k {k} cos {c}: {got} vs {want}"
                );
            }
        }
        // Normal incidence: ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2).
        let r0 =
            ((0.143f32 - 1.0).powi(2) + 3.98f32.powi(2)) / ((1.143f32).powi(2) + 3.98f32.powi(2));
        assert!((fresnel_conductor(1.0, 0.143, 3.98) - r0).abs() < 1e-6);
    }

    #[test]
    fn none_is_a_perfect_reflector_and_gold_is_yellow() {
        let none = metal("none").unwrap();
        for i in 0..=20 {
            let c = i as f32 / 20.0;
            let r = fresnel_conductor_rgb(c, Rgb::from_array(none.eta), Rgb::from_array(none.k));
            assert!((r.min_channel() - 1.0).abs() < 1e-6, "cos {c}: {r:?}");
        }
        let au = metal("Au").unwrap();
        let r = fresnel_conductor_rgb(1.0, Rgb::from_array(au.eta), Rgb::from_array(au.k));
        assert!(r.r > r.g && r.g > r.b && r.r > 0.9 && r.b < 0.5, "{r:?}");
        assert!(metal("Unobtainium").is_none());
        // Names are unique.
        for (i, m) in METALS.iter().enumerate() {
            assert!(
                METALS[i + 1..].iter().all(|o| o.name != m.name),
                "{}",
                m.name
            );
        }
    }
}
