//! Finding a ball's contact circle in a press: the colour change from the
//! background (exposure matched, at the working resolution), an Otsu
//! threshold, the largest connected region (kornia), and the circle of
//! the region's centroid and area, refined on the change's edge: where
//! the change peaks along rays from the centre, rays the frame's edge cuts
//! first left out, a circle fitted to the rest and refitted without those
//! far from it. Every distance is taken relative to the contact's own
//! size, so a 240x180 sensor's presses are found as a 1280x960 one's are.

use kornia_image::{Image, ImageSize};
use kornia_imgproc::connected_components::{Connectivity, connected_components};
use kornia_imgproc::filter::median_blur;

use crate::layout::Circle;
use crate::prepare::{PreparedBackground, WorkingImage};
use crate::{Error, Result};

/// Fewest working pixels a contact covers.
pub const MIN_CONTACT_PIXELS: usize = 12;

/// Otsu's threshold of `values` (256 bins over their range).
fn otsu(values: &[f32]) -> f32 {
    let (lo, hi) = values
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return hi;
    }
    let bins = 256;
    let mut hist = vec![0f64; bins];
    for &v in values {
        let b = (((v - lo) / (hi - lo)) * (bins - 1) as f32) as usize;
        hist[b.min(bins - 1)] += 1.0;
    }
    let total: f64 = hist.iter().sum();
    let sum_all: f64 = hist.iter().enumerate().map(|(i, c)| i as f64 * c).sum();
    let (mut w0, mut sum0, mut best, mut best_t) = (0.0, 0.0, -1.0, 0);
    for (t, &c) in hist.iter().enumerate() {
        w0 += c;
        sum0 += t as f64 * c;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0, (sum_all - sum0) / w1);
        let between = w0 * w1 * (m0 - m1).powi(2);
        if between > best {
            best = between;
            best_t = t;
        }
    }
    lo + (best_t as f32 + 0.5) / (bins - 1) as f32 * (hi - lo)
}

/// The contact circle of `frame` (exposure matched) in frame pixels.
/// `path` names the frame in errors (no contact found).
pub fn find_contact(
    background: &PreparedBackground,
    frame: &WorkingImage,
    path: &std::path::Path,
) -> Result<Circle> {
    let g = frame.grid;
    let (w, h) = (g.width(), g.height());
    let raw = background.change(frame);
    let change = despeckled(&raw, w, h)?;
    let t = otsu(&change);
    let mask: Vec<u8> = change.iter().map(|&v| u8::from(v > t)).collect();
    let src = Image::<u8, 1>::new(
        ImageSize {
            width: w,
            height: h,
        },
        mask,
    )?;
    let mut labels = Image::<i32, 1>::from_size_val(
        ImageSize {
            width: w,
            height: h,
        },
        0,
    )?;
    let n = connected_components(&src, &mut labels, Connectivity::Eight)?;
    let mut count = vec![0usize; n.max(1) as usize];
    for &l in labels.as_slice() {
        if l > 0 {
            count[l as usize] += 1;
        }
    }
    let (best, &size) = count
        .iter()
        .enumerate()
        .skip(1)
        .max_by_key(|(_, c)| **c)
        .unwrap_or((0, &0));
    if size < MIN_CONTACT_PIXELS {
        return Err(Error::Press {
            path: path.to_path_buf(),
            why: "no contact found (the frame hardly differs from the background)".into(),
        });
    }
    // The region's centroid starts the search; the contact's edge is
    // where the change peaks along each ray (the skin's slope, and with it
    // the colour change, is steepest at the edge and reverses beyond it);
    // a circle is fitted to those points.
    let (mut sx, mut sy) = (0.0, 0.0);
    for (i, &l) in labels.as_slice().iter().enumerate() {
        if l as usize == best {
            sx += (i % w) as f64;
            sy += (i / w) as f64;
        }
    }
    let mut c = (sx / size as f64, sy / size as f64);
    let mut r = (size as f64 / std::f64::consts::PI).sqrt();
    let inside =
        |x: f64, y: f64| (0.0..=(w - 1) as f64).contains(&x) && (0.0..=(h - 1) as f64).contains(&y);
    // Bilinear, at a point `inside` the grid.
    let sample = |map: &[f32], x: f64, y: f64| -> f64 {
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let v = |xx: usize, yy: usize| map[yy * w + xx] as f64;
        (v(x0, y0) * (1.0 - fx) + v(x1, y0) * fx) * (1.0 - fy)
            + (v(x0, y1) * (1.0 - fx) + v(x1, y1) * fx) * fy
    };
    // Three passes on the median's change find the contact wherever the
    // start was. A last one on the change itself, within 15 % of that
    // radius, sets the radius alone: the median rounds the change's narrow
    // peak off inwards (at 240x180, 1.5 px of the 640x480 frame's), and a
    // marker there is one ray the fit leaves out.
    for pass in 0..4 {
        let (map, (from, to)) = match pass {
            3 => (&raw[..], (0.85, 1.15)),
            _ => (&change[..], (0.5, 2.0)),
        };
        let mut points = Vec::with_capacity(RAYS);
        for k in 0..RAYS {
            let t = k as f64 * std::f64::consts::TAU / RAYS as f64;
            let (dx, dy) = (t.cos(), t.sin());
            let (mut best_d, mut best_drop, mut last_d) = (r, f64::MIN, None);
            let steps = 60;
            for s in 0..=steps {
                let d = r * (from + (to - from) * s as f64 / steps as f64);
                let (x, y) = (c.0 + dx * d, c.1 + dy * d);
                if !inside(x, y) {
                    break;
                }
                last_d = Some(d);
                let drop = sample(map, x, y);
                if drop > best_drop {
                    best_drop = drop;
                    best_d = d;
                }
            }
            // A ray the frame's edge cuts before the change peaks (a press
            // near the edge) holds no edge of the contact.
            let cut = last_d.is_some_and(|l| l < to * r && best_d == l);
            if last_d.is_some() && !cut {
                points.push((c.0 + dx * best_d, c.1 + dy * best_d));
            }
        }
        // Rays that caught something else (a scratch, the housing's glare)
        // are left out: those far from a circle fitted to them all. Their
        // distance from the start is no test, as the start may be off the
        // contact's centre (the region's centroid, pulled by the change
        // around the contact): there the edge's distance varies around
        // the rays by twice the offset.
        match robust_circle(&points) {
            Some((cx, cy, rr)) if rr > 1.0 => {
                if pass < 3 {
                    c = (cx, cy);
                }
                r = rr;
            }
            _ => break,
        }
    }
    let f = g.factor as f64;
    Ok(Circle {
        centre_x_px: g.frame_coord(c.0),
        centre_y_px: g.frame_coord(c.1),
        radius_px: r * f,
    })
}

