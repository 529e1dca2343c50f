//! The sensor contract (`sensors.md`, `datasets.md`) in one place: the
//! label threshold, the skin's rest dome, the sensing window and the label
//! columns. The virtual sensors render by these, the models train and run
//! by these and both front ends report by these, so a change to the
//! contract is made here once.

/// Label columns of the dataset layout (`datasets.md`).
pub mod columns {
    /// Frame image, relative to the dataset folder.
    pub const FILE: &str = "file";
    /// TacTip: contact shape name.
    pub const SHAPE: &str = "shape";
    /// TacTip: contact position, mm.
    pub const X_MM: &str = "x_mm";
    /// TacTip: contact position, mm.
    pub const Y_MM: &str = "y_mm";
    /// TacTip: edge orientation, degrees.
    pub const THETA_DEG: &str = "theta_deg";
    /// TacTip: indentation depth, mm.
    pub const DEPTH_MM: &str = "depth_mm";
    /// TacTip: normal force, newtons.
    pub const FORCE_N: &str = "force_n";
    /// Visuo-tactile: tendon mask image.
    pub const MASK: &str = "mask";
    /// Visuo-tactile: depth map (`.npy`).
    pub const DEPTH: &str = "depth";
    /// Visuo-tactile: 1 when a tendon is visible (see
    /// [`super::visuotactile::TENDON_MIN_AMPLITUDE_MM`]).
    pub const TENDON: &str = "tendon";
    /// Visuo-tactile: tendon direction in the image, degrees in [0, 180).
    pub const DIRECTION_DEG: &str = "direction_deg";
    /// Visuo-tactile: tendon path kind (straight, curved).
    pub const PATH: &str = "path";
    /// Visuo-tactile: press of the skin at the centre, mm.
    pub const PRESS_MM: &str = "press_mm";
    /// Visuo-tactile: the ridge's amplitude, mm (optional column).
    pub const RIDGE_MM: &str = "ridge_mm";
    /// Visuo-tactile: palpation video the frame belongs to.
    pub const SEQUENCE: &str = "sequence";
    /// Visuo-tactile: the frame's index in its video.
    pub const FRAME_INDEX: &str = "frame_index";
    /// Either kind: the authors' `train`/`val`/`test` split.
    pub const SPLIT: &str = "split";
}

/// The virtual TacTip (`sensors.md` section 1).
pub mod tactip {
    use super::columns;

    /// Whether a label means something on a frame of `shape`: theta is
    /// "the in-plane orientation of edges, axes and ridges", which a sphere
    /// and a flat have not, and a flat touches everywhere, so it has no
    /// contact position. Every other pair (other columns, other shapes,
    /// a real set's own shapes) does. Another implementation of the spec
    /// may draw and write such labels; no estimator can learn them.
    pub fn label_applies(shape: &str, column: &str) -> bool {
        match column {
            columns::THETA_DEG => !matches!(shape, "sphere" | "flat"),
            columns::X_MM | columns::Y_MM => shape != "flat",
            _ => true,
        }
    }
}

/// The virtual visuo-tactile sensor (`sensors.md` section 2).
pub mod visuotactile {
    /// Smallest ridge amplitude that counts as a visible tendon, mm: the
    /// `tendon` label is `A >= 0.03` mm.
    pub const TENDON_MIN_AMPLITUDE_MM: f64 = 0.03;
    /// Rest dome `d0(r) = 15 + 3 (r / r_max)^2` mm: its depth at the centre.
    pub const DOME_BASE_MM: f64 = 15.0;
    /// Rest dome: its rise from the centre to a corner, mm.
    pub const DOME_RISE_MM: f64 = 3.0;

    /// Camera-to-skin distance of the skin at rest, mm, at a pixel whose
    /// squared distance from the frame centre is `r2_fraction` of the
    /// squared half-diagonal (0 at the centre, 1 at a corner).
    pub fn rest_depth_mm(r2_fraction: f64) -> f64 {
        DOME_BASE_MM + DOME_RISE_MM * r2_fraction
    }

