"""An independent simulator of a real GelSight, calibrated from its ball
presses alone (numpy and Pillow, none of the project's code), to check that
the pipeline `tactile synth gelsight` trains for a sensor (`models/
gelsight-r15`) reads another simulator's frames of the same sensor, as
issue 33's checks do (`docs/own-sensor.md`).

    python scripts/gelsight_independent.py OUT SEQUENCES SEED [BALL]

writes SEQUENCES palpation videos of 5 frames in the visuo-tactile layout
with indentation maps (`docs/datasets.md`, "A calibrated sensor's rendered
data"), from the calibration folder BALL (default
`../shared/real/gelsight-ball`: `sensor.json`, `background.png`,
`presses.csv` with each press's annotated circle).

It follows Taxim's recipe (Si and Yuan, 2022) rather than the toolkit's:
- the colour change is a lookup table of the surface slope alone (its
  magnitude and azimuth, 24 x 72 bins), each bin the mean change of the
  presses' pixels of that slope, the ball's slope read from its annotated
  circle; no dependence on the place in the frame;
- the gel around a contact follows a sum of Gaussian spreads of the
  object's penetration (three widths), the object's own surface where that
  is deeper; the spread's gain and width are those of a small grid whose
  rendered presses match the real ones best around the contact;
- a tendon is a cylinder of its radius, its axis a straight line, an arc or
  an s-curve, pressed into the gel; negatives are no contact, a sphere, a
  flat punch with a rounded rim and a plate's rounded edge;
- a video's press rises and falls as `peak * sin(pi (k + 1) / 6)` over its
  five frames; light videos (peak 0.05-0.2 mm) are a fifth of them;
- the camera: exposure drift of +-3 %, a blur of sigma 0.5-0.9 px (through
  an FFT), noise of sigma 0.5-2 grey levels, rounding half to even.

Labels as `docs/datasets.md` gives them: the mask where a tendon pushes the
skin in by more than 0.03 mm, `tendon` 1 when any pixel is, the direction of
the centre line at its point nearest the frame's centre, the indentation map
in metres, `ridge_mm` and `peak_mm`.
"""
import csv
import json
import os
import sys

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tactip_independent import cli, staged, write_png  # noqa: E402

FRAMES = 5
BALL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "real", "gelsight-ball")
MAG_BINS, AZ_BINS, MAG_MAX = 24, 72, 2.4
# The gel's spread: Gaussians of these widths and relative weights, scaled
# by the factors the presses fit best (`Sensor.fit_spread`).
SPREAD_SIGMAS_MM, SPREAD_WEIGHTS = (0.3, 0.6, 1.2), (0.47, 0.33, 0.2)
SPREAD_GAINS, SPREAD_WIDTHS = (0.5, 0.75, 1.0), (1.0, 2.0, 3.0)
THRESHOLD_MM = 0.03


def read_rgb(path):
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"), dtype=np.float64)


