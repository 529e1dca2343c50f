//! `tactile robustness`: estimator errors under perturbed camera conditions.

use anyhow::Result;
use tactile_bench::robustness::{Robustness, robustness};

pub(crate) type RobustnessArgs = crate::args::Paged<Robustness>;

pub(crate) fn main(a: RobustnessArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.bench.data)?;
        tactile_bench::output::check_page(out, &[&ds])?;
    }
    let r = robustness(&a.bench)?;
    say_raw!("{}", r.markdown);
    if let Some(out) = &a.out {
        r.write(out)?;
        tactile_core::note!("wrote {} and its plot", out.display());
    }
    Ok(())
}
