//! Loading frame files (PNG, JPEG, BMP, TIFF, WebP, PGM/PPM, told by
//! their bytes) and saving 8-bit PNGs, with errors that name the file.

use std::path::Path;

use image::metadata::Orientation;
use image::{ColorType, DynamicImage, ImageDecoder, ImageReader};
use kornia_image::{Image, ImageSize};

use crate::{Error, Result};

/// An 8-bit single-channel image (kornia layout, row-major).
pub type GreyImage = Image<u8, 1>;
/// An 8-bit three-channel RGB image (kornia layout, row-major, interleaved).
pub type RgbImage = Image<u8, 3>;

/// Build a grey image from row-major pixels.
pub fn grey_image(width: usize, height: usize, data: Vec<u8>) -> Result<GreyImage> {
    Image::new(ImageSize { width, height }, data)
        .map_err(|e| Error::Invalid(format!("cannot build a {width}x{height} grey image: {e}")))
}

/// Build an RGB image from row-major interleaved pixels.
pub fn rgb_image(width: usize, height: usize, data: Vec<u8>) -> Result<RgbImage> {
    Image::new(ImageSize { width, height }, data)
        .map_err(|e| Error::Invalid(format!("cannot build a {width}x{height} RGB image: {e}")))
}

fn describe(color: ColorType) -> &'static str {
    match color {
        ColorType::L8 => "8-bit greyscale",
        ColorType::La8 => "8-bit greyscale with alpha",
        ColorType::Rgb8 => "8-bit RGB",
        ColorType::Rgba8 => "8-bit RGBA",
        ColorType::L16 => "16-bit greyscale",
        ColorType::La16 => "16-bit greyscale with alpha",
        ColorType::Rgb16 => "16-bit RGB",
        ColorType::Rgba16 => "16-bit RGBA",
        ColorType::Rgb32F => "32-bit float RGB",
        ColorType::Rgba32F => "32-bit float RGBA",
        _ => "an unsupported pixel format",
    }
}

/// Why a frame file of another depth (16-bit, float) is not read, and
/// what to do: the sensor contract is 8 bits per channel, and only the
/// user knows which of 16 bits their camera fills (a 12-bit camera's
/// levels cut to the high byte would read as a blank frame).
fn not_eight_bit(color: ColorType, expected: &str) -> String {
    format!(
        "{} image; expected {expected}: save the frames with 8 bits per channel, your camera's levels scaled to 0-255",
        describe(color)
    )
}

/// Largest image decoded, in pixels (8K UHD, 7680 x 4320): the header is
/// read first, so a bigger file is refused before its pixels are allocated.
pub const MAX_IMAGE_PIXELS: u64 = 7680 * 4320;

/// Largest image file copied as bytes: an 8K frame of 16-bit RGBA stored
/// without compression is 265 MB.
pub const MAX_IMAGE_FILE_BYTES: u64 = 512 << 20;

/// What an image file's header says, read without decoding its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageHeader {
    /// Width as shown (its EXIF orientation applied), pixels.
    pub width: u32,
    /// Height as shown, pixels.
    pub height: u32,
    /// Its EXIF orientation turns it a quarter: the sides as shown are the
    /// stored ones swapped.
    pub turned_sideways: bool,
    /// The stored pixel format.
    pub color: ColorType,
}

impl ImageHeader {
    /// Stored as greyscale (with or without alpha, of any depth).
    pub fn grey(&self) -> bool {
        matches!(
            self.color,
            ColorType::L8 | ColorType::La8 | ColorType::L16 | ColorType::La16
        )
    }
}

fn open_image(path: &Path) -> Result<ImageReader<std::io::BufReader<std::fs::File>>> {
    ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))
}

/// How a picture's EXIF orientation (a camera held on its side, a
/// phone's photo) says it is shown: [`image::metadata::Orientation`] from
/// its metadata, no turn when it has none or one that cannot be read.
fn exif_orientation(decoder: &mut impl ImageDecoder) -> Orientation {
    // A damaged EXIF block is ignored, as OpenCV and browsers ignore it:
    // the pixels are still the picture, as stored.
    decoder.orientation().unwrap_or(Orientation::NoTransforms)
}

/// Whether `orientation` turns a picture a quarter, so that it is shown
/// with its stored sides swapped.
fn turns_sideways(orientation: Orientation) -> bool {
    matches!(
        orientation,
        Orientation::Rotate90
            | Orientation::Rotate270
            | Orientation::Rotate90FlipH
            | Orientation::Rotate270FlipH
    )
}

/// Decode a picture the way it is shown: its EXIF orientation applied,
/// as OpenCV's `imread` and `imdecode` apply it (the field's tools read
/// frames with them). Frame files and a bag's compressed images are
/// decoded here.
pub(crate) fn decode_upright<R: std::io::BufRead + std::io::Seek>(
    reader: ImageReader<R>,
) -> image::ImageResult<DynamicImage> {
    let mut decoder = reader.into_decoder()?;
    let orientation = exif_orientation(&mut decoder);
    upright(decoder, orientation)
}

/// `decoder`'s picture decoded, then turned as `orientation` says.
pub(crate) fn upright(
    decoder: impl ImageDecoder,
    orientation: Orientation,
) -> image::ImageResult<DynamicImage> {
    let mut img = DynamicImage::from_decoder(decoder)?;
    img.apply_orientation(orientation);
    Ok(img)
}

/// `path` opened for decoding, its header read (a regular file whose
/// header can be read, holding one picture).
fn open_decoder(path: &Path) -> Result<impl ImageDecoder> {
    crate::io::expect_regular(path)?;
    let reader = open_image(path)?;
    if let Some(format) = reader.format().filter(|f| may_hold_more_pictures(*f)) {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        if let Some(why) = more_than_one_picture(std::io::BufReader::new(file), format) {
            let why = match format {
                image::ImageFormat::Tiff => format!("{why}; {ONE_PICTURE_HERE}"),
                _ => why,
            };
            return Err(Error::image(path, why));
        }
    }
    reader
        .into_decoder()
        .map_err(|e| file_refusal(path, "cannot read the image header", e))
}

/// IFDs of a TIFF walked to count its pages: a camera's thumbnails are a
/// few; a stack is told by its second page.
const MAX_TIFF_IFDS_WALKED: usize = 64;

/// True for the frame formats that can hold more than one picture (a
/// TIFF's pages, an animated WebP's frames): those a file is opened a
/// second time for, to count them.
fn may_hold_more_pictures(format: image::ImageFormat) -> bool {
    matches!(format, image::ImageFormat::Tiff | image::ImageFormat::WebP)
}

/// What a frame file read as one picture (in a folder, or decoded alone)
/// that holds a stack is told to do: the stack given alone as the source
/// is read page by page ([`crate::stack`]).
const ONE_PICTURE_HERE: &str = "a frame file is one picture here (a TIFF stack given \
     alone to tactile run, predict, reconstruct, dataset from-video or tactile.frames is \
     read page by page): save each page as a file of its own";

