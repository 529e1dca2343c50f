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
/// `foxglove.RawImage` (protobuf), as the Foxglove SDK records raw frames.
pub const FOXGLOVE_RAW_IMAGE_TYPE: &str = "foxglove.RawImage";
/// `foxglove.CompressedImage` (protobuf), as the Foxglove SDK records
/// JPEG and PNG frames.
pub const FOXGLOVE_COMPRESSED_IMAGE_TYPE: &str = "foxglove.CompressedImage";

/// `foxglove.CompressedVideo` (protobuf), as the Foxglove SDK records a
/// video stream: one H.264, H.265, VP9 or AV1 frame per message.
pub const FOXGLOVE_COMPRESSED_VIDEO_TYPE: &str = "foxglove.CompressedVideo";
/// `foxglove_msgs/msg/CompressedVideo` (CDR): the same message in ROS 2,
/// as the Foxglove bridge and ROS 2 video encoders publish it.
pub const ROS_COMPRESSED_VIDEO_TYPE: &str = "foxglove_msgs/msg/CompressedVideo";
/// `ffmpeg_image_transport_msgs/msg/FFMPEGPacket` (CDR): one encoded
/// frame as ROS 2's `ffmpeg_image_transport` publishes it.
pub const FFMPEG_PACKET_TYPE: &str = "ffmpeg_image_transport_msgs/msg/FFMPEGPacket";
/// `h264_msgs/msg/Packet` (CDR): one H.264 packet as ROS 2's
/// `h264_image_transport` publishes a V4L2 camera's stream.
pub const H264_PACKET_TYPE: &str = "h264_msgs/msg/Packet";

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

/// `foxglove_msgs/msg/CompressedVideo`: one frame of a video stream.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompressedVideo<'a> {
    /// When the frame was taken.
    pub timestamp: Time,
    /// The camera's frame of reference.
    pub frame_id: String,
    /// The frame's packets (for H.264 and H.265, Annex B NAL units).
    #[serde(borrow, serialize_with = "as_bytes")]
    pub data: &'a [u8],
    /// `h264`, `h265`, `vp9` or `av1`.
    pub format: String,
}

/// `ffmpeg_image_transport_msgs/msg/FFMPEGPacket`: one packet of the
/// encoder `ffmpeg_image_transport` runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FfmpegPacket<'a> {
    /// Stamp and frame.
    pub header: Header,
    /// The frame's width before encoding.
    pub width: i32,
    /// The frame's height before encoding.
    pub height: i32,
    /// The codec, as its first `;`-separated token (`h264`, `hevc`), or,
    /// from older publishers, the encoder's name (`libx264`,
    /// `hevc_nvenc`).
    pub encoding: String,
    /// The encoder's presentation time.
    pub pts: u64,
    /// The encoder's packet flags.
    pub flags: u8,
    /// The publisher's byte order.
    pub is_bigendian: bool,
    /// The packet (Annex B NAL units).
    #[serde(borrow, serialize_with = "as_bytes")]
    pub data: &'a [u8],
}

/// `h264_msgs/msg/Packet`: one H.264 packet of `h264_image_transport`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct H264Packet<'a> {
    /// Stamp and frame.
    pub header: Header,
    /// The packet's number in the publisher's stream.
    pub seq: i64,
    /// The packet (Annex B NAL units).
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

/// How an `Image`'s bytes hold its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PixelLayout {
    Rgb,
    Bgr,
    Rgba,
    Bgra,
    Mono8,
    Mono16,
    /// Packed 4:2:2, `U Y0 V Y1` (ROS's `yuv422`).
    Uyvy,
    /// Packed 4:2:2, `Y0 U Y1 V` (ROS's `yuv422_yuy2`).
    Yuyv,
    Bayer(kornia_imgproc::color::BayerPattern),
}

