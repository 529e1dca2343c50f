//! Contact sheets: frames sampled evenly through a dataset, with their
//! labels drawn over them (TacTip: contact position and orientation;
//! visuo-tactile: tendon mask and direction arrow), for a person to look at.
//! Works on any dataset in the `datasets.md` layout, not only synthetic ones.

use std::path::Path;

use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::image_io::{load_grey, load_rgb, save_rgb_png};
use tactile_core::plot::{Mark, draw_marks};
use tactile_core::{Error, Result};

const COLUMNS: usize = 4;
const CAPTION_PX: usize = 22;
const YELLOW: [u8; 3] = [255, 220, 0];
const CYAN: [u8; 3] = [0, 220, 255];
const WHITE: [u8; 3] = [255, 255, 255];

/// Area-average RGB downscale by an integer factor.
fn downscale(rgb: &[u8], w: usize, h: usize, k: usize) -> (Vec<u8>, usize, usize) {
    let (ow, oh) = (w / k, h / k);
    let mut out = vec![0u8; ow * oh * 3];
    for y in 0..oh {
        for x in 0..ow {
            for c in 0..3 {
                let mut s = 0u32;
                for dy in 0..k {
                    for dx in 0..k {
                        s += rgb[((y * k + dy) * w + x * k + dx) * 3 + c] as u32;
                    }
                }
                out[(y * ow + x) * 3 + c] = (s / (k * k) as u32) as u8;
            }
        }
    }
    (out, ow, oh)
}

/// Evenly spaced rows (at most `n`).
fn pick(len: usize, n: usize) -> Vec<usize> {
    let n = n.min(len);
    let run = len / n.max(1);
    // One frame of each of `n` equal runs, at an offset that walks through
    // the run (golden-ratio steps), so videos whose length divides the run
    // do not show the same frame of each.
    (0..n)
        .map(|i| i * run + ((i as f64 * 0.618_034).fract() * run as f64) as usize)
        .collect()
}

fn arrow(centre: (f64, f64), deg: f64, len: f64, colour: [u8; 3]) -> Vec<Mark> {
    let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
    let tip = (centre.0 + c * len, centre.1 + s * len);
    let tail = (centre.0 - c * len, centre.1 - s * len);
    let p = |q: (f64, f64)| (q.0.round() as i32, q.1.round() as i32);
    let head = |a: f64| {
        let (hc, hs) = ((deg + a).to_radians().cos(), (deg + a).to_radians().sin());
        Mark::Line {
            from: p(tip),
            to: p((tip.0 - hc * len * 0.3, tip.1 - hs * len * 0.3)),
            colour,
            width: 2,
        }
    };
    vec![
        Mark::Line {
            from: p(tail),
            to: p(tip),
            colour,
            width: 2,
        },
        head(30.0),
        head(-30.0),
    ]
}

/// Most frames a contact sheet shows: 100 lines of 4 thumbnails (about
/// 75 MB of sheet), more than anyone reads on one picture.
pub const MAX_PREVIEW_FRAMES: usize = 400;

/// Refuse a contact sheet of no frames or of more than
/// [`MAX_PREVIEW_FRAMES`], before a dataset is written for it.
pub fn check_preview_frames(n: usize) -> Result<()> {
    if !(1..=MAX_PREVIEW_FRAMES).contains(&n) {
        return Err(tactile_core::Error::Config(format!(
            "preview_frames: a contact sheet shows 1 to {MAX_PREVIEW_FRAMES} frames, got {n} (leave out --preview for none)"
        )));
    }
    Ok(())
}

/// Frame pixels per thumbnail pixel for frames `w` wide: thumbnails about
/// 240 px wide, and at least 200 where the frame is (a caption such as
/// "s29 f2 press 0.2 straight 125°" takes 200; a 320x240 sensor's frames
/// halved would write it across the next thumbnail).
pub fn shrink_factor(w: usize) -> usize {
    (w / 200).clamp(1, w.div_ceil(240).max(1))
}

