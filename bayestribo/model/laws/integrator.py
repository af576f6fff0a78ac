r"""Compiled half-cycle integrator of Π for a law without a closed form.

Within one half cycle the sign of y' is fixed, the friction μ = μ(a) is a constant
(``a`` the magnitude of the turning point the half cycle began at), and the motion is
``u'' + u = -g(|y'|) sgn y'`` about the centre ``c = -μ sgn y'`` (``u = y - c``). By
the symmetry of the law (odd in y') every half cycle is computed as one that starts at
a positive turning point, where y' <= 0. In polar coordinates about the centre,

.. math::

    u = r\cos θ,\quad y' = -r\sin θ,\qquad
    \frac{dr}{dθ} = -\frac{\sin θ\, g(r\sin θ)}{D},\quad
    \frac{dτ}{dθ} = \frac{1}{D},\quad
    \frac{dI}{dθ} = \frac{E}{D},\qquad D = 1 - \frac{\cos θ\, g(r \sin θ)}{r},

with ``E = ½(y² + y'²) = ½(μ² + 2μ r cos θ + r²)`` and ``I = ∫E dτ`` (derived for
this module: ``r r' = u u' + y' y''`` and ``θ' = (u y'' ... )``, checked against
``solve_ivp`` in the tests). The half cycle ends exactly at ``θ = π`` (y' = 0):
there is no event to locate, and the turning point is ``Y = μ - r(π)`` in the
half cycle's frame. The angle is stretched, ``θ = θ₀ + (π - θ₀) S(ψ)`` with
``S(ψ) = ψ - sin(2πψ)/(2π)`` (ψ ∈ [0, 1]), so that a drag that is not smooth at
zero speed (``|y'|^α``, α not an integer) is still integrated at the method's order:
S vanishes to third order at both ends. Classical fourth-order Runge-Kutta with a
number of steps per half cycle chosen from the drag's equivalent damping at the
half cycle's peak speed, ``ζ_e = g(r)/(2r)``: about ``440 √ζ_e`` steps (32 at least),
since the scheme's error grows as ``ζ² h⁴``. The tests hold Π within 1e-8 of Π(0)
against the closed form and ``solve_ivp``. A caller may allow more error
(``tolerance``, a fraction of Π(0), of :meth:`bayestribo.model.laws.Law.pi_grid`;
the likelihood allows a hundredth of its increments' smallest noise sd over √m): the steps
inside the record fall as its fourth root, to 32 at least (``BASE_ERROR``, 2e-9, is
the usual steps' error; ``tests/test_model_laws_tolerance.py``).

Π at the grid: the cumulative energy integral ``C(τ) = ∫₀^τ E`` is known at every
step with its exact derivatives E and E' = -|y'|(g(|y'|) + μ) (the power the forces
dissipate), and is interpolated between steps by a quintic Hermite polynomial;
``Π(τ_j) = C(T) - C(τ_j)`` with ``T`` the end of motion or of the record.

The motion stops at the first turning point Y with ``|Y| <= ρ μ(|Y|)`` (ρ the ratio
μ_s/μ_k, Eq. 8). A law without friction never stops: past the end of the record
(when asked to run to the end of motion) half cycles are summed until they hold less
than 1e-12 of the total, and the rest is extrapolated as a geometric series (also for
a friction that vanishes with the amplitude, η|Y|). A decay that slows down (a drag
that grows faster than the speed, ΔE ∝ A^(α+1) with α > 1) would take tens of
thousands of half cycles to get there: once the half cycles past the record lose
less than 2 % of their amplitude each, the rest of the sum (up to the cap of half
cycles past the record) is taken from the averaged motion, whose rate of decay and
energy per half cycle are measured from a few half cycles of the law's own motion at
seven amplitudes (``_core.averaged_tail``; within ~1e-7 of the tail of the half
cycles' sum, which is as far as that sum's own steps take it), each span of amplitudes
halved where its interpolants miss their tolerance (a drag whose local power changes
down the tail). A fixed number of steps per half cycle integrates every half cycle
(``steps > 0``: the reference of convergence tests); ``steps < 0`` fixes -steps and
shortens the sum past the record as the default does, from those same half cycles (the
coarse model of the optimiser's multi-start). A drag below α = 1
ends the motion by an overdamped creep towards the centre (the drag at small speeds
outgrows the spring): the half cycle whose arc is overdamped is followed from its
last polar steps in time by an L-stable implicit Runge-Kutta method
(:mod:`bayestribo.model.laws._creep`), Π at the grid points on it, up to the record's
end, or to rest where the rest of its ∫E comes from the quasi-static balance; where
that rest diverges (a power law at α <= 1/3, summed to the end of motion) the row is
outside the law's domain (NaN). Summed to the end of motion of a record that holds its
stop, the creep may be given an end of its own (``creep_end``, the record's detected
stop): the creep never reaches rest in a finite time, and the data's Π ends where its
creep was seen to end, so the model's creep is integrated up to there (or not at all
where it begins later); the half cycles before it run to their end of motion as
before. Π within ~2e-8 of Π(0) of ``solve_ivp``'s
(``tests/test_model_laws_creep.py``).

A start inside a half cycle (y'₀ ≠ 0) needs μ at the half cycle's virtual turning
point, which is not known for a friction that varies with amplitude: it is taken
from ``a = √((y₀ - c)² + y'₀²) + μ`` (the turning point of the undamped arc through
the initial state) by a fixed-point iteration; for a constant friction this is exact.
"""

