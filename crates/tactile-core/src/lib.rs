//! The burn-free foundation of tactile-rs: the error type, the dataset
//! layout (`datasets.md`) with its checks, splits and import, the sensor
//! contract ([`spec`]), image loading, atomic file writes and staged
//! folders, frame sources (folders, videos, cameras, standard input, ROS 2
//! bags),
//! metrics, plots, progress, interrupts and benchmark helpers. It compiles
//! no tensor library, so the virtual sensors and the preprocessing build
//! in seconds; everything that needs burn lives in `tactile-burn`.

#![deny(missing_docs)]

pub mod bag;
pub mod bench;
pub mod csv_lines;
pub mod dataset;
pub mod error;
pub mod image_io;
pub mod import;
pub mod interrupt;
pub mod io;
pub mod metrics;
pub mod npy;
pub mod plot;
pub mod progress;
pub mod rng;
pub mod source;
pub mod spec;
pub mod stack;
pub mod video;

/// A progress note on stderr. Unlike `eprintln!` it never panics: a note
/// that cannot be written (stderr closed, a full pipe) is dropped. What it
/// quotes of a file is shown [`printable`].
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let _ = writeln!(std::io::stderr(), "{}", $crate::printable(&text));
    }};
}

/// `text` as it is safe to show on a terminal: a control character other
/// than a newline or a tab is written as its escape (`\x1b`, `\x00`,
/// `\x0d`), and so is a mark that reorders the text around it (`\u{202e}`).
/// Messages quote what files hold (a cell of a `labels.csv`, a frame's
/// name); escaped, a hostile one cannot clear the screen, retitle the
/// window, overwrite the line or show its text backwards, and a stray
/// byte is seen instead of hidden.
pub fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    escaped(text, |c| c == '\n' || c == '\t')
}

/// [`printable`] for one cell of a line (a frame's name in a table of
/// tab-separated columns, a label, a topic): a newline or a tab is
/// escaped too, so a name that holds one cannot break the row or shift
/// its columns.
pub fn one_cell(text: &str) -> std::borrow::Cow<'_, str> {
    escaped(text, |_| false)
}

/// `text` with every control character but those `kept` escaped, and
/// every mark that reorders text.
fn escaped(text: &str, kept: impl Fn(char) -> bool) -> std::borrow::Cow<'_, str> {
    // Arabic letter mark, the left-to-right and right-to-left marks, the
    // embeddings and overrides, and the isolates.
    let reorders = |c: char| {
        matches!(
            c,
            '\u{061c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}'
        )
    };
    let hidden = |c: char| (c.is_control() && !kept(c)) || reorders(c);
    if !text.chars().any(hidden) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut shown = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        match c {
            c if !hidden(c) => shown.push(c),
            c if (c as u32) < 0x100 => shown.push_str(&format!("\\x{:02x}", c as u32)),
            c => shown.push_str(&format!("\\u{{{:04x}}}", c as u32)),
        }
    }
    std::borrow::Cow::Owned(shown)
}

pub use error::{Error, Result};

#[cfg(test)]
mod tests {
    use super::{one_cell, printable};

    #[test]
    fn what_a_file_holds_is_printed_escaped_not_obeyed() {
        // Clear the screen, retitle the window, a NUL, a carriage return
        // that would overwrite the line, a C1 control, a right-to-left
        // override.
        let hostile = "a\u{1b}[2J\u{1b}]0;owned\u{7}b\0c\rd\u{9b}e\u{202e}gnp.exe";
        let shown = printable(hostile);
        assert_eq!(
            shown,
            "a\\x1b[2J\\x1b]0;owned\\x07b\\x00c\\x0dd\\x9be\\u{202e}gnp.exe"
        );
        assert!(!shown.chars().any(|c| c.is_control()));
        // Lines, tabs and every other character as they are, not copied.
        let plain = "frames/0001.png\t3.2\nÉté 温度 → ok";
        assert!(matches!(printable(plain), std::borrow::Cow::Borrowed(p) if p == plain));
        // One cell of a row escapes them too.
        assert_eq!(one_cell(plain), "frames/0001.png\\x093.2\\x0aÉté 温度 → ok");
        assert_eq!(one_cell(hostile), shown);
    }
}
