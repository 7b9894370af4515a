"""numpy baseline for the accuracy report (`cargo xtask accuracy --only map`): the 40 x 100
F-number x band map of the paper scene (examples/paper-theory.toml swept as
`asnr sweep --over lens.f_number=1.4:5:40 --over spectrum.range_nm=2:300:100`), computed the way
a careful numpy script would, so that BENCHMARKS.md can show the sweep's time beside it.

The scene: the paper's chromatic metalens (f0 = 3.36 mm, lambda0 = 800 nm), whose defocus is
affine in lambda (docs/physics.md, "Sign of the wavefront"):

    W020(lambda) = (1 - lambda/lambda0) f0 / (8 F#^2),

a flat source behind a Gaussian filter of "spectral range" 2 sqrt(2) sigma at 800 nm, constant
efficiencies, so that the detected weight is lambda G(lambda) (paper SI eq. S8); 5.2 um pixels,
no pixel MTF. Each point's result is the mean over [0, Nyquist] of |OTF_poly(nu)|,
OTF_poly = int w(l) OTF(nu l F#, W020(l)) dl / int w dl, with the defocused OTF of a circular
pupil (docs/physics.md, "Exact defocused OTF"):

    OTF(s, a) = (4/pi) int_0^{acos s} sin^2 t cos[a (cos t - s)] dt,   a = 8 pi W020 nu F#.

Method (fixed Gauss-Legendre rules, vectorized over every node of a point at once; the node
counts of each point chosen up front from the phases its rules must resolve, as any careful
script would, with `--scale` multiplying them all):
- in lambda: composite Gauss-Legendre over mu +- 6 sigma (the weight beyond is 2e-9 of it;
  cut at lambda > 0), 16 nodes a panel, a panel per 20 rad of the spectral phase
  8 pi nu F# |dW020/dl| 12 sigma at Nyquist;
- in t: one Gauss-Legendre rule on [0, acos s], its points from the largest defocus phase a;
- in frequency: composite Gauss-Legendre on [0, Nyquist], panels from the defocus spread's phase.

Timing: the wall time of the whole map (after numpy's import), numpy's BLAS held to one thread
(OMP/OPENBLAS/MKL_NUM_THREADS=1 unless already set). The harness also times the whole process
from outside (the interpreter's start and numpy's import included, as the sweep's start is).

Usage: python3 xtask/baselines/numpy_map.py [--scale 0.8] [--stride 1]
Prints `key=value` lines (seconds, points, numpy, scale), then `values:` and one CSV line per point
`f_number,range_nm,mean_mtf` in the sweep's order (F-number outer, band inner).
"""
import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from numpy.polynomial.legendre import leggauss  # noqa: E402

F0_M = 3.36e-3
LAMBDA0_M = 800e-9
PIXEL_M = 5.2e-6
F_NUMBERS = np.linspace(1.4, 5.0, 40)
RANGES_NM = np.linspace(2.0, 300.0, 100)
# elements of one block of the [lambda, nu, t] array (bounds the memory: 4e6 x 8 B x a few)
BLOCK = 4_000_000

_RULES = {}


def rule(n):
    """n-point Gauss-Legendre nodes and weights on [0, 1]."""
    if n not in _RULES:
        x, w = leggauss(n)
        _RULES[n] = (0.5 * (x + 1.0), 0.5 * w)
    return _RULES[n]


def composite(lo, hi, panels, per_panel=16):
    """Composite Gauss-Legendre nodes and weights on [lo, hi]."""
    x, w = rule(per_panel)
    edges = np.linspace(lo, hi, panels + 1)
    h = np.diff(edges)
    nodes = (edges[:-1, None] + h[:, None] * x[None, :]).ravel()
    weights = (h[:, None] * w[None, :]).ravel()
    return nodes, weights


def mean_mtf(f_number, range_nm, scale):
    mu = LAMBDA0_M
    sigma = range_nm * 1e-9 / (2.0 * np.sqrt(2.0))
    k = F0_M / (8.0 * f_number * f_number)  # W020 = k (1 - lambda/lambda0)
    nyquist = 1.0 / (2.0 * PIXEL_M)
    lo, hi = max(mu - 6.0 * sigma, 1e-3 * mu), mu + 6.0 * sigma
    # the spectral phase across the window at Nyquist, and the largest defocus phase in t
    spectral_phase = 8.0 * np.pi * nyquist * f_number * (k / LAMBDA0_M) * (hi - lo)
    a_max = 8.0 * np.pi * nyquist * f_number * k * max(abs(1.0 - lo / mu), abs(1.0 - hi / mu))
    spread_phase = 8.0 * np.pi * nyquist * f_number * (k / LAMBDA0_M) * sigma
    panels_l = int(np.ceil(1.0 + scale * spectral_phase / 40.0))
    nt = int(np.ceil(16.0 + scale * 0.25 * a_max))
    panels_nu = int(np.ceil(2.0 + scale * spread_phase / 32.0))
    lam, wl = composite(lo, hi, panels_l)
    weight = wl * lam * np.exp(-0.5 * ((lam - mu) / sigma) ** 2)
    weight /= weight.sum()
    nu, wn = composite(0.0, nyquist, panels_nu)
    xt, wt = rule(nt)
    w020 = k * (1.0 - lam / mu)
    poly = np.zeros_like(nu)
    rows = max(1, BLOCK // (lam.size * nt))
    for start in range(0, nu.size, rows):
        part = nu[start : start + rows]
        s = part[None, :] * lam[:, None] * f_number  # [lambda, nu]
        a = 8.0 * np.pi * w020[:, None] * part[None, :] * f_number
        t_end = np.arccos(np.minimum(s, 1.0))
        t = t_end[..., None] * xt  # [lambda, nu, t]
        cos_t = np.cos(t)
        integrand = (1.0 - cos_t * cos_t) * np.cos(a[..., None] * (cos_t - s[..., None]))
        otf = (4.0 / np.pi) * t_end * (integrand @ wt)
        otf = np.where(s < 1.0, otf, 0.0)
        poly[start : start + rows] = weight @ otf
    return (np.abs(poly) * wn).sum() / nyquist


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scale", type=float, default=0.8, help="multiplies the phase-driven node counts")
    parser.add_argument("--stride", type=int, default=1, help="every STRIDE-th point only (a quick check)")
    args = parser.parse_args()
    grid = [(f, r) for f in F_NUMBERS for r in RANGES_NM]
    grid = grid[:: max(1, args.stride)]
    start = time.perf_counter()
    values = [mean_mtf(f, r, args.scale) for f, r in grid]
    seconds = time.perf_counter() - start
    print(f"seconds={seconds:.4f}")
    print(f"points={len(grid)}")
    print(f"scale={args.scale}")
    print(f"numpy={np.__version__}")
    print("values:")
    for (f, r), v in zip(grid, values):
        print(f"{float(f)!r},{float(r)!r},{v:.15f}")


if __name__ == "__main__":
    main()
