#![allow(clippy::unwrap_used)]
//! Depth files and depth maps that must not slip through: NaN and infinity
//! (the error names the file and the pixel), the wrong dtype or shape, and
//! SSIM of constant maps.

use std::path::Path;

use tactile_rs::core::metrics::ssim;
use tactile_rs::depth::data::load_depth_mm;

/// A minimal NumPy v1.0 `.npy` writer for the fixtures.
fn write_npy(path: &Path, descr: &str, shape: &[usize], data: &[u8]) {
    let shape_txt = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape_txt}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend(data);
    std::fs::write(path, bytes).unwrap();
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn a_good_depth_file_loads_in_millimetres() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("ok.npy");
    write_npy(&p, "<f4", &[2, 4], &f32_bytes(&[0.015; 8]));
    let mm = load_depth_mm(&p, 2, 1).unwrap();
    assert_eq!(mm.len(), 2);
    assert!(mm.iter().all(|&v| (v - 15.0).abs() < 1e-4), "{mm:?}");
}

#[test]
fn nan_and_infinity_name_the_file_and_the_pixel() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bad) in [("nan.npy", f32::NAN), ("inf.npy", f32::INFINITY)] {
        let mut v = vec![0.015f32; 12];
        v[4 * 2 + 1] = bad; // row 2, column 1 of a 3 x 4 map
        let p = dir.path().join(name);
        write_npy(&p, "<f4", &[3, 4], &f32_bytes(&v));
        let e = load_depth_mm(&p, 2, 1).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("(1, 2)"), "{e}");
    }
}

#[test]
fn wrong_dtype_or_shape_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    // float64, as `numpy.save` writes a map computed in double precision:
    // read as the float32 it would have been saved as.
    let f64_bytes = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let p = dir.path().join("double.npy");
    write_npy(&p, "<f8", &[2, 4], &f64_bytes(&[0.015; 8]));
    let want = dir.path().join("single.npy");
    write_npy(&want, "<f4", &[2, 4], &f32_bytes(&[0.015; 8]));
    assert_eq!(
        load_depth_mm(&p, 2, 1).unwrap(),
        load_depth_mm(&want, 2, 1).unwrap()
    );
    // A double beyond float32's range is no distance; named by its pixel.
    let mut v = [0.015f64; 8];
    v[5] = 1e300;
    write_npy(&p, "<f8", &[2, 4], &f64_bytes(&v));
    let e = load_depth_mm(&p, 2, 1).unwrap_err().to_string();
    assert!(e.contains("double.npy") && e.contains("(1, 1)"), "{e}");
    // Big-endian (`dtype='>f4'` or `'>f8'`): byte-swapped, the same map.
    let be32: Vec<u8> = [0.015f32; 8].iter().flat_map(|x| x.to_be_bytes()).collect();
    let be64: Vec<u8> = [0.015f64; 8].iter().flat_map(|x| x.to_be_bytes()).collect();
    for (descr, bytes) in [(">f4", &be32), (">f8", &be64)] {
        let p = dir.path().join("big.npy");
        write_npy(&p, descr, &[2, 4], bytes);
        assert_eq!(
            load_depth_mm(&p, 2, 1).unwrap(),
            load_depth_mm(&want, 2, 1).unwrap(),
            "{descr}"
        );
        // Cut short, or asking for more than 8K: refused before reading.
        write_npy(&p, descr, &[2, 4], &bytes[..20]);
        let e = load_depth_mm(&p, 2, 1).unwrap_err().to_string();
        assert!(
            e.contains("big.npy") && e.contains("20 bytes follow it"),
            "{e}"
        );
        write_npy(&p, descr, &[100_000, 100_000], &bytes[..20]);
        let e = load_depth_mm(&p, 2, 1).unwrap_err().to_string();
        assert!(e.contains("big.npy") && e.contains("at most 8K"), "{e}");
    }
    // Other dtypes are refused naming the file and what is read.
    for (descr, bytes) in [
        ("<f2", vec![0u8; 16]),
        ("<i4", vec![0u8; 32]),
        (">f2", vec![0u8; 16]),
    ] {
        let p = dir.path().join("other.npy");
        write_npy(&p, descr, &[2, 4], &bytes);
        let e = load_depth_mm(&p, 2, 1).unwrap_err().to_string();
        assert!(
            e.contains("other.npy") && e.contains("float32 (or float64)"),
            "{descr}: {e}"
        );
    }
    let p = dir.path().join("cube.npy");
    write_npy(&p, "<f4", &[2, 2, 2], &f32_bytes(&[0.015; 8]));
    let e = load_depth_mm(&p, 1, 1).unwrap_err().to_string();
    assert!(e.contains("cube.npy") && e.contains("2-D"), "{e}");
    let p = dir.path().join("short.npy");
    write_npy(&p, "<f4", &[2, 4], &f32_bytes(&[0.015; 3]));
    assert!(
        load_depth_mm(&p, 1, 1)
            .unwrap_err()
            .to_string()
            .contains("short.npy")
    );
    // A map smaller than the model input cannot be shrunk to it.
    let p = dir.path().join("tiny.npy");
    write_npy(&p, "<f4", &[2, 2], &f32_bytes(&[0.015; 4]));
    assert!(
        load_depth_mm(&p, 8, 8)
            .unwrap_err()
            .to_string()
            .contains("tiny.npy")
    );
}

