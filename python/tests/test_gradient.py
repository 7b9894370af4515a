"""The gradient from Python, and the JAX and PyTorch bridges, against the command line.

`asnr.gradient` must be `asnr gradient --json` (the binary `$ASNR_BIN`, or `target/debug/asnr`)
to the last digit; `asnr.value_and_grad`, `jax.grad` of `asnr.jax.asnr_function` and torch's
autograd of `asnr.torch.asnr_function` must give that gradient. The exactness of the gradient
itself is tested in Rust against central differences of converged evaluations
(`cargo test -p asnr-report --lib gradient`); here one independent check is repeated: the
gradient against central differences of `asnr.evaluate` written in this file.

A bridge's tests are skipped when its package is missing, except where `ASNR_REQUIRE` names it
(`cargo xtask python` sets `ASNR_REQUIRE=jax,scipy`, `cargo xtask torch` `ASNR_REQUIRE=torch`):
there a missing package is a failure.
"""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import asnr

ROOT = Path(__file__).resolve().parents[2]
BINARY2 = ROOT / "examples" / "phase-binary2.toml"
LIBRARY = ROOT / "examples" / "library.toml"
BIN = Path(os.environ.get("ASNR_BIN", ROOT / "target" / "debug" / "asnr"))
REQUIRED = {name.strip() for name in os.environ.get("ASNR_REQUIRE", "").split(",") if name.strip()}

#: Keys of the paper scene whose derivatives the engines compute, with read noise and dark
#: current set so that their derivatives are not zero.
PAPER_SET = ["camera.read_noise_e=3", "camera.dark_current_e_per_s=40"]
PAPER_KEYS = ["exposure.time_ms", "camera.pixel_pitch_um", "camera.read_noise_e", "camera.dark_current_e_per_s", "lens.efficiency"]


def require(name: str) -> ModuleType:
    """The module `name`; skipped if it is missing, unless `ASNR_REQUIRE` names it."""
    if name.split(".")[0] in REQUIRED:
        return importlib.import_module(name)
    return pytest.importorskip(name)


def cli(*args: str) -> bytes:
    """The `asnr` command's stdout (it must succeed)."""
    done = subprocess.run([str(BIN), *args], capture_output=True, check=False)
    assert done.returncode == 0, done.stderr.decode()
    return done.stdout


def cli_gradient(keys: list[str], scene: Path | None = None, set_: list[str] = (), tolerance: str | None = None) -> dict:
    args = ["gradient", "--json"] + ([str(scene)] if scene else [])
    for key in keys:
        args += ["--wrt", key]
    for s in set_:
        args += ["--set", s]
    if tolerance is not None:
        args += ["--tolerance", tolerance]
    return json.loads(cli(*args))


def assert_same_json(ours: dict, theirs: dict, rel: float) -> None:
    """The same fields and keys in the same order, each number within `rel` of the other's."""
    assert list(ours) == list(theirs)
    for field, value in theirs.items():
        if isinstance(value, dict):
            assert list(ours[field]) == list(value), field
            assert list(ours[field].values()) == pytest.approx(list(value.values()), rel=rel), field
        else:
            assert ours[field] == pytest.approx(value, rel=rel), field


#: How far the Binary 2 derivatives of the wheel may be from the command line's: the wheel is
#: built for x86-64-v3 and the `asnr` binary for the native CPU, and the fused multiply-adds of the
#: derivatives' sums round differently (ARCHITECTURE.md, "Build settings"); measured 1 to 3 units
#: in the last place (below 4e-15 relative), so 1e-12 leaves room and still catches any other
#: difference. The paper scene's derivatives (no Binary 2 sums) are equal to the last digit.
ROUNDING = 1e-12


# --- asnr.gradient --------------------------------------------------------------------------


