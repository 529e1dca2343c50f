//! Depth networks trained apart (another `--seed`), answering as one
//! network: the pixel-wise mean of their maps. Each run's error is partly
//! its own training's draw: four runs of one recipe spread 2.4x on the
//! other simulator's renders (`docs/own-sensor-depth-seeds.md`), and their
//! mean takes a fifth off the held-out error of the best of them, at the
//! sum of their costs.
//!
//! An ensemble folder holds `ensemble.json` naming member depth folders
//! inside it ([`Ensemble`]). They read a frame alike (input size, channels,
//! the same mask or calibration as fourth channel, the same kind of map);
//! each keeps its own channel statistics and depth scale, so the network
//! takes the input normalised as the first member takes it and answers in
//! the first member's units, converting for the others inside its graph.
//! It is one burn module, so every runtime, the ONNX export and the
//! standalone export take it as they take one depth network.

use std::path::{Path, PathBuf};

use burn::module::{Module, Param};
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_burn::ensemble::Ensemble;
use tactile_burn::runtime::Forward;
use tactile_onnx::{Exportable, export_batch_dynamic};

use crate::Result;
use crate::artifact::DepthArtifact;
use crate::model::DepthNet;

/// One member's input and output in the first member's terms: per input
/// channel `x * gain + shift` (normalised as the first member normalises,
/// to normalised as this one does), and its output `z * out_gain +
/// out_shift` (its model units to the first member's).
#[derive(Module, Debug)]
pub struct MemberUnits {
    /// `[1, C, 1, 1]`.
    pub gain: Param<Tensor<4>>,
    /// `[1, C, 1, 1]`.
    pub shift: Param<Tensor<4>>,
    /// `[1, 1, 1, 1]`.
    pub out_gain: Param<Tensor<4>>,
    /// `[1, 1, 1, 1]`.
    pub out_shift: Param<Tensor<4>>,
}

/// The networks of a depth ensemble.
#[derive(Module, Debug)]
pub struct DepthEnsemble {
    /// The member networks.
    pub members: Vec<DepthNet>,
    /// Per member, its units against the first member's.
    pub units: Vec<MemberUnits>,
}

impl DepthEnsemble {
    /// The mean of the members' maps, in the first member's model units.
    ///
    /// # Shapes
    /// - `x`: `[N, C, H, W]`, as the first member takes it
    /// - output: `[N, 1, H, W]`
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let n = self.members.len() as f64;
        let mut sum: Option<Tensor<4>> = None;
        for (m, u) in self.members.iter().zip(&self.units) {
            let z = m.forward(x.clone() * u.gain.val() + u.shift.val());
            let z = z * u.out_gain.val() + u.out_shift.val();
            sum = Some(match sum {
                Some(s) => s + z,
                None => z,
            });
        }
        match sum {
            Some(s) => s / n,
            None => {
                let [b, _, h, w] = x.dims();
                Tensor::zeros([b, 1, h, w], &x.device())
            }
        }
    }
}

impl Forward for DepthEnsemble {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }

    fn for_inference(self) -> Self {
        Self {
            members: self
                .members
                .into_iter()
                .map(Forward::for_inference)
                .collect(),
            units: self.units,
        }
    }
}

/// A depth ensemble on disk: `ensemble.json` and its member folders.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct DepthEnsembleArtifact {
    /// The member folder names and provenance.
    #[serde(flatten)]
    pub ensemble: Ensemble,
    /// The members' configs, read with `ensemble.json` (not written into it).
    #[serde(skip)]
    pub members: Vec<DepthArtifact>,
    /// The calibration folder each member's prior names, resolved (none
    /// for networks without a prior).
    #[serde(skip)]
    priors: Vec<Option<PathBuf>>,
}

/// The folder a calibration path names, for comparing two (canonical when
/// it exists).
fn resolved(p: &Path) -> PathBuf {
    std::fs::canonicalize(p)
        .unwrap_or_else(|_| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()))
}

