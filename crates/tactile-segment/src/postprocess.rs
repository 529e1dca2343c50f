//! From a predicted mask to a tendon region and its direction (paper B):
//! keep the largest 8-connected region, discard a region lying on the outer
//! edge of the window (the LED glare), and measure its direction: by
//! default the tangent of the centre line at its point nearest the window
//! centre (the label's own definition), with paper B's first principal axis
//! of the region's pixels kept as the baseline. A pure function of the mask
//! and, when given, the per-pixel probabilities.

use crate::{Error, Result};
use kornia_image::{Image, ImageSize};
use kornia_imgproc::connected_components::{Connectivity, connected_components};
use kornia_imgproc::filter::{gaussian_blur, spatial_gradient_float};
use kornia_imgproc::morphology::{box_kernel, dilate};
use kornia_imgproc::padding::PaddingMode;
use serde::{Deserialize, Serialize};
use tactile_core::spec::visuotactile::Window;
use tactile_preprocess::visuo::FloatImage;

/// A binary mask, row-major, `true` = tendon.
#[derive(Debug, Clone, PartialEq)]
pub struct TendonMask {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// `width * height` flags, row-major.
    pub pixels: Vec<bool>,
}

impl TendonMask {
    /// A mask from probabilities thresholded at `t`.
    pub fn from_probabilities(width: usize, height: usize, p: &[f32], t: f64) -> Result<Self> {
        if p.len() != width * height {
            return Err(tactile_core::Error::shape(
                "probabilities",
                format!("{width}x{height}"),
                p.len(),
            )
            .into());
        }
        Ok(Self {
            width,
            height,
            pixels: p.iter().map(|&v| v as f64 >= t).collect(),
        })
    }

    /// A mask with no tendon pixel.
    pub fn empty(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: vec![false; width * height],
        }
    }

    /// Tendon pixels.
    pub fn area(&self) -> usize {
        self.pixels.iter().filter(|&&p| p).count()
    }
}

/// Settings of [`postprocess`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PostprocessConfig {
    /// Width of the window's edge band, as a fraction of the radius of the
    /// ellipse inscribed in the mask.
    pub edge_band: f64,
    /// A region with at least this fraction of its pixels in the edge band
    /// lies on the edge (glare) and is discarded.
    pub edge_fraction: f64,
    /// Eigenvalue ratio (major / minor) below which the region is too round
    /// to have a direction.
    pub min_anisotropy: f64,
    /// Regions smaller than this many pixels have no direction.
    pub min_area: usize,
    /// Take the axis from the region's pixels inside the ellipse inscribed
    /// in the mask only. A band cut by a square window is skewed toward the
    /// square's diagonals; cut by a disc it is mirror-symmetric about its
    /// own axis, so the principal axis is the band's direction exactly.
    #[serde(default = "yes")]
    pub axis_within_window: bool,
    /// How the direction is measured.
    #[serde(default)]
    pub direction: DirectionMethod,
}

/// How the direction of the kept region is measured.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DirectionMethod {
    /// The tangent of the centre line at its point nearest the window
    /// centre, from the orientation of the region's edges around that
    /// point. Holds for wide, short and curved regions, where the
    /// principal axis is round or leans toward the curve's chord.
    #[default]
    CentreLine,
    /// The first principal axis of the region's pixels (paper B; the
    /// baseline). No direction for regions rounder than `min_anisotropy`.
    PrincipalAxis,
}

fn yes() -> bool {
    true
}

impl Default for PostprocessConfig {
    fn default() -> Self {
        Self {
            edge_band: 0.12,
            edge_fraction: 0.8,
            min_anisotropy: 1.5,
            min_area: 3,
            axis_within_window: true,
            direction: DirectionMethod::CentreLine,
        }
    }
}

/// Why there is no direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoDirection {
    /// Nothing left after discarding edge regions.
    EmptyMask,
    /// Fewer pixels than `min_area` (one pixel has no axis).
    TooSmall,
    /// The region is nearly round: any angle would be noise.
    Isotropic,
}

/// The direction of the kept region.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Direction {
    /// Image direction, folded into [0, 180): 0 = pointing right, 90 =
    /// pointing down (sensors.md).
    pub angle_deg: f64,
    /// Major / minor eigenvalue of the pixel covariance (principal axis) or
    /// of the edge structure tensor (centre line); inf for a perfect line.
    pub anisotropy: f64,
    /// Where the direction was measured, `(u, v)` in pixels: the region's
    /// centroid (principal axis) or the centre-line point nearest the
    /// window centre.
    pub point: (f64, f64),
}