def test_gradient_is_the_command_lines_json_to_the_last_digit():
    ours = asnr.gradient(asnr.load(), PAPER_KEYS, set=PAPER_SET)
    theirs = cli_gradient(PAPER_KEYS, set_=PAPER_SET)
    assert ours == theirs
    assert list(ours) == ["asnr", "mean_mtf", "snr0", "photoelectrons", "gradient", "mean_mtf_gradient", "snr0_gradient", "photoelectrons_gradient"]
    assert list(ours["gradient"]) == PAPER_KEYS
    assert all(v != 0 for v in ours["gradient"].values()), ours["gradient"]
    # set as a dict, and the overrides of the scene itself, give the same
    as_dict = asnr.gradient(asnr.load().with_({"camera.read_noise_e": 3}), PAPER_KEYS, set={"camera.dark_current_e_per_s": 40})
    assert as_dict == theirs
    # a list key as a whole is every entry, each spelled one way; a tolerance is --tolerance's
    ours = asnr.gradient(asnr.load(BINARY2), "lens.binary2", tolerance=1e-8)
    assert_same_json(ours, cli_gradient(["lens.binary2"], BINARY2, tolerance="1e-8"), ROUNDING)
    assert list(ours["gradient"]) == [f"lens.binary2[{i}]" for i in range(4)]
    assert list(asnr.gradient(asnr.load(BINARY2), ["lens.binary2[01]"])["gradient"]) == ["lens.binary2[1]"]


def test_gradient_is_the_central_difference_of_evaluations():
    """∂ASNR/∂key against (ASNR(v + h) − ASNR(v − h))/2h of `asnr.evaluate` at a tolerance of
    1e-10. The keys enter the ASNR smoothly: N ∝ t and ε (f‴ of order f/v³), SNR0 through the
    read and dark noise, and the pixel pitch through N ∝ p² and the Nyquist band; with h = 1e-3 v
    the truncation error is ~h²f‴/6 ≈ 2e-7 f/v and the rounding ~1e-10 f/h, both well under the
    bound, 1e-5 of the gradient's norm (10× the default tolerance of 1e-6)."""
    at = {"exposure.time_ms": 1.23, "camera.pixel_pitch_um": 5.2, "camera.read_noise_e": 3.0, "camera.dark_current_e_per_s": 40.0, "lens.efficiency": 0.15}
    tight = {"options.tolerance": 1e-10}
    g = asnr.gradient(asnr.load().with_({**at, **tight}), PAPER_KEYS)
    norm = np.linalg.norm(list(g["gradient"].values()))
    for key in PAPER_KEYS:
        h = 1e-3 * at[key]
        up = asnr.evaluate(asnr.load().with_({**at, **tight, key: at[key] + h})).asnr
        down = asnr.evaluate(asnr.load().with_({**at, **tight, key: at[key] - h})).asnr
        difference = (up - down) / (2 * h)
        assert abs(difference - g["gradient"][key]) < 1e-5 * norm, (key, difference, g["gradient"][key])


def test_a_key_without_a_gradient_is_refused_naming_it():
    paper = asnr.load()
    cases = {
        # a library lens's design wavelength (its atoms chosen at λ0: piecewise)
        "lens.design_wavelength_nm": (asnr.load(LIBRARY), "lens.design_wavelength_nm: not differentiable here yet"),
        "camera.adc_bits": (paper, "camera.adc_bits: not differentiable: it is an integer"),
        "lens.nonsense": (paper, "lens.nonsense: embedded paper scene has no such key"),
    }
    for key, (source, message) in cases.items():
        with pytest.raises(asnr.SceneError, match=message.replace(".", r"\.")):
            asnr.gradient(source, [key])
        with pytest.raises(asnr.SceneError, match=message.replace(".", r"\.")):
            asnr.value_and_grad(source, [key])
    scene = paper
    with pytest.raises(asnr.SceneError, match=r"lens\.binary2\[1\] is given twice"):
        asnr.gradient(asnr.load(BINARY2), ["lens.binary2[1]", "lens.binary2[01]"])
    with pytest.raises(ValueError, match="no key"):
        asnr.gradient(scene, [])
    with pytest.raises(asnr.SceneError, match="worst_channel"):
        asnr.value_and_grad(scene, ["exposure.time_ms"], "worst_channel")


# --- asnr.value_and_grad and scipy ----------------------------------------------------------