from __future__ import annotations

import hashlib
import inspect
import os
import sys
from collections.abc import Callable, Mapping
from functools import cache
from pathlib import Path
from types import ModuleType

from bayestribo.model.laws import _core, _core_shared, _creep, _ladder
from bayestribo.model.laws.cache import CACHE_ENV, NUMBA_FOLDER, law_cache_dir, load_module

__all__ = [
    "BASE_ERROR",
    "CACHE_ENV",
    "DEFAULT_STEPS",
    "LADDER",
    "cached_functions",
    "compiled_law",
    "law_cache_dir",
    "law_module",
    "make_integrator",
]

DEFAULT_STEPS = _core.DEFAULT_STEPS
BASE_ERROR = _core.BASE_ERROR
LADDER = _core.LADDER


def _sum_source(name: str, forces: tuple, offsets: tuple, sizes: tuple, first: int) -> str:
    """Source of one compiled function summing the forces of one kind of term."""
    parts = ["0.0"] + [
        f"_f{first + i}(x, c[{o}:{o + n}])"
        for i, (o, n) in enumerate(zip(offsets, sizes, strict=True))
    ]
    return (
        '@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)\n'
        f"def {name}(x: float, c: NDArray) -> float:\n"
        f"    return {' + '.join(parts)}\n"
    )


def _off_source(offsets: tuple, sizes: tuple) -> str:
    """Source of ``friction_off(c)``: every friction term's coefficients are zero (each
    term's friction then vanishes: a term's force is proportional to its coefficients,
    as every built-in friction term's is)."""
    body = "".join(
        f"    for i in range({o}, {o + n}):\n        if c[i] != 0.0:\n            return False\n"
        for o, n in zip(offsets, sizes, strict=True)
    )
    return (
        '@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)\n'
        "def friction_off(c: NDArray) -> bool:\n"
        f"{body}    return True\n"
    )


def _importable(force: object) -> tuple[str, str] | None:
    """Module and name from which a term's compiled force can be imported again."""
    py = getattr(force, "py_func", None)
    module, name = getattr(py, "__module__", None), getattr(py, "__qualname__", "")
    if not module or "<" in name or "." in name or module == "__main__":
        return None
    if getattr(sys.modules.get(module), name, None) is not force:
        return None
    return module, name