/// What post-processing made of a mask.
#[derive(Debug, Clone, PartialEq)]
pub struct Tendon {
    /// The kept region (empty when none).
    pub region: TendonMask,
    /// Regions found.
    pub regions: usize,
    /// Regions that lay on the edge and were dropped.
    pub dropped_on_edge: usize,
    /// The region's direction, or why there is none.
    pub direction: std::result::Result<Direction, NoDirection>,
}

/// What a mask was made from, used to measure its direction.
#[derive(Debug, Clone, Copy, Default)]
pub struct Evidence<'a> {
    /// The network's per-pixel probabilities, `S * S` row-major: they keep
    /// the region's edges soft. Without them the mask's 0/1 values serve.
    pub probabilities: Option<&'a [f32]>,
    /// The RGB window the network saw (`S x S x 3`). Over a ridge the
    /// shading varies only across it, so its gradients give the direction
    /// even where the mask's outline is off (light presses).
    pub window: Option<&'a FloatImage>,
}

impl Evidence<'_> {
    fn check(&self, w: usize, h: usize) -> Result<()> {
        if let Some(p) = self.probabilities
            && p.len() != w * h
        {
            return Err(
                tactile_core::Error::shape("probabilities", format!("{w}x{h}"), p.len()).into(),
            );
        }
        if let Some(img) = self.window
            && (img.width, img.height, img.channels, img.data.len()) != (w, h, 3, w * h * 3)
        {
            return Err(tactile_core::Error::shape(
                "window",
                format!("{w}x{h}x3"),
                format!("{}x{}x{}", img.width, img.height, img.channels),
            )
            .into());
        }
        Ok(())
    }
}

/// The tendon of an `side x side` window from the network's per-pixel
/// `probabilities` (`None` for a blank window: an empty mask, hence no
/// direction), the pixels at or above `threshold` post-processed by `cfg`.
pub fn window_tendon(
    side: usize,
    probabilities: Option<&[f32]>,
    window: &FloatImage,
    threshold: f64,
    cfg: &PostprocessConfig,
) -> Result<Tendon> {
    let mask = match probabilities {
        Some(p) => TendonMask::from_probabilities(side, side, p, threshold)?,
        None => TendonMask::empty(side, side),
    };
    let evidence = Evidence {
        probabilities,
        window: Some(window),
    };
    postprocess(&mask, evidence, cfg)
}

/// Keep the largest region not on the window's edge and give its direction.
/// Ties between equal areas go to the region met first in raster order.
pub fn postprocess(
    mask: &TendonMask,
    evidence: Evidence<'_>,
    cfg: &PostprocessConfig,
) -> Result<Tendon> {
    let (w, h) = (mask.width, mask.height);
    if mask.pixels.len() != w * h {
        return Err(
            tactile_core::Error::shape("mask", format!("{w}x{h}"), mask.pixels.len()).into(),
        );
    }
    evidence.check(w, h)?;
    let empty = |regions, dropped, why| Tendon {
        region: TendonMask::empty(w, h),
        regions,
        dropped_on_edge: dropped,
        direction: Err(why),
    };
    if w == 0 || h == 0 || mask.area() == 0 {
        return Ok(empty(0, 0, NoDirection::EmptyMask));
    }
    let size = ImageSize {
        width: w,
        height: h,
    };
    let bytes: Vec<u8> = mask
        .pixels
        .iter()
        .map(|&p| if p { 255 } else { 0 })
        .collect();
    let img = Image::<u8, 1>::new(size, bytes).map_err(kornia)?;
    let mut labels = Image::<i32, 1>::from_size_val(size, 0).map_err(kornia)?;
    connected_components(&img, &mut labels, Connectivity::Eight)
        .map_err(|e| kornia(format!("connected components: {e}")))?;
    // Per label: area, edge-band pixels, first raster index.
    let window = Window::of_frame(w as f64, h as f64);
    let mut stats: std::collections::BTreeMap<i32, (usize, usize, usize)> = Default::default();
    for (i, &l) in labels.as_slice().iter().enumerate() {
        if l <= 0 {
            continue;
        }
        let (u, v) = ((i % w) as f64, (i / w) as f64);
        let r = window.radius(u, v);
        let e = stats.entry(l).or_insert((0, 0, i));
        e.0 += 1;
        if r >= 1.0 - cfg.edge_band {
            e.1 += 1;
        }
    }
    let regions = stats.len();
    let on_edge =
        |&(area, edge, _): &(usize, usize, usize)| edge as f64 >= cfg.edge_fraction * area as f64;
    let dropped = stats.values().filter(|s| on_edge(s)).count();
    let best = stats
        .iter()
        .filter(|(_, s)| !on_edge(s))
        .max_by(|a, b| a.1.0.cmp(&b.1.0).then(b.1.2.cmp(&a.1.2)))
        .map(|(&l, _)| l);
    let Some(best) = best else {
        return Ok(empty(regions, dropped, NoDirection::EmptyMask));
    };
    let pixels: Vec<bool> = labels.as_slice().iter().map(|&l| l == best).collect();
    let region = TendonMask {
        width: w,
        height: h,
        pixels,
    };
    let direction = match cfg.direction {
        DirectionMethod::PrincipalAxis => principal_axis(&region, cfg),
        DirectionMethod::CentreLine => centre_line(&region, evidence, cfg)?,
    };
    Ok(Tendon {
        region,
        regions,
        dropped_on_edge: dropped,
        direction,
    })
}