def test_value_and_grad_is_the_gradient_at_any_point():
    scene = asnr.load(BINARY2)
    f = asnr.value_and_grad(scene, "lens.binary2")
    assert f.keys == [f"lens.binary2[{i}]" for i in range(4)]
    assert f.x0.tolist() == [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]
    value, grad = f(f.x0)
    g = asnr.gradient(scene, "lens.binary2")
    assert value == pytest.approx(g["asnr"], rel=1e-14)
    np.testing.assert_allclose(grad, list(g["gradient"].values()), rtol=1e-12)
    # away from the scene's values: the command line's gradient with --set there
    x = f.x0 + np.array([3.0, -1.0, 0.5, 0.0])
    value, grad = f(x)
    theirs = cli_gradient(["lens.binary2"], BINARY2, set_=[f"lens.binary2[{i}]={float(v)!r}" for i, v in enumerate(x)])
    assert value == pytest.approx(theirs["asnr"], rel=ROUNDING)
    assert grad.tolist() == pytest.approx(list(theirs["gradient"].values()), rel=ROUNDING)
    assert f.value(x) == pytest.approx(value, rel=1e-6)  # the evaluation alone, at its own tolerance
    minus = asnr.value_and_grad(scene, "lens.binary2", sign=-1)
    assert minus(x)[0] == -value and minus(x)[1].tolist() == (-grad).tolist()
    # a key the scene's overrides set starts there, and each call sets it
    moved = asnr.value_and_grad(asnr.load().with_({"exposure.time_ms": 2.0}), "exposure.time_ms")
    assert moved.x0.tolist() == [2.0]
    at_scene = asnr.gradient(asnr.load(), "exposure.time_ms")
    assert moved([1.23]) == (at_scene["asnr"], pytest.approx([at_scene["gradient"]["exposure.time_ms"]], rel=1e-15))
    with pytest.raises(ValueError, match="expected a 1-D array of 4 values"):
        f(np.zeros(3))
    with pytest.raises(ValueError, match=r"lens\.binary2\[0\] = NaN: expected a finite number"):
        f(np.array([np.nan, 0, 0, 0]))


def test_scipy_minimize_with_the_gradient_finds_the_golden_sections_optimum():
    """The best defocus coefficient A1 of the Binary 2 lens (its others fixed) by
    scipy.optimize.minimize(jac=True, L-BFGS-B) on −ASNR, against `asnr.optimize`'s golden
    section over the same range, which uses values only: the same maximum, to the golden
    section's bracket (1e-4 of the range) in A1 and 1e-7 in the ASNR (a smooth maximum: the error
    in the ASNR is quadratic in that in A1)."""
    optimize = require("scipy.optimize")
    scene = asnr.load(BINARY2)
    lo, hi = -540.0, -515.0
    golden = asnr.optimize(scene, {"lens.binary2[0]": (lo, hi)}, xtol=1e-5)
    f = asnr.value_and_grad(scene, "lens.binary2[0]", sign=-1)
    result = optimize.minimize(f, f.x0, jac=True, method="L-BFGS-B", bounds=[(lo, hi)])
    assert result.success, result.message
    assert abs(result.x[0] - golden["best"]) < 1e-4 * (hi - lo), (result.x, golden["best"])
    assert -result.fun == pytest.approx(golden["asnr"], rel=1e-7)
    assert lo + 1 < result.x[0] < hi - 1  # an interior optimum: the gradient is zero there


def test_optimize_by_gradient_is_the_command_lines_search():
    scene = asnr.load()
    over = {"camera.pixel_pitch_um": (2, 8), "exposure.time_ms": (0.5, 2)}
    ours = asnr.optimize(scene, over, method="gradient")
    args = ["optimize", "--json", "--method", "gradient", "--over", "camera.pixel_pitch_um=2:8", "--over", "exposure.time_ms=0.5:2"]
    assert ours == json.loads(cli(*args))
    assert "gradient" in ours
    assert ours["best"] == {"camera.pixel_pitch_um": 8.0, "exposure.time_ms": 2.0}
    tight = asnr.optimize(scene, over, method="gradient", tolerance=1e-8)
    assert tight == json.loads(cli(*args, "--tolerance", "1e-8"))
    with pytest.raises(asnr.SceneError, match="--method newton"):
        asnr.optimize(scene, over, method="newton")
    with pytest.raises(asnr.SceneError, match=r"lens\.design_wavelength_nm: not differentiable here yet"):
        asnr.optimize(asnr.load(LIBRARY), {"lens.design_wavelength_nm": (790, 810)}, method="gradient")


# --- the JAX bridge ---------------------------------------------------------------------------