/// A member `name`'s relative path `path` from the ensemble's folder,
/// `..` taken back lexically (`member-0` and `../..` give `..`); an
/// absolute `path` stays as it is.
fn relative_to_ensemble(name: &str, path: &str) -> PathBuf {
    use std::path::Component;
    let joined = Path::new(name).join(path);
    let mut out: Vec<Component> = Vec::new();
    for c in joined.components() {
        match (c, out.last()) {
            (Component::CurDir, _) => {}
            (Component::ParentDir, Some(Component::Normal(_))) => {
                out.pop();
            }
            _ => out.push(c),
        }
    }
    match out.is_empty() {
        true => PathBuf::from("."),
        false => out.iter().collect(),
    }
}

/// Whether two calibration folders reconstruct a frame alike: one folder,
/// or copies of one calibration (its config, slope network and background
/// the same bytes), as a run trained on a copy of the sensor folder has.
fn same_calibration(a: &Path, b: &Path) -> bool {
    use tactile_gelsight::GelsightArtifact as G;
    if resolved(a) == resolved(b) {
        return true;
    }
    let bytes = |d: &Path, f: &str| {
        tactile_core::io::read_limited(d.join(f), tactile_core::io::MAX_WEIGHTS_BYTES).ok()
    };
    [
        G::CONFIG_FILE,
        G::WEIGHTS_FILE,
        tactile_gelsight::artifact::BACKGROUND_FILE,
    ]
    .iter()
    .all(|f| bytes(a, f).is_some_and(|x| Some(x) == bytes(b, f)))
}

/// Members must read a frame alike: input size, channels, the same fourth
/// channel (the mask, or the reconstruction of one calibration: one
/// folder or copies of it) and the same kind of map. Architecture, statistics
/// and depth scale may differ.
fn check_alike(
    (first, first_prior): (&DepthArtifact, Option<&Path>),
    (other, other_prior): (&DepthArtifact, Option<&Path>),
    dir: &Path,
) -> tactile_core::Result<()> {
    let (a, b) = (&first.model, &other.model);
    let describe = |m: &DepthArtifact, p: Option<&Path>| {
        let fourth = match (m.with_mask, p) {
            (true, _) => "the tendon mask".to_string(),
            (false, Some(p)) => format!("the calibration in {}", resolved(p).display()),
            (false, None) => "nothing".to_string(),
        };
        format!(
            "{}x{} input, {} channels, fourth channel {fourth}, {} maps",
            m.model.input_size[0],
            m.model.input_size[1],
            m.model.in_channels,
            m.depth_maps.name()
        )
    };
    let same = a.input_size == b.input_size
        && a.in_channels == b.in_channels
        && first.with_mask == other.with_mask
        && match (first_prior, other_prior) {
            (Some(a), Some(b)) => same_calibration(a, b),
            (a, b) => a.is_none() && b.is_none(),
        }
        && first.depth_maps == other.depth_maps;
    if !same {
        return Err(tactile_core::Error::model(
            dir.join(DepthArtifact::CONFIG_FILE),
            format!(
                "it reads frames as {}, and the first member as {}: an ensemble's depth networks must read a frame alike",
                describe(other, other_prior),
                describe(first, first_prior)
            ),
        ));
    }
    Ok(())
}

/// The config a depth folder is used with: its own, or an ensemble's
/// first member's with its prior's path made relative to the ensemble's
/// folder (input, statistics, depth scale, calibration).
pub fn read_config(dir: &Path) -> Result<DepthArtifact> {
    if DepthEnsembleArtifact::is_in(dir) {
        Ok(DepthEnsembleArtifact::read(dir)?.lead()?)
    } else {
        Ok(DepthArtifact::read(dir)?)
    }
}

/// Whether `dir` holds a depth network: one, or an ensemble.
pub fn is_depth(dir: &Path) -> bool {
    DepthArtifact::is_in(dir) || Ensemble::is_of::<DepthArtifact>(dir)
}

/// The ONNX graph of the depth network in `dir` (one or an ensemble) with
/// the config it is used with (see [`read_config`]).
pub fn depth_onnx(dir: &Path) -> Result<(DepthArtifact, Vec<u8>)> {
    let device = tactile_burn::DeviceKind::Flex.device();
    if DepthEnsembleArtifact::is_in(dir) {
        let l = DepthEnsembleArtifact::load(dir, &device)?;
        Ok((l.artifact.lead()?, l.artifact.onnx(&l.model)?))
    } else {
        let l = DepthArtifact::load(dir, &device)?;
        let bytes = l.artifact.onnx(&l.model)?;
        Ok((l.artifact, bytes))
    }
}

