//! Scoring a reconstruction against what the ball's geometry says: the
//! cap's shape inside the contact (mean absolute error once the unknown
//! sink is removed: the median difference), the far field (beyond three
//! contact radii the skin is at rest), the rim sink and the peak; the
//! circle finder against annotations; and leave-presses-out
//! cross-validation of a calibration recipe.

use serde::Serialize;

use crate::geometry::{Cap, FAR_FIELD_RADII};
use crate::inference::IndentationMap;
use crate::layout::{BallPresses, Circle};
use crate::training::PreparedPress;

/// One press's reconstruction scored.
#[derive(Debug, Clone, Serialize)]
pub struct PressScore {
    /// The press's frame.
    pub file: String,
    /// Inside the contact: mean |error| after removing the median offset, mm.
    pub shape_mae_mm: f64,
    /// Beyond three contact radii: mean |indentation|, mm (truth 0).
    pub far_field_mm: f64,
    /// The reconstructed sink of the contact's rim (the median offset), mm.
    pub rim_sink_mm: f64,
    /// The deepest indentation, mm.
    pub peak_mm: f64,
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Score a height map `map_mm` (`w x h`, row-major) whose pixel `i` along
/// each axis sits at frame coordinate `coord(i)`, against `cap`.
pub fn score_map(
    map_mm: &[f32],
    (w, h): (usize, usize),
    coord: impl Fn(usize) -> f64,
    cap: &Cap,
    file: &str,
) -> PressScore {
    let xs: Vec<f64> = (0..w).map(&coord).collect();
    let ys: Vec<f64> = (0..h).map(&coord).collect();
    let a = cap.circle.radius_px;
    let mut diffs = Vec::new();
    let (mut far, mut far_n) = (0.0, 0usize);
    let mut peak = f64::MIN;
    for (j, &y) in ys.iter().enumerate() {
        for (i, &x) in xs.iter().enumerate() {
            let v = map_mm[j * w + i] as f64;
            peak = peak.max(v);
            if let Some(t) = cap.height_mm(x, y) {
                diffs.push(v - t);
            } else if cap.r_px(x, y) >= FAR_FIELD_RADII * a {
                far += v.abs();
                far_n += 1;
            }
        }
    }
    // The median reorders the differences; the mean below does not care.
    let offset = median(&mut diffs);
    let shape = diffs.iter().map(|d| (d - offset).abs()).sum::<f64>() / diffs.len().max(1) as f64;
    PressScore {
        file: file.to_string(),
        shape_mae_mm: shape,
        far_field_mm: far / far_n.max(1) as f64,
        rim_sink_mm: offset,
        peak_mm: peak,
    }
}

/// Score a full-resolution reconstruction.
pub fn score_full(map: &IndentationMap, cap: &Cap, file: &str) -> PressScore {
    let mm: Vec<f32> = map.indentation_m.iter().map(|v| v * 1e3).collect();
    score_map(&mm, (map.width, map.height), |i| i as f64, cap, file)
}

/// Most presses one picture of [`circles_pictures`] shows.
pub const MAX_PICTURED_PRESSES: usize = 48;

/// The first picture's name in a calibrated sensor's folder; the next are
/// `circles-2.png`, `circles-3.png`, ...
pub const CIRCLES_PICTURE: &str = "circles.png";

/// The name of picture `page` (0 the first) of [`circles_pictures`].
pub fn circles_picture_name(page: usize) -> String {
    match page {
        0 => CIRCLES_PICTURE.to_string(),
        _ => format!("circles-{}.png", page + 1),
    }
}

/// Contact sheets of every press of `ds`, [`MAX_PICTURED_PRESSES`] to a
/// picture, in the folder's order, written into `dir`: each press with
/// the contact circle its targets use (green) and, where that is an
/// annotation, the circle the toolkit finds (yellow), captioned with how
/// far apart their centres are and the two radii (found/annotated). What a
/// calibration fitted, to look at: a mistyped line or a press the finder
/// mistook shows at a glance. Returns the pictures' names.
pub fn circles_pictures(
    ds: &BallPresses,
    presses: &[PreparedPress],
    dir: &std::path::Path,
) -> crate::Result<Vec<String>> {
    let mut names = Vec::new();
    for (page, first) in (0..presses.len()).step_by(MAX_PICTURED_PRESSES).enumerate() {
        let name = circles_picture_name(page);
        let last = (first + MAX_PICTURED_PRESSES).min(presses.len());
        circles_picture(ds, presses, first..last, &dir.join(&name))?;
        names.push(name);
    }
    Ok(names)
}

/// One picture of [`circles_pictures`]: the presses `range` (not empty).
fn circles_picture(
    ds: &BallPresses,
    presses: &[PreparedPress],
    range: std::ops::Range<usize>,
    path: &std::path::Path,
) -> crate::Result<()> {
    use tactile_core::plot::Mark;
    const GREEN: [u8; 3] = [40, 230, 60];
    const YELLOW: [u8; 3] = [255, 220, 0];
    let (w, h) = ds.size();
    let mut sheet = datasets_synth::preview::Sheet::new(range.len(), (w, h));
    let k = sheet.shrink as f64;
    for (slot, press) in range.enumerate() {
        let p = &presses[press];
        let (ox, oy) = sheet.origin(slot);
        // Read as it was when prepared (checked there: its size, colour
        // and channel order).
        let frame = ds.frame_as_saved(press)?;
        let small: Vec<u8> =
            tactile_preprocess::shrink_rgb_by(frame.as_slice(), (w, h), sheet.shrink)?
                .iter()
                .map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
                .collect();
        // A circle as 48 chords, in the thumbnail's pixels.
        let ring = |c: Circle, colour: [u8; 3], width: u32| {
            let at = move |s: usize| {
                let t = s as f64 * std::f64::consts::TAU / 48.0;
                let (x, y) = (
                    c.centre_x_px + c.radius_px * t.cos(),
                    c.centre_y_px + c.radius_px * t.sin(),
                );
                (
                    (ox as f64 + (x + 0.5) / k - 0.5).round() as i32,
                    (oy as f64 + (y + 0.5) / k - 0.5).round() as i32,
                )
            };
            (0..48).map(move |s| Mark::Line {
                from: at(s),
                to: at(s + 1),
                colour,
                width,
            })
        };
        let name = ds.press_name(press);
        let caption = match p.annotated.filter(|a| *a == p.circle) {
            Some(a) => {
                sheet.mark(ring(p.found, YELLOW, 1));
                let apart = (p.found.centre_x_px - a.centre_x_px)
                    .hypot(p.found.centre_y_px - a.centre_y_px);
                format!(
                    "{name}: off {apart:.1} px, r {:.0}/{:.0}",
                    p.found.radius_px, a.radius_px
                )
            }
            None => format!("{name}: found"),
        };
        sheet.mark(ring(p.circle, GREEN, 2));
        sheet.place(slot, &small, caption);
    }
    Ok(sheet.save(path)?)
}

/// The circle finder against annotated circles.
#[derive(Debug, Clone, Serialize)]
pub struct CircleAgreement {
    /// Presses with an annotation.
    pub presses: usize,
    /// Mean distance between found and annotated centres, px.
    pub centre_error_px: f64,
    /// Largest such distance, px.
    pub max_centre_error_px: f64,
    /// Mean |found - annotated| radius, px.
    pub radius_error_px: f64,
    /// Mean found - annotated radius (its bias), px.
    pub radius_bias_px: f64,
}

impl CircleAgreement {
    /// Over the presses that have an annotation; `None` without any.
    pub fn of(presses: &[PreparedPress]) -> Option<Self> {
        let pairs: Vec<_> = presses
            .iter()
            .filter_map(|p| p.annotated.map(|a| (p.found, a)))
            .collect();
        if pairs.is_empty() {
            return None;
        }
        let n = pairs.len() as f64;
        let centre: Vec<f64> = pairs
            .iter()
            .map(|(f, a)| (f.centre_x_px - a.centre_x_px).hypot(f.centre_y_px - a.centre_y_px))
            .collect();
        Some(Self {
            presses: pairs.len(),
            centre_error_px: centre.iter().sum::<f64>() / n,
            max_centre_error_px: centre.iter().copied().fold(0.0, f64::max),
            radius_error_px: pairs
                .iter()
                .map(|(f, a)| (f.radius_px - a.radius_px).abs())
                .sum::<f64>()
                / n,
            radius_bias_px: pairs
                .iter()
                .map(|(f, a)| f.radius_px - a.radius_px)
                .sum::<f64>()
                / n,
        })
    }

    /// One line for a person.
    pub fn describe(&self) -> String {
        format!(
            "circles found on {} annotated presses: centre error {:.2} px (largest {:.2}), radius error {:.2} px (bias {:+.2})",
            self.presses,
            self.centre_error_px,
            self.max_centre_error_px,
            self.radius_error_px,
            self.radius_bias_px
        )
    }
}
