//! Small line plots (training curves, error-vs-size sweeps) written as PNG.
//!
//! Text needs a TrueType font; the first common system font found is used.
//! On a machine without one the plot is still drawn, without text.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use crate::{Error, Result};

const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
];

fn font_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        for p in FONT_CANDIDATES {
            if let Ok(bytes) = std::fs::read(p) {
                let leaked: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, leaked).is_ok() {
                    return true;
                }
            }
        }
        false
    })
}

/// One named line of `(x, y)` points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Draw `series` as lines (with point markers) and save a PNG atomically.
/// `log_y` plots the y axis logarithmically (losses).
pub fn line_plot(
    path: impl AsRef<Path>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_y: bool,
) -> Result<()> {
    let path = path.as_ref();
    let (w, h) = (900u32, 560u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let pts = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in pts {
        if log_y && y <= 0.0 {
            continue;
        }
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        return Err(Error::Invalid(format!(
            "{}: nothing to plot",
            path.display()
        )));
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + y0.abs().max(1e-6);
    }
    let text = font_available();
    let mut draw = || -> std::result::Result<(), Box<dyn std::error::Error + '_>> {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .margin(20)
            .x_label_area_size(if text { 45 } else { 5 })
            .y_label_area_size(if text { 70 } else { 5 });
        if text {
            builder.caption(title, ("sans-serif", 24));
        }
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                let mut mesh = chart.configure_mesh();
                if text {
                    mesh.x_desc(x_label).y_desc(y_label);
                } else {
                    mesh.disable_x_axis().disable_y_axis();
                }
                mesh.draw()?;
                for (i, s) in series.iter().enumerate() {
                    let c = COLOURS[i % COLOURS.len()];
                    let pts: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0))
                        .collect();
                    let line =
                        chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?;
                    if text {
                        line.label(s.name.as_str()).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                        });
                    }
                    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
                }
                if text {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.8))
                        .border_style(BLACK)
                        .draw()?;
                }
            }};
        }
        if log_y {
            body!(builder.build_cartesian_2d(x0..x1, (y0 * 0.9..y1 * 1.1).log_scale())?);
        } else {
            let pad = (y1 - y0) * 0.05;
            body!(builder.build_cartesian_2d(x0..x1, y0 - pad..y1 + pad)?);
        }
        root.present()?;
        Ok(())
    };
    let drawn = draw().map_err(|e| e.to_string());
    drawn.map_err(|e| Error::Invalid(format!("{}: cannot draw plot: {e}", path.display())))?;
    crate::image_io::save_rgb_png(path, w as usize, h as usize, &buf)
}

/// Something to draw over an image (contact sheets, overlays).
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// A straight line, pixel coordinates.
    Line {
        from: (i32, i32),
        to: (i32, i32),
        colour: [u8; 3],
        width: u32,
    },
    /// A filled dot.
    Dot {
        at: (i32, i32),
        radius: u32,
        colour: [u8; 3],
    },
    /// Text with its top-left corner at `at` (skipped when no font is found).
    Text {
        at: (i32, i32),
        text: String,
        size: u32,
        colour: [u8; 3],
    },
}

/// Draw `marks` over an RGB buffer in place.
pub fn draw_marks(rgb: &mut [u8], width: usize, height: usize, marks: &[Mark]) -> Result<()> {
    if rgb.len() != width * height * 3 {
        return Err(Error::shape("RGB buffer", width * height * 3, rgb.len()));
    }
    let text = font_available();
    let mut draw = || -> std::result::Result<(), Box<dyn std::error::Error + '_>> {
        let root =
            BitMapBackend::with_buffer(rgb, (width as u32, height as u32)).into_drawing_area();
        for m in marks {
            match m {
                Mark::Line {
                    from,
                    to,
                    colour,
                    width,
                } => {
                    let c = RGBColor(colour[0], colour[1], colour[2]);
                    root.draw(&PathElement::new(vec![*from, *to], c.stroke_width(*width)))?;
                }
                Mark::Dot { at, radius, colour } => {
                    let c = RGBColor(colour[0], colour[1], colour[2]);
                    root.draw(&Circle::new(*at, *radius, c.filled()))?;
                }
                Mark::Text {
                    at,
                    text: t,
                    size,
                    colour,
                } if text => {
                    let c = RGBColor(colour[0], colour[1], colour[2]);
                    root.draw(&Text::new(
                        t.clone(),
                        *at,
                        ("sans-serif", *size).into_font().color(&c),
                    ))?;
                }
                Mark::Text { .. } => {}
            }
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| Error::Invalid(format!("cannot draw overlay: {e}")))
}

/// A perceptually ordered colour (dark blue -> teal -> yellow, close to
/// viridis) for `t` in [0, 1].
pub fn colour(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let mut out = [0u8; 3];
    for (c, o) in out.iter_mut().enumerate() {
        *o = (STOPS[i][c] * (1.0 - f) + STOPS[i + 1][c] * f).round() as u8;
    }
    out
}

/// Maps of the same size side by side as heat maps on one shared colour
/// scale (min to max over all of them), 4 px apart, saved atomically.
pub fn heat_maps(path: impl AsRef<Path>, maps: &[&[f32]], (w, h): (usize, usize)) -> Result<()> {
    if maps.is_empty() || maps.iter().any(|m| m.len() != w * h) {
        return Err(Error::Invalid(format!("heat maps must all be {w}x{h}")));
    }
    let (lo, hi) = maps
        .iter()
        .flat_map(|m| m.iter())
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v as f64), b.max(v as f64))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let gap = 4;
    let width = maps.len() * w + (maps.len() - 1) * gap;
    let mut rgb = vec![255u8; width * h * 3];
    for (k, m) in maps.iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                let c = colour((m[y * w + x] as f64 - lo) / span);
                let o = (y * width + k * (w + gap) + x) * 3;
                rgb[o..o + 3].copy_from_slice(&c);
            }
        }
    }
    crate::image_io::save_rgb_png(path, width, h, &rgb)
}
