//! `tactile compare`: feature sets against estimators on one split.

use anyhow::Result;
use tactile_bench::compare::{Compare, compare};

pub(crate) type CompareArgs = crate::args::Paged<Compare>;

pub(crate) fn main(a: CompareArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.bench.data)?;
        tactile_bench::output::check_page(out, &[&ds])?;
    }
    let r = compare(&a.bench)?;
    say_raw!("{}", r.markdown);
    if let Some(out) = &a.out {
        tactile_bench::output::write_markdown_and_json(out, &r.markdown, &r.rows())?;
    }
    Ok(())
}
