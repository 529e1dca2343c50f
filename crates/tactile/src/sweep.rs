//! `tactile sweep`: paper A's feature-count search.

use anyhow::Result;
use tactile_bench::sweep::{Sweep, sweep};

pub(crate) type SweepArgs = crate::args::Paged<Sweep>;

pub(crate) fn main(a: SweepArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.bench.data)?;
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let r = sweep(&a.bench)?;
    say_raw!("{}", r.markdown);
    if let Some(out) = &a.out {
        r.write(out)?;
        say!("table and plots written beside {}", out.display());
    }
    Ok(())
}
