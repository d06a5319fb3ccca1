//! `risotto render --display HOST:PORT`: the image as it renders, streamed to the tev viewer
//! (<https://github.com/Tom94/tev>), as pbrt-v4's `--display-server` does.
//!
//! tev's protocol (its `src/Ipc.cpp`, packet types 4 `CreateImage` and 6 `UpdateImageV3`):
//! every packet is `u32 length` (of the whole packet, these four bytes included), `u8 type`,
//! then the fields, little-endian, a `bool` as one byte, a string as its bytes and a NUL.
//! - CreateImage: `bool grab_focus, string name, i32 width, i32 height, i32 channels,
//!   string channel_name[channels]`.
//! - UpdateImageV3: `bool grab_focus, string name, i32 channels, string
//!   channel_name[channels], i32 x, i32 y, i32 width, i32 height, i64 offset[channels], i64
//!   stride[channels], f32 data[...]`, where channel `c` of pixel `p` (row-major within the
//!   rectangle) is `data[offset[c] + p * stride[c]]`: interleaved RGB is offsets 0, 1, 2 and
//!   strides 3.
//!
//! The display only watches: a viewer that is not running or goes away costs a warning,
//! never the render.

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

use risotto::engine::output::Image;
use risotto::engine::render::Window;

/// tev's default address (its `--hostname` default).
pub(crate) const DEFAULT_ADDRESS: &str = "127.0.0.1:14158";

/// How long a connection or a write may take before the display is given up.
const TIMEOUT: Duration = Duration::from_secs(5);

/// Pixels per update packet: large images go in bands of rows, each packet a few MB.
const PIXELS_PER_PACKET: usize = 1 << 18;

const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;
const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// A connection to a tev viewer showing one image.
pub(crate) struct TevDisplay {
    stream: TcpStream,
    name: String,
}

impl TevDisplay {
    /// Connects to the viewer at `address` (`HOST:PORT`) and opens an image `name` of the
    /// full `width` x `height` (a crop fills its window of it).
    pub(crate) fn connect(
        address: &str,
        name: &str,
        width: u32,
        height: u32,
    ) -> Result<Self, String> {
        let addrs: Vec<_> = address
            .to_socket_addrs()
            .map_err(|e| format!("--display {address}: {e}"))?
            .collect();
        let mut last = None;
        for addr in &addrs {
            match TcpStream::connect_timeout(addr, TIMEOUT) {
                Ok(stream) => {
                    stream
                        .set_write_timeout(Some(TIMEOUT))
                        .map_err(|e| format!("--display {address}: {e}"))?;
                    let mut d = TevDisplay {
                        stream,
                        name: name.to_owned(),
                    };
                    d.send(&create_image(name, width, height))
                        .map_err(|e| format!("--display {address}: {e}"))?;
                    return Ok(d);
                }
                Err(e) => last = Some(e),
            }
        }
        Err(match last {
            Some(e) => format!("--display {address}: cannot connect (is tev running?): {e}"),
            None => format!("--display {address}: the address resolves to nothing"),
        })
    }

    /// Shows `image`, the pixels of `window` of the full image.
    pub(crate) fn show(&mut self, image: &Image, window: Window) -> std::io::Result<()> {
        let width = image.width.max(1);
        let rows_per_packet = (PIXELS_PER_PACKET / width).max(1);
        let mut y = 0;
        while y < image.height {
            let rows = rows_per_packet.min(image.height - y);
            let pixels = &image.pixels[y * image.width..(y + rows) * image.width];
            let packet = update_image(
                &self.name,
                window.x0 as i32,
                window.y0 as i32 + y as i32,
                image.width as i32,
                rows as i32,
                pixels.iter().flat_map(|p| p.to_array()),
            );
            self.send(&packet)?;
            y += rows;
        }
        self.stream.flush()
    }

    fn send(&mut self, packet: &[u8]) -> std::io::Result<()> {
        self.stream.write_all(packet)
    }
}

