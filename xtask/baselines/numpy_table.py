"""numpy baseline for the accuracy report (`cargo xtask accuracy`): the mean MTF of one ASNR
point of the paper's chromatic metalens behind a tabulated filter, computed the way a careful
numpy script would, so that BENCHMARKS.md can show our engine's time beside it.

The scene is the one of examples/spectrometer.toml: a chromatic lens f(lambda) = f0 lambda0/lambda
(f0 = 3.36 mm, lambda0 = 800 nm, F/2.5 by default) with the detector at f0, a flat source behind
the filter table T(lambda) (CSV `wavelength_nm,transmission`, `#` comment lines, piecewise linear,
zero outside), constant lens efficiency and quantum efficiency, so that the detected weight is
lambda * T(lambda) (paper SI eq. S8); no pixel MTF. The result is the mean over [0, Nyquist]
(Nyquist = 1/(2 p)) of |OTF_poly(nu)|, OTF_poly = int w(l) OTF(nu l F#, W020(l)/l) dl / int w dl,
with the defocus OTF of a circular pupil in the t-form of docs/physics.md,
OTF(s, w) = 4/(pi a) int_0^{acos s} sin[a (cos t - s)] cos t dt, a = 8 pi w s, and
W020(l) = (1 - l/lambda0) f0/(8 F#^2).

Method (product integration, all rules fixed):
- in lambda: the OTF is interpolated by a Legendre polynomial of degree nl - 1 through nl
  Gauss-Legendre nodes over the table's range; the weights are the exact moments of the
  piecewise-linear w(l) against that basis (4-point Gauss-Legendre on every table interval,
  exact for the quadratic l T(l));
- in the pupil angle t: one nt-point Gauss-Legendre rule on [0, acos s];
- in frequency: one nnu-point Gauss-Legendre rule on [0, Nyquist] (sign changes of OTF_poly are
  not located: fine for the spectrometer scene, whose OTF_poly has none below Nyquist).

Timing: the table is read once; the median wall time of repeated calls of `mean_mtf` (after one
warm-up call) is reported, numpy's BLAS held to one thread (OMP/OPENBLAS/MKL_NUM_THREADS=1 unless
already set), as our rows are single-threaded and exclude reading the CSV too.

Usage: python3 xtask/baselines/numpy_table.py TABLE.csv [--f-number 2.5] [--pixel-um 5.2]
           [--nl 96] [--nnu 32] [--nt 32] [--seconds 2] [--sweep-f-numbers LO:HI:N]
Prints `key=value` lines: mean_mtf, median_ms, runs, nl, nnu, nt, numpy.

With `--sweep-f-numbers LO:HI:N` it is the baseline of a sweep instead (BENCHMARKS.md, "A sweep
point"): the mean MTF at N F-numbers evenly spaced from LO to HI (both included), each computed
once, as `asnr sweep --over lens.f_number=LO:HI:N` computes its points; it prints `points`,
`first_mean_mtf`, `last_mean_mtf`, `per_point_ms` (the loop's wall time over N) and `numpy`, and
the whole process is timed from outside.
"""
import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from numpy.polynomial.legendre import leggauss, legvander  # noqa: E402

F0_M = 3.36e-3
LAMBDA0_M = 800e-9


def read_table(path):
    """Wavelengths (m) and transmissions of a `wavelength_nm,transmission` CSV: `#` lines are
    comments, a first row that is not numbers is the column names."""
    rows = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split(",")
            try:
                rows.append((float(fields[0]), float(fields[1])))
            except ValueError:
                if rows:
                    raise
    data = np.array(rows)
    return data[:, 0] * 1e-9, data[:, 1]