def _law_source(
    template: ModuleType,
    layout: tuple,
    kernels: Mapping[str, object] | None = None,
    parts: tuple[ModuleType, ...] = (),
) -> tuple[str, dict[str, object], bool]:
    """The text of one law's module: the template's (:mod:`._core` or
    :mod:`._restoring_core`), the text the templates share (:mod:`._core_shared`), the
    template's own further ``parts`` (:mod:`._creep` for :mod:`._core`), then the law's
    forces, and a restoring force's compiled ``kernels`` by the names the template
    calls them. Also the functions to set in the module when one of them cannot be
    imported (no cache then), and whether the module may be cached."""
    drags, d_off, d_size, frictions, f_off, f_size = layout
    named: dict[str, object] = {f"_f{i}": f for i, f in enumerate((*drags, *frictions))}
    named.update(kernels or {})
    where = {name: _importable(f) for name, f in named.items()}
    cacheable = all(w is not None for w in where.values())
    lines = ["", "", "# -- the law " + "-" * 68]
    if cacheable:
        for name, (module, attr) in where.items():  # type: ignore[misc]
            lines.append(f"from {module} import {attr} as {name}  # noqa: E402")
    lines.append("")
    lines.append(_sum_source("drag", drags, d_off, d_size, 0))
    lines.append(_sum_source("friction", frictions, f_off, f_size, len(drags)))
    lines.append(_off_source(f_off, f_size))
    lines.append(f"HAS_FRICTION = {bool(frictions)}")
    lines.append(f"HAS_DRAG = {bool(drags)}")
    text = (
        inspect.getsource(template)
        + "\n\n# -- shared by the templates "
        + "-" * 52
        + "\n"
        + inspect.getsource(_core_shared)
        + "".join(
            "\n\n# -- " + part.__name__ + " " + "-" * 40 + "\n" + inspect.getsource(part)
            for part in parts
        )
        + "\n".join(lines)
        + "\n"
    )
    if not cacheable:
        return text.replace("cache=True", "cache=False"), named, False
    # a change of a force's or kernel's source, or of the compiled functions the template
    # imports (:mod:`._ladder`, linked into the law's own), is a new file, never a stale
    # cache
    text += f"# _ladder: {hashlib.sha1(inspect.getsource(_ladder).encode()).hexdigest()}\n"
    text += "".join(
        f"# {name}: {hashlib.sha1(inspect.getsource(f.py_func).encode()).hexdigest()}\n"  # type: ignore[attr-defined]
        for name, f in named.items()
    )
    return text, {}, True


def _module_name(text: str) -> str:
    """The module name of one law's text (:func:`_law_source`): its digest."""
    return f"bayestribo_law_{hashlib.sha1(text.encode()).hexdigest()[:20]}"


def _load(text: str, namespace: Mapping[str, object], cacheable: bool) -> ModuleType:
    """Execute one law's module text (:func:`_law_source`) in the law cache, or, when it
    may not be cached, in a temporary folder with ``namespace`` set first. A law a
    worker process is compiling into the cache (:mod:`.ahead`) is waited for first."""
    name = _module_name(text)
    folder = law_cache_dir() if cacheable else None
    if folder is not None:
        from bayestribo.model.laws.ahead import wait_for

        wait_for(name)
    return load_module(name, text, folder, namespace)


@cache
def _law_text(layout: tuple) -> tuple[str, dict[str, object], bool]:
    """:func:`_law_source` of the template :mod:`._core` (with :mod:`._creep`) for one
    law's ``layout`` (:func:`make_integrator`'s arguments in a tuple), made once."""
    return _law_source(_core, layout, parts=(_creep,))


def law_module(layout: tuple) -> str | None:
    """The name of one law's module in the law cache (``layout``: :func:`make_integrator`'s
    arguments in a tuple), or None when the law may not be cached (a term whose force
    cannot be imported by name)."""
    text, _, cacheable = _law_text(layout)
    return _module_name(text) if cacheable else None