def positive(meta, key, path):
    """`meta[key]` as a positive number, or an error naming the file."""
    try:
        value = float(meta[key])
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{path}: '{key}' must be a number, got {meta.get(key)!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{path}: '{key}' must be above 0, got {value}")
    return value


def presses(ball, shape, every=1):
    """Every `every`-th press of `ball/presses.csv` from the first, with its
    line and frame, or an error naming the line (a missing column, a circle
    that is no number, a frame of another size than the rest frame)."""
    path = os.path.join(ball, "presses.csv")
    with open(path) as f:
        for line, row in enumerate(csv.DictReader(f), start=2):
            if (line - 2) % every:
                continue
            try:
                file = row["file"]
                [float(row[k]) for k in ("centre_x_px", "centre_y_px", "contact_radius_px")]
            except (KeyError, TypeError, ValueError) as e:
                raise ValueError(f"{path}:{line}: needs file, centre_x_px, centre_y_px and contact_radius_px "
                                 f"({type(e).__name__}: {e})") from None
            frame = read_rgb(os.path.join(ball, file))
            if frame.shape != shape:
                raise ValueError(f"{path}:{line}: {file} is {frame.shape[1]}x{frame.shape[0]}, "
                                 f"the rest frame {shape[1]}x{shape[0]}")
            yield line, row, frame


class Sensor:
    """The sensor as its ball presses show it: the rest frame, the scale and
    the colour change by slope."""

    def __init__(self, ball):
        meta_path = os.path.join(ball, "sensor.json")
        with open(meta_path) as f:
            meta = json.load(f)
        self.mm_per_px = positive(meta, "mm_per_px", meta_path)
        radius_px = positive(meta, "ball_diameter_mm", meta_path) / 2 / self.mm_per_px
        self.background = read_rgb(os.path.join(ball, meta.get("background", "background.png")))
        self.h, self.w = self.background.shape[:2]
        sums = np.zeros((MAG_BINS, AZ_BINS, 3))
        counts = np.zeros((MAG_BINS, AZ_BINS))
        v, u = np.mgrid[0:self.h, 0:self.w]
        for _, row, frame in presses(ball, self.background.shape):
            cx, cy, a = (float(row[k]) for k in ("centre_x_px", "centre_y_px", "contact_radius_px"))
            du, dv = u - cx, v - cy
            r = np.hypot(du, dv)
            inside = r < 0.92 * a
            # the ball's surface slope (mm per mm), pointing away from its centre
            slope = r / np.sqrt(np.maximum(radius_px**2 - r**2, 1e-9))
            mag, az = slope[inside], np.arctan2(dv, du)[inside]
            mi, ai = self.bins(mag, az)
            np.add.at(sums, (mi, ai), frame[inside] - self.background[inside])
            np.add.at(counts, (mi, ai), 1)
        filled = counts >= 5
        table = np.where(filled[..., None], sums / np.maximum(counts, 1)[..., None], np.nan)
        # Bins the presses left empty take the nearest filled bin along the
        # slope's magnitude at their azimuth (flat: no change).
        table[0][~filled[0]] = 0.0
        for ai in range(AZ_BINS):
            last = table[0, ai]
            for mi in range(MAG_BINS):
                if np.isnan(table[mi, ai, 0]):
                    table[mi, ai] = last
                else:
                    last = table[mi, ai]
        # Neighbouring azimuths alike ([1, 2, 1] / 4, around the circle).
        self.table = (np.roll(table, 1, axis=1) + 2 * table + np.roll(table, -1, axis=1)) / 4
        self.gain, self.width = self.fit_spread(ball, radius_px * self.mm_per_px)

    def fit_spread(self, ball, radius_mm):
        """The spread's gain and width (of SPREAD_GAINS, SPREAD_WIDTHS) whose
        rendered presses best match every fourth real press's colour change
        between one and three contact radii (the ball pressed to its
        annotated contact)."""
        v, u = np.mgrid[0:self.h, 0:self.w]
        pressed = []
        for _, row, frame in presses(ball, self.background.shape, every=4):
            change = frame - self.background
            cx, cy, a = (float(row[k]) for k in ("centre_x_px", "centre_y_px", "contact_radius_px"))
            r = np.hypot(u - cx, v - cy) * self.mm_per_px
            a *= self.mm_per_px
            press = radius_mm - np.sqrt(radius_mm**2 - a**2)
            ball_pen = np.maximum(press - radius_mm + np.sqrt(np.maximum(radius_mm**2 - r**2, 0.0)), 0.0)
            pressed.append((ball_pen, change, (r > 1.05 * a) & (r < 3 * a)))
        best = None
        for gain in SPREAD_GAINS:
            for width in SPREAD_WIDTHS:
                self.gain, self.width = gain, width
                err = np.mean([np.abs(self.shade(self.spread(p)) - c)[ring].mean() for p, c, ring in pressed])
                if best is None or err < best[0]:
                    best = (err, gain, width)
        return best[1], best[2]

    def spread(self, penetration):
        """The gel's surface around a contact: the penetration where the
        object touches, Gaussian spreads of it beyond (Taxim's rule: the
        deeper of the two)."""
        mm = self.mm_per_px
        sigmas = np.array(SPREAD_SIGMAS_MM) * self.width / mm
        pad = int(3 * sigmas.max())
        p = np.pad(penetration, pad)
        out = gauss_fft(p, sigmas, [w * self.gain for w in SPREAD_WEIGHTS])
        return np.maximum(penetration, out[pad:-pad, pad:-pad])

    @staticmethod
    def bins(mag, az):
        mi = np.clip((mag / MAG_MAX * MAG_BINS).astype(int), 0, MAG_BINS - 1)
        ai = ((az + np.pi) / (2 * np.pi) * AZ_BINS).astype(int) % AZ_BINS
        return mi, ai

    def shade(self, surface_mm):
        """The colour change of a gel surface pushed in by `surface_mm`
        (toward the camera), from its slope."""
        gy, gx = np.gradient(surface_mm, self.mm_per_px)
        # A surface pushed in slopes away from its deepest point, as the
        # ball's does from its centre: the slope points down the push.
        mag, az = np.hypot(gx, gy), np.arctan2(-gy, -gx)
        # Linear in the magnitude between bin centres, from no change at
        # no slope: the far field's faint slopes shade faintly.
        pos = np.clip(mag / MAG_MAX * MAG_BINS - 0.5, -1.0, MAG_BINS - 1.0)
        lo = np.floor(pos).astype(int)
        t = (pos - lo)[..., None]
        _, ai = self.bins(mag, az)
        below = np.where(lo[..., None] >= 0, self.table[np.maximum(lo, 0), ai], 0.0)
        return below * (1 - t) + self.table[np.minimum(lo + 1, MAG_BINS - 1), ai] * t


def gauss_fft(a, sigma_px, weights=(1.0,)):
    """`a` blurred by Gaussians of `sigma_px` (one or several, summed with
    `weights`) through one FFT, wrapping at the borders."""
    ky = np.fft.fftfreq(a.shape[0])[:, None]
    kx = np.fft.fftfreq(a.shape[1])[None, :]
    g = sum(w * np.exp(-2 * (np.pi * s) ** 2 * (kx**2 + ky**2)) for s, w in zip(np.atleast_1d(sigma_px), weights))
    if a.ndim == 3:
        g = g[..., None]
        return np.real(np.fft.ifft2(np.fft.fft2(a, axes=(0, 1)) * g, axes=(0, 1)))
    return np.real(np.fft.ifft2(np.fft.fft2(a) * g))


def centre_line(rng, path, x0, y0, heading):
    """Points every 0.05 mm along a tendon's axis (mm, frame coordinates),
    14 mm each way from (x0, y0)."""
    s = np.arange(-14.0, 14.0, 0.05)
    if path == "straight":
        th = np.full_like(s, heading)
    elif path == "arc":
        th = heading + s / (rng.uniform(8, 25) * rng.choice([-1, 1]))
    else:  # s-curve: the heading swings one way then the other
        th = heading + rng.uniform(0.25, 0.6) * np.sin(2 * np.pi * s / rng.uniform(12, 24))
    ds = np.gradient(s)
    x = x0 + np.cumsum(np.cos(th) * ds)
    y = y0 + np.cumsum(np.sin(th) * ds)
    i0 = np.argmin(np.abs(s))
    return x - x[i0] + x0, y - y[i0] + y0, th


def distance_to(px, py, xs, ys, mm_per_px, reach):
    """Each pixel's distance (mm) to a polyline, within `reach` mm."""
    d = np.full(px.shape, np.inf)
    for x, y in zip(xs[::4], ys[::4]):
        j0, j1 = int((x - reach) / mm_per_px), int((x + reach) / mm_per_px) + 2
        i0, i1 = int((y - reach) / mm_per_px), int((y + reach) / mm_per_px) + 2
        j0, i0 = max(j0, 0), max(i0, 0)
        j1, i1 = min(j1, px.shape[1]), min(i1, px.shape[0])
        if j0 >= j1 or i0 >= i1:
            continue
        dd = np.hypot(px[i0:i1, j0:j1] - x, py[i0:i1, j0:j1] - y)
        np.minimum(d[i0:i1, j0:j1], dd, out=d[i0:i1, j0:j1])
    return d


def scene(rng, sensor):
    """One video's object: a function of the press (mm) giving the
    penetration map (mm), and its labels that do not change with it."""
    mm = sensor.mm_per_px
    v, u = np.mgrid[0:sensor.h, 0:sensor.w]
    px, py = u * mm, v * mm
    cx, cy = (sensor.w - 1) / 2 * mm, (sensor.h - 1) / 2 * mm
    kind = rng.choice(["tendon"] * 6 + ["none", "sphere", "punch", "flat"])
    if kind == "tendon":
        path = str(rng.choice(["straight", "arc", "s-curve"]))
        radius = rng.uniform(1.5, 3.5)
        x0, y0 = cx + rng.uniform(-0.3, 0.3) * sensor.w * mm, cy + rng.uniform(-0.3, 0.3) * sensor.h * mm
        xs, ys, th = centre_line(rng, path, x0, y0, rng.uniform(0, np.pi))
        d = distance_to(px, py, xs, ys, mm, radius)
        k = np.argmin(np.hypot(xs - cx, ys - cy))
        direction = float(np.degrees(th[k]) % 180.0)

        def pen(press):
            return np.maximum(press - radius + np.sqrt(np.maximum(radius**2 - d**2, 0.0)), 0.0)
        return path, direction, pen
    if kind == "none":
        return "none", None, None
    x0, y0 = cx + rng.uniform(-0.25, 0.25) * sensor.w * mm, cy + rng.uniform(-0.25, 0.25) * sensor.h * mm
    r = np.hypot(px - x0, py - y0)
    if kind == "sphere":
        rs = rng.uniform(2.0, 6.0)

        def pen(press):
            return np.maximum(press - rs + np.sqrt(np.maximum(rs**2 - r**2, 0.0)), 0.0)
    elif kind == "punch":
        rp, edge = rng.uniform(1.0, 3.0), 0.3

        def pen(press):
            beyond = np.maximum(r - (rp - edge), 0.0)
            return np.maximum(press - edge + np.sqrt(np.maximum(edge**2 - beyond**2, 0.0)), 0.0) * (r < rp)
    else:
        t = rng.uniform(0, np.pi)
        across = (px - x0) * -np.sin(t) + (py - y0) * np.cos(t)
        edge = 1.0

        def pen(press):
            beyond = np.maximum(across, 0.0)
            return np.maximum(press - edge + np.sqrt(np.maximum(edge**2 - beyond**2, 0.0)), 0.0) * (beyond < edge)
    return kind, None, pen


def camera(rng, sensor, surface_mm):
    img = sensor.background + sensor.shade(surface_mm)
    img = img * (1 + rng.uniform(-0.03, 0.03))
    img = gauss_fft(img, rng.uniform(0.5, 0.9))
    img = img + rng.normal(0, rng.uniform(0.5, 2.0), img.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def write_dataset(out, sequences, seed, ball):
    rng = np.random.default_rng(seed)
    sensor = Sensor(ball)
    for d in ("frames", "masks", "depth"):
        os.makedirs(os.path.join(out, d))
    rows, n = [], 0
    for seq in range(sequences):
        path, direction, pen = scene(rng, sensor)
        peak = rng.uniform(0.05, 0.2) if rng.uniform() < 0.2 else rng.uniform(0.05, 1.5)
        for k in range(FRAMES):
            press = peak * np.sin(np.pi * (k + 1) / (FRAMES + 1)) if pen else 0.0
            p = pen(press) if pen else np.zeros((sensor.h, sensor.w))
            surface = sensor.spread(p)
            tendon_push = surface if direction is not None else np.zeros_like(surface)
            mask = tendon_push > THRESHOLD_MM
            tendon = bool(mask.any())
            name = f"{n:06d}"
            write_png(os.path.join(out, "frames", name + ".png"), camera(rng, sensor, surface))
            write_png(os.path.join(out, "masks", name + ".png"), (mask * 255).astype(np.uint8))
            np.save(os.path.join(out, "depth", name + ".npy"), (surface / 1000.0).astype(np.float32))
            rows.append([f"frames/{name}.png", f"masks/{name}.png", f"depth/{name}.npy", int(tendon),
                         f"{direction:.3f}" if tendon else "", path, f"{press:.4f}", seq, k,
                         f"{float(tendon_push.max()):.4f}", f"{float(surface.max()):.4f}"])
            n += 1
    with open(os.path.join(out, "labels.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["file", "mask", "depth", "tendon", "direction_deg", "path", "press_mm", "sequence",
                    "frame_index", "ridge_mm", "peak_mm"])
        w.writerows(rows)
    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump({"format": "tactile-dataset/1", "kind": "visuotactile",
                   "sensor_spec": "calibrated: an independent simulator of the sensor of " + os.path.basename(
                       os.path.abspath(ball)),
                   "depth": "indentation", "width": sensor.w, "height": sensor.h,
                   "generator": "scripts/gelsight_independent.py (numpy, Taxim's recipe, from the ball presses)",
                   "seed": seed, "count": n,
                   "config": {"spread_gain": sensor.gain, "spread_width": sensor.width}}, f, indent=1)


def main(out, sequences, seed, ball=BALL):
    """Write `sequences` videos as a dataset at `out` (see `staged`)."""
    if not 1 <= sequences <= 100_000:
        raise ValueError(f"SEQUENCES: must be 1 to 100000 videos, got {sequences}")
    staged(out, seed, "gelsight", lambda folder: write_dataset(folder, sequences, seed, ball))


if __name__ == "__main__":
    ball = sys.argv.pop(4) if len(sys.argv) == 5 else BALL
    cli("usage: python scripts/gelsight_independent.py OUT SEQUENCES SEED [BALL]",
        lambda out, n, seed: main(out, n, seed, ball))
