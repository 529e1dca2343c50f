#![allow(clippy::unwrap_used)]
//! A calibrated sensor's rendered data: the same frames for the same seed,
//! and labels that agree with each other and with the indentation map.

use datasets_synth::calibrated::{
    CalibratedConfig, CalibratedSensor, Contact, GelResponse, OpticsSample, REAL_PRESS_PATH,
    RealFrame, RealFrames, RenderModel, SensorOptics, sample,
};
use datasets_synth::{WriteOptions, write_calibrated};
use tactile_core::spec::DepthMaps;
use tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM;

/// A small sensor whose colour follows the slope: red with x, green with
/// y, blue against x.
fn sensor() -> CalibratedSensor {
    let (w, h) = (160, 120);
    let mut samples = vec![];
    for k in 0..60_000usize {
        let (x, y) = ((k % w) as f64, ((k / w) % h) as f64);
        let gx = ((k * 7919) % 1000) as f64 / 250.0 - 2.0;
        let gy = ((k * 104_729) % 1000) as f64 / 250.0 - 2.0;
        samples.push(OpticsSample {
            x,
            y,
            gx,
            gy,
            change: [(0.1 * gx) as f32, (0.1 * gy) as f32, (-0.05 * gx) as f32],
            weight: 1.0,
        });
    }
    let optics = SensorOptics::fit((w, h), 17, 2.0, &samples).unwrap();
    CalibratedSensor {
        dir: "test-sensor".into(),
        model: RenderModel {
            sensor: "test unit".into(),
            mm_per_px: 0.06,
            optics,
            gel: GelResponse {
                sigma_mm: 0.5,
                gain: 0.7,
            },
            fit: serde_json::Value::Null,
        },
        background: vec![128; w * h * 3],
    }
}

fn config() -> CalibratedConfig {
    CalibratedConfig {
        frames_per_sequence: 6,
        ..CalibratedConfig::default()
    }
}

#[test]
fn the_same_seed_renders_the_same_frames() {
    let s = sensor();
    let c = config();
    let (a_scene, a) = sample(&s, &c, 11, 3, 2);
    let (b_scene, b) = sample(&s, &c, 11, 3, 2);
    assert_eq!(a_scene, b_scene);
    assert_eq!(a.rgb, b.rgb);
    assert_eq!(a.indentation_m, b.indentation_m);
    let (_, other) = sample(&s, &c, 12, 3, 2);
    assert_ne!(a.rgb, other.rgb);
}

#[test]
fn mask_direction_and_indentation_agree() {
    let s = sensor();
    let c = config();
    let (mut tendons, mut others) = (0, 0);
    for seq in 0..40u64 {
        for f in [0, 2, 3] {
            let (scene, fr) = sample(&s, &c, 5, seq, f);
            assert_eq!(fr.rgb.len(), 160 * 120 * 3);
            assert!(fr.indentation_m.iter().all(|v| v.is_finite() && *v >= 0.0));
            let min = (CONTACT_MIN_INDENTATION_MM * 1e-3) as f32;
            let pushed: Vec<bool> = fr.indentation_m.iter().map(|&v| v > min).collect();
            match &scene.contact {
                Contact::Tendon { .. } => {
                    let mask: Vec<bool> = fr.mask.iter().map(|&m| m == 255).collect();
                    assert_eq!(
                        mask, pushed,
                        "the mask is where a tendon pushes past 0.03 mm"
                    );
                    assert_eq!(fr.tendon, pushed.iter().any(|&p| p));
                    assert_eq!(fr.direction_deg.is_some(), fr.tendon);
                    if let Some(d) = fr.direction_deg {
                        assert!((0.0..180.0).contains(&d));
                        assert_eq!(Some(d), scene.contact.direction_deg());
                    }
                    assert!((fr.ridge_mm - fr.peak_mm).abs() < 1e-9);
                    tendons += usize::from(fr.tendon);
                }
                _ => {
                    assert!(!fr.tendon && fr.direction_deg.is_none());
                    assert!(fr.mask.iter().all(|&m| m == 0));
                    assert_eq!(fr.ridge_mm, 0.0);
                    others += 1;
                }
            }
            if fr.press_mm == 0.0 {
                assert!(
                    fr.indentation_m.iter().all(|&v| v == 0.0),
                    "no press, no push"
                );
            }
            let peak = fr.indentation_m.iter().copied().fold(0f32, f32::max) as f64 * 1e3;
            assert!((peak - fr.peak_mm).abs() < 1e-4);
            // The skin never sinks deeper than the object pushes it.
            assert!(
                fr.peak_mm <= fr.press_mm + 1e-6,
                "{} > {}",
                fr.peak_mm,
                fr.press_mm
            );
        }
    }
    assert!(
        tendons > 10 && others > 5,
        "{tendons} tendon and {others} other frames"
    );
}