def mean_mtf(lam_tab, trans, f_number=2.5, pixel_m=5.2e-6, nl=96, nnu=32, nt=32):
    """Mean MTF over [0, Nyquist] of the chromatic lens behind the table (see the module doc)."""
    lo, hi = lam_tab[0], lam_tab[-1]
    # exact moments of w(l) = l T(l) against the Legendre basis on [lo, hi]
    xg, wg = leggauss(4)
    h = np.diff(lam_tab)
    lg = (lam_tab[:-1, None] + h[:, None] * (xg + 1) / 2).ravel()
    wl = (h[:, None] / 2 * wg).ravel() * np.interp(lg, lam_tab, trans) * lg
    moments = legvander((2 * lg - lo - hi) / (hi - lo), nl - 1).T @ wl
    x, _ = leggauss(nl)
    weights = np.linalg.solve(legvander(x, nl - 1).T, moments)
    lam = lo + (hi - lo) * (x + 1) / 2
    # frequencies: Gauss-Legendre on [0, Nyquist]
    nyquist = 0.5 / pixel_m
    xn, wn = leggauss(nnu)
    nu = 0.5 * nyquist * (xn + 1)
    s = nu[None, :] * lam[:, None] * f_number  # (nl, nnu)
    waves = (1 - lam / LAMBDA0_M) * F0_M / (8 * f_number**2) / lam
    # the defocus OTF by nt-point Gauss-Legendre in t on [0, acos s]
    xt, wt = leggauss(nt)
    tmax = np.arccos(np.minimum(s, 1.0))
    t = 0.5 * tmax[..., None] * (xt + 1)
    g = np.cos(t) - s[..., None]
    a = 8 * np.pi * waves[:, None, None] * s[..., None]
    small = np.abs(a) < 1e-14
    kernel = np.where(small, g, np.sin(a * g) / np.where(small, 1.0, a)) * np.cos(t)
    otf = 4 / np.pi * np.sum(0.5 * tmax[..., None] * wt * kernel, axis=-1)
    poly = (weights[:, None] * otf).sum(axis=0) / weights.sum()
    return float(np.sum(0.5 * wn * np.abs(poly)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("table")
    parser.add_argument("--f-number", type=float, default=2.5)
    parser.add_argument("--pixel-um", type=float, default=5.2)
    parser.add_argument("--nl", type=int, default=96)
    parser.add_argument("--nnu", type=int, default=32)
    parser.add_argument("--nt", type=int, default=32)
    parser.add_argument("--seconds", type=float, default=2.0, help="time budget of the repeated runs")
    parser.add_argument("--sweep-f-numbers", help="LO:HI:N, a sweep over the F-number instead")
    args = parser.parse_args()
    lam, trans = read_table(args.table)
    if args.sweep_f_numbers:
        lo, hi, n = args.sweep_f_numbers.split(":")
        f_numbers = np.linspace(float(lo), float(hi), int(n))
        start = time.perf_counter()
        means = [mean_mtf(lam, trans, f, args.pixel_um * 1e-6, args.nl, args.nnu, args.nt) for f in f_numbers]
        elapsed = time.perf_counter() - start
        print(f"points={len(means)}")
        print(f"first_mean_mtf={means[0]!r}")
        print(f"last_mean_mtf={means[-1]!r}")
        print(f"per_point_ms={elapsed / len(means) * 1e3!r}")
        print(f"numpy={np.__version__}")
        return
    run = lambda: mean_mtf(lam, trans, args.f_number, args.pixel_um * 1e-6, args.nl, args.nnu, args.nt)  # noqa: E731
    value = run()  # warm-up
    samples = []
    start = time.perf_counter()
    while len(samples) < 5 or (time.perf_counter() - start < args.seconds and len(samples) < 1000):
        t = time.perf_counter()
        run()
        samples.append(time.perf_counter() - t)
    print(f"mean_mtf={value!r}")
    print(f"median_ms={float(np.median(samples)) * 1e3!r}")
    print(f"runs={len(samples)}")
    print(f"nl={args.nl}")
    print(f"nnu={args.nnu}")
    print(f"nt={args.nt}")
    print(f"numpy={np.__version__}")


if __name__ == "__main__":
    main()
