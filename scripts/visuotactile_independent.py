"""An independent virtual visuo-tactile palpation sensor, written from
`sensors.md` section 2 alone (numpy and the standard library, none of the
project's code), to check that paper B's models trained on the project's
generator read another implementation's frames and labels, as held-out data
made by others will be (`docs/synth.md`).

    python scripts/visuotactile_independent.py OUT SEQUENCES SEED

writes SEQUENCES palpation videos of 12 frames at 640 x 360 in the shared
layout (`docs/datasets.md`). Where the spec leaves a choice open this one
differs from `datasets-synth` on purpose:
- the principal point at `(W/2, H/2)`, not the pixel grid's centre;
- the tendon anchored anywhere in the central disc (uniform by area) with
  any tangent, its `direction_deg` measured on the drawn centre line at its
  point nearest the frame centre; arcs and s-curves followed for 20 mm of
  arc length each way and ending there (no straight continuation);
- tendons out of view placed 0 to 3 ridge widths outside the window, the
  labels following the spec's mask rule (a ridge reaching over the rim
  makes a positive);
- two more label columns: `ridge_mm` (the ridge amplitude `A`) and
  `outside_window_w` (for a centre line outside the window, how far, in
  ridge widths `w`; empty when it crosses the window);
- a half-sine press `peak * sin(pi t) - 0.3 mm`, written as it is (negative
  before first touch);
- normals from finite differences of the depth field, the exposure applied
  after the glare, the blur through an FFT (wrapping at the borders),
  rounding half to even.
"""
import csv
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tactip_independent import cli, staged, write_png  # noqa: E402

W, H, FRAMES = 640, 360, 12
CX, CY = W / 2, H / 2
FX = W / 2  # horizontal field of view 90 degrees
MM = 15.0 / FX  # skin-plane mm per pixel at the nominal 15 mm
U, V = np.meshgrid(np.arange(W), np.arange(H))  # pixel centres
XMM, YMM = (U - CX) * MM, (V - CY) * MM
R2 = ((U - CX) ** 2 + (V - CY) ** 2) / ((W / 2) ** 2 + (H / 2) ** 2)
D0 = 15.0 + 3.0 * R2
WINDOW = ((U - CX) / (W / 2)) ** 2 + ((V - CY) / (H / 2)) ** 2 <= 1.0
LIGHTS = [np.array([np.cos(np.radians(30)) * np.cos(np.radians(a)),
                    np.cos(np.radians(30)) * np.sin(np.radians(a)),
                    -np.sin(np.radians(30))]) for a in (90, 210, 330)]
GX, GY = CX + 0.92 * (W / 2) * np.cos(np.radians(-45)), CY + 0.92 * (H / 2) * np.sin(np.radians(-45))
GLARE = 0.6 * np.exp(-((U - GX) ** 2 + (V - GY) ** 2) / (2 * (0.03 * W) ** 2))


def centre_line(path, anchor, heading, radius, turn):
    """Points every 0.25 mm along the tendon's centre line (mm, skin plane),
    20 mm of arc length each way from the anchor, first curving to the
    side `turn` (+1 or -1)."""
    step, n = 0.25, 80
    pts = []
    for sign in (-1, 1):
        p, h = np.array(anchor, float), heading + (np.pi if sign < 0 else 0.0)
        # walking back along one circle turns the other way; an s-curve's
        # second half curves opposite to its first
        side = turn * (sign if path == "arc" else 1.0)
        half = [p.copy()]
        for _ in range(n):
            if path != "straight":
                h += side * step / radius
            p = p + step * np.array([np.cos(h), np.sin(h)])
            half.append(p.copy())
        pts.append(half[::-1] if sign < 0 else half[1:])
    return np.concatenate([np.array(pts[0]), np.array(pts[1])])


def distance_to(line, x, y):
    """Distance of every (x, y) to the polyline, and the index of the
    nearest segment."""
    best = np.full(x.shape, np.inf)
    a, b = line[:-1], line[1:]
    for (ax, ay), (bx, by) in zip(a, b):
        dx, dy = bx - ax, by - ay
        t = np.clip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0, 1)
        best = np.minimum(best, np.hypot(x - ax - t * dx, y - ay - t * dy))
    return best


def blur(a, sigma):
    ky, kx = np.fft.fftfreq(a.shape[0]), np.fft.fftfreq(a.shape[1])
    g = np.exp(-2 * (np.pi * sigma) ** 2 * (ky[:, None] ** 2 + kx[None, :] ** 2))
    return np.real(np.fft.ifft2(np.fft.fft2(a) * g))


