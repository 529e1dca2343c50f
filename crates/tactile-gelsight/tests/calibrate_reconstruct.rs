#![allow(clippy::unwrap_used)]
//! The calibration layout's refusals and a calibrate-then-reconstruct
//! round trip on a few of the shared GelSight ball presses
//! (`../shared/real/gelsight-ball`, read in place; subsets are written to
//! temporary folders).

use std::path::{Path, PathBuf};

use tactile_burn::{DeviceKind, Runtime};
use tactile_core::image_io::load_rgb;
use tactile_gelsight::training::{CalibrationConfig, prepare_presses};
use tactile_gelsight::{BallPresses, CircleSource, Error, Reconstructor, calibrate};

fn shared() -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/real/gelsight-ball");
    assert!(p.is_dir(), "{} missing", p.display());
    p
}

/// A calibration folder of the first `n` presses (copied), its CSV edited
/// by `edit`.
fn subset(dir: &Path, n: usize, edit: impl Fn(&str) -> String) {
    let src = shared();
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    for f in ["sensor.json", "background.png"] {
        std::fs::copy(src.join(f), dir.join(f)).unwrap();
    }
    let text = std::fs::read_to_string(src.join("presses.csv")).unwrap();
    let mut lines = text.lines();
    let mut csv = format!("{}\n", lines.next().unwrap());
    for l in lines.take(n) {
        let file = l.split(',').next().unwrap();
        std::fs::copy(src.join(file), dir.join(file)).unwrap();
        csv.push_str(&edit(l));
        csv.push('\n');
    }
    std::fs::write(dir.join("presses.csv"), csv).unwrap();
}

/// The calibration folder `dir` calibrated into `out` in two epochs of a
/// coarse model, two presses held out: enough to see what it says.
fn short_calibration(dir: &Path, out: &Path) -> tactile_gelsight::training::Calibration {
    let ds = BallPresses::open(dir).unwrap();
    let mut cfg = CalibrationConfig::new()
        .with_factor(Some(8))
        .with_val_presses(2);
    cfg.schedule.max_epochs = 2;
    calibrate(&cfg, &ds, out, DeviceKind::Flex).unwrap()
}

