r"""Tables of a solution: coordinates with their rates, reactions, applied loads and energies,
each column with its physical dimension and, when the model declares units
(``m.set_units``), its unit; as a pandas DataFrame, an xarray Dataset, or a file (CSV,
Parquet, HDF5, netCDF).

A column's dimension is :math:`L^a M^b T^c` (length, mass, time), written once per kind:

* translational coordinate :math:`L`, angle ``rad`` (planar ``th``), Euler parameter
  :math:`1`; each time derivative multiplies by :math:`T^{-1}`;
* reaction and applied force :math:`M L T^{-2}`, moment :math:`M L^2 T^{-2}` (about the body
  origin, global axes: ``sol.reaction(c, b)``, ``sol.loads(b, coordinates="global")``);
* kinetic and potential energy :math:`M L^2 T^{-2}`.

Model variables (a gear angle, a rope length, a cam parameter, a generalized coordinate)
have no dimension mechsys can know: their unit is left empty (``None``), never guessed.

Example::

    sol = m.solve(t, solution="dynamic")
    df = sol.to_dataframe(reactions=True, loads=True, energies=True)
    df.attrs["units"]["piston.x"]        # "mm" after m.set_units(length="mm", ...)
    sol.quantity("piston.x").to("m")     # a pint Quantity (needs pint)
    sol.save("run.parquet", reactions=True)
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import MechError, ModelError

#: dimension exponents (length, mass, time)
LENGTH, ONE = (1, 0, 0), (0, 0, 0)
FORCE, MOMENT = (1, 1, -2), (2, 1, -2)
ENERGY = MOMENT


@dataclass(frozen=True)
class Column:
    """One column: its values ``(N,)``, dimension exponents ``(length, mass, time)`` (None:
    not known) and a description."""

    name: str
    values: np.ndarray
    dims: tuple | None
    description: str
    angle: bool = False


def dimension_text(dims: tuple | None, angle: bool = False) -> str | None:
    """``"L/T"``, ``"M*L^2/T^2"``, ``"1"``, ``"rad/T"``; ``None`` when unknown."""
    return _compose(dims, ("L", "M", "T"), "rad" if angle else "1")


def unit_text(dims: tuple | None, units: dict | None, angle: bool = False) -> str | None:
    """The unit of a dimension in the model's declared units (``{"length": "mm", ...}``), or
    None when a base it needs is not declared or the dimension is unknown."""
    if dims is None:
        return None
    names = []
    for base, power in zip(("length", "mass", "time"), dims):
        if power and not (units and base in units):
            return None
        names.append(units[base] if units and base in units else "")
    return _compose(dims, names, "rad" if angle else "1")


def _compose(dims, names, unitless: str) -> str | None:
    if dims is None:
        return None
    num, den = ([], [])
    if unitless == "rad":
        num.append("rad")
    for k in (1, 0, 2):  # mass, length, time: "kg*mm/s^2"
        name, power = names[k], dims[k]
        if power:
            (num if power > 0 else den).append(name + (f"^{abs(power)}" if abs(power) != 1 else ""))
    text = "*".join(num) or "1"
    return text + ("/" + "/".join(den) if den else "")


def _rate(dims, k):
    return None if dims is None else (dims[0], dims[1], dims[2] - k)


def columns(sol, reactions: bool = False, loads: bool = False,
            energies: bool = False) -> list[Column]:
    """The columns of :meth:`Solution.to_dataframe` in order: ``t``; each coordinate with
    ``_d`` and ``_dd``; then, on request, reactions ``<constraint>.<body>.F<x|y|z>`` and
    ``.M<...>``, applied loads ``<body>.applied.F<x>`` ..., energies ``<body>.kinetic``,
    ``kinetic``, ``potential``."""
    m = sol.model
    dim = m.space.dim
    axes = "xyz"[:dim]
    maxes = "z" if dim == 2 else "xyz"
    trans = _translational(sol.system)
    out = [Column("t", np.asarray(sol.t, dtype=float), (0, 0, 1), "time")]
    for j, name in enumerate(sol.names):
        if trans[j] is None:
            dims, angle, what = None, False, "model variable (unit not known to mechsys)"
        elif trans[j]:
            dims, angle, what = LENGTH, False, "position coordinate"
        else:
            angle = dim == 2
            dims, what = ONE, "rotation angle" if angle else "Euler parameter"
        out.append(Column(name, sol.q[:, j], dims, what, angle))
        for k, arr, suffix in ((1, sol.qd, "_d"), (2, sol.qdd, "_dd")):
            if arr is not None:
                out.append(Column(name + suffix, arr[:, j], _rate(dims, k),
                                  f"{what}, time derivative {k}", angle))
    if reactions:
        out += _reaction_columns(sol, axes, maxes)
    if loads:
        for b in _moving_bodies(m):
            F, M = sol.loads(b, "applied", coordinates="global")
            out += _wrench_columns(f"{b.name}.applied", F, M, axes, maxes,
                                   f"applied loads on {b.name} at its origin, global axes")
    if energies:
        total = np.zeros(len(sol.t))
        for b in _moving_bodies(m):
            e = np.broadcast_to(np.asarray(sol.body_energy(b), dtype=float), total.shape)
            total = total + e
            out.append(Column(f"{b.name}.kinetic", e.copy(), ENERGY, f"kinetic energy of {b.name}"))
        out.append(Column("kinetic", total, ENERGY, "kinetic energy of the mechanism"))
        pe = np.broadcast_to(np.asarray(sol.potential_energy(), dtype=float), total.shape)
        out.append(Column("potential", pe.copy(), ENERGY,
                          "potential energy of gravity and linear springs"))
    names = [c.name for c in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ModelError(f"the table would have the column(s) {dup} twice: rename the bodies or "
                         "constraints whose names make them")
    return out


def _translational(system):
    """Per coordinate: True (position), False (rotation), None (a model variable), from the
    layout's column kinds (:func:`~mechsys.solvers._linalg._column_kinds`)."""
    from ..solvers._linalg import _column_kinds

    trans, body = _column_kinds(system)
    return [None if b < 0 else bool(t) for t, b in zip(trans, body)]


