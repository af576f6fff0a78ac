r"""The single-run log posterior of every walker in one compiled call (numba).

:class:`~bayestribo.inference.posterior.Posterior` evaluates priors × likelihood with
numpy over a few walkers at a time, where each of the hundred-odd array operations
costs a few microseconds of interpreter and dispatch time and the arithmetic almost
nothing. :class:`FusedLogPosterior` computes the same density in one numba function
that loops over the walkers:

1. the priors (:class:`~bayestribo.inference.priors.Uniform`,
   :class:`~bayestribo.inference.priors.Normal`,
   :class:`~bayestribo.inference.priors.LogUniform`), summed in sampling order; a
   walker outside their support gets −inf and its likelihood is not evaluated;
2. the model parameters from the sampled and fixed coordinates: μ_s = μ_k × (μ_s/μ_k),
   the discrepancy scales s = 10^log10_discrepancy and s_c = 10^log10_shape;
3. the model Π on the grid, exact (the compiled kernel of
   :mod:`bayestribo.model._kernel`, with sticking) or averaged (Eq. 34 and 40 with the
   corrected Eq. 41, :mod:`bayestribo.model.averaged`), and its increments M_j;
4. the increment variances V_j (+ s² ∫_j E² with the discrepancy term), the
   residuals and the design whitened where the increments are correlated, and the
   Gaussian log-likelihood with the linear nuisances marginalised analytically: the
   equilibrium (δ₀, δ₁), the noise level's error (a standard normal coefficient)
   and, with the shape discrepancy, its coefficients c_k (a q × q system, q = 3 +
   the shape terms, solved by Cholesky; see
   :mod:`bayestribo.inference.likelihood`):

.. math::

    \log p = \sum_i \log π_i(θ_i) - \tfrac12\left[r^\top W r - b^\top A^{-1} b\right]
             - \tfrac12 \sum_j \log 2πV_j - \tfrac12 \log|A| - \tfrac12 \log|P|.

The log posterior has no other nuisance: the calibration nuisances of the load, the
mass and ζ₀ enter only the derived quantities, drawn after sampling
(:func:`bayestribo.inference.assemble.derived_quantities`).

A law without a closed form (:mod:`bayestribo.model.laws`) has its Π from its own
compiled integrator (:meth:`~bayestribo.model.laws.Law.pi_grid`, called once for the
walkers inside the priors' support, :class:`LawSource`) and the rest, priors and
likelihood, compiled here; a row whose Π is not finite (an overdamped arc) has
log p = −inf, as in the reference. The compiled sampler step
(:mod:`bayestribo.inference.fused_step`) does not serve such a law.

The numpy implementation (:meth:`Posterior.reference`) stays the reference; the
tests require the two to agree to 1e-10 of max(1, |log p|) over random parameter
sets, −inf and NaN at the same points. :meth:`FusedLogPosterior.build` returns None
for what it does not compile (a prior of another kind, a likelihood subclass that
overrides the model): the posterior then evaluates the reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.likelihood import BASE_NUISANCES, PiLikelihood
from bayestribo.inference.priors import LogUniform, Normal, PriorSet, Uniform
from bayestribo.inference.surrogate import SurrogateLikelihood
from bayestribo.model._averaged_kernel import averaged_amplitude as _averaged_amplitude
from bayestribo.model._averaged_kernel import pi_of_amplitude as _pi_of_amplitude
from bayestribo.model._kernel import _one

#: The nuisances every likelihood has (a compile-time constant of the kernels).
_BASE = BASE_NUISANCES

__all__ = ["FusedLogPosterior", "SurrogateLayout"]

#: Parameters in the order of the ``columns`` table (as posterior.PARAMETERS).
_ORDER = ("zeta", "mu_k", "mu_s_ratio", "y0", "log10_discrepancy", "log10_shape")
_SAMPLED_FROM_FIXED = -1  # the parameter is fixed at a value
_ABSENT = -2  # the parameter is neither sampled nor fixed
_UNIFORM, _NORMAL, _LOGUNIFORM = 0, 1, 2
_EXACT, _AVERAGED, _SURROGATE = 0, 1, 2
_LOG_2PI = math.log(2.0 * math.pi)
#: The files whose compiled functions those of this file call, and a digest of each
#: (SHA-256, 16 hex digits). numba's cache of a function is invalidated by a change of
#: its own file only: when one of these changes, its digest here must be updated (a
#: test says so), and this file's change discards the stale machine code.
DEPENDS_ON = {
    "bayestribo/model/_kernel.py": "532336f67810bf79",
    "bayestribo/model/_averaged_kernel.py": "9c5b431925c61df2",
}


@numba.njit(cache=True, error_model="numpy")
def _log_prior(row: NDArray, prior: NDArray) -> float:
    """Σ log π_i(θ_i) in sampling order; −inf outside the support (NaN for a NaN
    argument of an unbounded prior, as the numpy priors give)."""
    total = 0.0
    for i in range(row.size):
        x = row[i]
        kind = prior[i, 0]
        a = prior[i, 1]
        b = prior[i, 2]
        if kind == _UNIFORM:
            total += -math.log(b - a) if (x >= a and x <= b) else -math.inf
        elif kind == _NORMAL:
            z = (x - a) / b
            total += -0.5 * z * z - math.log(b * math.sqrt(2.0 * math.pi))
        else:
            if x >= a and x <= b:
                total += -math.log(x) - math.log(math.log(b / a))
            else:
                total += -math.inf
    return total


@numba.njit(cache=True, error_model="numpy")
def _value(row: NDArray, columns: NDArray, fixed: NDArray, k: int, default: float) -> float:
    c = columns[k]
    if c >= 0:
        return row[c]
    if c == _SAMPLED_FROM_FIXED:
        return fixed[k]
    return default


@numba.njit(cache=True, error_model="numpy")
def _averaged_grid(
    tau: NDArray, amp: float, z: float, mk: float, tau_end: float, out: NDArray
) -> None:
    """Π_app on the grid (Eq. 40), truncated at ``tau_end`` when it is finite."""
    pi_end = 0.0
    if math.isfinite(tau_end):
        pi_end = _pi_of_amplitude(_averaged_amplitude(tau_end, amp, z, mk), z, mk)
    for i in range(tau.size):
        pi = _pi_of_amplitude(_averaged_amplitude(tau[i], amp, z, mk), z, mk)
        if math.isfinite(tau_end):
            out[i] = pi - pi_end if tau[i] < tau_end else 0.0
        else:
            out[i] = pi


#: The base scalars' slot holding the row of ``data`` where the whitening T of
#: correlated increments starts (m rows, :attr:`PiLikelihood.whitening`), 0 without.
_WHITENING_SLOT = 7
#: Slots of the scalars after the base eight where a quadratic surrogate's layout is
#: written (:class:`SurrogateLayout`, :meth:`SurrogateLayout.header`): its coordinates
#: p, monomials per piece R, where its coordinates' columns, centres, scales and the
#: thresholds start in the scalars, the column of μ_s/μ_k (-1 without pieces), the
#: number of pieces K, and the row of ``data`` where its first piece's table starts.
(
    _P_SLOT,
    _R_SLOT,
    _COLUMNS_SLOT,
    _CENTRE_SLOT,
    _SCALE_SLOT,
    _RATIO_SLOT,
    _PIECES_SLOT,
    _THRESHOLDS_SLOT,
    _TABLE_SLOT,
) = range(8, 17)
_HEADER_END = 17


@dataclass(frozen=True)
class SurrogateLayout:
    """Where a :class:`~bayestribo.inference.surrogate.QuadraticPi`'s numbers sit in
    the compiled density's tables.

    Its header (:meth:`header`) follows the base scalars at the ``_*_SLOT`` positions,
    and the compiled density reads every offset from there; its coordinates' columns,
    centres, scales and the thresholds' rows follow the header in the scalars (the
    slices below); its coefficient tables are rows of ``data``, piece after piece
    (:meth:`piece_rows`).

    Attributes
    ----------
    n_coordinates : int
        p, the coordinates of the quadratic.
    n_pieces : int
        K, its pieces in μ_s/μ_k.
    table_row : int
        The row of ``data`` where the first piece's table starts (after τ, D, V, ∫E²
        and the nuisances' design).
    """

    n_coordinates: int
    n_pieces: int
    table_row: int

    @property
    def rows_per_piece(self) -> int:
        """R, the monomials of one piece: 1 + p + p(p+1)/2."""
        p = self.n_coordinates
        return 1 + p + p * (p + 1) // 2

    @property
    def columns(self) -> slice:
        """The coordinates' columns of θ, in the scalars."""
        return slice(_HEADER_END, _HEADER_END + self.n_coordinates)

    @property
    def centre(self) -> slice:
        """The expansion point, in the scalars."""
        return slice(self.columns.stop, self.columns.stop + self.n_coordinates)

    @property
    def scale(self) -> slice:
        """The unit of each coordinate, in the scalars."""
        return slice(self.centre.stop, self.centre.stop + self.n_coordinates)

    @property
    def thresholds(self) -> slice:
        """The K - 1 thresholds' rows of R coefficients, row after row, in the scalars."""
        return slice(self.scale.stop, self.scale.stop + (self.n_pieces - 1) * self.rows_per_piece)

    def piece_rows(self, piece: int) -> slice:
        """The rows of ``data`` holding piece ``piece``'s table."""
        r = self.rows_per_piece
        return slice(self.table_row + piece * r, self.table_row + (piece + 1) * r)

    def header(self, ratio_column: int) -> NDArray:
        """The header's values, slots ``_P_SLOT`` to ``_TABLE_SLOT`` in order."""
        values = np.empty(_HEADER_END - _P_SLOT)
        values[_P_SLOT - _P_SLOT] = self.n_coordinates
        values[_R_SLOT - _P_SLOT] = self.rows_per_piece
        values[_COLUMNS_SLOT - _P_SLOT] = self.columns.start
        values[_CENTRE_SLOT - _P_SLOT] = self.centre.start
        values[_SCALE_SLOT - _P_SLOT] = self.scale.start
        values[_RATIO_SLOT - _P_SLOT] = ratio_column
        values[_PIECES_SLOT - _P_SLOT] = self.n_pieces
        values[_THRESHOLDS_SLOT - _P_SLOT] = self.thresholds.start
        values[_TABLE_SLOT - _P_SLOT] = self.table_row
        return values

    def pack(self, base: NDArray, surrogate: Any, columns: list[int], ratio_column: int) -> NDArray:
        """The scalars: the base eight, the header, then the surrogate's numbers.

        Parameters
        ----------
        base : ndarray
            The base scalars (shape (8,)).
        surrogate : QuadraticPi
            The quadratic.
        columns : list of int
            The column of θ of each of its coordinates.
        ratio_column : int
            The column of μ_s/μ_k (-1 without pieces).
        """
        out = np.empty(self.thresholds.stop)
        out[:_P_SLOT] = base
        out[_P_SLOT:_HEADER_END] = self.header(ratio_column)
        out[self.columns] = columns
        out[self.centre] = surrogate.centre
        out[self.scale] = surrogate.scale
        out[self.thresholds] = np.ravel(surrogate.thresholds)
        return out

    @classmethod
    def read(cls, scalars: NDArray) -> SurrogateLayout:
        """The layout a table of scalars holds (its header)."""
        return cls(int(scalars[_P_SLOT]), int(scalars[_PIECES_SLOT]), int(scalars[_TABLE_SLOT]))