/// A picture of `format` read from `r` that holds more than one, named
/// with its count: a stack of frames saved in one file (ImageJ, a
/// camera's burst, an animated WebP), of which the decoder, as OpenCV's
/// `imread` and PIL, would give the first alone, losing the rest without
/// a word. Where one picture is read it is refused; given alone as the
/// source it is read page by page ([`crate::stack`]). A TIFF's
/// reduced-resolution pages (thumbnails: NewSubfileType bit 0) are not
/// counted. `None` for one picture, or when the file cannot be read so
/// far (decoding then says why).
pub(crate) fn more_than_one_picture<R: std::io::BufRead + std::io::Seek>(
    r: R,
    format: image::ImageFormat,
) -> Option<String> {
    match format {
        image::ImageFormat::Tiff => {
            let mut tiff = tiff::decoder::Decoder::new(r).ok()?;
            let (mut pages, mut walked) = (0usize, 0usize);
            loop {
                pages += usize::from(!is_thumbnail(&mut tiff));
                walked += 1;
                if walked == MAX_TIFF_IFDS_WALKED
                    || !tiff.more_images()
                    || tiff.next_image().is_err()
                {
                    break;
                }
            }
            let more = match tiff.more_images() && walked == MAX_TIFF_IFDS_WALKED {
                true => "at least ",
                false => "",
            };
            (pages > 1)
                .then(|| format!("a TIFF of {more}{pages} pages (a stack of frames in one file)"))
        }
        image::ImageFormat::WebP => {
            let webp = image_webp::WebPDecoder::new(r).ok()?;
            let frames = webp.num_frames();
            (webp.is_animated() && frames > 1).then(|| {
                format!(
                    "an animated WebP of {frames} frames (a stack of frames in one file), \
                     whose frames are not read: its decoder composes them a level off; save \
                     them as a TIFF of pages or as files of their own"
                )
            })
        }
        _ => None,
    }
}

/// True when `tiff`'s current directory is a reduced-resolution page (a
/// thumbnail: NewSubfileType bit 0), not a frame of its own.
pub(crate) fn is_thumbnail<R: std::io::Read + std::io::Seek>(
    tiff: &mut tiff::decoder::Decoder<R>,
) -> bool {
    tiff.find_tag_unsigned::<u32>(tiff::tags::Tag::NewSubfileType)
        .ok()
        .flatten()
        .is_some_and(|t| t & 1 == 1)
}

/// Bytes of a JPEG read for its start-of-frame marker: the segments before
/// it (EXIF, ICC profiles) are at most 64 KiB each.
const JPEG_HEAD_BYTES: u64 = 1 << 20;

/// Why `path` was not decoded: [`unread_jpeg_coding`]'s words for a JPEG
/// of a coding the decoder does not read, else `what` and the decoder's.
fn file_refusal(path: &Path, what: &str, e: image::ImageError) -> Error {
    use std::io::Read;
    let mut head = Vec::new();
    let read =
        std::fs::File::open(path).and_then(|f| f.take(JPEG_HEAD_BYTES).read_to_end(&mut head));
    Error::image(
        path,
        refusal(what, &e, &head[..read.map_or(0, |_| head.len())]),
    )
}

/// `what` and the decoder's error `e`, or, when `bytes` (the picture, or
/// its first [`JPEG_HEAD_BYTES`]) are a JPEG of a coding the decoder does
/// not read, that, since the decoder's words do not say it (a lossless
/// JPEG is refused as "Number of components cannot be zero").
pub(crate) fn refusal(what: &str, e: &image::ImageError, bytes: &[u8]) -> String {
    use image::error::{ImageFormatHint, UnsupportedErrorKind};
    if let Some(why) = unread_jpeg_coding(bytes) {
        return why;
    }
    match e {
        image::ImageError::Unsupported(u) => match (u.kind(), u.format_hint()) {
            (UnsupportedErrorKind::Format(_), ImageFormatHint::Exact(format)) => format!(
                "{what}: a {} picture, a format frames are not read in; they are read from {}",
                (format.extensions_str().first())
                    .map_or_else(|| format!("{format:?}"), |x| x.to_uppercase()),
                crate::source::FRAME_FORMATS
            ),
            _ => format!("{what}: {e}"),
        },
        // The decoders' words for these ("failed to fill whole buffer",
        // "Memory limit exceeded") do not say what is wrong with the file.
        _ if cut_short(e) => format!("{what}: the file ends before its picture does (cut short)"),
        image::ImageError::Limits(_) => format!(
            "{what}: its header asks for more than a frame may take ({e}): a damaged file, \
             or not a camera's frame"
        ),
        _ => format!("{what}: {e}"),
    }
}

/// True when a decoder's error `e` is, or was caused by, reading past the
/// end of the file (some decoders wrap it in their own format error).
fn cut_short(e: &image::ImageError) -> bool {
    let eof = |io: &std::io::Error| io.kind() == std::io::ErrorKind::UnexpectedEof;
    if let image::ImageError::IoError(io) = e {
        return eof(io);
    }
    let mut source = std::error::Error::source(e);
    while let Some(cause) = source {
        if cause.downcast_ref::<std::io::Error>().is_some_and(eof) {
            return true;
        }
        source = cause.source();
    }
    false
}

/// True for the picture formats frames are read in, told by their bytes
/// ([`crate::source::FRAME_FORMATS`]).
pub(crate) fn is_frame_format(format: image::ImageFormat) -> bool {
    use image::ImageFormat::{Bmp, Jpeg, Png, Pnm, Tiff, WebP};
    matches!(format, Png | Jpeg | Bmp | Tiff | WebP | Pnm)
}

/// The JPEG coding of `bytes` when the decoder (zune-jpeg: 8-bit baseline,
/// extended and progressive Huffman coding) does not read it, from the
/// first start-of-frame marker (ITU T.81, B.1.1.3, table B.1); `None` for
/// one it reads, or bytes that are not a JPEG whose markers can be walked.
fn unread_jpeg_coding(bytes: &[u8]) -> Option<String> {
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    let mut at = 2usize;
    loop {
        // A marker may follow fill bytes of 0xFF.
        while bytes.get(at..at + 2) == Some(&[0xFF, 0xFF]) {
            at += 1;
        }
        let (&ff, &marker) = (bytes.get(at)?, bytes.get(at + 1)?);
        if ff != 0xFF {
            return None;
        }
        match marker {
            // Markers without a segment: TEM, RSTn, SOI.
            0x01 | 0xD0..=0xD8 => {
                at += 2;
                continue;
            }
            // A scan or the end before any frame header.
            0xD9 | 0xDA => return None,
            // SOFn: every 0xCn but DHT (C4), JPG (C8) and DAC (CC).
            0xC0..=0xCF if !matches!(marker, 0xC4 | 0xC8 | 0xCC) => {
                return jpeg_coding_words(marker - 0xC0, *bytes.get(at + 4)?);
            }
            _ => {}
        }
        let length = u16::from_be_bytes([*bytes.get(at + 2)?, *bytes.get(at + 3)?]) as usize;
        if length < 2 {
            return None;
        }
        at += 2 + length;
    }
}

