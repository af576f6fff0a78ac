"""Which laws ``law="auto"`` need not sample: those that can no longer change its choice.

The comparison (:mod:`bayestribo.inference.comparison`) samples its laws smallest
first. Its verdict is the simplest adequate law as good as the best by PSIS-LOO (the
simplest converged one where none is adequate). Once some laws are sampled, the
verdict among them (the *provisional* verdict V, and the best B) is known, and a law L
still to be sampled can change the choice only

* by being chosen itself: L is adequate (then it may also enter the ΔE(A) averaged over
  the laws as good, or be a rival), or no law is adequate, L is as good as the best and
  it wins the tie-break against V (fewer terms, then fewer parameters, then the order
  of the laws compared);
* by pushing V out of the laws as good: L's elpd above V's by the tie rule's reach
  ``max(4, 2 dse)``; or by becoming the best and so moving the others' differences.

At its optimum each law's elpd is estimated already (Akaike's,
:func:`bayestribo.inference.screening.optimum_elpd`; the screening's estimate), and the
difference of two laws' estimates follows their PSIS-LOO difference to well inside the
tie rule's reach: of the 17 laws settled on the bundled, AppStat and spring-and-disc
recordings (``benchmarks/results/auto_speed_real.json``), 16 came within a fifth of the
reach of the difference the sampled comparison found; the law-free fit on HarmOsc1,
whose one-per-parameter penalty counts six parameters the data barely constrain, was
1.68 off (2.05 against 0.37: 0.42 of the reach 4), on the side that kept its standing.
An estimate errs that way for a law of weakly constrained parameters: it makes the law
look worse than PSIS-LOO does. A law is *settled* without sampling when, judged there
against V and B (:func:`settle`):

1. it misfits at its optimum (not adequate: the caller's check), or it holds there and
   is clearly not as good as the best (below);
2. it cannot push V out: its estimated gain over V short of the reach by a
   :data:`FACTOR` th of it; and it cannot become the best by more than noise: its gain
   over B at most a :data:`FACTOR` th of the reach;
3. whether it is as good as the best is clear at its optimum: its estimated difference
   from B short of the reach by a :data:`FACTOR` th of it (as good), or beyond it by
   that much (not as good);
4. it cannot be chosen: V is adequate, or L loses the tie-break to V, or L is not as
   good as the best.

An adequate law as good as the best is always sampled in the comparison of
``law="auto"``: its draws may enter the ΔE(A) averaged over the laws as good as the
verdict, and it may be a rival; one clearly not as good is settled as a misfitting law
is. The rivals' comparison on the finer grid uses its draws for its choice alone, and
there an adequate law is settled too when it cannot be chosen (not as good as the
best, or V adequate and simpler).

A settled law is reported with its estimate and whether it is as good (its row's
``settle``); it is in the comparison's ``as_good`` when the estimate says so. The
comparison checks every settled law again against the final verdict and best, and
samples the ones that no longer pass (a later law may have moved the verdict).

Order. Which laws can be settled depends on which are sampled first: a law sampled
early against a provisional verdict that a later law moves was sampled for nothing.
The comparison therefore samples first the verdict the optima predict
(:func:`sampling_order`: the simplest adequate law whose estimate is as good as the
best estimate by the tie rule, else the simplest as good), then the others smallest
first. On HarmOsc2 (verdict ``coulomb+power``) smallest first sampled ``viscous``,
``power`` and ``viscous+quadratic``, each the provisional verdict or ahead of it when
its turn came and 47-139 of elpd behind the best in the end; sampled after the
verdict, they are settled behind it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.choice import tie_key
from bayestribo.inference.screening import SCREEN_FACTOR, optimum_elpd

__all__ = ["FACTOR", "sampling_order", "settle"]

#: How far inside (or beyond) the tie rule's reach an estimate at the optimum must be
#: for the verdict not to hang on it: a third of the reach, the screening's factor.
FACTOR = SCREEN_FACTOR


def _dse(a: NDArray, b: NDArray) -> float:
    """Standard error of the summed pointwise difference of two laws."""
    with np.errstate(invalid="ignore"):
        d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
        return float(np.sqrt(d.size * np.var(d))) if d.size > 1 else 0.0


def settle(
    law: tuple[NDArray, int],
    verdict: tuple[NDArray, int],
    best: tuple[NDArray, int],
    *,
    verdict_adequate: bool,
    loses_tie: bool,
    small: float,
    factor: float = FACTOR,
    adequate: bool = False,
) -> dict[str, Any]:
    """Whether a law can change the comparison's choice, judged at its optimum (module
    notes).

    Parameters
    ----------
    law, verdict, best : tuple of (ndarray, int)
        Each law's pointwise log-likelihood of the Π increments at its optimum and its
        number of sampled parameters: the law judged, the provisional verdict V and the
        provisional best B (both sampled).
    verdict_adequate : bool
        Whether V is adequate and converged.
    loses_tie : bool
        Whether the law is more complex than V (or as complex and later in order).
    small : float
        The tie rule's smallest reach (an elpd difference).
    factor : float
        :data:`FACTOR` by default.
    adequate : bool
        Whether the law is adequate at its optimum (only a comparison whose draws serve
        its choice alone judges such a law here: the rivals' on the finer grid). It
        cannot be chosen when it is not as good as the best, or V is adequate and it
        loses the tie-break.

    Returns
    -------
    dict
        ``elpd_diff`` (B's estimate less the law's), ``dse`` and ``reach`` (the tie
        rule's, against B), ``verdict_gain`` and ``verdict_reach`` (the law's estimate
        less V's, and the reach against V), ``as_good`` (True or False where the
        estimate is clear, None where it is not) and ``settled``.
    """
    pw, k = np.asarray(law[0], dtype=float), int(law[1])
    mine = optimum_elpd(pw, k)
    gain_v = mine - optimum_elpd(verdict[0], verdict[1])
    reach_v = max(small, 2.0 * _dse(pw, verdict[0]))
    diff = optimum_elpd(best[0], best[1]) - mine
    dse = _dse(best[0], pw)
    reach = max(small, 2.0 * dse)
    as_good: bool | None = None
    # clear of the tie rule's edge by a factor-th of its reach, on either side
    if diff <= reach * (1.0 - 1.0 / factor):
        as_good = True
    elif diff >= reach * (1.0 + 1.0 / factor):
        as_good = False
    cannot_push = (
        bool(np.isfinite(mine))
        and gain_v <= reach_v * (1.0 - 1.0 / factor)
        and -diff <= reach / factor
    )
    if adequate:
        cannot_be_chosen = as_good is False or (verdict_adequate and loses_tie)
    else:
        cannot_be_chosen = verdict_adequate or loses_tie or as_good is False
    return {
        "elpd_diff": float(diff),
        "dse": dse,
        "reach": float(reach),
        "verdict_gain": float(gain_v),
        "verdict_reach": float(reach_v),
        "as_good": as_good,
        "settled": bool(cannot_push and as_good is not None and cannot_be_chosen),
    }


def sampling_order(
    laws: Sequence[str],
    estimates: Mapping[str, tuple[NDArray, int]],
    adequate: Callable[[str], bool],
    rank: Sequence[str],
    *,
    small: float,
    leads: Callable[[str], bool] | None = None,
) -> list[str]:
    """The laws in the order to sample them: the verdict their optima predict first,
    the others in the order given (module notes, Order).

    Parameters
    ----------
    laws : sequence of str
        The laws to sample, smallest first.
    estimates : mapping of str to (ndarray, int)
        Each law's pointwise log-likelihood of the Π increments at its optimum and its
        number of sampled parameters.
    adequate : callable
        ``adequate(law)``: whether the law holds at its optimum (the misfit checks);
        asked of the laws as good as the best estimate alone.
    rank : sequence of str
        The order of the laws compared, for the tie-break
        (:func:`bayestribo.inference.choice.tie_key`).
    small : float
        The tie rule's smallest reach (an elpd difference).
    leads : callable, optional
        ``leads(law)``: whether the law may go first (default: every law); a caller
        keeps back a law that would reduce to another at its optimum.

    Returns
    -------
    list of str
        ``laws`` with the predicted verdict moved to the front; unchanged when no law
        has a finite estimate or none as good as the best may go first.
    """
    laws = list(laws)
    elpd = {law: optimum_elpd(*estimates[law]) for law in laws if law in estimates}
    finite = [law for law, value in elpd.items() if np.isfinite(value)]
    if not finite:
        return laws
    best = max(finite, key=elpd.__getitem__)
    top = estimates[best][0]
    as_good = sorted(
        (
            law
            for law in finite
            if elpd[best] - elpd[law] < max(small, 2.0 * _dse(top, estimates[law][0]))
        ),
        key=lambda law: tie_key(law, rank),
    )
    allowed = [law for law in as_good if leads is None or leads(law)]
    if not allowed:
        return laws
    first = next((law for law in allowed if adequate(law)), allowed[0])
    return [first, *(law for law in laws if law != first)]