/// A contact sheet being drawn: thumbnails of frames of one size, four to
/// a line, each over its caption, with marks drawn over them when saved.
/// Shared by the datasets' previews and a calibration's `circles.png`.
pub struct Sheet {
    /// Frame pixels per thumbnail pixel ([`shrink_factor`]).
    pub shrink: usize,
    /// A thumbnail's size, pixels.
    pub tile: (usize, usize),
    columns: usize,
    width: usize,
    height: usize,
    rgb: Vec<u8>,
    marks: Vec<Mark>,
}

impl Sheet {
    /// A sheet of `count` (at least 1) thumbnails of `w` x `h` frames.
    pub fn new(count: usize, (w, h): (usize, usize)) -> Self {
        let shrink = shrink_factor(w);
        let (tw, th) = (w / shrink, h / shrink);
        let columns = COLUMNS.min(count.max(1));
        let (width, height) = (
            columns * tw,
            count.max(1).div_ceil(columns) * (th + CAPTION_PX),
        );
        Self {
            shrink,
            tile: (tw, th),
            columns,
            width,
            height,
            rgb: vec![0; width * height * 3],
            marks: Vec::new(),
        }
    }

    /// The sheet pixel of thumbnail `slot`'s top-left corner.
    pub fn origin(&self, slot: usize) -> (usize, usize) {
        (
            (slot % self.columns) * self.tile.0,
            (slot / self.columns) * (self.tile.1 + CAPTION_PX),
        )
    }

    /// Put `thumbnail` (interleaved RGB of [`Self::tile`]'s size) at
    /// `slot`, captioned `caption`.
    pub fn place(&mut self, slot: usize, thumbnail: &[u8], caption: String) {
        let (ox, oy) = self.origin(slot);
        let (tw, th) = self.tile;
        for y in 0..th {
            let dst = ((oy + y) * self.width + ox) * 3;
            self.rgb[dst..dst + tw * 3].copy_from_slice(&thumbnail[y * tw * 3..(y + 1) * tw * 3]);
        }
        self.marks.push(Mark::Text {
            at: (ox as i32 + 4, (oy + th + 3) as i32),
            text: caption,
            size: 13,
            colour: WHITE,
        });
    }

    /// Marks to draw over the thumbnails, in sheet pixels.
    pub fn mark(&mut self, marks: impl IntoIterator<Item = Mark>) {
        self.marks.extend(marks);
    }

    /// Draw the marks and write the sheet as a PNG.
    pub fn save(mut self, out: &Path) -> Result<()> {
        draw_marks(&mut self.rgb, self.width, self.height, &self.marks)?;
        save_rgb_png(out, self.width, self.height, &self.rgb)
            .map_err(|e| Error::Invalid(format!("writing {}: {e}", out.display())))
    }
}