impl DepthEnsembleArtifact {
    /// The first member's config, its prior's path relative to the
    /// ensemble's folder: the input, statistics, depth scale and
    /// calibration the ensemble as a whole is used with.
    pub fn lead(&self) -> Result<DepthArtifact> {
        let (Some(first), Some(name)) = (self.members.first(), self.ensemble.members.first())
        else {
            return Err(
                tactile_core::Error::Invalid("a depth ensemble without members".into()).into(),
            );
        };
        let mut lead = first.clone();
        if let Some(p) = &mut lead.prior {
            p.calibration = relative_to_ensemble(name, &p.calibration)
                .display()
                .to_string();
        }
        Ok(lead)
    }

    /// Copy the depth folders `members` (trained apart, reading a frame
    /// alike) into a new ensemble folder `out` (staged; an existing `out`
    /// is left alone). Members with a prior all take the first member's
    /// calibration (copies of one calibration are one): `../..` when
    /// `out`'s parent holds it (the documented layout,
    /// `SENSOR/depth/member-0`), so the sensor folder can be moved whole;
    /// its absolute path otherwise.
    pub fn assemble(members: &[PathBuf], out: &Path) -> Result<Ensemble> {
        let prior_of = |a: &DepthArtifact, dir: &Path| a.prior.as_ref().map(|p| p.folder(dir));
        let first = members.first().cloned().unwrap_or_default();
        let calibration = match DepthArtifact::read(&first)
            .ok()
            .and_then(|a| prior_of(&a, &first))
        {
            Some(c) => {
                let parent = std::path::absolute(out)
                    .ok()
                    .and_then(|o| o.parent().map(Path::to_path_buf));
                Some(match parent {
                    Some(p) if same_calibration(&p, &c) => "../..".to_string(),
                    _ => resolved(&c).display().to_string(),
                })
            }
            None => None,
        };
        let rewrite = |copy: &Path| -> tactile_core::Result<()> {
            let mut art = DepthArtifact::read(copy)?;
            if let (Some(p), Some(c)) = (&mut art.prior, &calibration) {
                p.calibration = c.clone();
                tactile_core::io::write_json_atomic(copy.join(DepthArtifact::CONFIG_FILE), &art)?;
            }
            Ok(())
        };
        Ok(Ensemble::assemble::<DepthArtifact>(
            members,
            out,
            |a, b, dir| {
                check_alike(
                    (a, prior_of(a, &first).as_deref()),
                    (b, prior_of(b, dir).as_deref()),
                    dir,
                )
            },
            |_| Ok(serde_json::json!({})),
            rewrite,
        )?)
    }

    /// Per member, from the first member's input and units to its own.
    fn units(&self, device: &Device) -> Vec<MemberUnits> {
        let Some(lead) = self.members.first() else {
            return Vec::new();
        };
        let t = |v: Vec<f32>, c: usize| {
            Param::from_tensor(Tensor::from_data(TensorData::new(v, [1, c, 1, 1]), device))
        };
        self.members
            .iter()
            .map(|m| {
                let c = m.model.in_channels;
                // RGB: x0 = (v - m0) / s0 and xk = (v - mk) / sk, so
                // xk = x0 * s0 / sk + (m0 - mk) / sk.
                let (l, s) = (&lead.stats, &m.stats);
                let mut gain: Vec<f32> = (0..3).map(|i| l.std[i] / s.std[i]).collect();
                let mut shift: Vec<f32> =
                    (0..3).map(|i| (l.mean[i] - s.mean[i]) / s.std[i]).collect();
                // A prior in model units: p0 = (d - o0) / u0 and
                // pk = (d - ok) / uk, so pk = p0 * u0 / uk + (o0 - ok) / uk.
                // The same conversion, the other way, for the output.
                let (a, b) = (lead.scale, m.scale);
                if c > 3 {
                    let prior = m.prior.is_some();
                    gain.push(if prior { a.unit_mm / b.unit_mm } else { 1.0 });
                    shift.push(if prior {
                        (a.offset_mm - b.offset_mm) / b.unit_mm
                    } else {
                        0.0
                    });
                }
                MemberUnits {
                    gain: t(gain, c),
                    shift: t(shift, c),
                    out_gain: t(vec![b.unit_mm / a.unit_mm], 1),
                    out_shift: t(vec![(b.offset_mm - a.offset_mm) / a.unit_mm], 1),
                }
            })
            .collect()
    }

