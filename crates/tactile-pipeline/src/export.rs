//! Any model folder of the workspace to ONNX: the folder says which model
//! it holds (its config file), the model says how it exports.

use std::path::Path;

use tactile_burn::{Artifact, DeviceKind};
use tactile_cae::CaeArtifact;
use tactile_depth::ensemble::{depth_onnx, is_depth};
use tactile_detect::ensemble::{detector_onnx, is_detector};
use tactile_onnx::Exportable;
use tactile_segment::SegmenterArtifact;

use crate::Result;

/// Which part of a CAE folder to export (other models export their network).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Part {
    /// The network used at inference (for a CAE: pin image -> features).
    Encoder,
    /// A CAE's whole autoencoder (pin image -> reconstruction).
    Autoencoder,
}

impl std::str::FromStr for Part {
    type Err = tactile_core::Error;
    /// By the names the command line takes (`--part`), from the one
    /// `clap::ValueEnum` derive, so Python reads the same names.
    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        <Part as clap::ValueEnum>::from_str(s, false).map_err(|_| {
            tactile_core::Error::Config(format!(
                "unknown part '{s}': expected encoder or autoencoder"
            ))
        })
    }
}

/// An exported model.
pub struct Exported {
    /// What it is ("detector", "CAE encoder", ...).
    pub kind: &'static str,
    /// The ONNX protobuf.
    pub bytes: Vec<u8>,
}

fn export<A>(dir: &Path) -> Result<Vec<u8>>
where
    A: Exportable,
    A::Model: tactile_burn::runtime::Forward + Send + 'static,
{
    let l = A::load(dir, &DeviceKind::Flex.device())?;
    Ok(l.artifact.onnx(&l.model)?)
}

/// Export the model in `dir` to the ONNX file `out`, as `tactile export`
/// and Python's `tactile.export` do: the output is checked before any
/// work (never a file of an input it lies in) and written whole or not
/// at all. `part` is a CAE's (default: its encoder); `standalone` a paper
/// B network's ([`export_standalone`]), so the two are not asked together.
pub fn export_to(dir: &Path, out: &Path, part: Option<Part>, standalone: bool) -> Result<Exported> {
    tactile_core::dataset::check_output_file(out, &[])?;
    let e = match (standalone, part) {
        (true, Some(_)) => {
            return Err(tactile_core::Error::Config(format!(
                "{}: part and standalone together: a part is a CAE's (encoder or autoencoder), a standalone model a detector's, segmenter's or depth network's; ask for one of them",
                dir.display()
            ))
            .into());
        }
        (true, None) => export_standalone(dir)?,
        (false, part) => export_model(dir, part.unwrap_or(Part::Encoder))?,
    };
    tactile_onnx::save_onnx(out, &e.bytes)?;
    Ok(e)
}

/// Export the model in `dir`.
pub fn export_model(dir: &Path, part: Part) -> Result<Exported> {
    tactile_core::io::expect_folder(dir, "model folder")?;
    if tactile_pose::PoseEnsemble::is_in(dir) {
        let members = tactile_pose::PoseEnsemble::read(dir)?.members;
        return Err(tactile_core::Error::Invalid(format!(
            "{}: an ensemble of {} pose networks ({}), each reading the frame through its own pin image: export each member (`tactile export --model {} --out {}.onnx`) and average their estimates in the labels' units, as `tactile predict` does",
            dir.display(),
            members.len(),
            members.join(", "),
            dir.join(&members[0]).display(),
            members[0]
        ))
        .into());
    }
    if part == Part::Autoencoder && !CaeArtifact::is_in(dir) {
        return Err(tactile_core::Error::Invalid(format!(
            "{}: part autoencoder: only a CAE has an autoencoder (its decoder beside the encoder), and this folder holds no cae.json; leave out the part to export its network",
            dir.display()
        ))
        .into());
    }
    let (kind, bytes) = if is_detector(dir) {
        ("detector", detector_onnx(dir)?.1)
    } else if SegmenterArtifact::is_in(dir) {
        ("segmenter", export::<SegmenterArtifact>(dir)?)
    } else if is_depth(dir) {
        ("depth network", depth_onnx(dir)?.1)
    } else if tactile_gelsight::GelsightArtifact::is_in(dir) {
        (
            "calibrated sensor model",
            export::<tactile_gelsight::GelsightArtifact>(dir)?,
        )
    } else if tactile_pose::PoseArtifact::is_in(dir) {
        ("pose network", export::<tactile_pose::PoseArtifact>(dir)?)
    } else if part == Part::Autoencoder {
        let l = CaeArtifact::load(dir, &DeviceKind::Flex.device())?;
        let px = l.artifact.model.input_px;
        (
            "CAE autoencoder",
            tactile_cae::export::autoencoder_onnx(&l.model, px)?,
        )
    } else if CaeArtifact::is_in(dir) {
        ("CAE encoder", export::<CaeArtifact>(dir)?)
    } else {
        let exportable = |d: &Path| {
            is_detector(d)
                || SegmenterArtifact::is_in(d)
                || is_depth(d)
                || tactile_gelsight::GelsightArtifact::is_in(d)
                || tactile_pose::PoseArtifact::is_in(d)
                || CaeArtifact::is_in(d)
        };
        let hint =
            tactile_burn::artifact::folder_hint(dir, exportable, "a model `export` does not write");
        return Err(tactile_core::Error::wrong_kind(
            dir,
            "model folder",
            format!("no cae.json, pose.json, detector.json, segmenter.json, depth.json or gelsight.json{hint}"),
        )
        .into());
    };
    Ok(Exported { kind, bytes })
}