#[test]
fn objects_are_pressed_over_their_own_range_tendons_over_theirs() {
    let s = sensor();
    let c = CalibratedConfig {
        press_mm: datasets_synth::Range::new(0.2, 0.4),
        object_press_mm: datasets_synth::Range::new(2.0, 2.5),
        ..config()
    };
    let (mut tendons, mut objects) = (0, 0);
    for seq in 0..60u64 {
        let (scene, _) = sample(&s, &c, 9, seq, 0);
        let p = scene.peak_press_mm;
        match scene.contact {
            Contact::Tendon { .. } => {
                assert!((0.2..=0.4).contains(&p), "tendon pressed {p} mm");
                tendons += 1;
            }
            Contact::Nothing => {}
            _ => {
                assert!((2.0..=2.5).contains(&p), "object pressed {p} mm");
                objects += 1;
            }
        }
    }
    assert!(
        tendons > 10 && objects > 5,
        "{tendons} tendons, {objects} objects"
    );
    let bad = CalibratedConfig {
        object_press_mm: datasets_synth::Range::new(1.0, 9.0),
        ..config()
    };
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("object_press_mm"), "{e}");
}

/// By default a plate covers the frame's centre; `plate_edge_reach` puts
/// its edge line where asked along its normal, past the centre too, so the
/// plate may only clip the frame; `punch_fillet` sets a punch's rim.
#[test]
fn plates_reach_where_asked_and_punch_rims_are_as_sharp_as_asked() {
    let s = sensor();
    let (hw, hh) = s.half_mm();
    let only = |kind: &str| CalibratedConfig {
        tendon_share: 0.0,
        sphere_share: 0.0,
        nothing_share: 0.0,
        punch_share: if kind == "punch" { 1.0 } else { 0.0 },
        flat_share: if kind == "flat" { 1.0 } else { 0.0 },
        ..config()
    };
    // The edge line's place along the plate's normal (positive: past the
    // centre, which is then off the plate), and the way to the border.
    let edges = |c: &CalibratedConfig| -> Vec<(f64, f64)> {
        (0..80u64)
            .map(|seq| match sample(&s, c, 5, seq, 0).0.contact {
                Contact::Edge { point, normal, .. } => (
                    point.0 * normal.0 + point.1 * normal.1,
                    normal.0.abs() * hw + normal.1.abs() * hh,
                ),
                other => panic!("a plate was asked for, got {}", other.name()),
            })
            .collect()
    };
    for (d, _) in edges(&only("flat")) {
        assert!(
            (-0.5 * hh - 1e-9..=1e-9).contains(&d),
            "default edge at {d} mm"
        );
    }
    let reach = CalibratedConfig {
        plate_edge_reach: Some(datasets_synth::Range::new(-0.75, 0.75)),
        ..only("flat")
    };
    let placed = edges(&reach);
    for &(d, border) in &placed {
        assert!(
            d.abs() <= 0.75 * border + 1e-9,
            "edge at {d} of {border} mm"
        );
    }
    let clipping = placed.iter().filter(|(d, b)| *d > 0.25 * b).count();
    assert!(
        clipping >= 15,
        "{clipping} of 80 plates only clip the frame"
    );
    let sharp = CalibratedConfig {
        punch_fillet: datasets_synth::Range::new(0.05, 0.05),
        ..only("punch")
    };
    for seq in 0..20u64 {
        match sample(&s, &sharp, 5, seq, 0).0.contact {
            Contact::Punch {
                radius_mm,
                fillet_mm,
                ..
            } => assert!((fillet_mm - 0.05 * radius_mm).abs() < 1e-12),
            other => panic!("a punch was asked for, got {}", other.name()),
        }
    }
    for (bad, key) in [
        (
            CalibratedConfig {
                plate_edge_reach: Some(datasets_synth::Range::new(-2.0, 0.5)),
                ..config()
            },
            "plate_edge_reach",
        ),
        (
            CalibratedConfig {
                punch_fillet: datasets_synth::Range::new(0.0, 0.5),
                ..config()
            },
            "punch_fillet",
        ),
    ] {
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains(key), "{e}");
    }
}

