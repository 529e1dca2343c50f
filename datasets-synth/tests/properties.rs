#![allow(clippy::unwrap_used)]
//! Labels agree with the images they describe, on fixed seeds.

use datasets_synth::rng::Range;
use datasets_synth::tactip::{self, PenetrationField, Shape, TactipScene};
use datasets_synth::visuotactile::{self, TendonPath};
use datasets_synth::{TactipConfig, VisuotactileConfig, WriteOptions};
use tactile_core::dataset::Dataset;
use tactile_core::image_io::load_grey;

fn small_visuo() -> VisuotactileConfig {
    VisuotactileConfig {
        width: 320,
        height: 180,
        frames_per_sequence: 8,
        ..Default::default()
    }
}

/// Principal-axis direction of the set pixels, degrees in [0, 180).
fn principal_axis_deg(mask: &[u8], width: usize) -> f64 {
    let pts: Vec<(f64, f64)> = mask
        .iter()
        .enumerate()
        .filter(|(_, m)| **m > 0)
        .map(|(i, _)| ((i % width) as f64, (i / width) as f64))
        .collect();
    let n = pts.len() as f64;
    let (mu, mv) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let (mut suu, mut svv, mut suv) = (0.0, 0.0, 0.0);
    for p in &pts {
        suu += (p.0 - mu).powi(2);
        svv += (p.1 - mv).powi(2);
        suv += (p.0 - mu) * (p.1 - mv);
    }
    visuotactile::fold_180((0.5 * (2.0 * suv).atan2(suu - svv)).to_degrees())
}

fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

#[test]
fn visuotactile_labels_match_masks_depth_and_press() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("vt");
    let cfg = small_visuo();
    datasets_synth::write_visuotactile(&cfg, 48, 11, &out, WriteOptions::default()).unwrap();
    let ds = Dataset::open(&out).unwrap();
    assert_eq!(ds.len(), 48);
    let (mut positives, mut negatives) = (0, 0);
    for i in 0..ds.len() {
        let mask = load_grey(ds.path_of(i, "mask").unwrap()).unwrap();
        let set = mask.as_slice().iter().filter(|&&m| m == 255).count();
        assert!(mask.as_slice().iter().all(|&m| m == 0 || m == 255));
        let tendon = ds.number(i, "tendon").unwrap() == 1.0;
        assert_eq!(
            set > 0,
            tendon,
            "row {i}: mask pixels {set}, tendon {tendon}"
        );
        assert_eq!(ds.number_opt(i, "direction_deg").unwrap().is_some(), tendon);
        if let Some(d) = ds.number_opt(i, "direction_deg").unwrap() {
            assert!((0.0..180.0).contains(&d));
        }
        let press = ds.number(i, "press_mm").unwrap();
        if press == 0.0 {
            assert!(!tendon, "row {i}: a tendon without contact");
        }
        let (w, h, depth) =
            datasets_synth::npy::read_depth_npy(ds.path_of(i, "depth").unwrap()).unwrap();
        assert_eq!((w, h), (320, 180));
        let (lo, hi) = depth
            .iter()
            .fold((f32::MAX, f32::MIN), |a, &d| (a.0.min(d), a.1.max(d)));
        assert!(lo >= 0.012 && hi <= 0.018, "row {i}: depth {lo}..{hi} m");
        if press == 0.0 {
            // At rest the depth is exactly the dome d0: 15 mm at the centre.
            let c = depth[90 * 320 + 160];
            assert!((c - 0.015).abs() < 1e-5, "{c}");
        }
        if tendon {
            positives += 1;
        } else {
            negatives += 1;
        }
    }
    assert!(positives > 10 && negatives > 5, "{positives} / {negatives}");
}

#[test]
fn straight_tendon_direction_matches_the_mask_axis() {
    // Thin, shallow tendons so the mask is a long narrow band.
    let cfg = VisuotactileConfig {
        paths: vec![TendonPath::Straight],
        tendon_radius_mm: Range::new(1.5, 2.0),
        burial_mm: Range::new(1.0, 1.5),
        press_mm: Range::new(2.0, 4.0),
        out_of_view_fraction: 0.0,
        frames_per_sequence: 1,
        ..small_visuo()
    };
    let mut checked = 0;
    for seq in 0..24 {
        let (_, f) = visuotactile::sample(&cfg, 5, seq, 0);
        assert!(f.tendon, "sequence {seq}: expected a visible tendon");
        let axis = principal_axis_deg(&f.mask, f.width);
        let label = f.direction_deg.unwrap();
        assert!(
            angle_diff(axis, label) < 4.0,
            "sequence {seq}: label {label:.1}, mask axis {axis:.1}"
        );
        checked += 1;
    }
    assert_eq!(checked, 24);
}

