//! Video topics of a bag: `foxglove.CompressedVideo`, as the Foxglove SDK
//! records a camera, ROS 2's `foxglove_msgs/msg/CompressedVideo`, as ROS 2
//! video encoders publish one, `ffmpeg_image_transport_msgs/msg/
//! FFMPEGPacket`, as ROS 2's `ffmpeg_image_transport` does, and
//! `h264_msgs/msg/Packet`, as `h264_image_transport` does: an H.264,
//! H.265, VP9 or AV1 frame per message, decoded by the system's FFmpeg. No
//! codec is written here.
//!
//! The topic's packets are written in order to an FFmpeg process from a
//! thread of their own while the decoded frames are read back here (PAM
//! pictures, which carry their size). Each packet goes in as an IVF frame
//! with its stamp as its presentation time, and FFmpeg gives each frame's
//! time back beside its picture, so every frame takes its own packet's
//! stamp: in display order when the stream has B-frames (whose packets
//! come in decoding order, each stamped with the time it shows, as
//! `ffmpeg_image_transport` publishes them), and the frames after a
//! damaged packet that gave none keep their own (the lost packets are
//! named in a warning). Only a stream whose stamps are not its frames'
//! display order gives times that name no packet (or that FFmpeg raised
//! so they do not go back); each such frame takes the stamp of the
//! earliest written packet without a frame, which is its own without
//! B-frames while no frame is lost. A packet whose headers show no frame
//! (invisible VP9 frames, hidden AV1 ones) is owed none; H.264 or H.265
//! parameter sets sent alone join the next packet. Packets
//! before the stream's first keyframe (a recording begun mid-stream)
//! cannot be decoded by anyone: they are skipped, with a warning.

use std::borrow::Cow;
use std::collections::BTreeSet;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::thread::JoinHandle;

use image::codecs::pnm::PnmDecoder;
use image::{ColorType, ImageDecoder};

use super::messages::{
    COMPRESSED_IMAGE_TYPE, CompressedImage, CompressedVideo, FFMPEG_PACKET_TYPE,
    FOXGLOVE_COMPRESSED_IMAGE_TYPE, FOXGLOVE_COMPRESSED_VIDEO_TYPE, FfmpegPacket, H264_PACKET_TYPE,
    H264Packet, ROS_COMPRESSED_VIDEO_TYPE, from_cdr,
};
use super::{
    BagFrame, TopicMessage, TopicMessages, bag_error, foxglove_message, foxglove_stamp,
    stamp_or_log_time,
};
use crate::image_io::{MAX_IMAGE_PIXELS, RgbImage, rgb_image};
use crate::video::{demuxer_time_base, keep_tail, last_words, passthrough_options, spawn_error};
use crate::{Error, Result};

/// True for the video message types.
pub(super) fn is_video_type(t: &str) -> bool {
    [
        FOXGLOVE_COMPRESSED_VIDEO_TYPE,
        ROS_COMPRESSED_VIDEO_TYPE,
        FFMPEG_PACKET_TYPE,
        H264_PACKET_TYPE,
    ]
    .contains(&t)
}

/// True when a message of a compressed image type (ROS 2's or Foxglove's)
/// carries video: its `format` names a codec read (`h264`, `h265`,
/// `hevc`, `vp9`, `av1`), as GStreamer's ROS 2 sink and
/// `nimbro_cam_transport` publish H.264 packets. Such a topic is read as a
/// video topic.
pub(super) fn carries_video(topic: &TopicMessages, m: &TopicMessage) -> Result<bool> {
    let format = match m.message_type.as_str() {
        COMPRESSED_IMAGE_TYPE => {
            let c: CompressedImage<'_> =
                from_cdr(&m.data).map_err(|e| topic.message_error(m.index, e))?;
            c.format
        }
        FOXGLOVE_COMPRESSED_IMAGE_TYPE => {
            foxglove_message::<foxglove::messages::CompressedImage>(topic, m)?.format
        }
        _ => return Ok(false),
    };
    Ok(is_video_format(&format))
}

/// True when a compressed image's `format` names a video codec read.
pub(crate) fn is_video_format(format: &str) -> bool {
    Codec::of(format.trim()).is_some()
}

/// The video formats read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Codec {
    H264,
    H265,
    Vp9,
    Av1,
}

/// The size of an IVF file's header; each frame's is 12 bytes (its size
/// and presentation time).
const IVF_FILE_HEADER: usize = 32;

/// The IVF time base's denominator: packets' times are written in
/// nanoseconds, as their stamps are.
const IVF_NANOSECONDS: usize = 1_000_000_000;

/// AV1's temporal delimiter (an OBU of type 2 with its size field, empty;
/// AV1 5.6), which begins each temporal unit of the low overhead format.
const AV1_TEMPORAL_DELIMITER: [u8; 2] = [0x12, 0x00];

/// An AV1 temporal unit without its own leading temporal delimiter
/// ([`Codec::write_packet`] writes one before each).
fn without_temporal_delimiter(data: &[u8]) -> &[u8] {
    data.strip_prefix(&AV1_TEMPORAL_DELIMITER).unwrap_or(data)
}

/// The OBUs of AV1 data in the low overhead format (AV1 5.3: a header
/// byte, an extension byte when flagged, a LEB128 size when flagged), each
/// as its type and payload; the walk stops at one that does not fit.
fn av1_obus(mut data: &[u8]) -> impl Iterator<Item = (u8, &[u8])> {
    std::iter::from_fn(move || {
        let (&header, rest) = data.split_first()?;
        let rest = rest.get(usize::from(header & 0x04 != 0)..)?;
        let (size, rest) = match header & 0x02 != 0 {
            true => leb128(rest)?,
            false => (rest.len(), rest),
        };
        let payload = rest.get(..size)?;
        data = &rest[size..];
        Some(((header >> 3) & 0x0f, payload))
    })
}

/// The NAL units of Annex B data: the bytes after each `00 00 01` start
/// code up to the next one (without the zero bytes before it: a 4-byte
/// start code's first, or trailing ones).
fn nal_units(data: &[u8]) -> impl Iterator<Item = &[u8]> {
    // memchr's vectorised search: 57 GB/s against 2.8 for a byte-wise scan
    // (30 frames of 1080p x264, 777 KB, here).
    let mut starts = memchr::memmem::find_iter(data, &[0, 0, 1]).peekable();
    std::iter::from_fn(move || {
        let at = starts.next()? + 3;
        let end = starts.peek().copied().unwrap_or(data.len()).max(at);
        let unit = &data[at..end];
        let len = unit.iter().rposition(|&b| b != 0).map_or(0, |p| p + 1);
        Some(&unit[..len])
    })
}

/// A VP9 key frame's format and size, read from its uncompressed header
/// (VP9 6.2) by a bit reader: the frame marker (2), profile (and a
/// reserved bit in profile 3), `show_existing_frame` 0, `frame_type` 0,
/// `show_frame` and `error_resilient_mode`, the sync code 49 83 42, then
/// `color_config` (bit depth, color space, range, subsampling) and
/// `frame_size`. `None` when the packet's (first) frame is no key frame.
fn vp9_key_frame(data: &[u8]) -> Option<[u32; 7]> {
    use bitstream_io::{BigEndian, BitRead, BitReader};
    let mut r = BitReader::endian(data, BigEndian);
    let mut bits = |n: u32| r.read_var::<u32>(n).ok();
    if bits(2)? != 2 {
        return None;
    }
    let profile = bits(1)? | (bits(1)? << 1);
    if profile == 3 {
        bits(1)?;
    }
    // show_existing_frame, then frame_type (0: a key frame).
    if bits(1)? != 0 || bits(1)? != 0 {
        return None;
    }
    bits(2)?;
    if bits(24)? != 0x49_83_42 {
        return None;
    }
    let depth = if profile >= 2 { bits(1)? } else { 0 };
    let color_space = bits(3)?;
    let (mut range, mut subsampling) = (0, 0);
    let full_chroma = profile == 1 || profile == 3;
    // 7: CS_RGB, which has no range and no subsampling.
    if color_space != 7 {
        range = bits(1)?;
        if full_chroma {
            subsampling = bits(2)?;
            bits(1)?;
        }
    } else if full_chroma {
        bits(1)?;
    }
    let (width, height) = (bits(16)? + 1, bits(16)? + 1);
    Some([
        profile,
        depth,
        color_space,
        range,
        subsampling,
        width,
        height,
    ])
}

/// The frames of a VP9 packet: those of its superframe index (VP9 Annex
/// B: a last byte `110` + size bytes - 1 (2 bits) + frames - 1 (3 bits),
/// repeated before the sizes), else the packet itself.
fn vp9_frames(data: &[u8]) -> Box<dyn Iterator<Item = &[u8]> + '_> {
    let whole = || Box::new(std::iter::once(data));
    let Some(&marker) = data.last() else {
        return whole();
    };
    if marker & 0xe0 != 0xc0 {
        return whole();
    }
    let (size_bytes, frames) = (
        usize::from((marker >> 3) & 3) + 1,
        usize::from(marker & 7) + 1,
    );
    let index = 2 + size_bytes * frames;
    let Some(start) = data.len().checked_sub(index) else {
        return whole();
    };
    if data[start] != marker {
        return whole();
    }
    let sizes = data[start + 1..data.len() - 1].chunks(size_bytes).map(|b| {
        b.iter()
            .rev()
            .fold(0usize, |size, &byte| (size << 8) | usize::from(byte))
    });
    let mut at = 0usize;
    let mut parts = Vec::with_capacity(frames);
    for size in sizes {
        match data[..start].get(at..at.saturating_add(size)) {
            Some(part) => parts.push(part),
            None => return whole(),
        }
        at += size;
    }
    Box::new(parts.into_iter())
}

/// True unless a VP9 frame's uncompressed header (VP9 6.2) says it is
/// invisible: `show_existing_frame` 0 and `show_frame` 0. A frame not read
/// (no frame marker) is taken to show.
fn vp9_shows_frame(frame: &[u8]) -> bool {
    use bitstream_io::{BigEndian, BitRead, BitReader};
    let mut r = BitReader::endian(frame, BigEndian);
    let mut bits = |n: u32| r.read_var::<u32>(n).ok();
    let mut hidden = || -> Option<bool> {
        if bits(2)? != 2 {
            return None;
        }
        let profile = bits(1)? | (bits(1)? << 1);
        if profile == 3 {
            bits(1)?;
        }
        // show_existing_frame, frame_type, show_frame.
        if bits(1)? == 1 {
            return Some(false);
        }
        bits(1)?;
        Some(bits(1)? == 0)
    };
    hidden() != Some(true)
}

/// An unsigned LEB128 value (at most 8 bytes, AV1 4.10.5) and what follows.
fn leb128(data: &[u8]) -> Option<(usize, &[u8])> {
    let mut value = 0u64;
    for (i, &b) in data.iter().enumerate().take(8) {
        value |= u64::from(b & 0x7f) << (7 * i);
        if b & 0x80 == 0 {
            return Some((usize::try_from(value).ok()?, &data[i + 1..]));
        }
    }
    None
}

impl Codec {
    /// The codec of `format`, or the error naming what is read.
    fn read(format: &str) -> std::result::Result<Self, String> {
        Self::of(format).ok_or_else(|| {
            format!(
                "video in format {format:?}; read are \"h264\" and \"h265\" (Annex B), \"vp9\" (a frame or superframe per message) and \"av1\" (low overhead OBUs), as the Foxglove SDK and ROS 2's video encoders record them"
            )
        })
    }

    /// The codec of a message's `format`.
    fn of(format: &str) -> Option<Self> {
        match format.to_ascii_lowercase().as_str() {
            "h264" => Some(Self::H264),
            "h265" | "hevc" => Some(Self::H265),
            "vp9" => Some(Self::Vp9),
            "av1" => Some(Self::Av1),
            _ => None,
        }
    }

    /// The format an `ffmpeg_image_transport` packet's `encoding` names:
    /// its codec (`h264`, `hevc`, `vp9`, `av1`: the first `;`-separated
    /// token) or, from older publishers, its encoder (`libx264`,
    /// `h264_nvenc`, `hevc_vaapi`, `libvpx-vp9`, `libsvtav1`). Anything
    /// else is kept, to be refused by name.
    fn of_encoding(encoding: &str) -> String {
        let codec = encoding
            .split(';')
            .next()
            .unwrap_or("")
            .to_ascii_lowercase();
        if codec.contains("av1") {
            Self::Av1.name().into()
        } else if codec.contains("vp9") {
            Self::Vp9.name().into()
        } else if codec.contains("hevc") || codec.contains("265") {
            Self::H265.name().into()
        } else if codec.contains("264") {
            Self::H264.name().into()
        } else {
            codec
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::H264 => "h264",
            Self::H265 => "h265",
            Self::Vp9 => "vp9",
            Self::Av1 => "av1",
        }
    }

    /// Write a packet as an IVF frame (its size and presentation time
    /// `pts` before it), after the IVF file header for a decoder's `first`
    /// packet. FFmpeg reads VP9 only inside a container, and in IVF every
    /// codec's frame ends where its size says, so each packet is decoded as
    /// soon as it is in (live, no delimiter waits for the next), and each
    /// frame comes out with its own packet's `pts` (read back beside the
    /// picture: [`frame_times`]), which tells whose frame it is, B-frames
    /// and lost frames alike. AV1's temporal unit gets one temporal
    /// delimiter, its own dropped ([`without_temporal_delimiter`]), so it
    /// reads alike whether or not the recorder kept it.
    fn write_packet(
        self,
        out: &mut impl Write,
        data: &[u8],
        first: bool,
        pts: i64,
    ) -> std::io::Result<()> {
        let data: Cow<'_, [u8]> = match self {
            Self::Av1 => {
                let unit = without_temporal_delimiter(data);
                let mut d = Vec::with_capacity(AV1_TEMPORAL_DELIMITER.len() + unit.len());
                d.extend_from_slice(&AV1_TEMPORAL_DELIMITER);
                d.extend_from_slice(unit);
                Cow::Owned(d)
            }
            _ => Cow::Borrowed(data),
        };
        // An IVF frame's size is 32 bits.
        if u32::try_from(data.len()).is_err() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("a {} packet of 4 GiB or more", self.name()),
            ));
        }
        // Framed in memory: the `ivf` crate's writers panic on a write
        // error, and FFmpeg's input is a pipe that may close.
        let mut framed = Vec::with_capacity(IVF_FILE_HEADER + 12 + data.len());
        if first {
            // The size is the decoder's to read from the stream; times
            // are in nanoseconds (the muxer names AV1: the fourcc is set).
            ivf::write_ivf_header(&mut framed, 0, 0, IVF_NANOSECONDS, 1);
            framed[8..12].copy_from_slice(self.fourcc());
        }
        // FFmpeg reads the 64 bits back as a signed time.
        ivf::write_ivf_frame(&mut framed, pts as u64, &data);
        out.write_all(&framed)
    }

    /// The codec's IVF fourcc: FFmpeg's ivf demuxer knows VP9's, AV1's and
    /// H.264's; H.265's decoder is named on its command line
    /// ([`Self::forced_decoder`]).
    fn fourcc(self) -> &'static [u8; 4] {
        match self {
            Self::H264 => b"H264",
            Self::H265 => b"HEVC",
            Self::Vp9 => b"VP90",
            Self::Av1 => b"AV01",
        }
    }

    /// The decoder FFmpeg is told to use, for a codec whose IVF fourcc it
    /// does not know (FFmpeg 5.1's ivf demuxer reads no H.265 tag).
    fn forced_decoder(self) -> Option<&'static str> {
        match self {
            Self::H265 => Some("hevc"),
            _ => None,
        }
    }

    /// Frames FFmpeg's decoder of this stream holds back for reordering
    /// (B-frames), as the parameters of `keyframe`, a packet a decoder
    /// starts at, declare them: H.264's `max_num_reorder_frames`, H.265's
    /// `sps_max_num_reorder_pics`, read by `ffprobe` as the stream's
    /// `has_b_frames` (FFmpeg's own parser). 0 for VP9 and AV1, whose
    /// decoders hold none back, for an H.264 stream that declares nothing
    /// (its decoder learns its delay as it goes), and when `ffprobe`
    /// fails or takes longer than [`REORDER_PROBE_WAIT`].
    fn frames_held_back(self, keyframe: &[u8]) -> u64 {
        let format = match self {
            Self::H264 => "h264",
            Self::H265 => "hevc",
            Self::Vp9 | Self::Av1 => return 0,
        };
        let Ok(mut child) = Command::new("ffprobe")
            .args(["-v", "error", "-f", format, "-i", "pipe:0"])
            .args(["-select_streams", "v:0"])
            .args(["-show_entries", "stream=has_b_frames", "-of", "csv=p=0"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
        else {
            return 0;
        };
        let stdin = child.stdin.take();
        let deadline = std::time::Instant::now() + REORDER_PROBE_WAIT;
        let ended = std::thread::scope(|scope| {
            // Written on a thread: ffprobe may stop reading once it knows
            // the stream, and is killed if it takes too long, which ends
            // the write.
            scope.spawn(move || {
                if let Some(mut stdin) = stdin {
                    let _ = stdin.write_all(keyframe);
                }
            });
            loop {
                match child.try_wait() {
                    Ok(Some(status)) => break status.success(),
                    Ok(None) if std::time::Instant::now() < deadline => {
                        std::thread::sleep(std::time::Duration::from_millis(2));
                    }
                    _ => {
                        kill(&mut child);
                        break false;
                    }
                }
            }
        });
        let mut out = String::new();
        if !ended
            || child
                .stdout
                .take()
                .is_none_or(|mut o| o.read_to_string(&mut out).is_err())
        {
            return 0;
        }
        out.trim()
            .parse::<u64>()
            .map_or(0, |n| n.min(MAX_FRAMES_HELD_BACK))
    }

    /// True when the packet is a keyframe a decoder can start at
    /// ([`Self::keyframe`]).
    #[cfg(test)]
    fn starts_stream(self, data: &[u8]) -> bool {
        self.keyframe(data) == Keyframe::Starts
    }

    /// Whether the packet (Annex B NAL units, each after a `00 00 01`
    /// start code) is a keyframe a decoder can start at: a random-access
    /// picture with the sequence parameter set it needs, as the format
    /// requires every keyframe to carry. The unit's type is the low five
    /// bits of H.264's first header byte (7: SPS, 5: IDR slice; ITU-T
    /// H.264 7.3.1) and bits 1-6 of H.265's (33: SPS, 16-23: IRAP; ITU-T
    /// H.265 7.3.1.2). A delta frame that repeats the SPS is no start: the
    /// decoder would drop it, and the frames after it would take the
    /// wrong packets' stamps. An AV1 packet starts one when it holds a
    /// sequence header OBU (type 1) and its first frame header (in an OBU
    /// of type 3 or 6) is a shown key frame: `show_existing_frame` 0 and
    /// `frame_type` 0 in its first three bits (AV1 5.9.2), or any frame
    /// of a sequence of still pictures (`reduced_still_picture_header`,
    /// the fifth bit of the sequence header; AV1 5.5.1). A VP9 packet starts
    /// one when its (first) frame is a key frame ([`vp9_key_frame`]). A
    /// random-access picture (an AV1 key frame) without its sequence
    /// parameter set (sequence header) is told apart: an encoder that sent
    /// them once, before the recording began.
    fn keyframe(self, data: &[u8]) -> Keyframe {
        let of = |random_access: bool, parameters: bool| match (random_access, parameters) {
            (false, _) => Keyframe::No,
            (true, false) => Keyframe::WithoutParameters,
            (true, true) => Keyframe::Starts,
        };
        if self == Self::Vp9 {
            return of(vp9_key_frame(data).is_some(), true);
        }
        if self == Self::Av1 {
            let (mut sequence, mut still) = (false, false);
            for (kind, payload) in av1_obus(data) {
                match kind {
                    1 => {
                        sequence = true;
                        still = payload.first().is_some_and(|b| b & 0x08 != 0);
                    }
                    3 | 6 => {
                        let key = still || payload.first().is_some_and(|b| b & 0xe0 == 0);
                        return of(key, sequence);
                    }
                    _ => {}
                }
            }
            return Keyframe::No;
        }
        let types = nal_units(data).filter_map(|u| u.first().map(|&h| self.nal_type(h)));
        let (mut sps, mut random_access) = (false, false);
        for t in types {
            match (self, t) {
                (Self::H264, 7) | (Self::H265, 33) => sps = true,
                (Self::H264, 5) | (Self::H265, 16..=23) => random_access = true,
                _ => {}
            }
        }
        of(random_access, sps)
    }

    /// What a keyframe must carry to start a stream
    /// ([`Keyframe::WithoutParameters`]).
    fn parameters_name(self) -> &'static str {
        match self {
            Self::Av1 => "sequence header",
            _ => "sequence parameter set",
        }
    }

    /// False when the packet shows no frame, so none is owed for it: a
    /// VP9 packet whose every frame (of a superframe, VP9 Annex B) is
    /// invisible (`show_frame` 0 and no `show_existing_frame`, VP9 6.2), as
    /// libvpx's encoder gives its alternate reference frames when no muxer
    /// merges them; an AV1 one whose frame headers (OBU type 3 or 6) all
    /// have `show_existing_frame` and `show_frame` 0 (AV1 5.9.2); an
    /// H.264 or H.265 one with NAL units but no picture's (H.264 types
    /// 1-5, H.265 0-31): parameter sets or SEI alone. A packet not read
    /// (empty, or not of this form) is taken to show one.
    fn shows_frame(self, data: &[u8]) -> bool {
        match self {
            Self::H264 | Self::H265 => {
                let mut units = nal_units(data).filter_map(|u| u.first()).peekable();
                units.peek().is_none() || units.any(|&h| self.is_picture(h))
            }
            Self::Vp9 => vp9_frames(data).any(vp9_shows_frame),
            Self::Av1 => {
                let mut headers = av1_obus(data)
                    .filter(|(kind, _)| matches!(kind, 3 | 6))
                    .map(|(_, payload)| payload.first().copied())
                    .peekable();
                // show_existing_frame (bit 7), show_frame (bit 4).
                headers.peek().is_none() || headers.any(|b| b.is_none_or(|b| b & 0x90 != 0))
            }
        }
    }

    /// True for an H.264 or H.265 packet of parameter sets (H.264's SPS
    /// and PPS, types 7 and 8; H.265's VPS, SPS and PPS, 32-34) and no
    /// picture: an encoder that sends them in a message of their own,
    /// before the keyframe they belong to.
    fn parameter_sets_alone(self, data: &[u8]) -> bool {
        if !matches!(self, Self::H264 | Self::H265) {
            return false;
        }
        let mut sets = false;
        for u in nal_units(data) {
            let Some(&h) = u.first() else { continue };
            if self.is_picture(h) {
                return false;
            }
            sets |= self.is_parameter_set(h);
        }
        sets
    }

    /// True for an H.264 or H.265 NAL unit (by its first header byte) of a
    /// picture: H.264 types 1-5, H.265 0-31 (VCL units).
    fn is_picture(self, header: u8) -> bool {
        match (self, self.nal_type(header)) {
            (Self::H264, t) => (1..=5).contains(&t),
            (_, t) => t < 32,
        }
    }

    /// True for an H.264 or H.265 NAL unit (by its first header byte) of a
    /// parameter set: H.264's SPS and PPS (7, 8), H.265's VPS, SPS and PPS
    /// (32-34).
    fn is_parameter_set(self, header: u8) -> bool {
        matches!(
            (self, self.nal_type(header)),
            (Self::H264, 7 | 8) | (Self::H265, 32..=34)
        )
    }

    /// A NAL unit's type from its first header byte: its low five bits in
    /// H.264 (ITU-T H.264 7.3.1), bits 1-6 in H.265 (ITU-T H.265 7.3.1.2).
    fn nal_type(self, header: u8) -> u8 {
        match self {
            Self::H264 => header & 0x1f,
            _ => (header >> 1) & 0x3f,
        }
    }

    /// The stream parameters a keyframe carries: H.264's sequence
    /// parameter sets (NAL type 7), H.265's video and sequence ones (32,
    /// 33), AV1's sequence header OBUs, VP9's key frame format and size.
    /// A keyframe whose parameters differ from its stream's begins a new
    /// stream (a camera restarted at another size), decoded by a new
    /// FFmpeg process: one process would scale every later frame to the
    /// first frame's size.
    fn parameters(self, data: &[u8]) -> Vec<u8> {
        match self {
            // Each set once: a keyframe joined by the sets sent before it
            // ([`HeldParameterSets`]) may carry them twice.
            Self::H264 | Self::H265 => nal_units(data)
                .filter(|u| {
                    u.first().is_some_and(|&h| {
                        matches!(
                            (self, self.nal_type(h)),
                            (Self::H264, 7) | (Self::H265, 32 | 33)
                        )
                    })
                })
                .collect::<BTreeSet<&[u8]>>()
                .into_iter()
                .flatten()
                .copied()
                .collect(),
            Self::Av1 => av1_obus(data)
                .filter(|(kind, _)| *kind == 1)
                .flat_map(|(_, payload)| payload)
                .copied()
                .collect(),
            Self::Vp9 => vp9_key_frame(data)
                .into_iter()
                .flatten()
                .flat_map(u32::to_le_bytes)
                .collect(),
        }
    }
}