@numba.njit(cache=True, error_model="numpy")
def _surrogate_pi(row: NDArray, data: NDArray, scalars: NDArray, pi: NDArray) -> None:
    """The quadratic surrogate's Π (:class:`~bayestribo.inference.surrogate.QuadraticPi`)
    into ``pi``, every offset read from its header (:class:`SurrogateLayout`): the
    monomials of its coordinates, the piece that μ_s/μ_k falls in between the
    thresholds, and that piece's table."""
    m = pi.size
    p = int(scalars[_P_SLOT])
    r = int(scalars[_R_SLOT])
    columns = int(scalars[_COLUMNS_SLOT])
    centre = int(scalars[_CENTRE_SLOT])
    scale = int(scalars[_SCALE_SLOT])
    basis = np.empty(r)
    basis[0] = 1.0
    for a in range(p):
        basis[1 + a] = (row[int(scalars[columns + a])] - scalars[centre + a]) / scalars[scale + a]
    k = 1 + p
    for a in range(p):
        for b in range(a, p):
            basis[k] = basis[1 + a] * basis[1 + b]
            k += 1
    ratio_column = int(scalars[_RATIO_SLOT])
    pieces = int(scalars[_PIECES_SLOT])
    piece = 0
    if ratio_column >= 0:
        ratio = row[ratio_column]
        thresholds = int(scalars[_THRESHOLDS_SLOT])
        for edge in range(pieces - 1):
            threshold = 0.0
            for i in range(r):
                threshold += scalars[thresholds + edge * r + i] * basis[i]
            if threshold <= ratio:
                piece += 1
    first = int(scalars[_TABLE_SLOT]) + piece * r
    for j in range(m):
        pi[j] = 0.0
    for i in range(r):
        w = basis[i]
        for j in range(m):
            pi[j] += data[first + i, j] * w


