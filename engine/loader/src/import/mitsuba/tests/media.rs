//! The importer's media: grid and constant volumes placed as Mitsuba places them (a
//! medium exists only inside its volume's box), 3-channel grids as colour patterns.

use super::*;

/// Writes a float32 Mitsuba `.vol` of `dims` voxels and `channels` channels over the box
/// `[0, 1]^3` (its header: "VOL", version 3, encoding 1, dims, channels, box).
fn write_vol(path: &std::path::Path, dims: [i32; 3], channels: i32, values: &[f32]) {
    let mut vol = b"VOL\x03".to_vec();
    for v in [1, dims[0], dims[1], dims[2], channels] {
        vol.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(values) {
        vol.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, vol).unwrap();
}

/// A grid medium in a mesh (whose bounds the importer does not read) or in a shape reaching
/// beyond the grid: Mitsuba's medium exists only inside the grid's box, clamped there, so
/// the density is a world-space grid pattern with `border = "box"`; a turned grid box that
/// is not the shape's own is a located error.
#[test]
fn grid_media_in_meshes_exist_only_inside_the_grid_box() {
    let dir = temp("grid_in_mesh");
    // A 2 x 1 x 1 one-channel float32 .vol with the header box [0, 1]^3.
    write_vol(&dir.join("g.vol"), [2, 1, 1], 1, &[0.5, 1.0]);
    let medium = |transform: &str| {
        scene(&format!(
            r#"<medium type="heterogeneous" id="m"><volume name="sigma_t" type="gridvolume">
    <string name="filename" value="g.vol"/><transform name="to_world">{transform}</transform></volume></medium>
<shape type="obj"><string name="filename" value="cube.obj"/><bsdf type="null"/><ref id="m" name="interior"/>
    <transform name="to_world"><scale value="1.5"/></transform></shape>"#
        ))
    };
    let s = convert_in(
        &dir,
        "s.xml",
        &medium(r#"<scale value="1.5"/><translate x="-0.5" y="-0.5" z="-0.5"/>"#),
        &[],
    )
    .unwrap()
    .scene;
    let interior = s.materials[0].1.table["interior"].as_table().unwrap();
    let density = interior["density"].as_table().unwrap();
    assert_eq!(density["pattern"].as_str(), Some("grid"));
    assert_eq!(density["border"].as_str(), Some("box"));
    assert_eq!(floats(&density["min"]), [-0.5; 3]);
    assert_eq!(floats(&density["max"]), [1.0; 3]);
    let e = convert_in(&dir, "s.xml", &medium(r#"<rotate y="1" angle="30"/>"#), &[]).unwrap_err();
    assert!(e.contains("is turned") && e.contains("s.xml:"), "{e}");
}

#[test]
fn constvolume_media_exist_only_inside_the_volume_box() {
    // Mitsuba's constvolume spans [0, 1]^3 without a to_world (its `intersect_aabb`,
    // measured): in a cube [-1, 1]^3 the medium fills one octant. Its colour goes to the
    // medium's scale.
    let medium = |transform: &str, shape: &str| {
        scene(&format!(
            r#"<medium type="heterogeneous" id="m"><float name="scale" value="5"/><volume name="sigma_t" type="constvolume">
    <rgb name="value" value="0.5, 0.4, 0.3"/>{transform}</volume></medium>
<shape type="{shape}"><bsdf type="null"/><ref id="m" name="interior"/></shape>"#
        ))
    };
    let interior = |text: &str| {
        let s = convert(text).unwrap().scene;
        s.materials[0].1.table["interior"]
            .as_table()
            .unwrap()
            .clone()
    };
    let octant = interior(&medium("", "cube"));
    assert_eq!(floats(&octant["scale"]), [2.5, 2.0, 1.5]);
    let density = octant["density"].as_table().unwrap();
    assert_eq!(density["pattern"].as_str(), Some("grid"));
    assert_eq!(density["border"].as_str(), Some("box"));
    assert_eq!(floats(&density["min"]), [0.0; 3]);
    assert_eq!(floats(&density["max"]), [1.0; 3]);
    // Placed on the cube's own box, it is a constant.
    let whole = interior(&medium(
        r#"<transform name="to_world"><scale value="2"/><translate value="-1, -1, -1"/></transform>"#,
        "cube",
    ));
    assert_eq!(whole["density"]["constant"].as_float(), Some(1.0));
}

#[test]
fn three_channel_albedo_grids_become_a_sum_of_channel_patterns() {
    let dir = temp("rgb_albedo");
    // One voxel, three channels, box [0, 1]^3.
    write_vol(&dir.join("a.vol"), [1, 1, 1], 3, &[0.2, 0.5, 0.9]);
    let text = scene(
        r#"<medium type="heterogeneous" id="m"><volume name="albedo" type="gridvolume"><string name="filename" value="a.vol"/></volume></medium>
<shape type="cube"><bsdf type="null"/><ref id="m" name="interior"/></shape>"#,
    );
    let s = convert_in(&dir, "s.xml", &text, &[]).unwrap().scene;
    let albedo = &s.materials[0].1.table["interior"]["albedo"];
    assert_eq!(albedo["pattern"].as_str(), Some("remap"));
    // add(add(r * [1,0,0], g * [0,1,0]), b * [0,0,1]).
    let sum = &albedo["a"];
    let terms = [&sum["a"]["a"], &sum["a"]["b"], &sum["b"]];
    for (term, (channel, primary)) in terms.into_iter().zip([
        ("r", [1.0, 0.0, 0.0]),
        ("g", [0.0, 1.0, 0.0]),
        ("b", [0.0, 0.0, 1.0]),
    ]) {
        assert_eq!(term["pattern"].as_str(), Some("multiply"));
        assert_eq!(term["a"]["channel"].as_str(), Some(channel));
        assert_eq!(floats(&term["b"]), primary);
    }
}

#[test]
fn three_channel_density_grids_in_meshes_become_bordered_channel_patterns() {
    // A 3-channel sigma_t grid whose box is not the mesh's own: a density per channel
    // (a colour graph, not clamped as an albedo is), each channel's grid bordered by the box.
    let dir = temp("rgb_density");
    write_vol(&dir.join("s.vol"), [1, 1, 1], 3, &[0.2, 5.0, 9.0]);
    let text = scene(
        r#"<medium type="heterogeneous" id="m"><volume name="sigma_t" type="gridvolume">
    <string name="filename" value="s.vol"/><transform name="to_world"><scale value="1.5"/><translate x="-0.5" y="-0.5" z="-0.5"/></transform></volume></medium>
<shape type="obj"><string name="filename" value="cube.obj"/><bsdf type="null"/><ref id="m" name="interior"/></shape>"#,
    );
    let s = convert_in(&dir, "s.xml", &text, &[]).unwrap().scene;
    let density = &s.materials[0].1.table["interior"]["density"];
    assert_eq!(density["pattern"].as_str(), Some("add"));
    let terms = [&density["a"]["a"], &density["a"]["b"], &density["b"]];
    for (term, (channel, primary)) in terms.into_iter().zip([
        ("r", [1.0, 0.0, 0.0]),
        ("g", [0.0, 1.0, 0.0]),
        ("b", [0.0, 0.0, 1.0]),
    ]) {
        assert_eq!(term["pattern"].as_str(), Some("multiply"));
        let grid = &term["a"];
        assert_eq!(grid["channel"].as_str(), Some(channel));
        assert_eq!(grid["border"].as_str(), Some("box"));
        assert_eq!(floats(&grid["min"]), [-0.5; 3]);
        assert_eq!(floats(&grid["max"]), [1.0; 3]);
        assert_eq!(floats(&term["b"]), primary);
    }
}
