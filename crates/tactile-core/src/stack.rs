//! A file of many frames, read one after another as a video's frames are:
//! a TIFF's pages (ImageJ's and Micro-Manager's stacks, a camera's burst),
//! when the file is given alone as the source. Where a frame file is one
//! picture (in a folder, decoded alone) such a file is refused instead, so
//! no page is lost without a word. An animated WebP is refused as a
//! source too: its decoder (`image-webp` 0.2) composes an animation's
//! frames a level off where libwebp gives the frame exactly.
//!
//! Each TIFF page is decoded by the `image` crate as a TIFF's first page
//! is: the file is read with its header's first-directory offset pointing
//! at the page's directory (every other offset in a TIFF is absolute), so
//! a page is read exactly as a one-page TIFF of the same bytes would be,
//! its orientation tag applied, thumbnails (reduced-resolution pages)
//! skipped as [`crate::image_io`] skips them when it counts pages.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use image::{ImageDecoder, ImageFormat, ImageReader};

use crate::image_io::{
    ImageHeader, RgbImage, beyond_limit, header_of, is_thumbnail, refusal, rgb_frame, upright,
};
use crate::{Error, Result};

/// Most pages a stack is read with: their directories' offsets are kept
/// (8 bytes a page) once the header pass has walked them.
pub const MAX_STACK_PAGES: usize = 1_000_000;

/// The pages of one TIFF stack, in order, their headers read.
pub struct StackFrames {
    path: PathBuf,
    /// How the file was named when opened: "a TIFF of 12 pages (...)".
    what: String,
    /// The file's first 16 bytes (a BigTIFF header is 16 long).
    head: Vec<u8>,
    /// Each page's directory offset (thumbnails left out).
    pages: Vec<u64>,
    /// Each page's header, as shown.
    headers: Vec<ImageHeader>,
    /// The warning of a file cut short inside a page's directory (a
    /// recording stopped while it was written): the pages before it are
    /// read, as a video cut short keeps its frames.
    cut_short: Option<String>,
}

/// A TIFF's header with its first-directory offset set to `ifd`: the file
/// read through it starts at that page. `None` for a header that is not
/// a TIFF's (the walker, which read it, would have refused it).
fn header_pointing_at(head: &[u8], ifd: u64) -> Option<Vec<u8>> {
    let mut h = head.to_vec();
    let little = match head.get(..2)? {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let word = |b: &[u8]| match little {
        true => u16::from_le_bytes([b[0], b[1]]),
        false => u16::from_be_bytes([b[0], b[1]]),
    };
    match word(head.get(2..4)?) {
        42 => {
            let v = u32::try_from(ifd).ok()?;
            let b = if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            };
            h.get_mut(4..8)?.copy_from_slice(&b);
        }
        43 => {
            let b = if little {
                ifd.to_le_bytes()
            } else {
                ifd.to_be_bytes()
            };
            h.get_mut(8..16)?.copy_from_slice(&b);
        }
        _ => return None,
    }
    Some(h)
}

/// A file read with its first bytes replaced by `head`.
struct WithHead {
    file: File,
    head: Vec<u8>,
}

impl Read for WithHead {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let at = self.file.stream_position()?;
        let n = self.file.read(buf)?;
        if let Ok(at) = usize::try_from(at)
            && let Some(head) = self.head.get(at..)
        {
            let k = head.len().min(n);
            buf[..k].copy_from_slice(&head[..k]);
        }
        Ok(n)
    }
}

impl Seek for WithHead {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

/// The decoder of the page whose directory is at `ifd`, its header read:
/// the file opened anew and read through a header pointing at that
/// directory, as a TIFF. A page that cannot be read is named by `at`; a
/// file that cannot be opened is the disk's error, not the page's.
fn page_decoder(
    path: &Path,
    head: &[u8],
    ifd: u64,
    at: impl Fn(String) -> Error,
) -> Result<impl ImageDecoder> {
    let head =
        header_pointing_at(head, ifd).ok_or_else(|| at("its directory cannot be found".into()))?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    ImageReader::with_format(BufReader::new(WithHead { file, head }), ImageFormat::Tiff)
        .into_decoder()
        .map_err(|e| at(refusal("cannot read its header", &e, &[])))
}

impl StackFrames {
    /// `path` as a stack when it is a TIFF of more than one page, the
    /// headers of its first `limit` pages (all without one) read and
    /// checked as a folder's frames are: a page that is no picture, past
    /// 8K or not 8 bits per channel is refused, named by its number,
    /// before any is decoded. `None` for any other file (one picture,
    /// another format, or one that cannot be read so far: reading it as
    /// one picture then says why). An animated WebP of more than one
    /// frame is refused, saying why.
    pub fn open(path: &Path, limit: Option<u64>) -> Result<Option<Self>> {
        crate::io::expect_regular(path)?;
        let reader = ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| Error::io(path, e))?;
        let Some(format) = reader.format() else {
            return Ok(None);
        };
        let file = || {
            File::open(path)
                .map(BufReader::new)
                .map_err(|e| Error::io(path, e))
        };
        let Some(what) = crate::image_io::more_than_one_picture(file()?, format) else {
            return Ok(None);
        };
        if format != ImageFormat::Tiff {
            return Err(Error::image(path, what));
        }
        let mut head = Vec::with_capacity(16);
        file()?
            .take(16)
            .read_to_end(&mut head)
            .map_err(|e| Error::io(path, e))?;
        let mut stack = Self {
            path: path.to_path_buf(),
            what,
            head,
            pages: Vec::new(),
            headers: Vec::new(),
            cut_short: None,
        };
        stack.read_headers(limit)?;
        Ok(Some(stack))
    }

