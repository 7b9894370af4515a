"""numpy baseline for the accuracy report (`cargo xtask accuracy --only map`): the 40 x 100
F-number x band map of the paper scene (examples/paper-theory.toml swept as
`asnr sweep --over lens.f_number=1.4:5:40 --over spectrum.range_nm=2:300:100`), computed as the
strongest numpy evaluation we know of: the closed form of the spectral integral, vectorized over
the whole grid at once, so that BENCHMARKS.md can show the sweep's time beside it.

The scene: the paper's chromatic metalens (f0 = 3.36 mm, lambda0 = 800 nm), whose defocus is
affine in lambda (docs/physics.md, "Sign of the wavefront"):

    W020(lambda) = (1 - lambda/lambda0) f0 / (8 F#^2),

a flat source behind a Gaussian filter of "spectral range" 2 sqrt(2) sigma at 800 nm, constant
efficiencies, so that the detected weight is lambda G(lambda) (paper SI eq. S8); 5.2 um pixels,
no pixel MTF. Each point's result is the mean over [0, Nyquist] of |OTF_poly(nu)| with the
defocused OTF of a circular pupil in its t-form (docs/physics.md, "Exact defocused OTF").

The closed form (docs/physics.md, "Polychromatic OTF", and optics/src/closed.rs): with
s = nu F# lambda and a = 8 pi W020 nu F# affine in lambda, swapping the integrals over lambda and
the pupil angle t (t <= acos s  <=>  lambda <= c/beta, c = cos t, beta = nu F#) gives

    W OTF_poly(nu) = (4/pi) int_0^{pi/2} sin^2 t Re E(cos t) dt,
    E(c) = int_{-inf}^{(c/beta - mu)/sigma} Q(x) exp(-x^2/2 + i(phi0 + phi1 x + phi2 x^2)) dx,

a Gaussian integral with a complex quadratic exponent: error functions of complex argument (the
scaled erfcx, Weideman's rational series with 36 terms, SIAM J. Numer. Anal. 31 (1994) 1497, and
its asymptotic series beyond |z| = 12; the same approximation as optics/src/faddeeva.rs, here
vectorized) for the moment x^0 and an endpoint term for x^1 (Q(x) = sigma (mu + sigma x) for the
weight lambda G). The spectrum's part below lambda = 0 (at most 3e-14 of the weight, at 300 nm)
is ignored. What is left per point is the integral over t, done by a fixed composite
Gauss-Legendre rule over the part of the pupil angle where the spectrum has weight
(c >= beta (mu - 8 sigma)), its panel count per point from the phase E turns through there
(8 pi beta |W020'| (c-window) sigma-scaled, as a careful script would), and the frequency rule:
a fixed composite Gauss-Legendre rule on [0, Nyquist].

Vectorization: every point of the grid that needs the same t-rule is one block: arrays of
[points, nu, t] evaluated at once (bounded to BLOCK elements a block), numpy's BLAS on one thread
(OMP/OPENBLAS/MKL_NUM_THREADS=1 unless already set). The harness also times the whole process
from outside (the interpreter's start and numpy's import included, as the sweep's start is).

Usage: python3 xtask/baselines/numpy_map.py [--scale 0.1] [--nu-scale 0.5] [--stride 1]
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
# elements of one block of the [point, nu, t] arrays (bounds the memory: 2e6 x 16 B x a few)
BLOCK = 2_000_000
# Gaussian sigmas below the centre beyond which the spectrum's weight is ignored (e^{-32}: 1e-14)
TAIL = 8.0

# Weideman's series for erfcx (N = 36 terms), the coefficients a_1..a_N of optics/src/faddeeva.rs
_N = 36
_L = np.sqrt(_N / np.sqrt(2.0))


def _weideman():
    m = 2 * _N
    k = np.arange(-m + 1, m)
    theta = k * np.pi / m
    t = _L * np.tan(0.5 * theta)
    f = np.exp(-t * t) * (_L * _L + t * t)
    a = np.array([(f * np.cos(n * theta)).sum() / (2 * m) for n in range(_N + 1)])
    return a[1:][::-1].copy()  # highest power first, for the Horner loop


_COEFFICIENTS = _weideman()
_ROOT_PI = np.sqrt(np.pi)


def erfcx(z):
    """exp(z^2) erfc(z) for Re z >= 0 (elementwise)."""
    zeta = 1j * z
    inv = 1.0 / (_L - 1j * zeta)
    big_z = (_L + 1j * zeta) * inv
    p = np.zeros_like(z)
    for c in _COEFFICIENTS:
        p = p * big_z + c
    series = 2.0 * p * inv * inv + inv / _ROOT_PI
    far = np.abs(z) > 12.0
    if far.any():
        zf = z[far]
        inv_2z2 = 1.0 / (2.0 * zf * zf)
        term = np.ones_like(zf)
        total = term.copy()
        for k in range(1, 12):
            term = term * (-inv_2z2 * (2 * k - 1))
            total = total + term
        series[far] = total / (zf * _ROOT_PI)
    return series


_RULES = {}


def rule(n):
    """n-point Gauss-Legendre nodes and weights on [0, 1]."""
    if n not in _RULES:
        x, w = leggauss(n)
        _RULES[n] = (0.5 * (x + 1.0), 0.5 * w)
    return _RULES[n]


def composite(panels, per_panel=16):
    """Composite Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = rule(per_panel)
    edges = np.linspace(0.0, 1.0, panels + 1)
    h = np.diff(edges)
    return (edges[:-1, None] + h[:, None] * x[None, :]).ravel(), (h[:, None] * w[None, :]).ravel()