/// Export the detector, segmenter or depth network in `dir` as a model
/// that stands alone ([`tactile_onnx::standalone`]): input `frame`, uint8
/// `[N, H, W, 3]` at the model's input size (the segmenter's: its square
/// window); output `tendon_probability` `[N, 1]`, `mask_probability`
/// `[N, 1, S, S]` or `depth_mm` `[N, 1, H, W]`; the threshold, statistics,
/// input size and toolkit version in its metadata.
pub fn export_standalone(dir: &Path) -> Result<Exported> {
    use tactile_onnx::standalone::{
        ExposureLevel, GateSpec, LayoutGate, ProfileGate, StandaloneOutput, StandaloneSpec,
        f32_at_or_above, make_standalone,
    };
    let device = DeviceKind::Flex.device();
    let list = |v: &[f32]| serde_json::to_string(v).unwrap_or_default();
    let common = |kind: &str, w: usize, h: usize, bits: u8, mean: &[f32], std: &[f32]| {
        let levels = if bits == 16 {
            " (the resized frame times 65535)"
        } else {
            ""
        };
        vec![
            ("tactile.model".to_string(), kind.to_string()),
            ("tactile.version".into(), env!("CARGO_PKG_VERSION").into()),
            ("input_size".into(), format!("{w}x{h}")),
            (
                "input".into(),
                format!("frame: uint{bits} [N, {h}, {w}, 3] RGB{levels}"),
            ),
            ("channel_mean".into(), list(mean)),
            ("channel_std".into(), list(std)),
        ]
    };
    let (kind, bytes) = if is_detector(dir) {
        let (a, onnx) = detector_onnx(dir)?;
        let [w, h] = a.model.input_size;
        let bits = a.model.bits();
        let mut metadata = common("detector", w, h, bits, &a.stats.mean, &a.stats.std);
        if a.model.normalises_exposure() {
            metadata.push((
                "exposure".into(),
                "each channel divided by its median over the frame's centre (in the graph)".into(),
            ));
        }
        metadata.push(("threshold".into(), a.threshold.to_string()));
        metadata.push((
            "output".into(),
            "tendon_probability: float32 [N, 1], 0 for a gated frame; gate: int64 [N], 0 passed, 1 blank, 2 foreign (outside the input profile, or grey where its training frames were in colour); input_score: float32 [N] (0 without a profile); tendon: bool [N], the decision".into(),
        ));
        let profile = a.input_profile.as_ref().map(|p| {
            let r = tactile_preprocess::profile::Regions::of(w, h);
            ProfileGate {
                luma: tactile_preprocess::profile::LUMA,
                window: r.window,
                texture: r.texture,
                housing: r.housing,
                centre: p.centre.clone(),
                scale: p.scale.clone(),
                threshold: p.threshold,
                grey_frames: p.grey_frames,
                layout: p.layout.as_ref().map(|l| LayoutGate {
                    columns: l.columns,
                    rows: l.rows,
                    reference: l.reference.clone(),
                    contrast_weights: l.contrast_weights(),
                }),
            }
        });
        if let Some(p) = &a.input_profile {
            metadata.push(("input_profile_threshold".into(), p.threshold.to_string()));
        }
        let spec = StandaloneSpec {
            height: h,
            width: w,
            mean: a.stats.mean.clone(),
            std: a.stats.std.clone(),
            output: StandaloneOutput::Probability {
                name: "tendon_probability".into(),
            },
            metadata,
            input_bits: bits,
            exposure_level: a.model.normalises_exposure().then(|| ExposureLevel {
                pixels: tactile_preprocess::visuo::exposure_pixels(w, h),
                level: tactile_preprocess::visuo::FLAT_SKIN_LEVEL,
            }),
            gates: Some(GateSpec {
                blank_std: tactile_preprocess::visuo::BLANK_FRAME_STD,
                profile,
                threshold: f32_at_or_above(a.threshold),
            }),
        };
        ("detector", make_standalone(&onnx, &spec)?)
    } else if SegmenterArtifact::is_in(dir) {
        let l = SegmenterArtifact::load(dir, &device)?;
        let a = &l.artifact;
        let s = a.model.side;
        let mut metadata = common("segmenter", s, s, 8, &a.stats.mean, &a.stats.std);
        metadata.push(("threshold".into(), a.threshold.to_string()));
        metadata.push((
            "output".into(),
            format!("mask_probability: float32 [N, 1, {s}, {s}]; tendon pixels at >= threshold"),
        ));
        metadata.push((
            "window".into(),
            format!("the frame scaled so its shorter side is {s} px, the centred {s} x {s} square"),
        ));
        let spec = StandaloneSpec {
            height: s,
            width: s,
            mean: a.stats.mean.clone(),
            std: a.stats.std.clone(),
            output: StandaloneOutput::Probability {
                name: "mask_probability".into(),
            },
            metadata,
            input_bits: 8,
            exposure_level: None,
            gates: None,
        };
        ("segmenter", make_standalone(&a.onnx(&l.model)?, &spec)?)
    } else if is_depth(dir) {
        let a = &tactile_depth::ensemble::read_config(dir)?;
        if a.with_mask || a.prior.is_some() {
            return Err(tactile_core::Error::Invalid(format!(
                "{}: this depth network also takes a {} channel; a standalone export takes the frame only (export it with `tactile export` and feed the fourth channel)",
                dir.display(),
                if a.with_mask { "mask" } else { "calibration prior" }
            ))
            .into());
        }
        let [w, h] = a.model.input_size;
        let mut metadata = common("depth", w, h, 8, &a.stats.mean, &a.stats.std);
        metadata.push((
            "output".into(),
            format!("depth_mm: float32 [N, 1, {h}, {w}], camera to skin, mm"),
        ));
        let spec = StandaloneSpec {
            height: h,
            width: w,
            mean: a.stats.mean.clone(),
            std: a.stats.std.clone(),
            output: StandaloneOutput::Affine {
                name: "depth_mm".into(),
                scale: a.scale.unit_mm,
                offset: a.scale.offset_mm,
            },
            metadata,
            input_bits: 8,
            exposure_level: None,
            gates: None,
        };
        (
            "depth network",
            make_standalone(&depth_onnx(dir)?.1, &spec)?,
        )
    } else {
        return Err(tactile_core::Error::wrong_kind(
            dir,
            "detector, segmenter or depth model folder",
            "no detector.json, segmenter.json or depth.json",
        )
        .into());
    };
    Ok(Exported { kind, bytes })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The refusal of exporting the shipped model `name`'s `part`.
    fn refused(name: &str, part: Part) -> String {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../models")
            .join(name);
        match export_model(&dir, part) {
            Ok(e) => panic!("{name} exported as a {}", e.kind),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_pose_ensemble_is_refused_with_how_to_export_its_members() {
        let e = refused("pose-surface", Part::Encoder);
        assert!(
            e.contains("an ensemble of 2 pose networks (member-0, member-1)")
                && e.contains("pose-surface/member-0 --out member-0.onnx"),
            "{e}"
        );
    }

    #[test]
    fn an_autoencoder_is_asked_only_of_a_cae() {
        let e = refused("segmenter", Part::Autoencoder);
        assert!(
            e.contains("segmenter: part autoencoder: only a CAE has an autoencoder"),
            "{e}"
        );
    }
}