/// The encodings read, as `sensor_msgs/image_encodings` and Foxglove name
/// them: OpenCV's `8UC3`/`8UC4` (what `cv_bridge` writes for a frame
/// without an encoding) are its BGR order.
pub const IMAGE_ENCODINGS: &str = "rgb8, bgr8, rgba8, bgra8, mono8, mono16, 8UC1, 8UC3, 8UC4, 16UC1, yuv422 (uyvy), yuv422_yuy2 (yuyv), bayer_rggb8, bayer_bggr8, bayer_gbrg8, bayer_grbg8";

impl PixelLayout {
    fn of(encoding: &str) -> Option<Self> {
        use kornia_imgproc::color::BayerPattern as B;
        Some(match encoding {
            "rgb8" => Self::Rgb,
            "bgr8" | "8UC3" => Self::Bgr,
            "rgba8" => Self::Rgba,
            "bgra8" | "8UC4" => Self::Bgra,
            "mono8" | "8UC1" => Self::Mono8,
            "mono16" | "16UC1" => Self::Mono16,
            "yuv422" | "uyvy" => Self::Uyvy,
            "yuv422_yuy2" | "yuyv" => Self::Yuyv,
            "bayer_rggb8" => Self::Bayer(B::Rggb),
            "bayer_bggr8" => Self::Bayer(B::Bggr),
            "bayer_gbrg8" => Self::Bayer(B::Gbrg),
            "bayer_grbg8" => Self::Bayer(B::Grbg),
            _ => return None,
        })
    }

    fn bytes_per_pixel(self) -> usize {
        match self {
            Self::Rgb | Self::Bgr => 3,
            Self::Rgba | Self::Bgra => 4,
            Self::Mono8 | Self::Bayer(_) => 1,
            Self::Mono16 | Self::Uyvy | Self::Yuyv => 2,
        }
    }
}

impl Image<'_> {
    /// The pixels as 8-bit RGB: BGR orders swapped, alpha dropped, `mono8`
    /// repeated, `mono16` kept to its high byte; packed YUV 4:2:2 and
    /// Bayer mosaics converted by `kornia-imgproc` (BT.601; bilinear
    /// demosaicing). Sizes are checked against 8K and the data before
    /// anything is allocated.
    pub fn to_rgb(&self) -> Result<RgbImage, String> {
        let (w, h) = (self.width as usize, self.height as usize);
        check_size(w as u64, h as u64)?;
        let Some(layout) = PixelLayout::of(&self.encoding) else {
            return Err(format!(
                "encoding {:?} is not one of {IMAGE_ENCODINGS}",
                self.encoding
            ));
        };
        if matches!(layout, PixelLayout::Uyvy | PixelLayout::Yuyv) && w % 2 == 1 {
            return Err(format!(
                "{w}x{h} {}: a 4:2:2 frame's width must be even",
                self.encoding
            ));
        }
        let row = w * layout.bytes_per_pixel();
        let step = self.step as usize;
        if step < row {
            return Err(format!(
                "{w}x{h} {}: step {step} is shorter than a row, which is {row} bytes",
                self.encoding
            ));
        }
        if (step as u64) * (h as u64) > self.data.len() as u64 {
            return Err(format!(
                "{w}x{h} {} with step {step} needs {} bytes of data; the message has {}",
                self.encoding,
                step as u64 * h as u64,
                self.data.len()
            ));
        }
        let rows = || (0..h).map(|y| &self.data[y * step..y * step + row]);
        // Byte layouts are rewritten pixel by pixel, a row at a time.
        let per_pixel = |write: &dyn Fn(&[u8], &mut Vec<u8>)| {
            let mut rgb = Vec::with_capacity(w * h * 3);
            rows().for_each(|line| write(line, &mut rgb));
            crate::image_io::rgb_image(w, h, rgb).map_err(|e| e.to_string())
        };
        match layout {
            PixelLayout::Rgb => per_pixel(&|line, rgb| rgb.extend_from_slice(line)),
            PixelLayout::Bgr => per_pixel(&|line, rgb| {
                line.chunks_exact(3)
                    .for_each(|p| rgb.extend([p[2], p[1], p[0]]))
            }),
            PixelLayout::Rgba => per_pixel(&|line, rgb| {
                line.chunks_exact(4)
                    .for_each(|p| rgb.extend([p[0], p[1], p[2]]))
            }),
            PixelLayout::Bgra => per_pixel(&|line, rgb| {
                line.chunks_exact(4)
                    .for_each(|p| rgb.extend([p[2], p[1], p[0]]))
            }),
            PixelLayout::Mono8 => {
                per_pixel(&|line, rgb| line.iter().for_each(|&v| rgb.extend([v, v, v])))
            }
            PixelLayout::Mono16 => per_pixel(&|line, rgb| {
                line.chunks_exact(2).for_each(|p| {
                    let hi = if self.is_bigendian != 0 { p[0] } else { p[1] };
                    rgb.extend([hi, hi, hi]);
                })
            }),
            PixelLayout::Uyvy | PixelLayout::Yuyv | PixelLayout::Bayer(_) => {
                // kornia's converters take the rows packed: borrowed as
                // they are unless the message pads them.
                let packed: std::borrow::Cow<'_, [u8]> = match step == row {
                    true => self.data[..row * h].into(),
                    false => rows().flatten().copied().collect::<Vec<u8>>().into(),
                };
                kornia_to_rgb(layout, w, h, packed)
                    .map_err(|e| format!("cannot convert the {} pixels: {e}", self.encoding))
            }
        }
    }
}

