"""The short Gauss-Legendre rules across the pupil's v coordinate (optics/src/radial.rs,
`small_rule`): the largest phase turn theta for which an n-point rule on [0, 1] integrates
cos(phi0 + theta p(v)) to eps, for p = v^2 and p = v^4 (the phase across v is a function of v^2:
docs/physics.md, "Designs given as data"), against a 200-point rule, over phi0 in
{0, 0.5, 1, 1.5, 2.3}. The error models in `small_rule` are fitted to the rows `h4` and `h8` of this table.

The rows `h4` and `h8` are the rules `small_rule` uses (since 2026-12-06; the rows `4` and `8`
are the n-point rules on [0, 1] it used before): the positive half of the 2n-point rule on
[-1, 1], n nodes on [0, 1] with the 2n-point rule's weights. The integrand is even in v (a
function of v^2), so that rule is exact for polynomials of degree 2n - 1 in v^2 where the
n-point rule on [0, 1] is exact to degree n - 1: the same lanes hold a larger theta
(docs/physics.md, "Designs given as data" and "The flat lens's exact image").

Usage: python3 xtask/baselines/short_rules.py
Prints one line per shape and rule: `shape n eps:theta ...` (`hn` for the half rules).
"""
import numpy as np
from numpy.polynomial.legendre import leggauss

RULES = {n: leggauss(n) for n in (4, 8, 200)}


def integral(n, f):
    x, w = RULES[n]
    return 0.5 * (w * f(0.5 * (x + 1.0))).sum()


def half_integral(n, f):
    """The positive half of the 2n-point rule on [-1, 1]: n nodes, for f even in v."""
    x, w = leggauss(2 * n)
    keep = x > 0
    return (w[keep] * f(x[keep])).sum()


def largest_theta(n, shape, eps, rule=integral):
    best = 0.0
    for theta in np.geomspace(1e-4, 20.0, 600):
        error = max(
            abs(rule(n, lambda v: np.cos(p0 + theta * shape(v))) - integral(200, lambda v: np.cos(p0 + theta * shape(v))))
            for p0 in (0.0, 0.5, 1.0, 1.5, 2.3)
        )
        if error > eps:
            break
        best = theta
    return best


def main():
    for name, shape in (("v2", lambda v: v * v), ("v4", lambda v: v**4)):
        for n in (4, 8):
            cells = [f"{eps:.0e}:{largest_theta(n, shape, eps):.3g}" for eps in (1e-12, 1e-10, 1e-8, 1e-6)]
            print(name, n, " ".join(cells))
        for n in (4, 8):
            cells = [f"{eps:.0e}:{largest_theta(n, shape, eps, half_integral):.3g}" for eps in (1e-12, 1e-10, 1e-8, 1e-6)]
            print(name, f"h{n}", " ".join(cells))


if __name__ == "__main__":
    main()