def _moving_bodies(m):
    return [b for b in m.bodies if not b.is_ground and b.gen_joint is None]


def _reaction_columns(sol, axes, maxes):
    if sol.lam is None:
        raise MechError("reactions=True needs the Lagrange multipliers: solve with "
                        "solution='static' or 'dynamic' (inverse dynamics), or run free motion")
    from ..constraints._generalized import GenJoint

    m = sol.model
    owners = []
    for o in sol.system.layout.eq_owner:
        if not isinstance(o, str) and all(o is not x for x in owners):
            owners.append(o)
    out = []
    for c in owners:
        if isinstance(c, GenJoint):
            F, M = sol.joint_reaction(c)
            out += _wrench_columns(f"{c.name}.{c.slave.name}", F, M, axes, maxes,
                                   f"force and moment {c.name} applies to {c.slave.name} at its origin")
            continue
        for b in c.bodies():
            b = m.body(b)
            if b.is_ground or b.gen_joint is not None:
                continue
            F, M = sol.reaction(c, b)
            out += _wrench_columns(f"{c.name}.{b.name}", F, M, axes, maxes,
                                   f"force and moment {c.name} applies to {b.name} at its origin")
    return out


def _wrench_columns(prefix, F, M, axes, maxes, what):
    F = np.atleast_2d(np.asarray(F, dtype=float))
    M = np.asarray(M, dtype=float)
    M = M.reshape(len(F), -1)
    cols = [Column(f"{prefix}.F{a}", F[:, i], FORCE, what + " (force)") for i, a in enumerate(axes)]
    cols += [Column(f"{prefix}.M{a}", M[:, i], MOMENT, what + " (moment)")
             for i, a in enumerate(maxes)]
    return cols


# -- the three forms --------------------------------------------------------------------------
def to_dataframe(sol, **which):
    """pandas DataFrame of :func:`columns`; ``df.attrs`` holds ``units`` (column -> unit or
    None), ``dimensions`` and ``descriptions``."""
    try:
        import pandas as pd
    except ImportError:
        raise MechError("to_dataframe needs pandas: pip install pandas") from None
    cols = columns(sol, **which)
    df = pd.DataFrame({c.name: c.values for c in cols})
    units = getattr(sol.model, "units", None)
    df.attrs["units"] = {c.name: unit_text(c.dims, units, c.angle) for c in cols}
    df.attrs["dimensions"] = {c.name: dimension_text(c.dims, c.angle) for c in cols}
    df.attrs["descriptions"] = {c.name: c.description for c in cols}
    return df


def to_xarray(sol, **which):
    """xarray Dataset over the dimension ``t``; each variable's attrs: ``units`` (when known),
    ``dimension``, ``long_name``."""
    try:
        import xarray as xr
    except ImportError:
        raise MechError("to_xarray needs xarray: pip install xarray") from None
    cols = columns(sol, **which)
    units = getattr(sol.model, "units", None)
    data = {}
    for c in cols[1:]:
        attrs = {"dimension": dimension_text(c.dims, c.angle) or "unknown", "long_name": c.description}
        u = unit_text(c.dims, units, c.angle)
        if u is not None:
            attrs["units"] = u
        data[c.name] = ("t", c.values, attrs)
    t_attrs = {"long_name": "time", "dimension": "T"}
    if unit_text((0, 0, 1), units):
        t_attrs["units"] = unit_text((0, 0, 1), units)
    return xr.Dataset(data, coords={"t": ("t", cols[0].values, t_attrs)})


