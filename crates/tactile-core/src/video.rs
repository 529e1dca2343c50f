//! Video in and out through the system's FFmpeg, driven as a process: it
//! decodes any container and codec it knows (mp4, mkv, avi; H.264, MJPEG,
//! ...) and a V4L2 camera to raw RGB frames on a pipe, which are read here
//! one frame at a time. No codec is written here.
//!
//! The size of the stream is read with `ffprobe` first and checked against
//! [`MAX_IMAGE_PIXELS`] before any frame buffer is allocated. Frames are
//! read as they are shown: a stream's display rotation (a phone's video
//! recorded upright) is applied, as FFmpeg's own command line and OpenCV's
//! `VideoCapture` apply it, and as a frame file's EXIF orientation is
//! ([`crate::image_io`]). Inputs are
//! passed as `file:` URLs, so a file name is never taken for an option or
//! another protocol; a network stream's URL ([`StreamUrl`]) is opened with
//! only network protocols allowed, so nothing it leads to reads a file.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};

use crate::image_io::{MAX_IMAGE_PIXELS, RgbImage, rgb_image};
use crate::{Error, Result};

/// What to install when FFmpeg is missing.
const INSTALL_HINT: &str = "reading video needs FFmpeg (ffmpeg and ffprobe on PATH); on Debian or Ubuntu: apt-get install ffmpeg";

/// How much of FFmpeg's stderr is kept for an error message.
const STDERR_TAIL: usize = 4096;

/// An FFmpeg tool that could not be started for `path`: missing (say how
/// to install it) or another I/O failure.
pub(crate) fn spawn_error(path: &Path, e: std::io::Error) -> Error {
    match e.kind() {
        std::io::ErrorKind::NotFound => Error::Invalid(INSTALL_HINT.into()),
        _ => Error::io(path, e),
    }
}

/// FFmpeg's options that keep every decoded frame as it is, none dropped
/// or repeated to make a rate: the global ones (before the outputs) and
/// each output's. `-fps_mode passthrough` since FFmpeg 5.1; before it
/// (Ubuntu 22.04's 4.4, which ROS 2 Humble runs on) the global `-vsync
/// passthrough`, which 5.1 on still reads but calls deprecated.
pub(crate) fn passthrough_options() -> (&'static [&'static str], &'static [&'static str]) {
    match ffmpeg_release().is_none_or(|r| r >= (5, 1)) {
        true => (&[], &["-fps_mode", "passthrough"]),
        false => (&["-vsync", "passthrough"], &[]),
    }
}

/// `-enc_time_base`'s value for the demuxer's time base: `demux` since
/// FFmpeg 6.1, which calls the older `-1` deprecated.
pub(crate) fn demuxer_time_base() -> &'static str {
    match ffmpeg_release().is_none_or(|r| r >= (6, 1)) {
        true => "demux",
        false => "-1",
    }
}

/// The system FFmpeg's release (major, minor), read once from `ffmpeg
/// -version`; `None` for a build from git or a line not understood, which
/// is taken as new.
fn ffmpeg_release() -> Option<(u32, u32)> {
    static RELEASE: std::sync::OnceLock<Option<(u32, u32)>> = std::sync::OnceLock::new();
    *RELEASE.get_or_init(|| {
        let out = Command::new("ffmpeg")
            .arg("-version")
            .stdin(Stdio::null())
            .stderr(Stdio::null())
            .output()
            .ok()?;
        release_of(&String::from_utf8_lossy(&out.stdout))
    })
}

/// The release `ffmpeg -version`'s first line names ("ffmpeg version
/// 4.4.2-0ubuntu0.22.04.1", "n4.4", "7.1"), or `None` ("N-112233-g…").
fn release_of(version: &str) -> Option<(u32, u32)> {
    let release = version.lines().next()?.strip_prefix("ffmpeg version ")?;
    let mut numbers = release
        .trim_start_matches('n')
        .split(|c: char| !c.is_ascii_digit())
        .map(str::parse::<u32>);
    let major = numbers.next()?.ok()?;
    let minor = numbers.next().and_then(Result::ok).unwrap_or(0);
    Some((major, minor))
}