/// One message of a video type, or a compressed image carrying video: its
/// packet bytes, format and stamp (0 when it carries none).
fn packet<'a>(topic: &TopicMessages, m: &'a TopicMessage) -> Result<(Cow<'a, [u8]>, String, i64)> {
    let bad = |e: String| topic.message_error(m.index, e);
    if m.message_type == ROS_COMPRESSED_VIDEO_TYPE {
        let v: CompressedVideo<'_> = from_cdr(&m.data).map_err(bad)?;
        return Ok((Cow::Borrowed(v.data), v.format, v.timestamp.nanos()));
    }
    if m.message_type == H264_PACKET_TYPE {
        let v: H264Packet<'_> = from_cdr(&m.data).map_err(bad)?;
        let format = Codec::H264.name().to_string();
        return Ok((Cow::Borrowed(v.data), format, v.header.stamp.nanos()));
    }
    if m.message_type == FFMPEG_PACKET_TYPE {
        let v: FfmpegPacket<'_> = from_cdr(&m.data).map_err(bad)?;
        let format = Codec::of_encoding(&v.encoding);
        return Ok((Cow::Borrowed(v.data), format, v.header.stamp.nanos()));
    }
    if m.message_type == COMPRESSED_IMAGE_TYPE {
        let v: CompressedImage<'_> = from_cdr(&m.data).map_err(bad)?;
        let format = v.format.trim().to_string();
        return Ok((Cow::Borrowed(v.data), format, v.header.stamp.nanos()));
    }
    if m.message_type == FOXGLOVE_COMPRESSED_IMAGE_TYPE {
        let v: foxglove::messages::CompressedImage = foxglove_message(topic, m)?;
        let (data, format) = (Vec::from(v.data), v.format.trim().to_string());
        return Ok((Cow::Owned(data), format, foxglove_stamp(v.timestamp)));
    }
    let v: foxglove::messages::CompressedVideo = foxglove_message(topic, m)?;
    Ok((
        Cow::Owned(Vec::from(v.data)),
        v.format,
        foxglove_stamp(v.timestamp),
    ))
}

/// The stamp and place of a packet written to the decoder, ordered by
/// the decoder it went to, then by stamp, then by place (the field order).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Stamp {
    /// The decoder (0, then 1 after the stream's parameters changed, ...).
    segment: u32,
    stamp_ns: i64,
    index: u64,
    log_time_ns: u64,
    /// The time written with the packet: its stamp less the stamp of its
    /// decoder's first packet (small, so FFmpeg's floating point keeps it
    /// to the nanosecond).
    pts: i64,
    /// True when the packet shows no frame ([`Codec::shows_frame`]).
    hidden: bool,
}

/// Stamps of the packets written that have no frame yet, earliest first.
#[derive(Default)]
struct PendingStamps {
    stamps: BTreeSet<Stamp>,
    /// The latest packets that show no frame (an invisible VP9 frame, an
    /// AV1 temporal unit of hidden frames, H.264 or H.265 SEI alone):
    /// no frame is waited for, nor counted lost. A frame whose time names
    /// one takes its stamp all the same, should FFmpeg show it.
    hidden: std::collections::VecDeque<Stamp>,
    /// The latest stamp a frame took by its time, and its decoder: the
    /// pending stamps before it are passed, their frames presumably lost
    /// (frames come in display order). They are kept, for a stream whose
    /// stamps are not its display order, which may still give them, until
    /// [`MAX_REORDERED`] says.
    shown: Option<(u32, i64)>,
    /// The latest written packet whose frame came, and its decoder.
    latest: Option<(u32, u64)>,
    /// The last frame's time, and its decoder. FFmpeg keeps its frames'
    /// times from going back: a time that would is raised to the last,
    /// so a time that does not rise names no packet surely (it may be
    /// another packet's of the same stamp).
    last_time: Option<(u32, i64)>,
}

/// Packets a decoder may show after a packet written later (H.264's and
/// H.265's largest picture buffer): a packet written more before one whose
/// frame came gave none.
const MAX_REORDERED: u64 = 16;

/// A decoded frame's stamp, and what it told of the packets before it.
#[derive(Debug)]
struct Taken {
    stamp: Stamp,
    /// Places of packets given up as lost (a damaged packet gives no
    /// frame): written [`MAX_REORDERED`] packets or more before one whose
    /// frame came.
    lost: Vec<u64>,
    /// Pending stamps this frame passed (shown before it, no frame yet).
    passed: u64,
    /// False when the frame's time named no pending packet, so it took
    /// the earliest written packet's stamp, which after a lost frame may
    /// be that packet's.
    own: bool,
}

impl PendingStamps {
    fn add(&mut self, stamp: Stamp) {
        if !stamp.hidden {
            self.stamps.insert(stamp);
            return;
        }
        if self.hidden.len() as u64 >= MAX_REORDERED {
            self.hidden.pop_front();
        }
        self.hidden.push_back(stamp);
    }

    fn extend(&mut self, stamps: impl IntoIterator<Item = Stamp>) {
        for stamp in stamps {
            self.add(stamp);
        }
    }

    /// The stamp of the frame just decoded, whose time FFmpeg gave as
    /// `time`: that of its own packet in the current decoder (one taken to
    /// show no frame too); without a time, one that does not rise, or one
    /// no packet has (a stream whose stamps are not its display order),
    /// that of the earliest written packet (see the module's
    /// documentation). The error when every packet written (`written`)
    /// already has its frame.
    fn take(&mut self, time: Option<i64>, written: u64) -> std::result::Result<Taken, String> {
        // The decoder giving frames now: the earliest one with a packet
        // (one that shows no frame too, should FFmpeg show one of it).
        let first = (self.stamps.first().into_iter())
            .chain(self.hidden.front())
            .min_by_key(|s| s.segment)
            .cloned();
        let Some(first) = first else {
            return Err(format!(
                "FFmpeg gave more frames than the {written} packets written to it"
            ));
        };
        let segment = first.segment;
        // Every packet of a decoder has its time from the same stamp.
        let base_ns = first.stamp_ns.wrapping_sub(first.pts);
        let last = self.last_time.filter(|(seg, _)| *seg == segment);
        if let Some(t) = time {
            self.last_time = Some((segment, t));
        }
        let rising = time.filter(|t| last.is_none_or(|(_, at)| *t > at));
        let own = rising.and_then(|t| {
            let stamp_ns = base_ns.wrapping_add(t);
            let from = Stamp {
                segment,
                stamp_ns,
                index: 0,
                log_time_ns: 0,
                pts: i64::MIN,
                hidden: false,
            };
            let pending = (self.stamps.range(from..).next())
                .filter(|s| s.segment == segment && s.stamp_ns == stamp_ns)
                .cloned();
            // Else a packet taken to show no frame, which showed one.
            pending.or_else(|| {
                let at = (self.hidden.iter())
                    .rposition(|h| h.segment == segment && h.stamp_ns == stamp_ns)?;
                self.hidden.remove(at)
            })
        });
        let own_found = own.is_some();
        let passed_before = self.passed(segment);
        let stamp = match own {
            Some(own) => {
                if self
                    .shown
                    .is_none_or(|(seg, at)| seg != segment || at < own.stamp_ns)
                {
                    self.shown = Some((segment, own.stamp_ns));
                }
                own
            }
            // The earliest written packet: without B-frames, the frames
            // come in the packets' order, whatever their stamps. With none
            // waiting, the earliest that shows no frame (which showed one).
            None => match (self.stamps.iter())
                .take_while(|s| s.segment == segment)
                .min_by_key(|s| s.index)
                .cloned()
            {
                Some(earliest) => earliest,
                None => self.hidden.pop_front().unwrap_or(first),
            },
        };
        self.stamps.remove(&stamp);
        let passed = self.passed(segment);
        // A packet written more than a decoder may reorder before one whose
        // frame came gave none.
        let latest = match self.latest {
            Some((seg, at)) if seg == segment => at.max(stamp.index),
            _ => stamp.index,
        };
        self.latest = Some((segment, latest));
        let mut lost = Vec::new();
        self.stamps.retain(|s| {
            let overdue = s.segment == segment && s.index.saturating_add(MAX_REORDERED) < latest;
            if overdue {
                lost.push(s.index);
            }
            !overdue
        });
        Ok(Taken {
            stamp,
            lost,
            passed: passed.saturating_sub(passed_before) as u64,
            own: own_found,
        })
    }

    /// Pending stamps of decoder `segment` before the latest shown.
    fn passed(&self, segment: u32) -> usize {
        match self.shown {
            Some((seg, at)) if seg == segment => self
                .stamps
                .iter()
                .take_while(|s| s.segment == segment && s.stamp_ns < at)
                .count(),
            _ => 0,
        }
    }

    /// Pending stamps whose frames may still come: those not passed.
    fn due(&self) -> u64 {
        let segment = self.stamps.first().map_or(0, |s| s.segment);
        (self.stamps.len() - self.passed(segment)) as u64
    }

    /// Forget the stamps of decoders before `segment`, whose frames never
    /// came (FFmpeg lost them); their places.
    fn drop_before(&mut self, segment: u32) -> Vec<u64> {
        self.hidden.retain(|s| s.segment >= segment);
        let mut lost = Vec::new();
        while self.stamps.first().is_some_and(|s| s.segment < segment) {
            lost.extend(self.stamps.pop_first().map(|s| s.index));
        }
        lost
    }

    /// Forget every stamp, the stream having ended; their places.
    fn drain(&mut self) -> Vec<u64> {
        self.hidden.clear();
        std::mem::take(&mut self.stamps)
            .into_iter()
            .map(|s| s.index)
            .collect()
    }
}

/// The packets written to a stream's decoders, for the bag reader's
/// feeder and the live decoder: the current decoder's number, how many it
/// took, and the stamp of its first, which its packets' times are from.
#[derive(Default)]
struct DecoderClock {
    segment: u32,
    in_segment: u64,
    base_ns: i64,
}

impl DecoderClock {
    /// The stamp of the next packet written to the current decoder, with
    /// its time, and whether it is the decoder's first; `hidden` when it
    /// shows no frame ([`Codec::shows_frame`]).
    fn stamp(
        &mut self,
        stamp_ns: i64,
        index: u64,
        log_time_ns: u64,
        hidden: bool,
    ) -> (Stamp, bool) {
        let first = self.in_segment == 0;
        if first {
            self.base_ns = stamp_ns;
        }
        self.in_segment += 1;
        let stamp = Stamp {
            segment: self.segment,
            stamp_ns,
            index,
            log_time_ns,
            pts: stamp_ns.wrapping_sub(self.base_ns),
            hidden,
        };
        (stamp, first)
    }

    /// The packets from now on go to a new decoder.
    fn next_decoder(&mut self) {
        self.segment = self.segment.saturating_add(1);
        self.in_segment = 0;
    }
}

/// Whether a packet is a keyframe ([`Codec::keyframe`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Keyframe {
    /// Not a keyframe.
    No,
    /// A random-access picture without the parameters it needs (H.264's
    /// and H.265's sequence parameter set, AV1's sequence header).
    WithoutParameters,
    /// A keyframe a decoder can start at.
    Starts,
}

/// What a packet is to the stream it joins.
#[derive(Debug, PartialEq, Eq)]
enum PacketRole {
    /// Before the stream's first keyframe: no decoder can read it.
    BeforeKeyframe,
    /// Before the stream's first keyframe, a random-access picture
    /// without the parameters it needs ([`Keyframe::WithoutParameters`]).
    KeyframeWithoutParameters,
    /// A packet of the stream as it is.
    InStream,
    /// A keyframe whose stream parameters differ from the stream's so far.
    NewParameters,
}

/// The stream parameters of a stream's last keyframe
/// ([`Codec::parameters`]); `None` before its first. One for the bag
/// reader's feeder and the live decoder.
#[derive(Default)]
struct StreamParameters(Option<Vec<u8>>);

impl StreamParameters {
    /// The role of the stream's next packet, `data`; a keyframe's
    /// parameters are kept.
    fn role(&mut self, codec: Codec, data: &[u8]) -> PacketRole {
        let keyframe = codec.keyframe(data);
        if keyframe != Keyframe::Starts {
            return match (&self.0, keyframe) {
                (Some(_), _) => PacketRole::InStream,
                (None, Keyframe::WithoutParameters) => PacketRole::KeyframeWithoutParameters,
                (None, _) => PacketRole::BeforeKeyframe,
            };
        }
        let new = codec.parameters(data);
        let changed = self.0.as_ref().is_some_and(|old| *old != new);
        self.0 = Some(new);
        match changed {
            true => PacketRole::NewParameters,
            false => PacketRole::InStream,
        }
    }
}

/// H.264 or H.265 parameter sets that came in a message of their own
/// ([`Codec::parameter_sets_alone`]), held to be written with the next
/// message, so a keyframe whose parameter sets came just before it starts
/// a stream as one that carries them does. One for the bag reader's feeder
/// and the live decoder.
#[derive(Default)]
struct HeldParameterSets {
    sets: Vec<u8>,
    /// The messages they came in.
    messages: u64,
}

/// Most bytes of parameter sets held for the next message: past it, a
/// hostile topic of parameter sets alone keeps only its latest.
const MAX_HELD_PARAMETER_SETS: usize = 1 << 20;

impl HeldParameterSets {
    /// `data` after the parameter sets held, with the number of messages
    /// they came in; `None` when it is parameter sets alone, now held.
    fn join<'a>(&mut self, codec: Codec, data: Cow<'a, [u8]>) -> Option<(Cow<'a, [u8]>, u64)> {
        if codec.parameter_sets_alone(&data) {
            if self.sets.len().saturating_add(data.len()) > MAX_HELD_PARAMETER_SETS {
                self.sets.clear();
            }
            self.sets.extend_from_slice(&data);
            self.messages += 1;
            return None;
        }
        let messages = std::mem::take(&mut self.messages);
        if self.sets.is_empty() {
            return Some((data, messages));
        }
        let mut joined = std::mem::take(&mut self.sets);
        joined.extend_from_slice(&data);
        Some((Cow::Owned(joined), messages))
    }
}

/// A decoder started by the feeder for a new stream, handed to the reader.
struct Segment {
    child: Child,
    stdout: ChildStdout,
    times: FrameTimes,
    stderr: Option<JoinHandle<Vec<u8>>>,
}

/// What the feeder did, once it ended.
struct Fed {
    /// The topic's messages, handed back (their files' warnings).
    messages: TopicMessages,
    /// Why it stopped before the topic's end.
    error: Option<Error>,
    /// Messages before the first keyframe.
    before: BeforeFirstKeyframe,
    /// Packets written to the decoders, and those of them that show no
    /// frame ([`Codec::shows_frame`]).
    fed: u64,
    hidden: u64,
    /// The keyframes with new stream parameters, and those that began no
    /// new decoder.
    changes: StreamChanges,
}