/// First principal axis of the `true` pixels: f64, centred coordinates,
/// closed-form eigen-decomposition of the 2x2 covariance.
pub fn principal_axis(
    mask: &TendonMask,
    cfg: &PostprocessConfig,
) -> std::result::Result<Direction, NoDirection> {
    let window = Window::of_frame(mask.width as f64, mask.height as f64);
    let pts: Vec<(f64, f64)> = mask
        .pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| **p)
        .map(|(i, _)| ((i % mask.width) as f64, (i / mask.width) as f64))
        .filter(|&(u, v)| !cfg.axis_within_window || window.contains(u, v))
        .collect();
    if pts.is_empty() {
        return Err(NoDirection::EmptyMask);
    }
    if pts.len() < cfg.min_area.max(2) {
        return Err(NoDirection::TooSmall);
    }
    let n = pts.len() as f64;
    let (mu, mv) = pts.iter().fold((0.0, 0.0), |(a, b), (u, v)| (a + u, b + v));
    let (mu, mv) = (mu / n, mv / n);
    let (mut suu, mut svv, mut suv) = (0.0, 0.0, 0.0);
    for (u, v) in &pts {
        let (du, dv) = (u - mu, v - mv);
        suu += du * du;
        svv += dv * dv;
        suv += du * dv;
    }
    let (suu, svv, suv) = (suu / n, svv / n, suv / n);
    // Eigenvalues of [[suu, suv], [suv, svv]].
    let half_trace = (suu + svv) / 2.0;
    let disc = (((suu - svv) / 2.0).powi(2) + suv * suv).sqrt();
    let (major, minor) = (half_trace + disc, half_trace - disc);
    let anisotropy = if minor > 1e-12 * major.max(1e-300) {
        major / minor
    } else {
        f64::INFINITY
    };
    if major <= 0.0 || anisotropy < cfg.min_anisotropy {
        return Err(NoDirection::Isotropic);
    }
    // Angle of the major eigenvector: 0.5 * atan2(2 suv, suu - svv).
    let angle = 0.5 * (2.0 * suv).atan2(suu - svv);
    Ok(Direction {
        angle_deg: angle.to_degrees().rem_euclid(180.0),
        anisotropy,
        point: (mu, mv),
    })
}

/// Probability at which the soft region counts as tendon when looking for
/// the centre line across it.
const CENTRE_LINE_LEVEL: f32 = 0.5;

/// Width of the Gaussian weight around the centre-line point for the
/// shading gradients, as a fraction of the window side (4 px of a 48 px
/// window): local enough for an s-curve's turning tangent, wide enough to
/// average the sensor noise of a light press. Chosen on held-out seeds 200
/// and 501-503 among 2-8 px and the band-width rule of the mask edges.
const SHADING_SIGMA_PER_SIDE: f64 = 1.0 / 12.0;

