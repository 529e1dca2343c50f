//! The ROS 2 messages a bag's image topics hold, as serde types read (and,
//! for tests and writers, written) by the CDR (de)serialiser, and their
//! conversion to an 8-bit RGB frame.

use crate::image_io::{MAX_IMAGE_PIXELS, RgbImage};
use byteorder::{BigEndian, LittleEndian};
use serde::{Deserialize, Serialize};

/// `sensor_msgs/msg/Image`.
pub const IMAGE_TYPE: &str = "sensor_msgs/msg/Image";
/// `sensor_msgs/msg/CompressedImage`.
pub const COMPRESSED_IMAGE_TYPE: &str = "sensor_msgs/msg/CompressedImage";

/// `builtin_interfaces/msg/Time`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Time {
    /// Nanoseconds since the epoch.
    pub fn nanos(self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }

    /// The time of `ns` nanoseconds since the epoch.
    pub fn from_nanos(ns: i64) -> Self {
        Self {
            sec: ns.div_euclid(1_000_000_000) as i32,
            nanosec: ns.rem_euclid(1_000_000_000) as u32,
        }
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Header {
    /// When the frame was taken.
    pub stamp: Time,
    /// The camera's frame of reference.
    pub frame_id: String,
}

/// `sensor_msgs/msg/Image`: raw pixels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Image<'a> {
    /// Stamp and frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`rgb8`, `mono16`, ...).
    pub encoding: String,
    /// 1 when multi-byte pixels are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// The pixels.
    #[serde(borrow, serialize_with = "as_bytes")]
    pub data: &'a [u8],
}

/// `sensor_msgs/msg/CompressedImage`: an encoded picture.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage<'a> {
    /// Stamp and frame.
    pub header: Header,
    /// `jpeg` or `png` (possibly with a prefix such as `rgb8; jpeg compressed bgr8`).
    pub format: String,
    /// The file's bytes.
    #[serde(borrow, serialize_with = "as_bytes")]
    pub data: &'a [u8],
}

/// A `uint8[]` written in one piece (length, then the bytes) rather than
/// byte by byte: the same CDR, a memcpy for a 1080p frame.
fn as_bytes<S: serde::Serializer>(data: &&[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_bytes(data)
}

/// Read a CDR message (its 4-byte encapsulation header first: little- or
/// big-endian plain CDR).
pub fn from_cdr<'a, T: Deserialize<'a>>(bytes: &'a [u8]) -> Result<T, String> {
    if bytes.len() < 4 {
        return Err(format!(
            "{} bytes, too short for a CDR message",
            bytes.len()
        ));
    }
    let body = &bytes[4..];
    let r = match (bytes[0], bytes[1]) {
        (0, 1) => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        (0, 0) => cdr_encoding::from_bytes::<T, BigEndian>(body),
        (a, b) => {
            return Err(format!(
                "CDR encapsulation {a:#04x}{b:02x} is not plain CDR"
            ));
        }
    };
    r.map(|(v, _)| v)
        .map_err(|e| format!("not a valid message: {e}"))
}

/// A message as little-endian CDR with its encapsulation header.
pub fn to_cdr<T: Serialize>(msg: &T) -> Result<Vec<u8>, String> {
    to_cdr_with_capacity(msg, 256)
}

/// [`to_cdr`] into a buffer of `capacity` bytes to start with (an image's
/// data and a little more: written once, never regrown).
pub fn to_cdr_with_capacity<T: Serialize>(msg: &T, capacity: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(capacity);
    out.extend_from_slice(&[0, 1, 0, 0]);
    // The serialiser aligns relative to its own first byte, after the header.
    cdr_encoding::to_writer::<T, LittleEndian, _>(&mut out, msg).map_err(|e| e.to_string())?;
    Ok(out)
}

fn check_size(width: u64, height: u64) -> Result<(), String> {
    if width == 0 || height == 0 || width * height > MAX_IMAGE_PIXELS {
        return Err(format!(
            "image is {width}x{height}; frames must be 1 to {MAX_IMAGE_PIXELS} pixels (8K)"
        ));
    }
    Ok(())
}

impl Image<'_> {
    /// The pixels as 8-bit RGB: `bgr8`/`bgra8` swapped, `mono8` repeated,
    /// `mono16` kept to its high byte. Sizes are checked against 8K and the
    /// data before anything is allocated.
    pub fn to_rgb(&self) -> Result<RgbImage, String> {
        let (w, h) = (self.width as usize, self.height as usize);
        check_size(w as u64, h as u64)?;
        let channels = match self.encoding.as_str() {
            "rgb8" | "bgr8" => 3,
            "rgba8" | "bgra8" => 4,
            "mono8" | "8UC1" => 1,
            "mono16" | "16UC1" => 2,
            other => {
                return Err(format!(
                    "encoding {other:?} is not one of rgb8, bgr8, rgba8, bgra8, mono8, mono16"
                ));
            }
        };
        let row = w * channels;
        let step = self.step as usize;
        if step < row || (step as u64) * (h as u64) > self.data.len() as u64 {
            return Err(format!(
                "{w}x{h} {} needs rows of at least {row} bytes and {} bytes of data; the message has step {step} and {} bytes",
                self.encoding,
                step as u64 * h as u64,
                self.data.len()
            ));
        }
        let mut rgb = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            let line = &self.data[y * step..y * step + row];
            match self.encoding.as_str() {
                "rgb8" => rgb.extend_from_slice(line),
                "bgr8" => line
                    .chunks_exact(3)
                    .for_each(|p| rgb.extend([p[2], p[1], p[0]])),
                "rgba8" => line
                    .chunks_exact(4)
                    .for_each(|p| rgb.extend([p[0], p[1], p[2]])),
                "bgra8" => line
                    .chunks_exact(4)
                    .for_each(|p| rgb.extend([p[2], p[1], p[0]])),
                "mono8" | "8UC1" => line.iter().for_each(|&v| rgb.extend([v, v, v])),
                _ => line.chunks_exact(2).for_each(|p| {
                    let hi = if self.is_bigendian != 0 { p[0] } else { p[1] };
                    rgb.extend([hi, hi, hi]);
                }),
            }
        }
        crate::image_io::rgb_image(w, h, rgb).map_err(|e| e.to_string())
    }
}