/// Messages of a topic a warning names: how many, and the places of the
/// first few.
#[derive(Default)]
struct MessagePlaces {
    count: u64,
    first: Vec<u64>,
}

impl MessagePlaces {
    fn add(&mut self, places: impl IntoIterator<Item = u64>) {
        for place in places {
            self.count += 1;
            if self.first.len() < 10 {
                self.first.push(place);
            }
        }
    }

    /// The places, "3, 7", then "… (12 {all})" past the first few.
    fn describe(&self, all: &str) -> String {
        let mut at: Vec<String> = self.first.iter().map(u64::to_string).collect();
        if self.count > at.len() as u64 {
            at.push(format!("… ({} {all})", self.count));
        }
        at.join(", ")
    }
}

/// The messages of a stream before its first keyframe, which no decoder
/// can read (a recording begun mid-stream): how many, with the parameter
/// sets that joined them, and the keyframes among them without their
/// parameters. One for the bag reader's feeder and the live decoder.
#[derive(Default)]
struct BeforeFirstKeyframe {
    skipped: u64,
    without_parameters: MessagePlaces,
}

impl BeforeFirstKeyframe {
    /// Skip message `index` of `role`, with the `joined` messages of
    /// parameter sets before it; false when it is of the stream.
    fn skip(&mut self, role: &PacketRole, index: u64, joined: u64) -> bool {
        match role {
            PacketRole::KeyframeWithoutParameters => self.without_parameters.add([index]),
            PacketRole::BeforeKeyframe => {}
            PacketRole::InStream | PacketRole::NewParameters => return false,
        }
        self.skipped += 1 + joined;
        true
    }

    /// Why keyframes among them started no stream, to follow a warning or
    /// error; empty when none came.
    fn describe_keyframes_without_parameters(&self, codec: Codec) -> String {
        let places = &self.without_parameters;
        if places.count == 0 {
            return String::new();
        }
        let one = places.count == 1;
        let how = match codec {
            Codec::H264 | Codec::H265 => {
                " (x264's and x265's `repeat-headers=1`, GStreamer's `h264parse` or `h265parse` with `config-interval=-1`)"
            }
            _ => "",
        };
        format!(
            "; message{} {} {} keyframe{} without {} {}: the encoder sent it only at its start, before the first of these messages, so have it repeat it at every keyframe{how}",
            if one { "" } else { "s" },
            places.describe("in all"),
            if one { "is a" } else { "are" },
            if one { "" } else { "s" },
            if one { "its" } else { "their" },
            codec.parameters_name(),
        )
    }
}

/// Decoders a video stream may start after its first, one per change of
/// its parameters ([`Codec::parameters`]), before any is earned by the
/// packets written ([`PACKETS_PER_RESTART`]): two in unit tests, so the
/// limit is exercised.
const MAX_STREAM_RESTARTS: u64 = if cfg!(test) { 2 } else { 64 };

/// Packets written that earn a stream one more new decoder past
/// [`MAX_STREAM_RESTARTS`]. A new FFmpeg process costs about 80 ms, the
/// decoding of eight 1080p frames or hundreds of tiny ones: a hostile
/// topic whose every keyframe changes its parameters starts a process per
/// 32 packets, not one each, while a camera restarted at another size any
/// number of times, no more often than that on average, keeps every
/// frame's size.
const PACKETS_PER_RESTART: u64 = if cfg!(test) { 8 } else { 32 };

/// The changes of a stream's parameters, each given a new decoder while
/// the budget allows ([`MAX_STREAM_RESTARTS`], [`PACKETS_PER_RESTART`]);
/// the others are decoded by the decoder before, which scales their
/// frames to its size. One for the bag reader's feeder and the live
/// decoder.
#[derive(Default)]
struct StreamChanges {
    /// The messages of every change, and of those scaled.
    changed: MessagePlaces,
    scaled: MessagePlaces,
    restarts: u64,
}

impl StreamChanges {
    /// A change at message `index`, after `written` packets: true when it
    /// may start a new decoder.
    fn restart(&mut self, index: u64, written: u64) -> bool {
        self.changed.add([index]);
        let allowed = MAX_STREAM_RESTARTS.saturating_add(written / PACKETS_PER_RESTART);
        let restart = self.restarts < allowed;
        match restart {
            true => self.restarts += 1,
            false => self.scaled.add([index]),
        }
        restart
    }
}

/// Where the feeder writes: the decoder's input, and the channels to the
/// reader for each packet's stamp and each new decoder.
struct FeedTo {
    codec: Codec,
    path: PathBuf,
    stdin: ChildStdin,
    stamps: mpsc::Sender<Stamp>,
    segments: mpsc::Sender<Segment>,
}

/// Write the topic's packets, from `first` on, to the decoder's input, the
/// stamp of each sent before it; the input is closed at the end, so the
/// decoder gives its last frames and exits. A keyframe with new stream
/// parameters ([`Codec::parameters`]) goes to a new decoder, handed to the
/// reader before the old one's input is closed.
fn feed(mut messages: TopicMessages, first: TopicMessage, to: FeedTo) -> Fed {
    let FeedTo {
        codec,
        path,
        mut stdin,
        stamps,
        segments,
    } = to;
    let (mut before, mut fed, mut hidden_packets) = (BeforeFirstKeyframe::default(), 0, 0);
    let mut clock = DecoderClock::default();
    let mut parameters = StreamParameters::default();
    let mut held = HeldParameterSets::default();
    let mut changes = StreamChanges::default();
    let mut next = Some(first);
    let error = loop {
        // Ctrl-C ends the feed, then the decoder, then the reader's wait.
        if let Err(e) = crate::interrupt::check() {
            break Some(e);
        }
        let m = match next.take() {
            Some(m) => m,
            None => match messages.next() {
                Ok(Some(m)) => m,
                Ok(None) => break None,
                Err(e) => break Some(e),
            },
        };
        let image = [COMPRESSED_IMAGE_TYPE, FOXGLOVE_COMPRESSED_IMAGE_TYPE];
        if !is_video_type(&m.message_type) && !image.contains(&m.message_type.as_str()) {
            break Some(messages.message_error(
                m.index,
                format!(
                    "a {} message on a video topic: a topic's frames are one stream",
                    m.message_type
                ),
            ));
        }
        let (data, format, stamp_ns) = match packet(&messages, &m) {
            Ok(p) => p,
            Err(e) => break Some(e),
        };
        if Codec::of(&format) != Some(codec) {
            break Some(messages.message_error(
                m.index,
                format!(
                    "format {format:?} after {:?} ones: a topic's frames are one stream",
                    codec.name()
                ),
            ));
        }
        // Parameter sets alone join the next message, and are skipped
        // with it.
        let Some((data, joined)) = held.join(codec, data) else {
            continue;
        };
        let role = parameters.role(codec, &data);
        if before.skip(&role, m.index, joined) {
            continue;
        }
        if role == PacketRole::NewParameters && changes.restart(m.index, fed) {
            let Decoder {
                child,
                stdin: next_stdin,
                stdout,
                times,
                stderr,
            } = match spawn_decoder(codec, None, &path) {
                Ok(d) => d,
                Err(e) => break Some(e),
            };
            // The reader takes the new decoder before the old one
            // ends, so it finds it when the old one's frames end.
            let next = Segment {
                child,
                stdout,
                times,
                stderr,
            };
            if let Err(mpsc::SendError(mut next)) = segments.send(next) {
                kill(&mut next.child);
                break None;
            }
            // The old decoder's input closes: it gives its last
            // frames and exits.
            stdin = next_stdin;
            clock.next_decoder();
        }
        let stamp_ns = stamp_or_log_time(stamp_ns, m.log_time);
        let hidden = !codec.shows_frame(&data);
        let (stamp, first) = clock.stamp(stamp_ns, m.index, m.log_time, hidden);
        let pts = stamp.pts;
        // A decoder that stopped reading has exited or was stopped: the
        // reader reports why.
        // The stamp goes first: the frame cannot come out before it.
        if stamps.send(stamp).is_err() || codec.write_packet(&mut stdin, &data, first, pts).is_err()
        {
            break None;
        }
        fed += 1;
        // A packet that shows no frame is owed none.
        hidden_packets += u64::from(hidden);
    };
    drop(stdin);
    Fed {
        messages,
        error,
        before,
        fed,
        hidden: hidden_packets,
        changes,
    }
}

/// One picture FFmpeg decoded (PAM), its size checked before it is held;
/// errors made by `error`.
fn read_picture(stdout: &mut impl BufRead, error: impl Fn(String) -> Error) -> Result<RgbImage> {
    let bad = |e: String| error(format!("a frame FFmpeg decoded could not be read: {e}"));
    let decoder = PnmDecoder::new(stdout).map_err(|e| bad(e.to_string()))?;
    let (width, height) = decoder.dimensions();
    if u64::from(width) * u64::from(height) > MAX_IMAGE_PIXELS {
        return Err(error(format!(
            "its video is {width}x{height}, more than the {MAX_IMAGE_PIXELS} pixels a frame may have"
        )));
    }
    if decoder.color_type() != ColorType::Rgb8 {
        return Err(bad(format!("{:?}, not 8-bit RGB", decoder.color_type())));
    }
    let mut buf = vec![0u8; (u64::from(width) * u64::from(height) * 3) as usize];
    decoder
        .read_image(&mut buf)
        .map_err(|e| bad(e.to_string()))?;
    rgb_image(width as usize, height as usize, buf)
}

/// How a decoder's stream ended, for bags and live alike: no keyframe
/// among the messages skipped (`before`, which names those without their
/// parameters), so nothing was `written`; no frame of the packets
/// written; or FFmpeg's failure (`status`, its `last` words) after
/// `frames` frames.
fn stream_end(
    codec: Codec,
    before: &BeforeFirstKeyframe,
    written: u64,
    frames: u64,
    status: ExitStatus,
    last: &str,
) -> std::result::Result<(), String> {
    let name = codec.name();
    if written == 0 {
        let keyframe = match codec {
            Codec::Vp9 => "a key frame".to_string(),
            Codec::Av1 => format!("a key frame with its {}", codec.parameters_name()),
            _ => format!(
                "a random-access picture with its {}",
                codec.parameters_name()
            ),
        };
        return Err(format!(
            "none of its {} messages is a keyframe of its {name} stream ({keyframe}), so no frame can be decoded{}",
            before.skipped,
            before.describe_keyframes_without_parameters(codec)
        ));
    }
    if frames == 0 {
        return Err(format!(
            "FFmpeg decoded no frame of its {written} {name} packets: {last}"
        ));
    }
    decoder_ended_well(codec, status, last)
}

/// An FFmpeg decoder's end: the error naming its exit `status` and its
/// `last` words when it failed.
fn decoder_ended_well(
    codec: Codec,
    status: ExitStatus,
    last: &str,
) -> std::result::Result<(), String> {
    match status.success() {
        true => Ok(()),
        false => Err(format!(
            "FFmpeg could not decode its {} stream ({status}): {last}",
            codec.name()
        )),
    }
}

/// Stop a decoder and reap it.
fn kill(child: &mut Child) {
    let _ = child.kill();
    let _ = child.wait();
}

/// A decoder process with its input, its output, and its error output
/// read on a thread: each frame's time ([`frame_times`]) and the tail of
/// the rest.
struct Decoder {
    child: Child,
    stdin: ChildStdin,
    stdout: ChildStdout,
    times: FrameTimes,
    stderr: Option<JoinHandle<Vec<u8>>>,
}

