"""numpy baseline for the accuracy report (`cargo xtask accuracy`): the mean MTF of a metalens
given by its Zemax Binary 2 phase (examples/phase-binary2.toml), computed the way a careful numpy
script would, so that BENCHMARKS.md can show our radial engine's time beside it.

The scene: the paper's aperture (F/2.5, f0 = 3.36 mm, R = 0.672 mm, lambda0 = 800 nm) with the
hyperbolic phase as four Binary 2 coefficients A_i (radians, rho = r/R_norm, R_norm = R, M = 1),
a geometric-phase lens (the radian phase the same at every wavelength), the wavefront against the
exact reference sphere at the detector (docs/physics.md, "Designs given as data"):

    W(q) = (lambda/2 pi) Phi(q) + (sqrt(R^2 q + f0^2) - f0),   q = rho^2,

a flat source behind a Gaussian filter of "spectral range" 2 sqrt(2) sigma = 50 nm at 800 nm,
constant efficiencies, so that the detected weight is lambda G(lambda) (paper SI eq. S8); no
pixel MTF. The result is the mean over [0, Nyquist] (5.2 um pixels) of |OTF_poly(nu)|,
OTF_poly = int w(l) OTF(nu l F#, l) dl / int w dl, with the OTF of the radially symmetric pupil
as the autocorrelation integral of docs/physics.md:

    OTF(s) = (4/pi) int_0^{acos s} sin^2 t int_0^1 cos(k [W(q1) - W(q2)]) dv dt,
    q1 = cos^2 t + v^2 sin^2 t,  q2 = q1 - 4 s (cos t - s).

Method (all rules fixed, vectorized over every node at once):
- in lambda: nl-point Gauss-Hermite nodes of the Gaussian, weights times lambda;
- in t: one nt-point Gauss-Legendre rule on [0, acos s]; in v: one nv-point rule on [0, 1];
- in frequency: one nnu-point Gauss-Legendre rule on [0, Nyquist] (OTF_poly has no sign change
  below Nyquist in this scene).

Timing: the median wall time of repeated calls of `mean_mtf` (after one warm-up call), numpy's
BLAS held to one thread (OMP/OPENBLAS/MKL_NUM_THREADS=1 unless already set). With `--once`, one
call and no timing: the script as a user runs it, for a whole-process time measured from outside
(the interpreter's start and numpy's import included, as `asnr evaluate`'s start is).

Usage: python3 xtask/baselines/numpy_radial.py [--nl 24] [--nnu 16] [--nt 24] [--nv 6]
           [--seconds 2 | --once]
Prints `key=value` lines: mean_mtf, median_ms, runs, nl, nnu, nt, nv, numpy (`--once`: mean_mtf,
nl, nnu, nt, nv, numpy).
"""
import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from numpy.polynomial.hermite import hermgauss  # noqa: E402
from numpy.polynomial.legendre import leggauss  # noqa: E402

F0_M = 3.36e-3
LAMBDA0_M = 800e-9
F_NUMBER = 2.5
RADIUS_M = 0.5 * F0_M / F_NUMBER
BINARY2 = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]
RANGE_M = 50e-9
PIXEL_M = 5.2e-6


def phase(q):
    """The Binary 2 phase (radians) at q = rho^2 (R_norm = R, M = 1)."""
    out = np.zeros_like(q)
    for a in reversed(BINARY2):
        out = (out + a) * q
    return out


def sag(q):
    """sqrt(R^2 q + f0^2) - f0, without cancellation."""
    r2 = RADIUS_M * RADIUS_M * q
    return r2 / (np.sqrt(r2 + F0_M * F0_M) + F0_M)


def mean_mtf(nl, nnu, nt, nv):
    sigma = RANGE_M / (2.0 * np.sqrt(2.0))
    x, w = hermgauss(nl)
    lam = LAMBDA0_M + np.sqrt(2.0) * sigma * x
    weight = w * lam
    weight /= weight.sum()
    nyquist = 1.0 / (2.0 * PIXEL_M)
    xn, wn = leggauss(nnu)
    nu = 0.5 * nyquist * (xn + 1.0)
    xt, wt = leggauss(nt)
    xv, wv = leggauss(nv)
    v = 0.5 * (xv + 1.0)
    wv = 0.5 * wv
    # axes: [lambda, nu, t, v]
    s = (nu[None, :] * lam[:, None] * F_NUMBER)[:, :, None, None]
    t_end = np.arccos(np.minimum(s, 1.0))
    t = 0.5 * t_end * (xt[None, None, :, None] + 1.0)
    cos_t, sin_t = np.cos(t), np.sin(t)
    q1 = cos_t * cos_t + (v * v)[None, None, None, :] * sin_t * sin_t
    q2 = np.maximum(q1 - 4.0 * s * (cos_t - s), 0.0)
    k = (2.0 * np.pi / lam)[:, None, None, None]
    dphi = phase(q1) - phase(q2) + k * (sag(q1) - sag(q2))
    inner = (np.cos(dphi) * wv[None, None, None, :]).sum(axis=3)
    otf = (4.0 / np.pi) * 0.5 * t_end[:, :, 0, 0] * (wt[None, None, :] * sin_t[..., 0] ** 2 * inner).sum(axis=2)
    otf = np.where(s[..., 0, 0] < 1.0, otf, 0.0)
    poly = (weight[:, None] * otf).sum(axis=0)
    return 0.5 * (np.abs(poly) * wn).sum()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--nl", type=int, default=24)
    parser.add_argument("--nnu", type=int, default=16)
    parser.add_argument("--nt", type=int, default=24)
    parser.add_argument("--nv", type=int, default=6)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--once", action="store_true")
    args = parser.parse_args()
    value = mean_mtf(args.nl, args.nnu, args.nt, args.nv)
    if args.once:
        print(f"mean_mtf={value:.15f}")
        for key in ("nl", "nnu", "nt", "nv"):
            print(f"{key}={getattr(args, key)}")
        print(f"numpy={np.__version__}")
        return
    times = []
    deadline = time.perf_counter() + args.seconds
    while len(times) < 3 or time.perf_counter() < deadline:
        start = time.perf_counter()
        mean_mtf(args.nl, args.nnu, args.nt, args.nv)
        times.append(time.perf_counter() - start)
    times.sort()
    print(f"mean_mtf={value:.15f}")
    print(f"median_ms={1e3 * times[len(times) // 2]:.4f}")
    print(f"runs={len(times)}")
    print(f"nl={args.nl}")
    print(f"nnu={args.nnu}")
    print(f"nt={args.nt}")
    print(f"nv={args.nv}")
    print(f"numpy={np.__version__}")


if __name__ == "__main__":
    main()