    fn alike_all(&self, dir: &Path) -> tactile_core::Result<()> {
        let dirs = self.ensemble.member_dirs(dir);
        let mut all = dirs.iter().zip(&self.members).zip(&self.priors);
        let Some(((_, first), first_prior)) = all.next() else {
            return Ok(());
        };
        for ((d, m), p) in all {
            check_alike((first, first_prior.as_deref()), (m, p.as_deref()), d)?;
        }
        Ok(())
    }
}

impl Artifact for DepthEnsembleArtifact {
    type Model = DepthEnsemble;
    const KIND: &'static str = "depth ensemble";
    const CONFIG_FILE: &'static str = Ensemble::FILE;
    /// Each member keeps its own weights file.
    const WEIGHTS_FILE: &'static str = DepthArtifact::WEIGHTS_FILE;

    fn init(&self, device: &Device) -> tactile_core::Result<DepthEnsemble> {
        Ok(DepthEnsemble {
            members: Ensemble::init_members(&self.members, device, Self::KIND)?,
            units: self.units(device),
        })
    }

    /// `ensemble.json` (checked by [`Ensemble::read`]) and every member's
    /// config, which must read a frame as the first's does.
    fn read_unfinished(dir: &Path) -> tactile_core::Result<Self> {
        let (ensemble, members) = Ensemble::read_with_configs::<DepthArtifact>(dir, Self::KIND)?;
        let dirs = ensemble.member_dirs(dir);
        let priors = members
            .iter()
            .zip(&dirs)
            .map(|(m, d)| m.prior.as_ref().map(|p| p.folder(d)))
            .collect();
        let e = Self {
            ensemble,
            members,
            priors,
        };
        e.alike_all(dir)?;
        Ok(e)
    }

    fn load_unfinished(
        dir: &Path,
        device: &Device,
    ) -> tactile_core::Result<tactile_burn::Loaded<Self>> {
        let artifact = Self::read_unfinished(dir)?;
        let members = artifact
            .ensemble
            .load_members::<DepthArtifact>(dir, device)?;
        let model = DepthEnsemble {
            members,
            units: artifact.units(device),
        };
        Ok(tactile_burn::Loaded {
            artifact,
            model,
            dir: dir.to_path_buf(),
            device: device.clone(),
        })
    }

    /// Every member into its folder (weights, then config), then
    /// `ensemble.json`, each atomically.
    fn save(&self, model: &DepthEnsemble, dir: &Path) -> tactile_core::Result<()> {
        self.ensemble
            .save_members(&self.members, &model.members, dir)
    }
}

impl Exportable for DepthEnsembleArtifact {
    /// `[N, C, H, W]` frames as the first member takes them -> `[N, 1, H,
    /// W]` mean depth in the first member's model units.
    fn onnx(&self, model: &DepthEnsemble) -> tactile_onnx::Result<Vec<u8>> {
        let lead = self
            .lead()
            .map_err(|e| tactile_onnx::Error::Export(e.to_string()))?;
        let [w, h] = lead.model.input_size;
        let c = lead.model.in_channels;
        export_batch_dynamic(model, [1, c, h, w], |m: &DepthEnsemble, x| m.forward(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_members_calibration_is_named_from_the_ensembles_folder() {
        let r = |name, path| relative_to_ensemble(name, path);
        assert_eq!(r("member-0", "../.."), Path::new(".."));
        assert_eq!(r("member-1", ".."), Path::new("."));
        assert_eq!(r("member-0", "../../other"), Path::new("../other"));
        assert_eq!(r("member-0", "/abs/sensor"), Path::new("/abs/sensor"));
        assert_eq!(r("member-0", "./../../.."), Path::new("../.."));
    }
}
