//! `docs/calibration.md`: sensor models of a ball-press calibration
//! cross-validated by press (the lookup table, the per-pixel MLP and the
//! toolkit's convolutional models), with the circle finder's agreement,
//! fit times and speed per runtime, and two plots: shape error against
//! latency, and reconstructed against true cap profiles.

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_core::plot::{Series, line_plot};
use tactile_gelsight::bench::{BenchOptions, Candidate, CandidateResult, cross_validate};
use tactile_gelsight::eval::CircleAgreement;
use tactile_gelsight::geometry::Cap;
use tactile_gelsight::training::prepare_presses;
use tactile_gelsight::{BallPresses, CalibrationConfig};

use crate::Result;

/// `tactile bench calibration`'s flags: the folder, the split, the
/// robustness and timing settings, and the shipped recipe the candidates
/// are built from ([`Self::bench`] makes the [`CalibrationBench`]).
#[derive(Debug, Clone, clap::Args)]
pub struct CalibrationRequest {
    /// Calibration folder (docs/datasets.md: the calibration layout).
    #[arg(long, default_value = "../shared/real/gelsight-ball")]
    pub data: PathBuf,
    /// Folds of the leave-presses-out split (press i in fold i mod folds).
    #[arg(long, default_value_t = 8)]
    pub folds: usize,
    /// Exposure change of the robustness rows (0.15: +-15 %).
    #[arg(long, default_value_t = 0.15)]
    pub exposure: f64,
    /// Frames timed per runtime (median reported).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub runs: u32,
    /// Only these candidates (lookup, mlp, conv-slopes, shipped); all by default.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub candidates: Vec<String>,
    /// The shipped recipe the candidates are built from.
    #[command(flatten)]
    pub recipe: tactile_gelsight::BallOptions,
}

impl CalibrationRequest {
    /// The bench these flags ask for, its recipe checked
    /// ([`tactile_gelsight::BallOptions::config`]); progress is shown.
    pub fn bench(self) -> Result<CalibrationBench> {
        Ok(CalibrationBench {
            base: self.recipe.config()?,
            options: BenchOptions {
                folds: self.folds,
                exposure: self.exposure,
                runs: self.runs as usize,
                device: self.recipe.schedule.device,
                progress: true,
            },
            data: self.data,
            only: self.candidates,
        })
    }
}

/// What the page is made from.
#[derive(Debug, Clone)]
pub struct CalibrationBench {
    /// The calibration folder.
    pub data: PathBuf,
    /// The shipped recipe (the other candidates are built beside it).
    pub base: CalibrationConfig,
    /// Folds, exposure change, timing runs, device.
    pub options: BenchOptions,
    /// The candidates to run, by key ([`Candidate::KEYS`]); empty: all.
    pub only: Vec<String>,
}

/// The page's numbers.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationReport {
    /// Presses.
    pub presses: usize,
    /// Folds.
    pub folds: usize,
    /// The circle finder against the annotations.
    pub circles: Option<CircleAgreement>,
    /// Seconds to find circles and build targets for every press.
    pub prepare_s: f64,
    /// One row per candidate.
    pub candidates: Vec<CandidateResult>,
}

/// Cross-validate every candidate on the presses of `b.data`.
pub fn bench_calibration(b: &CalibrationBench) -> Result<CalibrationReport> {
    let ds = BallPresses::open(&b.data)?;
    b.options.check(ds.presses.len(), &ds.root)?;
    let t0 = std::time::Instant::now();
    let (bg, presses) = prepare_presses(&ds, b.base.working_factor(&ds), b.base.circles)?;
    let prepare_s = t0.elapsed().as_secs_f64();
    let circles = CircleAgreement::of(&presses);
    if let Some(bad) = b
        .only
        .iter()
        .find(|k| !Candidate::KEYS.contains(&k.as_str()))
    {
        return Err(tactile_core::Error::Config(format!(
            "candidates: no candidate {bad:?} (known: {})",
            Candidate::KEYS.join(", ")
        ))
        .into());
    }
    let mut candidates = Vec::new();
    for (key, name, c) in Candidate::standard(&b.base) {
        if !b.only.is_empty() && !b.only.iter().any(|k| k == key) {
            continue;
        }
        tactile_core::note!("cross-validating {name} ({} folds)", b.options.folds);
        candidates.push(cross_validate(&name, &c, &ds, (&bg, &presses), &b.options)?);
    }
    Ok(CalibrationReport {
        presses: presses.len(),
        folds: b.options.folds,
        circles,
        prepare_s,
        candidates,
    })
}

fn ms(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.2}"))
}

