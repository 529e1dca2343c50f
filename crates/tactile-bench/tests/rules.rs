//! The benchmark crate's own rules, without a model: the README's headline
//! block is replaced in place (and a README without its markers is named,
//! not overwritten), and the detector selection rule picks the smallest
//! model that clears the target by a standard error.

use std::path::{Path, PathBuf};

use tactile_bench::models::{Candidate, choose_detector};
use tactile_bench::report::{HEADLINE_BEGIN, HEADLINE_END, replace_headline};

#[test]
fn the_headline_is_replaced_between_its_markers_only() {
    let readme = format!("# Title\nintro\n{HEADLINE_BEGIN}\nold table\n{HEADLINE_END}\nrest\n");
    let out = replace_headline(&readme, "| new |\n", Path::new("README.md")).unwrap();
    assert_eq!(
        out,
        format!("# Title\nintro\n{HEADLINE_BEGIN}\n| new |\n{HEADLINE_END}\nrest\n")
    );
    for bad in [
        "no markers at all\n".to_string(),
        format!("{HEADLINE_END}\nx\n{HEADLINE_BEGIN}\n"),
    ] {
        let e = replace_headline(&bad, "t", Path::new("docs/MY.md"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("docs/MY.md"), "{e}");
    }
}

#[test]
fn the_selection_rule_wants_a_standard_error_of_margin() {
    let c = |name: &str, parameters: usize, accuracy: f64, frames: usize| Candidate {
        parameters,
        input_pixels: 320 * 240,
        folder: PathBuf::from(format!("data/{name}")),
        accuracy,
        frames,
    };
    // 0.992 on 200 frames is within a standard error (0.0063) of 0.99:
    // not enough; 0.999 on 2,000 frames is, and the larger model loses.
    let verdict = choose_detector(&[
        c("tiny", 10_000, 0.992, 200),
        c("small", 50_000, 0.999, 2_000),
        c("large", 900_000, 1.0, 2_000),
    ]);
    assert!(verdict.contains("picks `small`"), "{verdict}");
    let none = choose_detector(&[c("tiny", 10_000, 0.95, 2_000)]);
    assert!(none.contains("No model here meets it"), "{none}");
    assert!(choose_detector(&[]).is_empty());
}