impl CompressedImage<'_> {
    /// The picture decoded to 8-bit RGB (JPEG or PNG, told by its bytes);
    /// its header's size is checked against 8K before decoding.
    pub fn to_rgb(&self) -> Result<RgbImage, String> {
        use image::{DynamicImage, ImageReader};
        let reader = || {
            ImageReader::new(std::io::Cursor::new(self.data))
                .with_guessed_format()
                .map_err(|e| e.to_string())
        };
        let format = reader()?.format();
        if !matches!(
            format,
            Some(image::ImageFormat::Jpeg) | Some(image::ImageFormat::Png)
        ) {
            return Err(format!(
                "format {:?}: the data is not a JPEG or PNG picture",
                self.format
            ));
        }
        let (w, h) = reader()?
            .into_dimensions()
            .map_err(|e| format!("cannot read the picture's header: {e}"))?;
        check_size(w as u64, h as u64)?;
        let img = reader()?
            .decode()
            .map_err(|e| format!("cannot decode the picture: {e}"))?;
        let data = match img {
            DynamicImage::ImageRgb8(b) => b.into_raw(),
            DynamicImage::ImageLuma8(b) => b.as_raw().iter().flat_map(|&v| [v, v, v]).collect(),
            other => other.to_rgb8().into_raw(),
        };
        crate::image_io::rgb_image(w as usize, h as usize, data).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_round_trip_through_cdr_and_hostile_sizes_are_refused() {
        let px = [10u8, 20, 30, 40, 50, 60];
        let msg = Image {
            header: Header {
                stamp: Time { sec: 5, nanosec: 7 },
                frame_id: "cam".into(),
            },
            height: 1,
            width: 2,
            encoding: "bgr8".into(),
            is_bigendian: 0,
            step: 6,
            data: &px,
        };
        let bytes = to_cdr(&msg).unwrap();
        let back: Image<'_> = from_cdr(&bytes).unwrap();
        assert_eq!(back, msg);
        let rgb = back.to_rgb().unwrap();
        assert_eq!(rgb.as_slice(), &[30, 20, 10, 60, 50, 40]);
        // 100k pixels wide with 6 bytes of data: refused, nothing allocated.
        let wide = Image {
            width: 100_000,
            height: 100_000,
            step: 300_000,
            ..msg.clone()
        };
        assert!(wide.to_rgb().err().unwrap_or_default().contains("8K"));
        let short = Image {
            width: 3,
            ..msg.clone()
        };
        assert!(
            short
                .to_rgb()
                .err()
                .unwrap_or_default()
                .contains("needs rows")
        );
        let odd = Image {
            encoding: "yuv422".into(),
            ..msg
        };
        assert!(odd.to_rgb().err().unwrap_or_default().contains("yuv422"));
        // Truncated and foreign bytes are errors, not panics.
        assert!(from_cdr::<Image<'_>>(&bytes[..bytes.len() - 3]).is_err());
        assert!(from_cdr::<Image<'_>>(&[1, 2]).is_err());
        let not_a_picture = CompressedImage {
            header: Header::default(),
            format: "jpeg".into(),
            data: b"definitely not a jpeg",
        };
        assert!(
            not_a_picture
                .to_rgb()
                .err()
                .unwrap_or_default()
                .contains("not a JPEG or PNG")
        );
        assert_eq!(
            Time::from_nanos(Time { sec: 3, nanosec: 9 }.nanos()),
            Time { sec: 3, nanosec: 9 }
        );
    }
}
