"""The text of a law's compiled module (:func:`bayestribo.model.laws.integrator._law_source`):
a template, the text the two templates share once, then the law's definitions."""

from __future__ import annotations

import hashlib
import inspect
import re

import numpy as np
import pytest

from bayestribo.model.laws import _core, _core_shared, _ladder, _restoring_core, get_law
from bayestribo.model.laws.integrator import _law_source, compiled_law
from bayestribo.model.restoring import get_restoring

LAW = "viscous+quadratic+coulomb"


def _pendulum() -> dict[str, object]:
    kernel = get_restoring("pendulum").kernel()
    return {"spring": kernel.spring_kernel, "potential": kernel.potential_kernel}


@pytest.mark.parametrize(
    ("template", "kernels"),
    [(_core, None), (_restoring_core, _pendulum())],
    ids=["linear", "pendulum"],
)
def test_a_law_module_holds_each_function_once(template, kernels):
    text, namespace, cacheable = _law_source(template, get_law(LAW)._layout[0], kernels)
    assert cacheable and not namespace
    own = inspect.getsource(template)
    shared = inspect.getsource(_core_shared)
    assert text.startswith(own)
    assert text.count(shared) == 1
    assert text.index(shared) > len(own) - 1
    # a function of the shared text copied back into a template would be defined twice
    defined = re.findall(r"^def (\w+)\(", text, flags=re.MULTILINE)
    assert len(defined) == len(set(defined)), sorted(n for n in defined if defined.count(n) > 1)
    for name in ("outside_domain", "geometric_rest", "finish", "swing_ends"):
        assert name in defined and not re.search(rf"^def {name}\(", own, flags=re.MULTILINE)
    # the restoring force's kernels are imported under the names the template calls
    if kernels is not None:
        assert re.search(r"^from \S+ import \w+ as spring  # noqa", text, flags=re.MULTILINE)
        assert re.search(r"^from \S+ import \w+ as potential  # noqa", text, flags=re.MULTILINE)


def test_the_step_ladder_is_compiled_once_for_every_law_not_per_law():
    text, _, cacheable = _law_source(_core, get_law(LAW)._layout[0])
    assert cacheable
    defined = re.findall(r"^def (\w+)\(", text, flags=re.MULTILINE)
    # compiled in their own module (the package's cache), imported by the template
    assert "nodes" not in defined and "ladder_tables" not in defined
    assert re.search(r"^from bayestribo\.model\.laws\._ladder import .*\bnodes\b", text, re.M)
    # their code is linked into the law's functions: a change of it is a new law file
    digest = hashlib.sha1(inspect.getsource(_ladder).encode()).hexdigest()
    assert f"# _ladder: {digest}\n" in text


def test_a_law_reads_the_ladders_shared_tables():
    module = compiled_law(*get_law("quadratic")._layout[0])
    assert module._TABLES is _ladder.TABLES and module._OFFSETS is _ladder.OFFSETS
    assert module.nodes is _ladder.nodes and module.LADDER is _ladder.LADDER
    for i, steps in enumerate(_ladder.LADDER):
        start = _ladder.OFFSETS[i]
        block = _ladder.TABLES[:, start : start + 2 * steps + 1]
        assert np.array_equal(block, _ladder.nodes(0.0, steps))
    assert _ladder.TABLES.shape[1] == _ladder.OFFSETS[-1] + 2 * _ladder.LADDER[-1] + 1
