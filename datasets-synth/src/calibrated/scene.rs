//! What presses a calibrated sensor in one palpation video: a tendon (a
//! cylinder along a straight or curved centre line), a sphere, a flat
//! punch, the rounded edge of a flat plate, or nothing; where, how hard,
//! and the optics' and gel's per-video variation.

use std::f64::consts::PI;

use crate::rng::SampleRng;
use crate::visuotactile::camera::{P2, perp, scale, sub, unit_at};
use crate::visuotactile::{CentreLine, TendonPath};

use super::CalibratedConfig;

/// The object of one video.
#[derive(Debug, Clone, PartialEq)]
pub enum Contact {
    /// A tendon: a cylinder of `radius_mm` along `line`.
    Tendon {
        /// Centre-line family.
        path: TendonPath,
        /// Cylinder radius, mm.
        radius_mm: f64,
        /// Centre line, frame-centred mm (x right, y down).
        line: CentreLine,
    },
    /// A sphere of `radius_mm` centred over `centre`.
    Sphere {
        /// Radius, mm.
        radius_mm: f64,
        /// Centre, frame-centred mm.
        centre: P2,
    },
    /// A flat cylindrical punch with a rounded edge.
    Punch {
        /// Radius, mm.
        radius_mm: f64,
        /// Edge fillet, mm.
        fillet_mm: f64,
        /// Centre, frame-centred mm.
        centre: P2,
    },
    /// A flat plate whose rounded edge crosses the frame: the plate lies
    /// on the side of `normal` from the edge line through `point`.
    Edge {
        /// A point of the edge line, mm.
        point: P2,
        /// Unit normal pointing onto the plate.
        normal: P2,
        /// Edge fillet, mm.
        fillet_mm: f64,
    },
    /// Nothing touches the skin.
    Nothing,
}

impl Contact {
    /// The scene kind's name (the `path` column: a tendon's path, else
    /// the object).
    pub fn name(&self) -> &'static str {
        match self {
            Contact::Tendon { path, .. } => path.name(),
            Contact::Sphere { .. } => "sphere",
            Contact::Punch { .. } => "punch",
            Contact::Edge { .. } => "flat",
            Contact::Nothing => "none",
        }
    }

    /// The object's surface at frame-centred `p` (mm), as its height above
    /// its lowest point, mm; `None` off the object.
    pub fn height_mm(&self, p: P2) -> Option<f64> {
        let round = |r: f64, d: f64| -> Option<f64> { (d < r).then(|| r - (r * r - d * d).sqrt()) };
        match self {
            Contact::Tendon {
                radius_mm, line, ..
            } => {
                let (dx, dy) = sub(p, line.nearest(p));
                round(*radius_mm, dx.hypot(dy))
            }
            Contact::Sphere { radius_mm, centre } => {
                let (dx, dy) = sub(p, *centre);
                round(*radius_mm, dx.hypot(dy))
            }
            Contact::Punch {
                radius_mm,
                fillet_mm,
                centre,
            } => {
                let (dx, dy) = sub(p, *centre);
                let past = dx.hypot(dy) - (radius_mm - fillet_mm);
                if past <= 0.0 {
                    Some(0.0)
                } else {
                    round(*fillet_mm, past)
                }
            }
            Contact::Edge {
                point,
                normal,
                fillet_mm,
            } => {
                // Distance onto the plate from where its rounding starts.
                let (dx, dy) = sub(p, *point);
                let inward = dx * normal.0 + dy * normal.1;
                if inward >= 0.0 {
                    Some(0.0)
                } else {
                    round(*fillet_mm, -inward)
                }
            }
            Contact::Nothing => None,
        }
    }

    /// The tendon's direction, degrees in `[0, 180)` (tendons only).
    pub fn direction_deg(&self) -> Option<f64> {
        match self {
            Contact::Tendon { line, .. } => Some(line.direction_deg()),
            _ => None,
        }
    }
}

/// One palpation video of a calibrated sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibratedScene {
    /// The object.
    pub contact: Contact,
    /// Peak press of the video (approach past first touch), mm.
    pub peak_press_mm: f64,
    /// Per-channel gain on the optics' colour change (this video's unit
    /// and lighting).
    pub optics_gain: [f64; 3],
    /// Factor on the gel's spread width.
    pub gel_sigma_factor: f64,
    /// Optical blur, pixels.
    pub blur_px: f64,
    /// Shift of the background, pixels (x, y).
    pub shift_px: (i64, i64),
}