def test_jax_grad_of_the_asnr_is_the_command_lines_gradient():
    jax = require("jax")
    import jax.numpy as jnp

    import asnr.jax

    jax.config.update("jax_enable_x64", True)
    scene = asnr.load(BINARY2)
    f = asnr.jax.asnr_function(scene, "lens.binary2")
    theirs = cli_gradient(["lens.binary2"], BINARY2)
    expected = np.array(list(theirs["gradient"].values()))
    x0 = jnp.asarray(f.x0)
    assert x0.dtype == jnp.float64
    np.testing.assert_allclose(np.asarray(jax.grad(f)(x0)), expected, rtol=1e-12)
    value, grad = jax.jit(jax.value_and_grad(f))(x0)
    assert float(value) == pytest.approx(theirs["asnr"], rel=1e-14)
    np.testing.assert_allclose(np.asarray(grad), expected, rtol=1e-12)
    # the value alone under jit: one evaluation, the command line's ASNR to its tolerance
    assert float(jax.jit(f)(x0)) == pytest.approx(theirs["asnr"], rel=1e-6)

    # one term of a loss: the chain rule through jax's own operations
    def loss(x):
        return -f(x) + 0.5 * jnp.sum(jnp.diff(x) ** 2)

    slope = np.diff(f.x0)
    penalty = np.zeros(4)
    penalty[:-1] -= slope
    penalty[1:] += slope
    np.testing.assert_allclose(np.asarray(jax.jit(jax.grad(loss))(x0)), -expected + penalty, rtol=1e-12)
    # vmap: one point after another
    points = jnp.stack([x0, x0 + jnp.array([2.0, 0.0, 0.0, 0.0])])
    values = jax.vmap(f)(points)
    assert float(values[0]) == pytest.approx(theirs["asnr"], rel=1e-6)
    assert float(values[1]) == pytest.approx(asnr.evaluate(scene.with_({"lens.binary2[0]": f.x0[0] + 2.0})).asnr, rel=1e-12)
    with pytest.raises(ValueError, match="expected a 1-D array of 4 values"):
        f(jnp.zeros(3))
    with pytest.raises(asnr.SceneError, match=r"lens\.design_wavelength_nm"):
        asnr.jax.asnr_function(asnr.load(LIBRARY), ["lens.design_wavelength_nm"])  # piecewise: refused by name


# --- the geometric-phase lens's Binary 2 gradient against a numpy radial reference ----------

#: examples/phase-binary2.toml, as numbers: F/2.5, f0 = 3.36 mm, λ0 = 800 nm, R = R_norm = f0/(2F#),
#: M = 1, a geometric-phase lens (the radian phase the same at every wavelength), a flat source
#: behind a Gaussian of range 2√2σ = 50 nm at 800 nm, constant efficiencies, 5.2 µm pixels without
#: the pixel MTF. The test checks these against the file through the mean MTF itself.
B2_F0_M = 3.36e-3
B2_LAMBDA0_M = 800e-9
B2_F_NUMBER = 2.5
B2_RADIUS_M = 0.5 * B2_F0_M / B2_F_NUMBER
B2_RANGE_M = 50e-9
B2_PIXEL_M = 5.2e-6
B2_COEFFICIENTS = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]


