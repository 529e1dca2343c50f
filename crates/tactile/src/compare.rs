//! `tactile compare`: feature sets against estimators on one split.

use anyhow::Result;
use tactile_bench::compare::{Compare, compare};

pub(crate) type CompareArgs = crate::args::Paged<Compare>;

pub(crate) fn main(a: CompareArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.bench.data)?;
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let md = compare(&a.bench)?;
    say_raw!("{md}");
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic(out, md.as_bytes())?;
    }
    Ok(())
}
