//! The sensor's pinhole camera (90-degree horizontal field of view) and
//! the plane geometry the scene is drawn in.

use tactile_core::spec::visuotactile as spec;

use super::{GLARE_DIRECTION_DEG, GLARE_RADIUS_FRACTION, NOMINAL_DEPTH_MM};

/// The camera of a frame size: pinhole, 90-degree horizontal field of view.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    /// Frame width, pixels.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Focal length, pixels (`width / 2`).
    pub fx: f64,
    /// Principal point, column.
    pub cx: f64,
    /// Principal point, row.
    pub cy: f64,
    /// Half-diagonal of the frame, pixels.
    pub r_max: f64,
}

impl Camera {
    /// The camera of a `width x height` frame.
    pub fn new(width: u32, height: u32) -> Self {
        let (w, h) = (width as f64, height as f64);
        Self {
            width: width as usize,
            height: height as usize,
            fx: w / 2.0,
            cx: (w - 1.0) / 2.0,
            cy: (h - 1.0) / 2.0,
            r_max: libm::hypot(w, h) / 2.0,
        }
    }

    /// Skin-plane mm at nominal depth of pixel `(u, v)`.
    pub fn to_mm(&self, u: f64, v: f64) -> (f64, f64) {
        let k = NOMINAL_DEPTH_MM / self.fx;
        ((u - self.cx) * k, (v - self.cy) * k)
    }

    /// Pixel of skin-plane mm.
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        let k = self.fx / NOMINAL_DEPTH_MM;
        (self.cx + x * k, self.cy + y * k)
    }

    /// Semi-axes of the window ellipse, pixels.
    pub fn window_radii(&self) -> (f64, f64) {
        (self.width as f64 / 2.0, self.height as f64 / 2.0)
    }

    /// Centre of the LED glare, pixels: on the window's rim ellipse
    /// ([`GLARE_RADIUS_FRACTION`] of the way out) at [`GLARE_DIRECTION_DEG`].
    pub fn glare_centre(&self) -> (f64, f64) {
        let (a, b) = self.window_radii();
        let angle = GLARE_DIRECTION_DEG.to_radians();
        (
            self.cx + GLARE_RADIUS_FRACTION * a * libm::cos(angle),
            self.cy + GLARE_RADIUS_FRACTION * b * libm::sin(angle),
        )
    }

    /// True inside the sensing window (the inscribed ellipse).
    pub fn in_window(&self, u: f64, v: f64) -> bool {
        spec::Window::of_frame(self.width as f64, self.height as f64).contains(u, v)
    }

    /// Rest depth `d0` at pixel `(u, v)`, mm.
    pub fn rest_depth_mm(&self, u: f64, v: f64) -> f64 {
        let r2 = (u - self.cx).powi(2) + (v - self.cy).powi(2);
        spec::rest_depth_mm(r2 / (self.r_max * self.r_max))
    }
}

/// A point or vector in the skin's plane, mm.
pub(crate) type P2 = (f64, f64);

pub(crate) fn sub(a: P2, b: P2) -> P2 {
    (a.0 - b.0, a.1 - b.1)
}
pub(crate) fn add(a: P2, b: P2) -> P2 {
    (a.0 + b.0, a.1 + b.1)
}
pub(crate) fn scale(a: P2, k: f64) -> P2 {
    (a.0 * k, a.1 * k)
}
pub(crate) fn dot(a: P2, b: P2) -> f64 {
    a.0 * b.0 + a.1 * b.1
}
pub(crate) fn perp(a: P2) -> P2 {
    (-a.1, a.0)
}
pub(crate) fn unit_at(angle: f64) -> P2 {
    (libm::cos(angle), libm::sin(angle))
}