@numba.njit(cache=True, error_model="numpy")
def _model_pi(
    row: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    pi: NDArray,
) -> bool:
    """Model Π on the grid into ``pi``; False (and ``pi`` untouched) where the averaged
    model's parameters are outside its domain."""
    tau = data[0]
    yp0 = scalars[0]
    end = scalars[1]
    model = scalars[5]
    if model == _SURROGATE:
        _surrogate_pi(row, data, scalars, pi)
        return True
    zeta = _value(row, columns, fixed, 0, 0.0)
    mu_k = _value(row, columns, fixed, 1, 0.0)
    mu_s = mu_k * _value(row, columns, fixed, 2, 1.0) if columns[2] != _ABSENT else mu_k
    y0 = _value(row, columns, fixed, 3, 0.0)
    if model == _EXACT:
        _one(tau, y0, zeta, mu_k, mu_s, yp0, end, pi)
        return True
    if not (zeta >= 0.0 and zeta < 1.0 and mu_k >= 0.0 and math.isfinite(mu_k)):
        return False
    _averaged_grid(tau, math.hypot(y0, yp0), zeta, mu_k, end, pi)
    return True


@numba.njit(cache=True, error_model="numpy")
def _cholesky_solve(a: NDArray, b: NDArray, q: int, x: NDArray) -> float:
    """Solve A x = b for the symmetric positive definite q × q ``a`` (overwritten by
    its Cholesky factor); returns log|A|, NaN when A is not positive definite."""
    logdet = 0.0
    for i in range(q):
        for j in range(i + 1):
            acc = a[i, j]
            for k in range(j):
                acc -= a[i, k] * a[j, k]
            if i == j:
                if not acc > 0.0:
                    return math.nan
                a[i, i] = math.sqrt(acc)
                logdet += 2.0 * math.log(a[i, i])
            else:
                a[i, j] = acc / a[j, j]
    for i in range(q):
        acc = b[i]
        for k in range(i):
            acc -= a[i, k] * x[k]
        x[i] = acc / a[i, i]
    for i in range(q - 1, -1, -1):
        acc = x[i]
        for k in range(i + 1, q):
            acc -= a[k, i] * x[k]
        x[i] = acc / a[i, i]
    return logdet


