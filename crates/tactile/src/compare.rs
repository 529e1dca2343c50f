//! `tactile compare`: feature sets against estimators on one split.

use anyhow::Result;
use tactile_bench::compare::{Compare, CompareResult, compare};
use tactile_bench::output::with_page;

pub(crate) type CompareArgs = crate::args::Paged<Compare>;

pub(crate) fn main(a: CompareArgs) -> Result<()> {
    with_page(
        &a.bench.data,
        a.out.as_deref(),
        || {
            let r = compare(&a.bench)?;
            say_raw!("{}", r.markdown);
            Ok(r)
        },
        CompareResult::write,
    )?;
    Ok(())
}
