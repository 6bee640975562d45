r"""The numbers that the Python solvers and their compiled loops must share, and the signal
:class:`Singular` that a factorisation raises when one of them is crossed.

A leaf of ``solvers/`` (it imports no module of the package): the compiled loops
(``_jit_*_loop``) bake these constants in when they compile, and importing them from here
spares a loop the import of a Python solver (``_kinematics``, ``_position``, ``_rank``), which
once tied the loops and the solvers in an import circle (decision 0058). Each constant is
documented where it is defined, here; the modules that use it import it by name.

The thresholds on the reciprocal condition number :math:`r = 1/\kappa_1(A)` of a scaled
matrix:

.. math:: r < \mathrm{RCOND\_MIN} \Rightarrow \text{singular}, \qquad
          r < \mathrm{RCOND\_WARN} \Rightarrow \text{near a singular position (warned)}

Example::

    from mechsys.solvers._tolerances import RCOND_MIN, Singular

    if rcond < RCOND_MIN:
        raise Singular(f"reciprocal condition {rcond:.2e} below {RCOND_MIN:g}")
"""

from __future__ import annotations

import math

#: above this many unknowns the solvers take sparse matrices (SuperLU, ``FixedPattern``)
#: and the compiled loops their banded or sparse LU; at or below it, dense LAPACK
SPARSE_THRESHOLD = 150
#: a scaled matrix whose reciprocal condition number is below this is singular
RCOND_MIN = 1e-13
#: a lever arm below this fraction of the model's length is round-off (see ``Scaling.of``)
ARM_ROUNDOFF = 1e-9
#: threshold partial pivoting of the sparse LU: the fill-reducing order's diagonal entry is
#: the pivot while ``|b_kk| >= PIVOT_TOL max_i |b_ik|`` (the fill the ordering planned)
PIVOT_TOL = 0.1

#: below this reciprocal condition number of the scaled Phi_q a sweep warns (near a toggle
#: position) and does not trust qd, qdd in its predictor
RCOND_WARN = 1e-6
#: in a compiled sweep's ``rconds``: an estimate proven to be at least ``RCOND_WARN`` and not
#: computed yet (``SweepResult.rcond`` computes it when asked: decision 0023)
RCOND_PENDING = math.inf
#: largest distance (rad) of a solved rotational coordinate from its prediction
ROTATION_JUMP = math.pi / 2
#: largest rotation (rad) of the first predictor step when the sweep starts near a toggle
ROTATION_START = math.pi / 8
#: a Taylor prediction may turn this much (rad) more than 4 x the secant step
ROTATION_SLACK = 0.25

#: a chord step (with a factorisation of an earlier Jacobian, see ``solve_position``) is
#: kept when it reduces the scaled residual at least this much; otherwise Newton takes over.
#: (At 0.1 a chord took 6-7 steps on a coarse sweep where Newton takes 2-3, and near that
#: rate rounding decided between a step more or less.)
CHORD_RATE = 0.01

#: singular-value ratio s_min / s_max of the scaled Jacobian below which free motion is in
#: the "zone" of a singular instant (measured by the reciprocal condition of J^ J^T < ZONE^2)
ZONE = 1e-3


class Singular(Exception):
    """Raised by a factorisation (``_linalg.factor``, ``FixedPattern``, the compiled sparse
    LU's ``SparseLU``) when the matrix is numerically singular: its reciprocal condition
    number below :data:`RCOND_MIN`, or a pivot column without a nonzero entry. Internal: the
    solvers catch it and raise the user-facing :class:`~mechsys.SingularJacobianError`."""


__all__ = ["ARM_ROUNDOFF", "CHORD_RATE", "PIVOT_TOL", "RCOND_MIN", "RCOND_PENDING", "RCOND_WARN",
           "ROTATION_JUMP", "ROTATION_SLACK", "ROTATION_START", "SPARSE_THRESHOLD", "Singular",
           "ZONE"]