#[test]
fn skin_at_rest_is_uniform_grey_and_contact_shades_it() {
    let cfg = VisuotactileConfig {
        noise_sigma: Range::fixed(0.0),
        exposure_jitter: Range::fixed(0.0),
        ..small_visuo()
    };
    let cam = visuotactile::Camera::new(cfg.width, cfg.height);
    let scene = visuotactile::SequenceScene::draw(
        &cfg,
        &cam,
        &mut datasets_synth::rng::SampleRng::new(1, 1, 0),
    );
    let rest = visuotactile::render(
        &cfg,
        &scene,
        0.0,
        &mut datasets_synth::rng::SampleRng::new(1, 2, 0),
    );
    // Centre pixel, away from the glare: albedo 0.8 * (0.25 + sin 30) = 0.6 -> 153.
    let i = (90 * 320 + 160) * 3;
    assert_eq!(&rest.rgb[i..i + 3], &[153, 153, 153]);
    assert!(!rest.tendon && rest.mask.iter().all(|&m| m == 0));
    let pressed = visuotactile::render(
        &cfg,
        &scene,
        3.0,
        &mut datasets_synth::rng::SampleRng::new(1, 2, 0),
    );
    let diff: u64 = pressed
        .rgb
        .iter()
        .zip(&rest.rgb)
        .map(|(a, b)| a.abs_diff(*b) as u64)
        .sum();
    assert!(diff > 1000, "contact changed the image by only {diff}");
}

#[test]
fn native_resolution_frame_renders() {
    let cfg = VisuotactileConfig {
        width: 1920,
        height: 1080,
        press_mm: Range::new(2.0, 3.0),
        out_of_view_fraction: 0.0,
        frames_per_sequence: 1,
        ..Default::default()
    };
    cfg.validate().unwrap();
    let (_, f) = visuotactile::sample(&cfg, 3, 0, 0);
    assert_eq!((f.width, f.height), (1920, 1080));
    assert_eq!(f.rgb.len(), 1920 * 1080 * 3);
    assert!(f.tendon);
    assert!(f.depth_m.iter().all(|d| (0.012..=0.018).contains(d)));
}

#[test]
fn force_grows_with_depth() {
    for shape in [
        Shape::Sphere { radius_mm: 6.0 },
        Shape::Cylinder { radius_mm: 4.0 },
        Shape::Cuboid,
        Shape::Prism,
        Shape::Edge,
        Shape::Flat,
    ] {
        let forces: Vec<f64> = [0.5, 1.5, 2.5, 3.5, 4.5]
            .iter()
            .map(|&d| {
                let mut scene = TactipScene::clean(shape, 1.0, -2.0, 30.0, d);
                scene.force_noise = 0.02;
                scene.force_noise_draw = if d > 2.0 { -2.0 } else { 2.0 }; // adversarial noise
                let mut rng = datasets_synth::rng::SampleRng::new(0, 0, 0);
                tactip::render(&scene, &mut rng).force_n
            })
            .collect();
        assert!(
            forces.windows(2).all(|w| w[1] > w[0]),
            "{}: {forces:?}",
            shape.name()
        );
    }
}

#[test]
fn pins_move_away_from_a_sphere_and_grow_under_it() {
    let contact = (2.0, -1.5);
    let scene = TactipScene::clean(
        Shape::Sphere { radius_mm: 6.0 },
        contact.0,
        contact.1,
        0.0,
        3.0,
    );
    let field = PenetrationField::new(&scene);
    let moved = tactip::deform_pins(&field);
    let rest = tactip::pin_rest_positions_mm();
    let (mut checked, mut cos_sum) = (0, 0.0);
    for (pin, &(x, y)) in moved.iter().zip(&rest) {
        let (u0, v0) = tactip::mm_to_px(x, y);
        let (du, dv) = (pin.u - u0, pin.v - v0);
        let (rx, ry) = (x - contact.0, y - contact.1);
        let dist = (rx * rx + ry * ry).sqrt();
        if (1.5..6.0).contains(&dist) {
            // Outward: the displacement points away from the contact point
            // (first touch sits a little toward the apex of the tilted tip).
            let cos = (du * rx + dv * ry) / ((du * du + dv * dv).sqrt() * dist);
            assert!(cos > 0.8, "pin at ({x:.1}, {y:.1}): cos {cos:.3}");
            cos_sum += cos;
            assert!(pin.radius_px > tactip::PIN_RADIUS_MM * tactip::PX_PER_MM);
            checked += 1;
        }
        if dist > 14.0 {
            assert!((du * du + dv * dv).sqrt() < 0.05, "far pin moved");
        }
    }
    assert!(checked >= 6, "{checked}");
    assert!(
        cos_sum / checked as f64 > 0.97,
        "mean cos {}",
        cos_sum / checked as f64
    );
}

