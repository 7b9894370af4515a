"""The ASNR as a differentiable JAX function (the ``jax`` extra: ``pip install "asnr[jax]"``).

``asnr.jax.asnr_function(scene, keys)`` returns ``f``, a function of a 1-D JAX array of the keys'
values (one entry per key, in the order of ``f.keys``) whose value is the scene's ASNR there and
whose derivative is the engines' exact gradient (:func:`asnr.value_and_grad`; docs/physics.md,
"Gradients"), so that the ASNR can be one term of a loss::

    import jax, jax.numpy as jnp
    import asnr, asnr.jax
    f = asnr.jax.asnr_function(asnr.load("examples/phase-binary2.toml"), ["lens.binary2"])
    loss = lambda x: -f(x) + 1e-3 * jnp.sum(jnp.diff(x) ** 2)
    step = jax.jit(jax.grad(loss))

The evaluation runs on the host, in float64, through ``jax.pure_callback`` (so ``f`` works under
``jax.jit`` and ``jax.vmap``, one point after another), and its derivative is a custom VJP: the
forward pass of ``jax.grad`` computes the value and gradient in one call, the backward pass scales
the gradient by the cotangent. Without ``jax_enable_x64`` JAX arrays are float32 and ``f``'s value
and gradient are rounded to float32 (a relative 6e-8). Higher derivatives (``jax.hessian``) are
not defined: the VJP's own derivative is not computed. ``asnr`` itself never imports JAX.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

import asnr

__all__ = ["asnr_function"]


def asnr_function(
    scene: asnr.Scene,
    keys: str | Iterable[str],
    *,
    objective: str = "asnr",
    tolerance: float | None = None,
) -> Callable[[Any], Any]:
    """The objective of ``scene`` (``"asnr"``, ``"asnr_glare"`` or ``"fov_mean"``) as a JAX
    function of a 1-D array of the values of ``keys`` (``"lens.binary2"`` means every entry),
    differentiable by ``jax.grad`` (a custom VJP on the exact gradient) and callable under
    ``jax.jit`` (a host callback). The function carries ``keys`` (each entry spelled out) and
    ``x0`` (their values in the scene, a numpy array). The keys are checked now: an unknown or
    non-differentiable key raises :class:`asnr.SceneError` naming it."""
    host = asnr.value_and_grad(scene, keys, objective, tolerance=tolerance)
    n = len(host.keys)

    def check(x: Any) -> None:
        if jnp.ndim(x) != 1 or jnp.shape(x)[0] != n:
            raise ValueError(f"{jnp.shape(x)}: expected a 1-D array of {n} values, one per key ({', '.join(host.keys)})")

    def value_on_host(x: np.ndarray) -> np.ndarray:
        return np.asarray(host.value(x), dtype=x.dtype)

    def value_and_grad_on_host(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        value, grad = host(x)
        return np.asarray(value, dtype=x.dtype), np.asarray(grad, dtype=x.dtype)

    @jax.custom_vjp
    def f(x: Any) -> Any:
        check(x)
        scalar = jax.ShapeDtypeStruct((), x.dtype)
        return jax.pure_callback(value_on_host, scalar, x, vmap_method="sequential")

    def forward(x: Any) -> tuple[Any, Any]:
        check(x)
        shapes = (jax.ShapeDtypeStruct((), x.dtype), jax.ShapeDtypeStruct((n,), x.dtype))
        value, grad = jax.pure_callback(value_and_grad_on_host, shapes, x, vmap_method="sequential")
        return value, grad

    def backward(grad: Any, cotangent: Any) -> tuple[Any]:
        return (cotangent * grad,)

    f.defvjp(forward, backward)

    def asnr_of(x: Any) -> Any:
        return f(jnp.asarray(x))

    asnr_of.keys = host.keys  # type: ignore[attr-defined]
    asnr_of.x0 = host.x0  # type: ignore[attr-defined]
    asnr_of.__doc__ = f"The {objective} of {scene.label} as a function of ({', '.join(host.keys)})."
    return asnr_of