@numba.njit(cache=True, error_model="numpy")
def _normal_matrix(design: NDArray, var: NDArray, q: int, out: NDArray) -> None:
    """XᵀWX (q × q) of the nuisances' design rows ``design`` (q, m), W = diag(1/V)."""
    m = var.size
    for k in range(q):
        for i in range(k + 1):
            acc = 0.0
            for j in range(m):
                acc += design[k, j] * design[i, j] / var[j]
            out[k, i] = acc
            out[i, k] = acc


@numba.njit(cache=True, error_model="numpy")
def _whiten(t: NDArray, z: NDArray) -> None:
    """``z ← T z`` in place for the lower triangular whitening T (m, m)."""
    for i in range(z.size - 1, -1, -1):
        acc = 0.0
        for k in range(i + 1):
            acc += t[i, k] * z[k]
        z[i] = acc


@numba.njit(cache=True, error_model="numpy")
def _whitened_design(
    design: NDArray, var: NDArray, t: NDArray, q: int, xw: NDArray, a: NDArray
) -> None:
    """The nuisances' design whitened, ``T (X / √V)`` (q, m) into ``xw``, and its Gram
    matrix XᵀΣ⁻¹X (q × q) into ``a``."""
    m = var.size
    for k in range(q):
        for j in range(m):
            xw[k, j] = design[k, j] / math.sqrt(var[j])
        _whiten(t, xw[k])
    for k in range(q):
        for i in range(k + 1):
            acc = 0.0
            for j in range(m):
                acc += xw[k, j] * xw[i, j]
            a[k, i] = acc
            a[i, k] = acc


@numba.njit(cache=True, error_model="numpy")
def _whitening(data: NDArray, scalars: NDArray) -> NDArray:
    """The whitening T of correlated increments (m rows of ``data``), or no rows."""
    first = int(scalars[_WHITENING_SLOT])
    if first <= 0:
        return data[0:0]
    return data[first : first + data.shape[1]]


@numba.njit(cache=True, error_model="numpy")
def _log_det_correlation(t: NDArray) -> float:
    """log|R| = -2 Σ log T_jj (0 without a whitening)."""
    out = 0.0
    for j in range(t.shape[0]):
        out -= 2.0 * math.log(t[j, j])
    return out


@numba.njit(cache=True, error_model="numpy")
def _precisions(
    row: NDArray, columns: NDArray, fixed: NDArray, scalars: NDArray, q: int, out: NDArray
) -> float:
    """Prior precisions of the q nuisances into ``out``; returns log|P|."""
    out[0] = scalars[2]
    out[1] = scalars[3]
    out[2] = 1.0  # the noise level's error, standard normal
    log_p = scalars[4]
    if q > _BASE:
        log_c = _value(row, columns, fixed, 5, 0.0)
        sc = 10.0**log_c
        for k in range(_BASE, q):
            out[k] = 1.0 / (sc * sc)
        log_p += 2.0 * (q - _BASE) * math.log(10.0) * log_c
    return log_p


@numba.njit(cache=True, error_model="numpy")
def _standardized(
    theta: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    out: NDArray,
) -> int:
    """Conditional residuals over √V_j of each row into ``out`` (n, m), as
    :meth:`PiLikelihood.standardized_residuals`; returns the number of rows outside
    the averaged model's domain or with a singular nuisance system (left unset: the
    caller uses the reference)."""
    tau = data[0]
    m = tau.size
    q = _BASE + int(scalars[6])
    pi = np.empty(m)
    var = np.empty(m)
    a = np.empty((q, q))
    b = np.empty(q)
    x = np.empty(q)
    prec = np.empty(q)
    xw = np.empty((q, m))
    flagged = 0
    for n in range(theta.shape[0]):
        row = theta[n]
        if not _model_pi(row, columns, fixed, data, scalars, pi):
            flagged += 1
            continue
        if not _standardized_row(
            row, pi, columns, fixed, data, scalars, var, a, b, x, prec, xw, out[n]
        ):
            flagged += 1
    return flagged