/// The refusal of a JPEG whose frame header is SOF`n` with samples of
/// `precision` bits, `None` for one the decoder reads.
fn jpeg_coding_words(n: u8, precision: u8) -> Option<String> {
    let coding = match n {
        0..=2 => None,
        3 => Some("a lossless"),
        5 => Some("a hierarchical"),
        6 => Some("a hierarchical progressive"),
        7 => Some("a hierarchical lossless"),
        9 => Some("an arithmetic-coded"),
        10 => Some("an arithmetic-coded progressive"),
        11 => Some("an arithmetic-coded lossless"),
        _ => Some("an arithmetic-coded hierarchical"),
    };
    let save = "save the frames as PNG (lossless too) or as baseline JPEG";
    match (coding, precision) {
        (Some(coding), _) => Some(format!(
            "{coding} JPEG (SOF{n}), a JPEG coding that is not read: {save}"
        )),
        (None, 8) => None,
        (None, bits) => Some(format!(
            "a {bits}-bit JPEG; frames are read with 8 bits per channel: {save}, \
             your camera's levels scaled to 0-255"
        )),
    }
}

/// What an opened picture's header says, and its EXIF orientation.
pub(crate) fn header_of(decoder: &mut impl ImageDecoder) -> (ImageHeader, Orientation) {
    let orientation = exif_orientation(decoder);
    let turned_sideways = turns_sideways(orientation);
    let (stored_width, stored_height) = decoder.dimensions();
    let (width, height) = match turned_sideways {
        true => (stored_height, stored_width),
        false => (stored_width, stored_height),
    };
    let header = ImageHeader {
        width,
        height,
        turned_sideways,
        color: decoder.color_type(),
    };
    (header, orientation)
}

/// Read `path`'s header only: its size as shown (its EXIF orientation
/// applied, as decoding applies it) and pixel format, so a folder's
/// frames can be checked before any is decoded.
pub fn image_header(path: &Path) -> Result<ImageHeader> {
    Ok(header_of(&mut open_decoder(path)?).0)
}

/// Refuse a picture whose header claims more pixels than 8K.
fn within_limit(path: &Path, header: &ImageHeader) -> Result<()> {
    beyond_limit(header.width, header.height).map_or(Ok(()), |why| Err(Error::image(path, why)))
}

/// Why a picture of `w` x `h` pixels is not decoded: more than 8K.
pub(crate) fn beyond_limit(w: u32, h: u32) -> Option<String> {
    (w as u64 * h as u64 > MAX_IMAGE_PIXELS).then(|| {
        format!(
            "image is {w}x{h}, larger than 8K ({MAX_IMAGE_PIXELS} pixels); refusing to decode it"
        )
    })
}

/// What [`load_rgb`] expects of a frame file.
const RGB_FRAME: &str = "8-bit RGB (or 8-bit greyscale)";

/// True for the pixel formats [`load_rgb`] reads (8 bits per channel; an
/// alpha channel is dropped when every pixel is opaque, which only the
/// pixels tell).
fn rgb_readable(color: ColorType) -> bool {
    matches!(
        color,
        ColorType::Rgb8 | ColorType::L8 | ColorType::Rgba8 | ColorType::La8
    )
}

/// `path`'s header, checked as [`load_rgb`] will read the frame: a header
/// that can be read, at most 8K pixels, 8 bits per channel. A folder's
/// frames are checked this way before any is decoded, so a bad one is
/// named at once, not after every frame before it.
pub fn rgb_frame_header(path: &Path) -> Result<ImageHeader> {
    let header = image_header(path)?;
    match rgb_header_refusal(&header) {
        Some(why) => Err(Error::image(path, why)),
        None => Ok(header),
    }
}

/// Why a picture of `header` would not be read as an RGB frame (past 8K,
/// not 8 bits per channel); `None` when [`rgb_frame`] will take it.
pub(crate) fn rgb_header_refusal(header: &ImageHeader) -> Option<String> {
    beyond_limit(header.width, header.height)
        .or_else(|| (!rgb_readable(header.color)).then(|| not_eight_bit(header.color, RGB_FRAME)))
}

/// `path` decoded as it is shown, opened once: its header checked against
/// 8K before its pixels are allocated.
fn decode(path: &Path) -> Result<DynamicImage> {
    let mut decoder = open_decoder(path)?;
    let (header, orientation) = header_of(&mut decoder);
    within_limit(path, &header)?;
    upright(decoder, orientation).map_err(|e| file_refusal(path, "cannot decode image", e))
}

/// Luma from RGB exactly as OpenCV's `cvtColor(RGB2GRAY)` does for 8-bit
/// (14-bit fixed point, weights 0.299/0.587/0.114), so a colour capture
/// preprocesses as it would in the authors' code.
pub fn rgb_to_grey(rgb: &[u8]) -> Vec<u8> {
    rgb.chunks_exact(3)
        .map(|p| {
            let v = p[0] as u32 * 4899 + p[1] as u32 * 9617 + p[2] as u32 * 1868 + (1 << 13);
            (v >> 14) as u8
        })
        .collect()
}

/// RGB from grey, each level repeated in the three channels: how a grey
/// frame is read where a colour one is.
pub fn grey_to_rgb(grey: &[u8]) -> Vec<u8> {
    grey.iter().flat_map(|&v| [v, v, v]).collect()
}

/// The pixels of `channels` interleaved 8-bit channels, the last alpha,
/// without it when every pixel is opaque (as tools that add an alpha
/// channel save a camera's frames); otherwise the count of pixels that are
/// not, since what lies under a transparent pixel is not the sensor's
/// picture. Frame files and Python's arrays go through this one rule.
pub fn drop_opaque_alpha(data: &[u8], channels: usize) -> std::result::Result<Vec<u8>, usize> {
    if channels < 2 {
        // No colour channel beside an alpha: nothing to drop.
        return Ok(data.to_vec());
    }
    let see_through = data
        .chunks_exact(channels)
        .filter(|p| p[channels - 1] != u8::MAX)
        .count();
    if see_through > 0 {
        return Err(see_through);
    }
    Ok(data
        .chunks_exact(channels)
        .flat_map(|p| p[..channels - 1].iter().copied())
        .collect())
}

