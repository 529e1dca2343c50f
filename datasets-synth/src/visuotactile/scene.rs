//! The phantom and palpation of one video: the tendon's centre line
//! (straight or curved pieces), its placement, and the press over time.

use std::f64::consts::PI;

use crate::rng::SampleRng;

use super::camera::{Camera, P2, add, dot, perp, scale, sub, unit_at};
use super::*;

/// One piece of a centre line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Piece {
    /// From `start` along unit `dir` for `length` mm.
    Segment { start: P2, dir: P2, length: f64 },
    /// Circle arc about `centre`: angles `start_angle` .. `start_angle + sweep`.
    Arc {
        centre: P2,
        radius: f64,
        start_angle: f64,
        sweep: f64,
    },
}

impl Piece {
    fn nearest(&self, p: P2) -> P2 {
        match *self {
            Piece::Segment { start, dir, length } => {
                let t = dot(sub(p, start), dir).clamp(0.0, length);
                add(start, scale(dir, t))
            }
            Piece::Arc {
                centre,
                radius,
                start_angle,
                sweep,
            } => {
                let d = sub(p, centre);
                let a = libm::atan2(d.1, d.0);
                let rel = (sweep.signum() * (a - start_angle)).rem_euclid(2.0 * PI);
                if rel <= sweep.abs() {
                    add(centre, scale(unit_at(a), radius))
                } else {
                    let s = add(centre, scale(unit_at(start_angle), radius));
                    let e = add(centre, scale(unit_at(start_angle + sweep), radius));
                    let ds = dot(sub(p, s), sub(p, s));
                    let de = dot(sub(p, e), sub(p, e));
                    if ds <= de { s } else { e }
                }
            }
        }
    }
}

/// A tendon centre line in skin-plane mm (x right, y down).
#[derive(Debug, Clone, PartialEq)]
pub struct CentreLine {
    pieces: Vec<Piece>,
    /// The point nearest the frame centre and the unit tangent there.
    pub anchor: P2,
    /// The unit tangent there.
    pub tangent: P2,
}

impl CentreLine {
    /// A straight line through `anchor` along `tangent`.
    pub fn straight(anchor: P2, tangent: P2) -> Self {
        Self {
            pieces: vec![Piece::Segment {
                start: sub(anchor, scale(tangent, RAY_MM)),
                dir: tangent,
                length: 2.0 * RAY_MM,
            }],
            anchor,
            tangent,
        }
    }

    /// Arcs of radius `radius` on both sides of `anchor`, each turning
    /// through `half_angle`, then straight on. `bend` is +1/-1 (which side
    /// the forward half curves to); `s_curve` makes the backward half curve
    /// the other way.
    pub fn curved(
        anchor: P2,
        tangent: P2,
        radius: f64,
        half_angle: f64,
        bend: f64,
        s_curve: bool,
    ) -> Self {
        let mut pieces = Vec::new();
        // Forward half along +tangent, backward half along -tangent. For one
        // circle the backward half (walking -tangent) bends the other way.
        let halves = [
            (tangent, bend),
            (scale(tangent, -1.0), if s_curve { bend } else { -bend }),
        ];
        for (dir, sign) in halves {
            let centre = add(anchor, scale(perp(dir), sign * radius));
            let d = sub(anchor, centre);
            let start_angle = libm::atan2(d.1, d.0);
            let sweep = sign * half_angle;
            let end_angle = start_angle + sweep;
            let end = add(centre, scale(unit_at(end_angle), radius));
            let end_dir = scale((-libm::sin(end_angle), libm::cos(end_angle)), sign);
            pieces.push(Piece::Arc {
                centre,
                radius,
                start_angle,
                sweep,
            });
            pieces.push(Piece::Segment {
                start: end,
                dir: end_dir,
                length: RAY_MM,
            });
        }
        Self {
            pieces,
            anchor,
            tangent,
        }
    }

    /// The nearest point of the line to `p`.
    pub fn nearest(&self, p: P2) -> P2 {
        let mut best = self.anchor;
        let mut best_d = f64::INFINITY;
        for piece in &self.pieces {
            let q = piece.nearest(p);
            let d = dot(sub(p, q), sub(p, q));
            if d < best_d {
                best_d = d;
                best = q;
            }
        }
        best
    }

    /// Image direction of the line at its anchor, degrees in `[0, 180)`.
    pub fn direction_deg(&self) -> f64 {
        fold_180(libm::atan2(self.tangent.1, self.tangent.0).to_degrees())
    }
}