def quantities(sol, names=None, **which) -> dict:
    """``{column: pint Quantity}``: the columns of :func:`columns` (``names``: those only, in
    that order) as arrays in the model's declared units (``m.set_units``), each with the unit
    of its dimension (angles in ``rad``, Euler parameters dimensionless). A column whose unit
    is not known (a model variable; a base unit the model did not declare) is left out of the
    whole table and refused when named. Needs pint."""
    from .._errors import choice
    from ..geometry._units import _registry

    units = getattr(sol.model, "units", None)
    if not units:
        raise ModelError("results in units need the model's units: declare them with "
                         "m.set_units(length=..., mass=..., time=...) before solving")
    ureg = _registry()
    cols = {c.name: c for c in columns(sol, **which)}
    if names is None:
        picked = [c for c in cols.values() if unit_text(c.dims, units, c.angle) is not None]
    else:
        if isinstance(names, str):
            names = [names]
        picked = []
        for name in names:
            if name not in cols:
                choice(name, list(cols), "quantity: column")
            c = cols[name]
            if unit_text(c.dims, units, c.angle) is None:
                why = ("its dimension is not known to mechsys (a model variable)" if c.dims is None
                       else f"its dimension {dimension_text(c.dims, c.angle)} needs a base unit "
                            "the model did not declare (m.set_units)")
                raise ModelError(f"quantity: column {name!r} has no unit: {why}; take its "
                                 "numbers from sol.to_dataframe() or sol[...] instead")
            picked.append(c)
    return {c.name: ureg.Quantity(np.asarray(c.values, dtype=float),
                                  unit_text(c.dims, units, c.angle).replace("^", "**"))
            for c in picked}


#: first characters a spreadsheet reads as a formula (OWASP's list for CSV injection)
_FORMULA = ("=", "+", "-", "@", "\t", "\r")


def csv_cell(text: str) -> str:
    """A text cell a spreadsheet shows as text and never evaluates: a name starting like a
    formula (``=``, ``+``, ``-``, ``@``, tab, carriage return) gets a leading apostrophe; the
    csv module quotes commas, quotes and newlines. (One rule for every CSV mechsys writes:
    ``sol.save`` and ``mechsys run``.)"""
    return "'" + text if text.startswith(_FORMULA) else text


def save(sol, path, **which) -> Path:
    """Write the table to ``path`` by its suffix: ``.csv`` (header ``name [unit]``; floats
    written repr-exact, so they read back to the same doubles), ``.parquet`` (pyarrow; units
    in each field's metadata), ``.h5``/``.hdf5`` (h5py; one dataset per column with
    ``units``), ``.nc`` (netCDF through xarray). The optional writer is named when missing."""
    path = Path(path)
    suffix = path.suffix.lower()
    writers = {".csv": _write_csv, ".parquet": _write_parquet, ".h5": _write_hdf5,
               ".hdf5": _write_hdf5, ".nc": _write_netcdf}
    if suffix not in writers:
        raise ModelError(f"save({str(path)!r}): write .csv, .parquet, .h5/.hdf5 or .nc "
                         f"(got {suffix or 'no suffix'!r})")
    writers[suffix](sol, path, which)
    return path


def _labelled(sol, which):
    cols = columns(sol, **which)
    units = getattr(sol.model, "units", None)
    return cols, [unit_text(c.dims, units, c.angle) for c in cols]


def _write_csv(sol, path, which):
    cols, units = _labelled(sol, which)
    header = [csv_cell(c.name + (f" [{u}]" if u else "")) for c, u in zip(cols, units)]
    data = np.column_stack([c.values for c in cols])
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, quoting=csv.QUOTE_MINIMAL)
        w.writerow(header)
        for row in data:
            w.writerow([repr(float(v)) for v in row])


def _write_parquet(sol, path, which):
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise MechError("writing .parquet needs pyarrow: pip install pyarrow") from None
    cols, units = _labelled(sol, which)
    fields = [pa.field(c.name, pa.float64(), metadata={
        "unit": u or "", "dimension": dimension_text(c.dims, c.angle) or "unknown",
        "description": c.description}) for c, u in zip(cols, units)]
    table = pa.table([pa.array(c.values, pa.float64()) for c in cols], schema=pa.schema(fields))
    pq.write_table(table, path)


def _write_hdf5(sol, path, which):
    try:
        import h5py
    except ImportError:
        raise MechError("writing .h5 needs h5py: pip install h5py") from None
    cols, units = _labelled(sol, which)
    with h5py.File(path, "w") as fh:
        for c, u in zip(cols, units):
            # a name with "/" would open an HDF5 group: keep every column a top-level dataset
            ds = fh.create_dataset(c.name.replace("/", "\u2215"), data=c.values)
            ds.attrs["name"] = c.name
            ds.attrs["units"] = u or ""
            ds.attrs["dimension"] = dimension_text(c.dims, c.angle) or "unknown"
            ds.attrs["description"] = c.description


def _write_netcdf(sol, path, which):
    ds = to_xarray(sol, **which)
    try:
        ds.to_netcdf(path)
    except (ImportError, ValueError) as exc:
        raise MechError(f"writing .nc needs a netCDF engine (pip install netCDF4 or scipy): "
                        f"{exc}") from None
