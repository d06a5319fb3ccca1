use super::*;
use crate::microfacet::{Beckmann, Ggx, Microfacet};

/// The largest difference over the cosines between two tables' entries and averages.
fn max_diff(a: &AlbedoTable, b: &AlbedoTable) -> f32 {
    a.e.iter()
        .zip(&b.e)
        .map(|(x, y)| (x - y).abs())
        .fold((a.e_avg - b.e_avg).abs(), f32::max)
}

#[test]
fn an_axis_spreads_its_points_and_collapses_to_one_for_a_constant() {
    let a = RoughnessAxis::new(0.2, 0.6, 5);
    assert_eq!((a.at(0), a.at(4)), (0.2, 0.6));
    assert!((a.at(2) - (0.2f32 * 0.6).sqrt()).abs() < 1e-6);
    let c = RoughnessAxis::new(0.3, 0.3, 5);
    assert_eq!((c.points, c.at(0), c.cell(0.9)), (1, 0.3, (0, 0.0)));
}

#[test]
fn grid_points_return_their_own_tables_exactly() {
    let axis = RoughnessAxis::new(0.1, 0.9, 5);
    let grid = RoughnessGrid::new(axis, None, |a, _| {
        AlbedoTable::from_fn(|mu| 1.0 - a * (1.0 - mu))
    });
    for i in 0..5 {
        let a = axis.at(i);
        let want = AlbedoTable::from_fn(|mu| 1.0 - a * (1.0 - mu));
        assert!(max_diff(&grid.at(a, 0.0), &want) < 1e-6, "alpha {a}");
    }
}

/// The conductor's albedo between grid points, against the table integrated there: the
/// error the energy compensation of a roughness pattern carries (a furnace is off by it).
#[test]
fn conductor_tables_interpolate_within_0_6_percent_between_grid_points() {
    for (name, make) in [
        (
            "ggx",
            (|a| Ggx::isotropic(a).into()) as fn(f32) -> Microfacet,
        ),
        ("beckmann", |a| Beckmann::new(a, a).into()),
    ] {
        let axis = RoughnessAxis::new(0.01, 1.0, POINTS_1D);
        let grid = RoughnessGrid::new(axis, None, |a, _| AlbedoTable::conductor(&make(a)));
        let mut worst = 0.0f32;
        for i in 0..POINTS_1D - 1 {
            let a = (axis.at(i) * axis.at(i + 1)).sqrt();
            let exact = AlbedoTable::conductor(&make(a));
            worst = worst.max(max_diff(&grid.at(a, a), &exact));
        }
        println!("{name}: worst |E_interp - E| at cell midpoints over [0.01, 1]: {worst:.5}");
        assert!(worst < 6e-3, "{name}: {worst}");
    }
}

#[test]
fn an_anisotropic_grid_interpolates_both_roughnesses() {
    let u = RoughnessAxis::new(0.05, 0.8, POINTS_2D);
    let v = RoughnessAxis::new(0.05, 0.8, POINTS_2D);
    let grid = RoughnessGrid::new(u, Some(v), |au, av| {
        AlbedoTable::conductor(&Ggx::new(au, av).into())
    });
    assert_eq!(grid.len(), POINTS_2D * POINTS_2D);
    let mut worst = 0.0f32;
    for (au, av) in [(0.3, 0.11), (0.62, 0.45), (0.09, 0.77)] {
        let exact = AlbedoTable::conductor(&Ggx::new(au, av).into());
        worst = worst.max(max_diff(&grid.at(au, av), &exact));
    }
    println!("anisotropic ggx: worst |E_interp - E| off the grid: {worst:.5}");
    assert!(worst < 1e-2, "{worst}");
}