/// Fold an angle in degrees into `[0, 180)`.
pub fn fold_180(deg: f64) -> f64 {
    let f = deg.rem_euclid(180.0);
    if f >= 180.0 { 0.0 } else { f }
}

/// The phantom and palpation of one video.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceScene {
    /// The centre line's family.
    pub path: TendonPath,
    /// Tendon radius, mm.
    pub tendon_radius_mm: f64,
    /// Burial depth, mm.
    pub burial_mm: f64,
    /// Radius of curvature of curved paths, mm.
    pub curvature_radius_mm: f64,
    /// The centre line.
    pub line: CentreLine,
    /// False when the centre line stays outside the window.
    pub in_view: bool,
    /// Peak press of the video, mm.
    pub peak_press_mm: f64,
}

impl SequenceScene {
    /// Ridge width `w`, mm.
    pub fn ridge_width_mm(&self) -> f64 {
        RIDGE_WIDTH.0 * self.tendon_radius_mm + RIDGE_WIDTH.1 * self.burial_mm
    }

    /// Ridge amplitude `A` at `press`, mm.
    pub fn ridge_amplitude_mm(&self, press_mm: f64) -> f64 {
        if press_mm <= 0.0 {
            0.0
        } else {
            RIDGE_GAIN * press_mm * self.tendon_radius_mm / (self.tendon_radius_mm + self.burial_mm)
        }
    }

    /// Draw the phantom of a sequence. The draw order is fixed.
    pub fn draw(config: &VisuotactileConfig, camera: &Camera, rng: &mut SampleRng) -> Self {
        let path = config.paths[rng.index(config.paths.len())];
        let tendon_radius_mm = rng.draw(config.tendon_radius_mm);
        let burial_mm = rng.draw(config.burial_mm);
        let curvature_radius_mm = rng.draw(config.curvature_radius_mm);
        let peak_press_mm = rng.draw(config.press_mm);
        let in_view = !rng.chance(config.out_of_view_fraction);
        let psi = rng.uniform() * 2.0 * PI;
        let radial = unit_at(psi);
        let forward = rng.chance(0.5);
        let bend = if rng.chance(0.5) { 1.0 } else { -1.0 };
        let offset_u = rng.uniform();
        let margin_u = rng.uniform();
        let half_width_mm = camera
            .to_mm(camera.cx + camera.width as f64 / 2.0, camera.cy)
            .0;
        let half_diag_mm = camera.r_max * NOMINAL_DEPTH_MM / camera.fx;
        // The tangent at the anchor is perpendicular to the radial direction,
        // so the anchor is the line's point nearest the frame centre.
        let tangent = if forward {
            perp(radial)
        } else {
            scale(perp(radial), -1.0)
        };
        let w = RIDGE_WIDTH.0 * tendon_radius_mm + RIDGE_WIDTH.1 * burial_mm;
        let (line, path) = if in_view {
            let anchor = scale(radial, offset_u * config.centre_fraction * half_width_mm);
            let half_angle = (half_diag_mm / curvature_radius_mm).min(PI / 2.0);
            let line = match path {
                TendonPath::Straight => CentreLine::straight(anchor, tangent),
                TendonPath::Arc => CentreLine::curved(
                    anchor,
                    tangent,
                    curvature_radius_mm,
                    half_angle,
                    bend,
                    false,
                ),
                TendonPath::SCurve => {
                    CentreLine::curved(anchor, tangent, curvature_radius_mm, half_angle, bend, true)
                }
            };
            (line, path)
        } else {
            // A straight tendon beyond the window: at the default margin
            // its mask-level ridge (|s| < 1.56 w) never reaches the ellipse.
            let (a, b) = camera.window_radii();
            let k = NOMINAL_DEPTH_MM / camera.fx;
            let support = libm::hypot(a * k * radial.0, b * k * radial.1);
            let anchor = scale(
                radial,
                support + config.out_of_view_margin_w.at(margin_u) * w,
            );
            (CentreLine::straight(anchor, tangent), TendonPath::Straight)
        };
        Self {
            path,
            tendon_radius_mm,
            burial_mm,
            curvature_radius_mm,
            line,
            in_view,
            peak_press_mm,
        }
    }
}

/// `press` at frame `index` of `frames`: from a quarter of the peak below
/// first touch up to the peak (40 % of the video), hold (20 %), and back.
pub fn press_profile(peak_mm: f64, index: usize, frames: usize) -> f64 {
    if frames <= 1 {
        return peak_mm;
    }
    let t = index as f64 / (frames - 1) as f64;
    let ramp = |s: f64| -0.25 + 1.25 * (s / 0.4).min(1.0);
    peak_mm * ramp(t.min(1.0 - t))
}
