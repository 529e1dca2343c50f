//! `tactile dataset from-video`: a video or a folder of frames with a CSV
//! of labels becomes a dataset every command reads.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use tactile_core::dataset::DatasetKind;
use tactile_core::import::{ImportOptions, import_dataset};

#[derive(Subcommand)]
pub(crate) enum DatasetCmd {
    /// A video file (or a folder of frames) and a labels CSV with a
    /// `frame` column (the frame's number from 0, or its file name) become
    /// a dataset of the documented layout; unlabelled frames are skipped.
    FromVideo(FromVideoArgs),
}

#[derive(Args)]
pub(crate) struct FromVideoArgs {
    /// The video file (anything FFmpeg decodes), a ROS 2 bag (its folder or
    /// one .mcap; a frame's number is its index on --topic) or a folder of
    /// frames (a frame's number is its place when ordered by the numbers in
    /// the names), or a TIFF of many pages (a stack: a frame's number is its
    /// page's).
    #[arg(long)]
    video: PathBuf,
    /// A bag's image topic (without it, the bag's only image topic).
    #[arg(long)]
    topic: Option<String>,
    /// Labels CSV: a `frame` column and the kind's label columns
    /// (docs/datasets.md); `mask` and `depth` name files beside it.
    #[arg(long)]
    labels: PathBuf,
    /// Which sensor the frames are from (TacTip frames are saved grey).
    #[arg(long, value_enum)]
    kind: DatasetKind,
    /// The dataset folder to write.
    #[arg(long)]
    out: PathBuf,
    /// The manifest's `sensor_spec`: your rig and camera, in words.
    #[arg(long, default_value = "real sensor")]
    sensor: String,
    /// Replace an existing dataset at --out.
    #[arg(long)]
    force: bool,
}

pub(crate) fn main(cmd: DatasetCmd) -> Result<()> {
    match cmd {
        DatasetCmd::FromVideo(a) => {
            let s = import_dataset(&ImportOptions {
                frames: a.video,
                topic: a.topic,
                labels: a.labels,
                kind: a.kind,
                out: a.out,
                sensor: a.sensor,
                force: a.force,
            })?;
            say!("{}", s.describe());
        }
    }
    Ok(())
}