impl CalibratedScene {
    /// Draw the video's scene; `half_mm` is the frame's half-size in mm.
    /// The draw order is fixed.
    pub fn draw(config: &CalibratedConfig, half_mm: P2, rng: &mut SampleRng) -> Self {
        let kind = rng.uniform();
        // One draw sets the press; an object's is at the same place in
        // its own range.
        let press_at = rng.uniform();
        let at = |r: crate::rng::Range| r.at(press_at);
        let mut optics_gain = [1.0; 3];
        for g in optics_gain.iter_mut() {
            *g = 1.0 + config.optics_jitter * (2.0 * rng.uniform() - 1.0);
        }
        let gel_sigma_factor = 1.0 + config.gel_jitter * (2.0 * rng.uniform() - 1.0);
        let blur_px = rng.draw(config.blur_px);
        let s = config.shift_px as f64;
        let shift_px = (
            (s * (2.0 * rng.uniform() - 1.0)).round() as i64,
            (s * (2.0 * rng.uniform() - 1.0)).round() as i64,
        );
        // Anywhere over the frame, within `fraction` of each half-size.
        let place = |rng: &mut SampleRng, fraction: f64| -> P2 {
            (
                half_mm.0 * fraction * (2.0 * rng.uniform() - 1.0),
                half_mm.1 * fraction * (2.0 * rng.uniform() - 1.0),
            )
        };
        let [t, sp, pu, ed, _] = config.scene_weights();
        let contact = if kind < t {
            let path = config.paths[rng.index(config.paths.len())];
            let radius_mm = rng.draw(config.tendon_radius_mm);
            let curvature = rng.draw(config.curvature_radius_mm);
            let psi = rng.uniform() * 2.0 * PI;
            let radial = unit_at(psi);
            let tangent = match rng.chance(0.5) {
                true => perp(radial),
                false => scale(perp(radial), -1.0),
            };
            let bend = if rng.chance(0.5) { 1.0 } else { -1.0 };
            let reach = half_mm.0.min(half_mm.1);
            // Out of view: the cylinder never reaches the frame.
            let offset = match rng.chance(config.out_of_view_fraction) {
                true => half_mm.0.hypot(half_mm.1) + radius_mm * (1.2 + rng.uniform()),
                false => rng.uniform() * config.centre_fraction * reach,
            };
            let anchor = scale(radial, offset);
            let half_angle = (half_mm.0.hypot(half_mm.1) / curvature).min(PI / 2.0);
            let line = match path {
                TendonPath::Straight => CentreLine::straight(anchor, tangent),
                TendonPath::Arc => {
                    CentreLine::curved(anchor, tangent, curvature, half_angle, bend, false)
                }
                TendonPath::SCurve => {
                    CentreLine::curved(anchor, tangent, curvature, half_angle, bend, true)
                }
            };
            Contact::Tendon {
                path,
                radius_mm,
                line,
            }
        } else if kind < t + sp {
            Contact::Sphere {
                radius_mm: rng.draw(config.sphere_radius_mm),
                centre: place(rng, 0.7),
            }
        } else if kind < t + sp + pu {
            let radius_mm = rng.draw(config.punch_radius_mm);
            Contact::Punch {
                radius_mm,
                fillet_mm: config.punch_fillet.at(rng.uniform()) * radius_mm,
                centre: place(rng, 0.6),
            }
        } else if kind < t + sp + pu + ed {
            let normal = unit_at(rng.uniform() * 2.0 * PI);
            let u = rng.uniform();
            let point = match config.plate_edge_reach {
                // The way to the frame's border along the normal.
                Some(r) => {
                    let border = normal.0.abs() * half_mm.0 + normal.1.abs() * half_mm.1;
                    scale(normal, r.at(u) * border)
                }
                None => scale(normal, -0.5 * half_mm.1 * u),
            };
            Contact::Edge {
                point,
                normal,
                fillet_mm: 0.5 + 2.5 * rng.uniform(),
            }
        } else {
            Contact::Nothing
        };
        let peak_press_mm = match contact {
            Contact::Tendon { .. } => at(config.press_mm),
            _ => at(config.object_press_mm),
        };
        Self {
            contact,
            peak_press_mm,
            optics_gain,
            gel_sigma_factor,
            blur_px,
            shift_px,
        }
    }
}