/// Set `field` of the folder's `sensor.json` to `value` (JSON text).
fn set_sensor_value(dir: &Path, field: &str, value: &str) {
    let sensor = std::fs::read_to_string(dir.join("sensor.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&sensor).unwrap();
    json[field] = serde_json::from_str(value).unwrap();
    std::fs::write(dir.join("sensor.json"), json.to_string()).unwrap();
}

/// Every picture of the folder `dir` (its background and frames) replaced
/// by `edit` of it.
fn edit_pictures(dir: &Path, edit: impl Fn(image::RgbImage) -> image::RgbImage) {
    let mut files = vec![dir.join("background.png")];
    files.extend(
        std::fs::read_dir(dir.join("frames"))
            .unwrap()
            .map(|e| e.unwrap().path()),
    );
    for f in files {
        edit(image::open(&f).unwrap().to_rgb8()).save(&f).unwrap();
    }
}

/// The circles the toolkit finds in the presses of `dir`, against their
/// annotations.
fn found_against_annotated(dir: &Path) -> tactile_gelsight::eval::CircleAgreement {
    let ds = BallPresses::open(dir).unwrap();
    let (_, presses) = prepare_presses(&ds, 4, CircleSource::Found)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    tactile_gelsight::eval::CircleAgreement::of(&presses).unwrap()
}

#[test]
fn the_circle_finder_agrees_with_the_annotations() {
    let c = found_against_annotated(&shared());
    assert_eq!(c.presses, 32);
    assert!(
        c.centre_error_px < 3.0 && c.radius_error_px < 4.0,
        "{}",
        c.describe()
    );
}

#[test]
fn the_circle_finder_finds_every_press_at_any_frame_size() {
    // A researcher's sensor may give 320x240 frames (a DIGIT, a GelSight
    // Mini as streamed) or 1280x960. The shared R1.5's 32 presses scaled
    // to those sizes, the scale and the annotations with them: every
    // circle is found as well as at 640x480 (centre within 3 px on
    // average and 7 px at most, radius within 4 px, in 640x480 pixels).
    // Before, the finder kept its first guess (the changed region's area,
    // half as wide again as the contact) whenever a third of its rays
    // disagreed with their median from a start off the centre: at 240x180
    // and 320x240 presses 1 and 11, and at 1280x960 press 32, came out
    // wider than the ball, so the calibration was refused without
    // annotations.
    let tmp = tempfile::tempdir().unwrap();
    for (w, h) in [(240u32, 180u32), (320, 240), (1280, 960)] {
        let s = f64::from(w) / 640.0;
        let d = tmp.path().join(format!("{w}x{h}"));
        subset(&d, 32, |line| {
            let cells: Vec<&str> = line.split(',').collect();
            let v = |i: usize| cells[i].parse::<f64>().unwrap();
            // Pixel centres scale about the frame's corner.
            let at = |i: usize| (v(i) + 0.5) * s - 0.5;
            format!("{},{:.2},{:.2},{:.2}", cells[0], at(1), at(2), v(3) * s)
        });
        set_sensor_value(&d, "mm_per_px", &(0.0295 / s).to_string());
        edit_pictures(&d, |rgb| {
            image::imageops::resize(&rgb, w, h, image::imageops::FilterType::Triangle)
        });
        let c = found_against_annotated(&d);
        assert_eq!(c.presses, 32);
        assert!(
            c.centre_error_px / s < 3.0
                && c.max_centre_error_px / s < 7.0
                && c.radius_error_px / s < 4.0,
            "{w}x{h}: {}",
            c.describe()
        );
    }
    // A found circle wider than the ball (here: a scale mistyped three
    // times too coarse, no annotations) is refused saying what to check,
    // its numbers to a tenth of a pixel.
    let d = tmp.path().join("320x240");
    std::fs::remove_file(d.join("presses.csv")).unwrap();
    set_sensor_value(&d, "mm_per_px", "0.177");
    let ds = BallPresses::open(&d).unwrap();
    let e = prepare_presses(&ds, 4, CircleSource::Auto)
        .err()
        .unwrap()
        .to_string();
    // The radius said, as "contact radius 30.4 px".
    let radius = e
        .split("contact radius ")
        .nth(1)
        .and_then(|r| r.split(" px").next())
        .unwrap_or("");
    assert!(
        e.contains("frames/press_01.png: the contact circle found in it: ")
            && radius.parse::<f64>().is_ok()
            && radius.split('.').nth(1).is_some_and(|f| f.len() == 1)
            && e.contains("is not smaller than the ball's radius 11.3 px")
            && e.contains("give the press's circle in presses.csv")
            && e.contains("check ball_diameter_mm and mm_per_px in sensor.json"),
        "{e}"
    );
}

#[test]
fn a_sensor_of_another_scale_works_on_the_r15s_working_pixel() {
    use tactile_gelsight::training::factor_for_scale;
    // The recipe was chosen on the R1.5 at 4 frame pixels (0.118 mm) per
    // working pixel. A camera of three times the resolution calibrated at
    // 4 took 20 s an epoch (16 min) for the same held-out shape errors as
    // at 12; a GelSight Mini at 320x240 (0.0634 mm per pixel) calibrated
    // at 4 works on 0.25 mm. Each now gets the R1.5's working pixel.
    assert_eq!(factor_for_scale(0.0295, (640, 480)), 4);
    assert_eq!(factor_for_scale(0.0634, (320, 240)), 2);
    assert_eq!(factor_for_scale(0.0295 / 3.0, (1920, 1440)), 12);
    assert_eq!(factor_for_scale(0.5, (640, 480)), 1);
    // Within the grid's limits: 16 at most, 16 working pixels across.
    assert_eq!(factor_for_scale(1e-4, (7680, 4320)), 16);
    assert_eq!(factor_for_scale(0.001, (200, 150)), 9);
    // The R1.5's presses at twice the resolution, calibrated with the
    // defaults: a grid of 160x120 as at 640x480.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("1280x960");
    subset(&d, 6, |line| {
        let cells: Vec<&str> = line.split(',').collect();
        let v = |i: usize| cells[i].parse::<f64>().unwrap();
        let at = |i: usize| (v(i) + 0.5) * 2.0 - 0.5;
        format!("{},{:.2},{:.2},{:.2}", cells[0], at(1), at(2), v(3) * 2.0)
    });
    set_sensor_value(&d, "mm_per_px", "0.01475");
    edit_pictures(&d, |rgb| {
        image::imageops::resize(&rgb, 1280, 960, image::imageops::FilterType::Triangle)
    });
    let ds = BallPresses::open(&d).unwrap();
    let mut cfg = CalibrationConfig::new().with_val_presses(2);
    cfg.schedule.max_epochs = 1;
    let cal = calibrate(&cfg, &ds, &tmp.path().join("m"), DeviceKind::Flex).unwrap();
    let g = cal.working_grid;
    assert_eq!((g.factor, g.width(), g.height()), (8, 160, 120));
    assert!((cal.working_pixel_mm - 0.118).abs() < 1e-9);
    let record = std::fs::read_to_string(tmp.path().join("m/training.json")).unwrap();
    assert!(record.contains("\"factor\": 8"), "{record}");
    let line = cal.describe(&tmp.path().join("m")).join("\n");
    assert!(
        line.contains("working grid 160x120: 8 frame pixels, 0.118 mm of skin, per working pixel"),
        "{line}"
    );
    // --factor still sets it.
    let cal = calibrate(
        &cfg.clone().with_factor(Some(16)),
        &ds,
        &tmp.path().join("m16"),
        DeviceKind::Flex,
    )
    .unwrap();
    assert_eq!(cal.working_grid.width(), 80);
}

/// Printed markers on a gel, as dark dots.
#[derive(Clone, Copy)]
struct Markers {
    /// Each dot's radius, pixels.
    radius_px: f64,
    /// The grid's pitch, pixels.
    pitch_px: usize,
}

/// `markers` over `rgb`, each pushed out from the contact `(cx, cy, r)`
/// by the skin's stretch (up to 2.5 px at the contact's rim; none without
/// a contact).
fn with_markers(rgb: &mut image::RgbImage, contact: Option<(f64, f64, f64)>, markers: Markers) {
    let (w, h) = (rgb.width() as f64, rgb.height() as f64);
    let (dot, reach) = (markers.radius_px, markers.radius_px + 1.0);
    for gy in (12..h as u32).step_by(markers.pitch_px) {
        for gx in (12..w as u32).step_by(markers.pitch_px) {
            let (mut x, mut y) = (f64::from(gx), f64::from(gy));
            if let Some((cx, cy, r)) = contact {
                let d = (x - cx).hypot(y - cy);
                if d > 1e-6 && d < 2.5 * r {
                    let stretch = 2.5 * (-((d - r) / r).powi(2)).exp();
                    (x, y) = (x + (x - cx) / d * stretch, y + (y - cy) / d * stretch);
                }
            }
            for py in (y - reach).max(0.0) as u32..((y + reach + 1.0).min(h) as u32) {
                for px in (x - reach).max(0.0) as u32..((x + reach + 1.0).min(w) as u32) {
                    if (f64::from(px) - x).hypot(f64::from(py) - y) <= dot {
                        let p = rgb.get_pixel_mut(px, py);
                        p.0 = p.0.map(|v| v / 4);
                    }
                }
            }
        }
    }
}

#[test]
fn the_circle_finder_finds_presses_on_a_gel_with_markers() {
    // Many GelSight-like gels carry printed markers that move with the
    // skin. The shared presses with a grid of such dots, pushed out around
    // each contact: the circles are found as on the bare gel. Before, each
    // moved dot's strong change drew the threshold's region and the rays
    // off the contact: press 1 was found 76 px in radius, wider than the
    // ball's 68, so a calibration without annotations was refused. Dots of
    // 3 px every 28 px, and of 8 px every 37 (0.5 mm dots 1.1 mm apart at
    // the R1.5's 0.0295 mm per pixel, wider than the finder's median).
    for markers in [
        Markers {
            radius_px: 3.0,
            pitch_px: 28,
        },
        Markers {
            radius_px: 8.0,
            pitch_px: 37,
        },
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path().join("markers");
        subset(&d, 32, str::to_string);
        let ds = BallPresses::open(&d).unwrap();
        let mut bg = image::open(d.join("background.png")).unwrap().to_rgb8();
        with_markers(&mut bg, None, markers);
        bg.save(d.join("background.png")).unwrap();
        for p in &ds.presses {
            let a = p.annotated.unwrap();
            let f = d.join(&p.file);
            let mut rgb = image::open(&f).unwrap().to_rgb8();
            let contact = (a.centre_x_px, a.centre_y_px, a.radius_px);
            with_markers(&mut rgb, Some(contact), markers);
            rgb.save(&f).unwrap();
        }
        let c = found_against_annotated(&d);
        assert!(
            c.centre_error_px < 3.5 && c.max_centre_error_px < 8.0 && c.radius_error_px < 4.5,
            "dots of {} px: {}",
            markers.radius_px,
            c.describe()
        );
    }
}

#[test]
fn an_annotation_far_from_the_contact_found_is_named() {
    // A mistyped line of presses.csv: press 2's column and row swapped
    // (300, 169 given as 169, 300), press 5's radius missing a digit (6
    // for 61). Each is still a circle on the frame, so the calibration
    // fits the sensor model to balls that were not there; the finder,
    // which lands within 0.13 of a radius of every annotation measured,
    // names them. Before, nothing was said.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("presses");
    subset(&d, 6, |line| match line.split(',').next() {
        Some("frames/press_02.png") => "frames/press_02.png,169,300,61".into(),
        Some("frames/press_05.png") => line.replace(",61", ",6"),
        _ => line.to_string(),
    });
    let csv = std::fs::read_to_string(d.join("presses.csv")).unwrap();
    assert!(csv.contains("frames/press_05.png,356,360,6\n"), "{csv}");
    let cal = short_calibration(&d, &tmp.path().join("model"));
    let w = cal.warnings.join("\n");
    assert!(
        w.contains("the annotated contact circles of 2 of the 6 presses lie far from the contacts the toolkit finds")
            && w.contains("(the first: frames/press_02.png, annotated at (169.0, 300.0) of radius 61.0 px, found at (299.7, 168.4) of radius 58.3 px)")
            && w.contains("centre_x_px is the column"),
        "{w}"
    );
}

/// A NumPy `.npz` archive as `numpy.savez` (stored) or
/// `savez_compressed` (deflated) writes it: one `.npy` per array.
fn write_label_npz(path: &Path, centre: [f64; 2], radius: i64, method: zip::CompressionMethod) {
    use ndarray_npy::WriteNpyExt;
    let mut z = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
    let opts = zip::write::SimpleFileOptions::default().compression_method(method);
    z.start_file("center.npy", opts).unwrap();
    ndarray::arr1(&centre).write_npy(&mut z).unwrap();
    z.start_file("radius.npy", opts).unwrap();
    ndarray::arr0(radius).write_npy(&mut z).unwrap();
    z.finish().unwrap();
}

/// The first `n` shared presses as gs_sdk's calibration folder holds
/// them: `catalog.csv`, `4.000mm/<i>/gelsight.png` and its `label.npz`
/// (the annotated circle), `background.png`, and a `sensor.json` giving
/// only the scale (gs_sdk keeps it in the sensor's config).
fn gs_sdk_folder(dir: &Path, n: usize) {
    let src = shared();
    std::fs::create_dir_all(dir).unwrap();
    std::fs::copy(src.join("background.png"), dir.join("background.png")).unwrap();
    std::fs::write(dir.join("sensor.json"), r#"{"mm_per_px": 0.0295}"#).unwrap();
    let text = std::fs::read_to_string(src.join("presses.csv")).unwrap();
    let mut catalog = String::from("experiment_reldir,diameter(mm)\n");
    for (i, l) in text.lines().skip(1).take(n).enumerate() {
        let v: Vec<&str> = l.split(',').collect();
        let press = dir.join(format!("4.000mm/{i}"));
        std::fs::create_dir_all(&press).unwrap();
        std::fs::copy(src.join(v[0]), press.join("gelsight.png")).unwrap();
        let method = match i % 2 {
            0 => zip::CompressionMethod::Stored,
            _ => zip::CompressionMethod::Deflated,
        };
        let (x, y, r) = (
            v[1].parse().unwrap(),
            v[2].parse().unwrap(),
            v[3].parse().unwrap(),
        );
        write_label_npz(&press.join("label.npz"), [x, y], r, method);
        catalog.push_str(&format!("4.000mm/{i},4.000\n"));
    }
    std::fs::write(dir.join("catalog.csv"), catalog).unwrap();
}

#[test]
fn a_gs_sdk_calibration_folder_calibrates_as_it_is() {
    // A researcher who collected and labelled presses with gs_sdk (or the
    // Taxim code it rewrites) has catalog.csv, a folder per press and its
    // label.npz. Before, the toolkit asked for frames/ and presses.csv and
    // every press had to be retyped by hand.
    let tmp = tempfile::tempdir().unwrap();
    let (gs, ours) = (tmp.path().join("gs"), tmp.path().join("ours"));
    gs_sdk_folder(&gs, 6);
    subset(&ours, 6, str::to_string);
    let (a, b) = (
        BallPresses::open(&gs).unwrap(),
        BallPresses::open(&ours).unwrap(),
    );
    assert_eq!(a.sensor.ball_diameter_mm, 4.0, "the ball from catalog.csv");
    assert_eq!(
        a.annotations,
        tactile_gelsight::layout::Annotations::LabelNpz
    );
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    let files: Vec<_> = a.presses.iter().map(|p| p.file.as_str()).collect();
    assert_eq!(
        files[..2],
        ["4.000mm/0/gelsight.png", "4.000mm/1/gelsight.png"]
    );
    let circles = |ds: &BallPresses| {
        ds.presses
            .iter()
            .map(|p| p.annotated.unwrap())
            .collect::<Vec<_>>()
    };
    assert_eq!(circles(&a), circles(&b), "stored and deflated labels");
    // circles.png captions each press by its folder: every frame is
    // gelsight.png.
    assert_eq!(
        (a.press_name(1), b.press_name(1)),
        ("4.000mm/1".to_string(), "press_02.png".to_string())
    );
    // A label saved before its circle was moved onto the contact is named
    // with gs_sdk's own mend.
    write_label_npz(
        &gs.join("4.000mm/1/label.npz"),
        [160.0, 120.0],
        40,
        zip::CompressionMethod::Stored,
    );
    let cal = short_calibration(&gs, &tmp.path().join("model"));
    assert_eq!((cal.train_presses, cal.val_presses), (4, 2));
    let w = cal.warnings.join("\n");
    assert!(
        w.contains("label.npz: the annotated contact circles of 1 of the 6 presses")
            && w.contains("(the first: 4.000mm/1/gelsight.png, annotated at (160.0, 120.0)")
            && w.contains("Label the press again"),
        "{w}"
    );
}

/// gs_sdk's config for the shared R1.5 presses, as gs_sdk writes its own
/// (`examples/configs/gsmini.yaml`), with `edit` applied.
fn gs_sdk_config(edit: impl Fn(&str) -> String) -> String {
    edit(
        "# Device Name\n\
         device_name: \"GelSight R1.5\"\n\
         # Pixel Per Millimeter\n\
         ppmm: 0.0295\n\
         # Desired Image Width and Height\n\
         imgh: 480\n\
         imgw: 640\n\
         # Raw image width, height, and framerate\n\
         raw_imgh: 2464\n\
         raw_imgw: 3280\n\
         framerate: 25\n",
    )
}

#[test]
fn a_gs_sdk_config_copied_in_gives_the_scale() {
    // gs_sdk keeps the scale in the sensor's YAML config, which each of
    // its scripts is given. Before, the researcher wrote sensor.json by
    // hand from it; now the config copied beside catalog.csv gives it.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("gs");
    gs_sdk_folder(&d, 3);
    std::fs::remove_file(d.join("sensor.json")).unwrap();
    let write = |file: &str, text: &str| std::fs::write(d.join(file), text).unwrap();
    let open = || BallPresses::open(&d).map(|_| ()).unwrap_err().to_string();
    write("gsmini.yaml", &gs_sdk_config(str::to_string));
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(
        (ds.sensor.mm_per_px, ds.sensor.ball_diameter_mm),
        (0.0295, 4.0),
        "the scale from the config, the ball from catalog.csv"
    );
    assert_eq!(ds.sensor.sensor, "GelSight R1.5");
    assert!(ds.warnings.is_empty(), "{:?}", ds.warnings);
    // The camera's frames cut as gs_sdk's resize_crop cuts them.
    let cut = ds.gs_sdk_config.as_ref().unwrap().camera_cut().unwrap();
    assert_eq!(
        (cut.camera, cut.crop, cut.size),
        ((3280, 2464), (2344, 1758, 468, 354), (640, 480))
    );
    // The same presses as with sensor.json.
    let with_json = tmp.path().join("json");
    gs_sdk_folder(&with_json, 3);
    let b = BallPresses::open(&with_json).unwrap();
    assert_eq!(ds.presses.len(), b.presses.len());
    assert!(ds.frame(2).unwrap().as_slice() == b.frame(2).unwrap().as_slice());
    // Messages that ask to check the scale name the config, not a
    // sensor.json there is none of (an unlabelled press whose ball is
    // mistyped: its circle is found wider than the ball).
    let catalog = std::fs::read_to_string(d.join("catalog.csv")).unwrap();
    write(
        "catalog.csv",
        &catalog.replace("4.000mm/2,4.000", "4.000mm/2,0.500"),
    );
    let label = d.join("4.000mm/2/label.npz");
    let kept = std::fs::read(&label).unwrap();
    std::fs::remove_file(&label).unwrap();
    let e = prepare_presses(&BallPresses::open(&d).unwrap(), 8, CircleSource::Auto)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("check catalog.csv's diameter(mm) and gsmini.yaml's ppmm"),
        "{e}"
    );
    write("catalog.csv", &catalog);
    std::fs::write(&label, kept).unwrap();
    // A config of another frame size: its ppmm is not these frames' scale.
    write(
        "gsmini.yaml",
        &gs_sdk_config(|t| t.replace("480", "240").replace("640", "320")),
    );
    let e = open();
    assert!(
        e.contains("background.png: 640x480, but gsmini.yaml's ppmm 0.0295 is the scale of frames of 320x240")
            && e.contains("{\"mm_per_px\": 0.01475}"),
        "{e}"
    );
    // What is wrong in a config, by its line.
    for (edit, said) in [
        (
            ("ppmm: 0.0295", "ppmm: 33.9"),
            "line 4: ppmm = 33.9 is not a scale of 0.0001-1 mm per pixel (gs_sdk's ppmm is millimetres per pixel",
        ),
        (
            ("ppmm: 0.0295", "ppmm: \"0.0295\""),
            "line 4: ppmm is the text \"0.0295\", not a number",
        ),
        (
            ("ppmm: 0.0295", "ppmm: [0.0295]"),
            "line 4: ppmm is a list or keys, not a number",
        ),
        (("imgh: 480\n", ""), "line 6: gives imgw without imgh"),
        (
            ("imgw: 640", "imgw: 640.5"),
            "line 7: imgw = 640.5 is no frame side of 1-8192 pixels",
        ),
        (
            ("framerate: 25", "ppmm: 0.03"),
            "line 11: key ppmm a second time (first on line 4)",
        ),
        (("imgw: 640", "imgw: [640"), "is not YAML"),
    ] {
        write(
            "gsmini.yaml",
            &gs_sdk_config(|t| t.replacen(edit.0, edit.1, 1)),
        );
        let e = open();
        assert!(
            e.contains("gsmini.yaml") && e.contains(said),
            "{edit:?}: {e}"
        );
    }
    // Aliases are refused: a few hundred bytes of them would stand for
    // gigabytes where a document loader copies each.
    let mut laughs = String::from("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n");
    for i in 1..12u8 {
        let (p, q) = ((b'a' + i - 1) as char, (b'a' + i) as char);
        laughs.push_str(&format!(
            "{q}: &{q} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
        ));
    }
    write("gsmini.yaml", &format!("ppmm: 0.0295\n{laughs}"));
    let e = open();
    assert!(e.contains("gsmini.yaml: line 3: uses a YAML alias"), "{e}");
    // A config too large for one is refused before it is parsed.
    write(
        "gsmini.yaml",
        &format!("ppmm: 0.0295\nnote: \"{}\"\n", "x".repeat(70_000)),
    );
    let e = open();
    assert!(
        e.contains("gsmini.yaml: 70022 bytes is too large (at most 65536)"),
        "{e}"
    );
    // A YAML file that cannot be read beside the config is left alone.
    write("gsmini.yaml", &gs_sdk_config(str::to_string));
    write("notes.yaml", "# to do\n");
    write("broken.yml", "a: [1\n");
    assert_eq!(BallPresses::open(&d).unwrap().sensor.mm_per_px, 0.0295);
    std::fs::remove_file(d.join("notes.yaml")).unwrap();
    std::fs::remove_file(d.join("broken.yml")).unwrap();
    // Two sensors' configs: which made the presses is not known.
    write("gsmini.yaml", &gs_sdk_config(str::to_string));
    write(
        "digit.yaml",
        "device_name: \"DIGIT\"\nppmm: 0.0655\nimgh: 240\nimgw: 320\n",
    );
    let e = open();
    assert!(
        e.contains("holds 2 gs_sdk configs (digit.yaml, gsmini.yaml)"),
        "{e}"
    );
    // A folder of many YAML files is not read through.
    for i in 0..40 {
        write(&format!("notes-{i:02}.yml"), "shading: true\n");
    }
    let e = open();
    assert!(
        e.contains("holds 42 YAML files, more than the 32 looked through"),
        "{e}"
    );
    for i in 0..40 {
        std::fs::remove_file(d.join(format!("notes-{i:02}.yml"))).unwrap();
    }
    // YAML that is no config is named where the scale is missing.
    std::fs::remove_file(d.join("gsmini.yaml")).unwrap();
    write("digit.yaml", "shading: true\n");
    let e = open();
    assert!(
        e.contains("sensor.json: missing")
            && e.contains("copy that config here")
            && e.contains("(digit.yaml here has no ppmm)"),
        "{e}"
    );
    std::fs::remove_file(d.join("digit.yaml")).unwrap();
    // A config linked from outside the folder is not read.
    #[cfg(unix)]
    {
        let outside = tmp.path().join("gsmini.yaml");
        std::fs::write(&outside, gs_sdk_config(str::to_string)).unwrap();
        std::os::unix::fs::symlink(&outside, d.join("gsmini.yaml")).unwrap();
        let e = open();
        assert!(e.contains("sensor.json: missing"), "{e}");
        std::fs::remove_file(d.join("gsmini.yaml")).unwrap();
    }
    // Beside sensor.json, the config is a check: a scale unlike it is
    // named, sensor.json's used.
    write("gsmini.yaml", &gs_sdk_config(str::to_string));
    write("sensor.json", r#"{"mm_per_px": 0.031}"#);
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(ds.sensor.mm_per_px, 0.031);
    let w = ds.warnings.join("\n");
    assert!(
        w.contains("sensor.json's mm_per_px 0.031 is not the scale gs_sdk's config")
            && w.contains("(0.02950 mm per pixel)"),
        "{w}"
    );
    // ... and agreeing, or the config of the frames at another size, none.
    write("sensor.json", r#"{"mm_per_px": 0.0295}"#);
    assert!(BallPresses::open(&d).unwrap().warnings.is_empty());
    write(
        "gsmini.yaml",
        &gs_sdk_config(|t| {
            t.replace("480", "240")
                .replace("640", "320")
                .replace("0.0295", "0.059")
        }),
    );
    assert!(BallPresses::open(&d).unwrap().warnings.is_empty());
}

#[test]
fn a_gs_sdk_folder_names_what_it_cannot_read() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("gs");
    gs_sdk_folder(&d, 3);
    let open = || BallPresses::open(&d).map(|_| ()).unwrap_err().to_string();
    let write = |file: &str, text: &str| std::fs::write(d.join(file), text).unwrap();
    // No scale: gs_sdk keeps it in the sensor's config.
    std::fs::remove_file(d.join("sensor.json")).unwrap();
    let e = open();
    assert!(
        e.contains("sensor.json: missing") && e.contains("ppmm"),
        "{e}"
    );
    write("sensor.json", r#"{"mm_per_px": 0.0295}"#);
    // Presses of two balls: each press is fitted with its own, unless
    // sensor.json chooses one.
    let catalog = std::fs::read_to_string(d.join("catalog.csv")).unwrap();
    std::fs::create_dir_all(d.join("6.000mm/0")).unwrap();
    std::fs::copy(
        d.join("4.000mm/0/gelsight.png"),
        d.join("6.000mm/0/gelsight.png"),
    )
    .unwrap();
    write("catalog.csv", &format!("{catalog}6.000mm/0,6.000\n"));
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(ds.presses.len(), 4);
    assert_eq!((ds.ball_diameter_mm(0), ds.ball_diameter_mm(3)), (4.0, 6.0));
    assert_eq!(ds.describe_balls(), "balls of 4, 6 mm");
    write(
        "sensor.json",
        r#"{"mm_per_px": 0.0295, "ball_diameter_mm": 4}"#,
    );
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(ds.presses.len(), 3);
    assert!(
        ds.warnings.len() == 1
            && ds.warnings[0].contains("other balls are left out (6.000 mm: 1 press)"),
        "{:?}",
        ds.warnings
    );
    write(
        "sensor.json",
        r#"{"mm_per_px": 0.0295, "ball_diameter_mm": 5}"#,
    );
    let e = open();
    assert!(e.contains("lists no press of a 5 mm ball"), "{e}");
    write("sensor.json", r#"{"mm_per_px": 0.0295}"#);
    write("catalog.csv", &catalog);
    // A press folder the catalog does not list is named.
    std::fs::create_dir_all(d.join("4.000mm/7")).unwrap();
    std::fs::copy(
        d.join("4.000mm/0/gelsight.png"),
        d.join("4.000mm/7/gelsight.png"),
    )
    .unwrap();
    let w = BallPresses::open(&d).unwrap().warnings.join("\n");
    assert!(
        w.contains("1 press folders hold a gelsight.png and are not listed")
            && w.contains("4.000mm/7"),
        "{w}"
    );
    // Rows naming no press, or a folder outside, by their line.
    for (row, said) in [
        (
            "4.000mm/9,4.000",
            "line 5: press folder '4.000mm/9' has no gelsight.png",
        ),
        (
            "../elsewhere,4.000",
            "line 5: '../elsewhere/gelsight.png' is not a path inside",
        ),
        (
            "4.000mm/0,4.000",
            "line 5: press folder '4.000mm/0' is listed already on line 2",
        ),
        (
            "4.000mm/7,four",
            "line 5: 'four' in diameter(mm) is not a number",
        ),
    ] {
        write("catalog.csv", &format!("{catalog}{row}\n"));
        let e = open();
        assert!(e.contains("catalog.csv") && e.contains(said), "{row}: {e}");
    }
    write("catalog.csv", "file,centre_x_px\n");
    let e = open();
    assert!(e.contains("not gs_sdk's ball catalog"), "{e}");
    write("catalog.csv", &catalog);
    // Labels that are no circle, each named by its file.
    let label = d.join("4.000mm/2/label.npz");
    std::fs::write(&label, "center,radius\n300,220,60\n").unwrap();
    let e = open();
    assert!(
        e.contains("4.000mm/2/label.npz") && e.contains("not a NumPy .npz archive"),
        "{e}"
    );
    {
        use ndarray_npy::WriteNpyExt;
        let mut z = zip::ZipWriter::new(std::fs::File::create(&label).unwrap());
        let opts = zip::write::SimpleFileOptions::default();
        z.start_file("center.npy", opts).unwrap();
        ndarray::arr1(&[300.0f32, 220.0]).write_npy(&mut z).unwrap();
        z.start_file("radius.npy", opts).unwrap();
        ndarray::arr1(&[60i32, 61, 62]).write_npy(&mut z).unwrap();
        z.finish().unwrap();
    }
    let e = open();
    assert!(
        e.contains("label.npz: its 'radius': holds 3 numbers (shape [3]), not 1"),
        "{e}"
    );
    write_label_npz(&label, [300.0, 220.0], 90, zip::CompressionMethod::Stored);
    let e = open();
    assert!(
        e.contains(
            "4.000mm/2/label.npz: contact radius 90.0 px is not smaller than the ball's radius"
        ),
        "{e}"
    );
    // A press left unlabelled has its circle found.
    std::fs::remove_file(&label).unwrap();
    let ds = BallPresses::open(&d).unwrap();
    assert!(ds.presses[2].annotated.is_none() && ds.presses[1].annotated.is_some());
    // Its ball mistyped (0.5 mm for 4): the circle found is wider than the
    // ball, and the message names where its diameter is written.
    write(
        "catalog.csv",
        &catalog.replace("4.000mm/2,4.000", "4.000mm/2,0.500"),
    );
    let ds = BallPresses::open(&d).unwrap();
    let e = prepare_presses(&ds, 8, CircleSource::Auto)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("4.000mm/2/gelsight.png: the contact circle found in it")
            && e.contains("label the press's circle with gs_sdk's label_data.py")
            && e.contains("check catalog.csv's diameter(mm) and sensor.json's mm_per_px"),
        "{e}"
    );
}

/// One array of a pack: its `.npy` bytes.
struct Npy(Vec<u8>);

/// A pack's arrays by name, in the order written.
type PackArrays = Vec<(&'static str, Npy)>;

/// A change to a pack's arrays.
type PackEdit = Box<dyn FnOnce(&mut PackArrays)>;

/// The `.npy` bytes of `a`.
fn npy<A: ndarray_npy::WritableElement, D: ndarray::Dimension>(a: ndarray::Array<A, D>) -> Npy {
    use ndarray_npy::WriteNpyExt;
    let mut bytes = Vec::new();
    a.write_npy(&mut bytes).unwrap();
    Npy(bytes)
}

/// The `.npy` bytes of `texts` as NumPy keeps a list of `str` (`<U`,
/// UTF-32), which `ndarray-npy` does not write.
fn npy_strings(texts: &[&str]) -> Npy {
    let width = texts
        .iter()
        .map(|t| t.chars().count())
        .max()
        .unwrap_or(1)
        .max(1);
    let dict = format!(
        "{{'descr': '<U{width}', 'fortran_order': False, 'shape': ({},), }}",
        texts.len()
    );
    let mut header = dict.into_bytes();
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(b' ');
    }
    header.push(b'\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(&header);
    for t in texts {
        let mut chars: Vec<u32> = t.chars().map(u32::from).collect();
        chars.resize(width, 0);
        chars
            .iter()
            .for_each(|c| bytes.extend_from_slice(&c.to_le_bytes()));
    }
    Npy(bytes)
}

/// A `.npz` archive of `arrays` at `path`, as `numpy.savez` (stored) or
/// `savez_compressed` writes it.
fn write_npz(path: &Path, arrays: Vec<(&str, Npy)>, method: zip::CompressionMethod) {
    use std::io::Write;
    let mut z = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(method)
        .large_file(true);
    for (name, Npy(bytes)) in arrays {
        z.start_file(format!("{name}.npy"), opts).unwrap();
        z.write_all(&bytes).unwrap();
    }
    z.finish().unwrap();
}

/// `img` as an `H x W x 3` array in OpenCV's order (BGR).
fn bgr_array(img: &tactile_core::image_io::RgbImage) -> ndarray::Array3<u8> {
    let (w, h) = (img.width(), img.height());
    let mut a = ndarray::Array3::from_shape_vec((h, w, 3), img.as_slice().to_vec()).unwrap();
    a.lanes_mut(ndarray::Axis(2))
        .into_iter()
        .for_each(|mut px| px.swap(0, 2));
    a
}

/// The first `n` shared presses as Taxim's `generateDataPack.py` saves
/// them: `dataPack.npz` holding `f0` and `imgs` (BGR, as OpenCV read
/// them), `touch_center` ([x, y]) and `touch_radius` as its labelling tool
/// leaves them, the frames' `names` and `img_size`; and a `sensor.json`
/// giving what Taxim keeps in `sensorParams.py`. `edit` changes the
/// arrays before they are written.
fn taxim_folder(dir: &Path, n: usize, edit: impl FnOnce(&mut PackArrays)) {
    let src = shared();
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(
        dir.join("sensor.json"),
        r#"{"ball_diameter_mm": 4.0, "mm_per_px": 0.0295}"#,
    )
    .unwrap();
    let bg = load_rgb(src.join("background.png")).unwrap();
    let text = std::fs::read_to_string(src.join("presses.csv")).unwrap();
    let rows: Vec<Vec<String>> = (text.lines().skip(1).take(n))
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let (h, w) = (bg.height(), bg.width());
    let mut imgs = ndarray::Array4::<u8>::zeros((n, h, w, 3));
    for (i, r) in rows.iter().enumerate() {
        let frame = load_rgb(src.join(&r[0])).unwrap();
        imgs.index_axis_mut(ndarray::Axis(0), i)
            .assign(&bgr_array(&frame));
    }
    let centres: Vec<f64> = (rows.iter())
        .flat_map(|r| [r[1].parse().unwrap(), r[2].parse().unwrap()])
        .collect();
    let radii: Vec<i64> = rows.iter().map(|r| r[3].parse().unwrap()).collect();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r[0].trim_start_matches("frames/"))
        .collect();
    let mut arrays = vec![
        ("f0", npy(bgr_array(&bg))),
        ("imgs", npy(imgs)),
        (
            "touch_center",
            npy(ndarray::Array2::from_shape_vec((n, 2), centres).unwrap()),
        ),
        ("touch_radius", npy(ndarray::Array1::from(radii))),
        ("names", npy_strings(&names)),
        ("img_size", npy(ndarray::arr1(&[h as i64, w as i64, 3]))),
    ];
    edit(&mut arrays);
    write_npz(
        &dir.join("dataPack.npz"),
        arrays,
        zip::CompressionMethod::Stored,
    );
}

#[test]
fn a_taxim_data_pack_calibrates_as_it_is() {
    // A researcher who labelled presses with Taxim (or a tool built on it)
    // has one dataPack.npz: the background, the presses and their circles.
    // Before, the toolkit asked for sensor.json, background.png, frames/
    // and presses.csv, and the folder was refused ("sensor.json: missing",
    // then "frames/: missing").
    let tmp = tempfile::tempdir().unwrap();
    let (taxim, ours) = (tmp.path().join("taxim"), tmp.path().join("ours"));
    taxim_folder(&taxim, 6, |_| {});
    subset(&ours, 6, str::to_string);
    let (a, b) = (
        BallPresses::open(&taxim).unwrap(),
        BallPresses::open(&ours).unwrap(),
    );
    assert_eq!(
        a.annotations,
        tactile_gelsight::layout::Annotations::DataPack
    );
    assert_eq!(
        (a.sensor.ball_diameter_mm, a.sensor.mm_per_px),
        (4.0, 0.0295)
    );
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    assert_eq!(a.presses[1].file, "dataPack.npz:press_02.png");
    assert_eq!(a.press_name(1), "press_02.png");
    // The same pixels, in the same order (the pack's BGR turned to RGB),
    // and the same circles.
    assert_eq!(a.background.as_slice(), b.background.as_slice());
    for i in 0..6 {
        assert_eq!(
            a.frame(i).unwrap().as_slice(),
            b.frame(i).unwrap().as_slice()
        );
        assert_eq!(a.presses[i].annotated, b.presses[i].annotated);
    }
    // The pack itself may be given, under any name (Taxim's repository
    // ships dataPack_small.npz), with sensor.json beside it.
    std::fs::rename(taxim.join("dataPack.npz"), taxim.join("dataPack_small.npz")).unwrap();
    let c = BallPresses::open(taxim.join("dataPack_small.npz")).unwrap();
    assert_eq!(c.presses.len(), 6);
    assert_eq!(
        c.press_path(0),
        taxim.join("dataPack_small.npz:press_01.png")
    );
    std::fs::rename(taxim.join("dataPack_small.npz"), taxim.join("dataPack.npz")).unwrap();
    // It calibrates, and the model keeps the pack's background as a PNG
    // of the same pixels.
    let model = tmp.path().join("model");
    let cal = short_calibration(&taxim, &model);
    assert_eq!((cal.train_presses, cal.val_presses), (4, 2));
    let kept = load_rgb(model.join("background.png")).unwrap();
    assert_eq!(kept.as_slice(), b.background.as_slice());
    assert!(
        cal.validation
            .iter()
            .all(|v| v.file.starts_with("dataPack.npz:press_")),
        "{:?}",
        cal.validation.iter().map(|v| &v.file).collect::<Vec<_>>()
    );
    let mut rec = Reconstructor::load(&model, Runtime::BurnNdarray, 0).unwrap();
    let map = rec
        .reconstruct(&b.frame(0).unwrap(), &ours.join("x.png"))
        .unwrap();
    assert!(map.indentation_m.iter().any(|v| *v > 1e-4));
}

#[test]
fn a_taxim_packs_presses_are_reconstructed_as_their_files_are() {
    // A Taxim user's presses are only in the pack: `tactile reconstruct`
    // takes it (the file, or its folder) as it takes a folder of frames,
    // each press's map named by its frame (press_01.npy), or by its place
    // in the pack where it has no names.
    use tactile_gelsight::reconstruct::{ReconstructOptions, reconstruct_folder};
    let tmp = tempfile::tempdir().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/gelsight-r15");
    let (taxim, ours) = (tmp.path().join("taxim"), tmp.path().join("ours"));
    taxim_folder(&taxim, 3, |_| {});
    subset(&ours, 3, str::to_string);
    let o = ReconstructOptions {
        background: None,
        render: None,
        runtime: Runtime::BurnFlex,
    };
    let run = |data: &Path, out: &str| {
        let out = tmp.path().join(out);
        reconstruct_folder(&model, data, &out, &o, None).unwrap();
        out
    };
    let files = run(&ours.join("frames"), "files");
    for pack in [
        run(&taxim.join("dataPack.npz"), "pack"),
        run(&taxim, "folder"),
    ] {
        for name in ["press_01.npy", "press_02.npy", "press_04.npy"] {
            assert_eq!(
                std::fs::read(pack.join(name)).unwrap(),
                std::fs::read(files.join(name)).unwrap(),
                "{name}"
            );
        }
    }
    let plain = tmp.path().join("plain");
    taxim_folder(&plain, 2, |a| a.retain(|(n, _)| *n != "names"));
    let out = run(&plain.join("dataPack.npz"), "plain-out");
    assert!(out.join("dataPack-000001.npy").is_file());
    // A pack of another sensor's size is refused, naming its first press.
    let small = tmp.path().join("small");
    taxim_folder(&small, 2, |a| {
        a[0].1 = npy(ndarray::Array3::<u8>::from_elem((240, 320, 3), 90));
        a[1].1 = npy(ndarray::Array4::<u8>::from_elem((2, 240, 320, 3), 90));
    });
    let e = reconstruct_folder(&model, &small, &tmp.path().join("s"), &o, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("small/dataPack.npz:press_01.png: frame is (320, 240)"),
        "{e}"
    );
}

#[test]
fn a_damaged_pack_or_label_is_read_or_refused_naming_it_never_a_panic() {
    // Seeded damage where the archives' structure is (zip headers, the
    // central directory, each .npy header), and anywhere: each read gives
    // presses or an error naming the file.
    use tactile_core::rng::SampleRng;
    let tmp = tempfile::tempdir().unwrap();
    let (taxim, gs) = (tmp.path().join("taxim"), tmp.path().join("gs"));
    taxim_folder(&taxim, 2, |_| {});
    gs_sdk_folder(&gs, 2);
    let pack = taxim.join("dataPack.npz");
    let label = gs.join("4.000mm/1/label.npz");
    let runs: u64 = std::env::var("TACTILE_FUZZ_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150);
    for (file, name) in [(&pack, "dataPack.npz"), (&label, "label.npz")] {
        let clean = std::fs::read(file).unwrap();
        // Where the structure is: 96 bytes after each signature.
        let marks: Vec<usize> = (0..clean.len().saturating_sub(4))
            .filter(|&i| {
                [&b"PK\x03\x04"[..], b"PK\x01\x02", b"PK\x05\x06", b"\x93NUM"]
                    .contains(&&clean[i..i + 4])
            })
            .collect();
        let (mut read, mut refused) = (0, 0);
        for k in 0..runs {
            let mut rng = SampleRng::new(23, 0, k);
            let mut bytes = clean.clone();
            for _ in 0..1 + rng.index(4) {
                if bytes.len() < 2 {
                    break;
                }
                let at = match rng.chance(0.8) {
                    true => (marks[rng.index(marks.len())] + rng.index(96)).min(bytes.len() - 1),
                    false => rng.index(bytes.len()),
                };
                match rng.index(5) {
                    0 => bytes[at] ^= 1 << rng.index(8),
                    1 => bytes[at] = [0, 0xff, b'9', b'(', b','][rng.index(5)],
                    2 => {
                        bytes.remove(at);
                    }
                    3 => bytes.insert(at, rng.index(256) as u8),
                    _ => bytes.truncate(at.max(1)),
                }
            }
            std::fs::write(file, &bytes).unwrap();
            let outcome = BallPresses::open(if name == "label.npz" { &gs } else { &pack })
                .and_then(|ds| (0..ds.presses.len()).try_for_each(|i| ds.frame(i).map(|_| ())))
                .and_then(|()| match name {
                    "dataPack.npz" => tactile_gelsight::taxim::read_frames(&pack).map(|_| ()),
                    _ => Ok(()),
                });
            match outcome {
                Ok(()) => read += 1,
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.contains(name), "run {k}: {e}");
                    refused += 1;
                }
            }
        }
        std::fs::write(file, &clean).unwrap();
        assert!(refused > runs / 2, "{name}: {read} read, {refused} refused");
    }
}

#[test]
fn a_taxim_pack_names_what_it_cannot_read() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("taxim");
    let open = |d: &Path| BallPresses::open(d).map(|_| ()).unwrap_err().to_string();
    // No ball or scale: Taxim keeps them in its code.
    taxim_folder(&d, 3, |_| {});
    std::fs::remove_file(d.join("sensor.json")).unwrap();
    let e = open(&d);
    assert!(
        e.contains("sensor.json: missing") && e.contains("sensorParams.py") && e.contains("pixmm"),
        "{e}"
    );
    // A background named beside the pack's own.
    std::fs::write(
        d.join("sensor.json"),
        r#"{"ball_diameter_mm": 4.0, "mm_per_px": 0.0295, "background": "bg.png"}"#,
    )
    .unwrap();
    let e = open(&d);
    assert!(
        e.contains("names a background, but dataPack.npz holds its own (f0)"),
        "{e}"
    );
    // A pack under another name, its folder given: read as a folder, it
    // is not, and the message says how to give it.
    let other = tmp.path().join("other");
    taxim_folder(&other, 3, |_| {});
    std::fs::rename(other.join("dataPack.npz"), other.join("dataPack_small.npz")).unwrap();
    let e = open(&other);
    assert!(
        e.contains(
            "if dataPack_small.npz here is Taxim's calibration pack, give it itself (--data"
        ) && e.contains("other/dataPack_small.npz)"),
        "{e}"
    );
    // Each refusal names the pack and the array.
    let cases: Vec<(&str, PackEdit)> = vec![
        (
            "its 'f0': missing: Taxim's generateDataPack.py saves the background",
            Box::new(|a| a.retain(|(n, _)| *n != "f0")),
        ),
        (
            "its 'imgs': its dtype is '<f4', not uint8",
            Box::new(|a| a[1].1 = npy(ndarray::Array4::<f32>::zeros((3, 480, 640, 3)))),
        ),
        (
            "its 'imgs': frames of 320x240, the background (f0) is 640x480",
            Box::new(|a| a[1].1 = npy(ndarray::Array4::<u8>::zeros((3, 240, 320, 3)))),
        ),
        (
            "its 'imgs': has shape [3, 480, 640], not N x height x width x 3",
            Box::new(|a| a[1].1 = npy(ndarray::Array3::<u8>::zeros((3, 480, 640)))),
        ),
        (
            "its 'touch_radius': holds 2 numbers (shape [2]), not 3",
            Box::new(|a| a[3].1 = npy(ndarray::arr1(&[60i64, 61]))),
        ),
        (
            "holds one of touch_center and touch_radius without the other",
            Box::new(|a| a.retain(|(n, _)| *n != "touch_radius")),
        ),
        (
            // Taxim's labelling tool starts every circle at radius 75: one
            // saved unmoved is wider than a 4 mm ball at 0.0295 mm/px.
            "press 1 (press_02.png): its touch_center and touch_radius: contact radius 75.0 px is not smaller than the ball's radius 67.8 px",
            Box::new(|a| a[3].1 = npy(ndarray::arr1(&[63i64, 75, 61]))),
        ),
        (
            // Some tools built on Taxim save [row, column].
            "press 0 (press_01.png): its touch_center and touch_radius: contact circle at (220.0, 560.0) radius 63.0 px: its centre is off the 640x480 frame (saved as [row, column]? Taxim's touch_center is [x, y])",
            Box::new(|a| {
                let c = [220.0, 560.0, 300.0, 169.0, 256.0, 332.0];
                a[2].1 = npy(ndarray::Array2::from_shape_vec((3, 2), c.to_vec()).unwrap());
            }),
        ),
    ];
    std::fs::write(
        d.join("sensor.json"),
        r#"{"ball_diameter_mm": 4.0, "mm_per_px": 0.0295}"#,
    )
    .unwrap();
    for (k, (want, edit)) in cases.into_iter().enumerate() {
        let d = tmp.path().join(format!("case{k}"));
        taxim_folder(&d, 3, edit);
        let e = open(&d);
        assert!(
            e.contains("dataPack.npz: ") && e.contains(want),
            "{want}\n{e}"
        );
    }
    // A pack damaged on disk: a pixel flipped in a stored press.
    let d = tmp.path().join("damaged");
    taxim_folder(&d, 3, |_| {});
    let mut bytes = std::fs::read(d.join("dataPack.npz")).unwrap();
    let at = bytes.len() / 2;
    bytes[at] ^= 0x40;
    std::fs::write(d.join("dataPack.npz"), bytes).unwrap();
    let e = open(&d);
    assert!(
        e.contains("dataPack.npz: its 'imgs': is damaged")
            && e.contains("do not match the archive's checksum"),
        "{e}"
    );
    // Without names, presses are named by their place in the pack; without
    // circles, each is found; a pack saying its colours are RGB is read so.
    let d = tmp.path().join("plain");
    taxim_folder(&d, 3, |a| {
        a.retain(|(n, _)| !matches!(*n, "names" | "touch_center" | "touch_radius"));
        a.push(("color_order", npy_strings(&["RGB"])));
    });
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(ds.press_name(2), "#2");
    assert!(ds.presses.iter().all(|p| p.annotated.is_none()));
    let rgb = load_rgb(shared().join("background.png")).unwrap();
    let swapped: Vec<u8> = (rgb.as_slice().chunks_exact(3))
        .flat_map(|p| [p[2], p[1], p[0]])
        .collect();
    assert_eq!(ds.background.as_slice(), &swapped[..]);
}

#[test]
fn a_scale_far_out_of_range_is_named_in_a_few_characters() {
    // A sensor.json value far out of range is refused in the form it was
    // written. Before, "ball_diameter_mm = 1000…000 is no ball" printed
    // all 309 digits of 1e308.
    let tmp = tempfile::tempdir().unwrap();
    for (field, value, want) in [
        (
            "ball_diameter_mm",
            "1e308",
            "ball_diameter_mm = 1e308 is no ball of 0.1-100 mm",
        ),
        (
            "mm_per_px",
            "1e-30",
            "mm_per_px = 1e-30 is not a scale of 0.0001-1 mm per pixel",
        ),
        ("mm_per_px", "2.5", "mm_per_px = 2.5 is not a scale"),
    ] {
        let d = tmp.path().join(format!("{field}-{value}"));
        subset(&d, 3, str::to_string);
        set_sensor_value(&d, field, value);
        let e = BallPresses::open(&d).unwrap_err().to_string();
        assert!(e.contains(want) && e.len() < 300, "{e}");
    }
}

#[test]
fn a_calibration_folder_saved_by_windows_tools_opens() {
    // sensor.json and presses.csv written by hand in Notepad or Excel
    // ("CSV UTF-8"): a UTF-8 byte order mark first, CRLF line ends.
    // Before, "sensor.json: not a sensor description: expected value at
    // line 1 column 1".
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("windows");
    subset(&d, 3, str::to_string);
    for f in ["sensor.json", "presses.csv"] {
        let text = std::fs::read_to_string(d.join(f)).unwrap();
        let text = format!("\u{feff}{}", text.replace('\n', "\r\n"));
        std::fs::write(d.join(f), text).unwrap();
    }
    let windows = BallPresses::open(&d).unwrap();
    let plain_dir = tmp.path().join("plain");
    subset(&plain_dir, 3, str::to_string);
    let plain = BallPresses::open(&plain_dir).unwrap();
    assert_eq!(windows.sensor, plain.sensor);
    assert_eq!(
        format!("{:?}", windows.presses),
        format!("{:?}", plain.presses)
    );
    assert_eq!(windows.presses.len(), 3);
    // sensor.json saved as UTF-16 (Notepad's "UTF-16 LE"): refused,
    // saying how to save it.
    let sensor = std::fs::read_to_string(plain_dir.join("sensor.json")).unwrap();
    let utf16: Vec<u8> = [0xfeff_u16]
        .into_iter()
        .chain(sensor.encode_utf16())
        .flat_map(u16::to_le_bytes)
        .collect();
    std::fs::write(plain_dir.join("sensor.json"), utf16).unwrap();
    let e = BallPresses::open(&plain_dir).unwrap_err().to_string();
    assert!(
        e.contains("sensor.json: is not UTF-8 text (it is UTF-16 text"),
        "{e}"
    );
    // Its frames named with backslashes (`os.path.join` on Windows): the
    // error says how to write them.
    let csv = std::fs::read_to_string(d.join("presses.csv")).unwrap();
    std::fs::write(d.join("presses.csv"), csv.replace("frames/", "frames\\")).unwrap();
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(
        e.contains("does not exist (a backslash is no folder separator here: write 'frames/"),
        "{e}"
    );
}

#[test]
fn the_layout_refuses_what_it_cannot_calibrate_from_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    // No folder, and a file where the folder should be, told apart.
    let e = BallPresses::open(tmp.path().join("nowhere")).unwrap_err();
    assert!(
        e.to_string().contains("calibration folder does not exist"),
        "{e}"
    );
    let file = tmp.path().join("presses.csv");
    std::fs::write(&file, "file\n").unwrap();
    let e = BallPresses::open(&file).unwrap_err().to_string();
    assert!(
        e.contains("presses.csv: not a calibration folder (a file)"),
        "{e}"
    );
    // A missing background.
    let d = tmp.path().join("nobg");
    subset(&d, 2, str::to_string);
    std::fs::remove_file(d.join("background.png")).unwrap();
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(e.contains("background.png") && e.contains("missing"), "{e}");
    // Annotated circles that cannot be a ball's contact, each named by
    // its line of presses.csv (where it is mended) and its frame: centred
    // off the frame, wider than the ball (radius 2 mm = 67.8 px), too small, and
    // not a finite number.
    for (name, edit, why) in [
        (
            "off",
            (",299,220,", ",650,220,"),
            "its centre is off the 640x480 frame",
        ),
        ("wide", (",63", ",70"), "ball's radius"),
        ("small", (",63", ",1"), "no contact"),
        ("inf", (",63", ",inf"), "not a finite number"),
        ("nan", (",299,", ",NaN,"), "not a finite number"),
        // Far out of range: said as written, not in 301 digits.
        (
            "huge",
            (",63", ",1e300"),
            "contact radius 1e300 px is not smaller than the ball's radius 67.8 px",
        ),
        (
            "tiny",
            (",63", ",-1e300"),
            "contact radius -1e300 px is no contact",
        ),
    ] {
        let d = tmp.path().join(name);
        subset(&d, 2, |l| l.replace(edit.0, edit.1));
        let e = BallPresses::open(&d).unwrap_err().to_string();
        assert!(
            e.contains("presses.csv")
                && e.contains("line 2")
                && e.contains("press_01.png")
                && e.contains(why),
            "{name}: {e}"
        );
    }
    // A press listed twice (as `frames/…` and `./frames/…`): named by both
    // its lines. Before, it was fitted twice, and could be held out too.
    let d = tmp.path().join("twice");
    subset(&d, 2, |l| {
        l.replace(
            "frames/press_02.png,300,169,61",
            "frames/press_02.png,300,169,61\n./frames/press_01.png,299,220,63",
        )
    });
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(
        e.contains("presses.csv")
            && e.contains("line 4")
            && e.contains("press_01.png")
            && e.contains("listed already on line 2"),
        "{e}"
    );
    // Written as `./frames/…` alone, it is read (before, it was "not a
    // path inside the calibration folder").
    let d = tmp.path().join("dot");
    subset(&d, 2, |l| {
        l.replace("frames/press_01.png", "./frames/press_01.png")
    });
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(ds.presses.len(), 2);
    assert_eq!(ds.frame(0).unwrap().width(), 640);
    // Every frame listed (`./frames/…` too): no warning. A press added to
    // frames/ without its row is no press: named, not silently left out.
    assert!(ds.warnings.is_empty(), "{:?}", ds.warnings);
    std::fs::copy(d.join("frames/press_02.png"), d.join("frames/press_09.png")).unwrap();
    let ds = BallPresses::open(&d).unwrap();
    assert_eq!(ds.presses.len(), 2);
    assert!(
        ds.warnings.len() == 1
            && ds.warnings[0].contains("1 of its 3 frames are not listed in presses.csv")
            && ds.warnings[0].contains("(press_09.png)"),
        "{:?}",
        ds.warnings
    );
    // A frame of another size.
    let d = tmp.path().join("size");
    subset(&d, 2, str::to_string);
    tactile_core::image_io::save_rgb_png(
        d.join("frames/press_02.png"),
        320,
        240,
        &vec![90u8; 320 * 240 * 3],
    )
    .unwrap();
    let ds = BallPresses::open(&d).unwrap();
    let e = ds.frame(1).err().unwrap().to_string();
    assert!(e.contains("press_02.png") && e.contains("640, 480"), "{e}");
    // A press saved grey against the colour background: its colours are
    // what the sensor is calibrated from, so it is named, not fitted.
    let d = tmp.path().join("grey");
    subset(&d, 2, str::to_string);
    save_grey_copy(&d.join("frames/press_02.png"));
    let ds = BallPresses::open(&d).unwrap();
    assert!(ds.frame(0).is_ok());
    let e = ds.frame(1).err().unwrap();
    assert!(matches!(e, Error::GreyFrame { .. }), "{e}");
    assert!(e.is_frame_refusal(), "{e}");
    assert!(e.to_string().contains("press_02.png"), "{e}");
    // The background saved grey beside colour presses: the presses are
    // named, not fitted against the wrong rest (before, it calibrated,
    // its circles found 62 px off on average).
    let d = tmp.path().join("grey-background");
    subset(&d, 2, str::to_string);
    save_grey_copy(&d.join("background.png"));
    let ds = BallPresses::open(&d).unwrap();
    let e = ds.frame(0).err().unwrap();
    assert!(matches!(e, Error::ColourFrame { .. }), "{e}");
    assert!(e.is_frame_refusal(), "{e}");
    let e = e.to_string();
    assert!(
        e.contains("press_01.png") && e.contains("the sensor's background is grey"),
        "{e}"
    );
    // A blank background (the light off, the lens covered) or a blank
    // press is named as blank, not as grey or another sensor's colour
    // (before, the presses were refused as "a colour frame ... the
    // sensor's background is grey", and a black press as greyscale).
    let d = tmp.path().join("blank");
    subset(&d, 2, str::to_string);
    let black = vec![0u8; 640 * 480 * 3];
    tactile_core::image_io::save_rgb_png(d.join("background.png"), 640, 480, &black).unwrap();
    let e = BallPresses::open(&d).err().unwrap();
    assert!(matches!(e, Error::BlankFrame { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("background.png: a blank frame (every pixel of one colour, RGB (0, 0, 0))"),
        "{e}"
    );
    subset(&d, 2, str::to_string);
    let white = vec![255u8; 640 * 480 * 3];
    tactile_core::image_io::save_rgb_png(d.join("frames/press_02.png"), 640, 480, &white).unwrap();
    let ds = BallPresses::open(&d).unwrap();
    assert!(ds.frame(0).is_ok());
    let e = ds.frame(1).err().unwrap();
    assert!(
        matches!(e, Error::BlankFrame { .. }) && e.is_frame_refusal(),
        "{e}"
    );
    assert!(e.to_string().contains("press_02.png: a blank frame"), "{e}");
    // A press saved in BGR order beside the background in RGB is named,
    // not fitted as a skin mirrored.
    let d = tmp.path().join("bgr");
    subset(&d, 2, str::to_string);
    let press = d.join("frames/press_02.png");
    save_bgr_copy(&press, &press);
    let ds = BallPresses::open(&d).unwrap();
    assert!(ds.frame(0).is_ok());
    let e = ds.frame(1).err().unwrap();
    assert!(matches!(e, Error::SwappedChannels { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("press_02.png: red and blue look swapped"),
        "{e}"
    );
    // Too few presses: refused before anything is written.
    let d = tmp.path().join("few");
    subset(&d, 3, str::to_string);
    let ds = BallPresses::open(&d).unwrap();
    let out = tmp.path().join("model");
    let e = calibrate(&CalibrationConfig::new(), &ds, &out, DeviceKind::Flex).unwrap_err();
    assert!(matches!(e, Error::TooFewPresses { count: 3, .. }), "{e}");
    assert!(!out.exists());
    // Nor can they be cross-validated in 8 folds (the bench's default):
    // said in presses and folds, before any press is prepared. Before,
    // "folds must be 2-3, got 8".
    let e = tactile_gelsight::bench::check_folds(8, ds.presses.len(), &ds.root).unwrap_err();
    assert!(
        e.to_string()
            .ends_with("few: a cross-validation of 8 folds (a press per fold) needs at least 8"),
        "{e}"
    );
    assert!(tactile_gelsight::bench::check_folds(3, ds.presses.len(), &ds.root).is_ok());
    assert!(tactile_gelsight::bench::check_folds(1, ds.presses.len(), &ds.root).is_err());
    // A path out of the folder in the CSV.
    let d = tmp.path().join("escape");
    subset(&d, 1, |l| {
        l.replace("frames/press_01.png", "../escape/frames/press_01.png")
    });
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(e.contains("presses.csv") && e.contains("line 2"), "{e}");
    // The same on the third line of a file with CRLF endings (Python's csv
    // module, spreadsheets) after a blank line: the physical line is named.
    let d = tmp.path().join("escape-crlf");
    subset(&d, 2, |l| {
        l.replace("frames/press_02.png", "\n../escape/frames/press_02.png")
    });
    let csv = std::fs::read_to_string(d.join("presses.csv")).unwrap();
    std::fs::write(d.join("presses.csv"), csv.replace('\n', "\r\n")).unwrap();
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(e.contains("presses.csv") && e.contains("line 4"), "{e}");
    // A frame that is a link out of the folder, named in the CSV or found
    // in frames/: refused by its name, not read.
    let d = tmp.path().join("link");
    subset(&d, 1, str::to_string);
    let press = d.join("frames/press_01.png");
    std::fs::remove_file(&press).unwrap();
    std::os::unix::fs::symlink(shared().join("frames/press_01.png"), &press).unwrap();
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(
        e.contains("presses.csv") && e.contains("line 2") && e.contains("leaves"),
        "{e}"
    );
    std::fs::remove_file(d.join("presses.csv")).unwrap();
    let e = BallPresses::open(&d).unwrap_err().to_string();
    assert!(e.contains("press_01.png") && e.contains("leaves"), "{e}");
}

#[test]
fn a_folder_without_presses_csv_reads_png_and_jpeg_presses_and_names_the_rest() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("listed");
    subset(&d, 2, str::to_string);
    std::fs::remove_file(d.join("presses.csv")).unwrap();
    // The second press saved as JPEG, as some recorders do.
    let png = d.join("frames/press_02.png");
    image::open(&png)
        .unwrap()
        .to_rgb8()
        .save(d.join("frames/press_02.jpg"))
        .unwrap();
    std::fs::remove_file(&png).unwrap();
    std::fs::write(d.join("frames/notes.txt"), "pressed at 2 N").unwrap();
    std::fs::create_dir(d.join("frames/old")).unwrap();
    let ds = BallPresses::open(&d).unwrap();
    let files: Vec<_> = ds.presses.iter().map(|p| p.file.as_str()).collect();
    assert_eq!(files, ["frames/press_01.png", "frames/press_02.jpg"]);
    assert_eq!(ds.frame(1).unwrap().width(), 640);
    assert_eq!(ds.warnings.len(), 1, "{:?}", ds.warnings);
    let w = &ds.warnings[0];
    assert!(
        w.contains("2 file(s)") && w.contains("notes.txt") && w.contains("old"),
        "{w}"
    );
    // A folder of frames only warns of nothing.
    std::fs::remove_file(d.join("frames/notes.txt")).unwrap();
    std::fs::remove_dir(d.join("frames/old")).unwrap();
    assert!(BallPresses::open(&d).unwrap().warnings.is_empty());
}

/// A scale or ball mistyped tenfold (0.00295 for 0.0295 mm per pixel, a
/// 40 mm ball for 4) makes every press a cap a few hundredths of a
/// millimetre deep. The calibration runs (a large ball pressed shallow
/// is such a cap too), and says that its render model barely explains
/// the presses, naming sensor.json and the two values. Before, it failed
/// after fitting, with "gel: no spread reaches the presses' contact radii".
#[test]
fn a_scale_mistyped_tenfold_is_named_after_calibrating() {
    let tmp = tempfile::tempdir().unwrap();
    for (field, value, said) in [
        (
            "mm_per_px",
            "0.00295",
            "(a 4 mm ball, 0.00295 mm per pixel)",
        ),
        (
            "ball_diameter_mm",
            "40",
            "(a 40 mm ball, 0.0295 mm per pixel)",
        ),
    ] {
        let d = tmp.path().join(field);
        subset(&d, 6, str::to_string);
        set_sensor_value(&d, field, value);
        let cal = short_calibration(&d, &tmp.path().join(format!("{field}-model")));
        let r = &cal.render;
        assert!(
            r.colour_error_levels > 0.7 * r.colour_error_unpressed_levels,
            "{r:?}"
        );
        let w = cal.warnings.join("\n");
        assert!(
            w.contains("sensor.json: the presses rendered back from this calibration")
                && w.contains("its render model barely explains them")
                && w.contains(said)
                && w.contains("check ball_diameter_mm and mm_per_px"),
            "{w}"
        );
    }
    // A gs_sdk folder: the balls are catalog.csv's, and the warning says so.
    let d = tmp.path().join("gs");
    gs_sdk_folder(&d, 6);
    std::fs::write(d.join("sensor.json"), r#"{"mm_per_px": 0.00295}"#).unwrap();
    let w = short_calibration(&d, &tmp.path().join("gs-model"))
        .warnings
        .join("\n");
    assert!(
        w.contains("as sensor.json and catalog.csv give them (a 4 mm ball, 0.00295 mm per pixel)")
            && w.contains("check catalog.csv's diameter(mm) and sensor.json's mm_per_px"),
        "{w}"
    );
}

/// Presses near the frame's edge: the first six presses with every frame
/// (and the background) cropped to its columns from 250 on, so presses 1,
/// 2 and 4 (centres at columns 49, 50 and 6, radii 61-63 px) run off the
/// left edge. Their annotated circles are read and calibrate; before, the
/// folder was refused ("not inside the 390x480 frame"). Found, not
/// annotated, such circles are named in a warning.
#[test]
fn presses_near_the_edge_calibrate_and_found_circles_there_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("cropped");
    subset(&d, 6, |line| {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        cells[1] = (cells[1].parse::<i32>().unwrap() - 250).to_string();
        cells.join(",")
    });
    edit_pictures(&d, |rgb| {
        image::imageops::crop_imm(&rgb, 250, 0, 390, 480).to_image()
    });
    let cal = short_calibration(&d, &tmp.path().join("annotated"));
    assert!(cal.warnings.is_empty(), "{:?}", cal.warnings);
    // The finder takes no ray the edge cuts for the contact's edge: press
    // 4, its centre 6 px from the edge, is found 6.8 px from its
    // annotation (before, 37 px; whole presses stay under 6 px).
    let found = found_against_annotated(&d);
    assert!(found.max_centre_error_px < 10.0, "{}", found.describe());
    std::fs::remove_file(d.join("presses.csv")).unwrap();
    let cal = short_calibration(&d, &tmp.path().join("found"));
    let w = cal.warnings.join("\n");
    assert!(
        w.contains("of the 6 presses run off the frame's edge, and their contact circles were found, not annotated (the first: frames/press_01.png")
            && w.contains("give their circles in presses.csv"),
        "{w}"
    );
}

/// Six real presses of the R1.5's 4 mm ball and four of a 6 mm ball that
/// the shipped R1.5 calibration's render model renders (contact radius 60
/// px, as the real ones), in `presses.csv` with a `ball_diameter_mm`
/// column: 6 for the rendered presses, or `rendered_as` where given.
fn two_ball_folder(dir: &Path, rendered_as: Option<&str>) {
    use tactile_gelsight::render_model::{BallPress, render_presses};
    subset(dir, 6, |l| format!("{l},"));
    let csv = std::fs::read_to_string(dir.join("presses.csv")).unwrap();
    let mut csv = csv.replacen("contact_radius_px", "contact_radius_px,ball_diameter_mm", 1);
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/gelsight-r15");
    let unit = datasets_synth::calibrated::CalibratedSensor::load(&models).unwrap();
    let background = load_rgb(dir.join("background.png")).unwrap();
    let pressed: Vec<BallPress> = [
        (220.0, 190.0),
        (420.0, 190.0),
        (220.0, 300.0),
        (420.0, 300.0),
    ]
    .iter()
    .map(|&(x, y)| BallPress {
        circle: tactile_gelsight::Circle {
            centre_x_px: x,
            centre_y_px: y,
            radius_px: 60.0,
        },
        ball_mm: 3.0,
    })
    .collect();
    for (k, (p, rgb)) in pressed
        .iter()
        .zip(render_presses(&unit.model, &background, &pressed))
        .enumerate()
    {
        let file = format!("frames/ball6_{k}.png");
        image::RgbImage::from_raw(640, 480, rgb.unwrap())
            .unwrap()
            .save(dir.join(&file))
            .unwrap();
        let c = p.circle;
        csv.push_str(&format!(
            "{file},{},{},{},{}\n",
            c.centre_x_px,
            c.centre_y_px,
            c.radius_px,
            rendered_as.unwrap_or("6")
        ));
    }
    std::fs::write(dir.join("presses.csv"), csv).unwrap();
}

#[test]
fn presses_of_several_balls_are_each_fitted_with_their_own() {
    // gs_sdk has a researcher press balls of several sizes into one
    // catalog. A press of a 6 mm ball touching 1.8 mm wide is a cap 0.6 mm
    // deep; taken for the 4 mm ball, 1.1 mm. Each press is now fitted with
    // its own ball; before, one ball was assumed for all of them.
    let tmp = tempfile::tempdir().unwrap();
    let (both, one) = (tmp.path().join("both"), tmp.path().join("one"));
    two_ball_folder(&both, None);
    two_ball_folder(&one, Some(""));
    let ds = BallPresses::open(&both).unwrap();
    assert_eq!(ds.describe_balls(), "balls of 4, 6 mm");
    let (_, prepared) = prepare_presses(&ds, 8, CircleSource::Annotated).unwrap();
    assert!((prepared[9].ball_radius_px - 3.0 / 0.0295).abs() < 1e-9);
    assert!((prepared[0].ball_radius_px - 2.0 / 0.0295).abs() < 1e-9);
    // The render model fitted on the presses renders them back nearer the
    // real ones when each has its own ball.
    let colour = |dir: &Path, out: &str| {
        let cal = short_calibration(dir, &tmp.path().join(out));
        (
            cal.render.colour_error_levels,
            cal.render.gel_profile_error_mm,
        )
    };
    let (right, wrong) = (colour(&both, "m-both"), colour(&one, "m-one"));
    eprintln!("each its own ball: {right:?}; all taken for the 4 mm ball: {wrong:?}");
    assert!(right.1 < wrong.1, "{right:?} {wrong:?}");
    // A ball that is no ball is refused by its line.
    let csv = std::fs::read_to_string(both.join("presses.csv")).unwrap();
    std::fs::write(
        both.join("presses.csv"),
        csv.replacen(",300,60,6\n", ",300,60,-6\n", 1),
    )
    .unwrap();
    let e = BallPresses::open(&both).unwrap_err().to_string();
    assert!(
        e.contains("presses.csv: line 10: ball_diameter_mm = -6 is no ball"),
        "{e}"
    );
}

#[test]
fn every_press_is_pictured_48_to_a_picture() {
    // gs_sdk asks for about 50 presses of each ball; circles.png showed the
    // first 48 only. The 32 shared presses and 18 of them again under other
    // names make 50: two pictures, the second of the last two presses.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("fifty");
    subset(&d, 32, str::to_string);
    let csv = std::fs::read_to_string(d.join("presses.csv")).unwrap();
    let mut more = csv.clone();
    for l in csv.lines().skip(1).take(18) {
        let file = l.split(',').next().unwrap();
        let again = file.replace(".png", "b.png");
        std::fs::copy(d.join(file), d.join(&again)).unwrap();
        more.push_str(&format!("{}\n", l.replacen(file, &again, 1)));
    }
    std::fs::write(d.join("presses.csv"), more).unwrap();
    let out = tmp.path().join("model");
    let cal = short_calibration(&d, &out);
    assert_eq!(cal.circle_pictures, ["circles.png", "circles-2.png"]);
    let size = |f: &str| image::image_dimensions(out.join(f)).unwrap();
    assert_eq!(size("circles.png"), (4 * 213, 12 * (160 + 22)));
    assert_eq!(size("circles-2.png"), (2 * 213, 160 + 22));
    let line = cal.describe(&out).join("\n");
    assert!(
        line.contains("circles.png and circles-2.png (green"),
        "{line}"
    );
}

#[test]
fn a_calibration_reconstructs_held_out_presses_and_rest() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("presses");
    subset(&d, 10, str::to_string);
    let ds = BallPresses::open(&d).unwrap();
    let mut cfg = CalibrationConfig::new()
        .with_factor(Some(8))
        .with_val_presses(2);
    cfg.schedule.max_epochs = 40;
    let out = tmp.path().join("model");
    let cal = calibrate(&cfg, &ds, &out, DeviceKind::Flex).unwrap();
    assert_eq!((cal.train_presses, cal.val_presses), (8, 2));
    assert!(cal.warnings.is_empty(), "{:?}", cal.warnings);
    for f in [
        "gelsight.json",
        "gelsight.bpk",
        "background.png",
        "training.json",
        "optics.json",
        "circles.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // The presses at a third of their size, four to a line under their
    // captions, each with its annotated circle in green: at the rightmost
    // point of the first press's circle (column and row, in the frame).
    let picture = image::open(out.join("circles.png")).unwrap().to_rgb8();
    assert_eq!(picture.dimensions(), (4 * 213, 3 * (160 + 22)));
    let a = ds.presses[0].annotated.unwrap();
    let at = |v: f64| ((v + 0.5) / 3.0 - 0.5).round() as u32;
    let (x, y) = (at(a.centre_x_px + a.radius_px), at(a.centre_y_px));
    let green = (x - 1..=x + 1)
        .flat_map(|x| (y - 1..=y + 1).map(move |y| (x, y)))
        .any(|(x, y)| picture.get_pixel(x, y).0 == [40, 230, 60]);
    assert!(green, "no green ring at ({x}, {y})");
    // The render model reproduces the presses better than the bare
    // background does, and loads as the renderer reads it.
    let r = &cal.render;
    assert!(
        r.colour_error_levels < 0.8 * r.colour_error_unpressed_levels,
        "{r:?}"
    );
    assert!(
        r.gel.gain > 0.0 && r.gel.gain <= 1.0 && r.gel.sigma_mm > 0.0,
        "{r:?}"
    );
    let unit = datasets_synth::calibrated::CalibratedSensor::load(&out).unwrap();
    assert_eq!((unit.width(), unit.height()), (640, 480));
    // A render model edited out of range is named at its file, said once.
    let optics = out.join("optics.json");
    let good = std::fs::read_to_string(&optics).unwrap();
    let mut bad: serde_json::Value = serde_json::from_str(&good).unwrap();
    bad["optics"]["bins"] = 0.into();
    std::fs::write(&optics, bad.to_string()).unwrap();
    let e = datasets_synth::calibrated::CalibratedSensor::load(&out)
        .err()
        .unwrap()
        .to_string();
    assert_eq!(
        e,
        format!(
            "invalid configuration: {}: optics: bins must be 2-128, got 0",
            optics.display()
        )
    );
    std::fs::write(&optics, good).unwrap();
    // Held-out presses: the cap's shape within 0.15 mm after a short fit.
    for s in &cal.validation {
        assert!(s.shape_mae_mm < 0.15, "{s:?}");
        assert!(s.peak_mm > 0.5, "{s:?}");
    }
    // The background reconstructs to rest; burn and onnxruntime agree.
    let bg = load_rgb(d.join("background.png")).unwrap();
    let mut burn = Reconstructor::load(&out, Runtime::BurnFlex, 0).unwrap();
    let rest = burn.reconstruct(&bg, &d.join("background.png")).unwrap();
    assert_eq!((rest.width, rest.height), (640, 480));
    assert!(
        rest.indentation_m.iter().all(|v| v.abs() < 1e-5),
        "rest is not flat"
    );
    let frame = load_rgb(d.join("frames/press_01.png")).unwrap();
    let a = burn.reconstruct(&frame, Path::new("press_01.png")).unwrap();
    let mut ort = Reconstructor::load(&out, Runtime::Onnx, 1).unwrap();
    let b = ort.reconstruct(&frame, Path::new("press_01.png")).unwrap();
    let worst = a
        .indentation_m
        .iter()
        .zip(&b.indentation_m)
        .map(|(x, y)| (x - y).abs())
        .fold(0f32, f32::max);
    assert!(worst < 1e-6, "burn and onnxruntime differ by {worst} m");
}

#[test]
fn the_lookup_anchor_cross_validates_and_the_folder_reconstruction_refuses_bad_input() {
    use tactile_gelsight::bench::{BenchOptions, Candidate, cross_validate};
    use tactile_gelsight::reconstruct::{ReconstructOptions, reconstruct_folder};
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("presses");
    subset(&d, 8, str::to_string);
    let ds = BallPresses::open(&d).unwrap();
    let (bg, presses) = prepare_presses(&ds, 4, CircleSource::Auto).unwrap();
    let options = BenchOptions {
        folds: 2,
        exposure: 0.15,
        runs: 2,
        device: DeviceKind::Flex,
        progress: false,
    };
    let r = cross_validate(
        "lookup",
        &Candidate::Lookup { bins: 24 },
        &ds,
        (&bg, &presses),
        &options,
    )
    .unwrap();
    // Every press scored once, by the table that did not see it: far better
    // than a flat answer (about 0.3 mm) and at rest far from the ball.
    assert_eq!(r.presses.len(), 8);
    assert!(r.mean.shape_mm < 0.12, "{:?}", r.mean);
    assert!(r.mean.far_field_mm < 0.03, "{:?}", r.mean);
    assert!(
        r.darker.shape_mm < 0.15 && r.brighter.shape_mm < 0.15,
        "{r:?}"
    );
    assert!(r.burn_ms > 0.0 && r.ort_ms.is_none());
    assert!(!r.profile.is_empty());
    let bad = BenchOptions {
        folds: 9,
        ..options.clone()
    };
    assert!(
        cross_validate(
            "lookup",
            &Candidate::Lookup { bins: 24 },
            &ds,
            (&bg, &presses),
            &bad
        )
        .unwrap_err()
        .to_string()
        .contains("folds")
    );
    // An exposure change of 90 % or more (a gain of 0.1 or less) is refused
    // with the runs and folds, before any candidate is fitted.
    for exposure in [0.9, -0.1, f64::NAN] {
        let bad = BenchOptions {
            exposure,
            ..options.clone()
        };
        let e = cross_validate(
            "lookup",
            &Candidate::Lookup { bins: 24 },
            &ds,
            (&bg, &presses),
            &bad,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("exposure must be in [0, 0.9)"), "{e}");
    }

    // A model folder to reconstruct with (a short fit is enough here).
    let mut cfg = CalibrationConfig::new()
        .with_factor(Some(8))
        .with_val_presses(2);
    cfg.schedule.max_epochs = 2;
    let model = tmp.path().join("model");
    calibrate(&cfg, &ds, &model, DeviceKind::Flex).unwrap();
    let o = ReconstructOptions {
        background: None,
        render: None,
        runtime: Runtime::BurnFlex,
    };
    // An output folder that holds files is refused before any work and
    // left alone.
    let taken = tmp.path().join("taken");
    std::fs::create_dir_all(&taken).unwrap();
    std::fs::write(taken.join("keep.txt"), "mine").unwrap();
    let e = reconstruct_folder(&model, &d.join("frames"), &taken, &o, None).unwrap_err();
    assert!(e.to_string().contains("already holds files"), "{e}");
    assert_eq!(
        std::fs::read_to_string(taken.join("keep.txt")).unwrap(),
        "mine"
    );
    // A frame of another size is named, and nothing is written.
    let odd = tmp.path().join("odd");
    std::fs::create_dir_all(&odd).unwrap();
    tactile_core::image_io::save_rgb_png(
        odd.join("small.png"),
        320,
        240,
        &vec![128u8; 320 * 240 * 3],
    )
    .unwrap();
    let out = tmp.path().join("out");
    let e = reconstruct_folder(&model, &odd, &out, &o, None).unwrap_err();
    assert!(matches!(e, Error::FrameSize { .. }), "{e}");
    assert!(e.to_string().contains("small.png"), "{e}");
    assert!(!out.exists());
    // Frames it cannot read after good ones (another size, one stored
    // grey) are found from their headers before any frame is
    // reconstructed, counted, the first named; nothing is written.
    let mixed = tmp.path().join("mixed");
    std::fs::create_dir_all(&mixed).unwrap();
    let mut presses: Vec<PathBuf> = std::fs::read_dir(d.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    presses.sort();
    for p in &presses[..2] {
        std::fs::copy(p, mixed.join(p.file_name().unwrap())).unwrap();
    }
    std::fs::copy(odd.join("small.png"), mixed.join("zz-a.png")).unwrap();
    std::fs::copy(odd.join("small.png"), mixed.join("zz-b.png")).unwrap();
    tactile_core::image_io::save_grey_png(mixed.join("zz-c.png"), 640, 480, &vec![90u8; 640 * 480])
        .unwrap();
    // A file cut before its header ends is counted with them, not a stop
    // at the first such file.
    std::fs::write(mixed.join("zz-d.png"), b"\x89PNG").unwrap();
    let e = reconstruct_folder(&model, &mixed, &out, &o, None).unwrap_err();
    let Error::UnreadableFrames {
        first,
        count,
        total,
    } = &e
    else {
        panic!("{e}")
    };
    assert_eq!((*count, *total), (4, 6), "{e}");
    assert!(matches!(**first, Error::FrameSize { .. }), "{e}");
    // The count of a folder's bad frames stops a reconstruction; one
    // frame's refusal is what a pipeline skips.
    assert!(first.is_frame_refusal() && !e.is_frame_refusal(), "{e}");
    assert!(e.to_string().contains("zz-a.png"), "{e}");
    assert!(!out.exists());
    std::fs::remove_file(mixed.join("zz-a.png")).unwrap();
    std::fs::remove_file(mixed.join("zz-b.png")).unwrap();
    std::fs::remove_file(mixed.join("zz-d.png")).unwrap();
    let e = reconstruct_folder(&model, &mixed, &out, &o, None).unwrap_err();
    assert!(
        matches!(e, Error::GreyFrame { .. }) && e.to_string().contains("zz-c.png"),
        "{e}"
    );
    assert!(!out.exists());
    // A press cut short behind a whole header is found only when decoded:
    // skipped and named, the other presses' maps written.
    std::fs::remove_file(mixed.join("zz-c.png")).unwrap();
    let whole = std::fs::read(&presses[0]).unwrap();
    std::fs::write(mixed.join("zz-e.png"), &whole[..whole.len() / 2]).unwrap();
    let r = reconstruct_folder(&model, &mixed, &out, &o, None).unwrap();
    assert_eq!((r.frames, r.undecodable_frames), (2, 1));
    assert!(
        r.warnings.len() == 1
            && r.warnings[0].contains("1 of the 3 frames could not be decoded past their header")
            && r.warnings[0].contains("zz-e.png: cannot decode image"),
        "{:?}",
        r.warnings
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 2);
    std::fs::remove_dir_all(&out).unwrap();
    // Alone, it is refused, and nothing is written.
    let cut = tmp.path().join("cut");
    std::fs::create_dir_all(&cut).unwrap();
    std::fs::rename(mixed.join("zz-e.png"), cut.join("zz-e.png")).unwrap();
    let e = reconstruct_folder(&model, &cut, &out, &o, None).unwrap_err();
    assert!(
        e.to_string().contains("zz-e.png: cannot decode image"),
        "{e}"
    );
    assert!(!out.exists());
    // A frame that links out of the folder is named, not read.
    let linked = tmp.path().join("linked");
    std::fs::create_dir_all(&linked).unwrap();
    std::os::unix::fs::symlink(odd.join("small.png"), linked.join("out.png")).unwrap();
    let e = reconstruct_folder(&model, &linked, &out, &o, None).unwrap_err();
    assert!(
        e.to_string().contains("out.png") && e.to_string().contains("leaves the folder"),
        "{e}"
    );
    assert!(!out.exists());
    // A folder without frames says so.
    let empty = tmp.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let e = reconstruct_folder(&model, &empty, &out, &o, None).unwrap_err();
    assert!(
        e.to_string()
            .contains("no frames (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM)"),
        "{e}"
    );
    // A JPEG frame is read like a PNG; one named like another frame but for
    // its extension is refused (both would be one .npy), naming both.
    let twins = tmp.path().join("twins");
    std::fs::create_dir_all(&twins).unwrap();
    let first = std::fs::read_dir(d.join("frames"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let rgb = tactile_core::image_io::load_rgb(&first).unwrap();
    image::RgbImage::from_raw(
        rgb.width() as u32,
        rgb.height() as u32,
        rgb.as_slice().to_vec(),
    )
    .unwrap()
    .save(twins.join("a.jpg"))
    .unwrap();
    std::fs::write(twins.join("notes.txt"), "not a frame").unwrap();
    let r = reconstruct_folder(&model, &twins, &out, &o, None).unwrap();
    assert_eq!(r.frames, 1);
    assert!(out.join("a.npy").is_file());
    assert!(
        r.warnings.iter().any(|w| w.contains("notes.txt")),
        "{:?}",
        r.warnings
    );
    std::fs::copy(&first, twins.join("a.png")).unwrap();
    let again = tmp.path().join("again");
    let e = reconstruct_folder(&model, &twins, &again, &o, None).unwrap_err();
    assert!(
        e.to_string().contains("a.jpg") && e.to_string().contains("a.png"),
        "{e}"
    );
    assert!(!again.exists());
    std::fs::remove_dir_all(&out).unwrap();
    // A TIFF stack given alone is reconstructed page by page: each page's
    // map is named by the stack and its number, and equals its frame
    // file's.
    use tiff::encoder::{TiffEncoder, colortype::RGB8};
    let mut pngs: Vec<std::path::PathBuf> = std::fs::read_dir(d.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    pngs.sort();
    let pair = tmp.path().join("pair");
    std::fs::create_dir_all(&pair).unwrap();
    let mut bytes = std::io::Cursor::new(Vec::new());
    let mut tiff = TiffEncoder::new(&mut bytes).unwrap();
    for (k, f) in pngs[..2].iter().enumerate() {
        let rgb = load_rgb(f).unwrap();
        let (w, h) = (rgb.width() as u32, rgb.height() as u32);
        tiff.write_image::<RGB8>(w, h, rgb.as_slice()).unwrap();
        std::fs::copy(f, pair.join(format!("p{k}.png"))).unwrap();
    }
    let stack = tmp.path().join("presses.tif");
    std::fs::write(&stack, bytes.into_inner()).unwrap();
    let r = reconstruct_folder(&model, &stack, &out, &o, None).unwrap();
    assert_eq!((r.frames, r.undecodable_frames), (2, 0));
    let by_file = tmp.path().join("by-file");
    reconstruct_folder(&model, &pair, &by_file, &o, None).unwrap();
    for k in 0..2 {
        let page = std::fs::read(out.join(format!("presses-{k:06}.npy"))).unwrap();
        assert!(page == std::fs::read(by_file.join(format!("p{k}.npy"))).unwrap());
    }
    std::fs::remove_dir_all(&out).unwrap();
    // A background of another size is refused, naming it.
    let o = ReconstructOptions {
        background: Some(odd.join("small.png")),
        ..o
    };
    let e = reconstruct_folder(&model, &d.join("frames"), &out, &o, None).unwrap_err();
    assert!(e.to_string().contains("small.png"), "{e}");
    assert!(!out.exists());
    // A grey frame, or a grey rest frame, of a colour sensor is named, not
    // read as a skin (before, the background saved grey reconstructed to a
    // 0.25 mm dent of nothing).
    let grey = tmp.path().join("grey");
    std::fs::create_dir_all(&grey).unwrap();
    std::fs::copy(d.join("background.png"), grey.join("rest.png")).unwrap();
    save_grey_copy(&grey.join("rest.png"));
    let no_background = ReconstructOptions {
        background: None,
        ..o.clone()
    };
    let e = reconstruct_folder(&model, &grey, &out, &no_background, None).unwrap_err();
    assert!(matches!(e, Error::GreyFrame { .. }), "{e}");
    assert!(e.to_string().contains("rest.png"), "{e}");
    let o = ReconstructOptions {
        background: Some(grey.join("rest.png")),
        ..o
    };
    let e = reconstruct_folder(&model, &d.join("frames"), &out, &o, None).unwrap_err();
    assert!(
        matches!(e, Error::GreyFrame { .. }) && e.to_string().contains("rest.png"),
        "{e}"
    );
    assert!(!out.exists());
    // A frame, or a rest frame, in BGR order (as OpenCV saves what it
    // read) is named, not read as a skin mirrored; before, it was
    // reconstructed without a word (a 0.27 mm peak and a -0.72 mm pit
    // where its press is 0.68 mm deep).
    let bgr_dir = tmp.path().join("bgr");
    std::fs::create_dir_all(&bgr_dir).unwrap();
    save_bgr_copy(
        &d.join("frames/press_01.png"),
        &bgr_dir.join("press_01.png"),
    );
    let e = reconstruct_folder(&model, &bgr_dir, &out, &no_background, None).unwrap_err();
    assert!(
        matches!(e, Error::SwappedChannels { .. }) && e.is_frame_refusal(),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("press_01.png: red and blue look swapped (BGR order"),
        "{e}"
    );
    save_bgr_copy(&d.join("background.png"), &bgr_dir.join("rest.png"));
    let o = ReconstructOptions {
        background: Some(bgr_dir.join("rest.png")),
        ..o
    };
    let e = reconstruct_folder(&model, &d.join("frames"), &out, &o, None).unwrap_err();
    assert!(
        matches!(e, Error::SwappedChannels { .. }) && e.to_string().contains("rest.png"),
        "{e}"
    );
    assert!(!out.exists());
    // A blank rest frame (the light off when it was taken) is named blank.
    let dark = grey.join("dark.png");
    tactile_core::image_io::save_rgb_png(&dark, 640, 480, &vec![3u8; 640 * 480 * 3]).unwrap();
    let o = ReconstructOptions {
        background: Some(dark),
        ..o
    };
    let e = reconstruct_folder(&model, &d.join("frames"), &out, &o, None).unwrap_err();
    assert!(
        matches!(e, Error::BlankFrame { .. })
            && e.to_string()
                .contains("dark.png: a blank frame (every pixel of one colour, RGB (3, 3, 3))"),
        "{e}"
    );
    assert!(!out.exists());
}

/// Save the colour PNG `from` at `to` in BGR order (as a tool that saved
/// what OpenCV read would).
fn save_bgr_copy(from: &Path, to: &Path) {
    let rgb = load_rgb(from).unwrap();
    let mut v = rgb.as_slice().to_vec();
    v.chunks_exact_mut(3).for_each(|p| p.swap(0, 2));
    tactile_core::image_io::save_rgb_png(to, rgb.width(), rgb.height(), &v).unwrap();
}

/// Overwrite the colour PNG `path` with its grey version, as RGB (the
/// three channels equal): a frame a tool saved grey.
fn save_grey_copy(path: &Path) {
    let rgb = load_rgb(path).unwrap();
    let grey: Vec<u8> = rgb
        .as_slice()
        .chunks_exact(3)
        .flat_map(|p| {
            let v = ((p[0] as u32 + p[1] as u32 + p[2] as u32) / 3) as u8;
            [v, v, v]
        })
        .collect();
    tactile_core::image_io::save_rgb_png(path, rgb.width(), rgb.height(), &grey).unwrap();
}