def _constants(f_number, sigma, nu):
    """Per-frequency constants of the closed form (optics/src/closed.rs, `at_frequency`)."""
    mu = LAMBDA0_M
    k = F0_M / (8.0 * f_number * f_number)
    w0, w1 = k, -k / LAMBDA0_M  # W020 = w0 + w1 lambda
    beta = nu * f_number
    scale = 8.0 * np.pi * beta
    a_mu, a1 = scale * (w0 + w1 * mu), scale * w1
    phi2 = -a1 * beta * sigma * sigma
    return beta, a_mu, a1, phi2


def _zones(f_number, sigma, nu):
    """The two zones of c = cos t where E has weight: the cut zone [c_lo, c_cut], where the cut
    lambda <= c/beta runs through the Gaussian's +-TAIL sigma (a narrow step, 2 TAIL beta sigma
    wide), and the uncut zone [c_cut, c_top], where E is the whole Gaussian integral, a bump of
    width w = sqrt(1 + 4 phi2^2)/|sigma a1| about c* = beta mu + beta a_mu/a1 (optics/src/closed.rs,
    `envelope`), cut 10 widths beyond it (e^{-50}); and the phase E turns through across each
    (its rate in c is a(lambda) at the weighted wavelengths: TAIL sigma from the centre, and the
    saddle point |Re m| = 2|phi1 phi2|/(1 + 4 phi2^2) sigma in the uncut zone)."""
    mu = LAMBDA0_M
    beta, a_mu, a1, phi2 = _constants(f_number, sigma, nu)
    c_lo = np.clip(beta * (mu - TAIL * sigma), 0.0, 1.0)
    c_cut = np.clip(beta * (mu + TAIL * sigma), 0.0, 1.0)
    c_star = beta * mu + beta * a_mu / a1
    width = np.sqrt(1.0 + 4.0 * phi2 * phi2) / np.abs(sigma * a1)
    c_top = np.clip(c_star + 10.0 * width, c_cut, 1.0)
    spread = np.abs(a1 * sigma)
    cut_phase = (c_cut - c_lo) * (np.abs(a_mu) + spread * TAIL)
    phi1 = sigma * (a1 * (c_top - beta * mu) - beta * a_mu)
    saddle = np.abs(2.0 * phi1 * phi2 / (1.0 + 4.0 * phi2 * phi2))
    uncut_phase = (c_top - c_cut) * (np.abs(a_mu) + spread * (TAIL + saddle))
    return c_lo, c_cut, c_top, cut_phase, uncut_phase


def spectral(f_number, sigma, nu, c, whole=False):
    """E(c) / W, the closed form of the spectral integral over lambda <= c/beta; `whole`: over the
    whole line (the uncut zone, where the cut lies beyond TAIL sigma: e^{-TAIL^2/2} = 1e-14)."""
    mu = LAMBDA0_M
    beta, a_mu, a1, phi2 = _constants(f_number, sigma, nu)
    a = 0.5 - 1j * phi2
    sqrt_a = np.sqrt(a)
    inv_2a = 1.0 / (2.0 * a)
    d = c - beta * mu
    phi0 = a_mu * d
    phi1 = sigma * (a1 * d - beta * a_mu)
    x_hi = (c / beta - mu) / sigma
    m = 1j * phi1 * inv_2a
    big_k = 1j * phi0 + a * m * m
    if whole:
        # M0 = e^K sqrt(pi/A), M1 = 0
        return (mu + sigma * m) * np.exp(big_k) * (_ROOT_PI / sqrt_a) / (mu * np.sqrt(2.0 * np.pi))
    # the integrand at the cut, where the phase vanishes: real
    e_hi = np.exp(-0.5 * np.minimum(x_hi * x_hi, 1400.0))
    z = sqrt_a * (x_hi - m)
    right = z.real >= 0.0
    w = erfcx(np.where(right, z, -z))
    # M0 = int_{-inf}^{x_hi} e^{K - A (x - m)^2} dx in bounded forms on both half planes
    # (optics/src/closed.rs, `moments`): e^K erfc(z) = e_hi erfcx(z)
    m0 = np.where(right, 2.0 * np.exp(big_k) - e_hi * w, e_hi * w) * (0.5 * _ROOT_PI / sqrt_a)
    m1 = -e_hi * inv_2a
    # Q(x) = sigma (mu + sigma x) with x = y + m; the weight W = sigma mu sqrt(2 pi)
    return ((mu + sigma * m) * m0 + sigma * m1) / (mu * np.sqrt(2.0 * np.pi))