@numba.njit(cache=True, inline="always", error_model="numpy")
def _standardized_row(
    row: NDArray,
    pi: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    var: NDArray,
    a: NDArray,
    b: NDArray,
    x: NDArray,
    prec: NDArray,
    xw: NDArray,
    out: NDArray,
) -> bool:
    """The standardized conditional residuals of one row given its model Π into
    ``out`` (m,), whitened where the increments are correlated; False where the
    nuisances' system is singular."""
    inc = data[1]
    var0 = data[2]
    e2 = data[3]
    m = inc.size
    q = _BASE + int(scalars[6])
    design = data[4 : 4 + q]
    s2 = 0.0
    if columns[4] != _ABSENT:
        s = 10.0 ** _value(row, columns, fixed, 4, 0.0)
        s2 = s * s
    for k in range(q):
        b[k] = 0.0
    t = _whitening(data, scalars)
    if t.shape[0] > 0:
        for j in range(m):
            var[j] = var0[j] + s2 * e2[j] if columns[4] != _ABSENT else var0[j]
            model_inc = pi[j] - pi[j + 1] if j < m - 1 else pi[j]
            out[j] = (inc[j] - model_inc) / math.sqrt(var[j])
        _whiten(t, out[:m])
        _whitened_design(design, var, t, q, xw, a)
        for j in range(m):
            for k in range(q):
                b[k] += out[j] * xw[k, j]
        _precisions(row, columns, fixed, scalars, q, prec)
        for k in range(q):
            a[k, k] += prec[k]
        if not math.isfinite(_cholesky_solve(a, b, q, x)):
            return False
        for j in range(m):
            for k in range(q):
                out[j] -= x[k] * xw[k, j]
        if out.size >= m + q:
            for k in range(q):
                out[m + k] = x[k] * math.sqrt(prec[k])
        return True
    for j in range(m):
        var[j] = var0[j] + s2 * e2[j] if columns[4] != _ABSENT else var0[j]
        model_inc = pi[j] - pi[j + 1] if j < m - 1 else pi[j]
        r = inc[j] - model_inc
        out[j] = r
        for k in range(q):
            b[k] += r * design[k, j] / var[j]
    _normal_matrix(design, var, q, a)
    _precisions(row, columns, fixed, scalars, q, prec)
    for k in range(q):
        a[k, k] += prec[k]
    if not math.isfinite(_cholesky_solve(a, b, q, x)):
        return False
    for j in range(m):
        fitted = 0.0
        for k in range(q):
            fitted += x[k] * design[k, j]
        out[j] = (out[j] - fitted) / math.sqrt(var[j])
    if out.size >= m + q:
        # the nuisances' conditional means over their prior sd: with these the sum
        # of squares is the log-likelihood's χ² part, rᵀWr - bᵀA⁻¹b
        for k in range(q):
            out[m + k] = x[k] * math.sqrt(prec[k])
    return True


@numba.njit(cache=True, error_model="numpy")
def _law_standardized(
    theta: NDArray,
    pi: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    out: NDArray,
) -> int:
    """:func:`_standardized` with the model Π of each row given, ``pi`` (n, m); a row
    whose Π is not finite is flagged (left unset) like a singular one."""
    m = data.shape[1]
    q = _BASE + int(scalars[6])
    var = np.empty(m)
    a = np.empty((q, q))
    b = np.empty(q)
    x = np.empty(q)
    prec = np.empty(q)
    xw = np.empty((q, m))
    flagged = 0
    for n in range(theta.shape[0]):
        moves = True
        for j in range(m):
            if not math.isfinite(pi[n, j]):
                moves = False
        if not moves or not _standardized_row(
            theta[n], pi[n], columns, fixed, data, scalars, var, a, b, x, prec, xw, out[n]
        ):
            flagged += 1
    return flagged


@numba.njit(cache=True, error_model="numpy")
def _log_posterior(
    theta: NDArray,
    prior: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    out: NDArray,
) -> int:
    """Log posterior of each row of ``theta`` into ``out`` (see the module notes).

    ``data`` rows: τ_j, D_j, V_j, ∫_j E², then the nuisances' design: ∫_j y, ∫_j τy,
    the noise bias's standard error and the shape columns D_j P_k(u_j) (j < m), and
    last, for correlated increments, the whitening T (m rows).
    ``scalars``: y'0, the end of the model's Π (inf when the record holds the end of
    motion), the prior precisions of δ₀ and δ₁, their log|P|, the model code, the
    number of shape terms, the row of ``data`` where T starts (0 without) (and for
    the quadratic surrogate of Π, whose table rows follow the design in ``data``: its
    number of coordinates p, their columns, centres and scales). Returns the
    number of rows whose log posterior is NaN or whose parameters are outside the
    averaged model's domain (NaN in ``out``): the caller then lets the reference
    raise its error.
    """
    pi, var, a, b, x, prec, c, xw, z, norm0 = _workspace(columns, data, scalars)
    return _log_posterior_in(
        theta, prior, columns, fixed, data, scalars, out, pi, var, a, b, x, prec, c, xw, z, norm0
    )


