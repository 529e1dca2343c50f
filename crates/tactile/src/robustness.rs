//! `tactile robustness`: estimator errors under perturbed camera conditions.

use anyhow::Result;
use tactile_bench::output::with_page;
use tactile_bench::robustness::{Robustness, RobustnessResult, robustness};

pub(crate) type RobustnessArgs = crate::args::Paged<Robustness>;

pub(crate) fn main(a: RobustnessArgs) -> Result<()> {
    with_page(
        &a.bench.data,
        a.out.as_deref(),
        || {
            let r = robustness(&a.bench)?;
            for w in &r.warnings {
                tactile_core::note!("warning: {w}");
            }
            say_raw!("{}", r.markdown);
            Ok(r)
        },
        RobustnessResult::write,
    )?;
    if let Some(out) = &a.out {
        tactile_core::note!("wrote {} and its plot", out.display());
    }
    Ok(())
}
