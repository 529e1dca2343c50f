//! The options layer: every trainer's options reach the command line and
//! Python by the same names, with the same defaults, and the Python stubs
//! that type them are the ones the library generates.

use std::path::PathBuf;

use serde_json::{Value, json};
use tactile_burn::options::Options;
use tactile_pipeline::options::{
    CALIBRATORS, EVALUATORS, GENERATORS, STUB_BEGIN, STUB_END, STUDIES, TRAINERS, python_stubs,
    trainer,
};

fn stub(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tactile-py/python/tactile")
        .join(name)
}

/// The generated part of a stub file as it is, and the file with `part`
/// in its place (the placeholder `# generated` or the last generated part).
fn generated_part(text: &str, part: &str) -> (Option<String>, String) {
    match (text.find(STUB_BEGIN), text.find(STUB_END)) {
        (Some(a), Some(b)) => {
            let end = b + STUB_END.len() + 1;
            let end = end.min(text.len());
            (
                Some(text[a..end].to_string()),
                format!("{}{part}{}", &text[..a], &text[end..]),
            )
        }
        _ => (None, text.replacen("# generated\n", part, 1)),
    }
}

#[test]
fn the_python_stubs_type_every_option_as_the_library_defines_it() {
    let stubs = python_stubs().unwrap();
    let bless = std::env::var_os("TACTILE_BLESS").is_some();
    for (file, part) in [
        ("_tactile.pyi", &stubs.native),
        ("train.pyi", &stubs.train),
        ("synth.pyi", &stubs.synth),
        ("eval.pyi", &stubs.eval),
        ("calibrate.pyi", &stubs.calibrate),
        ("study.pyi", &stubs.study),
    ] {
        let path = stub(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let (now, blessed) = generated_part(&text, part);
        if bless {
            std::fs::write(&path, blessed).unwrap();
            continue;
        }
        assert_eq!(
            now.as_deref(),
            Some(part.as_str()),
            "{} is not what the options generate: run TACTILE_BLESS=1 cargo test --release --workspace --test options",
            path.display()
        );
    }
    // The detector's keywords, typed as its flags parse them.
    for want in [
        "input_bits: int = 8",
        "normalise_exposure: bool = False",
        "soft_labels: Optional[float] = None",
        "input: Tuple[int, int] = (",
        "device: str = \"flex\"",
    ] {
        assert!(
            stubs.native.contains(want),
            "{want} not in\n{}",
            stubs.native
        );
    }
    assert!(stubs.train.contains("def pose(\n    data: _Path,\n    out: _Path,\n    *,\n    config: Optional[_Path] = None,\n    targets: Sequence[str] = (\"x_mm\", \"theta_deg\", \"depth_mm\"),"), "{}", stubs.train);
    // The generators' ranges are pairs, their defaults the spec's.
    for want in [
        "press_mm: Tuple[float, float] = (0.0, 4.0)",
        "paths: Sequence[str] = (\"straight\", \"arc\", \"s-curve\")",
        "sequences: Optional[int] = None",
        "blob_probability: float = 0.3",
    ] {
        assert!(stubs.synth.contains(want), "{want} not in\n{}", stubs.synth);
    }
    // What an evaluation writes is a keyword, as it is a flag.
    for want in [
        "def detector(\n    model: _Path,\n    data: _Path,\n    *,\n    runtime: str = \"burn-flex\",\n    config: Optional[_Path] = None,\n    frames: Optional[str] = None,\n    reliability: Optional[str] = None,",
        "png_frames: int = 8",
    ] {
        assert!(stubs.eval.contains(want), "{want} not in\n{}", stubs.eval);
    }
    // A calibration's recipe is keywords, as it is flags.
    for want in [
        "def ball(\n    data: _Path,\n    out: _Path,\n    *,\n    config: Optional[_Path] = None,",
        "kernels: Sequence[int] = (",
        "height_weight: float = ",
        "circles: str = \"auto\"",
    ] {
        assert!(
            stubs.calibrate.contains(want),
            "{want} not in\n{}",
            stubs.calibrate
        );
    }
    // A study's options are keywords after its inputs and `out`, as flags.
    for want in [
        "def compare(\n    encoder: _Path,\n    data: _Path,\n    *,\n    out: Optional[_Path] = None,\n    config: Optional[_Path] = None,\n    targets: Sequence[str] = (),\n    classify: Optional[str] = None,",
        "hidden: Sequence[int] = (256, 128)",
        "def sweep(\n    encoders: Union[_Path, Sequence[_Path]],",
        "heads: Sequence[str] = ()",
    ] {
        assert!(stubs.study.contains(want), "{want} not in\n{}", stubs.study);
    }
}

#[test]
fn every_option_of_every_trainer_is_a_flag_and_a_keyword() {
    assert_eq!(
        TRAINERS.iter().map(|t| t.name).collect::<Vec<_>>(),
        [
            "cae",
            "head",
            "regressor",
            "pose",
            "detector",
            "segmenter",
            "depth"
        ]
    );
    for t in TRAINERS
        .iter()
        .chain(GENERATORS)
        .chain(EVALUATORS)
        .chain(CALIBRATORS)
        .chain(STUDIES)
    {
        let docs = t.docs().unwrap();
        let least = if EVALUATORS.iter().any(|e| e.native == t.native) {
            2
        } else if STUDIES.iter().any(|e| e.native == t.native) {
            3
        } else {
            4
        };
        assert!(docs.len() >= least, "{}: {} options", t.name, docs.len());
        for d in &docs {
            // Every option the stubs and `--help` show is one a keyword
            // sets (the generator's `renderer`, left out of its serialised
            // defaults to keep manifests as they were, was refused as
            // "unknown option").
            let keyword = serde_json::Map::from_iter([(d.name.clone(), d.default.clone())]);
            t.takes(&keyword)
                .unwrap_or_else(|e| panic!("{}: {} = {}: {e}", t.name, d.name, d.default));
            assert!(!d.help.is_empty(), "{}: {} has no help", t.name, d.name);
            assert!(
                !d.name.contains('-') && d.name != "config",
                "{}: {} is no keyword",
                t.name,
                d.name
            );
        }
    }
    assert!(
        trainer("vgg")
            .err()
            .unwrap()
            .to_string()
            .contains("known: cae, head")
    );
}

/// Each option, set from a keyword to a value that is not its default,
/// reaches the config the trainer would use; and the same value given
/// through `--config FILE` does too, a keyword beside it winning.
#[test]
fn keywords_and_config_files_reach_the_training_config() {
    use tactile_pose::PoseOptions;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("p.json");
    std::fs::write(
        &file,
        json!({"input_px": 128, "widths": [16, 32, 32, 64, 64], "hidden": 256, "max_epochs": 60})
            .to_string(),
    )
    .unwrap();
    let overrides = json!({"max_epochs": 45, "loss": "l1", "targets": ["x_mm", "theta_deg:180"]});
    let p = PoseOptions::resolve(Some(&file), overrides.as_object().unwrap()).unwrap();
    let c = p.config().unwrap();
    assert_eq!(c.preprocess.output_px, 128);
    assert_eq!(c.model.input_px, 128);
    assert_eq!(c.model.widths, [16, 32, 32, 64, 64]);
    assert_eq!(c.schedule.max_epochs, 45, "the keyword wins over the file");
    assert_eq!(c.model.outputs, 3, "x and an angle's two columns");
    // The shipped recipe files are options files.
    for name in ["p128", "p64", "p64-wide"] {
        let f = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../configs/pose")
            .join(format!("{name}.json"));
        PoseOptions::resolve(Some(&f), &Default::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .config()
            .unwrap();
    }
    // An unknown option in a file names the file and the option.
    std::fs::write(&file, json!({"input_pix": 128}).to_string()).unwrap();
    let e = PoseOptions::resolve(Some(&file), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.json") && e.contains("unknown option 'input_pix'"),
        "{e}"
    );
    std::fs::write(&file, "[1, 2]").unwrap();
    let e = PoseOptions::resolve(Some(&file), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("JSON object"), "{e}");
    // A bad value from a file names the file and the option.
    std::fs::write(&file, json!({"hidden": "wide"}).to_string()).unwrap();
    let e = PoseOptions::resolve(Some(&file), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("p.json") && e.contains("option 'hidden'"), "{e}");
    // A whole number past 64 bits in a file is said as one, alone or in a
    // list (JSON reads it as a float: "invalid type: floating point").
    for (text, option) in [
        (r#"{"max_epochs": 1180591620717411303424}"#, "max_epochs"),
        (r#"{"widths": [16, 32, 1180591620717411303424]}"#, "widths"),
        (r#"{"hidden": -1e30}"#, "hidden"),
    ] {
        std::fs::write(&file, text).unwrap();
        let e = PoseOptions::resolve(Some(&file), &Default::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("p.json")
                && e.contains(&format!("option '{option}'"))
                && e.ends_with(": a whole number beyond 64 bits")
                && !e.contains("floating point"),
            "{e}"
        );
    }
    // A fraction keeps its own wording.
    std::fs::write(&file, r#"{"max_epochs": 2.5}"#).unwrap();
    let e = PoseOptions::resolve(Some(&file), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("floating point `2.5`"), "{e}");
    // Two bad values: the first is named with its own error, not the
    // other's.
    let two = json!({"max_epochs": "one", "widths": "wide"});
    let e = PoseOptions::resolve(None, two.as_object().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("option 'max_epochs' = \"one\": invalid type: string \"one\""),
        "{e}"
    );
    // A list given as one string reads as the flag reads it: commas
    // separate, numbers stay numbers.
    let csv =
        json!({"targets": "x_mm, theta_deg:180", "widths": "16,32,32,64,64", "input_px": 128});
    let c = PoseOptions::resolve(None, csv.as_object().unwrap())
        .unwrap()
        .config()
        .unwrap();
    assert_eq!(c.model.widths, [16, 32, 32, 64, 64]);
    assert_eq!(
        c.targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>(),
        ["x_mm", "theta_deg"]
    );
    // A file far larger than any options file is refused before it is read.
    let huge = " ".repeat(tactile_burn::options::MAX_OPTIONS_FILE_BYTES as usize + 1);
    std::fs::write(&file, format!("{{{huge}}}")).unwrap();
    let e = PoseOptions::resolve(Some(&file), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("p.json") && e.contains("too large"), "{e}");
    // Every option of every trainer takes its own default as a keyword.
    fn each_default<T: Options>() {
        let defaults = serde_json::to_value(T::defaults().unwrap()).unwrap();
        for (k, v) in defaults.as_object().unwrap() {
            let one: serde_json::Map<String, Value> =
                [(k.clone(), v.clone())].into_iter().collect();
            T::with_overrides(&one).unwrap_or_else(|e| panic!("{k}: {e}"));
        }
    }
    each_default::<tactile_cae::CaeOptions>();
    each_default::<tactile_pipeline::options::HeadOptions>();
    each_default::<tactile_pipeline::options::RegressorOptions>();
    each_default::<PoseOptions>();
    each_default::<tactile_detect::DetectorOptions>();
    each_default::<tactile_segment::SegmenterOptions>();
    each_default::<tactile_depth::DepthOptions>();
    each_default::<tactile_detect::eval::EvalOptions>();
    each_default::<tactile_depth::eval::EvalOptions>();
}