def scene(rng, out_of_view=0.15):
    """One phantom: the tendon's path, size and distance field; out of view
    with probability `out_of_view`."""
    path = ["straight", "arc", "s-curve"][rng.integers(3)]
    radius, burial = rng.uniform(1.5, 4.0), rng.uniform(1.0, 4.0)
    w = 0.6 * radius + 0.3 * burial
    curvature = rng.uniform(15.0, 60.0)
    heading = rng.uniform(0, 2 * np.pi)
    margin_w = None
    if rng.uniform() < out_of_view:
        # out of view: a straight line 0-3 ridge widths outside the window
        path = "straight"
        normal = rng.uniform(0, 2 * np.pi)
        nx, ny = np.cos(normal), np.sin(normal)
        reach = np.hypot(15.0 * nx, (H / 2) * MM * ny)  # the window's support in that direction
        margin_w = rng.uniform(0, 3)
        anchor = (nx * (reach + margin_w * w), ny * (reach + margin_w * w))
        heading = normal + np.pi / 2
    else:
        rho, phi = 0.3 * 15.0 * np.sqrt(rng.uniform()), rng.uniform(0, 2 * np.pi)
        anchor = (rho * np.cos(phi), rho * np.sin(phi))
    if path == "straight":
        line = np.array([anchor]) + np.outer(np.linspace(-60, 60, 3), [np.cos(heading), np.sin(heading)])
    else:
        line = centre_line(path, anchor, heading, curvature, rng.choice([-1.0, 1.0]))
    s = distance_to(line, XMM, YMM)
    near = np.argmin(np.hypot(line[:, 0], line[:, 1]))
    a, b = line[max(near - 1, 0)], line[min(near + 1, len(line) - 1)]
    direction = np.degrees(np.arctan2(b[1] - a[1], b[0] - a[0])) % 180.0
    return dict(path=path, radius=radius, burial=burial, w=w, s=s, direction=direction, margin_w=margin_w,
                peak=rng.uniform(0.3, 4.0))


def frame(rng, sc, press):
    """The picture, mask, depth and labels of one frame at `press` mm."""
    p = max(press, 0.0)
    amp = 0.35 * p * sc["radius"] / (sc["radius"] + sc["burial"])
    ridge = amp * np.exp(-sc["s"] ** 2 / (2 * sc["w"] ** 2))
    # shaded from the skin's displacement over the whole frame (the housing
    # is painted over it after), so the window's rim has no step
    disp = 0.4 * p * (1 - R2) + ridge
    depth = np.where(WINDOW, D0 - disp, D0)
    dedy, dedx = np.gradient(-disp, MM)
    norm = np.sqrt(dedx**2 + dedy**2 + 1)
    rgb = np.empty((H, W, 3))
    for c, light in enumerate(LIGHTS):
        ndotl = (dedx * light[0] + dedy * light[1] - light[2]) / norm
        rgb[..., c] = 0.8 * (0.25 + np.maximum(0, ndotl))
    rgb[~WINDOW] = np.array([10, 10, 12]) / 255
    rgb = (rgb + GLARE[..., None]) * rng.uniform(0.9, 1.1)
    for c in range(3):
        rgb[..., c] = blur(rgb[..., c], 1.0)
    rgb = rgb * 255 + rng.normal(0, rng.uniform(1, 3), rgb.shape)
    mask = WINDOW & (ridge > max(0.3 * amp, 0.02))
    tendon = press > 0 and amp >= 0.03 and mask.any()
    if not tendon:
        mask[:] = False
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8), mask, (depth / 1000).astype(np.float32), tendon, amp


def main(out, sequences, seed, out_of_view=0.15):
    """Write `sequences` palpation videos as a dataset at `out`, a fraction
    `out_of_view` of them with the tendon's centre line outside the window."""
    if not 1 <= sequences <= 100_000:
        raise ValueError(f"sequences: must be 1 to 100000, got {sequences}")
    if not 0 <= out_of_view <= 1:
        raise ValueError(f"out_of_view: must be a fraction 0 to 1, got {out_of_view}")
    staged(out, seed, "visuotactile", lambda folder: write_dataset(folder, sequences, seed, out_of_view))


def write_dataset(out, sequences, seed, out_of_view):
    rng = np.random.default_rng(seed)
    for sub in ("frames", "masks", "depth"):
        os.makedirs(os.path.join(out, sub))
    rows = []
    for k in range(sequences):
        sc = scene(rng, out_of_view)
        for f in range(FRAMES):
            press = sc["peak"] * np.sin(np.pi * f / (FRAMES - 1)) - 0.3
            img, mask, depth, tendon, amp = frame(rng, sc, press)
            i = k * FRAMES + f
            names = [f"frames/{i:06d}.png", f"masks/{i:06d}.png", f"depth/{i:06d}.npy"]
            write_png(os.path.join(out, names[0]), img)
            write_png(os.path.join(out, names[1]), mask.astype(np.uint8) * 255)
            np.save(os.path.join(out, names[2]), depth)
            margin = "" if sc["margin_w"] is None else f"{sc['margin_w']:.3f}"
            rows.append(names + [int(tendon), f"{sc['direction']:.3f}" if tendon else "", sc["path"],
                                 f"{press:.4f}", k, f, f"{amp:.4f}", margin])
    with open(os.path.join(out, "labels.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["file", "mask", "depth", "tendon", "direction_deg", "path", "press_mm", "sequence", "frame_index",
                    "ridge_mm", "outside_window_w"])
        w.writerows(rows)
    with open(os.path.join(out, "manifest.json"), "w") as fh:
        json.dump({"format": "tactile-dataset/1", "kind": "visuotactile", "sensor_spec": "virtual-visuotactile/1",
                   "width": W, "height": H,
                   "generator": "scripts/visuotactile_independent.py (numpy, from sensors.md)",
                   "seed": seed, "count": sequences * FRAMES}, fh, indent=1)


if __name__ == "__main__":
    cli("usage: python scripts/visuotactile_independent.py OUT SEQUENCES SEED", main)