/// An FFmpeg process decoding `codec`'s packets (IVF frames:
/// [`Codec::write_packet`]) from its input to PAM pictures on its output,
/// one thread; `live` starts it on the first packet instead of after
/// probing megabytes of the stream. Each frame's time goes first to its
/// error output, as a `framecrc` line of a second output (`-copyts`
/// keeps the packets' own times, `-enc_time_base` the demuxer's nanoseconds):
/// written before the picture, it is there when the picture is read, and
/// the thread reading it never waits for the pictures.
fn spawn_decoder(
    codec: Codec,
    live: Option<mpsc::Sender<LiveEvent>>,
    path: &std::path::Path,
) -> Result<Decoder> {
    let probe: &[&str] = match live {
        Some(_) => &["-probesize", "32", "-analyzeduration", "0"],
        None => &[],
    };
    let forced: &[&str] = match codec.forced_decoder() {
        Some(decoder) => &["-c:v", decoder],
        None => &[],
    };
    let (every_frame, each_output) = passthrough_options();
    let each_frame = ["-map", "0:v:0", "-enc_time_base", demuxer_time_base()];
    let mut child = Command::new("ffmpeg")
        .args(["-nostdin", "-hide_banner", "-loglevel", "error", "-copyts"])
        .args(every_frame)
        .args(["-threads", "1"])
        .args(probe)
        .args(forced)
        .args(["-f", "ivf", "-i", "pipe:0"])
        .args(each_frame)
        .args(each_output)
        .args(["-c:v", "wrapped_avframe", "-f", "framecrc", "pipe:2"])
        .args(each_frame)
        .args(each_output)
        .args(["-pix_fmt", "rgb24", "-c:v", "pam", "-f", "image2pipe"])
        .arg("pipe:1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| spawn_error(path, e))?;
    let (times, stderr) = frame_times(&mut child, live);
    match (child.stdin.take(), child.stdout.take()) {
        (Some(stdin), Some(stdout)) => Ok(Decoder {
            child,
            stdin,
            stdout,
            times,
            stderr,
        }),
        _ => {
            kill(&mut child);
            Err(Error::Invalid("ffmpeg started without its pipes".into()))
        }
    }
}

/// A decoder's error output read on a thread: the time of each frame it
/// decoded (the presentation time column of its `framecrc` lines, `0,
/// dts, pts, duration, size, crc`, in nanoseconds), sent in order as they
/// come, and the tail of its other lines (its messages), for
/// [`last_words`], each also told to a live stream's `errors` (FFmpeg
/// writes only errors). A line longer than FFmpeg writes is cut, not held.
fn frame_times(
    child: &mut Child,
    errors: Option<mpsc::Sender<LiveEvent>>,
) -> (FrameTimes, Option<JoinHandle<Vec<u8>>>) {
    let (send, times) = mpsc::channel();
    let tail = child.stderr.take().map(|err| {
        std::thread::spawn(move || {
            let mut err = BufReader::new(err);
            let (mut tail, mut line) = (Vec::new(), Vec::new());
            loop {
                line.clear();
                match (&mut err)
                    .take(MAX_STDERR_LINE)
                    .read_until(b'\n', &mut line)
                {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {}
                }
                if line.starts_with(b"#") {
                    continue;
                }
                if let Some(time) = framecrc_time(&line) {
                    // A reader that ended takes no more times.
                    let _ = send.send(time);
                    continue;
                }
                if let Some(errors) = &errors {
                    // A live stream that ended takes no more.
                    let _ = errors.send(LiveEvent::Error);
                }
                keep_tail(&mut tail, &line);
            }
            tail
        })
    });
    (FrameTimes::new(times), tail)
}

/// The longest line of FFmpeg's error output read as one.
const MAX_STDERR_LINE: u64 = 4096;

/// The presentation time of a `framecrc` line (`0, dts, pts, duration,
/// size, 0xcrc`), or `None` for another line. From FFmpeg 7 the muxer
/// writes on a thread of its own, and a message's prefixes (`[h264 @
/// 0x…] `, each written apart from its text) may come just before the
/// line: they are passed over.
fn framecrc_time(line: &[u8]) -> Option<i64> {
    let mut line = std::str::from_utf8(line).ok()?.trim();
    while let Some(rest) = line.strip_prefix('[') {
        let (context, rest) = rest.split_once("] ")?;
        if !context.contains(" @ ") {
            return None;
        }
        line = rest.trim_start();
    }
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    match fields.as_slice() {
        ["0", _, pts, _, _, crc] if crc.starts_with("0x") => pts.parse().ok(),
        _ => None,
    }
}

/// The times of a decoder's frames, in order ([`frame_times`]).
struct FrameTimes {
    times: mpsc::Receiver<i64>,
    /// False once a time failed to come: the later ones could belong to
    /// other frames, so none is used.
    in_step: bool,
}

impl FrameTimes {
    fn new(times: mpsc::Receiver<i64>) -> Self {
        Self {
            times,
            in_step: true,
        }
    }

    /// The time of the frame just read: FFmpeg wrote it before the
    /// picture, so it comes at once; `None` when it does not (FFmpeg
    /// ended, or an FFmpeg that writes its outputs in another order).
    fn next(&mut self) -> Option<i64> {
        if !self.in_step {
            return None;
        }
        let time = self.times.recv_timeout(FRAME_TIME_WAIT).ok();
        self.in_step = time.is_some();
        time
    }
}

/// How long a frame's time may take after its picture was read: it was
/// written before.
const FRAME_TIME_WAIT: std::time::Duration = std::time::Duration::from_secs(5);

/// The packets of a stream found to give no frame.
#[derive(Default)]
struct LostPackets {
    places: MessagePlaces,
    /// Frames that took the earliest written packet's stamp, their time
    /// naming none: after a lost frame, such a frame may carry an earlier
    /// packet's stamp.
    borrowed: u64,
}

impl LostPackets {
    /// The frame's stamp, its lost packets counted.
    fn count(&mut self, taken: Taken) -> Stamp {
        self.borrowed += u64::from(!taken.own);
        self.places.add(taken.lost);
        taken.stamp
    }
}

/// The frames of a video topic, decoded by an FFmpeg process fed from a
/// thread; the process is killed when this is dropped.
pub(super) struct VideoFrames {
    codec: Codec,
    /// The file the video began in, and the topic, for errors.
    path: PathBuf,
    topic: String,
    /// The index of the topic's message the video began at.
    first: u64,
    child: Child,
    stdout: BufReader<ChildStdout>,
    times: FrameTimes,
    stderr: Option<JoinHandle<Vec<u8>>>,
    stamps: mpsc::Receiver<Stamp>,
    pending: PendingStamps,
    /// Decoders of the streams after this one, and this one's number.
    segments: mpsc::Receiver<Segment>,
    segment: u32,
    /// The packets that gave no frame, as far as told.
    lost: LostPackets,
    feeder: Option<JoinHandle<Fed>>,
    fed: Option<Fed>,
    frames: u64,
    done: bool,
}

impl VideoFrames {
    /// Start decoding the topic at its first message, `first`.
    pub(super) fn start(messages: TopicMessages, first: TopicMessage) -> Result<Self> {
        let (_, format, _) = packet(&messages, &first)?;
        let codec = Codec::read(&format).map_err(|e| messages.message_error(first.index, e))?;
        let path = messages.records.path.clone();
        let topic = messages.topic.clone();
        let first_index = first.index;
        let Decoder {
            mut child,
            stdin,
            stdout,
            times,
            stderr,
        } = spawn_decoder(codec, None, &path)?;
        let (send, stamps) = mpsc::channel();
        let (send_segment, segments) = mpsc::channel();
        let to = FeedTo {
            codec,
            path: path.clone(),
            stdin,
            stamps: send,
            segments: send_segment,
        };
        let feeder = std::thread::Builder::new()
            .name("video-packets".into())
            .spawn(move || feed(messages, first, to));
        let feeder = match feeder {
            Ok(f) => f,
            Err(e) => {
                kill(&mut child);
                return Err(Error::io(&path, e));
            }
        };
        Ok(Self {
            codec,
            path,
            topic,
            first: first_index,
            child,
            stdout: BufReader::with_capacity(1 << 20, stdout),
            times,
            stderr,
            stamps,
            pending: PendingStamps::default(),
            segments,
            segment: 0,
            lost: LostPackets::default(),
            feeder: Some(feeder),
            fed: None,
            frames: 0,
            done: false,
        })
    }

    fn error(&self, message: impl ToString) -> Error {
        bag_error(&self.path, Some(&self.topic), None, message)
    }

    /// The topic's messages, once the video ended.
    pub(super) fn messages(&self) -> Option<&TopicMessages> {
        self.fed.as_ref().map(|f| &f.messages)
    }

    /// What a user should know of the frames decoded, once the video ended.
    pub(super) fn warnings(&self) -> Vec<String> {
        let Some(fed) = &self.fed else {
            return Vec::new();
        };
        let mut warnings = Vec::new();
        let before = &fed.before;
        if before.skipped > 0 {
            warnings.push(format!(
                "{} topic {}: its first {} messages come before the first keyframe of its {} stream (the recording began mid-stream) and cannot be decoded; its frames begin at message {}{}",
                self.path.display(),
                self.topic,
                before.skipped,
                self.codec.name(),
                self.first + before.skipped,
                before.describe_keyframes_without_parameters(self.codec)
            ));
        }
        let changes = &fed.changes;
        if changes.changed.count > 0 {
            let decoded = match changes.scaled.count {
                0 => "each part was decoded on its own, its frames at their own size".to_string(),
                _ => format!(
                    "{} began a new decoder; the frames after the changes at message{} {} (more than one per {PACKETS_PER_RESTART} messages, past the first {MAX_STREAM_RESTARTS} changes) were decoded by the decoder before, scaled to its size",
                    changes.restarts,
                    if changes.scaled.count == 1 { "" } else { "s" },
                    changes.scaled.describe("in all")
                ),
            };
            warnings.push(format!(
                "{} topic {}: its {} stream's parameters change at message{} {} (a keyframe with new ones: a camera restarted, or set to another size); {decoded}",
                self.path.display(),
                self.topic,
                self.codec.name(),
                if changes.changed.count == 1 { "" } else { "s" },
                changes.changed.describe("times")
            ));
        }
        let owed = fed.fed - fed.hidden;
        if self.frames < owed {
            let stamps = match self.lost.borrowed {
                0 => format!(
                    "messages that gave none: {}; every frame carries its own packet's stamp",
                    self.lost.places.describe("in all")
                ),
                _ => format!(
                    "so each frame after a lost one carries the stamp of an earlier packet (at most {} back)",
                    owed - self.frames
                ),
            };
            warnings.push(format!(
                "{} topic {}: FFmpeg gave a frame for {} of its {} packets{} (a damaged packet gives none); {stamps}",
                self.path.display(),
                self.topic,
                self.frames,
                owed,
                if fed.hidden > 0 { " that show one" } else { "" },
            ));
        }
        warnings
    }

    /// The next frame, `None` after the last.
    pub(super) fn next_frame(&mut self) -> Result<Option<BagFrame>> {
        if self.done {
            return Ok(None);
        }
        let mut at_end = self.stdout.fill_buf().map(<[u8]>::is_empty);
        // A decoder's frames ended: the next stream's decoder, if the
        // feeder started one (it does before closing this one's input).
        while let Ok(true) = at_end {
            let Ok(next) = self.segments.recv() else {
                self.done = true;
                self.finish(false)?;
                return Ok(None);
            };
            if let Err(e) = self.next_segment(next) {
                self.done = true;
                self.finish(true)?;
                return Err(e);
            }
            at_end = self.stdout.fill_buf().map(<[u8]>::is_empty);
        }
        let frame = match at_end {
            Err(e) => Err(Error::io(&self.path, e)),
            Ok(_) => self.read_picture(),
        }
        .and_then(|image| {
            // Every packet the frame needed was written, so its stamp was
            // sent, before the frame came out.
            self.pending.extend(self.stamps.try_iter());
            let time = self.times.next();
            let taken = self
                .pending
                .take(time, self.frames)
                .map_err(|e| self.error(e))?;
            let stamp = self.lost.count(taken);
            Ok(BagFrame {
                image,
                stamp_ns: stamp.stamp_ns,
                log_time_ns: stamp.log_time_ns,
                index: stamp.index,
            })
        });
        match frame {
            Ok(frame) => {
                self.frames += 1;
                Ok(Some(frame))
            }
            Err(e) => {
                self.done = true;
                // The decoder's or the feeder's reason comes first.
                self.finish(true)?;
                Err(e)
            }
        }
    }

    /// Go on with the next stream's decoder, once this one gave its last
    /// frame: this one must have ended well, and its packets without a
    /// frame are forgotten (lost), so the next stream's frames take their
    /// own stamps.
    fn next_segment(&mut self, next: Segment) -> Result<()> {
        let status = self.child.wait().map_err(|e| Error::io(&self.path, e));
        let last = last_words(self.stderr.take());
        let Segment {
            child,
            stdout,
            times,
            stderr,
        } = next;
        self.child = child;
        self.stdout = BufReader::with_capacity(1 << 20, stdout);
        self.times = times;
        self.stderr = stderr;
        decoder_ended_well(self.codec, status?, &last).map_err(|e| self.error(e))?;
        self.pending.extend(self.stamps.try_iter());
        self.segment += 1;
        self.lost.places.add(self.pending.drop_before(self.segment));
        Ok(())
    }

    /// One decoded picture.
    fn read_picture(&mut self) -> Result<RgbImage> {
        let (path, topic) = (&self.path, &self.topic);
        read_picture(&mut self.stdout, |e| bag_error(path, Some(topic), None, e))
    }

    /// Wait for the decoder (killed first when `stop`) and the feeder,
    /// and report what stopped them.
    fn finish(&mut self, stop: bool) -> Result<()> {
        // A decoder that failed by itself is named, not the broken frame.
        let failed = stop
            && self
                .child
                .try_wait()
                .ok()
                .flatten()
                .is_some_and(|s| !s.success());
        if stop {
            let _ = self.child.kill();
        }
        let status = self.child.wait().map_err(|e| Error::io(&self.path, e))?;
        let last = last_words(self.stderr.take());
        let fed = self.feeder.take().map(JoinHandle::join);
        crate::interrupt::check()?;
        let mut fed = match fed {
            Some(Ok(fed)) => fed,
            Some(Err(_)) => return Err(self.error("the thread writing its packets failed")),
            None => return Ok(()),
        };
        let error = fed.error.take();
        let fed = self.fed.insert(fed);
        // Packets still without a frame gave none.
        self.pending.extend(self.stamps.try_iter());
        self.lost.places.add(self.pending.drain());
        if let Some(e) = error {
            return Err(e);
        }
        if stop && !failed {
            return Ok(());
        }
        let ended = stream_end(self.codec, &fed.before, fed.fed, self.frames, status, &last);
        ended.map_err(|e| self.error(e))
    }
}

impl Drop for VideoFrames {
    fn drop(&mut self) {
        // The feeder then finds the decoder's input closed and ends; a
        // decoder it started that was not taken yet is stopped too.
        kill(&mut self.child);
        for mut next in self.segments.try_iter() {
            kill(&mut next.child);
        }
    }
}

/// A frame of a live video stream.
pub struct LiveFrame {
    /// The pixels.
    pub image: RgbImage,
    /// The stamp given with its packet, nanoseconds.
    pub stamp_ns: i64,
    /// Its packet's place among those given (0-based, counting the ones
    /// skipped before the first keyframe).
    pub packet: u64,
}

/// A video stream decoded as its packets arrive: a subscription to a
/// live `CompressedVideo`, `FFMPEGPacket` or `h264_msgs/msg/Packet` topic. The packets go to an
/// FFmpeg process that starts on the first keyframe (no probing; the
/// frames it holds back for B-frames are read from that keyframe's
/// parameters, `Codec::frames_held_back`) and
/// decodes each packet as soon as it is whole (an IVF frame), and a thread
/// reads its pictures back, so a packet's frame is usually ready before
/// [`Self::push`] returns. Frames take stamps as a bag's video does (their
/// own packet's, by the time FFmpeg gives each). The process is killed
/// when this is dropped.
pub struct LiveVideo {
    codec: Codec,
    name: String,
    decoder: LiveDecoder,
    pending: PendingStamps,
    /// Packets given, skipped before the first keyframe (with the
    /// parameter sets that joined them), written to the decoders, written
    /// that show no frame ([`Codec::shows_frame`]), and frames decoded.
    given: u64,
    before: BeforeFirstKeyframe,
    written: u64,
    hidden: u64,
    decoded: u64,
    /// The packets written to the current decoder, the stream
    /// parameters of its last keyframe, and their changes.
    clock: DecoderClock,
    parameters: StreamParameters,
    /// Parameter sets given alone, held for the next packet.
    held: HeldParameterSets,
    changes: StreamChanges,
    /// Frames FFmpeg holds back once every packet given is in, read from
    /// the stream's parameters where they declare it, else learnt from
    /// waits that timed out: a stream with B-frames holds as many as its
    /// reordering needs, and a lost frame never comes. A push waits
    /// only while more frames than these are out, so each returns the
    /// frames its packet made due, as soon as they are decoded.
    held_back: u64,
    /// Waits that timed out; after [`LIVE_TIMEOUTS`], pushes no longer wait.
    timeouts: u32,
    /// True once [`Self::finish`] ended the stream.
    finished: bool,
}

/// How long [`LiveVideo::push`] waits for a frame: far above a frame's
/// decoding (milliseconds at 1080p), so only a stream that holds frames
/// back (B-frames) or lost one waits it out.
const LIVE_FRAME_WAIT: std::time::Duration = std::time::Duration::from_secs(1);

/// How long [`Codec::frames_held_back`] waits for `ffprobe` (0.1 s on a
/// 1080p keyframe here), once per decoder a live stream starts.
const REORDER_PROBE_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// The most frames a decoder holds back for reordering: H.264's and
/// H.265's decoded picture buffer has at most 16.
const MAX_FRAMES_HELD_BACK: u64 = 16;

/// Waits of [`LIVE_FRAME_WAIT`] a live stream may time out, so a stream
/// that keeps losing frames is not held up a second each time.
const LIVE_TIMEOUTS: u32 = 3;

/// What a live stream's FFmpeg did: a picture decoded, with its time
/// ([`frame_times`]), or an error it wrote (a damaged packet).
enum LiveEvent {
    Picture(Result<(RgbImage, Option<i64>)>),
    Error,
}

/// How long a push waits for its frame after FFmpeg wrote an error: a
/// damaged packet's frame will not come, but a concealed one may.
const LIVE_ERROR_WAIT: std::time::Duration = std::time::Duration::from_millis(100);

/// A live stream's FFmpeg process: its input, and a thread reading its
/// pictures into a channel, which its error output's thread also tells.
struct LiveDecoder {
    child: Child,
    stdin: Option<ChildStdin>,
    events: mpsc::Receiver<LiveEvent>,
    reader: Option<JoinHandle<()>>,
    stderr: Option<JoinHandle<Vec<u8>>>,
}

impl LiveDecoder {
    /// A decoder of `codec` started at once (no probing), named `name`
    /// in errors.
    fn start(codec: Codec, name: &str) -> Result<Self> {
        let (send, events) = mpsc::channel();
        let Decoder {
            mut child,
            stdin,
            stdout,
            mut times,
            stderr,
        } = spawn_decoder(codec, Some(send.clone()), std::path::Path::new(name))?;
        let owner = name.to_string();
        let reader = std::thread::Builder::new()
            .name("live-video".into())
            .spawn(move || {
                let mut stdout = BufReader::with_capacity(1 << 20, stdout);
                while let Ok(false) = stdout.fill_buf().map(<[u8]>::is_empty) {
                    let picture =
                        read_picture(&mut stdout, |m| Error::Invalid(format!("{owner}: {m}")))
                            .map(|p| (p, times.next()));
                    let failed = picture.is_err();
                    if send.send(LiveEvent::Picture(picture)).is_err() || failed {
                        break;
                    }
                }
            });
        match reader {
            Ok(r) => Ok(Self {
                child,
                stdin: Some(stdin),
                events,
                reader: Some(r),
                stderr,
            }),
            Err(e) => {
                kill(&mut child);
                Err(Error::Invalid(format!(
                    "{name}: no thread to read its frames: {e}"
                )))
            }
        }
    }

    /// Close the input and wait for the last pictures and the exit: the
    /// pictures, the exit status and FFmpeg's last words.
    #[allow(clippy::type_complexity)]
    fn end(
        &mut self,
    ) -> (
        Vec<Result<(RgbImage, Option<i64>)>>,
        std::io::Result<ExitStatus>,
        String,
    ) {
        drop(self.stdin.take());
        // The channel closes when FFmpeg has exited (its error output's
        // thread ends) and its pictures are read (or the reader stopped at
        // one it could not read, closing FFmpeg's output).
        let pictures: Vec<_> = self
            .events
            .iter()
            .filter_map(|e| match e {
                LiveEvent::Picture(p) => Some(p),
                LiveEvent::Error => None,
            })
            .collect();
        // The reader stops at a picture it cannot read: FFmpeg, left
        // writing to no one, is stopped.
        if pictures.iter().any(Result::is_err) {
            let _ = self.child.kill();
        }
        let status = self.child.wait();
        let last = last_words(self.stderr.take());
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
        (pictures, status, last)
    }

    /// Kill the process; its last words.
    fn stop(&mut self) -> String {
        drop(self.stdin.take());
        kill(&mut self.child);
        last_words(self.stderr.take())
    }
}

impl Drop for LiveDecoder {
    fn drop(&mut self) {
        self.stop();
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}

impl LiveVideo {
    /// A decoder of `format` (`h264`, `h265`/`hevc`, `vp9`, `av1`; the
    /// codec, or the encoder's name as `ffmpeg_image_transport` writes
    /// it), named `name` (a topic) in errors.
    pub fn new(format: &str, name: &str) -> Result<Self> {
        let error = |m: String| Error::Invalid(format!("{name}: {m}"));
        let codec = Codec::read(&Codec::of_encoding(format)).map_err(error)?;
        Ok(Self {
            codec,
            name: name.to_string(),
            decoder: LiveDecoder::start(codec, name)?,
            pending: PendingStamps::default(),
            given: 0,
            before: BeforeFirstKeyframe::default(),
            written: 0,
            hidden: 0,
            decoded: 0,
            clock: DecoderClock::default(),
            parameters: StreamParameters::default(),
            held: HeldParameterSets::default(),
            changes: StreamChanges::default(),
            held_back: 0,
            timeouts: 0,
            finished: false,
        })
    }

    /// Packets given before the first keyframe, which no decoder can read
    /// (a subscription joined mid-stream): skipped.
    pub fn skipped(&self) -> u64 {
        self.before.skipped
    }

    /// Keyframes among the packets skipped that came without the
    /// parameters they need (H.264's and H.265's sequence parameter set,
    /// AV1's sequence header): an encoder that sent them only before the
    /// subscription began, so no frame comes until a keyframe carries
    /// them. A node logs it with the cure ([`Self::finish`]'s error says
    /// it): have the encoder repeat them at every keyframe.
    pub fn keyframes_without_parameters(&self) -> u64 {
        self.before.without_parameters.count
    }

    /// Packets that gave no frame (a damaged packet): those shown before a
    /// frame that came, their own not come, and after [`Self::finish`]
    /// every one without a frame.
    pub fn lost(&self) -> u64 {
        (self.written.saturating_sub(self.hidden))
            .saturating_sub(self.decoded)
            .saturating_sub(self.pending.due())
    }

    /// Changes of the stream's parameters (a camera restarted at another
    /// size) decoded by the decoder before, their frames scaled to its
    /// size: those past the first 64 that came sooner than one per 32
    /// packets (a hostile stream's every keyframe), which start no FFmpeg
    /// process each. Every other change's frames keep their own size.
    pub fn scaled(&self) -> u64 {
        self.changes.scaled.count
    }

    /// Give the next packet (one frame: Annex B, a VP9 frame, or an AV1
    /// temporal unit) and its stamp; the frames decoded so far, normally
    /// this packet's, after waiting for the frames due (up to a second
    /// each; see [`LiveVideo`]'s `held_back`). A keyframe with new stream
    /// parameters (a camera restarted at another size) first ends the
    /// current decoder, whose last frames come back here too, and starts
    /// a new one, so every frame keeps its own size.
    pub fn push(&mut self, data: &[u8], stamp_ns: i64) -> Result<Vec<LiveFrame>> {
        if self.finished {
            return Err(
                self.error("the video decoder was finished: no packet is decoded after it".into())
            );
        }
        let packet = self.given;
        self.given += 1;
        // Parameter sets alone join the next packet, and are skipped with
        // it.
        let Some((data, joined)) = self.held.join(self.codec, Cow::Borrowed(data)) else {
            return Ok(Vec::new());
        };
        let data: &[u8] = &data;
        let role = self.parameters.role(self.codec, data);
        if self.before.skip(&role, packet, joined) {
            return Ok(Vec::new());
        }
        let mut frames = Vec::new();
        if role == PacketRole::NewParameters && self.changes.restart(packet, self.written) {
            self.restart(&mut frames)?;
        }
        let Some(stdin) = self.decoder.stdin.as_mut() else {
            return Err(self.error("its stream was closed".into()));
        };
        let hidden = !self.codec.shows_frame(data);
        let (stamp, first) = self.clock.stamp(stamp_ns, packet, 0, hidden);
        if first {
            // A stream whose parameters declare its B-frames gets no push
            // that waits out its decoder's delay to learn it.
            self.held_back = self.held_back.max(self.codec.frames_held_back(data));
        }
        let pts = stamp.pts;
        self.pending.add(stamp);
        if let Err(e) = self
            .codec
            .write_packet(stdin, data, first, pts)
            .and_then(|()| stdin.flush())
        {
            let last = self.decoder.stop();
            return Err(self.error(format!("FFmpeg stopped reading its packets ({e}): {last}")));
        }
        self.written += 1;
        self.hidden += u64::from(hidden);
        let mut wait = LIVE_FRAME_WAIT;
        // An empty packet (a publisher's dropped frame) gives no frame: its
        // push does not wait, and a later frame passes it.
        while !data.is_empty()
            && self.timeouts < LIVE_TIMEOUTS
            && self.pending.due() > self.held_back
        {
            match self.decoder.events.recv_timeout(wait) {
                Ok(LiveEvent::Picture(p)) => frames.push(self.frame(p)?),
                // A damaged packet: its frame is waited for only briefly.
                Ok(LiveEvent::Error) => wait = LIVE_ERROR_WAIT,
                // Not held back, but lost (said by FFmpeg): no timeout.
                Err(mpsc::RecvTimeoutError::Timeout) if wait == LIVE_ERROR_WAIT => break,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    self.held_back = self.pending.due();
                    self.timeouts += 1;
                }
                // FFmpeg ended: the next push or `finish` says why.
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
        self.ready(&mut frames)?;
        Ok(frames)
    }

    /// End the stream: the frames still held, once FFmpeg has decoded
    /// every packet; the packets still without a frame are lost. A stream
    /// given no packet, or finished already, ends with none; one that gave
    /// no frame is refused as a bag's video is: no keyframe among its
    /// packets, or none of them decoded. [`Self::skipped`] and
    /// [`Self::lost`] keep their counts; a later push is refused.
    pub fn finish(&mut self) -> Result<Vec<LiveFrame>> {
        if std::mem::replace(&mut self.finished, true) {
            return Ok(Vec::new());
        }
        if self.given == 0 {
            self.decoder.stop();
            return Ok(Vec::new());
        }
        let mut frames = Vec::new();
        let ended = self.end_decoder(&mut frames);
        self.pending.drain();
        let (status, last) = ended?;
        stream_end(
            self.codec,
            &self.before,
            self.written,
            self.decoded,
            status,
            &last,
        )
        .map_err(|e| self.error(e))?;
        Ok(frames)
    }

    /// A new decoder for a stream with new parameters: the current one's
    /// last frames go to `frames`, and its packets that gave none are
    /// forgotten, so the new stream's frames take their own stamps.
    fn restart(&mut self, frames: &mut Vec<LiveFrame>) -> Result<()> {
        let (status, last) = self.end_decoder(frames)?;
        decoder_ended_well(self.codec, status, &last).map_err(|e| self.error(e))?;
        self.decoder = LiveDecoder::start(self.codec, &self.name)?;
        self.clock.next_decoder();
        self.pending.drop_before(self.clock.segment);
        self.held_back = 0;
        Ok(())
    }

    /// End the current decoder, its last frames going to `frames`; its
    /// exit status and last words.
    fn end_decoder(&mut self, frames: &mut Vec<LiveFrame>) -> Result<(ExitStatus, String)> {
        let (pictures, status, last) = self.decoder.end();
        for p in pictures {
            frames.push(self.frame(p)?);
        }
        let status =
            status.map_err(|e| self.error(format!("FFmpeg could not be waited for: {e}")))?;
        Ok((status, last))
    }

    /// The frames ready now, after `frames`.
    fn ready(&mut self, frames: &mut Vec<LiveFrame>) -> Result<()> {
        while let Ok(e) = self.decoder.events.try_recv() {
            if let LiveEvent::Picture(p) = e {
                frames.push(self.frame(p)?);
            }
        }
        Ok(())
    }

    /// A picture with its own packet's stamp, by its time (else the
    /// earliest written packet's).
    fn frame(&mut self, picture: Result<(RgbImage, Option<i64>)>) -> Result<LiveFrame> {
        let (image, time) = picture?;
        let taken = self
            .pending
            .take(time, self.written)
            .map_err(|e| self.error(e))?;
        // Frames found lost were not held back: later pushes wait for
        // theirs again.
        self.held_back = self.held_back.saturating_sub(taken.passed);
        let stamp = taken.stamp;
        // A packet taken to show no frame showed one after all.
        self.hidden = self.hidden.saturating_sub(u64::from(stamp.hidden));
        self.decoded += 1;
        Ok(LiveFrame {
            image,
            stamp_ns: stamp.stamp_ns,
            packet: stamp.index,
        })
    }

    fn error(&self, message: String) -> Error {
        Error::Invalid(format!("{}: {message}", self.name))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::bag::messages::{Header, Time, to_cdr};
    use crate::bag::{BagImages, image_topics};
    use std::collections::BTreeMap;
    use std::path::Path;

    /// `frames` 64x64 frames of FFmpeg's moving test pattern encoded by
    /// `encoder`: one packet per frame in decoding order (Annex B), and
    /// every frame as FFmpeg decodes the whole stream, in display order.
    fn encode(dir: &Path, encoder: &[&str], frames: usize) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        encode_sized(dir, encoder, frames, (64, 64))
    }

    /// [`encode`] at another size.
    fn encode_sized(
        dir: &Path,
        encoder: &[&str],
        frames: usize,
        (w, h): (usize, usize),
    ) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        let dir = dir.join(format!("{w}x{h}"));
        std::fs::create_dir_all(&dir).unwrap();
        let dir = dir.as_path();
        let name = format!("{}-%03d.bin", encoder[1]);
        encode_file(
            (dir, &name),
            "yuv420p",
            (w, h),
            frames,
            &[encoder],
            "image2",
        );
        let packets: Vec<Vec<u8>> = (1..=frames)
            .map(|i| std::fs::read(dir.join(format!("{}-{i:03}.bin", encoder[1]))).unwrap())
            .collect();
        let stream = dir.join(format!("{}.bin", encoder[1]));
        std::fs::write(&stream, packets.concat()).unwrap();
        (packets, decode_file(&stream, (w, h), frames))
    }

    /// Where each packet of `encode(dir, encoder, frames)` shows: the
    /// same encoding (x264 on one thread gives the same packets) through
    /// FFmpeg's `framecrc` muxer, which lists each packet's size and
    /// presentation stamp in decoding order; the stamps ranked.
    fn display_order(encoder: &[&str], frames: usize, packets: &[Vec<u8>]) -> Vec<usize> {
        let out = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
            .args(["-f", "lavfi", "-i", "testsrc=size=64x64:rate=10"])
            .args(["-frames:v", &frames.to_string(), "-pix_fmt", "yuv420p"])
            .args(encoder)
            .args(["-f", "framecrc", "-"])
            .output()
            .unwrap();
        assert!(out.status.success());
        let listed: Vec<(usize, i64)> = String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| {
                let f: Vec<&str> = l.split(',').map(str::trim).collect();
                (f[4].parse().unwrap(), f[2].parse().unwrap())
            })
            .collect();
        let sizes: Vec<usize> = listed.iter().map(|l| l.0).collect();
        assert_eq!(sizes, packets.iter().map(Vec::len).collect::<Vec<_>>());
        let mut pts: Vec<i64> = listed.iter().map(|l| l.1).collect();
        pts.sort_unstable();
        listed
            .iter()
            .map(|l| pts.binary_search(&l.1).unwrap())
            .collect()
    }

    /// `frames` 64x64 frames of the test pattern in AV1 (libaom, a key
    /// frame every 3, no hidden frames): one temporal unit per frame, each
    /// beginning with its temporal delimiter as FFmpeg's `obu` muxer
    /// writes them, and every frame as FFmpeg decodes the whole stream.
    fn encode_av1(dir: &Path, frames: usize) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        encode_av1_sized(dir, frames, (64, 64))
    }

    /// [`encode_av1`] at another size.
    fn encode_av1_sized(
        dir: &Path,
        frames: usize,
        (w, h): (usize, usize),
    ) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        let libaom = ["-c:v", "libaom-av1", "-cpu-used", "8", "-g", "3"];
        let options = ["-lag-in-frames", "0", "-threads", "1"];
        let name = format!("av1-{w}x{h}.obu");
        let stream = encode_file(
            (dir, &name),
            "yuv420p",
            (w, h),
            frames,
            &[&libaom, &options],
            "obu",
        );
        let data = std::fs::read(&stream).unwrap();
        // Split before each temporal delimiter.
        let mut packets: Vec<Vec<u8>> = Vec::new();
        let mut at = 0;
        for (kind, payload) in av1_obus(&data) {
            let end = payload.as_ptr() as usize - data.as_ptr() as usize + payload.len();
            if kind == 2 {
                packets.push(Vec::new());
            }
            packets
                .last_mut()
                .unwrap()
                .extend_from_slice(&data[at..end]);
            at = end;
        }
        assert_eq!(at, data.len());
        assert_eq!(packets.len(), frames);
        (packets, decode_file(&stream, (w, h), frames))
    }

    /// `frames` frames of H.264 without B-frames, a keyframe every `gop`:
    /// its packets and FFmpeg's decode of them.
    fn h264_without_b_frames(dir: &Path, gop: u32, frames: usize) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        let gop = gop.to_string();
        encode(dir, &["-c:v", "libx264", "-bf", "0", "-g", &gop], frames)
    }

    /// Each packet with its message's place, as the bag writers take them.
    fn numbered(packets: &[Vec<u8>]) -> Vec<(usize, &[u8])> {
        packets.iter().map(Vec::as_slice).enumerate().collect()
    }

    /// `frames` frames of FFmpeg's test pattern at `w`x`h` in `pix_fmt`,
    /// encoded with `encoder`'s options into `dir/name`, a file of
    /// `muxer`'s format.
    fn encode_file(
        (dir, name): (&Path, &str),
        pix_fmt: &str,
        (w, h): (usize, usize),
        frames: usize,
        encoder: &[&[&str]],
        muxer: &str,
    ) -> std::path::PathBuf {
        let stream = dir.join(name);
        let status = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error", "-y"])
            .args(["-f", "lavfi", "-i"])
            .arg(format!("testsrc=size={w}x{h}:rate=10"))
            .args(["-frames:v", &frames.to_string(), "-pix_fmt", pix_fmt])
            .args(encoder.concat())
            .args(["-f", muxer])
            .arg(&stream)
            .status()
            .unwrap();
        assert!(status.success());
        stream
    }

    /// Every frame of the video file at `path` as FFmpeg decodes it
    /// (`w`x`h` RGB), checked to be `frames`.
    fn decode_file(path: &Path, (w, h): (usize, usize), frames: usize) -> Vec<Vec<u8>> {
        let (every_frame, each_output) = passthrough_options();
        let out = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
            .args(every_frame)
            .arg("-i")
            .arg(path)
            .args(each_output)
            .args(["-f", "rawvideo"])
            .args(["-pix_fmt", "rgb24", "-"])
            .output()
            .unwrap();
        assert!(out.status.success());
        let decoded: Vec<Vec<u8>> = out.stdout.chunks(w * h * 3).map(<[u8]>::to_vec).collect();
        assert_eq!(decoded.len(), frames);
        decoded
    }

    /// `frames` 64x64 frames of the test pattern in VP9 (libvpx, `pix_fmt`,
    /// a key frame every 3): one frame per packet, as FFmpeg's IVF muxer
    /// frames them, and every frame as FFmpeg decodes the IVF file.
    fn encode_vp9(dir: &Path, pix_fmt: &str, frames: usize) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        encode_vp9_sized(dir, pix_fmt, frames, (64, 64))
    }

    /// [`encode_vp9`] at another size.
    fn encode_vp9_sized(
        dir: &Path,
        pix_fmt: &str,
        frames: usize,
        (w, h): (usize, usize),
    ) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        let libvpx = ["-c:v", "libvpx-vp9", "-g", "3", "-threads", "1"];
        let name = format!("{pix_fmt}-{w}x{h}.ivf");
        let stream = encode_file((dir, &name), pix_fmt, (w, h), frames, &[&libvpx], "ivf");
        (
            ivf_packets(&stream, b"VP90", frames),
            decode_file(&stream, (w, h), frames),
        )
    }

    /// The first `frames` packets of the IVF file at `path`, whose header
    /// names the codec `tag`: one frame (or temporal unit) per packet.
    fn ivf_packets(path: &Path, tag: &[u8; 4], frames: usize) -> Vec<Vec<u8>> {
        let mut file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        assert_eq!(&ivf::read_header(&mut file).unwrap().tag, tag);
        (0..frames)
            .map(|_| ivf::read_packet(&mut file).unwrap().data.into_vec())
            .collect()
    }

    const T0: u32 = 1_700_000_000;

    fn stamp_ns(i: usize) -> i64 {
        (T0 as i64 + i as i64) * 1_000_000_000
    }

    /// `packets` as ROS 2 `foxglove_msgs/msg/CompressedVideo` messages on
    /// `topic`, stamped `T0 + i` seconds, as one MCAP file.
    fn ros_bag(path: &Path, topic: &str, format: &str, packets: &[(usize, &[u8])]) {
        cdr_bag(
            path,
            topic,
            ROS_COMPRESSED_VIDEO_TYPE,
            packets,
            |i, data| {
                to_cdr(&CompressedVideo {
                    timestamp: Time::from_nanos(stamp_ns(i)),
                    frame_id: "cam".into(),
                    data,
                    format: format.into(),
                })
            },
        );
    }

    /// `packets` as messages of `schema` on `topic`, each made by
    /// `message(i, data)`, as one MCAP file.
    fn cdr_bag(
        path: &Path,
        topic: &str,
        schema: &str,
        packets: &[(usize, &[u8])],
        message: impl Fn(usize, &[u8]) -> std::result::Result<Vec<u8>, String>,
    ) {
        let mut out = std::io::Cursor::new(Vec::new());
        let mut w = mcap::Writer::new(&mut out).unwrap();
        let s = w.add_schema(schema, "ros2msg", b"").unwrap();
        let c = w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap();
        for &(i, data) in packets {
            let h = mcap::records::MessageHeader {
                channel_id: c,
                sequence: i as u32,
                log_time: i as u64,
                publish_time: i as u64,
            };
            w.write_to_known_channel(&h, &message(i, data).unwrap())
                .unwrap();
        }
        w.finish().unwrap();
        drop(w);
        std::fs::write(path, out.into_inner()).unwrap();
    }

    /// Every frame of `topic`, with its stamp and index, and the warnings.
    fn read_all(path: &Path, topic: &str) -> Result<(Vec<BagFrame>, Vec<String>)> {
        let mut r = BagImages::open(path, topic)?;
        let mut frames = Vec::new();
        while let Some(f) = r.next_frame()? {
            frames.push(f);
        }
        Ok((frames, r.warnings()))
    }

    #[test]
    fn a_video_topic_gives_each_packet_its_frame_and_stamp_from_its_first_keyframe() {
        let dir = tempfile::tempdir().unwrap();
        let x264 = [
            "-c:v",
            "libx264",
            "-bf",
            "0",
            "-g",
            "5",
            "-x264-params",
            "repeat-headers=1",
        ];
        let (packets, decoded) = encode(dir.path(), &x264, 12);
        // Recorded as a Foxglove SDK user records a camera, begun in the
        // middle of a group of pictures: packets 2 to 4 precede the next
        // keyframe (5), which nothing can decode. Their encoder repeats
        // the parameter sets before every frame (the SPS and PPS of the
        // first packet, before its IDR slice), so they are no start.
        let idr = packets[0]
            .windows(4)
            .position(|w| w == [0, 0, 1, 0x65])
            .unwrap();
        let parameter_sets = packets[0][..idr].to_vec();
        let mut packets = packets;
        for p in &mut packets[2..5] {
            p.splice(0..0, parameter_sets.iter().copied());
        }
        let sdk = dir.path().join("sdk.mcap");
        let ctx = foxglove::Context::new();
        let writer = ctx.mcap_writer().create_new_buffered_file(&sdk).unwrap();
        let channel = ctx
            .channel_builder("/cam/h264")
            .build::<foxglove::messages::CompressedVideo>();
        for (i, p) in packets.iter().enumerate().skip(2) {
            let stamp = foxglove::messages::Timestamp::new(T0 + i as u32, 0);
            channel.log_with_time(
                &foxglove::messages::CompressedVideo {
                    timestamp: Some(stamp),
                    frame_id: "cam".into(),
                    data: p.clone().into(),
                    format: "h264".into(),
                },
                stamp,
            );
        }
        writer.close().unwrap();
        let topics = image_topics(&sdk).unwrap();
        assert_eq!(topics[0].message_type, FOXGLOVE_COMPRESSED_VIDEO_TYPE);
        assert_eq!(topics[0].count, 10);
        let (frames, warnings) = read_all(&sdk, "/cam/h264").unwrap();
        // Each decoded frame is the whole stream's frame of its packet,
        // stamped with its packet's stamp.
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = (5..12).map(|i| (i as u64 - 2, stamp_ns(i))).collect();
        assert_eq!(got, want);
        for (f, i) in frames.iter().zip(5..) {
            assert_eq!((f.image.width(), f.image.height()), (64, 64));
            assert!(f.image.as_slice() == decoded[i].as_slice(), "frame {i}");
        }
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].contains("its first 3 messages come before the first keyframe of its h264 stream (the recording began mid-stream) and cannot be decoded; its frames begin at message 3"),
            "{}",
            warnings[0]
        );

        // H.265 as ROS 2 messages, from its first packet: every frame.
        let x265 = [
            "-c:v",
            "libx265",
            "-x265-params",
            "bframes=0:keyint=5:repeat-headers=1:log-level=error",
        ];
        let (packets, decoded) = encode(dir.path(), &x265, 7);
        let ros = dir.path().join("ros.mcap");
        let all = numbered(&packets);
        ros_bag(&ros, "/cam/h265", "h265", &all);
        let (frames, warnings) = read_all(&ros, "/cam/h265").unwrap();
        assert_eq!(frames.len(), 7);
        for (i, f) in frames.iter().enumerate() {
            assert_eq!((f.index, f.stamp_ns), (i as u64, stamp_ns(i)));
            assert!(f.image.as_slice() == decoded[i].as_slice(), "frame {i}");
        }
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    /// 12 frames of x264 with two B-frames between references (one thread,
    /// so its packets are the same each time): the packets in decoding
    /// order, the frames in display order, and where each packet shows.
    fn b_frame_stream(dir: &Path) -> (Vec<Vec<u8>>, Vec<Vec<u8>>, Vec<usize>) {
        let x264 = [
            "-c:v",
            "libx264",
            "-threads",
            "1",
            "-g",
            "6",
            "-x264-params",
            "bframes=2:b-adapt=0:b-pyramid=none:repeat-headers=1",
        ];
        let (packets, decoded) = encode(dir, &x264, 12);
        let shown = display_order(&x264, 12, &packets);
        (packets, decoded, shown)
    }

    #[test]
    fn frames_of_a_stream_with_b_frames_take_their_own_packets_stamps() {
        // Two B-frames between references: packets come in decoding
        // order, each stamped with the time its frame shows, as
        // ffmpeg_image_transport publishes an encoder's packets.
        let dir = tempfile::tempdir().unwrap();
        let (packets, decoded, shown) = b_frame_stream(dir.path());
        assert_ne!(shown, (0..12).collect::<Vec<_>>(), "no B-frames");
        let path = dir.path().join("b.mcap");
        let all = numbered(&packets);
        cdr_bag(&path, "/cam", FFMPEG_PACKET_TYPE, &all, |i, data| {
            to_cdr(&FfmpegPacket {
                header: Header {
                    stamp: Time::from_nanos(stamp_ns(shown[i])),
                    frame_id: "cam".into(),
                },
                width: 64,
                height: 64,
                encoding: "h264;yuv420p;rgb8;rgb8".into(),
                pts: shown[i] as u64,
                flags: u8::from(i % 6 == 0),
                is_bigendian: false,
                data,
            })
        });
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        // Frame k (display order) is the stream's frame k, with the stamp
        // and message of the packet that coded it.
        assert_eq!(frames.len(), 12);
        for (k, f) in frames.iter().enumerate() {
            let message = shown.iter().position(|&s| s == k).unwrap();
            assert_eq!((f.index, f.stamp_ns), (message as u64, stamp_ns(k)), "{k}");
            assert!(f.image.as_slice() == decoded[k].as_slice(), "frame {k}");
        }
    }

    /// A slice that no decoder takes: a damaged packet's stand-in.
    const DAMAGED: &[u8] = &[0, 0, 1, 0x65, 0xff, 0xff];

    #[test]
    fn frame_times_are_read_past_the_prefixes_of_ffmpeg_7s_messages() {
        // FFmpeg 7.0.2's error output for the damaged packet of the
        // Python test (each frame's line is written by the muxer's thread,
        // between a message's prefixes and its text). Before, a frame's
        // line after a prefix was taken for a message: its time was lost,
        // so each later frame took the next one's time and stamp.
        let lines: [(&str, Option<i64>); 9] = [
            (
                "0,   99999999,   99999999, 40000000,      440, 0x3ef51d55\n",
                Some(99_999_999),
            ),
            (
                "[h264 @ 0x1d1d1b40] 0,  133333332,  133333332, 40000000,      440, 0xd66d1ba3\n",
                Some(133_333_332),
            ),
            (
                "[vist#0:0/h264 @ 0x1d1e6400] [dec:h264 @ 0x1d1d0c40] 0,  199999998,  199999998, 40000000,      440, 0x016a1ddd\n",
                Some(199_999_998),
            ),
            ("A non-intra slice in an IDR NAL unit.\n", None),
            ("[h264 @ 0x1d1d1b40] decode_slice_header error\n", None),
            (
                "[vist#0:0/h264 @ 0x1d1e6400] [dec:h264 @ 0x1d1d0c40] Error submitting packet to decoder: Invalid data found when processing input\n",
                None,
            ),
            ("[h264 @ 0x1d1d1b40] 0, 1, 2, 3\n", None),
            ("[not a prefix] 0, 1, 2, 3, 4, 0x5\n", None),
            ("#tb 0: 1/1000000000\n", None),
        ];
        for (line, time) in lines {
            assert_eq!(framecrc_time(line.as_bytes()), time, "{line}");
        }
    }

    #[test]
    fn a_lost_frame_leaves_every_other_frame_its_own_stamp() {
        // Before, each frame took the earliest stamp still pending, so
        // every frame after a damaged packet carried an earlier packet's
        // stamp: frame 4 was stamped as message 3.
        let dir = tempfile::tempdir().unwrap();
        let (mut packets, decoded) = h264_without_b_frames(dir.path(), 50, 8);
        packets[3] = DAMAGED.to_vec();
        let path = dir.path().join("lost.mcap");
        let all = numbered(&packets);
        ros_bag(&path, "/cam", "h264", &all);
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let kept = [0, 1, 2, 4, 5, 6, 7];
        let want: Vec<(u64, i64)> = kept.iter().map(|&i| (i as u64, stamp_ns(i))).collect();
        assert_eq!(got, want);
        assert!(
            frames[..3]
                .iter()
                .zip(&decoded)
                .all(|(f, d)| f.image.as_slice() == d.as_slice())
        );
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].ends_with("FFmpeg gave a frame for 7 of its 8 packets (a damaged packet gives none); messages that gave none: 3; every frame carries its own packet's stamp"),
            "{}",
            warnings[0]
        );
        // Live: each push after the lost packet gives its own frame at once.
        let mut live = LiveVideo::new("h264", "/cam").unwrap();
        let mut got = Vec::new();
        for (i, p) in packets.iter().enumerate() {
            let frames = live.push(p, stamp_ns(i)).unwrap();
            let own: Vec<u64> = frames.iter().map(|f| f.packet).collect();
            let want: &[u64] = if i == 3 { &[] } else { &[i as u64] };
            assert_eq!(own, want, "push {i}");
            assert_eq!(live.lost(), u64::from(i > 3), "push {i}");
            got.extend(frames.iter().map(|f| (f.packet, f.stamp_ns)));
        }
        assert!(live.finish().unwrap().is_empty());
        assert_eq!(got, want);
        // A lost B-frame: the frames shown after it keep their own stamps.
        let (mut packets, _, shown) = b_frame_stream(dir.path());
        let b = (1..shown.len()).find(|&i| shown[i] < shown[i - 1]).unwrap();
        packets[b] = DAMAGED.to_vec();
        let path = dir.path().join("lost-b.mcap");
        let all = numbered(&packets);
        cdr_bag(&path, "/cam", ROS_COMPRESSED_VIDEO_TYPE, &all, |i, data| {
            to_cdr(&CompressedVideo {
                timestamp: Time::from_nanos(stamp_ns(shown[i])),
                frame_id: "cam".into(),
                data,
                format: "h264".into(),
            })
        });
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = (0..shown.len())
            .filter(|&k| k != shown[b])
            .map(|k| {
                let message = shown.iter().position(|&s| s == k).unwrap();
                (message as u64, stamp_ns(k))
            })
            .collect();
        assert_eq!(got, want);
        assert!(
            warnings[0].contains(&format!("messages that gave none: {b};")),
            "{warnings:?}"
        );
    }

    #[test]
    fn b_frames_stamped_in_decoding_order_give_every_frame_a_stamp_once() {
        // A recorder that stamps packets as they come (decoding order):
        // the frames' times are not in display order, so some name no
        // packet; still every frame comes, each packet's stamp used once,
        // in a bag and live.
        let dir = tempfile::tempdir().unwrap();
        let (packets, _, _) = b_frame_stream(dir.path());
        let path = dir.path().join("decoding-order.mcap");
        let all = numbered(&packets);
        ros_bag(&path, "/cam", "h264", &all);
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let mut stamps: Vec<i64> = frames.iter().map(|f| f.stamp_ns).collect();
        stamps.sort();
        assert_eq!(stamps, (0..12).map(stamp_ns).collect::<Vec<_>>());
        let mut live = LiveVideo::new("h264", "/cam").unwrap();
        let mut frames = Vec::new();
        for (i, p) in packets.iter().enumerate() {
            frames.extend(live.push(p, stamp_ns(i)).unwrap());
        }
        frames.extend(live.finish().unwrap());
        let mut stamps: Vec<i64> = frames.iter().map(|f| f.stamp_ns).collect();
        stamps.sort();
        assert_eq!(stamps, (0..12).map(stamp_ns).collect::<Vec<_>>());
    }

    /// An H.264 stream without B-frames whose packets are stamped
    /// `stamps`, in a bag (as `name`) and live: each frame must keep its
    /// own packet's stamp and place.
    fn each_frame_keeps_its_own_stamp(dir: &Path, name: &str, stamps: &[i64]) {
        let (packets, _) = h264_without_b_frames(dir, 50, stamps.len());
        let path = dir.join(format!("{name}.mcap"));
        let all = numbered(&packets);
        cdr_bag(&path, "/cam", ROS_COMPRESSED_VIDEO_TYPE, &all, |i, data| {
            to_cdr(&CompressedVideo {
                timestamp: Time::from_nanos(stamps[i]),
                frame_id: "cam".into(),
                data,
                format: "h264".into(),
            })
        });
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = stamps
            .iter()
            .enumerate()
            .map(|(i, &s)| (i as u64, s))
            .collect();
        assert_eq!(got, want, "{name}");
        let mut live = LiveVideo::new("h264", "/cam").unwrap();
        let mut got = Vec::new();
        for (p, &stamp) in packets.iter().zip(stamps) {
            got.extend(live.push(p, stamp).unwrap());
        }
        got.extend(live.finish().unwrap());
        let got: Vec<(u64, i64)> = got.iter().map(|f| (f.packet, f.stamp_ns)).collect();
        assert_eq!(got, want, "{name} live");
    }

    #[test]
    fn frames_stamped_alike_or_back_in_time_keep_their_own_stamps() {
        // A publisher that stamps every packet alike, and a clock that
        // steps back (a simulation restarted): FFmpeg raises a time that
        // would go back to the last one, which the second run's packet of
        // that stamp also has; each frame still takes its own packet's
        // stamp, in a bag and live.
        let dir = tempfile::tempdir().unwrap();
        let alike: Vec<i64> = (0..8).map(|_| stamp_ns(1)).collect();
        let back: Vec<i64> = (0..8).map(|i| stamp_ns(i % 4)).collect();
        each_frame_keeps_its_own_stamp(dir.path(), "alike", &alike);
        each_frame_keeps_its_own_stamp(dir.path(), "back", &back);
    }

    #[test]
    fn a_live_stream_of_several_damaged_packets_keeps_giving_frames_at_once() {
        // Four damaged packets, one more than the waits that may time
        // out: FFmpeg's error tells each push its frame is lost, so it
        // waits a tenth of a second, not a second, and no timeout is
        // spent. Before, the third lost frame ended waiting, and every
        // later frame came a push late. An empty packet (10) is not
        // waited for at all.
        let dir = tempfile::tempdir().unwrap();
        let (mut packets, _) = h264_without_b_frames(dir.path(), 50, 12);
        let damaged = [2, 4, 6, 8, 10];
        for k in &damaged[..4] {
            packets[*k] = DAMAGED.to_vec();
        }
        packets[10] = Vec::new();
        let mut live = LiveVideo::new("h264", "/cam").unwrap();
        for (i, p) in packets.iter().enumerate() {
            let started = std::time::Instant::now();
            let own: Vec<u64> = live
                .push(p, stamp_ns(i))
                .unwrap()
                .iter()
                .map(|f| f.packet)
                .collect();
            let lost = damaged.contains(&i);
            let want: &[u64] = if lost { &[] } else { &[i as u64] };
            assert_eq!(own, want, "push {i}");
            if lost {
                let waited = started.elapsed();
                assert!(waited < LIVE_FRAME_WAIT / 2, "push {i}: {waited:?}");
            }
        }
        assert_eq!((live.timeouts, live.lost()), (0, 5));
        assert!(live.finish().unwrap().is_empty());
    }

    #[test]
    fn frames_of_wildly_stamped_packets_keep_their_own_stamps() {
        // Stamps far apart (FFmpeg's floating point loses the nanosecond)
        // and out of order, and stamps counting down: the times name no
        // packet or do not rise, and each frame takes the earliest written
        // packet's. Before, each took the earliest stamp, so the
        // countdown's frame 1 was stamped as packet 9.
        let dir = tempfile::tempdir().unwrap();
        let s = |seconds: i64| seconds * 1_000_000_000 + 123;
        let wild = [
            0,
            2_000_000_000,
            1,
            1_500_000_000,
            5,
            3,
            2_147_483_647,
            7,
            0,
            9,
        ]
        .map(s);
        let countdown: Vec<i64> = (0..10).map(|i| s(2_000_000_000 - i)).collect();
        each_frame_keeps_its_own_stamp(dir.path(), "wild", &wild);
        each_frame_keeps_its_own_stamp(dir.path(), "countdown", &countdown);
    }

    #[test]
    fn b_frames_declared_by_a_stream_are_read_from_its_first_keyframe() {
        // The frames each decoder holds back, as FFmpeg's own parser reads
        // them from a keyframe's parameters: x264 with two B-frames and no
        // pyramid (1), x264's and x265's defaults with B-frame pyramids
        // (2), none without B-frames or from bytes that are no stream.
        // Pushed a packet at a time, back to back, each B-frame stream
        // waits out no delay: after the frames held, each push returns
        // exactly one frame, in display order with its own stamp and
        // FFmpeg's pixels, the 12 pushes within a second. Before, the
        // first push waited out a second to learn the delay (a timed-out
        // wait); before that, pushes stopped waiting after that timeout
        // and returned before FFmpeg had decoded the frame, so frames came
        // later (back to back as here, every one only at the finish).
        let dir = tempfile::tempdir().unwrap();
        let folder = |name: &str| {
            let d = dir.path().join(name);
            std::fs::create_dir(&d).unwrap();
            d
        };
        let x264 = ["-c:v", "libx264", "-threads", "1", "-g", "12"];
        let x265 = [
            "-c:v",
            "libx265",
            "-x265-params",
            "keyint=12:repeat-headers=1:frame-threads=1:pools=none:log-level=error",
        ];
        let no_pyramid = b_frame_stream(&folder("no-pyramid"));
        let encoded = |name: &str, encoder: &[&str], codec: Codec, held: u64| {
            let (packets, decoded) = encode(&folder(name), encoder, 12);
            let shown = display_order(encoder, 12, &packets);
            (codec, packets, decoded, shown, held)
        };
        for (codec, packets, decoded, shown, held) in [
            (Codec::H264, no_pyramid.0, no_pyramid.1, no_pyramid.2, 1),
            encoded("pyramid", &x264, Codec::H264, 2),
            encoded("x265", &x265, Codec::H265, 2),
        ] {
            let name = codec.name();
            assert_ne!(shown, (0..12).collect::<Vec<_>>(), "{name}: no B-frames");
            assert_eq!(codec.frames_held_back(&packets[0]), held, "{name}");
            let mut live = LiveVideo::new(name, "/cam").unwrap();
            let mut counts = Vec::new();
            let mut frames = Vec::new();
            let start = std::time::Instant::now();
            for (p, &k) in packets.iter().zip(&shown) {
                let got = live.push(p, stamp_ns(k)).unwrap();
                counts.push(got.len());
                frames.extend(got);
            }
            let pushed = start.elapsed();
            assert_eq!(live.timeouts, 0, "{name}: a push waited out its delay");
            assert!(
                pushed < LIVE_FRAME_WAIT,
                "{name}: 12 pushes took {pushed:?}"
            );
            let mut want = vec![0; held as usize];
            want.resize(12, 1);
            assert_eq!(counts, want, "{name}: frames from each push");
            frames.extend(live.finish().unwrap());
            assert_eq!(frames.len(), 12, "{name}");
            for (k, f) in frames.iter().enumerate() {
                assert_eq!(f.stamp_ns, stamp_ns(k), "{name} {k}");
                assert!(f.image.as_slice() == decoded[k].as_slice(), "{name} {k}");
            }
        }
        let (packets, _) = h264_without_b_frames(&folder("none"), 4, 4);
        assert_eq!(Codec::H264.frames_held_back(&packets[0]), 0);
        assert_eq!(Codec::H264.frames_held_back(b"not a stream"), 0);
        assert_eq!(Codec::H265.frames_held_back(&[]), 0);
        assert_eq!(Codec::Vp9.frames_held_back(&packets[0]), 0);
    }

    #[test]
    fn a_live_stream_gives_each_packets_frame_as_it_arrives() {
        // Joined mid-stream, as a subscriber joins a running camera: the
        // packets before the keyframe skipped, then each packet's frame
        // back from its own push (the decoder does not wait for the next
        // packet), with its stamp; H.265 too.
        let dir = tempfile::tempdir().unwrap();
        let x264 = ["-c:v", "libx264", "-bf", "0", "-g", "4"];
        let x265 = [
            "-c:v",
            "libx265",
            "-x265-params",
            "bframes=0:keyint=4:repeat-headers=1:log-level=error",
        ];
        for (encoder, format) in [(&x264[..], "h264;yuv420p;rgb8;rgb8"), (&x265[..], "hevc")] {
            let (packets, decoded) = encode(dir.path(), encoder, 10);
            let mut live = LiveVideo::new(format, "/cam").unwrap();
            let mut frames = Vec::new();
            let mut late = 0;
            for (i, p) in packets.iter().enumerate().skip(2) {
                let got = live.push(p, stamp_ns(i)).unwrap();
                late += usize::from(i >= 4 && !got.iter().any(|f| f.packet == i as u64 - 2));
                frames.extend(got);
            }
            assert_eq!(live.skipped(), 2);
            frames.extend(live.finish().unwrap());
            assert_eq!(late, 0, "{format}: frames came a packet late");
            let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.packet, f.stamp_ns)).collect();
            let want: Vec<(u64, i64)> = (4..10).map(|i| (i as u64 - 2, stamp_ns(i))).collect();
            assert_eq!(got, want, "{format}");
            for (f, i) in frames.iter().zip(4..) {
                assert!(f.image.as_slice() == decoded[i].as_slice(), "{format} {i}");
            }
        }
        let e = LiveVideo::new("vp8", "/cam").err().unwrap().to_string();
        assert!(e.contains("/cam: video in format \"vp8\""), "{e}");
    }

    #[test]
    fn a_live_stream_of_damaged_packets_gives_frames_or_an_error_never_a_hang() {
        // Bytes of a live stream's packets overwritten at random, as a bad
        // link leaves them: every push and the finish return, with frames
        // (at most one a packet) or an error naming the topic.
        // VP9's packets are framed by the toolkit (IVF), so a damaged one
        // cannot move the next one's start.
        let dir = tempfile::tempdir().unwrap();
        let (h264, _) = h264_without_b_frames(dir.path(), 3, 6);
        let (vp9, _) = encode_vp9(dir.path(), "yuv420p", 6);
        let mut rng = crate::rng::SampleRng::new(47, 0, 0);
        let mut outcomes = [0usize; 2];
        for round in 0..20 {
            let (format, packets) = match round < 12 {
                true => ("h264", &h264),
                false => ("vp9", &vp9),
            };
            let mut damaged = packets.clone();
            for _ in 0..1 + rng.index(8) {
                let p = rng.index(damaged.len());
                let at = rng.index(damaged[p].len());
                damaged[p][at] = rng.index(256) as u8;
            }
            let mut live = LiveVideo::new(format, "/cam").unwrap();
            let mut frames = 0;
            let ended = damaged
                .iter()
                .enumerate()
                .try_for_each(|(i, p)| {
                    frames += live.push(p, stamp_ns(i))?.len();
                    Ok::<_, Error>(())
                })
                .and_then(|()| live.finish().map(|rest| frames += rest.len()));
            match ended {
                Ok(()) => {
                    assert!(frames <= packets.len());
                    outcomes[0] += 1;
                }
                Err(e) => {
                    assert!(e.to_string().starts_with("/cam: "), "{e}");
                    outcomes[1] += 1;
                }
            }
        }
        assert!(outcomes[0] > 0, "{outcomes:?}");
    }

    #[test]
    fn video_that_cannot_be_decoded_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let (packets, _) = h264_without_b_frames(dir.path(), 50, 4);
        type Packets<'a> = Vec<(usize, &'a [u8])>;
        // Parameter sets that are not: no frame decodes.
        let garbage: &[u8] = &[
            0, 0, 0, 1, 0x67, 0xff, 0xff, 0xff, 0xff, 0, 0, 1, 0x65, 0xff,
        ];
        let cases: [(&str, Packets, &str); 4] = [
            (
                "vp8",
                vec![(0, &packets[0])],
                "topic /cam, message 0: video in format \"vp8\"; read are \"h264\" and \"h265\"",
            ),
            // No keyframe: the packets after the first.
            (
                "h264",
                packets[1..].iter().map(|p| (1, p.as_slice())).collect(),
                "topic /cam: none of its 3 messages is a keyframe of its h264 stream",
            ),
            (
                "h264",
                (0..3).map(|i| (i, garbage)).collect(),
                "topic /cam: FFmpeg decoded no frame of its 3 h264 packets",
            ),
            ("h264", vec![(0, &packets[0]), (1, DAMAGED)], ""),
        ];
        for (n, (format, packets, want)) in cases.into_iter().enumerate() {
            let path = dir.path().join(format!("{n}.mcap"));
            ros_bag(&path, "/cam", format, &packets);
            match read_all(&path, "/cam") {
                Err(e) => assert!(!want.is_empty() && e.to_string().contains(want), "{e}"),
                // A damaged packet after a keyframe: what decodes is read,
                // and a frame lost is said.
                Ok((frames, warnings)) => {
                    assert!(want.is_empty(), "{format}: {} frames", frames.len());
                    assert_eq!(frames.len(), 1);
                    assert_eq!(warnings.len(), 1, "{warnings:?}");
                    assert!(
                        warnings[0].contains("topic /cam: FFmpeg gave a frame for 1 of its 2 packets (a damaged packet gives none); messages that gave none: 1; every frame carries its own packet's stamp"),
                        "{}",
                        warnings[0]
                    );
                }
            }
        }
    }

    #[test]
    fn a_live_stream_that_gives_no_frame_says_why_as_a_bag_does() {
        // Before, each of these ended in FFmpeg's "Error marking filters as
        // finished" (exit status 1), even a decoder given no packet.
        let dir = tempfile::tempdir().unwrap();
        let (packets, _) = h264_without_b_frames(dir.path(), 50, 4);
        let garbage: &[u8] = &[
            0, 0, 0, 1, 0x67, 0xff, 0xff, 0xff, 0xff, 0, 0, 1, 0x65, 0xff,
        ];
        let mut nothing = LiveVideo::new("h264", "/cam").unwrap();
        assert!(nothing.finish().unwrap().is_empty());
        let cases: [(Vec<&[u8]>, &str); 2] = [
            (
                packets[1..].iter().map(Vec::as_slice).collect(),
                "/cam: none of its 3 messages is a keyframe of its h264 stream",
            ),
            (
                vec![garbage; 3],
                "/cam: FFmpeg decoded no frame of its 3 h264 packets",
            ),
        ];
        for (packets, want) in cases {
            let mut live = LiveVideo::new("h264", "/cam").unwrap();
            for (i, p) in packets.iter().enumerate() {
                assert!(live.push(p, stamp_ns(i)).unwrap().is_empty());
            }
            let e = live.finish().err().unwrap().to_string();
            assert!(e.starts_with(want), "{e}");
        }
    }

    #[test]
    fn a_video_frame_past_the_size_limit_is_refused_before_it_is_held() {
        // One keyframe of 7696x4320, a little past 8K UHD: refused from
        // the decoded picture's header, before its 100 MB are read.
        let dir = tempfile::tempdir().unwrap();
        let stream = dir.path().join("big.h264");
        let status = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
            .args(["-f", "lavfi", "-i", "color=c=gray:size=7696x4320"])
            .args(["-frames:v", "1", "-pix_fmt", "yuv420p"])
            .args(["-c:v", "libx264", "-preset", "ultrafast", "-f", "h264"])
            .arg(&stream)
            .status()
            .unwrap();
        assert!(status.success());
        let data = std::fs::read(&stream).unwrap();
        let path = dir.path().join("big.mcap");
        ros_bag(&path, "/cam", "h264", &[(0, &data)]);
        let e = read_all(&path, "/cam").err().unwrap().to_string();
        assert!(
            e.contains(&format!(
                "big.mcap: topic /cam: its video is 7696x4320, more than the {MAX_IMAGE_PIXELS} pixels a frame may have"
            )),
            "{e}"
        );
        // Live: the push or the finish says so, and the finish returns
        // (FFmpeg, left writing the picture to no one, is stopped).
        let mut live = LiveVideo::new("h264", "/cam").unwrap();
        live.timeouts = LIVE_TIMEOUTS;
        let pushed = live.push(&data, 0).map(|f| f.len());
        let e = pushed.and_then(|_| live.finish().map(|f| f.len()));
        let e = e.err().unwrap().to_string();
        assert!(e.contains("/cam: its video is 7696x4320"), "{e}");
    }

    #[test]
    fn damaged_packets_give_frames_or_an_error_never_a_hang() {
        // Bytes of the packets overwritten at random, as a bad link or
        // disk leaves them: each read ends, with frames (at most one a
        // packet) or an error naming the bag.
        let dir = tempfile::tempdir().unwrap();
        let (packets, _) = h264_without_b_frames(dir.path(), 3, 6);
        let mut rng = crate::rng::SampleRng::new(41, 0, 0);
        let path = dir.path().join("damaged.mcap");
        let mut outcomes = [0usize; 2];
        for _ in 0..24 {
            let mut damaged = packets.clone();
            for _ in 0..1 + rng.index(8) {
                let p = rng.index(damaged.len());
                let at = rng.index(damaged[p].len());
                damaged[p][at] = rng.index(256) as u8;
            }
            let all = numbered(&damaged);
            ros_bag(&path, "/cam", "h264", &all);
            match read_all(&path, "/cam") {
                Ok((frames, _)) => {
                    assert!(!frames.is_empty() && frames.len() <= packets.len());
                    outcomes[0] += 1;
                }
                Err(e) => {
                    assert!(e.to_string().contains("damaged.mcap: topic /cam"), "{e}");
                    outcomes[1] += 1;
                }
            }
        }
        assert!(outcomes[0] > 0, "{outcomes:?}");
    }

    #[test]
    fn mutated_video_bags_give_frames_or_errors_naming_the_file() {
        // The bag's own bytes mutated (random bytes, a cut, a length set
        // huge), as bag_mutations.rs does for image topics: each read of
        // the video topic ends in frames or an error naming the file.
        // VIDEO_MUTATION_ROUNDS=1200 runs longer (60 by default).
        let dir = tempfile::tempdir().unwrap();
        let (packets, _) = h264_without_b_frames(dir.path(), 2, 4);
        let good_path = dir.path().join("good.mcap");
        let all = numbered(&packets);
        ros_bag(&good_path, "/cam", "h264", &all);
        let good = std::fs::read(&good_path).unwrap();
        let path = dir.path().join("mutated.mcap");
        let mut rng = crate::rng::SampleRng::new(43, 0, 0);
        let rounds: usize = std::env::var("VIDEO_MUTATION_ROUNDS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(60);
        let mut outcomes = [0usize; 2];
        for round in 0..rounds {
            let mut b = good.clone();
            match round % 4 {
                0 | 1 => {
                    for _ in 0..1 + rng.index(4) {
                        let i = rng.index(b.len());
                        b[i] = rng.index(256) as u8;
                    }
                }
                2 => b.truncate(rng.index(b.len())),
                _ => {
                    let i = rng.index(b.len() - 8);
                    let v = [u64::MAX, 1 << 40, 1 << 31, 0xFFFF_FFFF][rng.index(4)];
                    b[i..i + 8].copy_from_slice(&v.to_le_bytes());
                }
            }
            std::fs::write(&path, &b).unwrap();
            match read_all(&path, "/cam") {
                Ok((frames, _)) => {
                    assert!(frames.len() <= packets.len());
                    outcomes[0] += 1;
                }
                Err(e) => {
                    assert!(e.to_string().contains("mutated.mcap"), "round {round}: {e}");
                    outcomes[1] += 1;
                }
            }
        }
        // Both kinds of ending are met (fixed seed).
        assert!(outcomes.iter().all(|&n| n > 0), "{outcomes:?}");
    }

    /// `frames` 64x64 frames of FFmpeg's Mandelbrot pattern in two-pass
    /// VP9 with alternate reference frames (superframes of an invisible
    /// frame and a shown one, each shown later by a packet of its own),
    /// and every frame as FFmpeg decodes them.
    fn vp9_with_hidden_frames(dir: &Path, frames: usize) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
        let stream = dir.join("hidden.ivf");
        let log = dir.join("vp9-passes");
        for pass in ["1", "2"] {
            let status = Command::new("ffmpeg")
                .args(["-nostdin", "-hide_banner", "-loglevel", "error", "-y"])
                .args(["-f", "lavfi", "-i", "mandelbrot=size=64x64:rate=10"])
                .args(["-frames:v", &frames.to_string(), "-pix_fmt", "yuv420p"])
                .args(["-c:v", "libvpx-vp9", "-g", "24", "-threads", "1"])
                .args(["-auto-alt-ref", "1", "-lag-in-frames", "25", "-b:v", "200k"])
                .args(["-pass", pass, "-passlogfile"])
                .arg(&log)
                .args(["-f", "ivf"])
                .arg(&stream)
                .status()
                .unwrap();
            assert!(status.success());
        }
        let packets = ivf_packets(&stream, b"VP90", frames);
        (packets, decode_file(&stream, (64, 64), frames))
    }

    #[test]
    fn parameter_sets_in_a_message_of_their_own_join_their_keyframe() {
        // An encoder that sends H.264's SPS and PPS (H.265's VPS, SPS and
        // PPS) in a message before each keyframe's picture: they join it,
        // so the stream starts at its first keyframe and every picture
        // keeps its own message's stamp, in a bag and live. Before, no
        // message was a keyframe with its parameter sets, and the topic
        // was refused.
        let dir = tempfile::tempdir().unwrap();
        let x265 = [
            "-c:v",
            "libx265",
            "-x265-params",
            "bframes=0:keyint=4:repeat-headers=1:log-level=error",
        ];
        for codec in [Codec::H264, Codec::H265] {
            let (packets, decoded) = match codec {
                Codec::H264 => h264_without_b_frames(dir.path(), 4, 12),
                _ => encode(dir.path(), &x265, 12),
            };
            parameter_sets_apart(dir.path(), codec, &packets, &decoded);
        }
    }

    /// NAL units as Annex B data, each after a `00 00 01` start code.
    fn annex_b<'a>(units: impl Iterator<Item = &'a [u8]>) -> Vec<u8> {
        units.flat_map(|u| [&[0, 0, 1][..], u].concat()).collect()
    }

    /// [`parameter_sets_in_a_message_of_their_own_join_their_keyframe`]
    /// for `codec`'s 12 `packets` (a keyframe every 4) and their frames.
    fn parameter_sets_apart(dir: &Path, codec: Codec, packets: &[Vec<u8>], decoded: &[Vec<u8>]) {
        let format = codec.name();
        let is_set = |u: &[u8]| u.first().is_some_and(|&h| codec.is_parameter_set(h));
        let (mut messages, mut own) = (Vec::new(), Vec::new());
        for p in packets {
            let sets = annex_b(nal_units(p).filter(|u| is_set(u)));
            if !sets.is_empty() {
                assert!(codec.parameter_sets_alone(&sets));
                messages.push(sets);
            }
            own.push(messages.len());
            messages.push(annex_b(nal_units(p).filter(|u| !is_set(u))));
        }
        assert_eq!(messages.len(), 15, "{format}");
        assert!(!codec.starts_stream(&messages[1]));
        let path = dir.join(format!("sets-{format}.mcap"));
        ros_bag(&path, "/cam", format, &numbered(&messages));
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(warnings.is_empty(), "{format}: {warnings:?}");
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = own.iter().map(|&m| (m as u64, stamp_ns(m))).collect();
        assert_eq!(got, want, "{format}");
        assert!((0..12).all(|k| frames[k].image.as_slice() == decoded[k].as_slice()));
        let mut live = LiveVideo::new(format, "/cam").unwrap();
        for (m, data) in messages.iter().enumerate() {
            let got: Vec<u64> = (live.push(data, stamp_ns(m)).unwrap().iter())
                .map(|f| f.packet)
                .collect();
            let want: &[u64] = if own.contains(&m) { &[m as u64] } else { &[] };
            assert_eq!(got, want, "{format} push {m}");
        }
        assert!(live.finish().unwrap().is_empty());
        assert_eq!((live.skipped(), live.lost()), (0, 0));
        // Sets sent apart before the second keyframe, which carries them
        // too: the same parameters, so no change of them is told.
        let mut twice = packets.to_vec();
        twice.insert(4, annex_b(nal_units(&packets[4]).filter(|u| is_set(u))));
        assert!(codec.parameter_sets_alone(&twice[4]) && codec.starts_stream(&twice[5]));
        let path = dir.join(format!("sets-twice-{format}.mcap"));
        ros_bag(&path, "/cam", format, &numbered(&twice));
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(
            frames.len() == 12 && warnings.is_empty(),
            "{format}: {warnings:?}"
        );
        // Begun mid-stream, after the first keyframe (the recording's
        // messages 0-2 are delta frames): they are skipped, and the stream
        // starts at the next keyframe's parameter sets (message 3), its
        // picture (message 4) the first frame.
        let late: Vec<(usize, &[u8])> = numbered(&messages).into_iter().skip(2).collect();
        let path = dir.join(format!("sets-late-{format}.mcap"));
        ros_bag(&path, "/cam", format, &late);
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert_eq!(frames.len(), 8);
        assert_eq!((frames[0].index, frames[0].stamp_ns), (4, stamp_ns(6)));
        assert!(
            warnings.len() == 1
                && warnings[0].contains("its first 3 messages come before the first keyframe")
                && warnings[0].ends_with("its frames begin at message 3"),
            "{warnings:?}"
        );
        let mut live = LiveVideo::new(format, "/cam").unwrap();
        let mut got = Vec::new();
        for &(m, data) in &late {
            got.extend(live.push(data, stamp_ns(m)).unwrap());
        }
        got.extend(live.finish().unwrap());
        assert_eq!((got.len(), got[0].packet, live.skipped()), (8, 4, 3));
    }

    #[test]
    fn keyframes_without_their_parameters_are_named_with_the_cure() {
        // An encoder that sends its parameter sets (AV1: its sequence
        // header) only at its start, recorded after it: the keyframes it
        // gives later cannot start a stream. Before, the error said only
        // that no message is a keyframe, though every few is one.
        let dir = tempfile::tempdir().unwrap();
        let (h264, decoded_h264) = h264_without_b_frames(dir.path(), 2, 6);
        let (av1, decoded_av1) = encode_av1(dir.path(), 8);
        let bare_h264 = |p: &[u8]| -> Vec<u8> {
            annex_b(
                nal_units(p)
                    .filter(|u| u.first().is_some_and(|&h| !Codec::H264.is_parameter_set(h))),
            )
        };
        // The OBUs but the sequence header (type 1), each with its size
        // field as libaom writes them.
        let bare_av1 = |mut p: &[u8]| -> Vec<u8> {
            let mut out = Vec::new();
            while let Some(&h) = p.first() {
                let (size, rest) = leb128(&p[1 + usize::from(h & 0x04 != 0)..]).unwrap();
                let len = p.len() - rest.len() + size;
                if (h >> 3) & 0x0f != 1 {
                    out.extend_from_slice(&p[..len]);
                }
                p = &p[len..];
            }
            out
        };
        let h264_bare: Vec<Vec<u8>> = h264.iter().map(|p| bare_h264(p)).collect();
        let av1_bare: Vec<Vec<u8>> = av1.iter().map(|p| bare_av1(p)).collect();
        assert_eq!(Codec::H264.keyframe(&h264[2]), Keyframe::Starts);
        assert_eq!(
            Codec::H264.keyframe(&h264_bare[2]),
            Keyframe::WithoutParameters
        );
        assert_eq!(Codec::H264.keyframe(&h264_bare[3]), Keyframe::No);
        assert_eq!(Codec::Av1.keyframe(&av1[3]), Keyframe::Starts);
        assert_eq!(
            Codec::Av1.keyframe(&av1_bare[3]),
            Keyframe::WithoutParameters
        );
        assert_eq!(Codec::Av1.keyframe(&av1_bare[4]), Keyframe::No);
        let cure = "the encoder sent it only at its start, before the first of these messages, so have it repeat it at every keyframe";
        // No keyframe with its parameters at all: refused, naming them.
        let refused = [
            (
                "h264",
                &h264_bare,
                format!(
                    "none of its 6 messages is a keyframe of its h264 stream (a random-access picture with its sequence parameter set), so no frame can be decoded; messages 0, 2, 4 are keyframes without their sequence parameter set: {cure} (x264's"
                ),
            ),
            (
                "av1",
                &av1_bare,
                format!(
                    "none of its 8 messages is a keyframe of its av1 stream (a key frame with its sequence header), so no frame can be decoded; messages 0, 3, 6 are keyframes without their sequence header: {cure}"
                ),
            ),
        ];
        for (format, packets, want) in refused {
            let path = dir.path().join(format!("bare-{format}.mcap"));
            ros_bag(&path, "/cam", format, &numbered(packets));
            let e = read_all(&path, "/cam").err().unwrap().to_string();
            assert!(e.contains(&want), "{e}");
            let mut live = LiveVideo::new(format, "/cam").unwrap();
            for (i, p) in packets.iter().enumerate() {
                assert!(live.push(p, stamp_ns(i)).unwrap().is_empty());
            }
            // Told as they come, before `finish`, for a node to log.
            assert_eq!(live.keyframes_without_parameters(), 3, "{format}");
            let e = live.finish().err().unwrap().to_string();
            assert!(e.contains(&want), "{e}");
        }
        // The encoder restarted with its parameters later on: the stream
        // starts there, and the warning names the keyframes before.
        let later = [
            (
                "h264",
                h264_bare[..4].iter().chain(&h264[4..]),
                4,
                &decoded_h264,
                "messages 0, 2 are keyframes without their sequence parameter set",
            ),
            (
                "av1",
                av1_bare[..3].iter().chain(&av1[3..]),
                3,
                &decoded_av1,
                "message 0 is a keyframe without its sequence header",
            ),
        ];
        for (format, packets, start, decoded, want) in later {
            let packets: Vec<Vec<u8>> = packets.cloned().collect();
            let path = dir.path().join(format!("bare-then-whole-{format}.mcap"));
            ros_bag(&path, "/cam", format, &numbered(&packets));
            let (frames, warnings) = read_all(&path, "/cam").unwrap();
            assert_eq!(frames.len(), packets.len() - start, "{format}");
            assert!(
                frames
                    .iter()
                    .zip(&decoded[start..])
                    .all(|(f, d)| f.image.as_slice() == d.as_slice())
            );
            assert!(
                warnings.len() == 1
                    && warnings[0].contains(&format!(
                        "its frames begin at message {start}; {want}: {cure}"
                    )),
                "{warnings:?}"
            );
        }
    }

    #[test]
    fn a_frame_of_a_packet_taken_to_show_none_takes_its_stamp() {
        // Should FFmpeg show a frame of a packet whose headers said it
        // shows none (a hidden frame read wrong), the frame takes that
        // packet's stamp by its time, or, with no time and no other packet
        // waiting, the earliest such packet's; never an error.
        let packet = |index: u64, hidden: bool| Stamp {
            segment: 0,
            stamp_ns: 100 + 10 * index as i64,
            index,
            log_time_ns: 0,
            pts: 10 * index as i64,
            hidden,
        };
        let mut pending = PendingStamps::default();
        pending.extend([packet(0, false), packet(1, true), packet(2, false)]);
        assert_eq!(pending.due(), 2);
        let taken: Vec<(u64, bool)> = [0, 10, 20]
            .iter()
            .map(|&t| pending.take(Some(t), 3).unwrap())
            .map(|t| (t.stamp.index, t.own))
            .collect();
        assert_eq!(taken, [(0, true), (1, true), (2, true)]);
        pending.add(packet(3, true));
        let last = pending.take(None, 4).unwrap();
        assert_eq!((last.stamp.index, last.own), (3, false));
        assert!(
            pending
                .take(None, 4)
                .unwrap_err()
                .contains("more frames than")
        );
    }

    #[test]
    fn packets_that_show_no_frame_are_owed_none() {
        // An encoder's invisible VP9 frames as messages of their own (as
        // libvpx gives them when no muxer merges them into superframes):
        // each shows no frame, so it is not waited for nor counted lost,
        // and every frame keeps its own packet's stamp. Before, the bag
        // warned that the invisible ones were damaged, and live, each
        // waited a second; after the third, every later frame came only
        // at the finish.
        let dir = tempfile::tempdir().unwrap();
        let (superframes, decoded) = vp9_with_hidden_frames(dir.path(), 24);
        let mut packets: Vec<Vec<u8>> = Vec::new();
        for p in &superframes {
            packets.extend(vp9_frames(p).map(<[u8]>::to_vec));
        }
        let shown: Vec<usize> = (0..packets.len())
            .filter(|&i| Codec::Vp9.shows_frame(&packets[i]))
            .collect();
        assert_eq!(shown.len(), 24);
        assert!(packets.len() >= 26, "{} packets", packets.len());
        let path = dir.path().join("hidden.mcap");
        ros_bag(&path, "/cam", "vp9", &numbered(&packets));
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = shown.iter().map(|&i| (i as u64, stamp_ns(i))).collect();
        assert_eq!(got, want);
        for (k, f) in frames.iter().enumerate() {
            assert!(f.image.as_slice() == decoded[k].as_slice(), "frame {k}");
        }
        let mut live = LiveVideo::new("vp9", "/cam").unwrap();
        for (i, p) in packets.iter().enumerate() {
            let started = std::time::Instant::now();
            let got: Vec<u64> = live
                .push(p, stamp_ns(i))
                .unwrap()
                .iter()
                .map(|f| f.packet)
                .collect();
            let want: &[u64] = if shown.contains(&i) { &[i as u64] } else { &[] };
            assert_eq!(got, want, "push {i}");
            assert!(started.elapsed().as_secs_f64() < 0.5, "push {i}");
        }
        assert!(live.finish().unwrap().is_empty());
        assert_eq!(live.lost(), 0);
        // AV1 with hidden frames, each temporal unit a message as the
        // format asks: every frame its own packet's. Alone (a unit cut
        // after its first frame OBU, hidden), they show none.
        let libaom = [
            "-c:v",
            "libaom-av1",
            "-cpu-used",
            "8",
            "-g",
            "24",
            "-threads",
            "1",
        ];
        let stream = encode_file(
            (dir.path(), "hidden.obu"),
            "yuv420p",
            (64, 64),
            12,
            &[&libaom, &["-lag-in-frames", "35"]],
            "obu",
        );
        let data = std::fs::read(&stream).unwrap();
        let decoded = decode_file(&stream, (64, 64), 12);
        let mut units: Vec<Vec<u8>> = Vec::new();
        let mut hidden_alone = None;
        let mut at = 0;
        for (kind, payload) in av1_obus(&data) {
            let end = payload.as_ptr() as usize - data.as_ptr() as usize + payload.len();
            if kind == 2 {
                units.push(Vec::new());
            }
            let unit = units.last_mut().unwrap();
            let first_frame = matches!(kind, 3 | 6) && !Codec::Av1.shows_frame(unit);
            unit.extend_from_slice(&data[at..end]);
            if first_frame && payload[0] & 0x90 == 0 && hidden_alone.is_none() {
                hidden_alone = Some(unit.clone());
            }
            at = end;
        }
        assert_eq!(units.len(), 12);
        let hidden_alone = hidden_alone.expect("a hidden frame");
        assert!(!Codec::Av1.shows_frame(&hidden_alone));
        assert!(units.iter().all(|u| Codec::Av1.shows_frame(u)));
        let path = dir.path().join("hidden-av1.mcap");
        ros_bag(&path, "/cam", "av1", &numbered(&units));
        let (frames, warnings) = read_all(&path, "/cam").unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let got: Vec<i64> = frames.iter().map(|f| f.stamp_ns).collect();
        assert_eq!(got, (0..12).map(stamp_ns).collect::<Vec<_>>());
        assert!((0..12).all(|k| frames[k].image.as_slice() == decoded[k].as_slice()));
        let mut live = LiveVideo::new("av1", "/cam").unwrap();
        for (i, u) in units.iter().enumerate() {
            let got = live.push(u, stamp_ns(i)).unwrap();
            assert_eq!(got.len(), 1, "push {i}");
            assert!(got[0].image.as_slice() == decoded[i].as_slice(), "push {i}");
        }
        // H.264's parameter sets alone show none; with a picture, they do.
        let (h264, _) = h264_without_b_frames(dir.path(), 50, 2);
        let idr = nal_units(&h264[0])
            .position(|u| u.first().is_some_and(|&h| h & 0x1f == 5))
            .unwrap();
        let sets = annex_b(nal_units(&h264[0]).take(idr));
        assert!(!Codec::H264.shows_frame(&sets));
        assert!(Codec::H264.shows_frame(&h264[0]));
        assert!(Codec::H264.shows_frame(&h264[1]));
        assert!(Codec::Vp9.shows_frame(&[]) && Codec::H264.shows_frame(&[]));
    }

    #[test]
    fn av1_video_is_read_from_a_bag_and_live() {
        // AV1 as the Foxglove SDK's format has it (low overhead OBUs, a
        // temporal unit per message, the sequence header with each key
        // frame), begun after the first key frame; every other message
        // without its temporal delimiter, as a recorder that drops them
        // writes it.
        let dir = tempfile::tempdir().unwrap();
        let (packets, decoded) = encode_av1(dir.path(), 8);
        assert!(Codec::Av1.starts_stream(&packets[3]));
        assert!(!Codec::Av1.starts_stream(&packets[4]));
        let stripped: Vec<&[u8]> = packets
            .iter()
            .enumerate()
            .map(|(i, p)| match i % 2 {
                0 => &p[..],
                _ => without_temporal_delimiter(p),
            })
            .collect();
        read_begun_mid_stream(dir.path(), "av1", "libaom-av1", &stripped, &decoded);
    }

    #[test]
    fn vp9_video_is_read_from_a_bag_and_live() {
        // VP9 as the Foxglove SDK's format has it (a frame per message),
        // begun after the first key frame.
        let dir = tempfile::tempdir().unwrap();
        let (packets, decoded) = encode_vp9(dir.path(), "yuv420p", 8);
        // Key frames of every profile (0: 4:2:0 8-bit, 1: 4:4:4, 3:
        // 4:4:4 10-bit, whose header has one bit more) start a stream;
        // the frames after them do not.
        for (pix_fmt, profile) in [("yuv444p", 1), ("yuv444p10le", 3)] {
            let (p, _) = encode_vp9(dir.path(), pix_fmt, 2);
            assert_eq!((p[0][0] >> 4) & 0b11, [0b00, 0b10, 0b01, 0b11][profile]);
            assert!(Codec::Vp9.starts_stream(&p[0]), "{pix_fmt}");
            assert!(!Codec::Vp9.starts_stream(&p[1]), "{pix_fmt}");
        }
        assert!(Codec::Vp9.starts_stream(&packets[3]));
        assert!(!Codec::Vp9.starts_stream(&packets[4]));
        assert!(!Codec::Vp9.starts_stream(&packets[3][..4]));
        let packets: Vec<&[u8]> = packets.iter().map(Vec::as_slice).collect();
        read_begun_mid_stream(dir.path(), "vp9", "libvpx-vp9", &packets, &decoded);
    }

    #[test]
    fn video_resized_on_inter_frames_comes_at_its_display_size() {
        // Real-time encoders at a low bitrate (WebRTC's adaptive streams)
        // shrink the picture on inter frames: libvpx's VP9 and libaom's
        // AV1 with dynamic resizing, 640x480 from the key frame, 480x360
        // from frame 60 (and VP9 320x240 from frame 90), of FFmpeg's
        // `testsrc` (`tests/data/README.md` says how they were made). Each
        // resized frame declares the key frame's 640x480 as its display
        // size (render_size), so each frame comes at 640x480 with its own
        // stamp, in a bag and live, nothing lost or counted as scaled past
        // the decoders' limit.
        let (w, h) = (640, 480);
        let source = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
            .args(["-f", "lavfi", "-i", "testsrc=size=640x480:rate=30"])
            .args([
                "-frames:v",
                "96",
                "-f",
                "rawvideo",
                "-pix_fmt",
                "rgb24",
                "-",
            ])
            .output()
            .unwrap()
            .stdout;
        let source: Vec<&[u8]> = source.chunks(w * h * 3).collect();
        let mean_error = |a: &[u8], b: &[u8]| {
            let sum: f64 = a
                .iter()
                .zip(b)
                .map(|(x, y)| f64::from(x.abs_diff(*y)))
                .sum();
            sum / a.len() as f64
        };
        let dir = tempfile::tempdir().unwrap();
        for (name, codec, tag, encoder, frames) in [
            ("vp9", Codec::Vp9, b"VP90", "libvpx-vp9", 96),
            ("av1", Codec::Av1, b"AV01", "libaom-av1", 72),
        ] {
            let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("tests/data/{name}-resized-inter-frames.ivf"));
            let packets = ivf_packets(&fixture, tag, frames);
            // One key frame: the size changes come on inter frames.
            let keys: Vec<usize> = (0..frames)
                .filter(|&i| codec.starts_stream(&packets[i]))
                .collect();
            assert_eq!(keys, [0], "{name}");
            let decoded = decode_file(&fixture, (w, h), frames);
            // FFmpeg's pictures are the source's at full size after each
            // resize too, not a corner of them or an older frame.
            for (i, d) in decoded.iter().enumerate() {
                let error = mean_error(d, source[i]);
                assert!(error < 10.0, "{name} {i}: mean error {error:.1}");
                if i >= 30 {
                    let earlier = mean_error(d, source[i - 30]);
                    assert!(error < earlier, "{name} {i}: nearer a second before");
                }
            }
            let topic = format!("/cam/{name}");
            let path = dir.path().join(format!("{name}.mcap"));
            let all = numbered(&packets);
            ros_bag(&path, &topic, name, &all);
            let (bag, warnings) = read_all(&path, &topic).unwrap();
            assert!(warnings.is_empty(), "{name}: {warnings:?}");
            assert_eq!(bag.len(), frames, "{name}");
            for (i, f) in bag.iter().enumerate() {
                assert_eq!((f.index, f.stamp_ns), (i as u64, stamp_ns(i)), "{name}");
                assert_eq!((f.image.width(), f.image.height()), (w, h), "{name} {i}");
                assert!(f.image.as_slice() == decoded[i].as_slice(), "{name} {i}");
            }
            let mut live = LiveVideo::new(encoder, &topic).unwrap();
            for (i, p) in all {
                let got = live.push(p, stamp_ns(i)).unwrap();
                assert_eq!(got.len(), 1, "{name} live {i}");
                assert_eq!(got[0].stamp_ns, stamp_ns(i), "{name} live {i}");
                let pixels = got[0].image.as_slice();
                assert!(pixels == decoded[i].as_slice(), "{name} live {i}");
            }
            assert!(live.finish().unwrap().is_empty(), "{name}");
            assert_eq!((live.lost(), live.scaled()), (0, 0), "{name}");
        }
    }

    /// `packets` (a keyframe every 3) from the second on, as a bag's topic
    /// of `format` and live (to the decoder of `encoder`, named as
    /// `ffmpeg_image_transport` names it): the frames from the keyframe at
    /// 3 on, each FFmpeg's decode (`decoded`) with its own stamp, the two
    /// messages before it skipped with a warning, and each live frame back
    /// from its own push.
    fn read_begun_mid_stream(
        dir: &Path,
        format: &str,
        encoder: &str,
        packets: &[&[u8]],
        decoded: &[Vec<u8>],
    ) {
        let topic = format!("/cam/{format}");
        let path = dir.join(format!("{format}.mcap"));
        let late: Vec<(usize, &[u8])> = packets.iter().copied().enumerate().skip(1).collect();
        ros_bag(&path, &topic, format, &late);
        let (frames, warnings) = read_all(&path, &topic).unwrap();
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = (3..packets.len())
            .map(|i| (i as u64 - 1, stamp_ns(i)))
            .collect();
        assert_eq!(got, want, "{format}");
        for (f, i) in frames.iter().zip(3..) {
            assert!(f.image.as_slice() == decoded[i].as_slice(), "{format} {i}");
        }
        let skipped =
            format!("its first 2 messages come before the first keyframe of its {format} stream");
        assert!(warnings[0].contains(&skipped), "{warnings:?}");
        let mut live = LiveVideo::new(encoder, &topic).unwrap();
        for (i, p) in late {
            let got = live.push(p, stamp_ns(i)).unwrap();
            let want: Vec<i64> = match i {
                1 | 2 => vec![],
                _ => vec![stamp_ns(i)],
            };
            let stamps: Vec<i64> = got.iter().map(|f| f.stamp_ns).collect();
            assert_eq!(stamps, want, "{format} live {i}");
            for f in &got {
                assert!(
                    f.image.as_slice() == decoded[i].as_slice(),
                    "{format} live {i}"
                );
            }
        }
        assert_eq!(live.skipped(), 2);
        assert!(live.finish().unwrap().is_empty());
    }

    #[test]
    fn h264_in_compressed_image_messages_is_read_as_video() {
        // As GStreamer's ROS 2 sink publishes H.264: a sensor_msgs
        // CompressedImage per packet, format "h264", begun mid-stream.
        // Before, each message was refused as an image it is not.
        let dir = tempfile::tempdir().unwrap();
        let (packets, decoded) = h264_without_b_frames(dir.path(), 3, 6);
        let path = dir.path().join("compressed.mcap");
        let write = |format: fn(usize) -> &'static str| {
            let late = numbered(&packets)[1..].to_vec();
            cdr_bag(
                &path,
                "/cam/compressed",
                COMPRESSED_IMAGE_TYPE,
                &late,
                |i, data| {
                    to_cdr(&CompressedImage {
                        header: Header {
                            stamp: Time::from_nanos(stamp_ns(i)),
                            frame_id: "cam".into(),
                        },
                        format: format(i).into(),
                        data,
                    })
                },
            )
        };
        write(|_| "h264");
        let (frames, warnings) = read_all(&path, "/cam/compressed").unwrap();
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = (3..6).map(|i| (i as u64 - 1, stamp_ns(i))).collect();
        assert_eq!(got, want);
        for (f, i) in frames.iter().zip(3..) {
            assert!(f.image.as_slice() == decoded[i].as_slice(), "frame {i}");
        }
        assert!(warnings[0].contains("its first 2 messages"), "{warnings:?}");
        // A JPEG among the packets: named, not decoded as video.
        write(|i| match i {
            5 => "jpeg",
            i if i % 2 == 0 => " H264",
            _ => "h264",
        });
        let e = read_all(&path, "/cam/compressed")
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("topic /cam/compressed, message 4: format \"jpeg\" after \"h264\" ones"),
            "{e}"
        );
    }

    #[test]
    fn a_stream_whose_parameters_change_gives_each_frame_at_its_own_size() {
        // A camera restarted at another size within one recording: three
        // frames at 64x64, then a keyframe with new parameters (H.264's
        // SPS; VP9's key frame size; AV1's sequence header) and three at
        // 96x48. Before, one FFmpeg process scaled the last three to 64x64.
        let dir = tempfile::tempdir().unwrap();
        let x264 = ["-c:v", "libx264", "-bf", "0", "-g", "50"];
        for codec in ["h264", "vp9", "av1"] {
            let (mut packets, mut decoded, mut sizes) = (Vec::new(), Vec::new(), Vec::new());
            for size in [(64, 64), (96, 48)] {
                let (p, d) = match codec {
                    "h264" => encode_sized(dir.path(), &x264, 3, size),
                    "vp9" => encode_vp9_sized(dir.path(), "yuv420p", 3, size),
                    _ => encode_av1_sized(dir.path(), 3, size),
                };
                packets.extend(p);
                decoded.extend(d);
                sizes.extend([size; 3]);
            }
            let path = dir.path().join(format!("{codec}.mcap"));
            let all = numbered(&packets);
            ros_bag(&path, "/cam", codec, &all);
            let (frames, warnings) = read_all(&path, "/cam").unwrap();
            assert_eq!(frames.len(), 6, "{codec}");
            for (i, f) in frames.iter().enumerate() {
                assert_eq!((f.image.width(), f.image.height()), sizes[i], "{codec} {i}");
                assert!(f.image.as_slice() == decoded[i].as_slice(), "{codec} {i}");
                assert_eq!(
                    (f.index, f.stamp_ns),
                    (i as u64, stamp_ns(i)),
                    "{codec} {i}"
                );
            }
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(
                warnings[0].contains(&format!(
                    "its {codec} stream's parameters change at message 3"
                )),
                "{warnings:?}"
            );
            // Live: each push gives its own frame, at its own size.
            let mut live = LiveVideo::new(codec, "/cam").unwrap();
            for (i, p) in packets.iter().enumerate() {
                let got = live.push(p, stamp_ns(i)).unwrap();
                assert_eq!(got.len(), 1, "{codec} live {i}");
                assert_eq!(got[0].stamp_ns, stamp_ns(i));
                let size = (got[0].image.width(), got[0].image.height());
                assert_eq!(size, sizes[i], "{codec} live {i}");
                assert!(got[0].image.as_slice() == decoded[i].as_slice());
            }
            assert!(live.finish().unwrap().is_empty());
        }
    }

    /// The frame sizes of an H.264 stream of `parts`, `frames` each, read
    /// from a bag and live: the bag's sizes and warnings, the live sizes
    /// and [`LiveVideo::scaled`].
    #[allow(clippy::type_complexity)]
    fn sizes_of_parts(
        parts: &[(usize, usize)],
        frames: usize,
    ) -> (Vec<(usize, usize)>, Vec<String>, Vec<(usize, usize)>, u64) {
        let dir = tempfile::tempdir().unwrap();
        let x264 = ["-c:v", "libx264", "-bf", "0", "-g", "50"];
        let packets: Vec<Vec<u8>> = parts
            .iter()
            .flat_map(|&size| encode_sized(dir.path(), &x264, frames, size).0)
            .collect();
        let size = |f: &RgbImage| (f.width(), f.height());
        let path = dir.path().join("changing.mcap");
        ros_bag(&path, "/cam", "h264", &numbered(&packets));
        let (bag, warnings) = read_all(&path, "/cam").unwrap();
        let bag = bag.iter().map(|f| size(&f.image)).collect();
        let mut live = LiveVideo::new("h264", "/cam").unwrap();
        let mut got = Vec::new();
        for (i, p) in packets.iter().enumerate() {
            let frames = live.push(p, stamp_ns(i)).unwrap();
            got.extend(frames.iter().map(|f| size(&f.image)));
        }
        got.extend(live.finish().unwrap().iter().map(|f| size(&f.image)));
        (bag, warnings, got, live.scaled())
    }

    #[test]
    fn a_stream_whose_parameters_keep_changing_starts_at_most_the_limit_of_decoders() {
        // Four parts of two frames, alternating 64x64 and 96x48: three
        // changes of parameters, at messages 2, 4 and 6, past the limit of
        // two new decoders in unit tests (64 otherwise) before eight
        // packets (32 otherwise) earn a third. The first two begin new
        // decoders; the last part is decoded by the last one, scaled to
        // its 64x64, and the warning says so; live, `scaled` counts it.
        let sizes = [(64, 64), (96, 48), (64, 64), (96, 48)];
        let want: Vec<(usize, usize)> = [(64, 64), (96, 48), (64, 64), (64, 64)]
            .iter()
            .flat_map(|&s| [s, s])
            .collect();
        let (bag, warnings, live, scaled) = sizes_of_parts(&sizes, 2);
        assert_eq!(bag, want);
        assert!(
            warnings[0].contains("parameters change at messages 2, 4, 6 (")
                && warnings[0].contains(
                    "2 began a new decoder; the frames after the changes at message 6 (more than one per 8 messages, past the first 2 changes) were decoded by the decoder before, scaled to its size"
                ),
            "{warnings:?}"
        );
        assert_eq!((live, scaled), (want, 1));
    }

    #[test]
    fn a_camera_restarted_at_another_size_again_and_again_keeps_every_frames_size() {
        // Five parts of eight frames, alternating 64x64 and 96x48: four
        // changes, twice the two decoders a stream may start at once in
        // unit tests, but no more than one per eight packets, so each
        // earns its own decoder. Before, a stream started at most the
        // limit, and the frames of the last two parts were scaled.
        let sizes = [(64, 64), (96, 48), (64, 64), (96, 48), (64, 64)];
        let want: Vec<(usize, usize)> = sizes.iter().flat_map(|&s| [s; 8]).collect();
        let (bag, warnings, live, scaled) = sizes_of_parts(&sizes, 8);
        assert_eq!(bag, want);
        assert!(
            warnings[0].contains("parameters change at messages 8, 16, 24, 32 (")
                && warnings[0].contains("each part was decoded on its own"),
            "{warnings:?}"
        );
        assert_eq!((live, scaled), (want, 0));
    }

    #[test]
    fn h264_image_transport_packets_are_read() {
        // As h264_image_transport's camera node publishes a V4L2 camera's
        // H.264: each packet with its header stamp and sequence number.
        let dir = tempfile::tempdir().unwrap();
        let (packets, decoded) = h264_without_b_frames(dir.path(), 3, 5);
        let all = numbered(&packets);
        let path = dir.path().join("h264.mcap");
        cdr_bag(
            &path,
            "/image_raw/h264",
            H264_PACKET_TYPE,
            &all,
            |i, data| {
                to_cdr(&H264Packet {
                    header: Header {
                        stamp: Time::from_nanos(stamp_ns(i)),
                        frame_id: "camera_frame".into(),
                    },
                    seq: 100 + i as i64,
                    data,
                })
            },
        );
        assert_eq!(
            image_topics(&path).unwrap()[0].message_type,
            H264_PACKET_TYPE
        );
        let (frames, warnings) = read_all(&path, "/image_raw/h264").unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
        let want: Vec<(u64, i64)> = (0..5).map(|i| (i as u64, stamp_ns(i))).collect();
        assert_eq!(got, want);
        for (f, want) in frames.iter().zip(&decoded) {
            assert!(f.image.as_slice() == want.as_slice());
        }
    }

    #[test]
    fn ffmpeg_image_transport_packets_are_read() {
        // As ROS 2's ffmpeg_image_transport publishes: its current
        // `encoding` ("codec;pixel formats…") and its older one (the
        // encoder's name), each begun mid-stream.
        let dir = tempfile::tempdir().unwrap();
        let (packets, decoded) = h264_without_b_frames(dir.path(), 3, 8);
        let late = numbered(&packets)[1..].to_vec();
        // The packets as FFMPEGPackets of `encoding` on /cam/ffmpeg.
        let path = dir.path().join("ffmpeg.mcap");
        let write = |encoding: &str| {
            cdr_bag(
                &path,
                "/cam/ffmpeg",
                FFMPEG_PACKET_TYPE,
                &late,
                |i, data| {
                    to_cdr(&FfmpegPacket {
                        header: Header {
                            stamp: Time::from_nanos(stamp_ns(i)),
                            frame_id: "cam".into(),
                        },
                        width: 64,
                        height: 64,
                        encoding: encoding.into(),
                        pts: i as u64,
                        flags: u8::from(i % 3 == 0),
                        is_bigendian: false,
                        data,
                    })
                },
            )
        };
        for encoding in ["h264;yuv420p;bgr8;bgr8", "libx264", "h264_nvenc"] {
            write(encoding);
            assert_eq!(
                image_topics(&path).unwrap()[0].message_type,
                FFMPEG_PACKET_TYPE
            );
            let (frames, warnings) = read_all(&path, "/cam/ffmpeg").unwrap();
            // Messages 0 and 1 (packets 1 and 2) precede the keyframe.
            let got: Vec<(u64, i64)> = frames.iter().map(|f| (f.index, f.stamp_ns)).collect();
            let want: Vec<(u64, i64)> = (3..8).map(|i| (i as u64 - 1, stamp_ns(i))).collect();
            assert_eq!(got, want, "{encoding}");
            for (f, i) in frames.iter().zip(3..) {
                assert!(
                    f.image.as_slice() == decoded[i].as_slice(),
                    "{encoding} {i}"
                );
            }
            assert!(warnings[0].contains("its first 2 messages"), "{warnings:?}");
        }
        // An encoder of another codec: refused by name.
        write("libvpx");
        let e = read_all(&path, "/cam/ffmpeg").err().unwrap().to_string();
        assert!(e.contains("video in format \"libvpx\""), "{e}");
    }
}
