//! From a predicted mask to a tendon region and its direction (paper B):
//! keep the largest 8-connected region, discard a region lying on the outer
//! edge of the window (the LED glare), and take the first principal axis of
//! the region's pixels. A pure function of the mask.

use crate::{Error, Result};
use kornia_image::{Image, ImageSize};
use kornia_imgproc::connected_components::{Connectivity, connected_components};
use serde::{Deserialize, Serialize};

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
    /// Image direction of the first principal axis, folded into [0, 180):
    /// 0 = pointing right, 90 = pointing down (sensors.md).
    pub angle_deg: f64,
    /// Major / minor eigenvalue of the pixel covariance (inf for a line).
    pub anisotropy: f64,
    /// Centroid `(u, v)` in pixels.
    pub centroid: (f64, f64),
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

/// Keep the largest region not on the window's edge and give its direction.
/// Ties between equal areas go to the region met first in raster order.
pub fn postprocess(mask: &TendonMask, cfg: &PostprocessConfig) -> Result<Tendon> {
    let (w, h) = (mask.width, mask.height);
    if mask.pixels.len() != w * h {
        return Err(
            tactile_core::Error::shape("mask", format!("{w}x{h}"), mask.pixels.len()).into(),
        );
    }
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
    let kornia = |e: String| Error::Preprocess(tactile_preprocess::Error::Kornia(e));
    let img = Image::<u8, 1>::new(size, bytes).map_err(|e| kornia(e.to_string()))?;
    let mut labels = Image::<i32, 1>::from_size_val(size, 0).map_err(|e| kornia(e.to_string()))?;
    connected_components(&img, &mut labels, Connectivity::Eight)
        .map_err(|e| kornia(format!("connected components: {e}")))?;
    // Per label: area, edge-band pixels, first raster index.
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let (rx, ry) = (w as f64 / 2.0, h as f64 / 2.0);
    let mut stats: std::collections::BTreeMap<i32, (usize, usize, usize)> = Default::default();
    for (i, &l) in labels.as_slice().iter().enumerate() {
        if l <= 0 {
            continue;
        }
        let (u, v) = ((i % w) as f64, (i / w) as f64);
        let r = (((u - cx) / rx).powi(2) + ((v - cy) / ry).powi(2)).sqrt();
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
    let direction = principal_axis(&region, cfg);
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
    let (w, h) = (mask.width as f64, mask.height as f64);
    let (cx, cy, rx, ry) = ((w - 1.0) / 2.0, (h - 1.0) / 2.0, w / 2.0, h / 2.0);
    let pts: Vec<(f64, f64)> = mask
        .pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| **p)
        .map(|(i, _)| ((i % mask.width) as f64, (i / mask.width) as f64))
        .filter(|(u, v)| {
            !cfg.axis_within_window || ((u - cx) / rx).powi(2) + ((v - cy) / ry).powi(2) <= 1.0
        })
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
        centroid: (mu, mv),
    })
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
            let t = postprocess(&m, &cfg).unwrap();
            let d = t.direction.unwrap();
            assert!(direction_error_deg(d.angle_deg, deg) < 1.0, "{deg}: {d:?}");
            assert!((0.0..180.0).contains(&d.angle_deg));
            assert!(d.anisotropy > 10.0);
        }
    }

    #[test]
    fn empty_single_pixel_and_round_regions_have_no_direction() {
        let cfg = PostprocessConfig::default();
        let t = postprocess(&mask(16, 16, |_, _| false), &cfg).unwrap();
        assert_eq!(t.direction, Err(NoDirection::EmptyMask));
        assert_eq!(t.region.area(), 0);
        let t = postprocess(&mask(16, 16, |u, v| (u, v) == (8, 8)), &cfg).unwrap();
        assert_eq!(t.direction, Err(NoDirection::TooSmall));
        let disc = mask(32, 32, |u, v| {
            (u as f64 - 15.5).powi(2) + (v as f64 - 15.5).powi(2) < 36.0
        });
        let t = postprocess(&disc, &cfg).unwrap();
        assert_eq!(t.direction, Err(NoDirection::Isotropic));
        assert_eq!(t.region.area(), disc.area());
        assert!(
            postprocess(
                &TendonMask {
                    width: 4,
                    height: 4,
                    pixels: vec![true; 3]
                },
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
        let t = postprocess(&m, &cfg).unwrap();
        assert_eq!(t.regions, 2);
        assert_eq!(t.dropped_on_edge, 1);
        assert_eq!(t.region.area(), 24 * 4);
        assert!(direction_error_deg(t.direction.unwrap().angle_deg, 0.0) < 1e-9);
        // Only the border: nothing left, no direction.
        let border = mask(64, 64, |u, v| u == 0 || v == 0 || u == 63 || v == 63);
        let t = postprocess(&border, &cfg).unwrap();
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
        let within = postprocess(&m, &PostprocessConfig::default()).unwrap();
        let square = postprocess(
            &m,
            &PostprocessConfig {
                axis_within_window: false,
                ..Default::default()
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
            let t = postprocess(&m, &cfg).unwrap();
            assert!(t.region.pixels[11 * 40 + 15] && !t.region.pixels[27 * 40 + 15]);
        }
    }
}