    /// The header pass: walk the chain of directories (bounded and
    /// checked for cycles by the `tiff` crate), keep each page's, and read
    /// its header as [`Self::load`] will.
    fn read_headers(&mut self, limit: Option<u64>) -> Result<()> {
        let wanted = limit.map_or(usize::MAX, |l| usize::try_from(l).unwrap_or(usize::MAX));
        let (path, what) = (&self.path, &self.what);
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut walker = tiff::decoder::Decoder::new(BufReader::new(file))
            .map_err(|e| Error::image(path, format!("{what}: {e}")))?;
        loop {
            // A long stack's header pass stops on a stop request, as a
            // folder's does (`Error::check_frames`).
            crate::interrupt::check()?;
            let number = self.pages.len();
            let at =
                |why: String| Error::image(path, format!("frame {number:06} of the stack: {why}"));
            if !is_thumbnail(&mut walker) {
                if number == MAX_STACK_PAGES {
                    return Err(Error::image(
                        path,
                        format!(
                            "{what}: more than {MAX_STACK_PAGES} pages, more than a stack is read with: split it, or read its first pages with a limit"
                        ),
                    ));
                }
                let ifd = walker
                    .ifd_pointer()
                    .ok_or_else(|| at("its directory cannot be found".into()))?
                    .0;
                let header = header_of(&mut page_decoder(path, &self.head, ifd, at)?).0;
                if let Some(why) = crate::image_io::rgb_header_refusal(&header) {
                    return Err(at(why));
                }
                self.pages.push(ifd);
                self.headers.push(header);
            }
            if self.pages.len() >= wanted || !walker.more_images() {
                return Ok(());
            }
            let Err(e) = walker.next_image() else {
                continue;
            };
            if is_cut_short(&e) {
                self.cut_short = Some(format!(
                    "warning: {} ends inside the directory of frame {number:06} of the stack \
                     (cut short): the {number} frames before it are read, as a video cut \
                     short keeps its frames",
                    path.display(),
                    number = self.pages.len()
                ));
                return Ok(());
            }
            return Err(at(format!("cannot read its directory: {e}")));
        }
    }

    /// The warning of a file cut short inside a page's directory, whose
    /// pages before it are read.
    pub fn cut_short_warning(&self) -> Option<&str> {
        self.cut_short.as_deref()
    }

    /// The pages read (the first `limit` when opened with one).
    pub fn len(&self) -> usize {
        self.pages.len()
    }

    /// True for no pages (never, once opened: a stack has two at least).
    pub fn is_empty(&self) -> bool {
        self.pages.is_empty()
    }

    /// Page `number`'s header (its size as shown, its pixel format), read
    /// when the stack was opened.
    pub fn header(&self, number: usize) -> Option<ImageHeader> {
        self.headers.get(number).copied()
    }

    /// The first page's width and height as shown.
    pub fn size(&self) -> (usize, usize) {
        self.headers
            .first()
            .map_or((0, 0), |h| (h.width as usize, h.height as usize))
    }

    /// Page `number` (from 0, thumbnails not counted) decoded as an 8-bit
    /// RGB frame, as it is shown. A page whose pixels cannot be decoded
    /// (cut short, corrupt) is an [`Error::Image`] naming the file and the
    /// frame's number.
    pub fn load(&self, number: usize) -> Result<RgbImage> {
        let path = &self.path;
        let at = |why: String| Error::image(path, format!("frame {number:06} of the stack: {why}"));
        let ifd = *self
            .pages
            .get(number)
            .ok_or_else(|| at("no such page".into()))?;
        let mut decoder = page_decoder(path, &self.head, ifd, at)?;
        let (header, orientation) = header_of(&mut decoder);
        if let Some(why) = beyond_limit(header.width, header.height) {
            return Err(at(why));
        }
        let img =
            upright(decoder, orientation).map_err(|e| at(refusal("cannot decode it", &e, &[])))?;
        rgb_frame(img).map_err(at)
    }
}

/// True for a `tiff` error that reads past the end of the file.
fn is_cut_short(e: &tiff::TiffError) -> bool {
    matches!(e, tiff::TiffError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof)
}
