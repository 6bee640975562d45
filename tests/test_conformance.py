"""The conformance suite over every registered constraint type."""

import pytest

from mechsys.constraints import REGISTRY
from mechsys.testing import CASES, check_constraint_case, iter_cases

ALL = list(iter_cases())


@pytest.mark.parametrize("name,case", ALL, ids=[c.label for _, c in ALL])
def test_constraint_conformance(name, case):
    errs = check_constraint_case(case)
    assert errs["residual"] < 1e-10


def test_every_registered_type_has_a_case():
    missing = sorted(set(REGISTRY) - set(CASES))
    assert not missing, f"constraint types without conformance cases: {missing}"
