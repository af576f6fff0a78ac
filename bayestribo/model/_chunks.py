"""Evaluate a broadcast computation over τ in cache-sized blocks.

The forward models evaluate a dozen elementwise expressions on arrays of shape
``(walkers, τ points)``. Arrays of 128 KiB and more are allocated by glibc with
``mmap`` and returned to the system when freed, so every temporary costs page faults;
at 64 × 256 points this made the models four times slower than their arithmetic.
Working through blocks of at most :data:`BLOCK` elements keeps the temporaries on
the heap and in cache.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

__all__ = ["BLOCK", "over_tau_blocks"]

#: Elements per block (4096 × 8 bytes = 32 KiB per temporary).
BLOCK = 4096


def over_tau_blocks(
    fn: Callable[[NDArray], NDArray | tuple[NDArray, ...]],
    tau: NDArray,
    param_shape: tuple[int, ...],
) -> NDArray | tuple[NDArray, ...]:
    """Apply ``fn(tau_block)`` to blocks of the last axis of ``tau`` and reassemble.

    ``fn`` must return arrays of shape ``broadcast(param_shape, tau_block.shape)``.
    Blocking is used only when the last axis of the result comes from ``tau`` alone
    (parameters of size 1 along it); otherwise ``fn(tau)`` is returned unchanged.
    """
    out_shape = np.broadcast_shapes(param_shape, tau.shape)
    size = math.prod(out_shape)
    blockable = (
        size > BLOCK
        and tau.ndim >= 1
        and tau.shape[-1] > 1
        and (len(param_shape) == 0 or param_shape[-1] == 1)
    )
    if not blockable:
        return fn(tau)
    width = max(1, BLOCK * out_shape[-1] // size)
    outs: tuple[NDArray, ...] | None = None
    single = False
    for start in range(0, tau.shape[-1], width):
        part = fn(tau[..., start : start + width])
        if outs is None:
            single = not isinstance(part, tuple)
            outs = tuple(np.empty(out_shape) for _ in range(1 if single else len(part)))
        for out, piece in zip(outs, (part,) if single else part, strict=True):
            out[..., start : start + width] = piece
    assert outs is not None
    return outs[0] if single else outs