def cached_functions(folder: Path) -> set[str]:
    """The compiled functions numba keeps in the law cache ``folder``, each as
    ``<module>.<function>`` (compiled by some process before; whether they match this
    machine and numba is numba's to decide as it loads them)."""
    try:
        files = os.listdir(folder / NUMBA_FOLDER)
    except OSError:
        return set()
    return {f.rsplit("-", 1)[0] for f in files if f.endswith(".nbi")}


@cache
def compiled_law(
    drags: tuple,
    drag_offsets: tuple,
    drag_sizes: tuple,
    frictions: tuple,
    friction_offsets: tuple,
    friction_sizes: tuple,
) -> ModuleType:
    """The compiled module of one law (the template :mod:`bayestribo.model.laws._core`
    and the text it shares with the other template, :mod:`._core_shared`, with the
    law's forces; arguments as :func:`make_integrator`'s), whose functions the
    tests call one by one (the averaged tail against the half cycles' sum)."""
    layout = (drags, drag_offsets, drag_sizes, frictions, friction_offsets, friction_sizes)
    return _load(*_law_text(layout))


@cache
def make_integrator(
    drags: tuple,
    drag_offsets: tuple,
    drag_sizes: tuple,
    frictions: tuple,
    friction_offsets: tuple,
    friction_sizes: tuple,
) -> tuple[Callable, Callable, Callable]:
    """The compiled Π-grid, turning-point and swing functions of one law.

    The template :mod:`bayestribo.model.laws._core` is written with the text it shares
    with the template of the laws on a restoring force
    (:mod:`bayestribo.model.laws._core_shared`) and the law's forces to a file of the
    law cache (:func:`~bayestribo.model.laws.cache.law_cache_dir`) and executed, so
    that numba compiles it once and later processes load it from its cache, each file
    checked against the SHA-256 recorded when it was written
    (:mod:`bayestribo.model.laws.cache`). Terms whose forces cannot be
    imported by name (defined in ``__main__`` or inside a function) are compiled in each
    process instead.

    Parameters
    ----------
    drags, frictions : tuple of numba functions
        The drag terms' ``g(w, c)`` and the friction terms' ``μ(a, c)``.
    drag_offsets, drag_sizes, friction_offsets, friction_sizes : tuple of int
        Where each term's coefficients sit in the coefficient row.

    Returns
    -------
    grid : callable
        ``grid(tau, y0, coef, ratio, yp0, tau_end, steps, creep_end=inf,
        error_weight=1.0) -> (Π, status)``: ``tau`` sorted (T,), ``y0`` (P,), ``coef``
        (P, K), ``ratio`` (P,) the static to kinetic friction ratio, ``steps`` 0 (chosen
        per half cycle) or fixed (see the module notes for its sign), ``creep_end``
        where a creep ends below ``tau_end``, ``error_weight`` >= 1 how many times the
        scheme's usual error Π may have where the steps are chosen
        (:meth:`bayestribo.model.laws.Law.pi_grid`'s ``tolerance``); Π of shape (P,
        T); status (P,) 0 when the motion could be
        integrated, 1 when the drag stops a half cycle before it turns (an overdamped
        arc: that row of Π is NaN).
    turns : callable
        ``turns(y0, coef_row, ratio, yp0, tau_max, max_count) -> (τ_n, Y_n)``: the
        turning points of one trajectory.
    swing_drops : callable
        ``swing_drops(coef, swing) -> drop``: for each row of ``coef`` (P, K) and each
        swing A (S,), the drop a_s - a_e of the half cycle from rest at a_s to the
        turning point a_e with ½(a_s + a_e) = A (static friction ignored), (P, S).
    """
    module = compiled_law(
        drags, drag_offsets, drag_sizes, frictions, friction_offsets, friction_sizes
    )
    return module.grid, module.turns, module.swing_drops
