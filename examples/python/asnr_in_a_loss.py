"""The ASNR as one term of a loss: −ASNR plus a penalty on the profile's slope, minimized with
scipy (the exact gradient, `asnr.value_and_grad`) and with JAX (`asnr.jax.asnr_function`).

The lens is the Binary 2 metalens of examples/phase-binary2.toml (a hyperbolic profile,
Φ(ρ) = M Σ A_i ρ^{2i}, ρ = r/R_norm, A_1…A_4 in radians; docs/physics.md, "Zemax Binary 2") with
two more terms, A_5 = A_6 = 0, so the search has six coefficients. A metasurface realizes the
phase's slope dΦ/dr with a local grating of period Λ(r) = 2π/|dΦ/dr|, and a fabrication process
has a smallest period it can make: the penalty is

    P(A) = μ · mean over 64 radii of max(0, Λ_min/Λ(r) − 1)²,   μ = 100

with Λ_min = 5 µm, above the smallest period of the hyperbola (4.08 µm at the edge of the F/2.5
aperture), so the hyperbola pays a penalty and the search trades ASNR against slope.
The loss is −ASNR + P: the ASNR's gradient comes from the engines, the penalty's from numpy
(scipy) or from JAX's own differentiation.

    pip install "asnr-….whl[jax]"     # or, from the clone: pip install "./python[jax]"
    python examples/python/asnr_in_a_loss.py

prints the loss, ASNR and smallest period at the start, after scipy.optimize.minimize
(L-BFGS-B, jac=True, 15 iterations) and after 8 steps of gradient descent in JAX (jax.jit of
jax.value_and_grad of the loss, a fixed step of 2 rad² per unit of the gradient). `--steps` sets
the JAX steps, `--maxiter` scipy's iterations.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from types import ModuleType

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

import asnr
import asnr.jax

ROOT = Path(__file__).resolve().parents[2]
KEYS = [f"lens.binary2[{i}]" for i in range(6)]
#: the smallest grating period the process makes, mm
PERIOD_MIN_MM = 5e-3
#: the penalty's weight, in ASNR units
WEIGHT = 100.0
#: the radii where the slope is checked, as a fraction of the aperture's radius
RHO = np.linspace(0.0, 1.0, 64)


def slope_basis(n: int, order: float, norm_radius_mm: float, aperture_ratio: float, rho: np.ndarray = RHO) -> np.ndarray:
    """B with dΦ/dr = B @ A at r = rho × the aperture's radius: B[j, i−1] =
    (M/R_norm) 2i ρ_j^{2i−1}, ρ_j = rho_j × aperture / R_norm, rad/mm per rad."""
    rho = rho[:, None] * aperture_ratio
    i = np.arange(1, n + 1)[None, :]
    return order / norm_radius_mm * 2 * i * rho ** (2 * i - 1)


def penalty(a, basis, xp: ModuleType = np):
    """P(A), written once for numpy and jax.numpy (`xp`)."""
    excess = xp.maximum(0.0, xp.abs(basis @ a) * PERIOD_MIN_MM / (2 * np.pi) - 1.0)
    return WEIGHT * xp.mean(excess**2)


def penalty_gradient(a: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """∂P/∂A in closed form (for scipy; JAX differentiates `penalty` itself)."""
    slope = basis @ a
    excess = np.maximum(0.0, np.abs(slope) * PERIOD_MIN_MM / (2 * np.pi) - 1.0)
    return WEIGHT * 2 / len(slope) * basis.T @ (excess * np.sign(slope) * PERIOD_MIN_MM / (2 * np.pi))


def smallest_period_um(a: np.ndarray, geometry: tuple[float, float, float]) -> float:
    slope = slope_basis(a.size, *geometry, rho=np.linspace(0.0, 1.0, 2001)) @ a
    return float(2 * np.pi / np.max(np.abs(slope)) * 1e3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maxiter", type=int, default=15, help="scipy's iterations")
    parser.add_argument("--steps", type=int, default=8, help="JAX's gradient-descent steps")
    args = parser.parse_args()

    design = asnr.load(ROOT / "examples" / "phase-binary2.toml")
    scene = design.with_({"lens.binary2[4]": 0.0, "lens.binary2[5]": 0.0})
    # the aperture's radius f/(2N) against Zemax's normalization radius (both 0.672 mm here)
    order, norm_radius_mm = 1.0, 0.672
    aperture_ratio = 3.36 / (2 * 2.5) / norm_radius_mm
    geometry = (order, norm_radius_mm, aperture_ratio)

    # --- scipy: minimize(fun, x0, jac=True) with the exact gradient ---------------------------
    asnr_vg = asnr.value_and_grad(scene, KEYS)
    x0 = asnr_vg.x0

    basis = slope_basis(len(KEYS), *geometry)

    def loss_and_grad(a: np.ndarray) -> tuple[float, np.ndarray]:
        value, grad = asnr_vg(a)
        return -value + penalty(a, basis), -grad + penalty_gradient(a, basis)

    def show(name: str, a: np.ndarray, seconds: float | None = None, calls: int | None = None) -> None:
        value = asnr.evaluate(design.with_(dict(zip(KEYS, map(float, a))))).asnr
        took = "" if seconds is None else f"  ({calls} evaluations with gradient, {seconds:.1f} s)"
        loss = -value + float(penalty(a, basis))
        print(f"{name:<22} loss {loss:+.5f}  ASNR {value:.5f}  smallest period {smallest_period_um(a, geometry):.3f} µm{took}")

    show("hyperbola (start)", x0)
    start = time.perf_counter()
    result = scipy.optimize.minimize(loss_and_grad, x0, jac=True, method="L-BFGS-B", options={"maxiter": args.maxiter})
    show("scipy L-BFGS-B", result.x, time.perf_counter() - start, result.nfev)
    print("  A =", np.array2string(result.x, precision=4))

    # --- JAX: the same loss, differentiated by JAX, the ASNR through the bridge ---------------
    jax.config.update("jax_enable_x64", True)
    f = asnr.jax.asnr_function(scene, KEYS)

    @jax.jit
    def step(a):
        value, grad = jax.value_and_grad(lambda a: -f(a) + penalty(a, jnp.asarray(basis), jnp))(a)
        return value, grad

    a = jnp.asarray(x0)
    rate = 2.0  # rad² per unit of the loss: below 2/(the loss's largest curvature)
    start = time.perf_counter()
    for k in range(args.steps):
        value, grad = step(a)
        print(f"  step {k}: loss {float(value):+.5f}")
        a = a - rate * grad
    show("jax gradient descent", np.asarray(a), time.perf_counter() - start, args.steps)
    print("  A =", np.array2string(np.asarray(a), precision=4))


if __name__ == "__main__":
    main()
