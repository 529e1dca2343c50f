//! `tactile dataset from-video`: a video or a folder of frames with a CSV
//! of labels becomes a dataset every command reads.

use anyhow::Result;
use clap::Subcommand;
use tactile_core::import::{ImportOptions, import_dataset};

#[derive(Subcommand)]
pub(crate) enum DatasetCmd {
    /// A video file (or a folder of frames) and a labels CSV with a
    /// `frame` column (the frame's number from 0, or its file name) become
    /// a dataset of the documented layout; unlabelled frames are skipped.
    FromVideo(ImportOptions),
}

pub(crate) fn main(cmd: DatasetCmd) -> Result<()> {
    match cmd {
        DatasetCmd::FromVideo(a) => {
            let summary = import_dataset(&a)?;
            for w in &summary.warnings {
                tactile_core::note!("{w}");
            }
            say!("{}", summary.describe())
        }
    }
    Ok(())
}