/// Write a contact sheet of up to `n` frames (1 to [`MAX_PREVIEW_FRAMES`])
/// of the dataset at `data` to `out`.
pub fn contact_sheet(data: &Path, out: &Path, n: usize) -> Result<()> {
    check_preview_frames(n)?;
    let ds = Dataset::open(data)?;
    if ds.is_empty() {
        return Err(tactile_core::Error::Config(format!(
            "{}: a dataset of no frames has no contact sheet",
            data.display()
        )));
    }
    let rows = pick(ds.len(), n);
    let (w, h) = (ds.manifest.width as usize, ds.manifest.height as usize);
    let mut sheet = Sheet::new(rows.len(), (w, h));
    let (k, (tw, th)) = (sheet.shrink, sheet.tile);
    let mut marks = Vec::new();
    for (slot, &row) in rows.iter().enumerate() {
        let (ox, oy) = sheet.origin(slot);
        let frame_path = ds.path_of(row, "file")?;
        let mut rgb = match ds.manifest.kind {
            DatasetKind::Tactip => {
                let g = load_grey(&frame_path)?;
                tactile_core::image_io::expect_size(&frame_path, g.width(), g.height(), (w, h))?;
                g.as_slice()
                    .iter()
                    .flat_map(|&v| [v, v, v])
                    .collect::<Vec<u8>>()
            }
            DatasetKind::Visuotactile => {
                let c = load_rgb(&frame_path)?;
                tactile_core::image_io::expect_size(&frame_path, c.width(), c.height(), (w, h))?;
                c.as_slice().to_vec()
            }
        };
        let caption;
        let scale = 1.0 / k as f64;
        match ds.manifest.kind {
            DatasetKind::Tactip => {
                let shape = ds.text_opt(row, "shape").unwrap_or("?");
                let depth = ds.number_opt(row, "depth_mm")?;
                let force = ds.number_opt(row, "force_n")?;
                caption = format!(
                    "{shape} d {} F {}",
                    depth.map(|d| format!("{d:.1}")).unwrap_or("-".into()),
                    force.map(|f| format!("{f:.1}")).unwrap_or("-".into())
                );
                let x = ds.number_opt(row, "x_mm")?;
                let y = ds.number_opt(row, "y_mm")?;
                let theta = ds.number_opt(row, "theta_deg")?;
                let to_px = |xm: f64, ym: f64| {
                    let (u, v) = crate::tactip::mm_to_px(xm, ym);
                    (
                        ox as f64 + u * scale * w as f64 / 300.0,
                        oy as f64 + v * scale * h as f64 / 300.0,
                    )
                };
                if let (Some(x), Some(t)) = (x, theta) {
                    // Contact point; for an edge, the point of the edge line nearest the centre.
                    let (cx, cy) = if shape == "edge" {
                        let t = t.to_radians();
                        (-t.sin() * x, t.cos() * x)
                    } else {
                        (x, y.unwrap_or(0.0))
                    };
                    marks.extend(arrow(to_px(cx, cy), t, 18.0, YELLOW));
                } else if let Some(x) = x {
                    let (u, v) = to_px(x, y.unwrap_or(0.0));
                    marks.push(Mark::Dot {
                        at: (u.round() as i32, v.round() as i32),
                        radius: 4,
                        colour: YELLOW,
                    });
                }
            }
            DatasetKind::Visuotactile => {
                let mask_path = ds.path_of(row, "mask")?;
                let m = load_grey(&mask_path)?;
                tactile_core::image_io::expect_size(&mask_path, m.width(), m.height(), (w, h))?;
                for (px, &mv) in rgb.chunks_exact_mut(3).zip(m.as_slice()) {
                    if mv > 127 {
                        px[0] = ((px[0] as u32 + 255) / 2) as u8;
                        px[1] /= 2;
                        px[2] /= 2;
                    }
                }
                let tendon = ds.number_opt(row, "tendon")?.unwrap_or(0.0) > 0.5;
                let dir = ds.number_opt(row, "direction_deg")?;
                let path = ds.text_opt(row, "path").unwrap_or("?");
                let press = ds.number_opt(row, "press_mm")?.unwrap_or(0.0);
                caption = format!(
                    "s{} f{} press {press:.1} {}",
                    ds.text_opt(row, "sequence").unwrap_or("?"),
                    ds.text_opt(row, "frame_index").unwrap_or("?"),
                    if tendon {
                        format!("{path} {:.0}°", dir.unwrap_or(f64::NAN))
                    } else {
                        "no tendon".into()
                    }
                );
                if let (true, Some(d)) = (tendon, dir) {
                    let c = (ox as f64 + tw as f64 / 2.0, oy as f64 + th as f64 / 2.0);
                    marks.extend(arrow(c, d, tw as f64 * 0.18, CYAN));
                }
            }
        }
        let (small, _, _) = downscale(&rgb, w, h, k);
        sheet.place(slot, &small, caption);
    }
    sheet.mark(marks);
    sheet.save(out)
}

#[cfg(test)]
mod tests {
    use super::shrink_factor;

    #[test]
    fn thumbnails_are_wide_enough_for_their_captions() {
        for w in [200, 240, 320, 400, 480, 640, 1280, 1920, 3840] {
            let k = shrink_factor(w);
            assert!((200..=320).contains(&(w / k)), "{w} px wide: shrunk by {k}");
        }
        // Frames narrower than a caption are shown as they are.
        assert_eq!(shrink_factor(120), 1);
        // The sizes of the shipped sheets keep their thumbnails.
        assert_eq!((shrink_factor(640), shrink_factor(1920)), (3, 8));
    }
}