#[test]
fn ssim_of_constant_maps_is_defined() {
    let a = vec![15.0f32; 64];
    assert_eq!(ssim(&a, &a, 8, 8, 6.0), 1.0);
    let b = vec![17.0f32; 64];
    let s = ssim(&a, &b, 8, 8, 6.0);
    assert!(s.is_finite() && (0.0..1.0).contains(&s), "{s}");
}

/// Window MAE (mm) of the shipped depth model on frame `frame` of
/// sequences `seqs` rendered with `cfg`.
fn shipped_mae(
    cfg: &tactile_rs::synth::VisuotactileConfig,
    seqs: std::ops::Range<u64>,
    frame: usize,
) -> f64 {
    use tactile_rs::core::spec::visuotactile::Window;
    use tactile_rs::depth::DepthEstimator;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/depth");
    let mut est = DepthEstimator::load(&root, tactile_rs::nn::Runtime::BurnFlex, 0).unwrap();
    let [w, h] = est.artifact.model.input_size;
    let window = Window::mask(w, h);
    let mut total = 0.0;
    for s in seqs.clone() {
        let (_, f) = tactile_rs::synth::visuotactile::sample(cfg, 77, s, frame);
        let img = tactile_rs::core::image_io::rgb_image(f.width, f.height, f.rgb).unwrap();
        let mm: Vec<f32> = f.depth_m.iter().map(|v| v * 1000.0).collect();
        let truth =
            tactile_rs::preprocess::resize_area_f32(&mm, (f.width, f.height), w, h).unwrap();
        let mask = est.artifact.with_mask.then(|| {
            let m: Vec<f32> = f.mask.iter().map(|&v| v as f32 / 255.0).collect();
            tactile_rs::preprocess::resize_area_f32(&m, (f.width, f.height), w, h)
                .unwrap()
                .iter()
                .map(|&v| v >= 0.5)
                .collect::<Vec<bool>>()
        });
        let pred = est.depth_mm(&img, mask.as_deref()).unwrap();
        assert!(pred.iter().all(|v| v.is_finite()));
        total += tactile_rs::core::metrics::masked_mae(&pred, &truth, Some(&window)).unwrap();
    }
    total / (seqs.end - seqs.start) as f64
}

#[test]
fn shipped_depth_model_handles_flat_skin_and_the_deepest_press() {
    let mut cfg = tactile_rs::synth::VisuotactileConfig::default();
    // Before first touch: the skin at rest (the dome), no deformation.
    let flat = shipped_mae(&cfg, 0..4, 0);
    // The deepest press of the range at the middle of each video.
    cfg.press_mm = tactile_rs::synth::Range { min: 4.0, max: 4.0 };
    let mid = cfg.frames_per_sequence / 2;
    let deepest = shipped_mae(&cfg, 0..4, mid);
    assert!(flat < 0.05, "flat skin: MAE {flat} mm");
    assert!(deepest < 0.15, "deepest press: MAE {deepest} mm");
}

#[test]
fn displacement_from_the_rest_dome_is_zero_at_rest_and_shows_the_ridge_when_pressed() {
    use datasets_synth::{VisuotactileConfig, visuotactile};
    use tactile_rs::depth::data::displacement_mm;
    let vc = VisuotactileConfig::default();
    let (w, h) = (vc.width as usize, vc.height as usize);
    let aspect = w as f64 / h as f64;
    // The generator's own labels, at rest and at the deepest press.
    let mut sequence = 0;
    let (rest, pressed) = loop {
        let (_, rest) = visuotactile::sample(&vc, 3, sequence, 0);
        let (_, pressed) = visuotactile::sample(&vc, 3, sequence, vc.frames_per_sequence / 2);
        if pressed.tendon && rest.press_mm == 0.0 {
            break (rest, pressed);
        }
        sequence += 1;
    };
    let mm = |f: &datasets_synth::visuotactile::VisuotactileFrame| -> Vec<f32> {
        f.depth_m.iter().map(|d| d * 1000.0).collect()
    };
    let at_rest = displacement_mm(&mm(&rest), w, h, aspect);
    let worst = at_rest.iter().fold(0f32, |a, v| a.max(v.abs()));
    assert!(worst < 0.01, "a frame at rest is {worst} mm off the dome");
    // Pressed on a tendon: the push is largest on the tendon's mask.
    let d = displacement_mm(&mm(&pressed), w, h, aspect);
    let mean = |on: bool| {
        let v: Vec<f32> = d
            .iter()
            .zip(&pressed.mask)
            .filter(|(_, m)| (**m > 0) == on)
            .map(|(v, _)| *v)
            .collect();
        v.iter().sum::<f32>() / v.len().max(1) as f32
    };
    assert!(
        mean(true) > mean(false) + 0.1,
        "tendon {} vs elsewhere {}",
        mean(true),
        mean(false)
    );
}
