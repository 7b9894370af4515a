"""numpy baseline of the slanted-edge e-SFR (`asnr sfr`, imaging/src/sfr.rs; docs/physics.md,
"Slanted-edge MTF"), the same algorithm written as a careful numpy script would, so that
BENCHMARKS.md can set our time and mean MTF beside it
(`cargo xtask accuracy --only sfr`, bench/src/bin/accuracy/sfr.rs).

Input: a .npy file holding one 2-D float64 image with one near-vertical edge filling it (the
example writes the exact image of a Gaussian-blurred, pixel-integrated edge). Steps:

1. per row, the centroid of the derivative (I[x+1] - I[x-1])/2, first under a Hamming window of
   half-width W/4 about the image's middle column, then twice under one of half-width
   clamp(W/8, 8, 32) about the fitted line x_e(y) = a + b y (least squares);
2. rows: the middle ones spanning a whole number of pixel phases (|tan theta| rows an integer),
   two trimmed at each end first;
3. ESF: each pixel within the reach R (16 px along the normal, less where the image ends) binned
   by 4 (x - x_e(y)) (quarter-pixel bins), positions along the normal (x - x_e) cos theta;
4. LSF: the central difference of the binned ESF, times a window flat over the middle half of
   +-(R - |c|) about its centroid c with Hamming tapers; its transform at f = 0, 0.01, ..., 1
   cycles/pixel, |O(f)|/|O(0)| divided by sinc(f b) sin(2 pi f b)/(2 pi f b), b = cos theta / 4;
5. the mean MTF to Nyquist by Simpson's rule on 50 intervals.

Output: one JSON line, `mean_mtf`, `mtf_nyquist`, `edge_angle_deg` and `seconds` (the median
wall time of repeated calls after a warm-up, numpy's BLAS held to one thread).
"""

import json
import os
import sys
import time

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402


def hamming(d, half):
    return np.where(np.abs(d) < half, 0.54 + 0.46 * np.cos(np.pi * d / half), 0.0)


def tapered(d, half):
    flat = half / 2.0
    return np.where(np.abs(d) <= flat, 1.0, hamming(np.abs(d) - flat, half - flat))


def sfr(image):
    h, w = image.shape
    deriv = np.zeros_like(image)
    deriv[:, 1:-1] = (image[:, 2:] - image[:, :-2]) / 2.0
    if deriv.sum() < 0:
        deriv = -deriv
    lines = np.arange(2, h - 2, dtype=float)
    cols = np.arange(w, dtype=float)
    fit = np.array([(w - 1) / 2.0, 0.0])
    half = max(w / 4.0, 8.0)
    for _ in range(3):
        centre = fit[0] + fit[1] * lines
        weights = hamming(cols[None, :] - centre[:, None], half)
        d = deriv[2 : h - 2, :] * weights
        d[:, 0] = d[:, -1] = 0.0
        s0 = d.sum(axis=1)
        ok = s0 > 0
        x = (d * cols[None, :]).sum(axis=1)[ok] / s0[ok]
        b, a = np.polyfit(lines[ok], x, 1)
        fit = np.array([a, b])
        half = min(max(w / 8.0, 8.0), 32.0)
    slope = fit[1]
    n_all = len(lines)
    phases = np.floor(n_all * abs(slope))
    used = int(min(max(round(phases / abs(slope)), 1), n_all))
    first = int(lines[0]) + (n_all - used) // 2
    rows = np.arange(first, first + used, dtype=float)
    cos = 1.0 / np.sqrt(1.0 + slope**2)
    centre = fit[0] + fit[1] * rows
    reach = min(np.min(np.minimum(centre - 1.0, (w - 2) - centre)) * cos, 16.0)
    b = cos / 4.0
    reach = np.floor(reach / b) * b
    bins = int(round(2 * reach / b))
    offset = (cols[None, :] - centre[:, None]) * cos
    k = np.floor((offset + reach) / b + 1e-9)
    inside = (k >= 0) & (k < bins)
    values = image[rows.astype(int), :]
    count = np.bincount(k[inside].astype(int), minlength=bins)
    total = np.bincount(k[inside].astype(int), weights=values[inside], minlength=bins)
    esf = total / count
    centres = (np.arange(bins) + 0.5) * b - reach
    lsf = (esf[2:] - esf[:-2]) / 2.0
    pos = centres[1:-1]
    c = np.clip((lsf * pos).sum() / lsf.sum(), -reach / 2, reach / 2)
    lsf = lsf * tapered(pos - c, reach - abs(c))
    f = np.arange(101) * 0.01
    o = np.abs(np.exp(-2j * np.pi * f[:, None] * pos[None, :]) @ lsf)
    x = np.pi * f * b
    with np.errstate(invalid="ignore", divide="ignore"):
        transfer = np.where(x == 0, 1.0, np.sin(x) / x * np.sin(2 * x) / (2 * x))
    mtf = o / o[0] / transfer
    simpson = np.ones(51)
    simpson[1:-1:2] = 4.0
    simpson[2:-1:2] = 2.0
    mean = 2.0 * (simpson * mtf[:51]).sum() * 0.01 / 3.0
    return mean, mtf[50], np.degrees(np.arctan(slope))


def main():
    image = np.load(sys.argv[1])
    sfr(image)
    times = []
    for _ in range(int(sys.argv[2]) if len(sys.argv) > 2 else 21):
        t0 = time.perf_counter()
        mean, nyquist, angle = sfr(image)
        times.append(time.perf_counter() - t0)
    print(json.dumps({"mean_mtf": mean, "mtf_nyquist": nyquist, "edge_angle_deg": angle, "seconds": float(np.median(times))}))


if __name__ == "__main__":
    main()