/// Packed 4:2:2 or a Bayer mosaic (`packed`, `w` x `h`, rows without
/// padding) to RGB through `kornia-imgproc`.
fn kornia_to_rgb(
    layout: PixelLayout,
    w: usize,
    h: usize,
    packed: std::borrow::Cow<'_, [u8]>,
) -> Result<RgbImage, String> {
    use kornia_imgproc::color as c;
    let mut out =
        crate::image_io::rgb_image(w, h, vec![0; w * h * 3]).map_err(|e| e.to_string())?;
    match layout {
        PixelLayout::Bayer(pattern) => {
            let mosaic = crate::image_io::grey_image(w, h, packed.into_owned())
                .map_err(|e| e.to_string())?;
            c::rgb_from_bayer(&mosaic, pattern, &mut out)
        }
        PixelLayout::Uyvy => c::rgb_from_uyvy(&packed, &mut out),
        PixelLayout::Yuyv => c::rgb_from_yuyv(&packed, &mut out),
        other => {
            return Err(format!(
                "{other:?} is rewritten byte by byte, not converted"
            ));
        }
    }
    .map_err(|e| e.to_string())?;
    Ok(out)
}

impl CompressedImage<'_> {
    /// The picture decoded to 8-bit RGB (JPEG, PNG or another frame format,
    /// told by its bytes, as `cv_bridge`'s `imdecode` tells it)
    /// as it is shown (its EXIF orientation applied, as `cv_bridge`'s
    /// `imdecode` applies it); its header's size is checked against 8K
    /// before decoding.
    pub fn to_rgb(&self) -> Result<RgbImage, String> {
        use image::{DynamicImage, ImageReader};
        let reader = || {
            ImageReader::new(std::io::Cursor::new(self.data))
                .with_guessed_format()
                .map_err(|e| e.to_string())
        };
        let format = reader()?.format();
        if !format.is_some_and(crate::image_io::is_frame_format) {
            if super::video::is_video_format(&self.format) {
                return Err(format!(
                    "format {:?} is a video packet, not a picture: a video topic's packets are decoded as one stream (a bag's topic that begins with one is read so; live, tactile.VideoDecoder, the ROS 2 node's video:=compressed)",
                    self.format
                ));
            }
            return Err(format!(
                "format {:?}: the data is not a picture in a format frames are read in ({})",
                self.format,
                crate::source::FRAME_FORMATS
            ));
        }
        let bytes = std::io::Cursor::new(self.data);
        if let Some(why) = format.and_then(|f| crate::image_io::more_than_one_picture(bytes, f)) {
            return Err(format!("{why}; a message's picture is one frame"));
        }
        let refusal =
            |what: &str, e: image::ImageError| crate::image_io::refusal(what, &e, self.data);
        let (w, h) = reader()?
            .into_dimensions()
            .map_err(|e| refusal("cannot read the picture's header", e))?;
        check_size(w as u64, h as u64)?;
        let img = crate::image_io::decode_upright(reader()?)
            .map_err(|e| refusal("cannot decode the picture", e))?;
        let (w, h) = (img.width(), img.height());
        let data = match img {
            DynamicImage::ImageRgb8(b) => b.into_raw(),
            DynamicImage::ImageLuma8(b) => crate::image_io::grey_to_rgb(b.as_raw()),
            other => other.to_rgb8().into_raw(),
        };
        crate::image_io::rgb_image(w as usize, h as usize, data).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_video_packet_in_a_compressed_image_is_named_as_video() {
        // An H.264 keyframe's start (SPS, IDR) as GStreamer's ROS 2 sink
        // publishes it, given as a picture: the error says what it is and
        // where it is read, not only that it is no JPEG.
        let data = [0, 0, 0, 1, 0x67, 0x42, 0, 0x1e, 0, 0, 0, 1, 0x65, 0x88];
        for format in ["h264", "H265", " vp9"] {
            let e = CompressedImage {
                header: Header::default(),
                format: format.into(),
                data: &data,
            }
            .to_rgb()
            .err()
            .unwrap();
            assert!(e.contains("is a video packet, not a picture"), "{e}");
            assert!(e.contains("tactile.VideoDecoder"), "{e}");
        }
        let e = CompressedImage {
            header: Header::default(),
            format: "jpeg".into(),
            data: &data,
        }
        .to_rgb()
        .err()
        .unwrap();
        assert!(
            e.contains("the data is not a picture in a format frames are read in (PNG, JPEG,"),
            "{e}"
        );
    }

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
        let e = short.to_rgb().err().unwrap_or_default();
        assert!(
            e.contains("3x1 bgr8: step 6 is shorter than a row, which is 9 bytes"),
            "{e}"
        );
        // A step of 0 is named as such, not as a need for 0 bytes.
        let no_step = Image {
            step: 0,
            ..msg.clone()
        };
        let e = no_step.to_rgb().err().unwrap_or_default();
        assert!(e.contains("step 0 is shorter than a row"), "{e}");
        let truncated = Image {
            height: 2,
            ..msg.clone()
        };
        let e = truncated.to_rgb().err().unwrap_or_default();
        assert!(
            e.contains("2x2 bgr8 with step 6 needs 12 bytes of data; the message has 6"),
            "{e}"
        );
        let odd = Image {
            encoding: "yuv422".into(),
            width: 3,
            step: 6,
            ..msg.clone()
        };
        let e = odd.to_rgb().err().unwrap_or_default();
        assert!(
            e.contains("yuv422") && e.contains("width must be even"),
            "{e}"
        );
        let unknown = Image {
            encoding: "nv21".into(),
            ..msg
        };
        let e = unknown.to_rgb().err().unwrap_or_default();
        assert!(e.contains("\"nv21\" is not one of rgb8"), "{e}");
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
                .contains("not a picture in a format frames are read in")
        );
        assert_eq!(
            Time::from_nanos(Time { sec: 3, nanosec: 9 }.nanos()),
            Time { sec: 3, nanosec: 9 }
        );
    }

    /// An `Image` of `data` in `encoding`, `step` bytes a row.
    fn image<'a>(encoding: &str, w: u32, h: u32, step: u32, data: &'a [u8]) -> Image<'a> {
        Image {
            header: Header::default(),
            height: h,
            width: w,
            encoding: encoding.into(),
            is_bigendian: 0,
            step,
            data,
        }
    }

    /// A smooth 16x12 RGB frame (the converters average neighbours).
    fn smooth() -> Vec<u8> {
        (0..12u32)
            .flat_map(|y| {
                (0..16u32).flat_map(move |x| [(60 + 8 * x) as u8, (40 + 10 * y) as u8, 120])
            })
            .collect()
    }

    fn max_diff(a: &[u8], b: &[u8]) -> u8 {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap_or(0)
    }

    #[test]
    fn opencv_yuv_and_bayer_encodings_give_the_frame() {
        let rgb = smooth();
        let (w, h) = (16u32, 12u32);
        // cv_bridge's 8UC3 / 8UC4: OpenCV's BGR order, as Foxglove reads it.
        let bgr: Vec<u8> = rgb.chunks(3).flat_map(|p| [p[2], p[1], p[0]]).collect();
        let bgra: Vec<u8> = rgb
            .chunks(3)
            .flat_map(|p| [p[2], p[1], p[0], 255])
            .collect();
        let got = image("8UC3", w, h, w * 3, &bgr).to_rgb().unwrap();
        assert_eq!(got.as_slice(), rgb.as_slice());
        let got = image("8UC4", w, h, w * 4, &bgra).to_rgb().unwrap();
        assert_eq!(got.as_slice(), rgb.as_slice());
        // Packed 4:2:2 made by kornia's encoder, rows padded by 8 bytes;
        // UYVY is the same samples in the other order.
        let src = crate::image_io::rgb_image(16, 12, rgb.clone()).unwrap();
        let mut yuyv = vec![0u8; 16 * 12 * 2];
        kornia_imgproc::color::yuyv_from_rgb(&src, &mut yuyv).unwrap();
        let pad = |rows: &[u8], row: usize| -> Vec<u8> {
            rows.chunks(row)
                .flat_map(|r| r.iter().copied().chain([7; 8]))
                .collect()
        };
        let uyvy: Vec<u8> = yuyv.chunks(2).flat_map(|p| [p[1], p[0]]).collect();
        for (enc, packed) in [
            ("yuv422_yuy2", &yuyv),
            ("yuyv", &yuyv),
            ("yuv422", &uyvy),
            ("uyvy", &uyvy),
        ] {
            let data = pad(packed, 32);
            let got = image(enc, w, h, 40, &data).to_rgb().unwrap();
            let d = max_diff(got.as_slice(), &rgb);
            assert!(d <= 12, "{enc}: off by {d}");
        }
        // Bayer mosaics sampled from the frame, demosaiced back.
        for (enc, at) in [
            ("bayer_rggb8", [[0, 1], [1, 2]]),
            ("bayer_bggr8", [[2, 1], [1, 0]]),
            ("bayer_grbg8", [[1, 0], [2, 1]]),
            ("bayer_gbrg8", [[1, 2], [0, 1]]),
        ] {
            let mosaic: Vec<u8> = (0..12usize)
                .flat_map(|y| (0..16usize).map(move |x| (x, y)))
                .map(|(x, y)| rgb[(y * 16 + x) * 3 + at[y % 2][x % 2]])
                .collect();
            let got = image(enc, w, h, w, &mosaic).to_rgb().unwrap();
            // Inside the border, where bilinear demosaicing has every neighbour.
            let inner = |v: &[u8]| -> Vec<u8> {
                (1..11usize)
                    .flat_map(|y| {
                        (1..15usize).flat_map(move |x| (0..3).map(move |c| (y * 16 + x) * 3 + c))
                    })
                    .map(|i| v[i])
                    .collect()
            };
            let d = max_diff(&inner(got.as_slice()), &inner(&rgb));
            assert!(d <= 6, "{enc}: off by {d}");
            // A channel out of place would be off by tens.
            assert!(
                got.as_slice()[(5 * 16 + 5) * 3 + 2].abs_diff(120) <= 6,
                "{enc}"
            );
        }
    }
}
