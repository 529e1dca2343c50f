//! What the ball's geometry says about the skin in a press. Inside the
//! contact circle (radius `a`) the skin follows the ball's cap, its
//! indentation `h(r) = c + sqrt(R^2 - r^2) - sqrt(R^2 - a^2)` with `c` (the
//! sink of the gel around the ball) unknown; beyond `3a` the skin is at
//! rest. Between the two nothing is known.

use crate::layout::Circle;
use crate::prepare::WorkingGrid;

/// Beyond this many contact radii the skin is at rest.
pub const FAR_FIELD_RADII: f64 = 3.0;
/// Gradient targets are taken inside this fraction of the contact radius
/// (the circle's edge is where annotation and finder disagree).
pub const INNER_FRACTION: f64 = 0.95;

/// A press's known geometry, in frame pixels and millimetres.
#[derive(Debug, Clone, Copy)]
pub struct Cap {
    /// The contact circle.
    pub circle: Circle,
    /// The ball's radius, pixels.
    pub ball_radius_px: f64,
    /// Millimetres per pixel.
    pub mm_per_px: f64,
}

impl Cap {
    /// Distance from the centre, frame pixels.
    pub fn r_px(&self, x: f64, y: f64) -> f64 {
        (x - self.circle.centre_x_px).hypot(y - self.circle.centre_y_px)
    }

    /// The cap's height above its rim at frame point `(x, y)` inside the
    /// contact, mm (`h - c`).
    pub fn height_mm(&self, x: f64, y: f64) -> Option<f64> {
        let (r, a, big) = (self.r_px(x, y), self.circle.radius_px, self.ball_radius_px);
        (r <= a).then(|| ((big * big - r * r).sqrt() - (big * big - a * a).sqrt()) * self.mm_per_px)
    }

    /// The indentation's slope (mm per mm, `dh/dx`, `dh/dy`) at frame point
    /// `(x, y)`, where it is known: inside [`INNER_FRACTION`] of the
    /// contact, or 0 beyond [`FAR_FIELD_RADII`] radii.
    pub fn slope(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let r = self.r_px(x, y);
        let a = self.circle.radius_px;
        if r <= INNER_FRACTION * a {
            let z = (self.ball_radius_px.powi(2) - r * r).sqrt();
            let (dx, dy) = (x - self.circle.centre_x_px, y - self.circle.centre_y_px);
            Some((-dx / z, -dy / z))
        } else if r >= FAR_FIELD_RADII * a {
            Some((0.0, 0.0))
        } else {
            None
        }
    }
}

/// The training targets of one press on the working grid: the slopes
/// (mm per mm) of the forward differences `gx`, `gy`, taken at the
/// midpoints between pixels, and each pixel's weight (0 where nothing is
/// known; the far field weighted down to the contact's pixel count so
/// both count alike).
#[derive(Debug, Clone)]
pub struct GradientTargets {
    /// Slope toward the next pixel right.
    pub gx: Vec<f32>,
    /// Slope toward the next pixel down.
    pub gy: Vec<f32>,
    /// Per pixel, for `gx` and `gy` alike.
    pub weight: Vec<f32>,
    /// The cap's height above its rim at each pixel's centre inside the
    /// contact (0 elsewhere), mm.
    pub cap_mm: Vec<f32>,
    /// 1 inside the contact, else 0.
    pub inside: Vec<f32>,
    /// 1 beyond [`FAR_FIELD_RADII`] contact radii (the skin at rest), else 0.
    pub far: Vec<f32>,
}

impl GradientTargets {
    /// The targets of `cap` on `grid`.
    pub fn of(cap: &Cap, grid: WorkingGrid) -> Self {
        let (w, h) = (grid.width(), grid.height());
        let half = grid.factor as f64 / 2.0;
        let mut gx = vec![0f32; w * h];
        let mut gy = vec![0f32; w * h];
        let mut inside = vec![false; w * h];
        let mut known = vec![false; w * h];
        let mut cap_mm = vec![0f32; w * h];
        let mut centre_inside = vec![0f32; w * h];
        let mut far = vec![0f32; w * h];
        for j in 0..h {
            for i in 0..w {
                let (x, y) = (grid.frame_coord(i as f64), grid.frame_coord(j as f64));
                let k = j * w + i;
                if let Some(t) = cap.height_mm(x, y) {
                    cap_mm[k] = t as f32;
                    centre_inside[k] = 1.0;
                } else if cap.r_px(x, y) >= FAR_FIELD_RADII * cap.circle.radius_px {
                    far[k] = 1.0;
                }
                // Both midpoints must be known.
                if let (Some((sx, _)), Some((_, sy))) =
                    (cap.slope(x + half, y), cap.slope(x, y + half))
                {
                    gx[k] = sx as f32;
                    gy[k] = sy as f32;
                    known[k] = true;
                    inside[k] = cap.r_px(x, y) < cap.circle.radius_px;
                }
            }
        }
        let n_in = inside.iter().filter(|&&v| v).count().max(1) as f32;
        let n_far = known
            .iter()
            .zip(&inside)
            .filter(|(k, i)| **k && !**i)
            .count()
            .max(1) as f32;
        let weight = known
            .iter()
            .zip(&inside)
            .map(|(&k, &i)| match (k, i) {
                (false, _) => 0.0,
                (true, true) => 1.0,
                (true, false) => n_in / n_far,
            })
            .collect();
        Self {
            gx,
            gy,
            weight,
            cap_mm,
            inside: centre_inside,
            far,
        }
    }
}
