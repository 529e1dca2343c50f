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
    /// Legend entry.
    pub name: String,
    /// The points, in drawing order.
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

/// Bounds that hold every point with a margin: 5 % of the span on each
/// side (on a log axis, of the span of the logarithms), and a visible span
/// around a single value.
fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (a, b) = padded(lo.log10(), hi.log10(), false);
        return (10f64.powf(a), 10f64.powf(b));
    }
    let span = hi - lo;
    if span > 0.0 {
        (lo - 0.05 * span, hi + 0.05 * span)
    } else {
        let half = (lo.abs() * 0.1).max(1e-6);
        (lo - half, hi + half)
    }
}

/// Tick label of `v` on an axis whose ticks are about `step` apart: whole
/// numbers without decimals, otherwise as many decimals as the step needs.
fn tick_label(v: f64, step: f64, integers: bool) -> String {
    if integers {
        return format!("{}", v.round() as i64);
    }
    let decimals = if step > 0.0 && step.is_finite() {
        (-(step.log10().floor()) as i32).clamp(0, 6) as usize
    } else {
        2
    };
    format!("{v:.decimals$}")
}

/// Tick label of `v` on an axis spanning `span`, whatever step the ticks
/// take (1, 2, 2.5 or 5 times a power of ten): one decimal more than a
/// tenth of the span needs, trailing zeros dropped (`-25`, `2.5`, `0.3`).
fn trimmed_tick_label(v: f64, span: f64) -> String {
    let label = tick_label(v, span / 100.0, false);
    let label = if label.contains('.') {
        label.trim_end_matches('0').trim_end_matches('.')
    } else {
        label.as_str()
    };
    if label == "-0" {
        "0".into()
    } else {
        label.into()
    }
}

/// The corner of the plot with the fewest points under where a legend
/// would go, so the legend hides none it can avoid.
fn legend_corner(
    pts: &[(f64, f64)],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    log_y: bool,
) -> SeriesLabelPosition {
    let ny = |y: f64| {
        if log_y {
            (y.log10() - y0.log10()) / (y1.log10() - y0.log10())
        } else {
            (y - y0) / (y1 - y0)
        }
    };
    let under = |left: bool, top: bool| {
        pts.iter()
            .filter(|&&(x, y)| {
                let (u, v) = ((x - x0) / (x1 - x0), ny(y));
                (if left { u < 0.35 } else { u > 0.65 }) && (if top { v > 0.7 } else { v < 0.3 })
            })
            .count()
    };
    [
        (SeriesLabelPosition::UpperRight, under(false, true)),
        (SeriesLabelPosition::UpperLeft, under(true, true)),
        (SeriesLabelPosition::LowerRight, under(false, false)),
        (SeriesLabelPosition::LowerLeft, under(true, false)),
    ]
    .into_iter()
    .min_by_key(|c| c.1)
    .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
}

/// Draw `series` as lines with a dot at every point and save a PNG
/// atomically. `log_y` plots the y axis logarithmically (losses). The
/// axes hold every point, tick labels are plain numbers (whole numbers on
/// an axis of whole numbers, such as epochs), and each legend entry shows
/// its series' line and dot.
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
    let keep = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0);
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(keep)
        .copied()
        .collect();
    if pts.is_empty() {
        return Err(Error::Invalid(format!(
            "{}: nothing to plot",
            path.display()
        )));
    }
    let fold = |f: fn(&(f64, f64)) -> f64| {
        pts.iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (x0, x1) = fold(|p| p.0);
    let (y0, y1) = fold(|p| p.1);
    let x_integers = pts.iter().all(|p| p.0.fract() == 0.0);
    let (x0, x1) = padded(x0, x1, false);
    let (y0, y1) = padded(y0, y1, log_y);
    let (x_step, y_step) = ((x1 - x0) / 10.0, (y1 - y0) / 10.0);
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
        let x_fmt = |v: &f64| tick_label(*v, x_step, x_integers);
        let y_fmt = |v: &f64| {
            if log_y {
                // A log axis spans decades: each label to its own scale.
                tick_label(*v, v.abs() / 10.0, false)
            } else {
                tick_label(*v, y_step, false)
            }
        };
        let corner = legend_corner(&pts, (x0, x1), (y0, y1), log_y);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                let mut mesh = chart.configure_mesh();
                if text {
                    mesh.x_desc(x_label)
                        .y_desc(y_label)
                        .x_label_formatter(&x_fmt)
                        .y_label_formatter(&y_fmt);
                } else {
                    mesh.disable_x_axis().disable_y_axis();
                }
                mesh.draw()?;
                for (i, s) in series.iter().enumerate() {
                    let c = COLOURS[i % COLOURS.len()];
                    let pts: Vec<(f64, f64)> = s.points.iter().filter(keep).copied().collect();
                    let line =
                        chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?;
                    if text {
                        line.label(s.name.as_str()).legend(move |(x, y)| {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (20, 0)], c.stroke_width(2))
                                + Circle::new((10, 0), 3, c.filled())
                        });
                    }
                    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
                }
                if text {
                    chart
                        .configure_series_labels()
                        .position(corner)
                        .background_style(WHITE.mix(0.8))
                        .border_style(BLACK)
                        .draw()?;
                }
            }};
        }
        if log_y {
            body!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())?);
        } else {
            body!(builder.build_cartesian_2d(x0..x1, y0..y1)?);
        }
        root.present()?;
        Ok(())
    };
    let drawn = draw().map_err(|e| e.to_string());
    drawn.map_err(|e| Error::Invalid(format!("{}: cannot draw plot: {e}", path.display())))?;
    crate::image_io::save_rgb_png(path, w as usize, h as usize, &buf)
}