/// True when `ffmpeg` and `ffprobe` run.
pub fn ffmpeg_available() -> bool {
    ["ffmpeg", "ffprobe"].iter().all(|tool| {
        Command::new(tool)
            .arg("-version")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

/// A video file's path as an FFmpeg input that cannot be read as an option
/// or a protocol.
fn file_url(path: &Path) -> Result<String> {
    let abs = std::path::absolute(path).map_err(|e| Error::io(path, e))?;
    let s = abs.to_str().ok_or_else(|| {
        Error::image(
            path,
            "the path is not valid UTF-8, which FFmpeg cannot be given",
        )
    })?;
    Ok(format!("file:{s}"))
}

/// The URL schemes read as a network stream: an IP camera's RTSP, a
/// camera served over HTTP (an MJPEG server on the robot's computer, an
/// HLS playlist), RTMP, SRT, or raw UDP, RTP or TCP.
pub const STREAM_SCHEMES: [&str; 10] = [
    "rtsp", "rtsps", "http", "https", "rtmp", "rtmps", "srt", "udp", "rtp", "tcp",
];

/// The protocols FFmpeg may open for a stream (`-protocol_whitelist`):
/// those of [`STREAM_SCHEMES`] and what they run on. A playlist or a
/// session that points at `file:`, `concat:` or `pipe:` is refused by
/// FFmpeg, so a URL never reads a file of this machine.
const STREAM_PROTOCOLS: &str =
    "rtsp,rtsps,http,https,httpproxy,rtmp,rtmps,rtmpt,rtmpts,srt,udp,rtp,srtp,tcp,tls,crypto";

/// How long a stream may send nothing before FFmpeg gives up, µs.
const STREAM_SILENCE_US: &str = "10000000";

/// The longest URL read, bytes: a signed URL with its tokens is a few
/// kilobytes; web servers refuse request lines past 8 KiB.
pub const MAX_URL_BYTES: usize = 16 * 1024;

/// How long a stream's probe may take before it is given up.
const STREAM_PROBE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30);

/// A network stream's URL, and the same URL as messages show it: with its
/// password, if it has one, hidden (`rtsp://admin:***@cam/stream`), as a
/// message may be pasted into an issue.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamUrl {
    url: String,
    shown: PathBuf,
}

impl StreamUrl {
    /// `text` as a stream's URL: `Ok(None)` when it is no URL
    /// (`scheme://…`), an error saying what is read when its scheme is
    /// not one of [`STREAM_SCHEMES`] (`file://`, `ftp://`).
    pub fn parse(text: &str) -> Result<Option<Self>> {
        let Some((scheme, rest)) = text.split_once("://") else {
            return Ok(None);
        };
        let is_scheme = scheme
            .bytes()
            .next()
            .is_some_and(|b| b.is_ascii_alphabetic())
            && scheme
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'+' | b'-' | b'.'));
        if !is_scheme {
            return Ok(None);
        }
        let shown = hide_password(scheme, rest);
        if !is_stream_scheme(scheme) {
            let what = match scheme.eq_ignore_ascii_case("file") {
                true => "give the file's path itself".to_string(),
                false => format!(
                    "a stream is read from {} URLs (through FFmpeg); fetch anything else first",
                    STREAM_SCHEMES.map(|s| format!("{s}://")).join(", ")
                ),
            };
            return Err(Error::Invalid(format!(
                "{}: {scheme}:// URLs are not read: {what}",
                crate::printable(&shown)
            )));
        }
        if text.len() > MAX_URL_BYTES {
            let start: String = shown.chars().take(60).collect();
            return Err(Error::Invalid(format!(
                "{}…: a URL of {} bytes; at most {MAX_URL_BYTES} are read",
                crate::printable(&start),
                text.len()
            )));
        }
        if text.chars().any(|c| c.is_control() || c.is_whitespace()) {
            return Err(Error::Invalid(format!(
                "{}: a URL holds no spaces or control characters (write a space as %20)",
                crate::printable(&shown)
            )));
        }
        // A scheme is read in any case (RFC 3986); FFmpeg knows its
        // protocols in lower case alone.
        Ok(Some(Self {
            url: format!("{}://{rest}", scheme.to_ascii_lowercase()),
            shown: PathBuf::from(shown),
        }))
    }

    /// The URL as messages show it (its password hidden).
    pub fn shown(&self) -> &Path {
        &self.shown
    }

    /// FFmpeg's words with the URL in them shown as messages show it.
    fn hide_in(&self, words: &str) -> String {
        words.replace(&self.url, &self.shown.to_string_lossy())
    }

    /// FFmpeg's options for it: only network protocols, and a silence
    /// after which it gives up: every protocol's `-rw_timeout`, and the
    /// `-timeout` of those that read it as one (RTSP's demuxer, UDP, RTP,
    /// SRT and TCP, which ignore the other; RTMP's `-timeout` would make it
    /// listen instead, HTTP has none).
    fn input_args(&self) -> Vec<String> {
        // Lower case since `parse`.
        let scheme = self.url.split_once("://").map_or("", |(s, _)| s);
        let mut args = vec![
            "-protocol_whitelist".to_string(),
            STREAM_PROTOCOLS.into(),
            "-rw_timeout".into(),
            STREAM_SILENCE_US.into(),
        ];
        if ["rtsp", "rtsps", "udp", "rtp", "srt", "tcp"].contains(&scheme) {
            args.extend(["-timeout".into(), STREAM_SILENCE_US.into()]);
        }
        args.extend(["-i".into(), self.url.clone()]);
        args
    }
}

/// The error of a path that names nothing and is a stream's URL with a
/// slash of its `//` lost (`rtsp:/cam/stream`): Python's `pathlib.Path`,
/// and so argparse's `type=Path`, collapse `//`. `None` for any other.
pub(crate) fn collapsed_url_error(text: &str) -> Option<Error> {
    let (scheme, rest) = text.split_once(":/")?;
    if !is_stream_scheme(scheme) || rest.is_empty() || rest.starts_with('/') {
        return None;
    }
    Some(Error::Invalid(format!(
        "{}: no file of that name, and as a URL a slash of its `{scheme}://` was lost (Python's \
         pathlib.Path, and argparse's `type=Path`, collapse `//`): give the URL as a str",
        crate::printable(&hide_password(scheme, rest).replacen("://", ":/", 1))
    )))
}

/// True for one of [`STREAM_SCHEMES`], in any case (RFC 3986).
fn is_stream_scheme(scheme: &str) -> bool {
    STREAM_SCHEMES
        .iter()
        .any(|s| s.eq_ignore_ascii_case(scheme))
}

/// `scheme://rest` with the password of its user part, if any, as `***`.
fn hide_password(scheme: &str, rest: &str) -> String {
    let authority_end = rest.find(['/', '?', '#']).unwrap_or(rest.len());
    let (authority, tail) = rest.split_at(authority_end);
    let shown = match authority.rsplit_once('@') {
        Some((user, host)) => match user.split_once(':') {
            Some((name, _)) => format!("{name}:***@{host}"),
            None => authority.to_string(),
        },
        None => authority.to_string(),
    };
    format!("{scheme}://{shown}{tail}")
}

/// Where frames come from: a file, a V4L2 camera device or a network
/// stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum VideoInput {
    /// A video file (mp4, mkv, avi, ...).
    File(PathBuf),
    /// A V4L2 camera (`/dev/videoN`), read live.
    Camera(PathBuf),
    /// A network stream (an IP camera's `rtsp://…`, `http://…`).
    Stream(StreamUrl),
}

impl VideoInput {
    /// The file or device, or the stream's URL as messages show it.
    pub fn path(&self) -> &Path {
        match self {
            VideoInput::File(p) | VideoInput::Camera(p) => p,
            VideoInput::Stream(url) => url.shown(),
        }
    }

    /// FFmpeg's words about it as messages show them: a stream's
    /// password hidden.
    fn hide_in(&self, words: &str) -> String {
        match self {
            VideoInput::Stream(url) => url.hide_in(words),
            _ => words.to_string(),
        }
    }

    /// The input as FFmpeg's and ffprobe's options.
    fn input_args(&self) -> Result<Vec<String>> {
        Ok(match self {
            VideoInput::File(p) => vec!["-i".into(), file_url(p)?],
            VideoInput::Stream(url) => url.input_args(),
            VideoInput::Camera(p) => vec![
                "-f".into(),
                "v4l2".into(),
                "-i".into(),
                p.to_str()
                    .ok_or_else(|| Error::image(p, "the device path is not valid UTF-8"))?
                    .into(),
            ],
        })
    }
}

