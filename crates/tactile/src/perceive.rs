//! `tactile perceive`: paper A's simultaneous deployment, one encoding per
//! frame and every estimator on it.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_burn::{DeviceKind, Runtime};
use tactile_core::dataset::Dataset;
use tactile_pipeline::tactip::Predictor;

#[derive(Args)]
pub(crate) struct PerceiveArgs {
    /// Trained encoder folder (its estimator subfolders run by default), or
    /// a pose-network folder.
    #[arg(long, visible_alias = "model")]
    encoder: PathBuf,
    /// Estimator folders: classifier heads (head.json) and regressors
    /// (regressor.json, or an ensemble of them: ensemble.json), all run on
    /// the same feature vector (default: every such folder inside ENCODER).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// Dataset of frames to perceive.
    #[arg(long)]
    data: PathBuf,
    /// Also write every estimate to this CSV, or, for a name ending in
    /// .mcap, as ROS 2 messages (tactile_msgs/msg/Estimates on
    /// /tactile/estimates, docs/robots.md).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frames to print (all go to --out).
    #[arg(long, default_value_t = 10)]
    show: usize,
    /// Device the networks run on.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
    /// Run the networks here instead of on --device: `onnx` runs each
    /// network's ONNX export through onnxruntime (the deployment path the
    /// benches time), `burn-flex`/`burn-ndarray` are --device's two.
    #[arg(long, value_enum, conflicts_with = "device")]
    runtime: Option<Runtime>,
}

pub(crate) fn main(a: PerceiveArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    if let Some(out) = &a.out {
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let mut p = Predictor::load(
        &a.encoder,
        &a.heads,
        a.runtime.unwrap_or(a.device.runtime()),
    )?;
    let r = p.perceive(&ds)?;
    let mut header = vec!["file".to_string()];
    header.extend(r.estimates.columns.iter().map(|c| c.0.clone()));
    let rows: Vec<Vec<String>> = r
        .files
        .iter()
        .enumerate()
        .map(|(i, f)| [vec![f.clone()], r.estimates.row(i)].concat())
        .collect();
    say!("{}", header.join("\t"));
    for row in rows.iter().take(a.show) {
        say!("{}", row.join("\t"));
    }
    match &p {
        Predictor::PoseNetwork(_) => say!(
            "{} frames: pose network {:.3} ms/frame (preprocessing included)",
            ds.len(),
            r.ms_encode
        ),
        Predictor::Encoder(_) => say!(
            "{} frames: encoding {:.3} ms/frame (preprocessing included), {} estimator{} {:.4} ms/frame",
            ds.len(),
            r.ms_encode,
            p.estimators(),
            if p.estimators() == 1 { "" } else { "s" },
            r.ms_estimate
        ),
    }
    if let Some(out) = a
        .out
        .as_deref()
        .filter(|o| tactile_core::bag::is_bag_file(o))
    {
        tactile_ros::estimates::write_estimates(out, &r.files, &r.estimates)?;
        say!("estimates written to {} (ROS 2 messages)", out.display());
    } else if let Some(out) = &a.out {
        tactile_core::io::write_atomic_with(out, |w| {
            let mut csv = csv::Writer::from_writer(w);
            csv.write_record(&header)?;
            for row in &rows {
                csv.write_record(row)?;
            }
            csv.flush()
        })?;
        say!("estimates written to {}", out.display());
    }
    Ok(())
}