/// [`drop_opaque_alpha`] of a decoded file, its refusal worded.
fn opaque(color: ColorType, data: &[u8], channels: usize) -> std::result::Result<Vec<u8>, String> {
    drop_opaque_alpha(data, channels).map_err(|n| {
        format!(
            "{} image with {n} of its {} pixels not opaque; expected 8-bit RGB or greyscale \
             (an alpha channel is dropped only when every pixel is opaque)",
            describe(color),
            data.len() / channels
        )
    })
}

/// Load a frame file as 8-bit greyscale. 8-bit RGB is converted to grey, and an
/// alpha channel dropped when every pixel is opaque; anything else
/// (16-bit, transparent pixels) is rejected with an error naming the file
/// and the format found.
pub fn load_grey(path: impl AsRef<Path>) -> Result<GreyImage> {
    let path = path.as_ref();
    let img = decode(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let color = img.color();
    let data = match img {
        DynamicImage::ImageLuma8(buf) => Ok(buf.into_raw()),
        DynamicImage::ImageRgb8(buf) => Ok(rgb_to_grey(buf.as_raw())),
        DynamicImage::ImageLumaA8(buf) => opaque(color, buf.as_raw(), 2),
        DynamicImage::ImageRgba8(buf) => {
            opaque(color, buf.as_raw(), 4).map(|rgb| rgb_to_grey(&rgb))
        }
        _ => Err(not_eight_bit(color, "8-bit greyscale (or 8-bit RGB)")),
    }
    .map_err(|e| Error::image(path, e))?;
    grey_image(w, h, data).map_err(|e| Error::image(path, e.to_string()))
}

/// Load a frame file as 8-bit RGB. 8-bit greyscale is expanded to RGB, and an alpha
/// channel dropped when every pixel is opaque; 16-bit images and
/// transparent pixels are rejected with an error naming the file.
pub fn load_rgb(path: impl AsRef<Path>) -> Result<RgbImage> {
    let path = path.as_ref();
    rgb_frame(decode(path)?).map_err(|e| Error::image(path, e))
}

/// A decoded picture as an 8-bit RGB frame, the one rule of a frame file
/// and a stack's page: 8-bit greyscale expanded, an alpha channel dropped
/// when every pixel is opaque; other depths and transparent pixels
/// refused, saying why.
pub(crate) fn rgb_frame(img: DynamicImage) -> std::result::Result<RgbImage, String> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let color = img.color();
    let data = match img {
        DynamicImage::ImageRgb8(buf) => Ok(buf.into_raw()),
        DynamicImage::ImageLuma8(buf) => Ok(grey_to_rgb(buf.as_raw())),
        DynamicImage::ImageRgba8(buf) => opaque(color, buf.as_raw(), 4),
        DynamicImage::ImageLumaA8(buf) => opaque(color, buf.as_raw(), 2).map(|g| grey_to_rgb(&g)),
        _ => Err(not_eight_bit(color, RGB_FRAME)),
    }?;
    rgb_image(w, h, data).map_err(|e| e.to_string())
}

/// Check an image's size, naming the file when it is wrong.
pub fn expect_size(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    expected: (usize, usize),
) -> Result<()> {
    if (width, height) != expected {
        return Err(Error::image(
            path,
            format!(
                "image is {width}x{height}, expected {}x{}",
                expected.0, expected.1
            ),
        ));
    }
    Ok(())
}

/// Encode `data` as a PNG of `color` and write it atomically.
fn save_png(
    path: &Path,
    width: usize,
    height: usize,
    data: &[u8],
    color: image::ExtendedColorType,
) -> Result<()> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(data, width as u32, height as u32, color)
        .map_err(|e| Error::io(path, std::io::Error::other(e)))?;
    crate::io::write_atomic(path, &bytes)
}

/// Save an 8-bit grey PNG atomically.
pub fn save_grey_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    data: &[u8],
) -> Result<()> {
    save_png(
        path.as_ref(),
        width,
        height,
        data,
        image::ExtendedColorType::L8,
    )
}

/// Save an 8-bit RGB PNG atomically.
pub fn save_rgb_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    data: &[u8],
) -> Result<()> {
    save_png(
        path.as_ref(),
        width,
        height,
        data,
        image::ExtendedColorType::Rgb8,
    )
}

/// The least value of a tendon pixel in a mask PNG (0 = background,
/// 255 = tendon): every reader of a mask's bits compares with this.
pub const MASK_TENDON_MIN: u8 = 128;