/// `cmd`'s exit status, its standard output (at most 1 MiB: ffprobe's
/// answer is a few hundred bytes) and its last words on standard error
/// ([`stderr_tail`], [`last_words`]), its run given up when Ctrl-C asks to
/// stop or when `deadline` passes (a stream whose server accepts and says
/// nothing).
fn run_within(
    mut cmd: Command,
    path: &Path,
    deadline: Option<std::time::Duration>,
) -> Result<(std::process::ExitStatus, Vec<u8>, String)> {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| spawn_error(path, e))?;
    let stdout = child.stdout.take().map(|mut out| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = out.by_ref().take(1 << 20).read_to_end(&mut bytes);
            let _ = std::io::copy(&mut out, &mut std::io::sink());
            bytes
        })
    });
    let stderr = stderr_tail(&mut child);
    let started = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| Error::io(path, e))? {
            break status;
        }
        let late = deadline.filter(|d| started.elapsed() > *d);
        if late.is_some() || crate::interrupt::requested() {
            let _ = child.kill();
            let _ = child.wait();
            crate::interrupt::check()?;
            return Err(Error::image(
                path,
                format!(
                    "no frames came in {} s: is the camera on and the URL right?",
                    late.map_or(0, |d| d.as_secs())
                ),
            ));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let stdout = stdout.and_then(|t| t.join().ok()).unwrap_or_default();
    Ok((status, stdout, last_words(stderr)))
}

/// The first video stream's size (as shown) and rate, from `ffprobe`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VideoInfo {
    /// Width as shown (its display rotation applied), pixels.
    pub width: usize,
    /// Height as shown, pixels.
    pub height: usize,
    /// How far the stream's display matrix turns its frames clockwise to
    /// show them, whole degrees in [0, 360) (0: shown as stored).
    pub turn_deg: u16,
    /// Whether the display matrix also mirrors them (a reflection: its
    /// determinant is negative, as a front camera's or a mirror rig's
    /// recording may say), shown mirrored as FFmpeg's command line shows
    /// them.
    pub mirrored: bool,
    /// Frames per second, when the container says.
    pub fps: Option<f64>,
    /// The stream's length in seconds, when the container says (the
    /// stream's own, else the file's).
    pub duration_s: Option<f64>,
}

/// The clockwise turn, whole degrees in [0, 360), that shows a stream
/// whose display matrix says `rotation_deg` (ffprobe's `rotation`,
/// degrees counterclockwise), as FFmpeg's command line reads it: rounded
/// to a degree, and a turn of at most one degree either way is none; 0 for
/// a value that is not finite.
fn clockwise_turn(rotation_deg: f64) -> u16 {
    if !rotation_deg.is_finite() {
        return 0;
    }
    // The matrix's angle lies in [-180, 180]; the cast saturates anyway.
    match (-rotation_deg.round() as i64).rem_euclid(360) {
        0 | 1 | 359 => 0,
        turn => turn as u16,
    }
}

/// Whether a display matrix, as `ffprobe` prints it (three lines of three
/// whole numbers, each line led by its offset and a colon), reflects the
/// frames: the determinant of its 2x2 part is negative. `false` when the
/// text is not such a matrix.
fn reflects(display_matrix: &str) -> bool {
    let numbers: Option<Vec<i64>> = display_matrix
        .lines()
        .filter_map(|line| line.split_once(':'))
        .flat_map(|(_, row)| row.split_whitespace())
        .map(|n| n.parse::<i32>().ok().map(i64::from))
        .collect();
    match numbers.as_deref() {
        // 16.16 fixed point in 32 bits: each product fits in i64.
        Some([a, b, _, c, d, _, _, _, _]) => a * d - b * c < 0,
        _ => false,
    }
}

impl VideoInfo {
    /// The FFmpeg filter that turns (and mirrors) a decoded frame to be
    /// shown, as FFmpeg's command line does: a quarter or half turn
    /// exactly, with its flip when the matrix mirrors (`transpose`'s
    /// `_flip` directions; `hflip` alone for a half turn, `vflip` for
    /// none), another angle by `rotate`, which keeps the size (a mirror
    /// there is left, as FFmpeg leaves it). OpenCV's `VideoCapture` turns
    /// alike but leaves every mirror. `None` when none is needed.
    fn turn_filter(&self) -> Option<String> {
        let filter = match (self.turn_deg, self.mirrored) {
            (0, false) => return None,
            (0, true) => "vflip",
            (90, false) => "transpose=clock",
            (90, true) => "transpose=cclock_flip",
            (180, false) => "hflip,vflip",
            (180, true) => "hflip",
            (270, false) => "transpose=cclock",
            (270, true) => "transpose=clock_flip",
            (turn, _) => return Some(format!("rotate={turn}*PI/180")),
        };
        Some(filter.into())
    }
}

/// Whether a clockwise turn of `turn_deg` swaps a frame's sides.
fn turned_sideways(turn_deg: u16) -> bool {
    matches!(turn_deg, 90 | 270)
}