/// `change` (`w` x `h`) through a 5x5 median: printed markers (a grid of
/// dark dots on many gels) move with the skin, and each moved dot changes
/// the colour strongly over a few pixels, which the threshold's region
/// and the rays would take for the contact; the median keeps the
/// contact's broad change and drops such specks. Quantised to 256 levels
/// of the largest change, as the threshold's histogram is.
fn despeckled(change: &[f32], w: usize, h: usize) -> Result<Vec<f32>> {
    let top = change.iter().copied().fold(0f32, f32::max);
    if !(top > 0.0 && top.is_finite()) {
        return Ok(change.to_vec());
    }
    let size = ImageSize {
        width: w,
        height: h,
    };
    let levels: Vec<u8> = change
        .iter()
        .map(|&v| (v / top * 255.0).round().clamp(0.0, 255.0) as u8)
        .collect();
    let src = Image::<u8, 1>::new(size, levels)?;
    let mut dst = Image::<u8, 1>::from_size_val(size, 0)?;
    median_blur(&src, &mut dst, if w >= 240 { 5 } else { 3 })?;
    Ok(dst
        .as_slice()
        .iter()
        .map(|&v| f32::from(v) / 255.0 * top)
        .collect())
}

/// Rays along which the contact's edge is sought.
const RAYS: usize = 48;

/// The circle (centre and radius) of `points` (the edge along each ray)
/// once those far from it are left out: the circle is fitted to them all,
/// the farthest point left out and the circle refitted, until every point
/// left lies within 15 % of its radius; `None` when fewer than a third of
/// the rays are left, or the fit is degenerate.
fn robust_circle(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let mut kept = points.to_vec();
    // Each round leaves out one point, or ends.
    while kept.len() >= RAYS / 3 {
        let (cx, cy, r) = fit_circle(&kept).filter(|f| f.2.is_finite())?;
        let off = |p: &(f64, f64)| ((p.0 - cx).hypot(p.1 - cy) - r).abs();
        // The worst point goes first, so one far outlier does not drag
        // the circle off the rest.
        let (worst, far) = kept
            .iter()
            .enumerate()
            .map(|(i, p)| (i, off(p)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        if far < 0.15 * r {
            return Some((cx, cy, r));
        }
        kept.swap_remove(worst);
    }
    None
}

/// The least-squares circle through `points` (Kasa's algebraic fit):
/// centre and radius, or `None` when they are degenerate.
fn fit_circle(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let (mut suu, mut svv, mut suv, mut suuu, mut svvv, mut suvv, mut svuu) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y) in points {
        let (u, v) = (x - mx, y - my);
        suu += u * u;
        svv += v * v;
        suv += u * v;
        suuu += u * u * u;
        svvv += v * v * v;
        suvv += u * v * v;
        svuu += v * u * u;
    }
    let det = suu * svv - suv * suv;
    if det.abs() < 1e-9 {
        return None;
    }
    let (b1, b2) = (0.5 * (suuu + suvv), 0.5 * (svvv + svuu));
    let uc = (b1 * svv - b2 * suv) / det;
    let vc = (suu * b2 - suv * b1) / det;
    let r = (uc * uc + vc * vc + (suu + svv) / n).sqrt();
    Some((uc + mx, vc + my, r))
}
