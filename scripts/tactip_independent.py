"""An independent virtual TacTip, written from `sensors.md` section 1 alone
(numpy and the standard library, none of the project's code), to check that
models trained on the project's generator read another implementation's
frames, as held-out data made by others will be (`docs/synth.md`).

    python scripts/tactip_independent.py OUT COUNT SEED

writes a dataset of the shared layout (`docs/datasets.md`). Where the spec
leaves a choice open this one differs from `datasets-synth` on purpose: pins
drawn with 4x4 sub-samples per pixel, the penetration field on a 0.1 mm grid
blurred through an FFT, the camera's gain applied before the light blob and
the blur, and every label written, a sphere's theta and a flat's position
too (drawn as ranges, as the spec lists them).
"""
import csv
import json
import os
import shutil
import signal
import struct
import sys
import tempfile
import zlib

import numpy as np

R, SPACING, PX_MM, SIZE, C = 20.0, 2.6, 9.0, 300, 149.5
SHAPES = ["cuboid", "cylinderR4", "cylinderR8", "prism", "edge", "sphere", "flat"]

def pins():
    # hexagonal lattice: centre + rings k=1..6 of 6k points
    pts = [(0.0, 0.0)]
    dirs = [np.array([np.cos(np.radians(60 * j)), np.sin(np.radians(60 * j))]) for j in range(6)]
    for k in range(1, 7):
        for j in range(6):
            a, b = dirs[j] * k * SPACING, dirs[(j + 1) % 6] * k * SPACING
            for t in range(k):
                pts.append(tuple(a + (b - a) * t / k))
    pts = np.array(pts)
    s = np.hypot(pts[:, 0], pts[:, 1])
    scale = np.where(s > 0, R * np.sin(s / R) / np.maximum(s, 1e-12), 1.0)
    return pts * scale[:, None]

G = 0.1  # mm per grid cell
n = int(2 * R / G)
xs = (np.arange(n) + 0.5) * G - R
X, Y = np.meshgrid(xs, xs)  # X along u (columns), Y along v (rows)
r2 = X**2 + Y**2
inside = r2 < R * R
H = np.where(inside, np.sqrt(np.maximum(R * R - r2, 0)), -np.inf)

def gauss_blur(a, sigma_cells):
    k = np.fft.fftfreq(a.shape[0])
    g = np.exp(-2 * (np.pi * k * sigma_cells) ** 2)
    pad = a
    return np.real(np.fft.ifft2(np.fft.fft2(pad) * g[:, None] * g[None, :]))

def object_surface(shape, x, y, th, rs):
    """Lower surface height of the object with offset 0 (inf where absent)."""
    t = np.radians(th)
    along = (X - x) * np.cos(t) + (Y - y) * np.sin(t)
    across = -(X - x) * np.sin(t) + (Y - y) * np.cos(t)
    inf = np.full_like(X, np.inf)
    if shape == "flat":
        return np.zeros_like(X)
    if shape == "sphere":
        d2 = (X - x) ** 2 + (Y - y) ** 2
        return np.where(d2 < rs * rs, -np.sqrt(np.maximum(rs * rs - d2, 0)), inf)
    if shape.startswith("cylinder"):
        rc = float(shape[len("cylinderR"):])
        return np.where(np.abs(across) < rc, -np.sqrt(np.maximum(rc * rc - across**2, 0)), inf)
    if shape == "cuboid":
        return np.where((np.abs(along) <= 13.5) & (np.abs(across) <= 4.5), 0.0, inf)
    if shape == "prism":
        return np.abs(across) * np.sqrt(3.0)
    if shape == "edge":
        nx, ny = -np.sin(t), np.cos(t)
        return np.where(nx * X + ny * Y <= x, 0.0, inf)
    raise ValueError(shape)

def penetration(shape, x, y, th, depth, rs):
    o0 = object_surface(shape, x, y, th, rs)
    gap = np.where(inside & np.isfinite(o0), H - o0, -np.inf)
    c = gap.max()  # offset at first touch
    o = o0 + c - depth
    p = np.where(inside & np.isfinite(o), np.maximum(H - o, 0.0), 0.0)
    return gauss_blur(p, 2.0 / G)

def sample(a, px, py):
    # bilinear at planar mm coordinates
    fx, fy = (px + R) / G - 0.5, (py + R) / G - 0.5
    i0, j0 = np.floor(fy).astype(int), np.floor(fx).astype(int)
    wy, wx = fy - i0, fx - j0
    i0, j0 = np.clip(i0, 0, n - 2), np.clip(j0, 0, n - 2)
    return (a[i0, j0] * (1 - wy) * (1 - wx) + a[i0 + 1, j0] * wy * (1 - wx)
            + a[i0, j0 + 1] * (1 - wy) * wx + a[i0 + 1, j0 + 1] * wy * wx)

SS = 4
uu = (np.arange(SIZE * SS) + 0.5) / SS - 0.5  # pixel coordinates of sub-samples