#[test]
fn tactip_labels_follow_the_spec() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tt");
    datasets_synth::write_tactip(
        &TactipConfig::default(),
        40,
        3,
        &out,
        WriteOptions::default(),
    )
    .unwrap();
    let ds = Dataset::open(&out).unwrap();
    let mut shapes = std::collections::BTreeSet::new();
    for i in 0..ds.len() {
        let shape = ds.text(i, "shape").unwrap().to_string();
        let depth = ds.number(i, "depth_mm").unwrap();
        assert!((0.0..=5.0).contains(&depth));
        assert!(ds.number(i, "force_n").unwrap() >= 0.0);
        match shape.as_str() {
            "edge" => assert_eq!(ds.number(i, "y_mm").unwrap(), 0.0),
            "sphere" => {
                assert!(ds.number_opt(i, "theta_deg").unwrap().is_none());
                assert!((4.0..=10.0).contains(&ds.number(i, "radius_mm").unwrap()));
            }
            "flat" => assert!(ds.number_opt(i, "x_mm").unwrap().is_none()),
            _ => {
                let x = ds.number(i, "x_mm").unwrap();
                assert!(x.abs() <= 6.0);
                assert!((0.0..180.0).contains(&ds.number(i, "theta_deg").unwrap()));
            }
        }
        let img = load_grey(ds.path_of(i, "file").unwrap()).unwrap();
        assert_eq!((img.width(), img.height()), (300, 300));
        shapes.insert(shape);
    }
    assert!(shapes.len() >= 6, "{shapes:?}");
}

#[test]
fn same_seed_same_bytes_and_extending_keeps_earlier_samples() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = small_visuo();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    datasets_synth::write_visuotactile(&cfg, 10, 9, &a, WriteOptions::default()).unwrap();
    datasets_synth::write_visuotactile(&cfg, 14, 9, &b, WriteOptions::default()).unwrap();
    for i in 0..10 {
        for f in [
            format!("frames/{i:06}.png"),
            format!("masks/{i:06}.png"),
            format!("depth/{i:06}.npy"),
        ] {
            assert_eq!(
                std::fs::read(a.join(&f)).unwrap(),
                std::fs::read(b.join(&f)).unwrap(),
                "{f}"
            );
        }
    }
    let la = std::fs::read_to_string(a.join("labels.csv")).unwrap();
    let lb = std::fs::read_to_string(b.join("labels.csv")).unwrap();
    assert!(lb.starts_with(&la));
    let (t1, t2) = (dir.path().join("t1"), dir.path().join("t2"));
    datasets_synth::write_tactip(&TactipConfig::default(), 3, 9, &t1, WriteOptions::default())
        .unwrap();
    datasets_synth::write_tactip(&TactipConfig::default(), 5, 9, &t2, WriteOptions::default())
        .unwrap();
    for i in 0..3 {
        let f = format!("frames/{i:06}.png");
        assert_eq!(
            std::fs::read(t1.join(&f)).unwrap(),
            std::fs::read(t2.join(&f)).unwrap()
        );
    }
}