@numba.njit(cache=True, error_model="numpy")
def _workspace(
    columns: NDArray, data: NDArray, scalars: NDArray
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, float]:
    """The work arrays of :func:`_log_posterior_in` and the parts of the log-likelihood
    that are the same for every row: without the white discrepancy the variances
    ``var``, A's data part ``c``, the whitened design ``xw`` of correlated increments
    and ``norm0`` = Σ log 2πV + log|R| (with it, log|R| alone, and ``var``, ``xw``
    scratch). Made once for any number of calls (the sampler step's splits)."""
    tau = data[0]
    var0 = data[2]
    m = tau.size
    q = _BASE + int(scalars[6])
    design = data[4 : 4 + q]
    pi = np.empty(m)
    var = np.empty(m)
    a = np.empty((q, q))
    b = np.empty(q)
    x = np.empty(q)
    prec = np.empty(q)
    # Without the white discrepancy the variances, hence A's data part and Σ log 2πV,
    # are the same for every walker (and the whitened design of correlated increments).
    c = np.zeros((q, q))
    t = _whitening(data, scalars)
    xw = np.empty((q, m))
    z = np.empty(m)
    norm0 = _log_det_correlation(t)
    if columns[4] == _ABSENT:
        for j in range(m):
            var[j] = var0[j]
            norm0 += math.log(var[j]) + _LOG_2PI
        if t.shape[0] > 0:
            _whitened_design(design, var, t, q, xw, c)
        else:
            _normal_matrix(design, var, q, c)
    return pi, var, a, b, x, prec, c, xw, z, norm0


@numba.njit(cache=True, error_model="numpy")
def _log_posterior_in(
    theta: NDArray,
    prior: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    out: NDArray,
    pi: NDArray,
    var: NDArray,
    a: NDArray,
    b: NDArray,
    x: NDArray,
    prec: NDArray,
    c: NDArray,
    xw: NDArray,
    z: NDArray,
    norm0: float,
) -> int:
    """:func:`_log_posterior` with the work arrays and constant parts of
    :func:`_workspace`."""
    q = _BASE + int(scalars[6])
    t = _whitening(data, scalars)
    flagged = 0
    for n in range(theta.shape[0]):
        row = theta[n]
        lp = _log_prior(row, prior)
        if not math.isfinite(lp):
            flagged += math.isnan(lp)
            out[n] = lp
            continue
        if not _model_pi(row, columns, fixed, data, scalars, pi):
            flagged += 1
            out[n] = math.nan
            continue
        out[n] = lp + _log_likelihood(
            row, pi, columns, fixed, data, scalars, q, var, a, b, x, prec, c, norm0, t, xw, z
        )
        flagged += math.isnan(out[n])
    return flagged


@numba.njit(cache=True, inline="always", error_model="numpy")
def _log_likelihood(
    row: NDArray,
    pi: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    q: int,
    var: NDArray,
    a: NDArray,
    b: NDArray,
    x: NDArray,
    prec: NDArray,
    c: NDArray,
    norm0: float,
    t: NDArray,
    xw: NDArray,
    z: NDArray,
) -> float:
    """The log-likelihood of one row given its model Π (see the module notes), with
    the work arrays of :func:`_log_posterior`; without the white discrepancy, ``var``,
    ``c`` (A's data part), ``xw`` (the whitened design of correlated increments) and
    ``norm0`` (Σ log 2πV + log|R|) are the same for every row. ``t``: the whitening
    (no rows for independent increments)."""
    inc = data[1]
    var0 = data[2]
    e2 = data[3]
    m = inc.size
    design = data[4 : 4 + q]
    norm = norm0
    whitened = t.shape[0] > 0
    if columns[4] != _ABSENT:
        s = 10.0 ** _value(row, columns, fixed, 4, 0.0)
        s2 = s * s
        for j in range(m):
            var[j] = var0[j] + s2 * e2[j]
            norm += math.log(var[j]) + _LOG_2PI
        if whitened:
            _whitened_design(design, var, t, q, xw, a)
        else:
            _normal_matrix(design, var, q, a)
    else:
        for k in range(q):
            for i in range(q):
                a[k, i] = c[k, i]
    for k in range(q):
        b[k] = 0.0
    rr = 0.0
    if whitened:
        for j in range(m):
            model_inc = pi[j] - pi[j + 1] if j < m - 1 else pi[j]
            z[j] = (inc[j] - model_inc) / math.sqrt(var[j])
        _whiten(t, z)
        for j in range(m):
            for k in range(q):
                b[k] += z[j] * xw[k, j]
            rr += z[j] * z[j]
    else:
        for j in range(m):
            model_inc = pi[j] - pi[j + 1] if j < m - 1 else pi[j]
            r = inc[j] - model_inc
            rw = r / var[j]
            for k in range(q):
                b[k] += rw * design[k, j]
            rr += r * rw
    log_prior_det = _precisions(row, columns, fixed, scalars, q, prec)
    for k in range(q):
        a[k, k] += prec[k]
    logdet = _cholesky_solve(a, b, q, x)
    explained = 0.0
    for k in range(q):
        explained += b[k] * x[k]
    chi2 = rr - explained
    return -0.5 * (chi2 + norm + logdet + log_prior_det)