/// The size (as shown) and rate of `input`'s first video stream, checked:
/// a stream larger than 8K or without a video stream is an error naming
/// the file.
pub fn probe(input: &VideoInput) -> Result<VideoInfo> {
    let path = input.path();
    let mut cmd = Command::new("ffprobe");
    cmd.args(["-v", "error", "-select_streams", "v:0"])
        .args([
            "-show_entries",
            // Side data as a whole: its fields vary with FFmpeg's release.
            "stream=width,height,avg_frame_rate,duration:stream_side_data:format=duration",
        ])
        .args(["-of", "json"]);
    cmd.args(input.input_args()?);
    let deadline = matches!(input, VideoInput::Stream(_)).then_some(STREAM_PROBE_TIMEOUT);
    // A camera on the network may take seconds to answer: said on a
    // terminal, so a wait is not taken for a hang.
    let waiting = deadline.map(|d| {
        crate::progress::spinner(&format!(
            "opening {} (given up after {} s)",
            path.display(),
            d.as_secs()
        ))
    });
    let probed = run_within(cmd, path, deadline);
    if let Some(w) = waiting {
        w.finish_and_clear();
    }
    let (status, stdout, last) = probed?;
    if !status.success() {
        let why = input.hide_in(match last.trim() {
            "" => "ffprobe failed",
            words => words,
        });
        // A device is read as a camera: one that is none (`/dev/null`, a
        // serial port) is said to be no camera, not no video file.
        let what = match input {
            VideoInput::File(_) => "cannot read as video",
            VideoInput::Camera(_) => {
                "cannot read as a camera (a device is read as a V4L2 camera, such as /dev/video0)"
            }
            VideoInput::Stream(_) => "cannot read the stream",
        };
        return Err(Error::image(path, format!("{what}: {why}")));
    }
    #[derive(serde::Deserialize)]
    struct Probe {
        #[serde(default)]
        streams: Vec<Stream>,
        format: Option<Format>,
    }
    #[derive(serde::Deserialize)]
    struct Stream {
        width: Option<u64>,
        height: Option<u64>,
        avg_frame_rate: Option<String>,
        duration: Option<String>,
        #[serde(default)]
        side_data_list: Vec<SideData>,
    }
    #[derive(serde::Deserialize)]
    struct SideData {
        /// A display matrix's turn, degrees counterclockwise.
        rotation: Option<serde_json::Value>,
        /// The matrix itself, as text: whether it mirrors.
        displaymatrix: Option<String>,
    }
    #[derive(serde::Deserialize)]
    struct Format {
        duration: Option<String>,
    }
    let probe: Probe = serde_json::from_slice(&stdout)
        .map_err(|e| Error::image(path, format!("unreadable ffprobe output: {e}")))?;
    let Some(s) = probe.streams.first() else {
        return Err(Error::image(path, "has no video stream"));
    };
    let (Some(w), Some(h)) = (s.width, s.height) else {
        return Err(Error::image(path, "the video stream has no frame size"));
    };
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_IMAGE_PIXELS {
        return Err(Error::image(
            path,
            format!("video frames are {w}x{h}; frames must be 1 to {MAX_IMAGE_PIXELS} pixels (8K)"),
        ));
    }
    let fps = s.avg_frame_rate.as_deref().and_then(|r| {
        let (n, d) = r.split_once('/')?;
        let (n, d): (f64, f64) = (n.parse().ok()?, d.parse().ok()?);
        (d > 0.0 && n > 0.0).then(|| n / d)
    });
    let seconds = |d: Option<&String>| {
        d.and_then(|d| d.parse::<f64>().ok())
            .filter(|d| d.is_finite() && *d > 0.0)
    };
    let duration_s = seconds(s.duration.as_ref())
        .or_else(|| seconds(probe.format.as_ref().and_then(|f| f.duration.as_ref())));
    // The display matrix's side data: its turn, and its text for a mirror.
    let (turn_deg, mirrored) = s
        .side_data_list
        .iter()
        .find_map(|d| {
            let rotation = d.rotation.as_ref().and_then(serde_json::Value::as_f64)?;
            Some((
                clockwise_turn(rotation),
                d.displaymatrix.as_deref().is_some_and(reflects),
            ))
        })
        .unwrap_or((0, false));
    let (w, h) = if turned_sideways(turn_deg) {
        (h, w)
    } else {
        (w, h)
    };
    Ok(VideoInfo {
        width: w as usize,
        height: h as usize,
        turn_deg,
        mirrored,
        fps,
        duration_s,
    })
}

/// How FFmpeg decodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DecodeOptions {
    /// Decoding threads (FFmpeg's `-threads`); 1 leaves the other core to
    /// the models.
    pub threads: usize,
}

impl Default for DecodeOptions {
    fn default() -> Self {
        Self { threads: 1 }
    }
}

/// Frames of a video file or a camera, decoded by an FFmpeg process to
/// rgb24 and read one at a time. The process is killed when the reader is
/// dropped.
pub struct VideoReader {
    input: VideoInput,
    info: VideoInfo,
    child: Arc<Mutex<Child>>,
    stdout: ChildStdout,
    stderr: Option<std::thread::JoinHandle<Vec<u8>>>,
    done: bool,
    decoded: u64,
    shortfall: Option<String>,
}

impl VideoReader {
    /// Start decoding `input`: probed first (size checked), then an FFmpeg
    /// process that writes raw RGB frames of that size.
    pub fn open(input: &VideoInput, options: DecodeOptions) -> Result<Self> {
        let path = input.path();
        if let VideoInput::File(p) = input {
            crate::io::expect_regular(p)?;
        }
        let info = probe(input)?;
        let threads = options.threads.clamp(1, 64).to_string();
        // Each frame once: FFmpeg's rawvideo output would otherwise repeat
        // and drop frames of a variable rate video (a phone's) to make its
        // average rate.
        let (every_frame, each_output) = passthrough_options();
        let mut child = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
            .args(every_frame)
            .args(["-threads", &threads])
            // Turned here as the probe read the display matrix, so the
            // turn and the size come from one reading.
            .arg("-noautorotate")
            .args(input.input_args()?)
            .args(["-map", "0:v:0", "-an", "-sn", "-dn"])
            .args(each_output)
            .args(
                info.turn_filter()
                    .map(|f| ["-vf".to_string(), f])
                    .into_iter()
                    .flatten(),
            )
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24"])
            // The probed size, whatever the stream does later.
            .args(["-s", &format!("{}x{}", info.width, info.height)])
            .arg("pipe:1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| spawn_error(path, e))?;
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| Error::Invalid("ffmpeg started without an output pipe".into()))?;
        let stderr = stderr_tail(&mut child);
        Ok(Self {
            input: input.clone(),
            info,
            child: Arc::new(Mutex::new(child)),
            stdout,
            stderr,
            done: false,
            decoded: 0,
            shortfall: None,
        })
    }

    /// Once a file's frames have ended: a warning when far fewer were
    /// decoded than its container's length and rate promise (a copy cut
    /// short, a recording stopped early: FFmpeg decodes what is there
    /// and says nothing), given once. The frames decoded are kept.
    pub fn take_shortfall_warning(&mut self) -> Option<String> {
        self.shortfall.take()
    }

    /// [`Self::take_shortfall_warning`]'s warning, judged at the end of
    /// the stream.
    fn judge_shortfall(&self) -> Option<String> {
        // A camera's stream has no length; a served file may.
        let path = match &self.input {
            VideoInput::File(p) => p.as_path(),
            VideoInput::Stream(url) => url.shown(),
            VideoInput::Camera(_) => return None,
        };
        let (duration_s, fps) = (self.info.duration_s?, self.info.fps?);
        let promised = (duration_s * fps).round();
        let decoded = self.decoded as f64;
        (decoded + 2.0 < promised && decoded < 0.9 * promised).then(|| {
            format!(
                "warning: {}: its container says {duration_s:.2} s at {fps:.2} frames per second \
                 (about {promised} frames), and {} were decoded: the file may be cut short (a copy \
                 or a recording stopped early); the frames decoded were kept",
                path.display(),
                self.decoded
            )
        })
    }

    /// The stream's size and rate.
    pub fn info(&self) -> VideoInfo {
        self.info
    }