#[test]
fn numpy_reads_the_depth_maps() {
    // numpy comes with the onnx wheel that scripts/install-ort.sh installs.
    let pythonpath = std::env::var_os("TACTILE_PYTHONPATH")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../.ort"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("vt");
    let cfg = VisuotactileConfig {
        frames_per_sequence: 1,
        press_mm: Range::new(3.0, 3.0),
        ..small_visuo()
    };
    datasets_synth::write_visuotactile(&cfg, 1, 4, &out, WriteOptions::default()).unwrap();
    let (_, _, ours) = datasets_synth::npy::read_depth_npy(out.join("depth/000000.npy")).unwrap();
    let run = std::process::Command::new("python3")
        .env("PYTHONPATH", &pythonpath)
        .args([
            "-c",
            "import sys, numpy as np; a = np.load(sys.argv[1]); \
             print(a.dtype, a.shape, repr(float(a.min())), repr(float(a.max())))",
        ])
        .arg(out.join("depth/000000.npy"))
        .output()
        .expect("python3");
    let text = String::from_utf8_lossy(&run.stdout).to_string();
    assert!(
        run.status.success(),
        "numpy could not read the depth map (run the tests through scripts/test.sh, \
         which installs numpy): {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let parts: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(parts[0], "float32", "{text}");
    assert_eq!(parts[1..3].join(" "), "(180, 320)", "{text}");
    let lo = ours.iter().copied().fold(f32::MAX, f32::min) as f64;
    assert_eq!(parts[3].parse::<f64>().unwrap(), lo, "{text}");
}

#[test]
fn the_alternate_renderer_draws_the_same_scene_with_the_same_labels() {
    let reference = VisuotactileConfig {
        press_mm: Range::new(1.0, 3.0),
        ..small_visuo()
    };
    let alternate = VisuotactileConfig {
        renderer: visuotactile::Renderer::Alternate,
        ..reference.clone()
    };
    let mut tendons = 0;
    for seq in 0..4 {
        for frame in [0, 3, 5] {
            let (_, a) = visuotactile::sample(&reference, 11, seq, frame);
            let (_, b) = visuotactile::sample(&alternate, 11, seq, frame);
            // Labels are geometry: identical.
            assert_eq!(a.mask, b.mask);
            assert_eq!(a.tendon, b.tendon);
            assert_eq!(a.direction_deg, b.direction_deg);
            assert_eq!(a.depth_m, b.depth_m);
            tendons += usize::from(a.tendon);
            // The pictures differ (another raster and shading path) but
            // show the same skin: a few levels apart on average.
            let diff: f64 = a
                .rgb
                .iter()
                .zip(&b.rgb)
                .map(|(x, y)| x.abs_diff(*y) as f64)
                .sum::<f64>()
                / a.rgb.len() as f64;
            assert!(
                diff > 0.3 && diff < 8.0,
                "sequence {seq} frame {frame}: {diff}"
            );
        }
    }
    assert!(tendons > 0);
    let bad: Result<visuotactile::Renderer, _> = "raytraced".parse();
    assert!(
        bad.unwrap_err()
            .to_string()
            .contains("reference, alternate")
    );
}

#[test]
fn tendons_just_outside_the_window_are_tendons_by_the_spec_labels() {
    // Out of view at the default margin (1.6-3.6 w): no ridge over the
    // mask's threshold inside the window, so a negative. Nearer (0-1 w),
    // its flank reaches over the rim and the spec's rule makes it a tendon
    // whose mask is a band along the rim, away from the centre.
    let outside = |margin| VisuotactileConfig {
        press_mm: Range::fixed(3.0),
        out_of_view_fraction: 1.0,
        out_of_view_margin_w: margin,
        frames_per_sequence: 1,
        ..small_visuo()
    };
    let (far, near) = (outside(Range::new(1.6, 3.6)), outside(Range::new(0.0, 1.0)));
    assert!(near.validate().is_ok());
    for seq in 0..12 {
        let (_, f) = visuotactile::sample(&far, 7, seq, 0);
        assert!(
            !f.tendon && f.mask.iter().all(|&m| m == 0),
            "sequence {seq}"
        );
        assert!(f.ridge_mm >= 0.03);
        let (_, f) = visuotactile::sample(&near, 7, seq, 0);
        assert!(f.tendon, "sequence {seq}: the ridge reaches over the rim");
        let (w, h) = (f.width as f64, f.height as f64);
        for (i, _) in f.mask.iter().enumerate().filter(|(_, m)| **m > 0) {
            let (u, v) = (
                (i % f.width) as f64 - (w - 1.0) / 2.0,
                (i / f.width) as f64 - (h - 1.0) / 2.0,
            );
            let r = (u / (w / 2.0)).powi(2) + (v / (h / 2.0)).powi(2);
            assert!(r > 0.09, "sequence {seq}: mask pixel {i} near the centre");
        }
    }
    let bad = outside(Range::new(-1.0, 1.0))
        .validate()
        .unwrap_err()
        .to_string();
    assert!(bad.contains("out_of_view_margin_w"), "{bad}");
}
