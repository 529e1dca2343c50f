//! Argument types shared by several verbs.

use std::path::Path;
use std::sync::OnceLock;

use clap::ArgMatches;
use tactile_burn::options::{Options, command_line};

pub(crate) use tactile_burn::options::Size;

/// A study's or bench's own flags (a library type), and the page it may
/// write.
#[derive(clap::Args)]
pub(crate) struct Paged<B: clap::Args> {
    #[command(flatten)]
    pub bench: B,
    /// Also write the table to this Markdown file, with its rows (NAME.json) and plots (NAME.png, NAME-*.png) beside it where it has them.
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
}

/// The parsed command line's innermost subcommand, for [`resolve`].
static LEAF: OnceLock<ArgMatches> = OnceLock::new();

/// Keep the matches of the command line, so [`resolve`] can tell a flag
/// the user gave from one left at its default.
pub(crate) fn keep_matches(mut m: ArgMatches) {
    while let Some((_, sub)) = m.remove_subcommand() {
        m = sub;
    }
    let _ = LEAF.set(m);
}

/// Options of another type `T` made from the flags given on the command
/// line, with `--config FILE` under them
/// ([`tactile_burn::options::command_line::resolve_as`]).
pub(crate) fn resolve_as<P: serde::Serialize, T: Options>(
    parsed: &P,
    config: Option<&Path>,
) -> anyhow::Result<T> {
    Ok(command_line::resolve_as(parsed, config, leaf())?)
}

/// The options a verb parsed, with `--config FILE` under them
/// ([`tactile_burn::options::command_line::resolve`]).
pub(crate) fn resolve<T: Options>(parsed: T, config: Option<&Path>) -> anyhow::Result<T> {
    Ok(command_line::resolve(parsed, config, leaf())?)
}

/// The innermost subcommand's matches, none kept (a unit test) giving none.
fn leaf() -> &'static ArgMatches {
    static NONE: OnceLock<ArgMatches> = OnceLock::new();
    LEAF.get()
        .unwrap_or_else(|| NONE.get_or_init(ArgMatches::default))
}
