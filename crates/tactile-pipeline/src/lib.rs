//! Paper B's palpation pipeline, frame by frame: the detector runs on
//! every frame; only when it sees a tendon do the segmenter, the
//! post-processing (largest region, glare override, PCA direction) and the
//! depth network run. The networks run on burn (ndarray or flex) or in
//! onnxruntime from their exported graphs; the preprocessing is the same.

use std::path::Path;
use std::time::Instant;

use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_core::image_io::RgbImage;
use tactile_core::{DeviceKind, Error, Result};
use tactile_depth::{DepthArtifact, DepthNet};
use tactile_detect::{Detector, DetectorArtifact};
use tactile_onnx::OrtModel;
use tactile_preprocess::visuo::is_blank;
use tactile_segment::{SegmenterArtifact, UNet};

/// Where the networks run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Runtime {
    BurnNdarray,
    BurnFlex,
    Onnx,
}

impl std::str::FromStr for Runtime {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "burn-ndarray" => Ok(Self::BurnNdarray),
            "burn-flex" => Ok(Self::BurnFlex),
            "onnx" => Ok(Self::Onnx),
            o => Err(Error::Config(format!(
                "unknown runtime '{o}': expected burn-ndarray, burn-flex or onnx"
            ))),
        }
    }
}

/// One network on one runtime: normalised input in, raw output out.
enum Net {
    Detector(Detector, Device),
    Segmenter(UNet, Device),
    Depth(DepthNet, Device),
    Ort(OrtModel),
}

impl Net {
    fn run(&mut self, shape: [usize; 4], x: Vec<f32>) -> Result<Vec<f32>> {
        let out = |t: Tensor<4>| -> Result<Vec<f32>> {
            t.into_data()
                .try_to_vec::<f32>()
                .map_err(|e| Error::Invalid(format!("network output: {e:?}")))
        };
        match self {
            Net::Detector(m, d) => {
                let t = Tensor::<4>::from_data(TensorData::new(x, shape), &*d);
                out(m.forward(t).reshape([shape[0], 1, 1, 1]))
            }
            Net::Segmenter(m, d) => {
                out(m.forward(Tensor::from_data(TensorData::new(x, shape), &*d)))
            }
            Net::Depth(m, d) => out(m.forward(Tensor::from_data(TensorData::new(x, shape), &*d))),
            Net::Ort(o) => Ok(o.run_f32(&shape, x)?.1),
        }
    }
}

/// What the pipeline made of one frame (one JSON Lines record).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameRecord {
    pub frame: String,
    pub tendon: bool,
    /// Detector probability.
    pub score: f32,
    pub direction_deg: Option<f64>,
    pub anisotropy: Option<f64>,
    /// Why there is no direction on a tendon frame (empty, too small, isotropic).
    pub no_direction: Option<String>,
    /// Pixels of the kept region in the segmenter's window.
    pub mask_area_px: usize,
    /// Camera-to-skin distance inside the sensing window, mm.
    pub depth_min_mm: Option<f32>,
    pub depth_mean_mm: Option<f32>,
    pub depth_max_mm: Option<f32>,
    /// The detector's own threshold decision (before any hysteresis).
    pub tendon_raw: bool,
    pub ms_detect: f64,
    pub ms_segment: Option<f64>,
    pub ms_depth: Option<f64>,
    pub ms_total: f64,
}

/// A two-threshold filter on the detector's probability over a sequence:
/// a tendon appears when the probability reaches `on` and disappears when
/// it falls below `off` (`off <= on`), so a score hovering around one
/// threshold at an onset or release does not flicker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    pub on: f32,
    pub off: f32,
    pub state: bool,
}

impl Hysteresis {
    pub fn new(on: f32, off: f32) -> Result<Self> {
        if !(0.0..=1.0).contains(&off) || !(0.0..=1.0).contains(&on) || off > on {
            return Err(Error::Config(format!(
                "hysteresis thresholds must satisfy 0 <= off <= on <= 1, got on {on}, off {off}"
            )));
        }
        Ok(Self {
            on,
            off,
            state: false,
        })
    }

    /// The decision for the next frame of the sequence.
    pub fn update(&mut self, p: f32) -> bool {
        self.state = if self.state {
            p >= self.off
        } else {
            p >= self.on
        };
        self.state
    }

    /// Start a new sequence (no tendon yet).
    pub fn reset(&mut self) {
        self.state = false;
    }
}

