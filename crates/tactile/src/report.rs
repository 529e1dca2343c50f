//! `tactile report`: regenerate `docs/results.md` and the README headline.

use anyhow::Result;
use tactile_bench::report::{Report, report};

pub(crate) fn main(a: Report) -> Result<()> {
    tactile_bench::output::check_page(&a.out, &[])?;
    report(&a)?;
    if let Some(readme) = &a.readme {
        say!("headline table in {}", readme.display());
    }
    say!("wrote {} and the tables beside it", a.out.display());
    Ok(())
}