/// The tangent of the region's centre line at its point nearest the window
/// centre.
///
/// The region (with a 2-pixel margin of its probabilities, so its edges stay
/// soft) is smoothed and its gradient taken; the gradients are the edge
/// normals, and the dominant eigenvector of their structure tensor, weighted
/// around a point, is the normal of the band there. Starting from the window
/// centre with a wide weight, each round walks along that normal through the
/// window centre, takes the middle of the tendon run it crosses as the
/// centre-line point nearest the centre, and narrows the weight to the
/// band's half-width around it. With the window image at hand, the final
/// normal comes from its shading gradients instead, weighted by the
/// probability and the same window around that point. Only gradients inside
/// the ellipse inscribed in the window (less the blur's reach) count, so the
/// window's own border adds no edge.
pub fn centre_line(
    region: &TendonMask,
    evidence: Evidence<'_>,
    cfg: &PostprocessConfig,
) -> Result<std::result::Result<Direction, NoDirection>> {
    let (w, h) = (region.width, region.height);
    evidence.check(w, h)?;
    let probabilities = evidence.probabilities;
    let area = region.area();
    if area == 0 {
        return Ok(Err(NoDirection::EmptyMask));
    }
    if area < cfg.min_area.max(2) {
        return Ok(Err(NoDirection::TooSmall));
    }
    let size = ImageSize {
        width: w,
        height: h,
    };
    let near = near_region(region, size)?;
    let soft: Vec<f32> = (0..w * h)
        .map(|i| match (near[i], probabilities) {
            (false, _) => 0.0,
            (_, Some(p)) if p[i].is_finite() => p[i].clamp(0.0, 1.0),
            (_, Some(_)) => 0.0,
            (_, None) => f32::from(u8::from(region.pixels[i])),
        })
        .collect();
    let (q, gx, gy) = smoothed_gradients(soft, size)?;
    let q = q.as_slice();
    // Gradients that count: inside the inscribed ellipse, 4 px (the blur's
    // reach) from its rim, so the window's border is no edge.
    let view = Window::of_frame(w as f64, h as f64).inset(4.0);
    let edges = strong_edges(gx.as_slice(), gy.as_slice(), w, &view);
    if edges.is_empty() {
        // No edge in view (the region fills the window): the pixels' own
        // axis is all there is.
        return Ok(principal_axis(region, cfg));
    }
    let mut point = (view.cx, view.cy);
    let mut sigma = w.min(h) as f64 / 2.0;
    let mut result = None;
    for _ in 0..4 {
        let Some((normal, anisotropy)) = dominant_normal(edges.iter().map(|&(u, v, dx, dy)| {
            let d2 = (u - point.0).powi(2) + (v - point.1).powi(2);
            ((-d2 / (2.0 * sigma * sigma)).exp(), dx, dy)
        })) else {
            break;
        };
        result = Some((normal + std::f64::consts::FRAC_PI_2, anisotropy));
        let Some((k, half_width)) = nearest_crossing(q, w, h, (view.cx, view.cy), normal) else {
            break;
        };
        let (ns, nc) = normal.sin_cos();
        point = (view.cx + k * nc, view.cy + k * ns);
        sigma = (1.5 * half_width).clamp(3.0, w.min(h) as f64 / 2.0);
    }
    if let (Some(img), Some(_)) = (evidence.window, result) {
        let weight = |i: usize| match probabilities {
            Some(p) if near[i] && p[i].is_finite() => p[i].clamp(0.0, 1.0) as f64,
            Some(_) => 0.0,
            None => f64::from(u8::from(region.pixels[i])),
        };
        if let Some(found) = shading_direction(img, w, h, point, &view, weight)? {
            result = Some(found);
        }
    }
    Ok(match result {
        Some((angle, anisotropy)) => Ok(Direction {
            angle_deg: angle.to_degrees().rem_euclid(180.0),
            anisotropy,
            point,
        }),
        None => principal_axis(region, cfg),
    })
}

/// The region grown by a 5 px box: where a segmenter's probabilities are
/// trusted as evidence of the band.
fn near_region(region: &TendonMask, size: ImageSize) -> Result<Vec<bool>> {
    let bytes: Vec<u8> = region.pixels.iter().map(|&p| u8::from(p)).collect();
    let img = Image::<u8, 1>::new(size, bytes).map_err(kornia)?;
    let mut near = Image::<u8, 1>::from_size_val(size, 0).map_err(kornia)?;
    dilate(&img, &mut near, &box_kernel(5), PaddingMode::Constant, [0]).map_err(kornia)?;
    Ok(near.as_slice().iter().map(|&v| v != 0).collect())
}

/// The gradients `(u, v, dx, dy)` inside `view` that are real edges: the
/// blur's far tails (below a thousandth of the strongest edge's squared
/// gradient) carry no direction, only cost.
fn strong_edges(gx: &[f32], gy: &[f32], w: usize, view: &Window) -> Vec<(f64, f64, f64, f64)> {
    let strongest = gx
        .iter()
        .zip(gy)
        .map(|(a, b)| a * a + b * b)
        .fold(0.0f32, f32::max) as f64;
    let floor = (1e-3 * strongest).max(1e-12);
    (0..gx.len())
        .filter_map(|i| {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            let (dx, dy) = (gx[i] as f64, gy[i] as f64);
            (view.contains(u, v) && dx * dx + dy * dy > floor).then_some((u, v, dx, dy))
        })
        .collect()
}

