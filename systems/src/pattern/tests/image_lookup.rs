//! `ImageLookup`: wrap modes, the nearest filter and the uv transform, at hand-computed
//! coordinates (Mitsuba 3's `bitmap` conventions: indices wrapped independently).

use super::*;
use glam::{Affine2, Vec2};

/// 2 x 1 texels: `A` left, `B` right.
const A: Rgb = Rgb::new(1.0, 0.0, 0.0);
const B: Rgb = Rgb::new(0.0, 0.0, 1.0);

fn pair() -> Texture {
    Texture::new(2, 1, vec![A, B]).unwrap()
}

fn how(wrap: Wrap, filter: TextureFilter) -> ImageLookup {
    ImageLookup {
        uv_transform: None,
        wrap,
        filter,
    }
}

fn close(a: Rgb, b: Rgb) -> bool {
    (a.r - b.r).abs() < 1e-6 && (a.g - b.g).abs() < 1e-6 && (a.b - b.b).abs() < 1e-6
}

#[test]
fn nearest_lookups_wrap_as_each_mode_says() {
    let t = pair();
    // (u, repeat, mirror, clamp): texel centres at u = 0.25 (A) and 0.75 (B).
    let cases = [
        (0.25, A, A, A),
        (0.75, B, B, B),
        // One tile to the right: repeat starts over, mirror runs backwards, clamp holds B.
        (1.25, A, B, B),
        (1.75, B, A, B),
        // One tile to the left.
        (-0.25, B, A, A),
        (-0.75, A, B, A),
        // Two tiles right: mirror is back in order (period 2).
        (2.25, A, A, B),
    ];
    for (u, repeat, mirror, clamp) in cases {
        for (wrap, want) in [
            (Wrap::Repeat, repeat),
            (Wrap::Mirror, mirror),
            (Wrap::Clamp, clamp),
        ] {
            let got = t.lookup_with(u, 0.5, &how(wrap, TextureFilter::Nearest));
            assert_eq!(got, want, "u = {u}, {wrap:?}");
        }
    }
}

#[test]
fn bilinear_lookups_blend_the_wrapped_neighbours() {
    let t = pair();
    let half = (A + B) * 0.5;
    // At u = 0 the lookup lies between texel -1 and texel 0: repeat blends B and A, mirror
    // A and A (texel -1 mirrors to 0), clamp A and A.
    let at = |u: f32, wrap| t.lookup_with(u, 0.5, &how(wrap, TextureFilter::Bilinear));
    assert!(close(at(0.0, Wrap::Repeat), half));
    assert!(close(at(0.0, Wrap::Mirror), A));
    assert!(close(at(0.0, Wrap::Clamp), A));
    assert!(close(at(1.0, Wrap::Mirror), B));
    assert!(close(at(1.0, Wrap::Clamp), B));
    assert!(close(at(-3.0, Wrap::Clamp), A));
    assert!(close(at(5.0, Wrap::Clamp), B));
    // Between the centres every mode is the plain blend.
    for wrap in [Wrap::Repeat, Wrap::Mirror, Wrap::Clamp] {
        assert!(close(at(0.5, wrap), half), "{wrap:?}");
    }
}

#[test]
fn the_default_lookup_is_the_plain_one_bit_for_bit() {
    let t = texture();
    let mut rng = SplitMix64(3);
    for _ in 0..1000 {
        let (u, v) = (rng.f32() * 6.0 - 3.0, rng.f32() * 6.0 - 3.0);
        assert_eq!(t.lookup_with(u, v, &ImageLookup::default()), t.lookup(u, v));
    }
}

#[test]
fn the_uv_transform_maps_before_the_lookup() {
    // Mitsuba's texture_interp scene: to_uv = translate(-0.5) * scale(2), u' = 2u - 0.5.
    let t = texture();
    let m = Affine2::from_cols(
        Vec2::new(2.0, 0.0),
        Vec2::new(0.0, 2.0),
        Vec2::new(-0.5, -0.5),
    );
    let with = ImageLookup {
        uv_transform: Some(m),
        ..ImageLookup::default()
    };
    let mut rng = SplitMix64(5);
    for _ in 0..100 {
        let (u, v) = (rng.f32(), rng.f32());
        assert_eq!(
            t.lookup_with(u, v, &with),
            t.lookup(2.0 * u - 0.5, 2.0 * v - 0.5)
        );
    }
    // The pattern node applies it too.
    let g = graph(vec![Node::Image(t.clone(), with)]);
    assert!(close(one(&g, Vec3::ZERO, 0.3, 0.6), t.lookup(0.1, 0.7)));
}