#[test]
fn a_dataset_says_its_depth_maps_are_indentation() {
    let s = sensor();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("set");
    write_calibrated(
        &s,
        &config(),
        8,
        3,
        &out,
        WriteOptions::default(),
        &RealFrames::default(),
    )
    .unwrap();
    let ds = tactile_core::dataset::Dataset::open(&out).unwrap();
    assert_eq!(ds.manifest.depth_maps(), DepthMaps::Indentation);
    assert_eq!((ds.manifest.width, ds.manifest.height), (160, 120));
    assert!(ds.manifest.sensor_spec.contains("test unit"));
    let (_, frame) = sample(&s, &config(), 3, 1, 1);
    let (w, h, m) = ds.load_depth_m(7).unwrap();
    assert_eq!((w, h), (160, 120));
    assert_eq!(m, frame.indentation_m);
    // A bad range is refused before anything is written.
    let bad = CalibratedConfig {
        press_mm: datasets_synth::Range::new(0.5, 0.1),
        ..config()
    };
    let e = write_calibrated(
        &s,
        &bad,
        4,
        1,
        &tmp.path().join("bad"),
        WriteOptions::default(),
        &RealFrames::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("press_mm"), "{e}");
    assert!(!tmp.path().join("bad").exists());
}

#[test]
fn real_frames_join_a_set_as_negatives_with_their_own_labels() {
    let s = sensor();
    let (w, h) = (s.width(), s.height());
    let frame = |k: u8| RealFrame {
        file: format!("frames/press_{k:02}.png"),
        rgb: vec![100 + k; 3 * w * h],
        indentation_m: (0..w * h).map(|i| (i % 7) as f32 * 1e-4).collect(),
    };
    let real = RealFrames {
        folder: "presses".into(),
        frames: vec![frame(1), frame(2)],
        held_out: vec!["frames/press_03.png".into()],
        copies: 3,
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("set");
    write_calibrated(&s, &config(), 8, 3, &out, WriteOptions::default(), &real).unwrap();
    let ds = tactile_core::dataset::Dataset::open(&out).unwrap();
    assert_eq!(ds.manifest.count, 8 + 6);
    let record = &ds.manifest.extra["real_frames"];
    assert_eq!(record["used"].as_array().unwrap().len(), 2);
    assert_eq!(record["held_out"][0], "frames/press_03.png");
    let text = std::fs::read_to_string(out.join("labels.csv")).unwrap();
    let rows: Vec<&str> = text.lines().skip(1).collect();
    let real_rows: Vec<&str> = rows[8..].to_vec();
    assert_eq!(real_rows.len(), 6);
    let mut sequences = std::collections::BTreeSet::new();
    for (k, r) in real_rows.iter().enumerate() {
        let c: Vec<&str> = r.split(',').collect();
        // No tendon, no direction, the real path, one video per frame.
        assert_eq!((c[3], c[4], c[5]), ("0", "", REAL_PRESS_PATH), "{r}");
        assert_eq!(c[8], (k % 3).to_string());
        sequences.insert(c[7].to_string());
        let (_, _, m) = ds.load_depth_m(8 + k).unwrap();
        assert_eq!(m, real.frames[k / 3].indentation_m);
    }
    assert_eq!(sequences.len(), 2);
    // Copies differ (exposure and noise), the same for the same seed.
    let a = tactile_core::image_io::load_rgb(out.join("frames/000008.png")).unwrap();
    let b = tactile_core::image_io::load_rgb(out.join("frames/000009.png")).unwrap();
    assert_ne!(a.as_slice(), b.as_slice());
    let again = tmp.path().join("again");
    write_calibrated(&s, &config(), 8, 3, &again, WriteOptions::default(), &real).unwrap();
    let c = tactile_core::image_io::load_rgb(again.join("frames/000008.png")).unwrap();
    assert_eq!(a.as_slice(), c.as_slice());
    // A frame of another size is refused, naming it.
    let mut bad = real.clone();
    bad.frames[1].rgb.truncate(10);
    let e = write_calibrated(
        &s,
        &config(),
        8,
        3,
        &tmp.path().join("bad"),
        WriteOptions::default(),
        &bad,
    )
    .unwrap_err();
    assert!(e.to_string().contains("press_02"), "{e}");
}