def otf_block(f_number, sigma, nu, rules):
    """OTF_poly at [points, nu] for the points' F-numbers and sigmas (arrays [points, 1, 1]) and
    frequencies nu [1, n_nu, 1]: (4/pi) int sin^2 t Re E(cos t) dt over the two zones, each by its
    composite Gauss-Legendre rule on [0, 1] (`rules`: nodes [n], weights [n]) mapped to the zone's
    t-interval."""
    c_lo, c_cut, c_top, _, _ = _zones(f_number, sigma, nu)
    total = 0.0
    for (lo, hi), (x, wx), whole in zip([(c_lo, c_cut), (c_cut, c_top)], rules, [False, True]):
        t_lo, t_hi = np.arccos(hi), np.arccos(lo)
        t = t_lo + (t_hi - t_lo) * x[None, None, :]
        integrand = np.sin(t) ** 2 * spectral(f_number, sigma, nu, np.cos(t), whole).real
        total = total + (t_hi - t_lo)[..., 0] * (integrand @ wx)
    return (4.0 / np.pi) * total


def t_panels(f_number, sigma, nu, scale):
    """Gauss-Legendre panels (16 points each) for the cut and the uncut zone of each (point,
    frequency): the phase E turns through across each zone, a panel per 12/scale radians."""
    _, _, _, cut_phase, uncut_phase = _zones(f_number, sigma, nu)
    return (np.ceil(1.0 + scale * cut_phase / 12.0).astype(int), np.ceil(1.0 + scale * uncut_phase / 12.0).astype(int))


def nu_panels(f_number, sigma, nu_scale):
    """Gauss-Legendre panels (16 points each) on [0, Nyquist] for a point: one, and one more per
    `16/nu_scale` radians of the spread of the defocus phase across the band at Nyquist,
    8 pi nu_N F# |W020'| sigma (where |OTF_poly| has its dips and kinks)."""
    nyquist = 1.0 / (2.0 * PIXEL_M)
    k = F0_M / (8.0 * f_number * f_number)
    spread = 8.0 * np.pi * nyquist * f_number * (k / LAMBDA0_M) * sigma
    return int(np.ceil(1.0 + nu_scale * spread / 16.0))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scale", type=float, default=0.1, help="multiplies the phase-driven t panels")
    parser.add_argument("--nu-scale", type=float, default=0.5, help="multiplies the phase-driven nu panels")
    parser.add_argument("--stride", type=int, default=1, help="every STRIDE-th point only (a quick check)")
    args = parser.parse_args()
    grid = [(f, r) for f in F_NUMBERS for r in RANGES_NM]
    grid = grid[:: max(1, args.stride)]
    start = time.perf_counter()
    nyquist = 1.0 / (2.0 * PIXEL_M)
    # every (point, frequency node) of the grid as one flat item
    items_f, items_sigma, items_nu, items_w, items_point = [], [], [], [], []
    for i, (f, r) in enumerate(grid):
        sigma = r * 1e-9 / (2.0 * np.sqrt(2.0))
        x, w = composite(nu_panels(f, sigma, args.nu_scale))
        items_f.append(np.full(x.size, f))
        items_sigma.append(np.full(x.size, sigma))
        items_nu.append(nyquist * x)
        items_w.append(w)
        items_point.append(np.full(x.size, i))
    f_all, sigma_all, nu_all = (np.concatenate(v) for v in (items_f, items_sigma, items_nu))
    w_all, point_all = np.concatenate(items_w), np.concatenate(items_point)
    cut, uncut = t_panels(f_all, sigma_all, nu_all, args.scale)
    otf = np.zeros(f_all.size)
    # items of the same pair of t-rules, evaluated at once: arrays [item, t]
    keys = cut * 4096 + uncut
    for key in np.unique(keys):
        members = np.nonzero(keys == key)[0]
        rules = [composite(int(key // 4096)), composite(int(key % 4096))]
        rows = max(1, BLOCK // sum(x.size for x, _ in rules))
        for begin in range(0, members.size, rows):
            chosen = members[begin : begin + rows]
            column = lambda v: v[chosen][:, None, None]  # noqa: E731
            otf[chosen] = otf_block(column(f_all), column(sigma_all), column(nu_all), rules)[:, 0]
    values = np.bincount(point_all, weights=np.abs(otf) * w_all, minlength=len(grid))
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