@numba.njit(cache=True, error_model="numpy")
def _law_log_posterior(
    theta: NDArray,
    pi: NDArray,
    prior: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    out: NDArray,
) -> int:
    """:func:`_log_posterior` with the model Π of each row given, ``pi`` (n, m), for a
    law without a closed form (:meth:`FusedLogPosterior.law_pi`; not read where the
    prior density is zero). A row whose Π is not finite (the law cannot move: an
    overdamped arc) is outside the law's domain: −inf. Returns the number of NaN rows."""
    m = data[1].size
    q = _BASE + int(scalars[6])
    t = _whitening(data, scalars)
    _, var, a, b, x, prec, c, xw, z, norm0 = _workspace(columns, data, scalars)
    flagged = 0
    for n in range(theta.shape[0]):
        row = theta[n]
        lp = _log_prior(row, prior)
        if not math.isfinite(lp):
            flagged += math.isnan(lp)
            out[n] = lp
            continue
        moves = True
        for j in range(m):
            if not math.isfinite(pi[n, j]):
                moves = False
        if not moves:
            out[n] = -math.inf
            continue
        out[n] = lp + _log_likelihood(
            row, pi[n], columns, fixed, data, scalars, q, var, a, b, x, prec, c, norm0, t, xw, z
        )
        flagged += math.isnan(out[n])
    return flagged


@numba.njit(cache=True, error_model="numpy")
def _log_priors(theta: NDArray, prior: NDArray, out: NDArray) -> None:
    """:func:`_log_prior` of each row of ``theta`` into ``out``."""
    for n in range(theta.shape[0]):
        out[n] = _log_prior(theta[n], prior)


@dataclass(frozen=True)
class FusedLogPosterior:
    """The tables of one posterior for the compiled log density.

    Attributes
    ----------
    prior : ndarray
        Shape (d, 3): kind (0 uniform, 1 normal, 2 log-uniform) and its two
        parameters (low, high or μ, σ) per sampled coordinate.
    columns : ndarray
        Shape (6,): for ζ, μ_k, μ_s/μ_k, y0, log10_discrepancy, log10_shape, the
        column of θ, -1 when fixed, -2 when absent.
    fixed : ndarray
        Shape (6,): the fixed values (where ``columns`` is -1).
    data : ndarray
        Shape (4 + q, m): τ_j, D_j, V_j, ∫_j E², then the q nuisance columns ∫_j y,
        ∫_j τy, the noise bias's standard error (and the shape columns D_j P_k(u_j)
        with the shape discrepancy); then a surrogate's table, and the whitening T of
        correlated increments (:attr:`PiLikelihood.whitening`, m rows) last.
    scalars : ndarray
        y'0, the end of Π, the prior precisions of δ₀ and δ₁, their log|P|, the model
        code, the number of shape terms, the row of ``data`` where T starts (0
        without).
    law : LawSource or None
        Where Π comes from for a law without a closed form (None: the closed form,
        compiled here).
    """

    prior: NDArray
    columns: NDArray
    fixed: NDArray
    data: NDArray
    scalars: NDArray
    law: LawSource | None = None

    @classmethod
    def build(
        cls, priors: PriorSet, likelihood: PiLikelihood, fixed: dict[str, float]
    ) -> FusedLogPosterior | None:
        """Tables for ``priors`` × ``likelihood`` with ``fixed`` values, or None when
        a prior is not one of the three kinds or the likelihood is a subclass (its
        methods may differ from what is compiled here)."""
        surrogate = None
        if type(likelihood) is SurrogateLikelihood:
            surrogate = likelihood.surrogate
            needed = [*surrogate.names, *([surrogate.ratio] if surrogate.ratio else [])]
            if any(name not in priors.names for name in needed):
                return None
        elif type(likelihood) is not PiLikelihood:
            return None
        law = None
        if surrogate is None and not likelihood.law.closed_form:
            if likelihood.model != "exact":
                return None
            law = LawSource.build(priors, likelihood, fixed)
        table = np.empty((len(priors), 3))
        for i, name in enumerate(priors.names):
            p: Any = priors[name]
            if type(p) is Uniform:
                table[i] = (_UNIFORM, p.low, p.high)
            elif type(p) is Normal:
                table[i] = (_NORMAL, p.mu, p.sigma)
            elif type(p) is LogUniform:
                table[i] = (_LOGUNIFORM, p.low, p.high)
            else:
                return None
        columns = np.full(len(_ORDER), _ABSENT, dtype=np.int64)
        values = np.zeros(len(_ORDER))
        for k, name in enumerate(_ORDER):
            if name in priors.names:
                columns[k] = priors.names.index(name)
            elif name in fixed:
                columns[k] = _SAMPLED_FROM_FIXED
                values[k] = float(fixed[name])
        d = likelihood.data
        shape = columns[5] != _ABSENT
        design = likelihood.design(shape)
        rows = [d.tau_grid[:-1], d.increments, d.variance, d.energy_squared, design.T]
        table_row = 4 + design.shape[1]
        if surrogate is not None:
            rows.append(surrogate.table)
        whitening = likelihood.whitening
        first = 0
        if whitening is not None:  # the last m rows
            first = sum(np.atleast_2d(r).shape[0] for r in rows)
            rows.append(whitening)
        data = np.ascontiguousarray(np.vstack(rows), dtype=np.float64)
        scalars = np.array(
            [
                float(d.yp0),
                math.inf if d.motion_ended else d.tau_end,
                likelihood.offset_sd**-2,
                likelihood.drift_sd**-2,
                likelihood._log_prior_det(),
                _EXACT if likelihood.model == "exact" else _AVERAGED,
                design.shape[1] - _BASE,
                first,
            ]
        )
        if surrogate is not None:
            scalars[5] = _SURROGATE
            layout = SurrogateLayout(surrogate.n_coordinates, surrogate.n_pieces, table_row)
            index = [priors.names.index(name) for name in surrogate.names]
            ratio = -1 if surrogate.ratio is None else priors.names.index(surrogate.ratio)
            scalars = layout.pack(scalars, surrogate, index, ratio)
        return cls(table, columns, values, data, scalars, law)

    def __call__(self, theta: NDArray) -> tuple[NDArray, int]:
        """Log posterior of each row of ``theta`` (n, d), and how many rows are NaN or
        outside the averaged model's domain (the caller evaluates those with the
        reference, which raises the error that names the cause).

        Parameters
        ----------
        theta : ndarray
            Sampled coordinates, shape (n, d).

        Returns
        -------
        log_p : ndarray
            Shape (n,): −inf outside the priors' support.
        flagged : int
            Rows whose value is NaN.
        """
        theta = np.ascontiguousarray(theta, dtype=np.float64)
        out = np.empty(theta.shape[0])
        if self.law is not None:
            # Π of the rows inside the priors' support from the law's integrator,
            # the rest compiled as for the closed form
            _log_priors(theta, self.prior, out)
            pi = np.zeros((theta.shape[0], self.data.shape[1]))
            inside = np.isfinite(out)
            if np.any(inside):
                pi[inside] = self.law.pi(theta[inside])
            flagged = _law_log_posterior(
                theta, pi, self.prior, self.columns, self.fixed, self.data, self.scalars, out
            )
            return out, flagged
        flagged = _log_posterior(
            theta, self.prior, self.columns, self.fixed, self.data, self.scalars, out
        )
        return out, flagged

    def log_prior(self, theta: NDArray) -> NDArray:
        """Σ log π_i(θ_i) of each row of ``theta`` (n, d), −inf outside the priors'
        support (the numpy priors' value to rounding, the same support)."""
        theta = np.ascontiguousarray(theta, dtype=np.float64)
        out = np.empty(theta.shape[0])
        _log_priors(theta, self.prior, out)
        return out

    def standardized_residuals(
        self, theta: NDArray, nuisances: bool = False
    ) -> tuple[NDArray, int]:
        """Conditional residuals over √V_j of each row of ``theta`` (n, d), shape
        (n, m) (:meth:`PiLikelihood.standardized_residuals`; with ``nuisances`` the q
        nuisances' conditional means over their prior sd follow, (n, m + q)), and how
        many rows are outside the averaged model's domain (the caller evaluates those
        with the reference)."""
        theta = np.ascontiguousarray(theta, dtype=np.float64)
        extra = _BASE + int(self.scalars[6]) if nuisances else 0
        out = np.empty((theta.shape[0], self.data.shape[1] + extra))
        if self.law is not None:
            pi = self.law.pi(theta)
            flagged = _law_standardized(
                theta, pi, self.columns, self.fixed, self.data, self.scalars, out
            )
            return out, flagged
        flagged = _standardized(theta, self.columns, self.fixed, self.data, self.scalars, out)
        return out, flagged