/// What a tendon frame looked like to the pipeline, for overlays.
pub struct FrameViews {
    /// The segmenter's window, `side x side x 3` in [0, 1].
    pub window: Vec<f32>,
    pub side: usize,
    /// The kept region.
    pub region: Vec<bool>,
    /// Direction (degrees) and centroid in window pixels.
    pub direction: Option<(f64, (f64, f64))>,
    /// Depth in mm at the depth network's input size.
    pub depth_mm: Vec<f32>,
    pub depth_size: [usize; 2],
}

impl FrameViews {
    /// Paper B's figure 3 style: the window enlarged `zoom` times with the
    /// kept region in green and the direction as a red line, and beside it
    /// the depth heat map at the same height. Written atomically as PNG.
    pub fn save_png(&self, path: &Path, zoom: usize) -> Result<()> {
        let s = self.side * zoom;
        let [dw, dh] = self.depth_size;
        let dscale = s as f64 / dh as f64;
        let dwz = (dw as f64 * dscale).round() as usize;
        let gap = 6;
        let width = s + gap + dwz;
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
        let (lo, hi) = self
            .depth_mm
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let span = if hi > lo { hi - lo } else { 1.0 };
        for y in 0..s {
            for x in 0..dwz {
                let (sx, sy) = (
                    ((x as f64) / dscale) as usize,
                    ((y as f64) / dscale) as usize,
                );
                let v = self.depth_mm[sy.min(dh - 1) * dw + sx.min(dw - 1)];
                let c = tactile_core::plot::colour(((v - lo) / span) as f64);
                let o = (y * width + s + gap + x) * 3;
                rgb[o..o + 3].copy_from_slice(&c);
            }
        }
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

/// The three models and their runtimes.
pub struct Pipeline {
    det: DetectorArtifact,
    seg: SegmenterArtifact,
    depth: DepthArtifact,
    det_net: Net,
    seg_net: Net,
    depth_net: Net,
    window: Vec<bool>,
}

impl Pipeline {
    /// Load `models/{detector,segmenter,depth}` from `dir` onto `runtime`
    /// (`threads` intra-op threads for onnxruntime).
    /// The detector's probability threshold.
    pub fn threshold(&self) -> f64 {
        self.det.threshold
    }

    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let flex = DeviceKind::Flex.device();
        let device = match runtime {
            Runtime::BurnNdarray => DeviceKind::Ndarray.device(),
            _ => flex.clone(),
        };
        let (det, d) = DetectorArtifact::load(dir.join("detector"), &device)?;
        let (seg, s) = SegmenterArtifact::load(dir.join("segmenter"), &device)?;
        let (depth, p) = DepthArtifact::load(dir.join("depth"), &device)?;
        if depth.with_mask {
            return Err(Error::Config(
                "the pipeline's depth model must take RGB only (mask-channel models are for evaluation)".into(),
            ));
        }
        let (det_net, seg_net, depth_net) = match runtime {
            Runtime::Onnx => (
                Net::Ort(OrtModel::from_bytes(
                    &tactile_onnx::export_detector(&d, det.detector.input_size)?,
                    threads,
                )?),
                Net::Ort(OrtModel::from_bytes(
                    &tactile_onnx::export_segmenter(&s, seg.unet.side)?,
                    threads,
                )?),
                Net::Ort(OrtModel::from_bytes(
                    &tactile_onnx::export_depth(&p, depth.net.in_channels, depth.net.input_size)?,
                    threads,
                )?),
            ),
            _ => (
                Net::Detector(d, device.clone()),
                Net::Segmenter(s, device.clone()),
                Net::Depth(p, device),
            ),
        };
        let [w, h] = depth.net.input_size;
        Ok(Self {
            det,
            seg,
            depth,
            det_net,
            seg_net,
            depth_net,
            window: tactile_depth::data::window_mask(w, h),
        })
    }

    /// Run on one frame. Frames without a tendon cost one detector pass.
    pub fn process(&mut self, name: &str, frame: &RgbImage) -> Result<FrameRecord> {
        Ok(self.process_with_views(name, frame)?.0)
    }

    /// [`Self::process`], also returning what a tendon frame looked like.
    pub fn process_with_views(
        &mut self,
        name: &str,
        frame: &RgbImage,
    ) -> Result<(FrameRecord, Option<FrameViews>)> {
        self.process_filtered(name, frame, None)
    }

    /// [`Self::process_with_views`] with the tendon decision taken by a
    /// hysteresis filter over the sequence instead of the fixed threshold.
    pub fn process_filtered(
        &mut self,
        name: &str,
        frame: &RgbImage,
        filter: Option<&mut Hysteresis>,
    ) -> Result<(FrameRecord, Option<FrameViews>)> {
        let t0 = Instant::now();
        let [dw, dh] = self.det.detector.input_size;
        let score = match self.det.frame_input(frame)? {
            None => 0.0,
            Some(x) => {
                let z = self.det_net.run([1, 3, dh, dw], x)?;
                1.0 / (1.0 + (-z[0]).exp())
            }
        };
        let tendon = match filter {
            Some(h) => h.update(score),
            None => score as f64 >= self.det.threshold,
        };
        let ms_detect = 1e3 * t0.elapsed().as_secs_f64();
        let mut rec = FrameRecord {
            frame: name.to_string(),
            tendon,
            score,
            tendon_raw: score as f64 >= self.det.threshold,
            direction_deg: None,
            anisotropy: None,
            no_direction: None,
            mask_area_px: 0,
            depth_min_mm: None,
            depth_mean_mm: None,
            depth_max_mm: None,
            ms_detect,
            ms_segment: None,
            ms_depth: None,
            ms_total: ms_detect,
        };
        if !tendon {
            return Ok((rec, None));
        }
        // Segment and point.
        let t1 = Instant::now();
        let cut = self.seg.frame_window(frame)?;
        let side = self.seg.unet.side;
        let t = if is_blank(&cut) {
            self.seg.tendon(None)?
        } else {
            let z = self
                .seg_net
                .run([1, 3, side, side], self.seg.stats.to_chw(&cut)?)?;
            let probs: Vec<f32> = z.iter().map(|&v| 1.0 / (1.0 + (-v).exp())).collect();
            self.seg.tendon(Some(&probs))?
        };
        rec.mask_area_px = t.region.area();
        let mut direction = None;
        match t.direction {
            Ok(d) => {
                rec.direction_deg = Some(d.angle_deg);
                rec.anisotropy = Some(d.anisotropy);
                direction = Some((d.angle_deg, d.centroid));
            }
            Err(why) => rec.no_direction = Some(format!("{why:?}")),
        }
        rec.ms_segment = Some(1e3 * t1.elapsed().as_secs_f64());
        // Depth.
        let t2 = Instant::now();
        let [w, h] = self.depth.net.input_size;
        let z = self
            .depth_net
            .run([1, 3, h, w], self.depth.frame_input(frame, None)?)?;
        let depth_mm: Vec<f32> = z.iter().map(|&v| self.depth.scale.to_mm(v)).collect();
        let mm: Vec<f32> = depth_mm
            .iter()
            .zip(&self.window)
            .filter(|(_, inside)| **inside)
            .map(|(&v, _)| v)
            .collect();
        rec.depth_min_mm = mm.iter().copied().reduce(f32::min);
        rec.depth_max_mm = mm.iter().copied().reduce(f32::max);
        rec.depth_mean_mm = Some(mm.iter().sum::<f32>() / mm.len().max(1) as f32);
        rec.ms_depth = Some(1e3 * t2.elapsed().as_secs_f64());
        rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
        let views = FrameViews {
            window: cut.data,
            side,
            region: t.region.pixels,
            direction,
            depth_mm,
            depth_size: [w, h],
        };
        Ok((rec, Some(views)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hysteresis_holds_through_a_dip_and_resets_per_sequence() {
        let mut h = Hysteresis::new(0.6, 0.2).unwrap();
        let p = [0.1, 0.5, 0.7, 0.4, 0.3, 0.1, 0.5, 0.9];
        let got: Vec<bool> = p.iter().map(|&v| h.update(v)).collect();
        assert_eq!(got, [false, false, true, true, true, false, false, true]);
        h.reset();
        assert!(!h.update(0.5));
        assert!(Hysteresis::new(0.2, 0.6).is_err());
        assert!(Hysteresis::new(1.5, 0.2).is_err());
        assert!("tensorflow".parse::<Runtime>().is_err());
        assert_eq!("burn-flex".parse::<Runtime>().unwrap(), Runtime::BurnFlex);
    }
}