    /// A handle that stops the decoder from another thread (a live reader
    /// blocked on the pipe returns at once).
    pub fn stopper(&self) -> VideoStopper {
        VideoStopper(Arc::clone(&self.child))
    }

    /// The next frame, or `None` at the end of the stream. A stream that
    /// ends inside a frame or an FFmpeg failure is an error naming the file
    /// with FFmpeg's last words.
    pub fn next_frame(&mut self) -> Result<Option<RgbImage>> {
        if self.done {
            return Ok(None);
        }
        let len = self.info.width * self.info.height * 3;
        let mut buf = vec![0u8; len];
        let got =
            read_full(&mut self.stdout, &mut buf).map_err(|e| Error::io(self.input.path(), e))?;
        if got == len {
            self.decoded += 1;
            return rgb_image(self.info.width, self.info.height, buf).map(Some);
        }
        self.done = true;
        let status = self
            .child
            .lock()
            .map_err(|_| Error::Invalid("the video decoder's lock was poisoned".into()))?
            .wait()
            .map_err(|e| Error::io(self.input.path(), e))?;
        crate::interrupt::check()?;
        let last = self.input.hide_in(&last_words(self.stderr.take()));
        if !status.success() {
            let again = match &self.input {
                // The probe read it, so the server let one client in and
                // not the decoder after it.
                VideoInput::Stream(_) if self.decoded == 0 => format!(
                    "; the stream answered ffprobe but not FFmpeg after it: a server that serves \
                     one client once (`ffmpeg … tcp://…?listen`) is read through standard input \
                     instead: `ffmpeg -i URL -f rawvideo -pix_fmt rgb24 - | tactile run --stdin \
                     --size {}x{}`",
                    self.info.width, self.info.height
                ),
                _ => String::new(),
            };
            return Err(Error::image(
                self.input.path(),
                format!("FFmpeg could not decode it ({status}): {last}{again}"),
            ));
        }
        if got > 0 {
            return Err(Error::image(
                self.input.path(),
                format!("the stream ended inside a frame ({got} of {len} bytes)"),
            ));
        }
        self.shortfall = self.judge_shortfall();
        Ok(None)
    }
}

