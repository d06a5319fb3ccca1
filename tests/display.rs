//! `risotto render --display`: the image streamed to a tev viewer (issue 35). A listener in
//! the test plays tev: it reads the packets as tev's `Ipc.cpp` does (length-prefixed,
//! `CreateImage` then `UpdateImageV3`), paints the updates into an image, and the image it
//! ends with must be the EXR's beauty, bit for bit; the display must not change the render.

use std::io::Read;
use std::net::TcpListener;
use std::path::{Path, PathBuf};

mod common;
use common::cli::{ok, risotto, SCENE};
use risotto::engine::output::read_exr_rgb;

fn setup(test: &str) -> (PathBuf, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("display-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    (dir, scene)
}

/// Reads tev packets from `bytes`: `(type, payload after the type byte)`.
fn packets(mut bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut out = Vec::new();
    while bytes.len() >= 5 {
        let len = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
        assert!(len >= 5 && len <= bytes.len(), "truncated packet");
        out.push((bytes[4], bytes[5..len].to_vec()));
        bytes = &bytes[len..];
    }
    assert!(bytes.is_empty(), "trailing bytes");
    out
}

/// A cursor over a packet's fields.
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        a
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.0.iter().position(|&b| b == 0).unwrap();
        let s = String::from_utf8(self.0[..end].to_vec()).unwrap();
        self.0 = &self.0[end + 1..];
        s
    }
}

#[test]
fn the_viewer_ends_with_the_rendered_image_and_the_render_is_unchanged() {
    let (dir, scene) = setup("stream");
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let viewer = std::thread::spawn(move || {
        let (mut conn, _) = listener.accept().unwrap();
        let mut bytes = Vec::new();
        conn.read_to_end(&mut bytes).unwrap();
        bytes
    });
    let shown = dir.join("shown.exr");
    ok(
        "render --display",
        risotto(&[
            "render",
            scene.to_str().unwrap(),
            "--display",
            &address,
            "--spp",
            "64",
            "-t",
            "2",
            "--no-preview",
            "-o",
            shown.to_str().unwrap(),
        ]),
    );
    let packets = packets(&viewer.join().unwrap());

    // CreateImage: focus, the output's name, the full size, R G B.
    let (kind, create) = &packets[0];
    assert_eq!(*kind, 4);
    let mut f = Fields(create);
    assert_eq!(f.u8(), 1);
    assert_eq!(f.string(), "shown.exr");
    let (w, h) = (f.i32() as usize, f.i32() as usize);
    assert_eq!((w, h), (16, 12));
    assert_eq!(f.i32(), 3);
    assert_eq!([f.string(), f.string(), f.string()], ["R", "G", "B"]);

    // Every UpdateImageV3 painted in order.
    let mut image = vec![[f32::NAN; 3]; w * h];
    assert!(packets.len() >= 2);
    for (kind, update) in &packets[1..] {
        assert_eq!(*kind, 6);
        let mut f = Fields(update);
        f.u8();
        assert_eq!(f.string(), "shown.exr");
        assert_eq!(f.i32(), 3);
        assert_eq!([f.string(), f.string(), f.string()], ["R", "G", "B"]);
        let (x, y, rw, rh) = (f.i32(), f.i32(), f.i32(), f.i32());
        let offsets = [f.i64(), f.i64(), f.i64()];
        let strides = [f.i64(), f.i64(), f.i64()];
        assert_eq!((offsets, strides), ([0, 1, 2], [3, 3, 3]));
        let data: Vec<f32> =
            f.0.chunks_exact(4)
                .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                .collect();
        assert_eq!(data.len(), (rw * rh * 3) as usize);
        for j in 0..rh as usize {
            for i in 0..rw as usize {
                let p = j * rw as usize + i;
                image[(y as usize + j) * w + x as usize + i] =
                    [data[3 * p], data[3 * p + 1], data[3 * p + 2]];
            }
        }
    }
    let exr = read_exr_rgb(&shown).unwrap();
    for (i, p) in exr.pixels.iter().enumerate() {
        assert_eq!(
            image[i].map(f32::to_bits),
            p.to_array().map(f32::to_bits),
            "pixel {i}"
        );
    }

    // The same render without the display: the same bits.
    let plain = dir.join("plain.exr");
    ok(
        "render",
        risotto(&[
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "64",
            "-t",
            "2",
            "--no-preview",
            "-o",
            plain.to_str().unwrap(),
        ]),
    );
    assert_eq!(read_exr_rgb(&plain).unwrap(), exr);
}

#[test]
fn a_missing_viewer_is_a_warning_and_the_render_goes_on() {
    let (dir, scene) = setup("missing");
    // A port nothing listens on: bind one, then free it.
    let port = TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let out = dir.join("out.exr");
    let o = ok(
        "render --display to nobody",
        risotto(&[
            "render",
            scene.to_str().unwrap(),
            "--display",
            &format!("127.0.0.1:{port}"),
            "--no-preview",
            "-o",
            out.to_str().unwrap(),
        ]),
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("warning: --display 127.0.0.1:") && stderr.contains("cannot connect"),
        "{stderr}"
    );
    assert!(out.exists());
}