def numpy_binary2_mean_mtf_and_gradient(coefficients, nl: int, nnu: int, nt: int, nv: int):
    """The mean MTF of the Binary 2 geometric-phase lens and its derivative with respect to each
    coefficient A_i (per radian), written here in numpy with fixed rules (the method of
    xtask/baselines/numpy_radial.py, not its code).

    Pupil phase at q = ρ² (ρ = r/R, R_norm = R, M = 1; docs/physics.md, "Sign of the wavefront",
    the field A·exp(+i 2π W/λ)): Φ(q) = Σ_i A_i q^(i+1) + (2π/λ)(√(R²q + f0²) − f0), the exact
    reference sphere at the detector. The OTF of the radially symmetric pupil at s = νλF#
    (docs/physics.md, "General pupils"):

        O(s) = (4/π) ∫_0^{acos s} sin²t ∫_0^1 cos(Φ(q1) − Φ(q2)) dv dt,
        q1 = cos²t + v² sin²t,  q2 = q1 − 4s(cos t − s),

    and, since ∂(Φ(q1) − Φ(q2))/∂A_i = q1^(i+1) − q2^(i+1) (the geometric phase does not scale
    with λ),

        ∂O/∂A_i = −(4/π) ∫ sin²t ∫ sin(Φ(q1) − Φ(q2)) (q1^(i+1) − q2^(i+1)) dv dt.

    The polychromatic OTF is the average over λ with the detected weight λG(λ) (paper SI eq. S8;
    nothing else depends on λ here), Gauss–Hermite nodes of the Gaussian; the mean MTF
    (1/ν_N) ∫_0^{ν_N} |O| dν by Gauss–Legendre in ν (O keeps its sign below Nyquist in this
    scene, so ∂|O| = sign(O) ∂O and the rule needs no split); t and v by Gauss–Legendre. Returns
    (mean MTF, array of the derivatives)."""
    from numpy.polynomial.hermite import hermgauss
    from numpy.polynomial.legendre import leggauss

    a = np.asarray(coefficients, dtype=float)
    sigma = B2_RANGE_M / (2.0 * np.sqrt(2.0))
    x, w = hermgauss(nl)
    lam = B2_LAMBDA0_M + np.sqrt(2.0) * sigma * x
    weight = w * lam
    weight /= weight.sum()
    nyquist = 1.0 / (2.0 * B2_PIXEL_M)
    xn, wn = leggauss(nnu)
    nu = 0.5 * nyquist * (xn + 1.0)
    xt, wt = leggauss(nt)
    xv, wv = leggauss(nv)
    v = 0.5 * (xv + 1.0)
    wv = 0.5 * wv
    # axes [λ, ν, t, v]
    s = (nu[None, :] * lam[:, None] * B2_F_NUMBER)[:, :, None, None]
    assert np.all(s < 1.0), "the band reaches the cutoff: the rule would need a split"
    t_end = np.arccos(s)
    t = 0.5 * t_end * (xt[None, None, :, None] + 1.0)
    cos_t, sin_t = np.cos(t), np.sin(t)
    q1 = cos_t * cos_t + (v * v)[None, None, None, :] * sin_t * sin_t
    q2 = np.maximum(q1 - 4.0 * s * (cos_t - s), 0.0)

    def sag(q):  # √(R²q + f0²) − f0 without cancellation
        r2 = B2_RADIUS_M * B2_RADIUS_M * q
        return r2 / (np.sqrt(r2 + B2_F0_M * B2_F0_M) + B2_F0_M)

    k = (2.0 * np.pi / lam)[:, None, None, None]
    powers1 = [q1 ** (i + 1) for i in range(len(a))]
    powers2 = [q2 ** (i + 1) for i in range(len(a))]
    dphi = sum(c * (p1 - p2) for c, p1, p2 in zip(a, powers1, powers2)) + k * (sag(q1) - sag(q2))
    outer = (4.0 / np.pi) * 0.5 * t_end[..., 0] * wt[None, None, :] * sin_t[..., 0] ** 2  # [λ, ν, t]

    def mean_over_band(pupil):  # ∫∫ pupil dv dt, averaged over λ: the polychromatic OTF [ν]
        otf = (outer * (pupil * wv).sum(axis=3)).sum(axis=2)
        return (weight[:, None] * otf).sum(axis=0)

    poly = mean_over_band(np.cos(dphi))
    sine = np.sin(dphi)
    derivatives = [mean_over_band(-sine * (p1 - p2)) for p1, p2 in zip(powers1, powers2)]
    sign = np.sign(poly)
    assert np.all(sign == sign[0]), "the polychromatic OTF changes sign below Nyquist"
    value = 0.5 * (np.abs(poly) * wn).sum()
    gradient = np.array([0.5 * (sign * d * wn).sum() for d in derivatives])
    return value, gradient