impl CalibrationReport {
    /// The page, with its plots written beside `out` (`NAME-speed.png`,
    /// `NAME-profiles.png`) and its numbers as `NAME.json`.
    pub fn write(&self, b: &CalibrationBench, command: &str, out: &Path) -> Result<String> {
        let _page = crate::output::lock_page(out)?;
        let (speed_path, speed_png) = crate::output::picture_beside(out, "speed");
        let (profile_path, profile_png) = crate::output::picture_beside(out, "profiles");
        let e = b.options.exposure * 100.0;
        let ds = BallPresses::open(&b.data)?;
        let mut md = String::new();
        md.push_str("# Ball-press calibration of a real GelSight\n\n");
        md.push_str(&format!(
            "Generated by `{command}`. Machine: {}; burn and onnxruntime on {} threads.\n\n",
            tactile_core::bench::Machine::detect().describe(),
            crate::latency::threads()
        ));
        md.push_str(&format!(
            "Data: `{}` ({} presses of {}, {:.4} mm per pixel). Leave-presses-out: press i is in fold i mod {}; each fold's presses are reconstructed by a model calibrated on the other {} folds (networks stop early on 4 of those, spread over the recording) and scored at the frame's size against the ball's geometry: the shape inside the contact circle (mean |error| once the median offset, the unknown sink of the rim, is removed), the far field (mean |indentation| beyond 3 contact radii, where the skin is at rest), the mean |slope error| inside the contact (working grid), and the reconstructed rim sink and peak. Circles, targets and every model are the toolkit's (`tactile calibrate ball`); the recipe is the shipped one with the changes the row names.\n\n",
            b.data.display(),
            self.presses,
            ds.describe_balls(),
            ds.sensor.mm_per_px,
            self.folds,
            self.folds - 1
        ));
        if let Some(c) = &self.circles {
            md.push_str(&format!(
                "Contact circles found by the toolkit against the annotations ({} presses): centre error {:.2} px (largest {:.2}), radius error {:.2} px (bias {:+.2}). Targets use the annotated circles where `{}` gives them. Finding circles and building targets for all presses: {:.1} s.\n\n",
                c.presses,
                c.centre_error_px,
                c.max_centre_error_px,
                c.radius_error_px,
                c.radius_bias_px,
                ds.annotations.file(),
                self.prepare_s
            ));
        }
        md.push_str("| sensor model | shape (mm) | far field (mm) | slope error | rim sink (mm) | peak (mm) | fit per fold (s) | ms/frame burn | ms/frame onnxruntime |\n");
        md.push_str("|---|---|---|---|---|---|---|---|---|\n");
        for c in &self.candidates {
            md.push_str(&format!(
                "| {} | {:.3} | {:.4} | {:.3} | {:.3} | {:.3} | {:.0} | {:.2} | {} |\n",
                c.name,
                c.mean.shape_mm,
                c.mean.far_field_mm,
                c.slope_error,
                c.mean.rim_sink_mm,
                c.mean.peak_mm,
                c.fit_s,
                c.burn_ms,
                ms(c.ort_ms)
            ));
        }
        md.push_str(&format!(
            "\nms/frame: median over 640x480 frames of the whole reconstruction (shrink, exposure match, model, Poisson solve, bilinear enlargement), the first fold's model; the lookup table runs in Rust without a runtime.\n\n## Exposure and no contact\n\nThe same held-out presses with every pixel scaled by {:.0} % and {:.0} % (the model keeps the calibration's background; the frame's exposure is matched to it), and the background itself at those exposures and as recorded, with +-2 grey levels of noise (no contact: truth 0 everywhere).\n\n",
            100.0 - e,
            100.0 + e
        ));
        md.push_str(&format!(
            "| sensor model | shape at -{e:.0} % (mm) | far field at -{e:.0} % | shape at +{e:.0} % (mm) | far field at +{e:.0} % | no contact: largest \\|indentation\\| (mm) |\n|---|---|---|---|---|---|\n"
        ));
        for c in &self.candidates {
            md.push_str(&format!(
                "| {} | {:.3} | {:.4} | {:.3} | {:.4} | {:.4} |\n",
                c.name,
                c.darker.shape_mm,
                c.darker.far_field_mm,
                c.brighter.shape_mm,
                c.brighter.far_field_mm,
                c.no_contact_max_mm
            ));
        }
        // Error against speed.
        let mut series: Vec<Series> = vec![];
        for (runtime, pick) in [
            (
                "burn",
                (|c: &CandidateResult| Some(c.burn_ms)) as fn(&CandidateResult) -> Option<f64>,
            ),
            ("onnxruntime", |c: &CandidateResult| c.ort_ms),
        ] {
            series.push(Series {
                name: runtime.into(),
                points: self
                    .candidates
                    .iter()
                    .filter_map(|c| pick(c).map(|m| (m, c.mean.shape_mm)))
                    .collect(),
            });
        }
        line_plot(
            speed_path,
            "Cap-shape error against reconstruction time (640x480)",
            "ms per frame",
            "inside-contact shape error (mm)",
            &series,
            false,
        )?;
        // Profiles of the first held-out press.
        let first = self.candidates.first().and_then(|c| c.presses.first());
        let mut profiles: Vec<Series> = self
            .candidates
            .iter()
            .map(|c| Series {
                name: c.name.clone(),
                points: c.profile.clone(),
            })
            .collect();
        if let Some(p) = first
            && let Some(i) = ds.presses.iter().position(|q| q.file == p.file)
        {
            let (_, prepared) = prepare_presses(&ds, b.base.working_factor(&ds), b.base.circles)?;
            let cap: Cap = prepared[i].cap(&ds);
            let a = cap.circle.radius_px;
            profiles.push(Series {
                name: "ball's cap (truth inside the contact)".into(),
                points: (0..=40)
                    .map(|k| {
                        let r = a * k as f64 / 40.0;
                        (
                            r * cap.mm_per_px,
                            cap.height_mm(cap.circle.centre_x_px + r, cap.circle.centre_y_px)
                                .unwrap_or(0.0),
                        )
                    })
                    .collect(),
            });
            md.push_str(&format!(
                "\n## Profiles\n\nThe first held-out press ({}): the reconstruction's mean over rings about the contact's centre, its rim offset removed, against the ball's cap (known inside the contact; beyond it the gel's own shape).\n\n![profiles]({profile_png})\n",
                p.file
            ));
            line_plot(
                profile_path,
                &format!("Cap profile of {}", p.file),
                "distance from the contact's centre (mm)",
                "height above the rim (mm)",
                &profiles,
                false,
            )?;
        }
        md.push_str(&format!(
            "\n## Error against speed\n\n![speed]({speed_png})\n"
        ));
        crate::output::markdown_and_json(out, &md, self)?;
        Ok(md)
    }
}
