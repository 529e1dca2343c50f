//! Pin tracking, the classical TacTip pipeline: the centroid of every pin
//! blob of the binary image, matched to a reference frame's pins so that
//! pin `i` is the same physical pin in every frame; features are the pins'
//! displacements from the reference (two numbers per pin).

use crate::{Error, Result};
use kornia_image::{Image, ImageSize};
use kornia_imgproc::connected_components::{Connectivity, connected_components};
use tactile_core::image_io::GreyImage;

use crate::{PinImage, PreprocessConfig, preprocess};

/// Centroids `(u, v)` in pixels of the 8-connected blobs of a binary image
/// with at least `min_area` pixels, in raster order of first appearance.
pub fn pin_centroids(binary: &GreyImage, min_area: usize) -> Result<Vec<(f32, f32)>> {
    let mut labels = Image::<i32, 1>::from_size_val(
        ImageSize {
            width: binary.width(),
            height: binary.height(),
        },
        0,
    )?;
    let n = connected_components(binary, &mut labels, Connectivity::Eight)
        .map_err(|e| Error::Kornia(format!("connected components: {e}")))?;
    let n = n.max(1) as usize;
    let (mut su, mut sv, mut area) = (vec![0f64; n], vec![0f64; n], vec![0usize; n]);
    let w = binary.width();
    for (i, &l) in labels.as_slice().iter().enumerate() {
        if l > 0 {
            let l = l as usize;
            su[l] += (i % w) as f64;
            sv[l] += (i / w) as f64;
            area[l] += 1;
        }
    }
    Ok((1..n)
        .filter(|&l| area[l] >= min_area)
        .map(|l| {
            (
                (su[l] / area[l] as f64) as f32,
                (sv[l] / area[l] as f64) as f32,
            )
        })
        .collect())
}

/// The binary image a config makes of a frame, at the frame's crop size
/// (no 28 x 28 resize, no pin growing): what pin tracking looks at.
pub fn full_resolution_binary(frame: &GreyImage, cfg: &PreprocessConfig) -> Result<GreyImage> {
    let mut c = cfg.clone();
    c.grow_px = 0;
    c.output_px = cfg.crop_px.min(frame.width()).min(frame.height());
    let PinImage { side, pixels } = preprocess(frame, &c)?;
    Ok(tactile_core::image_io::grey_image(
        side,
        side,
        pixels
            .iter()
            .map(|&p| if p > 0.5 { 255 } else { 0 })
            .collect(),
    )?)
}

/// The median over `points` of the distance to the nearest other point
/// (a pin lattice's spacing), pixels; `None` for fewer than 2 points.
pub fn median_spacing_px(points: &[(f32, f32)]) -> Option<f32> {
    if points.len() < 2 {
        return None;
    }
    let mut nn: Vec<f32> = points
        .iter()
        .enumerate()
        .map(|(i, a)| {
            points
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, b)| (a.0 - b.0).hypot(a.1 - b.1))
                .fold(f32::INFINITY, f32::min)
        })
        .collect();
    nn.sort_by(f32::total_cmp);
    Some(nn[nn.len() / 2])
}

/// Pins of a reference frame; matches other frames' centroids to them.
#[derive(Debug, Clone)]
pub struct PinTracker {
    /// Pin centroids of the reference frame, pixels.
    pub reference: Vec<(f32, f32)>,
    /// A centroid further than this from a reference pin is not that pin.
    pub max_shift_px: f32,
}

impl PinTracker {
    /// Track against `reference` centroids; the match radius is half the
    /// median nearest-neighbour spacing of the reference pins.
    pub fn new(reference: Vec<(f32, f32)>) -> Result<Self> {
        if reference.len() < 2 {
            return Err(tactile_core::Error::Invalid(format!(
                "pin tracking needs a reference frame with at least 2 pins, found {}",
                reference.len()
            ))
            .into());
        }
        let spacing = median_spacing_px(&reference).unwrap_or(0.0);
        Ok(Self {
            max_shift_px: spacing / 2.0,
            reference,
        })
    }

    /// Displacement `(du, dv)` of every reference pin (0 when no blob is
    /// close enough): `2 x reference.len()` features.
    pub fn displacements(&self, centroids: &[(f32, f32)]) -> Vec<f32> {
        self.reference
            .iter()
            .flat_map(|r| {
                let best = centroids
                    .iter()
                    .map(|c| ((c.0 - r.0).hypot(c.1 - r.1), c))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                match best {
                    Some((d, c)) if d <= self.max_shift_px => [c.0 - r.0, c.1 - r.1],
                    _ => [0.0, 0.0],
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dots(centres: &[(usize, usize)]) -> GreyImage {
        let (w, h) = (40, 30);
        let mut px = vec![0u8; w * h];
        for &(cu, cv) in centres {
            for v in cv - 1..=cv + 1 {
                for u in cu - 1..=cu + 1 {
                    px[v * w + u] = 255;
                }
            }
        }
        tactile_core::image_io::grey_image(w, h, px).unwrap()
    }

    #[test]
    fn centroids_and_displacements_follow_the_pins() {
        let rest = pin_centroids(&dots(&[(5, 5), (20, 5), (5, 20)]), 4).unwrap();
        assert_eq!(rest, vec![(5.0, 5.0), (20.0, 5.0), (5.0, 20.0)]);
        let tracker = PinTracker::new(rest).unwrap();
        // One pin moves 2 px right, one vanishes; a speck of 1 px is ignored.
        let mut img = dots(&[(7, 5), (5, 20)]);
        img.as_slice_mut()[25 * 40 + 30] = 255;
        let moved = pin_centroids(&img, 4).unwrap();
        assert_eq!(
            tracker.displacements(&moved),
            vec![2.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        );
    }
}
