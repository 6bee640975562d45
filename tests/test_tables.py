"""Result tables (issue 38, item 3): reactions, loads and energies beside the coordinates, each
column with its dimension and unit, as DataFrame, xarray Dataset and files. The numbers are
checked against independent relations: the static balance of every body, the kinetic energy
from the mass matrix, and exact round trips through each file format."""

from __future__ import annotations

import csv

import numpy as np
import pytest

import mechsys as ms
from mechsys import models

pd = pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def static():
    m = models.slider_crank_dynamic(piston_force=-40.0)
    return m, m.solve(np.linspace(0.05, 0.95, 7), solution="static")


@pytest.fixture(scope="module")
def dynamic():
    m = models.slider_crank_dynamic(piston_force=-40.0)
    m.set_units(length="mm", mass="kg", time="s")
    return m, m.solve(np.linspace(0.0, 1.0, 9), solution="dynamic")


def test_static_table_balances_every_body(static):
    """Statics: on each body, the applied loads plus the reactions of every constraint
    acting on it sum to zero (force and moment about the body origin)."""
    m, sol = static
    df = sol.to_dataframe(reactions=True, loads=True)
    for b in ("crank", "rod", "piston"):
        on_b = [c for c in df.columns if f".{b}." in c]
        scale = np.abs(df[on_b]).to_numpy().max()
        for comp in ("Fx", "Fy", "Mz"):
            react = [c for c in df.columns if c.endswith(f".{b}.{comp}") and "applied" not in c]
            assert len(react) >= 2, react
            total = df[f"{b}.applied.{comp}"] + df[react].sum(axis=1)
            assert np.abs(total).max() <= 1e-10 * scale, (b, comp)
    # the columns are the solution's own outputs
    F, M = sol.reaction("slider", "piston")
    assert np.array_equal(df["slider.piston.Fy"], F[:, 1])
    assert np.array_equal(df["slider.piston.Mz"], M)


def test_energy_columns_match_the_mass_matrix(dynamic):
    m, sol = dynamic
    df = sol.to_dataframe(energies=True)
    M = np.asarray(sol.mass_matrix(), dtype=float)
    ke = 0.5 * np.einsum("ki,kij,kj->k", sol.qd, M.reshape(len(sol.t), *M.shape[-2:]), sol.qd) \
        if M.ndim == 3 else 0.5 * np.einsum("ki,ij,kj->k", sol.qd, M, sol.qd)
    assert np.allclose(df["kinetic"], ke, rtol=1e-12, atol=1e-12 * ke.max())
    parts = df[["crank.kinetic", "rod.kinetic", "piston.kinetic"]].sum(axis=1)
    assert np.allclose(parts, df["kinetic"], rtol=1e-13)
    # gravity (9.81 down) on the three masses: V = g * sum m_i y_ci
    y = [sol.location(m.body(b).point(c))[:, 1] for b, c in
         (("crank", (1.0, 0)), ("rod", (3.0, 0)), ("piston", (0, 0)))]
    assert np.allclose(df["potential"], 9.81 * (1.5 * y[0] + 2.0 * y[1] + 3.0 * y[2]), atol=1e-9)


def test_units_and_dimensions_in_the_metadata(dynamic, static):
    _, sol = dynamic
    df = sol.to_dataframe(reactions=True, energies=True)
    u, d = df.attrs["units"], df.attrs["dimensions"]
    assert (u["t"], u["piston.x"], u["piston.x_d"], u["rod.th"], u["rod.th_dd"]) == \
        ("s", "mm", "mm/s", "rad", "rad/s^2")
    assert u["slider.piston.Fy"] == "kg*mm/s^2" and u["drive.crank.Mz"] == "kg*mm^2/s^2"
    assert u["kinetic"] == "kg*mm^2/s^2"
    assert d["slider.piston.Fy"] == "M*L/T^2" and d["piston.x_dd"] == "L/T^2"
    # no declared units: dimensions only, never a guessed unit
    df0 = static[1].to_dataframe()
    assert df0.attrs["units"]["piston.x"] is None and df0.attrs["dimensions"]["piston.x"] == "L"
    assert df0.attrs["units"]["crank.th"] == "rad"


def gear_pair(units=None):
    """Two gears on pins, the first driven: the gear's extra variable is a model variable."""
    m = ms.Model2D()
    a = m.add_body("a", guess=((0, 0), 0))
    b = m.add_body("b", guess=((3, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)))
    m.add(ms.Revolute2(m.ground.point((3, 0)), b.point(0)))
    m.add(ms.TwoGears1(a.point(0), 1.0, b.point(0), 2.0, 1))
    m.add(ms.RotationLock1(a, ms.T))
    if units:
        m.set_units(**units)
    return m


def test_model_variables_have_no_guessed_unit():
    """A gear's extra variable (model variable) gets no unit, not a length or angle."""
    sol = gear_pair().solve(np.linspace(0, 1, 3))
    df = sol.to_dataframe()
    variables = [n for n in sol.names if "." not in n]
    assert variables, sol.names
    for n in variables:
        assert df.attrs["units"][n] is None and df.attrs["dimensions"][n] is None


def test_reactions_need_multipliers():
    sol = models.slider_crank().solve(np.linspace(0, 1, 3))
    with pytest.raises(ms.MechError, match="solution='static' or 'dynamic'"):
        sol.to_dataframe(reactions=True)


def test_xarray_dataset_carries_units(dynamic):
    xr = pytest.importorskip("xarray")
    _, sol = dynamic
    ds = sol.to_xarray(reactions=True)
    assert isinstance(ds, xr.Dataset)
    assert np.array_equal(ds["t"].values, sol.t) and ds["t"].attrs["units"] == "s"
    assert ds["piston.x_d"].attrs["units"] == "mm/s"
    assert np.array_equal(ds["wrist pin.piston.Fx"].values, sol.reaction("wrist pin", "piston")[0][:, 0])


