//! What a frame looked like to the pipeline, as pictures: paper B's
//! figure 3 for a tendon frame (the segmenter's window with the kept
//! region and its direction, beside the depth heat map) and, for a
//! calibrated sensor, the frame beside its skin's indentation.

use std::path::Path;

use tactile_core::Result;
use tactile_core::image_io::RgbImage;
use tactile_gelsight::IndentationMap;
use tactile_preprocess::visuo::SquareWindow;

/// What the pipeline saw in one frame, for overlays and for the arrays a
/// caller asks for. Serde, so a frame's result can be sent to another
/// process whole (Python's pickle); [`FrameViews::check`] says whether
/// views read back fit together.
#[derive(Default, serde::Serialize, serde::Deserialize)]
pub struct FrameViews {
    /// A tendon frame's window, region, direction and depth.
    pub tendon: Option<TendonView>,
    /// A calibrated sensor's indentation.
    pub indentation: Option<SensorView>,
}

impl FrameViews {
    /// Whether there is anything to show.
    pub fn any(&self) -> bool {
        self.tendon.is_some() || self.indentation.is_some()
    }

    /// Whether views read back from elsewhere (a pickle) fit together and
    /// a `width x height` frame: every buffer as long as its sizes say,
    /// each side at most [`tactile_core::dataset::MAX_SIDE`], finite
    /// scales. Views the pipeline made always do.
    pub fn check(&self, width: usize, height: usize) -> crate::Result<()> {
        use tactile_core::dataset::MAX_SIDE;
        let bad = |what: String| crate::Error::from(tactile_core::Error::Invalid(what));
        let side_ok = |n: usize| (1..=MAX_SIDE as usize).contains(&n);
        if !side_ok(width) || !side_ok(height) {
            return Err(bad(format!(
                "frame views for a {width}x{height} frame: each side must be 1 to {MAX_SIDE}"
            )));
        }
        if let Some(t) = &self.tendon {
            let [dw, dh] = t.depth_size;
            let fits = side_ok(t.side)
                && t.window.len() == t.side * t.side * 3
                && t.region.len() == t.side * t.side
                && side_ok(dw)
                && side_ok(dh)
                && t.depth_mm.len() == dw * dh
                && t.frame_aspect.is_finite()
                && t.frame_aspect > 0.0;
            if !fits {
                return Err(bad(format!(
                    "tendon view: a {0}x{0} window with {1} values and {2} region pixels, \
                     a {dw}x{dh} depth map with {3} values, aspect {4}: they do not fit together",
                    t.side,
                    t.window.len(),
                    t.region.len(),
                    t.depth_mm.len(),
                    t.frame_aspect
                )));
            }
        }
        if let Some(s) = &self.indentation {
            let m = &s.map;
            if m.width != width
                || m.height != height
                || m.indentation_m.len() != width * height
                || !(s.mm_per_px.is_finite() && s.mm_per_px > 0.0)
            {
                return Err(bad(format!(
                    "indentation view: a {}x{} map with {} values at {} mm per pixel \
                     for a {width}x{height} frame: they do not fit together",
                    m.width,
                    m.height,
                    m.indentation_m.len(),
                    s.mm_per_px
                )));
            }
        }
        Ok(())
    }

    /// Write this frame's pictures into `dir`: `STEM-overlay.png` for a
    /// tendon frame, `STEM-indentation.png` for a calibrated sensor's
    /// frame (`frame` as it came).
    pub fn save_pngs(&self, dir: &Path, stem: &str, frame: &RgbImage) -> crate::Result<()> {
        if let Some(t) = &self.tendon {
            t.save_png(&dir.join(format!("{stem}-overlay.png")), 4)?;
        }
        if let Some(s) = &self.indentation {
            tactile_gelsight::reconstruct::render_picture(
                &dir.join(format!("{stem}-indentation.png")),
                frame,
                &s.map,
                s.mm_per_px,
            )
            .map_err(crate::Error::from)?;
        }
        Ok(())
    }
}

/// The names a run's pictures take: each frame's stem, and `STEM-2`,
/// `STEM-3`, ... for a later frame whose stem is taken (`a.png` and
/// `a.jpg`, or one file name in two folders of a dataset), so no frame's
/// pictures overwrite another's.
#[derive(Default)]
pub struct PictureStems {
    used: std::collections::HashSet<String>,
}

impl PictureStems {
    /// The name for the pictures of the frame named `frame_name`.
    pub fn next(&mut self, frame_name: &str) -> String {
        let stem = Path::new(frame_name)
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let mut name = stem.clone();
        let mut k = 2;
        while !self.used.insert(name.clone()) {
            name = format!("{stem}-{k}");
            k += 1;
        }
        name
    }
}