/// `q` (a `w x h` plane) at a real position, bilinearly; 0 off the plane.
fn bilinear(q: &[f32], w: usize, h: usize, u: f64, v: f64) -> f32 {
    if u < 0.0 || v < 0.0 || u > (w - 1) as f64 || v > (h - 1) as f64 {
        return 0.0;
    }
    let (u0, v0) = (u.floor() as usize, v.floor() as usize);
    let (u1, v1) = ((u0 + 1).min(w - 1), (v0 + 1).min(h - 1));
    let (fu, fv) = ((u - u0 as f64) as f32, (v - v0 as f64) as f32);
    let at = |a: usize, b: usize| q[b * w + a];
    (at(u0, v0) * (1.0 - fu) + at(u1, v0) * fu) * (1.0 - fv)
        + (at(u0, v1) * (1.0 - fu) + at(u1, v1) * fu) * fv
}

/// Walk the line through `centre` along `normal` (radians) in half-pixel
/// steps: the run of band (`q` at least [`CENTRE_LINE_LEVEL`]) nearest the
/// centre is where the centre line crosses it. Its weighted offset along
/// the normal and its half-width, pixels.
fn nearest_crossing(
    q: &[f32],
    w: usize,
    h: usize,
    centre: (f64, f64),
    normal: f64,
) -> Option<(f64, f64)> {
    let (ns, nc) = normal.sin_cos();
    let reach = ((w * w + h * h) as f64).sqrt() / 2.0;
    let steps = (2.0 * reach) as i64;
    let mut runs: Vec<(f64, f64, f64)> = Vec::new(); // (weight, weighted k, |k| min)
    let mut open = false;
    for step in -steps..=steps {
        let k = step as f64 * 0.5;
        let val = bilinear(q, w, h, centre.0 + k * nc, centre.1 + k * ns);
        if val >= CENTRE_LINE_LEVEL {
            if !open {
                runs.push((0.0, 0.0, f64::INFINITY));
                open = true;
            }
            if let Some(run) = runs.last_mut() {
                run.0 += val as f64;
                run.1 += val as f64 * k;
                run.2 = run.2.min(k.abs());
            }
        } else {
            open = false;
        }
    }
    let run = runs.iter().min_by(|a, b| a.2.total_cmp(&b.2))?;
    // The run's half-length (0.5 px steps) is the band's half-width.
    Some((run.1 / run.0, run.0 / 2.0 * 0.5))
}

/// The direction (radians, with its anisotropy) the window's shading gives
/// near `point`: the tendon's ridge shades the skin along its whole
/// length, so its gradients pin the angle finer than the mask's edges.
/// Pixels beyond 3 sigma of the point, outside `view` or of no `weight`
/// weigh (next to) nothing and are skipped.
fn shading_direction(
    img: &FloatImage,
    w: usize,
    h: usize,
    point: (f64, f64),
    view: &Window,
    weight: impl Fn(usize) -> f64,
) -> Result<Option<(f64, f64)>> {
    let shading = shading_gradients(img)?;
    let sigma = w.min(h) as f64 * SHADING_SIGMA_PER_SIDE;
    let reach2 = 9.0 * sigma * sigma;
    let found = dominant_normal(shading.iter().filter_map(|&(i, dx, dy)| {
        let (u, v) = ((i % w) as f64, (i / w) as f64);
        let d2 = (u - point.0).powi(2) + (v - point.1).powi(2);
        if d2 > reach2 || !view.contains(u, v) {
            return None;
        }
        let p = weight(i);
        (p > 0.0).then(|| (p * (-d2 / (2.0 * sigma * sigma)).exp(), dx, dy))
    }));
    Ok(found.map(|(normal, anisotropy)| (normal + std::f64::consts::FRAC_PI_2, anisotropy)))
}

/// The dominant orientation of weighted gradients `(weight, dx, dy)`: the
/// angle (radians) of the structure tensor's major eigenvector, and major /
/// minor eigenvalue. `None` when every weighted gradient is zero.
fn dominant_normal(gradients: impl Iterator<Item = (f64, f64, f64)>) -> Option<(f64, f64)> {
    let (mut jxx, mut jyy, mut jxy) = (0.0, 0.0, 0.0);
    for (k, dx, dy) in gradients {
        jxx += k * dx * dx;
        jyy += k * dy * dy;
        jxy += k * dx * dy;
    }
    let half_trace = (jxx + jyy) / 2.0;
    if half_trace.is_nan() || half_trace <= 1e-12 {
        return None;
    }
    let disc = (((jxx - jyy) / 2.0).powi(2) + jxy * jxy).sqrt();
    let (major, minor) = (half_trace + disc, half_trace - disc);
    let anisotropy = if minor > 1e-12 * major {
        major / minor
    } else {
        f64::INFINITY
    };
    Some((0.5 * (2.0 * jxy).atan2(jxx - jyy), anisotropy))
}

