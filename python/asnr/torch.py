"""The ASNR as a differentiable PyTorch function (the ``torch`` extra: ``pip install "asnr[torch]"``).

``asnr.torch.asnr_function(scene, keys)`` returns ``f``, a function of a 1-D tensor of the keys'
values (one entry per key, in the order of ``f.keys``) whose value is the scene's ASNR there (a
0-d tensor of the input's dtype and device) and whose derivative is the engines' exact gradient
(:func:`asnr.value_and_grad`; docs/physics.md, "Gradients"), through a
``torch.autograd.Function``::

    import torch
    import asnr, asnr.torch
    f = asnr.torch.asnr_function(asnr.load("examples/phase-binary2.toml"), ["lens.binary2"])
    x = torch.tensor(f.x0, requires_grad=True)
    loss = -f(x) + 1e-3 * torch.sum(torch.diff(x) ** 2)
    loss.backward()                                   # x.grad

The evaluation runs on the host in float64; a forward pass that needs no gradient evaluates the
value alone, one that does computes value and gradient in one call and keeps the gradient for the
backward pass. Higher derivatives are not defined (the backward pass is not differentiable).
``asnr`` itself never imports torch.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
import torch

import asnr

__all__ = ["asnr_function"]


class _Objective(torch.autograd.Function):
    """The objective of an :class:`asnr.ValueAndGrad` and its exact gradient."""

    @staticmethod
    def forward(ctx: Any, x: torch.Tensor, host: asnr.ValueAndGrad) -> torch.Tensor:  # type: ignore[override]
        values = x.detach().cpu().to(torch.float64).numpy()
        if ctx.needs_input_grad[0]:
            value, grad = host(values)
            ctx.save_for_backward(torch.as_tensor(np.asarray(grad), dtype=x.dtype, device=x.device))
        else:
            value = host.value(values)
        return torch.tensor(value, dtype=x.dtype, device=x.device)

    @staticmethod
    def backward(ctx: Any, cotangent: torch.Tensor) -> tuple[torch.Tensor, None]:  # type: ignore[override]
        (grad,) = ctx.saved_tensors
        return cotangent * grad, None


def asnr_function(
    scene: asnr.Scene,
    keys: str | Iterable[str],
    *,
    objective: str = "asnr",
    tolerance: float | None = None,
) -> Callable[[torch.Tensor], torch.Tensor]:
    """The objective of ``scene`` (``"asnr"``, ``"asnr_glare"`` or ``"fov_mean"``) as a torch
    function of a 1-D tensor of the values of ``keys`` (``"lens.binary2"`` means every entry),
    differentiable by autograd (``loss.backward()``, ``torch.autograd.grad``) with the exact
    gradient. The function carries ``keys`` (each entry spelled out) and ``x0`` (their values in
    the scene, a numpy array). The keys are checked now: an unknown or non-differentiable key
    raises :class:`asnr.SceneError` naming it."""
    host = asnr.value_and_grad(scene, keys, objective, tolerance=tolerance)
    n = len(host.keys)

    def asnr_of(x: Any) -> torch.Tensor:
        x = torch.as_tensor(x)
        if x.dim() != 1 or x.shape[0] != n:
            raise ValueError(f"{tuple(x.shape)}: expected a 1-D tensor of {n} values, one per key ({', '.join(host.keys)})")
        return _Objective.apply(x, host)

    asnr_of.keys = host.keys  # type: ignore[attr-defined]
    asnr_of.x0 = host.x0  # type: ignore[attr-defined]
    asnr_of.__doc__ = f"The {objective} of {scene.label} as a function of ({', '.join(host.keys)})."
    return asnr_of