impl Drop for VideoReader {
    fn drop(&mut self) {
        if let Ok(mut c) = self.child.lock() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Stops a [`VideoReader`]'s FFmpeg process from another thread.
#[derive(Clone)]
pub struct VideoStopper(Arc<Mutex<Child>>);

impl VideoStopper {
    /// Kill the decoder; its reader then sees the end of the stream.
    pub fn stop(&self) {
        if let Ok(mut c) = self.0.lock() {
            let _ = c.kill();
        }
    }
}

/// FFmpeg's stderr drained on its own thread (a full pipe would stall
/// it), keeping only its tail for an error message.
pub(crate) fn stderr_tail(child: &mut Child) -> Option<std::thread::JoinHandle<Vec<u8>>> {
    child.stderr.take().map(|mut err| {
        std::thread::spawn(move || {
            let mut tail = Vec::new();
            let mut buf = [0u8; 1024];
            while let Ok(n) = err.read(&mut buf) {
                if n == 0 {
                    break;
                }
                keep_tail(&mut tail, &buf[..n]);
            }
            tail
        })
    })
}

/// Add `bytes` to FFmpeg's error output kept for a message, keeping its
/// last [`STDERR_TAIL`] bytes.
pub(crate) fn keep_tail(tail: &mut Vec<u8>, bytes: &[u8]) {
    tail.extend_from_slice(bytes);
    if tail.len() > STDERR_TAIL {
        tail.drain(..tail.len() - STDERR_TAIL);
    }
}

/// The last line FFmpeg wrote to stderr (after it exited).
pub(crate) fn last_words(tail: Option<std::thread::JoinHandle<Vec<u8>>>) -> String {
    let tail = tail
        .and_then(|t| t.join().ok())
        .map(|t| String::from_utf8_lossy(&t).trim().to_string())
        .unwrap_or_default();
    tail.lines().last().unwrap_or("").to_string()
}

/// Read until `buf` is full or the stream ends; how many bytes were read.
pub fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// How [`encode`] compresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VideoCodec {
    /// H.264 (libx264, 4:4:4 chroma as FFmpeg picks for RGB input) at a
    /// constant rate factor: 0 is lossless in YUV, 23 FFmpeg's default.
    H264 {
        /// libx264's `-crf`, 0 to 51.
        crf: u8,
    },
    /// H.264 coding RGB itself losslessly (libx264rgb, `-qp 0`): the
    /// decoded frames are the encoded ones, bit for bit.
    H264LosslessRgb,
    /// Motion JPEG at FFmpeg's best quality scale (`-q:v 2`).
    Mjpeg,
    /// H.264 as cameras, phones and recorders store it: libx264 with 4:2:0
    /// chroma (half the colour resolution each way) at a constant rate
    /// factor. A frame of odd width or height is padded to even.
    H264Yuv420 {
        /// libx264's `-crf`, 0 to 51 (23 is FFmpeg's default).
        crf: u8,
    },
    /// Motion JPEG as a USB (UVC) camera sends it: 4:2:2 chroma at
    /// FFmpeg's quality scale. A frame of odd width or height is padded to
    /// even.
    MjpegYuv422 {
        /// FFmpeg's `-q:v`, 2 (best) to 31.
        q: u8,
    },
}

/// FFmpeg's filter padding a frame of odd width or height by one black
/// column or row, as chroma at half resolution needs (the 4:2:0 and 4:2:2
/// codecs; [`round_trip`] crops it off again).
const EVEN_PAD: &str = "pad=ceil(iw/2)*2:ceil(ih/2)*2";

impl VideoCodec {
    fn args(self) -> Vec<String> {
        let v: Vec<String> = match self {
            VideoCodec::H264 { crf } => vec![
                "-c:v".into(),
                "libx264".into(),
                "-crf".into(),
                crf.min(51).to_string(),
                "-pix_fmt".into(),
                "yuv444p".into(),
            ],
            VideoCodec::H264LosslessRgb => {
                vec!["-c:v".into(), "libx264rgb".into(), "-qp".into(), "0".into()]
            }
            VideoCodec::Mjpeg => vec![
                "-c:v".into(),
                "mjpeg".into(),
                "-q:v".into(),
                "2".into(),
                "-pix_fmt".into(),
                "yuvj444p".into(),
            ],
            VideoCodec::H264Yuv420 { crf } => vec![
                "-vf".into(),
                EVEN_PAD.into(),
                "-c:v".into(),
                "libx264".into(),
                "-crf".into(),
                crf.min(51).to_string(),
                "-pix_fmt".into(),
                "yuv420p".into(),
            ],
            VideoCodec::MjpegYuv422 { q } => vec![
                "-vf".into(),
                EVEN_PAD.into(),
                "-c:v".into(),
                "mjpeg".into(),
                "-q:v".into(),
                q.clamp(2, 31).to_string(),
                "-pix_fmt".into(),
                "yuvj422p".into(),
            ],
        };
        v
    }
}

/// Encode `frames` (all one size) as a video at `fps` with FFmpeg, written
/// to a temporary file and renamed to `out` (the container from its
/// extension: `.mp4`, `.mkv`, `.avi`): for tests, benchmarks and recorded
/// demos.
pub fn encode(frames: &[&RgbImage], fps: u32, codec: VideoCodec, out: &Path) -> Result<()> {
    encode_with(frames, fps, out, &codec.args())
}

/// `frames` as a recording holds them: encoded with `codec` in a
/// temporary file and decoded back, one frame each at its own size (for
/// measuring what a camera's or recorder's compression does to a model's
/// answers).
pub fn round_trip(frames: &[&RgbImage], codec: VideoCodec) -> Result<Vec<RgbImage>> {
    let dir = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let ext = match codec {
        VideoCodec::Mjpeg | VideoCodec::MjpegYuv422 { .. } => "avi",
        _ => "mkv",
    };
    let path = dir.path().join(format!("round-trip.{ext}"));
    encode(frames, 10, codec, &path)?;
    let mut reader = VideoReader::open(&VideoInput::File(path.clone()), DecodeOptions::default())?;
    let mut out = Vec::with_capacity(frames.len());
    let (w, h) = frames.first().map_or((0, 0), |f| (f.width(), f.height()));
    while let Some(f) = reader.next_frame()? {
        // What padding to an even size added is cropped off.
        if (f.width(), f.height()) == (w, h) {
            out.push(f);
            continue;
        }
        if f.width() < w || f.height() < h {
            return Err(Error::image(
                &path,
                format!(
                    "encoded at {w}x{h}, decoded at {}x{}",
                    f.width(),
                    f.height()
                ),
            ));
        }
        let data = f
            .as_slice()
            .chunks_exact(f.width() * 3)
            .take(h)
            .flat_map(|row| row[..w * 3].iter().copied())
            .collect();
        out.push(crate::image_io::rgb_image(w, h, data)?);
    }
    if out.len() != frames.len() {
        return Err(Error::image(
            &path,
            format!("{} frames encoded, {} decoded", frames.len(), out.len()),
        ));
    }
    Ok(out)
}

fn encode_with(frames: &[&RgbImage], fps: u32, out: &Path, codec: &[String]) -> Result<()> {
    use std::io::Write;
    let Some(first) = frames.first() else {
        return Err(Error::Invalid("no frames to encode".into()));
    };
    let (w, h) = (first.width(), first.height());
    if let Some(f) = frames.iter().find(|f| (f.width(), f.height()) != (w, h)) {
        return Err(Error::Shape {
            what: "a frame of the video".into(),
            expected: format!("{w}x{h}"),
            found: format!("{}x{}", f.width(), f.height()),
        });
    }
    crate::io::ensure_writable_parent(out)?;
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("mp4");
    let tmp = out.with_extension(format!("partial-{}.{ext}", std::process::id()));
    let mut child = Command::new("ffmpeg")
        .args(["-nostdin", "-hide_banner", "-loglevel", "error", "-y"])
        .args([
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            &format!("{w}x{h}"),
        ])
        .args(["-r", &fps.to_string(), "-i", "pipe:0"])
        .args(codec)
        .arg(file_url(&tmp)?)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| spawn_error(out, e))?;
    let write = (|| -> std::io::Result<()> {
        let mut stdin = child.stdin.take().ok_or(std::io::ErrorKind::BrokenPipe)?;
        for f in frames {
            stdin.write_all(f.as_slice())?;
        }
        Ok(())
    })();
    let result = child.wait_with_output().map_err(|e| Error::io(out, e))?;
    if let Err(e) = write.and_then(|_| {
        result.status.success().then_some(()).ok_or_else(|| {
            std::io::Error::other(String::from_utf8_lossy(&result.stderr).trim().to_string())
        })
    }) {
        std::fs::remove_file(&tmp).ok();
        return Err(Error::image(
            out,
            format!("FFmpeg could not encode it: {e}"),
        ));
    }
    std::fs::rename(&tmp, out).map_err(|e| Error::io(out, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_round_trip_gives_every_frame_back_as_the_codec_leaves_it() {
        // Three 64x48 frames of smooth colour ramps (a sensor's look):
        // each codec gives three frames of that size back, close to the
        // originals but, being lossy, not equal; 4:2:0 H.264 at a worse
        // rate factor strays further.
        let frames: Vec<RgbImage> = (0..3u32)
            .map(|k| {
                let px = (0..48u32)
                    .flat_map(|y| {
                        (0..64u32).flat_map(move |x| {
                            [
                                (60 + x + 10 * k) as u8,
                                (80 + y) as u8,
                                (120 + (x + y) / 2) as u8,
                            ]
                        })
                    })
                    .collect();
                crate::image_io::rgb_image(64, 48, px).unwrap()
            })
            .collect();
        let refs: Vec<&RgbImage> = frames.iter().collect();
        let error = |codec| {
            let back = round_trip(&refs, codec).unwrap();
            assert_eq!(back.len(), 3, "{codec:?}");
            let mut sum = 0.0;
            for (a, b) in frames.iter().zip(&back) {
                assert_eq!((b.width(), b.height()), (64, 48), "{codec:?}");
                sum += a
                    .as_slice()
                    .iter()
                    .zip(b.as_slice())
                    .map(|(&p, &q)| (p as f64 - q as f64).abs())
                    .sum::<f64>();
            }
            sum / (3.0 * 64.0 * 48.0 * 3.0)
        };
        let mjpeg = error(VideoCodec::MjpegYuv422 { q: 2 });
        let good = error(VideoCodec::H264Yuv420 { crf: 18 });
        let poor = error(VideoCodec::H264Yuv420 { crf: 40 });
        for e in [mjpeg, good, poor] {
            assert!(e > 0.0 && e < 6.0, "{mjpeg} {good} {poor}");
        }
        assert!(poor > good, "crf 40 {poor} against crf 18 {good}");
        // A frame of odd size comes back at its own size, not padded.
        let odd = crate::image_io::rgb_image(63, 47, vec![128; 63 * 47 * 3]).unwrap();
        for codec in [
            VideoCodec::MjpegYuv422 { q: 5 },
            VideoCodec::H264Yuv420 { crf: 23 },
        ] {
            let back = round_trip(&[&odd], codec).unwrap();
            assert_eq!((back[0].width(), back[0].height()), (63, 47), "{codec:?}");
        }
    }

    #[test]
    fn a_video_of_variable_frame_rate_gives_each_frame_once() {
        // 30 frames at 30 fps with a half-second pause after frame 10 and
        // slowing after frame 20, as a phone records: FFmpeg's rawvideo
        // output made 50 of them (repeats to fill its average rate).
        let dir = tempfile::tempdir().unwrap();
        let video = dir.path().join("vfr.mp4");
        let (every_frame, each_output) = passthrough_options();
        let status = Command::new("ffmpeg")
            .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
            .args(every_frame)
            .args(["-f", "lavfi", "-i", "testsrc=size=64x64:rate=30"])
            .args(["-frames:v", "30", "-vf"])
            .arg("setpts='PTS+if(gte(N,10),0.5/TB,0)+if(gte(N,20),0.02*(N-20)/TB,0)'")
            .args(each_output)
            .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
            .arg(&video)
            .status()
            .unwrap();
        assert!(status.success());
        let mut reader =
            VideoReader::open(&VideoInput::File(video), DecodeOptions::default()).unwrap();
        let mut frames = 0;
        while reader.next_frame().unwrap().is_some() {
            frames += 1;
        }
        assert_eq!(frames, 30);
    }

    #[test]
    fn a_video_recorded_turned_is_read_as_it_is_shown() {
        // Frames stored 64x32, a grey level a quarter, in a file whose
        // display matrix turns them (a quarter turn as a phone held upright
        // records, a half turn, three quarters): read as FFmpeg's command
        // line and OpenCV's VideoCapture show them, as a frame file's EXIF
        // orientation is applied. Before, read 64x32 as stored.
        let dir = tempfile::tempdir().unwrap();
        let (plain, turned) = (dir.path().join("plain.mp4"), dir.path().join("turned.mp4"));
        let ffmpeg = |args: &[&str]| {
            let out = Command::new("ffmpeg")
                .args(["-nostdin", "-hide_banner", "-loglevel", "error", "-y"])
                .args(args)
                .output()
                .unwrap();
            assert!(out.status.success(), "ffmpeg {args:?}");
            out.stdout
        };
        ffmpeg(&[
            "-f",
            "lavfi",
            "-i",
            "color=c=0x141414:s=32x16:r=10[a];color=c=0xe6e6e6:s=32x16:r=10[b];\
             color=c=0x787878:s=32x16:r=10[c];color=c=0xb4b4b4:s=32x16:r=10[d];\
             [a][b]hstack[top];[c][d]hstack[bottom];[top][bottom]vstack",
            "-frames:v",
            "5",
            "-c:v",
            "libx264",
            "-pix_fmt",
            "yuv444p",
            plain.to_str().unwrap(),
        ]);
        let first_frame = |video: &Path| {
            let input = VideoInput::File(video.to_path_buf());
            let info = probe(&input).unwrap();
            let mut reader = VideoReader::open(&input, DecodeOptions::default()).unwrap();
            let mut frames = Vec::new();
            while let Some(f) = reader.next_frame().unwrap() {
                assert_eq!((f.width(), f.height()), (info.width, info.height));
                frames.push(f);
            }
            assert_eq!(frames.len(), 5);
            frames.swap_remove(0)
        };
        // The first frame as FFmpeg's command line shows the file.
        let shown_by_ffmpeg = |video: &Path| {
            ffmpeg(&[
                "-i",
                video.to_str().unwrap(),
                "-frames:v",
                "1",
                "-f",
                "rawvideo",
                "-pix_fmt",
                "rgb24",
                "-",
            ])
        };
        let stored = first_frame(&plain);
        assert_eq!((stored.width(), stored.height()), (64, 32));
        for (tag, shown_size) in [("90", (32, 64)), ("180", (64, 32)), ("270", (32, 64))] {
            // The stream copied, tagged turned (FFmpeg writes the tag as
            // the file's display matrix).
            ffmpeg(&[
                "-i",
                plain.to_str().unwrap(),
                "-c",
                "copy",
                "-metadata:s:v:0",
                &format!("rotate={tag}"),
                turned.to_str().unwrap(),
            ]);
            let shown = first_frame(&turned);
            assert_eq!((shown.width(), shown.height()), shown_size, "{tag}");
            // Pixel for pixel as FFmpeg's command line shows the file.
            let cli = shown_by_ffmpeg(&turned);
            assert_eq!(shown.as_slice(), &cli[..], "{tag}");
            assert_ne!(shown.as_slice(), stored.as_slice(), "{tag}");
        }
        // A display matrix that mirrors (a reflection: a front camera's, a
        // mirror rig's), written into the file's track header: shown
        // mirrored as FFmpeg's command line shows it. Before, a mirror was
        // read as the turn ffprobe gives it (a horizontal flip as a half
        // turn: the frame upside down).
        let video = std::fs::read(&plain).unwrap();
        let tkhd = video.windows(4).position(|w| w == b"tkhd").unwrap();
        // The matrix follows the times, track id and duration (8 bytes
        // each in version 1, else 4), then layer, group and volume.
        let at = tkhd + if video[tkhd + 4] == 1 { 56 } else { 44 };
        let one = 1 << 16;
        for (name, [a, b, c, d], shown_size) in [
            ("horizontal flip", [-one, 0, 0, one], (64, 32)),
            ("vertical flip", [one, 0, 0, -one], (64, 32)),
            ("main diagonal", [0, one, one, 0], (32, 64)),
            ("other diagonal", [0, -one, -one, 0], (32, 64)),
        ] {
            let mut mirrored = video.clone();
            let matrix: [i32; 9] = [a, b, 0, c, d, 0, 0, 0, 1 << 30];
            for (i, v) in matrix.iter().enumerate() {
                mirrored[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_be_bytes());
            }
            std::fs::write(&turned, &mirrored).unwrap();
            let info = probe(&VideoInput::File(turned.clone())).unwrap();
            assert!(info.mirrored, "{name}: {info:?}");
            let shown = first_frame(&turned);
            assert_eq!((shown.width(), shown.height()), shown_size, "{name}");
            let cli = shown_by_ffmpeg(&turned);
            assert!(
                shown.as_slice() == &cli[..],
                "{name}: not as FFmpeg shows it"
            );
            assert!(shown.as_slice() != stored.as_slice(), "{name}: as stored");
        }
        // ffprobe's text of a matrix: mirrors when its determinant is
        // negative; a turn alone, or text that is no matrix, does not.
        let text = |m: [i32; 9]| {
            m.chunks(3)
                .enumerate()
                .map(|(i, r)| format!("\n{i:08x}: {:>11} {:>11} {:>11}", r[0], r[1], r[2]))
                .collect::<String>()
                + "\n"
        };
        assert!(reflects(&text([-one, 0, 0, 0, one, 0, 0, 0, 1 << 30])));
        assert!(!reflects(&text([0, one, 0, -one, 0, 0, 0, 0, 1 << 30])));
        assert!(!reflects(&text([-one, 0, 0, 0, -one, 0, 0, 0, 1 << 30])));
        assert!(!reflects("\n00000000: 1 2\n"));
        assert!(!reflects(
            "\n00000000: 99999999999 0 0\n00000001: 0 -1 0\n00000002: 0 0 1\n"
        ));
        // ffprobe's rotation (counterclockwise) read as FFmpeg reads it.
        for (rotation, turn, sideways) in [
            (90.0, 270, true),
            (-90.0, 90, true),
            (270.0, 90, true),
            (89.6, 270, true),
            (180.0, 180, false),
            (-180.0, 180, false),
            (0.0, 0, false),
            (359.6, 0, false),
            (-45.0, 45, false),
            (1.0, 0, false),
            (-1.0, 0, false),
            (2.0, 358, false),
            (f64::NAN, 0, false),
        ] {
            assert_eq!(clockwise_turn(rotation), turn, "{rotation}");
            assert_eq!(turned_sideways(turn), sideways, "{rotation}");
        }
    }

    #[test]
    fn the_release_of_ffmpeg_is_read_from_its_version_line() {
        for (line, release) in [
            (
                "ffmpeg version 5.1.9-0+deb12u1 Copyright (c) 2000-2026",
                Some((5, 1)),
            ),
            (
                "ffmpeg version 4.4.2-0ubuntu0.22.04.1 Copyright",
                Some((4, 4)),
            ),
            ("ffmpeg version n4.4 Copyright", Some((4, 4))),
            (
                "ffmpeg version 4.2.2-static https://johnvansickle.com/ffmpeg/",
                Some((4, 2)),
            ),
            ("ffmpeg version 7 Copyright", Some((7, 0))),
            ("ffmpeg version N-112233-gabcdef Copyright", None),
            ("something else", None),
        ] {
            assert_eq!(release_of(line), release, "{line}");
        }
    }

    #[test]
    fn a_streams_url_is_told_from_a_path_and_its_password_is_never_shown() {
        let shown = |text: &str| {
            StreamUrl::parse(text)
                .unwrap()
                .map(|u| u.shown().display().to_string())
        };
        for (text, want) in [
            (
                "rtsp://192.168.1.20:554/stream",
                "rtsp://192.168.1.20:554/stream",
            ),
            (
                "rtsp://admin:pa:ss@cam.local/h264?channel=1",
                "rtsp://admin:***@cam.local/h264?channel=1",
            ),
            ("HTTP://u:p@a@host:8080", "HTTP://u:***@host:8080"),
            ("http://user@host/x?to=a:b@c", "http://user@host/x?to=a:b@c"),
            ("srt://host:9000?mode=caller", "srt://host:9000?mode=caller"),
        ] {
            assert_eq!(shown(text).as_deref(), Some(want), "{text}");
        }
        // Paths, not URLs: read as files.
        for text in [
            "clip.mp4",
            "./rtsp:/x",
            "1://x",
            "a b://x",
            "://x",
            "/data/x://y",
        ] {
            assert_eq!(shown(text), None, "{text}");
        }
        for (text, want) in [
            ("file:///tmp/a.mkv", "give the file's path itself"),
            (
                "ftp://u:secret@lab/a.mkv",
                "ftp://u:***@lab/a.mkv: ftp:// URLs are not read",
            ),
            ("concat://a|b", "concat:// URLs are not read"),
            (
                "rtsp://cam/a b",
                "a URL holds no spaces or control characters",
            ),
            (
                "rtsp://cam/\u{1b}[2J",
                "rtsp://cam/\\x1b[2J: a URL holds no spaces",
            ),
        ] {
            let err = StreamUrl::parse(text).unwrap_err().to_string();
            assert!(
                err.contains(want) && !err.contains("secret"),
                "{text}: {err}"
            );
        }
        // A URL past the limit is refused before FFmpeg sees it, its
        // start shown with the password hidden however long the user part.
        let long = format!("rtsp://admin:{}@cam/s", "p".repeat(MAX_URL_BYTES));
        let err = StreamUrl::parse(&long).unwrap_err().to_string();
        assert!(
            err.starts_with("rtsp://admin:***@cam/s…: a URL of 16403 bytes; at most 16384")
                && !err.contains("pp"),
            "{err}"
        );
        // A URL that went through Python's pathlib.Path lost a slash.
        let err = collapsed_url_error("rtsp:/admin:secret@cam/s")
            .unwrap()
            .to_string();
        assert!(
            err.starts_with("rtsp:/admin:***@cam/s: no file of that name, and as a URL a slash")
                && err.contains("give the URL as a str"),
            "{err}"
        );
        for text in ["rtsp://cam/s", "frames/rtsp:/x", "ftp:/x", "http:/"] {
            assert!(collapsed_url_error(text).is_none(), "{text}");
        }
        // Only network protocols, and a silence after which FFmpeg gives
        // up that the protocol reads as one.
        let args = |text: &str| StreamUrl::parse(text).unwrap().unwrap().input_args();
        // Given in capitals, the scheme reaches FFmpeg in lower case.
        assert!(args("RTSP://cam/s").contains(&"rtsp://cam/s".to_string()));
        let rtmp = args("rtmp://host/live");
        assert!(rtmp.contains(&"-rw_timeout".to_string()));
        assert!(
            !rtmp.contains(&"-timeout".to_string()),
            "RTMP's -timeout listens"
        );
        assert!(args("rtsp://cam/s").contains(&"-timeout".to_string()));
        let list = &rtmp[rtmp
            .iter()
            .position(|a| a == "-protocol_whitelist")
            .unwrap()
            + 1];
        for p in list.split(',') {
            assert!(
                !["file", "pipe", "concat", "subfile", "data"].contains(&p),
                "{p}"
            );
        }
    }
}