/// Errors of kornia's image operations as this crate's.
fn kornia(e: impl std::fmt::Display) -> Error {
    Error::Preprocess(tactile_preprocess::Error::Kornia(e.to_string()))
}

/// `plane` smoothed (Gaussian, sigma 1 px) and the smoothed plane's x and y
/// derivatives (Sobel).
fn smoothed_gradients(
    plane: Vec<f32>,
    size: ImageSize,
) -> Result<(Image<f32, 1>, Image<f32, 1>, Image<f32, 1>)> {
    let plane = Image::<f32, 1>::new(size, plane).map_err(kornia)?;
    let mut smooth = Image::<f32, 1>::from_size_val(size, 0.0).map_err(kornia)?;
    gaussian_blur(&plane, &mut smooth, (0, 0), (1.0, 1.0)).map_err(kornia)?;
    let mut gx = Image::<f32, 1>::from_size_val(size, 0.0).map_err(kornia)?;
    let mut gy = Image::<f32, 1>::from_size_val(size, 0.0).map_err(kornia)?;
    spatial_gradient_float(&smooth, &mut gx, &mut gy).map_err(kornia)?;
    Ok((smooth, gx, gy))
}

/// Per pixel `(index, dx, dy)` of the window's shading, summed over the
/// three channels' structure tensors by listing each channel's gradient:
/// every channel smoothed (sigma 1 px) and differentiated.
fn shading_gradients(img: &FloatImage) -> Result<Vec<(usize, f64, f64)>> {
    let size = ImageSize {
        width: img.width,
        height: img.height,
    };
    let mut out = Vec::with_capacity(3 * img.width * img.height);
    for c in 0..3 {
        let channel: Vec<f32> = img.data.iter().skip(c).step_by(3).copied().collect();
        let (_, gx, gy) = smoothed_gradients(channel, size)?;
        out.extend(
            gx.as_slice()
                .iter()
                .zip(gy.as_slice())
                .enumerate()
                .map(|(i, (&dx, &dy))| (i, dx as f64, dy as f64)),
        );
    }
    Ok(out)
}