def render(rng, shape, x, y, th, depth, rs):
    p = penetration(shape, x, y, th, depth, rs)
    gy, gx = np.gradient(p, G)
    P = pins()
    dx, dy = -2.5 * sample(gx, P[:, 0], P[:, 1]), -2.5 * sample(gy, P[:, 0], P[:, 1])
    pp = sample(p, P[:, 0], P[:, 1])
    pin_grey, bg = rng.uniform(210, 240), rng.uniform(20, 45)
    canvas = np.full((SIZE * SS, SIZE * SS), bg)
    for (px, py), ddx, ddy, pv in zip(P, dx, dy, pp):
        cu, cv = C + PX_MM * (px + ddx), C + PX_MM * (py + ddy)
        rad = 0.4 * (1 + 0.08 * pv) * PX_MM
        j0, j1 = int(max(0, (cu - rad - 1) * SS)), int(min(SIZE * SS, (cu + rad + 2) * SS))
        i0, i1 = int(max(0, (cv - rad - 1) * SS)), int(min(SIZE * SS, (cv + rad + 2) * SS))
        sub_u, sub_v = uu[j0:j1], uu[i0:i1]
        m = (sub_u[None, :] - cu) ** 2 + (sub_v[:, None] - cv) ** 2 <= rad * rad
        canvas[i0:i1, j0:j1][m] = pin_grey
    img = canvas.reshape(SIZE, SS, SIZE, SS).mean(axis=(1, 3))
    u = np.arange(SIZE)
    up, vp = (u - C) / C, (u - C) / C
    Up, Vp = np.meshgrid(up, vp)
    g0, a, b = rng.uniform(0.8, 1.2), rng.uniform(-0.25, 0.25), rng.uniform(-0.25, 0.25)
    gain = g0 * (1 + a * Up + b * Vp) * (1 - 0.35 * (Up**2 + Vp**2))
    img = img * gain
    if rng.uniform() < 0.3:
        s, amp = rng.uniform(40, 90), rng.uniform(20, 60)
        bu, bv = rng.uniform(0, SIZE), rng.uniform(0, SIZE)
        Uu, Vv = np.meshgrid(u, u)
        img = img + amp * np.exp(-((Uu - bu) ** 2 + (Vv - bv) ** 2) / (2 * s * s))
    # optical blur sigma 0.8 px (FFT, wrap is harmless at the dark border)
    k = np.fft.fftfreq(SIZE)
    g = np.exp(-2 * (np.pi * k * 0.8) ** 2)
    img = np.real(np.fft.ifft2(np.fft.fft2(img) * g[:, None] * g[None, :]))
    img = img + rng.normal(0, rng.uniform(3, 8), img.shape)
    force = 0.06 * p.sum() * G * G
    force *= 1 + rng.normal(0, 0.02)
    return np.clip(np.round(img), 0, 255).astype(np.uint8), force

def write_png(path, pixels):
    """An 8-bit grey `(H, W)` or RGB `(H, W, 3)` PNG, written with the
    standard library alone."""
    h, w = pixels.shape[:2]
    colour = 2 if pixels.ndim == 3 else 0
    raw = b"".join(b"\0" + np.ascontiguousarray(pixels[r], np.uint8).tobytes() for r in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def main(out, count, seed):
    """Write `count` frames and their labels as a dataset at `out` (see
    `staged`)."""
    if not 1 <= count <= 10_000_000:
        raise ValueError(f"count: must be 1 to 10000000 frames, got {count}")
    staged(out, seed, "tactip", lambda folder: write_dataset(folder, count, seed))


def staged(out, seed, name, write):
    """Run `write(folder)` in a staging folder beside `out` and rename it to
    `out` at the end, so an error or an interrupt leaves nothing; an
    existing `out` is refused."""
    if os.path.lexists(out):
        raise FileExistsError(f"{out}: already exists (left alone); choose a new folder")
    if seed < 0:
        raise ValueError(f"seed: must be 0 or more, got {seed}")
    parent = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(parent):
        raise FileNotFoundError(f"{out}: its folder {parent} does not exist")
    staging = tempfile.mkdtemp(prefix=f".{name}-independent-", dir=parent)
    try:
        write(staging)
        os.rename(staging, out)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def write_dataset(out, count, seed):
    rng = np.random.default_rng(seed)
    os.makedirs(os.path.join(out, "frames"))
    rows = []
    for i in range(count):
        shape = SHAPES[i % len(SHAPES)]
        x, y = rng.uniform(-6, 6), rng.uniform(-6, 6)
        th, depth, rs = rng.uniform(0, 180), rng.uniform(0, 5), rng.uniform(4, 10)
        if shape == "edge":
            y = 0.0
        img, force = render(rng, shape, x, y, th, depth, rs)
        name = f"frames/{i:06d}.png"
        write_png(os.path.join(out, name), img)
        rows.append([name, shape, f"{x:.4f}", f"{y:.4f}", f"{th:.4f}", f"{depth:.4f}", f"{force:.4f}"])
    with open(os.path.join(out, "labels.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["file", "shape", "x_mm", "y_mm", "theta_deg", "depth_mm", "force_n"])
        w.writerows(rows)
    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump({"format": "tactile-dataset/1", "kind": "tactip", "sensor_spec": "virtual-tactip/1",
                   "width": SIZE, "height": SIZE,
                   "generator": "scripts/tactip_independent.py (numpy, from sensors.md)",
                   "seed": seed, "count": count}, f, indent=1)


def cli(usage, main):
    """`main(OUT, COUNT, SEED)` from the command line: bad arguments and
    errors in one line, SIGTERM and Ctrl-C leaving nothing."""
    if len(sys.argv) != 4:
        sys.exit(usage)
    try:
        count, seed = int(sys.argv[2]), int(sys.argv[3])
    except ValueError:
        sys.exit(f"COUNT and SEED are whole numbers, got {sys.argv[2]!r} and {sys.argv[3]!r}\n{usage}")
    # SIGTERM ends the run as Ctrl-C does: the staging folder removed.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    try:
        main(sys.argv[1], count, seed)
    except (OSError, ValueError) as e:
        sys.exit(f"error: {e}")
    except KeyboardInterrupt:
        sys.exit(130)


if __name__ == "__main__":
    cli("usage: python scripts/tactip_independent.py OUT COUNT SEED", main)