/// A calibrated sensor's skin under one frame.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct SensorView {
    /// The indentation at the frame's size, metres.
    pub map: IndentationMap,
    /// The sensor's scale, mm per pixel.
    pub mm_per_px: f64,
}

/// What a tendon frame looked like to the pipeline, for overlays.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct TendonView {
    /// The segmenter's window, `side x side x 3` in [0, 1].
    pub window: Vec<f32>,
    /// Its side, pixels.
    pub side: usize,
    /// The kept region.
    pub region: Vec<bool>,
    /// Direction (degrees) and centroid in window pixels.
    pub direction: Option<(f64, (f64, f64))>,
    /// Depth in mm at the depth network's input size.
    pub depth_mm: Vec<f32>,
    /// The depth network's input width and height.
    pub depth_size: [usize; 2],
    /// What the depth map holds.
    pub depth_maps: tactile_core::spec::DepthMaps,
    /// The frame's width / height (the depth map may be stretched).
    pub frame_aspect: f64,
}

impl TendonView {
    /// The kept region at the frame's resolution (`width x height`,
    /// row-major): each frame pixel takes the window pixel it was cut into
    /// (nearest); pixels the window does not see are not tendon. The cut is
    /// an unrotated scale and crop, so one lookup per column and per row
    /// does it.
    pub fn mask_at(&self, width: usize, height: usize) -> Vec<bool> {
        let win = SquareWindow { side: self.side };
        let s = self.side as isize;
        let inside = |p: f64| {
            let i = p.round() as isize;
            (0..s).contains(&i).then_some(i as usize)
        };
        let cols: Vec<Option<usize>> = (0..width)
            .map(|u| inside(win.frame_to_window((u as f64, 0.0), (width, height)).0))
            .collect();
        let rows: Vec<Option<usize>> = (0..height)
            .map(|v| inside(win.frame_to_window((0.0, v as f64), (width, height)).1))
            .collect();
        let mut out = vec![false; width * height];
        for (row, y) in out.chunks_mut(width.max(1)).zip(&rows) {
            let Some(y) = y else { continue };
            let region = &self.region[y * self.side..(y + 1) * self.side];
            for (px, x) in row.iter_mut().zip(&cols) {
                *px = x.is_some_and(|x| region[x]);
            }
        }
        out
    }

    /// The depth at the frame's resolution in metres: the network's output
    /// resized bilinearly (OpenCV's half-pixel centres, through kornia: its
    /// scalar OpenCV path measured faster here than its general resize).
    pub fn depth_m_at(&self, width: usize, height: usize) -> Result<Vec<f32>> {
        use kornia_image::{Image, ImageSize};
        let [dw, dh] = self.depth_size;
        let fail = |e: kornia_image::ImageError| {
            tactile_core::Error::Invalid(format!("depth map to {width}x{height}: {e}"))
        };
        let metres: Vec<f32> = self.depth_mm.iter().map(|mm| mm / 1000.0).collect();
        let src = Image::<f32, 1>::new(
            ImageSize {
                width: dw,
                height: dh,
            },
            metres,
        )
        .map_err(fail)?;
        let mut dst =
            Image::<f32, 1>::from_size_val(ImageSize { width, height }, 0.0).map_err(fail)?;
        kornia_imgproc::resize::resize_opencv_f32(
            &src,
            &mut dst,
            kornia_imgproc::interpolation::InterpolationMode::Bilinear,
        )
        .map_err(fail)?;
        Ok(dst.as_slice().to_vec())
    }

