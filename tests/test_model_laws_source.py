"""The text of a law's compiled module (:func:`bayestribo.model.laws.integrator._law_source`):
a template, the text the two templates share once, then the law's definitions."""

from __future__ import annotations

import inspect
import re

import pytest

from bayestribo.model.laws import _core, _core_shared, _restoring_core, get_law
from bayestribo.model.laws.integrator import _law_source
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
