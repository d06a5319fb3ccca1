//! `[render] filter`, `filter_radius`, `filter_stddev`: defaults, values and located errors.

use super::*;
use risotto_systems::pixel_filter::GaussianFilter;

fn with_render(extra: &str) -> String {
    base_with("spp = 4", &format!("spp = 4\n{extra}"))
}

#[test]
fn filters_default_to_mitsubas_parameters() {
    let filter = |extra: &str| parse(&with_render(extra)).unwrap().render.filter;
    assert_eq!(filter(""), PixelFilter::PIXEL_BOX);
    assert_eq!(filter("filter = \"box\""), PixelFilter::Box { radius: 0.5 });
    assert_eq!(
        filter("filter = \"box\"\nfilter_radius = 1"),
        PixelFilter::Box { radius: 1.0 }
    );
    assert_eq!(
        filter("filter = \"tent\""),
        PixelFilter::Tent { radius: 1.0 }
    );
    assert_eq!(
        filter("filter = \"tent\"\nfilter_radius = 2.5"),
        PixelFilter::Tent { radius: 2.5 }
    );
    // Mitsuba: stddev 0.5, radius 4 stddev.
    assert_eq!(
        filter("filter = \"gaussian\""),
        PixelFilter::Gaussian(GaussianFilter::new(0.5, 2.0).unwrap())
    );
    assert_eq!(
        filter("filter = \"gaussian\"\nfilter_stddev = 0.25"),
        PixelFilter::Gaussian(GaussianFilter::new(0.25, 1.0).unwrap())
    );
    // pbrt-v4's defaults, written out.
    assert_eq!(
        filter("filter = \"gaussian\"\nfilter_stddev = 0.5\nfilter_radius = 1.5"),
        PixelFilter::Gaussian(GaussianFilter::new(0.5, 1.5).unwrap())
    );
}

#[test]
fn bad_filters_are_located_errors() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "filter = \"mitchell\"",
            "filter =",
            &[
                "render",
                "filter",
                "`mitchell` has negative lobes",
                "`gaussian`",
            ],
        ),
        (
            "filter = \"blur\"",
            "filter =",
            &["unknown filter `blur`", "`box`, `tent` or `gaussian`"],
        ),
        (
            "filter = \"tent\"\nfilter_radius = 0",
            "filter_radius",
            &["filter_radius", "`0`", "> 0"],
        ),
        (
            "filter = \"box\"\nfilter_radius = 100",
            "filter_radius",
            &["filter_radius", "`100`", "<= 16"],
        ),
        (
            "filter = \"gaussian\"\nfilter_stddev = -1",
            "filter_stddev",
            &["filter_stddev", "`-1`", "> 0"],
        ),
        (
            "filter = \"tent\"\nfilter_stddev = 0.5",
            "filter_stddev",
            &["filter_stddev", "\"gaussian\"` only", "`tent`"],
        ),
        (
            "filter = \"gaussian\"\nfilter_stddev = 0.01\nfilter_radius = 2",
            "filter_radius",
            &["filter_radius", "200 standard deviations", "at most 64"],
        ),
        ("filter = 3", "filter =", &["filter", "string"]),
    ];
    for (extra, at, fragments) in cases {
        let text = with_render(extra);
        let e = parse_err(&text);
        assert_message(&e, line_of(&text, at), fragments);
    }
}
