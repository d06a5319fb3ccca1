//! A scene built in code has its settings checked when it is compiled, as a scene file's are
//! when it is read (issue 35): a size changed in the settings alone (which the camera, making
//! the rays, would ignore), an empty or huge image, an spp outside 1..=65536.

use glam::Vec3;
use risotto::engine::scene::{CompileError, RenderSettings, Scene};
use risotto::systems::camera::{Camera, Projection};

fn camera(w: u32, h: u32) -> Camera {
    let p = Projection::Perspective { fov_deg: 40.0 };
    Camera::look_at(p, Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, w, h).unwrap()
}

fn compile_error(scene: Scene) -> String {
    match scene.compile() {
        Ok(_) => panic!("should be refused"),
        Err(e @ CompileError::Invalid { .. }) => e.to_string(),
        Err(e) => panic!("wrong error: {e}"),
    }
}

#[test]
fn the_camera_gives_the_size_and_later_edits_must_agree() {
    // Scene::new takes the camera's size.
    let scene = Scene::new(camera(64, 32), RenderSettings::default());
    assert_eq!((scene.settings.width, scene.settings.height), (64, 32));
    let c = scene.compile().unwrap();
    assert_eq!((c.camera.width, c.camera.height), (64, 32));

    // Changing only the settings' size would be ignored: refused, naming both sizes.
    let mut scene = Scene::new(camera(512, 512), RenderSettings::default());
    scene.settings.width = 64;
    let m = compile_error(scene);
    assert!(m.contains("64x512") && m.contains("512x512"), "{m}");

    // Both changed together: fine.
    let mut scene = Scene::new(camera(512, 512), RenderSettings::default());
    scene.settings.width = 64;
    scene.camera.width = 64;
    assert_eq!(scene.compile().unwrap().camera.width, 64);
}

#[test]
fn spp_and_image_size_are_bounded() {
    for (spp, ok) in [(0, false), (1, true), (65536, true), (65537, false)] {
        let mut scene = Scene::new(camera(8, 8), RenderSettings::default());
        scene.settings.spp = spp;
        match ok {
            true => assert!(scene.compile().is_ok(), "spp {spp}"),
            false => assert!(compile_error(scene).contains(&format!("spp {spp}"))),
        }
    }
    for (w, h) in [(0, 8), (8, 0), (1 << 14, 1 << 13)] {
        let scene = Scene::new(camera(w.max(1), h.max(1)), RenderSettings::default());
        let mut scene = scene;
        (scene.settings.width, scene.settings.height) = (w, h);
        (scene.camera.width, scene.camera.height) = (w, h);
        let m = compile_error(scene);
        assert!(m.contains(&format!("{w}x{h}")), "{m}");
    }
}
