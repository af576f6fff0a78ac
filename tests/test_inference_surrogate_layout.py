"""The typed layouts of the quadratic surrogate: a law's coefficient columns per force
(inference/surrogate.py, CoefficientLayout) and the surrogate's place in the compiled
density's tables (inference/fused.py, SurrogateLayout)."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference.comparison import auto_laws
from bayestribo.inference.fused import _P_SLOT, SurrogateLayout, _surrogate_pi
from bayestribo.inference.surrogate import CoefficientLayout, QuadraticPi
from bayestribo.model.laws import get_law


@pytest.mark.parametrize("name", auto_laws())
def test_the_coefficient_layout_is_the_columns_the_law_gives(name):
    law = get_law(name)
    layout = CoefficientLayout.of(law)
    values = {p: np.array([0.5]) for p in law.parameter_names}
    if "mu_s_ratio" in values:
        values["mu_s_ratio"] = np.array([1.5])
    assert law.coefficients(values, 1.0).shape[1] == layout.width
    # the model's own packing of its compiled forces, drags then frictions
    packed = law._layout[0]
    for slots, (forces, offsets, sizes) in (
        (layout.drags, packed[:3]),
        (layout.frictions, packed[3:]),
    ):
        assert [s.force for s in slots] == list(forces)
        assert [s.columns.start for s in slots] == list(offsets)
        assert [s.columns.stop - s.columns.start for s in slots] == list(sizes)


def _quadratic(p: int, pieces: int, m: int, seed: int) -> QuadraticPi:
    """A quadratic of ``p`` coordinates and ``pieces`` pieces in a ratio, with random
    tables and thresholds that increase at the centre."""
    rng = np.random.default_rng(seed)
    r = 1 + p + p * (p + 1) // 2
    thresholds = 0.01 * rng.normal(size=(pieces - 1, r))
    thresholds[:, 0] = np.linspace(1.5, 3.5, pieces - 1)
    return QuadraticPi(
        names=tuple(f"x{a}" for a in range(p)),
        centre=rng.normal(size=p),
        scale=rng.uniform(0.5, 2.0, size=p),
        table=rng.normal(size=(pieces * r, m)),
        ratio="ratio",
        thresholds=thresholds,
    )


def test_the_packed_surrogate_reads_back_from_its_layout():
    q = _quadratic(3, 4, 5, seed=1)
    layout = SurrogateLayout(q.n_coordinates, q.n_pieces, table_row=9)
    base = np.arange(float(_P_SLOT))  # the base scalars
    scalars = layout.pack(base, q, [4, 0, 2], ratio_column=3)
    assert SurrogateLayout.read(scalars) == layout
    np.testing.assert_array_equal(scalars[:_P_SLOT], base)
    np.testing.assert_array_equal(scalars[layout.columns], [4, 0, 2])
    np.testing.assert_array_equal(scalars[layout.centre], q.centre)
    np.testing.assert_array_equal(scalars[layout.scale], q.scale)
    np.testing.assert_array_equal(scalars[layout.thresholds], np.ravel(q.thresholds))
    assert layout.thresholds.stop == scalars.size
    assert layout.rows_per_piece == q.rows_per_piece
    assert layout.piece_rows(2).start == 9 + 2 * q.rows_per_piece


def test_the_compiled_surrogate_is_the_quadratic_on_every_piece():
    # the compiled Π reads every offset from the header; the numpy QuadraticPi is the
    # reference, at draws whose ratios fall in every piece
    p, pieces, m = 3, 4, 6
    q = _quadratic(p, pieces, m, seed=2)
    columns = [4, 0, 2]  # θ's columns of x0, x1, x2; μ_s/μ_k in column 3
    table_row = 7
    layout = SurrogateLayout(p, pieces, table_row)
    scalars = layout.pack(np.zeros(_P_SLOT), q, columns, ratio_column=3)
    data = np.vstack([np.zeros((table_row, m)), q.table])
    rng = np.random.default_rng(3)
    n = 200
    theta = rng.normal(size=(n, 5))
    theta[:, 3] = rng.uniform(1.0, 4.0, size=n)
    params = {f"x{a}": theta[:, c] for a, c in enumerate(columns)}
    params["ratio"] = theta[:, 3]
    expected = q(params)
    u = np.column_stack([(params[f"x{a}"] - q.centre[a]) / q.scale[a] for a in range(p)])
    assert set(q.piece(theta[:, 3], q.monomials(u))) == set(range(pieces))
    got = np.empty((n, m))
    for i in range(n):
        _surrogate_pi(theta[i], data, scalars, got[i])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)