@pytest.mark.parametrize("shift", [None, (0, 3.0), (1, 1.0)], ids=["design", "defocused", "spherical"])
def test_binary2_gradient_of_the_geometric_phase_lens_is_the_numpy_radial_references(shift):
    """`asnr.gradient`'s mean_mtf_gradient of examples/phase-binary2.toml with respect to every
    Binary 2 coefficient against the numpy reference above, at the example's coefficients, with
    3 rad of defocus added to A1, and with 1 rad added to A2 (the ρ⁴ term).

    The reference's own error: its rule of 48 λ × 32 ν × 48 t × 12 v nodes agrees with one of
    64 × 40 × 64 × 16 within 1.2e-13 of the gradient's norm and 2.3e-15 in the mean MTF (measured
    at the three points); here it must agree with a coarser rule (36 × 24 × 36 × 8) within 1e-6 of
    the norm (measured 6.8e-8, 2.7e-9, 2.6e-8), so that a rule that stopped converging fails. The
    engine's mean MTF and gradient, asked for a tolerance of 1e-9, must be within 10× that
    relative to the gradient's norm (docs/physics.md, "Gradients": the rule that holds the value
    holds its derivatives to about the same accuracy relative to their norm; measured 1.7e-12 to
    3.2e-12), its mean MTF within 1e-8 (measured 1e-12). With 12 rad of defocus the engine
    refuses the gradient (that scene leaves the exact per-frequency engine), so the points stay
    within 3 rad."""
    coefficients = list(B2_COEFFICIENTS)
    overrides = {}
    if shift is not None:
        i, delta = shift
        coefficients[i] += delta
        overrides[f"lens.binary2[{i}]"] = coefficients[i]
    coarse_value, coarse = numpy_binary2_mean_mtf_and_gradient(coefficients, 36, 24, 36, 8)
    finer_value, finer = numpy_binary2_mean_mtf_and_gradient(coefficients, 48, 32, 48, 12)
    norm = np.linalg.norm(finer)
    assert abs(coarse_value - finer_value) < 1e-9, (coarse_value, finer_value)
    assert np.linalg.norm(coarse - finer) < 1e-6 * norm, (coarse, finer)

    tolerance = 1e-9
    ours = asnr.gradient(asnr.load(BINARY2), "lens.binary2", set=overrides, tolerance=tolerance)
    gradient = np.array(list(ours["mean_mtf_gradient"].values()))
    error = np.linalg.norm(gradient - finer) / norm
    print(f"{shift}: mean MTF {ours['mean_mtf']:.12f} (numpy {finer_value:.12f}); gradient {gradient} "
          f"against numpy {finer}: {error:.2e} of its norm")
    assert list(ours["mean_mtf_gradient"]) == [f"lens.binary2[{i}]" for i in range(4)]
    assert abs(ours["mean_mtf"] - finer_value) < 1e-8, (ours["mean_mtf"], finer_value)
    assert error < 10 * tolerance, (gradient, finer, error)
    # a check that can fail: each derivative is well above the error allowed
    assert np.all(np.abs(finer) > 1e3 * 10 * tolerance * norm), finer


# --- the PyTorch bridge -----------------------------------------------------------------------


def test_torch_autograd_of_the_asnr_is_the_command_lines_gradient():
    torch = require("torch")
    import asnr.torch

    scene = asnr.load(BINARY2)
    f = asnr.torch.asnr_function(scene, "lens.binary2")
    theirs = cli_gradient(["lens.binary2"], BINARY2)
    expected = np.array(list(theirs["gradient"].values()))
    x = torch.tensor(f.x0, dtype=torch.float64, requires_grad=True)
    value = f(x)
    assert value.dtype == torch.float64 and value.shape == ()
    assert float(value.detach()) == pytest.approx(theirs["asnr"], rel=1e-14)
    (grad,) = torch.autograd.grad(value, x)
    np.testing.assert_allclose(grad.numpy(), expected, rtol=1e-12)
    # one term of a loss
    x = torch.tensor(f.x0, dtype=torch.float64, requires_grad=True)
    loss = -f(x) + 0.5 * torch.sum(torch.diff(x) ** 2)
    loss.backward()
    slope = np.diff(f.x0)
    penalty = np.zeros(4)
    penalty[:-1] -= slope
    penalty[1:] += slope
    np.testing.assert_allclose(x.grad.numpy(), -expected + penalty, rtol=1e-12)
    # without a gradient: the value alone
    with torch.no_grad():
        assert float(f(torch.tensor(f.x0))) == pytest.approx(theirs["asnr"], rel=1e-6)
    with pytest.raises(ValueError, match="expected a 1-D tensor of 4 values"):
        f(torch.zeros(3, dtype=torch.float64))


def test_import_asnr_needs_neither_jax_nor_torch():
    code = "import sys, asnr; assert 'jax' not in sys.modules and 'torch' not in sys.modules, sorted(sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, check=False)
    assert done.returncode == 0, done.stderr.decode()