/// Angular difference between two directions in [0, 180): at most 90.
pub fn direction_error_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(w: usize, h: usize, on: impl Fn(usize, usize) -> bool) -> TendonMask {
        TendonMask {
            width: w,
            height: h,
            pixels: (0..w * h).map(|i| on(i % w, i / w)).collect(),
        }
    }

    #[test]
    fn a_line_gives_its_angle_folded_into_0_180() {
        let cfg = PostprocessConfig::default();
        for deg in [0.0f64, 30.0, 90.0, 135.0, 179.0] {
            let (s, c) = deg.to_radians().sin_cos();
            let m = mask(64, 64, |u, v| {
                let (x, y) = (u as f64 - 31.5, v as f64 - 31.5);
                (x * s - y * c).abs() < 1.3 && (x * c + y * s).abs() < 20.0
            });
            let t = postprocess(&m, Evidence::default(), &cfg).unwrap();
            let d = t.direction.unwrap();
            assert!(direction_error_deg(d.angle_deg, deg) < 1.0, "{deg}: {d:?}");
            assert!((0.0..180.0).contains(&d.angle_deg));
            assert!(d.anisotropy > 10.0);
        }
    }

    #[test]
    fn empty_single_pixel_and_round_regions_have_no_principal_axis() {
        let cfg = PostprocessConfig {
            direction: DirectionMethod::PrincipalAxis,
            ..Default::default()
        };
        let t = postprocess(&mask(16, 16, |_, _| false), Evidence::default(), &cfg).unwrap();
        assert_eq!(t.direction, Err(NoDirection::EmptyMask));
        assert_eq!(t.region.area(), 0);
        let t = postprocess(
            &mask(16, 16, |u, v| (u, v) == (8, 8)),
            Evidence::default(),
            &cfg,
        )
        .unwrap();
        assert_eq!(t.direction, Err(NoDirection::TooSmall));
        let disc = mask(32, 32, |u, v| {
            (u as f64 - 15.5).powi(2) + (v as f64 - 15.5).powi(2) < 36.0
        });
        let t = postprocess(&disc, Evidence::default(), &cfg).unwrap();
        assert_eq!(t.direction, Err(NoDirection::Isotropic));
        assert_eq!(t.region.area(), disc.area());
        assert!(
            postprocess(
                &TendonMask {
                    width: 4,
                    height: 4,
                    pixels: vec![true; 3]
                },
                Evidence::default(),
                &cfg
            )
            .is_err()
        );
    }

    #[test]
    fn keeps_the_largest_region_and_drops_edge_glare() {
        let cfg = PostprocessConfig::default();
        // A bar through the middle, a bigger blob hugging the top-right rim.
        let m = mask(64, 64, |u, v| {
            let bar = (20..44).contains(&u) && (30..34).contains(&v);
            let r = ((u as f64 - 31.5).powi(2) + (v as f64 - 31.5).powi(2)).sqrt();
            let glare = r > 29.0 && u > 40 && v < 24;
            bar || glare
        });
        let t = postprocess(&m, Evidence::default(), &cfg).unwrap();
        assert_eq!(t.regions, 2);
        assert_eq!(t.dropped_on_edge, 1);
        assert_eq!(t.region.area(), 24 * 4);
        let d = t.direction.unwrap();
        assert!(direction_error_deg(d.angle_deg, 0.0) < 1.0, "{d:?}");
        // Only the border: nothing left, no direction.
        let border = mask(64, 64, |u, v| u == 0 || v == 0 || u == 63 || v == 63);
        let t = postprocess(&border, Evidence::default(), &cfg).unwrap();
        assert_eq!(t.direction, Err(NoDirection::EmptyMask));
    }

    #[test]
    fn a_wide_off_centre_band_in_a_square_keeps_its_angle() {
        // A 20 px band at 30 degrees, 10 px off centre, filling a 64 px
        // square window: its pixels in the square lean toward the diagonal,
        // those in the inscribed disc do not.
        let (s, c) = 30f64.to_radians().sin_cos();
        let m = mask(64, 64, |u, v| {
            let (x, y) = (u as f64 - 31.5, v as f64 - 31.5);
            (x * s - y * c - 10.0).abs() < 10.0
        });
        let pca = PostprocessConfig {
            direction: DirectionMethod::PrincipalAxis,
            ..Default::default()
        };
        let within = postprocess(&m, Evidence::default(), &pca).unwrap();
        let square = postprocess(
            &m,
            Evidence::default(),
            &PostprocessConfig {
                axis_within_window: false,
                ..pca
            },
        )
        .unwrap();
        let e_disc = direction_error_deg(within.direction.unwrap().angle_deg, 30.0);
        let e_square = direction_error_deg(square.direction.unwrap().angle_deg, 30.0);
        assert!(e_disc < 0.5, "{e_disc}");
        assert!(e_square > 2.0 * e_disc, "{e_square} vs {e_disc}");
    }

    #[test]
    fn equal_regions_tie_break_to_the_first_in_raster_order() {
        let cfg = PostprocessConfig::default();
        let m = mask(40, 40, |u, v| {
            ((10..14).contains(&v) && (12..28).contains(&u))
                || ((26..30).contains(&v) && (12..28).contains(&u))
        });
        for _ in 0..3 {
            let t = postprocess(&m, Evidence::default(), &cfg).unwrap();
            assert!(t.region.pixels[11 * 40 + 15] && !t.region.pixels[27 * 40 + 15]);
        }
    }

    /// A shaded ridge along `deg` through `(off_u, off_v)` from the centre
    /// of an `s x s` window: the photometric model's three lights over a
    /// Gaussian bump, so only the across-ridge direction varies.
    fn ridge_window(s: usize, deg: f64, offset: f64, width: f64) -> FloatImage {
        let (sn, cs) = deg.to_radians().sin_cos();
        let c = (s as f64 - 1.0) / 2.0;
        let height = |u: f64, v: f64| {
            let d = (u - c) * sn - (v - c) * cs - offset;
            3.0 * (-d * d / (2.0 * width * width)).exp()
        };
        let mut data = Vec::with_capacity(s * s * 3);
        for v in 0..s {
            for u in 0..s {
                let (u, v) = (u as f64, v as f64);
                let gx = (height(u + 0.5, v) - height(u - 0.5, v)) / 1.0;
                let gy = (height(u, v + 0.5) - height(u, v - 0.5)) / 1.0;
                let n = (gx * gx + gy * gy + 1.0).sqrt();
                let normal = (-gx / n, -gy / n, -1.0 / n);
                for az in [90f64, 210.0, 330.0] {
                    let (a, b) = az.to_radians().sin_cos();
                    let l = (
                        30f64.to_radians().cos() * b,
                        30f64.to_radians().cos() * a,
                        -0.5,
                    );
                    let dot = (normal.0 * l.0 + normal.1 * l.1 + normal.2 * l.2).max(0.0);
                    data.push((0.8 * (0.25 + dot)) as f32);
                }
            }
        }
        FloatImage {
            width: s,
            height: s,
            channels: 3,
            data,
        }
    }

    fn band(s: usize, deg: f64, offset: f64, half: f64) -> TendonMask {
        let (sn, cs) = deg.to_radians().sin_cos();
        let c = (s as f64 - 1.0) / 2.0;
        mask(s, s, |u, v| {
            ((u as f64 - c) * sn - (v as f64 - c) * cs - offset).abs() < half
        })
    }

    #[test]
    fn a_band_as_wide_as_the_window_still_has_its_direction() {
        // 40 px of a 48 px window: round inside the window for the
        // principal axis, still two straight edges for the centre line.
        let m = band(48, 60.0, 0.0, 20.0);
        let pca = PostprocessConfig {
            direction: DirectionMethod::PrincipalAxis,
            ..Default::default()
        };
        let t = postprocess(&m, Evidence::default(), &pca).unwrap();
        assert_eq!(t.direction, Err(NoDirection::Isotropic));
        let t = postprocess(&m, Evidence::default(), &PostprocessConfig::default()).unwrap();
        let d = t.direction.unwrap();
        assert!(direction_error_deg(d.angle_deg, 60.0) < 1.0, "{d:?}");
    }

    #[test]
    fn the_centre_line_point_is_nearest_the_window_centre() {
        // An arc of radius 30 px whose nearest point to the centre is 6 px
        // to the right of it: the tangent there is vertical (90 degrees),
        // while the region's principal axis follows the chord.
        let (s, r) = (48usize, 30.0);
        let c = (s as f64 - 1.0) / 2.0;
        let centre = (c + 6.0 + r, c + 10.0);
        let nearest_u = centre.0 - r * (1.0f64 - (10.0 / r).powi(2)).sqrt();
        let m = mask(s, s, |u, v| {
            let d = ((u as f64 - centre.0).powi(2) + (v as f64 - centre.1).powi(2)).sqrt();
            (d - r).abs() < 3.0 && (v as f64) < c + 20.0
        });
        let t = postprocess(&m, Evidence::default(), &PostprocessConfig::default()).unwrap();
        let d = t.direction.unwrap();
        // The true tangent at the arc point nearest the window centre.
        let (pu, pv) = (d.point.0 - centre.0, d.point.1 - centre.1);
        let tangent = (pv.atan2(pu).to_degrees() + 90.0).rem_euclid(180.0);
        assert!(
            (d.point.0 - nearest_u).abs() < 3.0,
            "{d:?} vs u {nearest_u}"
        );
        assert!(
            direction_error_deg(d.angle_deg, tangent) < 3.0,
            "{d:?} vs {tangent}"
        );
    }

    #[test]
    fn shading_corrects_a_mask_outline_that_leans() {
        // The network's mask leans 8 degrees off the ridge (as at light
        // presses); the window's shading varies only across the ridge.
        let (s, truth) = (48, 35.0);
        let image = ridge_window(s, truth, 3.0, 4.0);
        let m = band(s, truth + 8.0, 3.0, 5.0);
        let p: Vec<f32> = m
            .pixels
            .iter()
            .map(|&b| if b { 0.9 } else { 0.1 })
            .collect();
        let cfg = PostprocessConfig::default();
        let outline = postprocess(
            &m,
            Evidence {
                probabilities: Some(&p),
                window: None,
            },
            &cfg,
        )
        .unwrap()
        .direction
        .unwrap();
        assert!(
            direction_error_deg(outline.angle_deg, truth) > 6.0,
            "{outline:?}"
        );
        let shaded = postprocess(
            &m,
            Evidence {
                probabilities: Some(&p),
                window: Some(&image),
            },
            &cfg,
        )
        .unwrap()
        .direction
        .unwrap();
        assert!(
            direction_error_deg(shaded.angle_deg, truth) < 1.0,
            "{shaded:?}"
        );
    }

    #[test]
    fn evidence_of_the_wrong_size_is_an_error_not_a_panic() {
        let m = band(16, 0.0, 0.0, 2.0);
        let p = vec![0.5f32; 10];
        let cfg = PostprocessConfig::default();
        let e = Evidence {
            probabilities: Some(&p),
            window: None,
        };
        assert!(postprocess(&m, e, &cfg).is_err());
        let img = ridge_window(8, 0.0, 0.0, 2.0);
        let e = Evidence {
            probabilities: None,
            window: Some(&img),
        };
        assert!(postprocess(&m, e, &cfg).is_err());
        // Non-finite probabilities count as background.
        let p = vec![f32::NAN; 256];
        let e = Evidence {
            probabilities: Some(&p),
            window: None,
        };
        assert!(postprocess(&m, e, &cfg).is_ok());
    }
}