    /// Paper B's figure 3 style: the window enlarged `zoom` times with the
    /// kept region in green and the direction as a red line, and beside it
    /// the skin's displacement from its rest dome (mm, so the tendon ridge
    /// shows) at the same height, with a labelled colour bar. Written
    /// atomically as PNG.
    pub fn save_png(&self, path: &Path, zoom: usize) -> Result<()> {
        let s = self.side * zoom;
        let [dw, dh] = self.depth_size;
        let dscale = s as f64 / dh as f64;
        let dwz = (dw as f64 * dscale).round() as usize;
        let gap = 6;
        let width = s + gap + dwz + gap + tactile_core::plot::COLOUR_BAR_WIDTH;
        let mut rgb = vec![255u8; width * s * 3];
        for y in 0..s {
            for x in 0..s {
                let i = (y / zoom) * self.side + x / zoom;
                let o = (y * width + x) * 3;
                for c in 0..3 {
                    let mut v = self.window[i * 3 + c];
                    if self.region[i] {
                        // Blend 45 % green over the tendon.
                        let g = if c == 1 { 1.0 } else { 0.0 };
                        v = 0.55 * v + 0.45 * g;
                    }
                    rgb[o + c] = (v * 255.0).round().clamp(0.0, 255.0) as u8;
                }
            }
        }
        let disp = tactile_depth::data::push_mm(
            &self.depth_mm,
            self.depth_maps,
            (dw, dh),
            self.frame_aspect,
        );
        let (lo, hi) = tactile_core::plot::colour_range(disp.iter().copied());
        let t = |v: f64| (v - lo) / (hi - lo);
        for y in 0..s {
            for x in 0..dwz {
                let (sx, sy) = (
                    ((x as f64) / dscale) as usize,
                    ((y as f64) / dscale) as usize,
                );
                let v = disp[sy.min(dh - 1) * dw + sx.min(dw - 1)];
                let c = tactile_core::plot::colour(t(v as f64));
                let o = (y * width + s + gap + x) * 3;
                rgb[o..o + 3].copy_from_slice(&c);
            }
        }
        tactile_core::plot::draw_colour_bar(
            &mut rgb,
            width,
            s,
            s + gap + dwz + gap,
            (lo, hi),
            "push from rest, mm",
        )?;
        if let Some((deg, (cx, cy))) = self.direction {
            let (sn, cs) = deg.to_radians().sin_cos();
            let half = s as f64 * 0.45;
            let (px, py) = ((cx + 0.5) * zoom as f64, (cy + 0.5) * zoom as f64);
            let marks = [tactile_core::plot::Mark::Line {
                from: ((px - cs * half) as i32, (py - sn * half) as i32),
                to: ((px + cs * half) as i32, (py + sn * half) as i32),
                colour: [230, 30, 30],
                width: 3,
            }];
            tactile_core::plot::draw_marks(&mut rgb, width, s, &marks)?;
        }
        tactile_core::image_io::save_rgb_png(path, width, s, &rgb)
    }
}

#[cfg(test)]
mod tests {
    use super::{FrameViews, PictureStems, SensorView, TendonView};
    use tactile_gelsight::IndentationMap;

    fn tendon(side: usize, depth: [usize; 2]) -> TendonView {
        TendonView {
            window: vec![0.5; side * side * 3],
            side,
            region: vec![false; side * side],
            direction: None,
            depth_mm: vec![15.0; depth[0] * depth[1]],
            depth_size: depth,
            depth_maps: Default::default(),
            frame_aspect: 16.0 / 9.0,
        }
    }

    #[test]
    fn views_read_back_must_fit_together_and_their_frame() {
        let good = FrameViews {
            tendon: Some(tendon(8, [6, 4])),
            indentation: Some(SensorView {
                map: IndentationMap {
                    width: 16,
                    height: 9,
                    indentation_m: vec![0.0; 144],
                },
                mm_per_px: 0.03,
            }),
        };
        good.check(16, 9).unwrap();
        assert_eq!(good.tendon.as_ref().unwrap().mask_at(16, 9).len(), 144);
        // A frame too large for any source, even without views.
        let e = FrameViews::default()
            .check(100_000, 9)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("100000x9 frame: each side must be 1 to 7680"),
            "{e}"
        );
        assert!(FrameViews::default().check(0, 9).is_err());
        // The indentation of another frame size.
        let e = good.check(17, 9).unwrap_err().to_string();
        assert!(e.contains("a 16x9 map with 144 values"), "{e}");
        // A window whose region is short (a later mask would index past it).
        let mut short = tendon(8, [6, 4]);
        short.region.pop();
        let bad = FrameViews {
            tendon: Some(short),
            indentation: None,
        };
        let e = bad.check(16, 9).unwrap_err().to_string();
        assert!(e.contains("63 region pixels"), "{e}");
        // A depth map bigger than its values, or an aspect that is no number.
        let mut big = tendon(8, [6, 4]);
        big.depth_size = [6000, 4000];
        assert!(
            FrameViews {
                tendon: Some(big),
                indentation: None
            }
            .check(16, 9)
            .is_err()
        );
        let mut nan = tendon(8, [6, 4]);
        nan.frame_aspect = f64::NAN;
        assert!(
            FrameViews {
                tendon: Some(nan),
                indentation: None
            }
            .check(16, 9)
            .is_err()
        );
    }

    #[test]
    fn frames_that_share_a_stem_get_pictures_of_their_own() {
        let mut stems = PictureStems::default();
        let names: Vec<String> = ["a.png", "a.jpg", "b.png", "a-2.png", "a.jpeg"]
            .iter()
            .map(|n| stems.next(n))
            .collect();
        assert_eq!(names, ["a", "a-2", "b", "a-2-2", "a-3"]);
    }
}