@dataclass(frozen=True)
class LawSource:
    """Where the model Π of a law without a closed form comes from, for
    :class:`FusedLogPosterior`: the law's compiled integrator
    (:meth:`bayestribo.model.laws.Law.pi_grid`) on the likelihood's grid, its
    parameters taken from the sampled coordinates, the fixed values or their null.

    Attributes
    ----------
    likelihood : PiLikelihood
        The likelihood (its law, grid, y'0, end of Π and reference amplitude).
    sources : tuple
        ``(name, column, value)`` for each parameter of the law and ``y0``: the column
        of θ, or -1 and the value (fixed, or the parameter's null).
    """

    likelihood: PiLikelihood
    sources: tuple[tuple[str, int, float], ...]

    @classmethod
    def build(
        cls, priors: PriorSet, likelihood: PiLikelihood, fixed: dict[str, float]
    ) -> LawSource:
        """The sources of ``likelihood``'s law parameters and y0 under ``priors`` and
        ``fixed``."""
        names = priors.names
        sources = []
        for p in (*likelihood.law.parameters, None):
            name = "y0" if p is None else p.name
            if name in names:
                sources.append((name, names.index(name), math.nan))
            else:
                null = math.nan if p is None else p.null
                sources.append((name, -1, float(fixed.get(name, null))))
        return cls(likelihood, tuple(sources))

    def pi(self, theta: NDArray) -> NDArray:
        """Model Π at the grid points for rows ``theta`` (n, d), shape (n, m); a row is
        NaN where the law cannot move (as :meth:`PiLikelihood.model_pi`)."""
        lik = self.likelihood
        n = theta.shape[0]
        values = {
            name: theta[:, column] if column >= 0 else np.full(n, value)
            for name, column, value in self.sources
        }
        y0 = values.pop("y0")
        return lik.law_pi(lik.data.tau_grid[:-1], values, y0)