def test_csv_round_trip_is_exact_and_names_survive(tmp_path):
    """Names with commas, quotes, newlines and a leading '=' keep their columns; the header
    cell of a formula-like name is neutralised; the floats read back bit for bit."""
    m = ms.Model2D()
    c = m.add_body('=cr,"ank"\nx', points={"tip": (1, 0)}, guess=((0, 0), 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)), name="pivot")
    m.add(ms.RotationLock1(c, 0.7 * ms.T + 0.1), name="drive")
    sol = m.solve(np.linspace(0, 1, 11))
    path = sol.save(tmp_path / "r.csv")
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], np.array(rows[1:], dtype=float)
    assert len(header) == 1 + 3 * len(sol.names)
    assert header[1] == "'" + sol.names[0]              # '=...' shown as text
    assert all(len(r) == len(header) for r in rows)
    j = header.index("'" + sol.names[2] + "_d")
    assert np.array_equal(body[:, j], sol.qd[:, 2]) and np.array_equal(body[:, 0], sol.t)


def test_parquet_hdf5_and_netcdf_keep_values_and_units(dynamic, tmp_path):
    _, sol = dynamic
    pq = pytest.importorskip("pyarrow.parquet")
    table = pq.read_table(sol.save(tmp_path / "r.parquet", reactions=True))
    field = table.schema.field("slider.piston.Fy")
    assert field.metadata[b"unit"] == b"kg*mm/s^2"
    fy = sol.reaction("slider", "piston")[0][:, 1]
    assert np.array_equal(table.column("slider.piston.Fy").to_numpy(), fy)
    h5py = pytest.importorskip("h5py")
    with h5py.File(sol.save(tmp_path / "r.h5", energies=True), "r") as fh:
        assert fh["kinetic"].attrs["units"] == "kg*mm^2/s^2"
        assert np.array_equal(fh["piston.x"][()], sol.q[:, sol.names.index("piston.x")])
    xr = pytest.importorskip("xarray")
    with xr.open_dataset(sol.save(tmp_path / "r.nc")) as ds:
        assert ds["piston.x"].attrs["units"] == "mm"
        assert np.array_equal(ds["piston.x"].values, sol.q[:, sol.names.index("piston.x")])


def test_unknown_format_is_refused(static, tmp_path):
    with pytest.raises(ms.ModelError, match=r"\.csv, \.parquet"):
        static[1].save(tmp_path / "r.xlsx")


def test_results_as_pint_quantities_in_the_declared_units(dynamic, static):
    pint = pytest.importorskip("pint")
    ureg = pint.get_application_registry()
    m, sol = dynamic                      # mm, kg, s
    x = sol.quantity("piston.x")
    assert x.units == ureg.mm and np.array_equal(x.magnitude, sol["piston.x"])
    assert np.allclose(x.to("m").magnitude, sol["piston.x"] / 1000, rtol=1e-15)
    v = sol.quantity("piston.x_d").to("m/s")
    assert np.allclose(v.magnitude, sol.qd[:, sol.names.index("piston.x")] / 1000, rtol=1e-15)
    w = sol.quantity("rod.th_d")
    assert w.units == ureg.rad / ureg.s
    # a reaction force in kg mm/s^2 is a millinewton
    F = sol.quantity("slider.piston.Fy", reactions=True)
    assert np.allclose(F.to("N").magnitude, sol.reaction("slider", "piston")[0][:, 1] / 1000,
                       rtol=1e-14)
    E = sol.quantity("kinetic", energies=True)
    assert E.dimensionality == (ureg.J).dimensionality
    everything = sol.quantities(reactions=True)
    assert "slider.piston.Fy" in everything and everything["t"].units == ureg.s


def test_quantities_refuse_what_has_no_unit(static):
    pytest.importorskip("pint")
    _, sol = static                       # no declared units
    with pytest.raises(ms.ModelError, match="m.set_units"):
        sol.quantity("piston.x")
    sol = gear_pair({"length": "mm", "time": "s"}).solve(np.linspace(0, 1, 3))
    variable = next(n for n in sol.names if "." not in n)
    with pytest.raises(ms.ModelError, match=f"{variable!r} has no unit"):
        sol.quantity(variable)
    assert variable not in sol.quantities() and "a.th" in sol.quantities()
    with pytest.raises(ms.OptionError, match="a.th"):
        sol.quantity("a.thh")


@pytest.mark.parametrize("suffix, module, package", [
    (".parquet", "pyarrow", "pyarrow"), (".h5", "h5py", "h5py"), (".nc", "xarray", "xarray")])
def test_a_missing_writer_is_named(static, tmp_path, monkeypatch, suffix, module, package):
    """Without its optional writer a format is refused with a MechError naming the package to
    install (as where it is not installed: the import fails); CSV needs none."""
    monkeypatch.setitem(__import__("sys").modules, module, None)
    with pytest.raises(ms.MechError, match=f"pip install {package}"):
        static[1].save(tmp_path / f"r{suffix}")
    assert static[1].save(tmp_path / "r.csv").stat().st_size > 0


def test_tables_and_units_name_their_missing_package(dynamic, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ms.MechError, match="pip install pandas"):
        dynamic[1].to_dataframe()
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(ms.MechError, match="pip install xarray"):
        dynamic[1].to_xarray()
    monkeypatch.setitem(sys.modules, "pint", None)
    with pytest.raises(ms.ModelError, match=r"pip install mechsys\[units\]"):
        dynamic[1].in_units.location("piston")