/// A packet being written: the length is filled in by [`Packet::finish`].
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Packet {
        let mut bytes = vec![0; 4];
        bytes.push(kind);
        Packet(bytes)
    }
    fn bool(&mut self, v: bool) {
        self.0.push(u8::from(v));
    }
    fn string(&mut self, s: &str) {
        // A NUL inside would end the string early for the reader.
        self.0.extend(s.bytes().filter(|&b| b != 0));
        self.0.push(0);
    }
    fn i32(&mut self, v: i32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn finish(mut self) -> Vec<u8> {
        let len = u32::try_from(self.0.len()).unwrap_or(u32::MAX);
        self.0[..4].copy_from_slice(&len.to_le_bytes());
        self.0
    }
}

/// tev's `CreateImage` for an RGB image.
fn create_image(name: &str, width: u32, height: u32) -> Vec<u8> {
    let mut p = Packet::new(CREATE_IMAGE);
    p.bool(true);
    p.string(name);
    p.i32(width as i32);
    p.i32(height as i32);
    p.i32(CHANNELS.len() as i32);
    for c in CHANNELS {
        p.string(c);
    }
    p.finish()
}

/// tev's `UpdateImageV3` of a `width` x `height` rectangle at `(x, y)`, interleaved RGB.
fn update_image(
    name: &str,
    x: i32,
    y: i32,
    width: i32,
    height: i32,
    rgb: impl Iterator<Item = f32>,
) -> Vec<u8> {
    let mut p = Packet::new(UPDATE_IMAGE_V3);
    p.bool(false);
    p.string(name);
    p.i32(CHANNELS.len() as i32);
    for c in CHANNELS {
        p.string(c);
    }
    for v in [x, y, width, height] {
        p.i32(v);
    }
    for offset in 0..CHANNELS.len() as i64 {
        p.i64(offset);
    }
    for _ in CHANNELS {
        p.i64(CHANNELS.len() as i64);
    }
    for v in rgb {
        p.f32(v);
    }
    p.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packets_carry_their_length_and_tevs_field_layout() {
        let c = create_image("a.exr", 640, 480);
        assert_eq!(
            u32::from_le_bytes(c[..4].try_into().unwrap()) as usize,
            c.len()
        );
        assert_eq!(c[4], 4);
        assert_eq!(c[5], 1);
        assert_eq!(&c[6..12], b"a.exr\0");
        assert_eq!(i32::from_le_bytes(c[12..16].try_into().unwrap()), 640);
        assert_eq!(i32::from_le_bytes(c[16..20].try_into().unwrap()), 480);
        assert_eq!(i32::from_le_bytes(c[20..24].try_into().unwrap()), 3);
        assert_eq!(&c[24..], b"R\0G\0B\0");

        let u = update_image("a", 2, 3, 1, 1, [0.5f32, 1.0, 2.0].into_iter());
        assert_eq!(
            u32::from_le_bytes(u[..4].try_into().unwrap()) as usize,
            u.len()
        );
        assert_eq!(u[4], 6);
        // grab focus, "a\0", 3 channels, names, x y w h, offsets 0 1 2, strides 3 3 3, data.
        let head = 4 + 1 + 1 + 2 + 4 + 6 + 16 + 24 + 24;
        assert_eq!(u.len(), head + 12);
        let f =
            |i: usize| f32::from_le_bytes(u[head + 4 * i..head + 4 * i + 4].try_into().unwrap());
        assert_eq!([f(0), f(1), f(2)], [0.5, 1.0, 2.0]);
        let off = 4 + 1 + 1 + 2 + 4 + 6 + 16;
        let i64_at = |o: usize| i64::from_le_bytes(u[o..o + 8].try_into().unwrap());
        assert_eq!([i64_at(off), i64_at(off + 8), i64_at(off + 16)], [0, 1, 2]);
        assert_eq!(i64_at(off + 24), 3);
    }
}