    /// The sensing window: the ellipse inscribed in the frame, centred on
    /// the pixel grid's centre. Pixels outside it see the housing.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub struct Window {
        /// Centre column, pixels.
        pub cx: f64,
        /// Centre row, pixels.
        pub cy: f64,
        /// Horizontal semi-axis, pixels.
        pub rx: f64,
        /// Vertical semi-axis, pixels.
        pub ry: f64,
    }

    impl Window {
        /// The window of a `width x height` frame (or map).
        pub fn of_frame(width: f64, height: f64) -> Self {
            Self {
                cx: (width - 1.0) / 2.0,
                cy: (height - 1.0) / 2.0,
                rx: width / 2.0,
                ry: height / 2.0,
            }
        }

        /// True when pixel `(u, v)` (column, row) is inside the window.
        pub fn contains(&self, u: f64, v: f64) -> bool {
            self.radius(u, v) <= 1.0
        }

        /// How far pixel `(u, v)` lies from the centre as a fraction of the
        /// rim's distance in its direction (1 on the rim).
        pub fn radius(&self, u: f64, v: f64) -> f64 {
            let (du, dv) = ((u - self.cx) / self.rx, (v - self.cy) / self.ry);
            (du * du + dv * dv).sqrt()
        }

        /// The same window `margin` pixels inside its rim (semi-axes at
        /// least one pixel).
        pub fn inset(self, margin: f64) -> Self {
            Self {
                rx: (self.rx - margin).max(1.0),
                ry: (self.ry - margin).max(1.0),
                ..self
            }
        }

        /// Row-major inside/outside of every pixel of a `w x h` map.
        pub fn mask(w: usize, h: usize) -> Vec<bool> {
            let win = Self::of_frame(w as f64, h as f64);
            (0..w * h)
                .map(|i| win.contains((i % w) as f64, (i / w) as f64))
                .collect()
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn the_window_is_the_inscribed_ellipse() {
            let m = Window::mask(8, 4);
            assert!(m[2 * 8 + 4], "the centre is inside");
            assert!(
                !m[0] && !m[7] && !m[3 * 8] && !m[3 * 8 + 7],
                "corners are not"
            );
            assert_eq!(rest_depth_mm(0.0), 15.0);
            assert_eq!(rest_depth_mm(1.0), 18.0);
        }
    }
}

/// What a visuo-tactile dataset's depth maps hold (`manifest.json`'s
/// `"depth"`): the virtual sensor's camera-to-skin distance, or a
/// calibrated sensor's indentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthMaps {
    /// Camera-to-skin distance (the rest dome plus the press), scored
    /// inside the sensing window ellipse.
    #[default]
    Distance,
    /// How far the skin is pushed toward the camera, 0 at rest, over the
    /// whole frame (a calibrated GelSight-like sensor).
    Indentation,
}

impl DepthMaps {
    /// The manifest's word for it.
    pub fn name(self) -> &'static str {
        match self {
            DepthMaps::Distance => "distance",
            DepthMaps::Indentation => "indentation",
        }
    }

    /// The pixels of a `w x h` map where the skin is seen and scored.
    pub fn window(self, w: usize, h: usize) -> Vec<bool> {
        match self {
            DepthMaps::Distance => visuotactile::Window::mask(w, h),
            DepthMaps::Indentation => vec![true; w * h],
        }
    }
}

/// A real sensor calibrated from ball presses (`datasets.md`: the
/// calibration layout) and the data rendered through its calibration.
pub mod calibrated {
    /// Skin pushed in by more than this is in contact (and, in rendered
    /// palpation frames, in the tendon mask), mm: the visuo-tactile
    /// sensor's label threshold.
    pub const CONTACT_MIN_INDENTATION_MM: f64 = super::visuotactile::TENDON_MIN_AMPLITUDE_MM;
}
