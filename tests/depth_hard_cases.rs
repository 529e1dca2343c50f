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
    let f64s: Vec<u8> = [0.015f64; 8].iter().flat_map(|x| x.to_le_bytes()).collect();
    let p = dir.path().join("double.npy");
    write_npy(&p, "<f8", &[2, 4], &f64s);
    let e = load_depth_mm(&p, 2, 1).unwrap_err().to_string();
    assert!(e.contains("double.npy") && e.contains("float32"), "{e}");
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
