//! `tactile sweep`: paper A's feature-count search.

use anyhow::Result;
use tactile_bench::output::with_page;
use tactile_bench::sweep::{Sweep, SweepResult, sweep};

pub(crate) type SweepArgs = crate::args::Paged<Sweep>;

pub(crate) fn main(a: SweepArgs) -> Result<()> {
    with_page(
        &a.bench.data,
        a.out.as_deref(),
        || {
            let r = sweep(&a.bench)?;
            say_raw!("{}", r.markdown);
            Ok(r)
        },
        SweepResult::write,
    )?;
    if let Some(out) = &a.out {
        say!("table and plots written beside {}", out.display());
    }
    Ok(())
}