/// Load a tendon mask (values of [`MASK_TENDON_MIN`] and more count as tendon),
/// refused when it has marked pixels but none reaches [`MASK_TENDON_MIN`]:
/// a 0/1 mask, as `mask.astype(numpy.uint8)` saves one, would otherwise be
/// read as empty and train a segmenter to find nothing.
pub fn load_mask(path: impl AsRef<Path>) -> Result<GreyImage> {
    let path = path.as_ref();
    let img = load_grey(path)?;
    let largest = img.as_slice().iter().copied().max().unwrap_or(0);
    if (1..MASK_TENDON_MIN).contains(&largest) {
        return Err(Error::image(
            path,
            format!(
                "a tendon mask whose largest value is {largest}: masks are 0 = background \
                 and 255 = tendon (a 0/1 mask needs multiplying by 255)"
            ),
        ));
    }
    Ok(img)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrupt_and_truncated_png_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("frame.png");
        save_grey_png(&p, 8, 8, &[7u8; 64]).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let trunc = dir.path().join("truncated.png");
        std::fs::write(&trunc, &bytes[..bytes.len() / 2]).unwrap();
        let e = load_grey(&trunc).err().unwrap().to_string();
        assert!(e.contains("truncated.png"), "{e}");
        let junk = dir.path().join("junk.png");
        std::fs::write(&junk, b"not a png at all").unwrap();
        let e = load_grey(&junk).err().unwrap().to_string();
        assert!(e.contains("junk.png"), "{e}");
        assert_eq!(load_grey(&p).unwrap().as_slice(), &[7u8; 64][..]);
    }

    #[test]
    fn frame_files_are_read_by_their_bytes_in_the_formats_opencv_reads_and_others_are_named() {
        // A 24x16 frame of distinct levels saved as a lab camera's tool
        // saves it (BMP, TIFF, lossless WebP, PPM) beside PNG: each reads
        // as the PNG does, whatever its name says (before, a folder of them
        // held "no PNG or JPEG frames" and a BMP named .png was refused).
        use image::ImageFormat::{Bmp, Png, Pnm, Tiff, WebP};
        let (w, h) = (24u32, 16u32);
        let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 251) as u8).collect();
        let frame = DynamicImage::ImageRgb8(image::RgbImage::from_raw(w, h, rgb.clone()).unwrap());
        let dir = tempfile::tempdir().unwrap();
        let files = [
            ("f0.png", Png),
            ("f1.bmp", Bmp),
            ("f2.tif", Tiff),
            ("f3.tiff", Tiff),
            ("f4.webp", WebP),
            ("f5.ppm", Pnm),
            ("f6-a-bmp-named.png", Bmp),
            ("f7-a-tiff-named.jpg", Tiff),
        ];
        for (name, format) in files {
            let path = dir.path().join(name);
            frame.save_with_format(&path, format).unwrap();
            let header = rgb_frame_header(&path).unwrap();
            assert_eq!((header.width, header.height), (w, h), "{name}");
            assert_eq!(load_rgb(&path).unwrap().as_slice(), &rgb[..], "{name}");
        }
        let grey: Vec<u8> = (0..w * h).map(|i| (i * 3 % 256) as u8).collect();
        let pgm = dir.path().join("f8.pgm");
        DynamicImage::ImageLuma8(image::GrayImage::from_raw(w, h, grey.clone()).unwrap())
            .save_with_format(&pgm, Pnm)
            .unwrap();
        assert_eq!(load_grey(&pgm).unwrap().as_slice(), &grey[..]);
        // A folder holding them reads each, in the order of its numbers.
        let list = crate::source::FrameList::open(dir.path()).unwrap();
        let names: Vec<_> = (list.frames.iter())
            .map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), files.len() + 1, "{names:?}");
        assert!(list.ignored.is_empty(), "{:?}", list.ignored);
        assert!(names[1] == "f1.bmp" && names[8] == "f8.pgm", "{names:?}");

        // A JPEG of a coding the decoder does not read is named, by the
        // header pass, by decoding and in a bag's compressed image (before:
        // lossless read "Number of components cannot be zero").
        let jpeg = |sof: u8, precision: u8| {
            let mut b = vec![0xFF, 0xD8, 0xFF, 0xE0, 0, 16];
            b.extend(b"JFIF\0\x01\x01\0\0\x01\0\x01\0\0");
            // A fill byte, then the frame header: 24x16, three components.
            b.extend([0xFF, 0xFF, 0xC0 + sof, 0, 17, precision, 0, 16, 0, 24, 3]);
            b.extend([1, 0x11, 0, 2, 0x11, 0, 3, 0x11, 0, 0xFF, 0xD9]);
            b
        };
        for (sof, precision, words) in [
            (
                3,
                8,
                "a lossless JPEG (SOF3), a JPEG coding that is not read: save the frames as PNG",
            ),
            (9, 8, "an arithmetic-coded JPEG (SOF9)"),
            (7, 8, "a hierarchical lossless JPEG (SOF7)"),
            (
                1,
                12,
                "a 12-bit JPEG; frames are read with 8 bits per channel",
            ),
        ] {
            let path = dir.path().join(format!("sof{sof}-{precision}.jpg"));
            let bytes = jpeg(sof, precision);
            std::fs::write(&path, &bytes).unwrap();
            for e in [
                rgb_frame_header(&path).unwrap_err().to_string(),
                load_grey(&path).err().unwrap().to_string(),
            ] {
                assert!(e.contains(&format!("sof{sof}-{precision}.jpg")), "{e}");
                assert!(e.contains(words), "{e}");
            }
            let message = crate::bag::messages::CompressedImage {
                header: Default::default(),
                format: "jpeg".into(),
                data: &bytes,
            };
            let e = message.to_rgb().err().unwrap();
            assert!(e.contains(words), "{e}");
        }
        // A frame cut short says so (before: "failed to fill whole buffer").
        let bmp = std::fs::read(dir.path().join("f1.bmp")).unwrap();
        let path = dir.path().join("cut.bmp");
        std::fs::write(&path, &bmp[..bmp.len() - 100]).unwrap();
        let e = load_rgb(&path).err().unwrap().to_string();
        assert!(
            e.contains("cut.bmp: cannot decode image: the file ends before its picture does"),
            "{e}"
        );
        // A baseline JPEG cut short keeps the decoder's own words.
        let path = dir.path().join("cut.jpg");
        std::fs::write(&path, jpeg(0, 8)).unwrap();
        let e = load_rgb(&path).err().unwrap().to_string();
        assert!(e.contains("cut.jpg") && !e.contains("JPEG coding"), "{e}");
        // A picture of another format is named as such.
        let gif = dir.path().join("anim.png");
        std::fs::write(&gif, b"GIF89a\x01\0\x01\0\0\0\0;").unwrap();
        let e = load_rgb(&gif).err().unwrap().to_string();
        assert!(
            e.contains("anim.png") && e.contains("a GIF picture, a format frames are not read in"),
            "{e}"
        );
    }

    /// An animated WebP of `frames` copies of `frame`'s picture (a lossless
    /// WebP, its `VP8L` chunk reused as each animation frame's).
    fn animated_webp(frame: &[u8], (w, h): (u32, u32), frames: usize) -> Vec<u8> {
        animation_of(&vec![frame; frames], (w, h))
    }

    /// An animated WebP whose frames are `pictures` (lossless WebPs of
    /// `w` x `h`, each `VP8L` chunk an animation frame's).
    fn animation_of(pictures: &[&[u8]], (w, h): (u32, u32)) -> Vec<u8> {
        let le24 = |v: u32| v.to_le_bytes()[..3].to_vec();
        let mut body = b"WEBPVP8X".to_vec();
        body.extend(10u32.to_le_bytes());
        body.extend([0x02, 0, 0, 0]); // the animation flag
        body.extend(le24(w - 1));
        body.extend(le24(h - 1));
        body.extend(b"ANIM");
        body.extend(6u32.to_le_bytes());
        body.extend([0; 6]); // background colour, loop forever
        for picture in pictures {
            let vp8l = &picture[12..]; // after "RIFF", its size and "WEBP"
            let mut anmf = [le24(0), le24(0), le24(w - 1), le24(h - 1), le24(100)].concat();
            anmf.push(0b10); // drawn over the canvas, not blended
            anmf.extend(vp8l);
            body.extend(b"ANMF");
            body.extend((anmf.len() as u32).to_le_bytes());
            body.extend(&anmf);
            if anmf.len() % 2 == 1 {
                body.push(0);
            }
        }
        let mut riff = b"RIFF".to_vec();
        riff.extend((body.len() as u32).to_le_bytes());
        riff.extend(body);
        riff
    }

    #[test]
    fn a_stack_of_frames_in_one_file_is_refused_not_read_as_its_first() {
        // A TIFF of several pages (ImageJ's stacks, a camera's burst) or an
        // animated WebP holds many frames; decoders, OpenCV's imread and
        // PIL give the first alone. Read as one frame, the rest would be
        // lost without a word: it is refused, saying what to do. A TIFF's
        // thumbnail page (reduced resolution) is no frame of its own.
        use tiff::encoder::{TiffEncoder, colortype::RGB8};
        let (w, h) = (24u32, 16u32);
        let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 5 % 253) as u8).collect();
        let dir = tempfile::tempdir().unwrap();
        let tiff_of = |pages: usize, thumbnail: bool| {
            let mut bytes = std::io::Cursor::new(Vec::new());
            let mut tiff = TiffEncoder::new(&mut bytes).unwrap();
            for _ in 0..pages {
                tiff.write_image::<RGB8>(w, h, &rgb).unwrap();
            }
            if thumbnail {
                let mut page = tiff.new_image::<RGB8>(w / 2, h / 2).unwrap();
                (page.encoder())
                    .write_tag(tiff::tags::Tag::NewSubfileType, 1u32)
                    .unwrap();
                page.write_data(&rgb[..(w * h * 3 / 4) as usize]).unwrap();
            }
            bytes.into_inner()
        };
        let mut webp = Vec::new();
        DynamicImage::ImageRgb8(image::RgbImage::from_raw(w, h, rgb.clone()).unwrap())
            .write_to(
                &mut std::io::Cursor::new(&mut webp),
                image::ImageFormat::WebP,
            )
            .unwrap();
        let cases = [
            (
                "stack.tif",
                tiff_of(3, false),
                Some("a TIFF of 3 pages (a stack of frames in one file)"),
            ),
            ("thumbnailed.tif", tiff_of(1, true), None),
            ("one.tif", tiff_of(1, false), None),
            (
                "burst.webp",
                animated_webp(&webp, (w, h), 2),
                Some("an animated WebP of 2 frames (a stack of frames in one file)"),
            ),
            ("one-frame.webp", animated_webp(&webp, (w, h), 1), None),
            ("still.webp", webp.clone(), None),
        ];
        for (name, bytes, refusal) in cases {
            let path = dir.path().join(name);
            std::fs::write(&path, &bytes).unwrap();
            let message = crate::bag::messages::CompressedImage {
                header: Default::default(),
                format: "tiff".into(),
                data: &bytes,
            };
            match refusal {
                Some(words) => {
                    // A frame file read as one picture says how to read it
                    // whole (a TIFF), or why it is not read (an animated
                    // WebP); a message's picture is one frame.
                    let here = match name.ends_with(".tif") {
                        true => {
                            "a frame file is one picture here (a TIFF stack given alone to tactile run"
                        }
                        false => "whose frames are not read: its decoder composes them a level off",
                    };
                    for e in [
                        rgb_frame_header(&path).unwrap_err().to_string(),
                        load_rgb(&path).err().unwrap().to_string(),
                    ] {
                        assert!(e.contains(words) && e.contains(here), "{name}: {e}");
                    }
                    let e = message.to_rgb().err().unwrap();
                    assert!(
                        e.contains(words) && e.contains("a message's picture is one frame"),
                        "{name}: {e}"
                    );
                }
                None => {
                    assert_eq!(load_rgb(&path).unwrap().as_slice(), &rgb[..], "{name}");
                    assert_eq!(message.to_rgb().unwrap().as_slice(), &rgb[..], "{name}");
                }
            }
        }
    }

    #[test]
    fn a_stack_given_alone_is_read_page_by_page_as_a_video_is() {
        // ImageJ's and Micro-Manager's stacks and a camera's burst are one
        // TIFF of many pages. Given alone as the source, each page is a
        // frame, in order, named by its number as a video's frames are;
        // thumbnails are skipped, each page's orientation tag applied, a
        // page no reader takes is named by its number, and a stack cut
        // short gives the pages before the cut. An animated WebP is
        // refused (its decoder composes frames a level off).
        use crate::source::{FrameSource, SourceKind, SourceOptions, SourceSpec};
        use tiff::encoder::{TiffEncoder, colortype::Gray16, colortype::RGB8};
        let (w, h) = (24u32, 16u32);
        let page = |k: u32| -> Vec<u8> {
            (0..w * h * 3)
                .map(|i| ((i * 5 + k * 41) % 253) as u8)
                .collect()
        };
        let dir = tempfile::tempdir().unwrap();
        let frames_of = |path: &Path| {
            let spec = SourceSpec::Path(path.to_path_buf());
            FrameSource::open(&spec, SourceOptions::default()).and_then(|mut source| {
                assert_eq!(source.kind(), SourceKind::Stack);
                let size = source.size();
                let mut got = Vec::new();
                while let Some(f) = source.next_frame()? {
                    got.push((
                        f.name,
                        f.image.width(),
                        f.image.height(),
                        f.image.as_slice().to_vec(),
                    ));
                }
                // A stack's length is known before its pages are read (a
                // progress bar's total).
                assert_eq!(source.known_frames(), Some(got.len() as u64));
                Ok((size, got))
            })
        };
        // Three pages with a thumbnail after the first and a page turned a
        // quarter (stored 16x24 with Orientation 6: shown 24x16).
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut tiff = TiffEncoder::new(&mut bytes).unwrap();
        tiff.write_image::<RGB8>(w, h, &page(0)).unwrap();
        let mut thumb = tiff.new_image::<RGB8>(w / 2, h / 2).unwrap();
        (thumb.encoder())
            .write_tag(tiff::tags::Tag::NewSubfileType, 1u32)
            .unwrap();
        thumb
            .write_data(&page(9)[..(w * h * 3 / 4) as usize])
            .unwrap();
        tiff.write_image::<RGB8>(w, h, &page(1)).unwrap();
        // Page 2 shown upright is page(2); stored turned back a quarter.
        let shown = image::RgbImage::from_raw(w, h, page(2)).unwrap();
        let stored = image::imageops::rotate270(&shown);
        let mut turned = tiff.new_image::<RGB8>(h, w).unwrap();
        (turned.encoder())
            .write_tag(tiff::tags::Tag::Orientation, 6u16)
            .unwrap();
        turned.write_data(stored.as_raw()).unwrap();
        let stack = dir.path().join("stack.tif");
        std::fs::write(&stack, bytes.into_inner()).unwrap();
        let (size, got) = frames_of(&stack).unwrap();
        assert_eq!(size, Some((w as usize, h as usize)));
        assert_eq!(got.len(), 3, "thumbnail skipped");
        for (k, (name, fw, fh, pixels)) in got.iter().enumerate() {
            assert_eq!(name, &format!("{k:06}"));
            assert_eq!((*fw, *fh), (w as usize, h as usize), "frame {k}");
            assert!(
                pixels == &page(k as u32),
                "frame {k}: not its page's pixels"
            );
        }
        // A BigTIFF stack reads alike (its header's offset is 8 bytes).
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut big = TiffEncoder::new_big(&mut bytes).unwrap();
        for k in 0..2 {
            big.write_image::<RGB8>(w, h, &page(k)).unwrap();
        }
        let big_stack = dir.path().join("big.tiff");
        std::fs::write(&big_stack, bytes.into_inner()).unwrap();
        let (_, got) = frames_of(&big_stack).unwrap();
        assert!(got.len() == 2 && got[1].3 == page(1), "BigTIFF pages");
        // A stack cut short (a recording stopped while it was written)
        // gives the pages before the cut, with a warning, as a video cut
        // short does.
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut tiff = TiffEncoder::new(&mut bytes).unwrap();
        for k in 0..4 {
            tiff.write_image::<RGB8>(w, h, &page(k)).unwrap();
        }
        let whole = bytes.into_inner();
        let cut = dir.path().join("cut.tif");
        std::fs::write(&cut, &whole[..whole.len() * 7 / 10]).unwrap();
        let spec = SourceSpec::Path(cut.clone());
        let mut source = FrameSource::open(&spec, SourceOptions::default()).unwrap();
        let mut given = Vec::new();
        while let Some(f) = source.next_frame().unwrap() {
            assert!(f.image.as_slice() == page(given.len() as u32), "{}", f.name);
            given.push(f.name);
        }
        assert_eq!(given, ["000000", "000001"]);
        assert_eq!(source.known_frames(), Some(2));
        let late = source.late_warnings().join("\n");
        assert!(
            late.contains(
                "cut.tif ends inside the directory of frame 000002 of the stack (cut short): \
                 the 2 frames before it are read"
            ),
            "{late}"
        );
        std::fs::remove_file(&cut).unwrap();
        // An animated WebP is refused as a source: image-webp composes its
        // frames a level off (libwebp gives them exactly).
        let webp = |k: u32| {
            let mut out = Vec::new();
            DynamicImage::ImageRgb8(image::RgbImage::from_raw(w, h, page(k)).unwrap())
                .write_to(
                    &mut std::io::Cursor::new(&mut out),
                    image::ImageFormat::WebP,
                )
                .unwrap();
            out
        };
        let (a, b) = (webp(3), webp(4));
        let anim = dir.path().join("burst.webp");
        std::fs::write(&anim, animation_of(&[&a, &b, &a], (w, h))).unwrap();
        let spec = SourceSpec::Path(anim.clone());
        let e = FrameSource::open(&spec, SourceOptions::default())
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("burst.webp: an animated WebP of 3 frames")
                && e.contains("whose frames are not read"),
            "{e}"
        );
        // A page of 16 bits is named by its number, with the usual advice.
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut tiff = TiffEncoder::new(&mut bytes).unwrap();
        tiff.write_image::<RGB8>(w, h, &page(0)).unwrap();
        tiff.write_image::<Gray16>(w, h, &vec![4000u16; (w * h) as usize])
            .unwrap();
        let deep = dir.path().join("deep.tif");
        std::fs::write(&deep, bytes.into_inner()).unwrap();
        let e = frames_of(&deep).unwrap_err().to_string();
        assert!(
            e.contains("deep.tif")
                && e.contains("frame 000001 of the stack")
                && e.contains("16-bit greyscale"),
            "{e}"
        );
        // One picture, or a stack in a folder, is not a stack source.
        let one = dir.path().join("one.tif");
        let mut bytes = std::io::Cursor::new(Vec::new());
        TiffEncoder::new(&mut bytes)
            .unwrap()
            .write_image::<RGB8>(w, h, &page(0))
            .unwrap();
        std::fs::write(&one, bytes.into_inner()).unwrap();
        assert!(
            crate::stack::StackFrames::open(&one, None)
                .unwrap()
                .is_none()
        );
        let spec = SourceSpec::Path(dir.path().to_path_buf());
        let e = FrameSource::open(&spec, SourceOptions::default())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("a frame file is one picture here"), "{e}");
    }

    /// A TIFF block of EXIF metadata holding one tag, the orientation
    /// (little-endian, as cameras write it): what a camera held on its side
    /// writes beside pixels stored as its sensor reads them.
    fn exif_orientation_block(orientation: u16) -> Vec<u8> {
        let mut b = b"II*\0".to_vec();
        b.extend(8u32.to_le_bytes()); // the first directory's offset
        b.extend(1u16.to_le_bytes()); // one entry
        b.extend(0x0112u16.to_le_bytes()); // Orientation
        b.extend(3u16.to_le_bytes()); // SHORT
        b.extend(1u32.to_le_bytes()); // one value
        b.extend(orientation.to_le_bytes());
        b.extend([0, 0]); // the value's field is four bytes
        b.extend(0u32.to_le_bytes()); // no next directory
        b
    }

    #[test]
    fn a_pictures_exif_orientation_is_applied_as_opencv_applies_it() {
        // A 32x16 picture, its left half dark and right half bright, stored
        // with EXIF orientation 6 ("turn 90 degrees clockwise to show"), as
        // a phone or a camera mounted on its side saves it. OpenCV's imread
        // and imdecode show it 16x32, the dark half on top; so must every
        // reader here, the header pass included (before, 32x16 as stored).
        use image::ImageEncoder as _;
        let (w, h) = (32u32, 16u32);
        let stored: Vec<u8> = (0..h)
            .flat_map(|_| (0..w).flat_map(|x| if x < w / 2 { [20u8; 3] } else { [230u8; 3] }))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let jpeg = dir.path().join("side.jpg");
        let mut bytes = Vec::new();
        let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95);
        enc.set_exif_metadata(exif_orientation_block(6)).unwrap();
        enc.write_image(&stored, w, h, image::ExtendedColorType::Rgb8)
            .unwrap();
        std::fs::write(&jpeg, &bytes).unwrap();
        let png = dir.path().join("side.png");
        let mut bytes = Vec::new();
        let mut enc = image::codecs::png::PngEncoder::new(&mut bytes);
        enc.set_exif_metadata(exif_orientation_block(6)).unwrap();
        enc.write_image(&stored, w, h, image::ExtendedColorType::Rgb8)
            .unwrap();
        std::fs::write(&png, &bytes).unwrap();
        // A TIFF says it in its own Orientation tag, which OpenCV applies too.
        let tif = dir.path().join("side.tif");
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut tiff = tiff::encoder::TiffEncoder::new(&mut bytes).unwrap();
        let mut page = (tiff.new_image::<tiff::encoder::colortype::RGB8>(w, h)).unwrap();
        (page.encoder())
            .write_tag(tiff::tags::Tag::Orientation, 6u16)
            .unwrap();
        page.write_data(&stored).unwrap();
        std::fs::write(&tif, bytes.into_inner()).unwrap();
        for path in [&jpeg, &png, &tif] {
            let header = rgb_frame_header(path).unwrap();
            assert_eq!((header.width, header.height), (h, w), "{path:?}");
            let rgb = load_rgb(path).unwrap();
            assert_eq!((rgb.width(), rgb.height()), (h as usize, w as usize));
            let at = |x: usize, y: usize| rgb.as_slice()[(y * h as usize + x) * 3];
            assert!(at(8, 4) < 60 && at(8, 27) > 190, "{path:?}");
            let grey = load_grey(path).unwrap();
            assert_eq!((grey.width(), grey.height()), (h as usize, w as usize));
        }
        // A dataset whose manifest gives the stored size (written by a
        // tool that reads pixels as stored, PIL's Image.open) is refused
        // saying why the frame reads turned.
        let e = crate::dataset::expect_manifest_size(&png, (h as usize, w as usize), (32, 16))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("side.png: is 16x32 as shown: its EXIF orientation turns the 32x16 pixels")
                && e.contains("make the manifest say 16x32"),
            "{e}"
        );
        // A bag's compressed image is decoded the same way.
        let png_bytes = std::fs::read(&png).unwrap();
        let msg = crate::bag::messages::CompressedImage {
            header: Default::default(),
            format: "png".into(),
            data: &png_bytes,
        };
        let rgb = msg.to_rgb().unwrap();
        assert_eq!((rgb.width(), rgb.height()), (h as usize, w as usize));
        assert_eq!(rgb.as_slice(), load_rgb(&png).unwrap().as_slice());
        // Orientation 1, and a damaged block, leave the picture as stored.
        for block in [exif_orientation_block(1), b"II*\0\xff\xff".to_vec()] {
            let mut bytes = Vec::new();
            let mut enc = image::codecs::png::PngEncoder::new(&mut bytes);
            enc.set_exif_metadata(block).unwrap();
            enc.write_image(&stored, w, h, image::ExtendedColorType::Rgb8)
                .unwrap();
            std::fs::write(&png, &bytes).unwrap();
            assert_eq!(load_rgb(&png).unwrap().as_slice(), &stored[..]);
            let header = rgb_frame_header(&png).unwrap();
            assert_eq!((header.width, header.height), (w, h));
            // A frame merely of the manifest's sides swapped is told so.
            let e = crate::dataset::expect_manifest_size(&png, (32, 16), (16, 32))
                .unwrap_err()
                .to_string();
            assert!(
                e.ends_with("is 32x16, but manifest.json says the frames are 16x32"),
                "{e}"
            );
        }
    }

    #[test]
    fn sixteen_bit_and_rgba_are_rejected_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let p16 = dir.path().join("deep.png");
        image::ImageBuffer::<image::Luma<u16>, _>::from_raw(4, 4, vec![1000u16; 16])
            .unwrap()
            .save(&p16)
            .unwrap();
        let e = load_grey(&p16).err().unwrap().to_string();
        assert!(e.contains("deep.png") && e.contains("16-bit"), "{e}");
        assert!(e.contains("8 bits per channel"), "{e}");
        let pa = dir.path().join("alpha.png");
        image::RgbaImage::from_raw(4, 4, vec![9u8; 64])
            .unwrap()
            .save(&pa)
            .unwrap();
        let e = load_grey(&pa).err().unwrap().to_string();
        assert!(
            e.contains("alpha.png: 8-bit RGBA image with 16 of its 16 pixels not opaque"),
            "{e}"
        );
        // One see-through pixel is enough to refuse, grey or colour.
        let mut px = [[200u8, 120, 40, 255]; 16].concat();
        px[4 * 5 + 3] = 254;
        image::RgbaImage::from_raw(4, 4, px.clone())
            .unwrap()
            .save(&pa)
            .unwrap();
        let e = load_rgb(&pa).err().unwrap().to_string();
        assert!(e.contains("1 of its 16 pixels not opaque"), "{e}");
        let pla = dir.path().join("grey-alpha.png");
        image::GrayAlphaImage::from_raw(2, 1, vec![10, 255, 20, 0])
            .unwrap()
            .save(&pla)
            .unwrap();
        let e = load_grey(&pla).err().unwrap().to_string();
        assert!(
            e.contains("grey-alpha.png: 8-bit greyscale with alpha image with 1 of its 2"),
            "{e}"
        );
    }

    #[test]
    fn an_opaque_alpha_channel_is_dropped() {
        // Frames saved with an alpha channel every pixel of which is opaque
        // (PIL's convert("RGBA"), screenshots, some camera tools) read as
        // the same frame without it. Before, refused as "8-bit RGBA image".
        let dir = tempfile::tempdir().unwrap();
        let rgb: Vec<u8> = (0..48u8).map(|v| v * 5).collect();
        let rgba: Vec<u8> = rgb
            .chunks(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        // Both readers give the frame with alpha as the frame without.
        let same = |alpha: &Path, plain: &Path| {
            let rgb = |p: &Path| load_rgb(p).unwrap().as_slice().to_vec();
            let grey = |p: &Path| load_grey(p).unwrap().as_slice().to_vec();
            assert_eq!(rgb(alpha), rgb(plain));
            assert_eq!(grey(alpha), grey(plain));
        };
        let (plain, alpha) = (dir.path().join("rgb.png"), dir.path().join("rgba.png"));
        save_rgb_png(&plain, 4, 4, &rgb).unwrap();
        image::RgbaImage::from_raw(4, 4, rgba)
            .unwrap()
            .save(&alpha)
            .unwrap();
        same(&alpha, &plain);
        let grey: Vec<u8> = (0..16u8).map(|v| v * 15).collect();
        let la: Vec<u8> = grey.iter().flat_map(|&v| [v, 255]).collect();
        let (plain, alpha) = (dir.path().join("grey.png"), dir.path().join("la.png"));
        save_grey_png(&plain, 4, 4, &grey).unwrap();
        image::GrayAlphaImage::from_raw(4, 4, la)
            .unwrap()
            .save(&alpha)
            .unwrap();
        same(&alpha, &plain);
    }

    #[test]
    fn a_mask_of_zeros_and_ones_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("mask01.png");
        let mut px = vec![0u8; 64];
        px[10..20].fill(1);
        save_grey_png(&p, 8, 8, &px).unwrap();
        let e = load_mask(&p).err().unwrap().to_string();
        assert!(
            e.contains("mask01.png") && e.contains("largest value is 1"),
            "{e}"
        );
        // Empty masks and 0/255 masks (with soft edges) are read.
        save_grey_png(&p, 8, 8, &[0u8; 64]).unwrap();
        assert!(load_mask(&p).is_ok());
        px[10..20].fill(255);
        px[20] = 40;
        save_grey_png(&p, 8, 8, &px).unwrap();
        assert_eq!(load_mask(&p).unwrap().as_slice(), &px[..]);
    }

    #[test]
    fn rgb_converts_like_opencv() {
        assert_eq!(
            rgb_to_grey(&[255, 255, 255, 0, 0, 0, 255, 0, 0]),
            vec![255, 0, 76]
        );
    }
}