/// One panel of [`scatter_grid`]: predictions against the truth of one
/// target, each point coloured by its absolute error.
pub struct ScatterPanel {
    /// Panel title (the target and its error).
    pub title: String,
    /// `(truth, prediction)` points.
    pub points: Vec<(f64, f64)>,
}

/// Panels of predicted against true values side by side (`columns` per
/// row), each with the identity line and its points coloured from dark
/// (exact) to yellow (the panel's 95th percentile error or worse), saved as
/// a PNG atomically: the error plots of pose papers.
pub fn scatter_grid(path: impl AsRef<Path>, panels: &[ScatterPanel], columns: usize) -> Result<()> {
    let path = path.as_ref();
    let columns = columns.clamp(1, 8);
    let rows = panels.len().div_ceil(columns).max(1);
    let (pw, ph) = (360u32, 340u32);
    let (w, h) = (pw * columns as u32, ph * rows as u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let text = font_available();
    let mut draw = || -> std::result::Result<(), Box<dyn std::error::Error + '_>> {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let areas = root.split_evenly((rows, columns));
        for (panel, area) in panels.iter().zip(areas) {
            let pts: Vec<(f64, f64)> = panel
                .points
                .iter()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .copied()
                .collect();
            if pts.is_empty() {
                continue;
            }
            let (lo, hi) = pts
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.0).min(p.1), b.max(p.0).max(p.1))
                });
            let (lo, hi) = padded(lo, hi, false);
            let mut err: Vec<f64> = pts.iter().map(|p| (p.1 - p.0).abs()).collect();
            err.sort_by(f64::total_cmp);
            let top = err[((err.len() as f64 * 0.95) as usize).min(err.len() - 1)].max(1e-12);
            let mut builder = ChartBuilder::on(&area);
            builder
                .margin(10)
                .x_label_area_size(if text { 30 } else { 5 })
                .y_label_area_size(if text { 45 } else { 5 });
            if text {
                builder.caption(panel.title.as_str(), ("sans-serif", 16));
            }
            let mut chart = builder.build_cartesian_2d(lo..hi, lo..hi)?;
            let mut mesh = chart.configure_mesh();
            mesh.disable_mesh();
            // Six ticks a side: ten labels such as "-25.0" overlap in a panel.
            let fmt = |v: &f64| trimmed_tick_label(*v, hi - lo);
            if text {
                mesh.x_desc("true")
                    .y_desc("predicted")
                    .x_labels(6)
                    .y_labels(6)
                    .x_label_formatter(&fmt)
                    .y_label_formatter(&fmt);
            } else {
                mesh.disable_x_axis().disable_y_axis();
            }
            mesh.draw()?;
            chart.draw_series(pts.iter().map(|&(t, p)| {
                let [r, g, b] = colour(((p - t).abs() / top).min(1.0));
                Circle::new((t, p), 1, RGBColor(r, g, b).filled())
            }))?;
            chart.draw_series(LineSeries::new(
                vec![(lo, lo), (hi, hi)],
                BLACK.stroke_width(1),
            ))?;
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
        /// Start, pixels.
        from: (i32, i32),
        /// End, pixels.
        to: (i32, i32),
        /// RGB.
        colour: [u8; 3],
        /// Stroke width, pixels.
        width: u32,
    },
    /// A filled dot.
    Dot {
        /// Centre, pixels.
        at: (i32, i32),
        /// Radius, pixels.
        radius: u32,
        /// RGB.
        colour: [u8; 3],
    },
    /// Text with its top-left corner at `at` (skipped when no font is found).
    Text {
        /// Top-left corner, pixels.
        at: (i32, i32),
        /// The words.
        text: String,
        /// Font size, pixels.
        size: u32,
        /// RGB.
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

/// Heat maps side by side, each `zoom` times enlarged, on one colour
/// scale over `range` (or their own range, 0 included), with a colour bar
/// on the right labelled with its values and `unit` (e.g.
/// "displacement, mm"). Written as PNG; without a font, without text.
pub fn heat_maps_with_bar(
    path: impl AsRef<Path>,
    maps: &[&[f32]],
    (w, h): (usize, usize),
    zoom: usize,
    unit: &str,
) -> Result<()> {
    if maps.is_empty() || maps.iter().any(|m| m.len() != w * h) || w == 0 || h == 0 {
        return Err(Error::Invalid(format!("heat maps must all be {w}x{h}")));
    }
    let (lo, hi) = colour_range(maps.iter().flat_map(|m| m.iter().copied()));
    let zoom = zoom.clamp(1, 16);
    let (zw, zh) = (w * zoom, h * zoom);
    let gap = 6;
    let width = maps.len() * (zw + gap) + COLOUR_BAR_WIDTH;
    let mut rgb = vec![255u8; width * zh * 3];
    let t = |v: f64| (v - lo) / (hi - lo);
    for (k, m) in maps.iter().enumerate() {
        for y in 0..zh {
            for x in 0..zw {
                let c = colour(t(m[(y / zoom) * w + x / zoom] as f64));
                let o = (y * width + k * (zw + gap) + x) * 3;
                rgb[o..o + 3].copy_from_slice(&c);
            }
        }
    }
    draw_colour_bar(&mut rgb, width, zh, maps.len() * (zw + gap), (lo, hi), unit)?;
    crate::image_io::save_rgb_png(path, width, zh, &rgb)
}

/// Pixels a colour bar with its labels takes ([`draw_colour_bar`]).
pub const COLOUR_BAR_WIDTH: usize = 16 + 185;

/// A vertical colour bar for values `lo..hi` (high at the top) at column
/// `x0` of an RGB buffer `width x height`, its values at five ticks and
/// `unit` beside it; it takes [`COLOUR_BAR_WIDTH`] columns.
pub fn draw_colour_bar(
    rgb: &mut [u8],
    width: usize,
    height: usize,
    x0: usize,
    (lo, hi): (f64, f64),
    unit: &str,
) -> Result<()> {
    let bar = 16;
    if x0 + COLOUR_BAR_WIDTH > width || rgb.len() != width * height * 3 || height == 0 {
        return Err(Error::Invalid(format!(
            "a colour bar at column {x0} does not fit a {width}x{height} image"
        )));
    }
    for y in 0..height {
        let c = colour(1.0 - y as f64 / (height - 1).max(1) as f64);
        for x in x0..x0 + bar {
            let o = (y * width + x) * 3;
            rgb[o..o + 3].copy_from_slice(&c);
        }
    }
    let x_text = (x0 + bar + 4) as i32;
    // Tick labels stay inside the image (also when it is shorter than a label).
    let tick_y = |k: usize| {
        let y = ((height - 1) as f64 * k as f64 / 4.0) as i32 - 6;
        y.min(height as i32 - 14).max(0)
    };
    let mut marks: Vec<Mark> = (0..=4)
        .map(|k| Mark::Text {
            at: (x_text, tick_y(k)),
            text: format!("{:.2}", hi - (hi - lo) * k as f64 / 4.0),
            size: 13,
            colour: [0, 0, 0],
        })
        .collect();
    marks.push(Mark::Text {
        at: (x_text + 46, height as i32 / 2 - 6),
        text: unit.to_string(),
        size: 13,
        colour: [0, 0, 0],
    });
    draw_marks(rgb, width, height, &marks)
}

/// The finite range of `values` with 0 inside it (displacements start
/// from rest); never empty.
pub fn colour_range(values: impl Iterator<Item = f32>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((0.0f64, 0.0f64), |(a, b), v| {
            (a.min(v as f64), b.max(v as f64))
        });
    if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_hold_every_point_and_ticks_are_plain_numbers() {
        let (a, b) = padded(1.0, 3.0, false);
        assert!(a < 1.0 && b > 3.0);
        let (a, b) = padded(2.0, 2.0, false);
        assert!(a < 2.0 && b > 2.0);
        let (a, b) = padded(0.01, 1.0, true);
        assert!(a < 0.01 && b > 1.0 && a > 0.0);
        assert_eq!(tick_label(4.0, 2.0, true), "4");
        assert_eq!(tick_label(0.126, 0.01, false), "0.13");
        assert_eq!(tick_label(12.5, 5.0, false), "12");
        assert_eq!(trimmed_tick_label(-25.0, 55.0), "-25");
        assert_eq!(trimmed_tick_label(2.5, 11.0), "2.5");
        assert_eq!(trimmed_tick_label(0.30000000000000004, 1.2), "0.3");
        assert_eq!(trimmed_tick_label(-0.0001, 1.2), "0");
        let d = tempfile::tempdir().unwrap();
        let one = [Series {
            name: "one point".into(),
            points: vec![(0.4, 1.0)],
        }];
        line_plot(d.path().join("p.png"), "t", "x", "y", &one, false).unwrap();
        line_plot(d.path().join("l.png"), "t", "x", "y", &one, true).unwrap();
    }
}
