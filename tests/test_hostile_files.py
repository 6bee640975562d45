"""Model files and the command line against hostile input (issue 39): every failure is a
MechError naming the field at fault (the CLI: one line on stderr, exit code 1, no
traceback); nothing reads without bound, blocks, or runs code."""

from __future__ import annotations

import io
import json
import os

import numpy as np
import pytest

import mechsys as ms
from mechsys import models
from mechsys.cli import main


@pytest.fixture(scope="module")
def base() -> dict:
    return ms.io.model_to_dict(models.slider_crank())


def _write(tmp_path, data, name="m.json") -> str:
    p = tmp_path / name
    p.write_text(json.dumps(data), encoding="utf-8")
    return str(p)


def _with_drive(base, text):
    d = json.loads(json.dumps(base))
    d["constraints"][-1]["args"][1] = {"expr": text}
    return d


def _cli(argv, capsys) -> tuple[int, str]:
    rc = main(argv)
    err = capsys.readouterr().err
    return rc, err


def _one_line_error(rc, err, *culprits):
    assert rc == 1
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for c in culprits:
        assert c in err, err


@pytest.mark.parametrize("text,why", [
    ("log(0)*T", "not finite"),
    ("T/0.0", "division by zero"),
    ("1/0.0 + T", "division by zero"),
    ("T/(0.0*T)", "division by zero"),
    ("zoo*T", "unknown name 'zoo'"),
    ("oo*T", "unknown name 'oo'"),
    ("T*log(0.0)", "not finite"),
    ("atan2(0, 0)*T", "not finite"),
])
def test_non_finite_drive_is_a_model_error(base, tmp_path, capsys, text, why):
    """log(0), 1/0.0 (float zero: SymPy 1.13's Float(0.0) != 0 slipped past the guard) and
    zoo gave a KeyError 'ComplexInfinity' at the first solve."""
    path = _write(tmp_path, _with_drive(base, text))
    with pytest.raises(ms.ModelError, match=why) as err:
        ms.load(path)
    assert "constraint 'drive'" in str(err.value)
    rc, out = _cli(["run", path, "--t", "0:1:3", "--out", str(tmp_path / "o.csv")], capsys)
    _one_line_error(rc, out, why)


def test_unknown_backend_in_a_file(base, tmp_path, capsys):
    d = json.loads(json.dumps(base))
    d["options"]["backend"] = "fortran"
    path = _write(tmp_path, d)
    with pytest.raises(ms.ModelError, match="options.backend 'fortran'"):
        ms.load(path)
    # and through the API: a ModelError (also a ValueError), not a bare ValueError
    import sympy as sp

    from mechsys.compile._backends import compile_exprs

    with pytest.raises(ms.ModelError, match="'fortran'"):
        compile_exprs([sp.Symbol("x")], [sp.Symbol("x") ** 2], backend="fortran")


def test_abstract_load_type_is_unknown(base, tmp_path):
    d = json.loads(json.dumps(base))
    d["loads"] = [{"name": "l", "type": "LoadBase", "args": [], "kwargs": {}}]
    with pytest.raises(ms.ModelError, match="unknown load type 'LoadBase'"):
        ms.load(_write(tmp_path, d))


def test_not_utf8(base, tmp_path, capsys):
    p = tmp_path / "latin1.json"
    p.write_bytes(json.dumps(base).replace("piston", "pist\u00f6n").encode("latin-1"))
    with pytest.raises(ms.ModelError, match="not UTF-8"):
        ms.load(p)
    _one_line_error(*_cli(["run", str(p)], capsys), "not UTF-8")


@pytest.mark.parametrize("name", ["pist\udcff", "pis\nton", "pis\x00ton", "pis\u2028ton"])
def test_names_must_be_printable(base, tmp_path, capsys, name):
    """A lone surrogate in a name (legal in JSON) ended the CLI with a UnicodeEncodeError."""
    p = tmp_path / "n.json"
    p.write_text(json.dumps(base).replace("piston", json.dumps(name)[1:-1]), encoding="utf-8")
    with pytest.raises(ms.ModelError, match="printable"):
        ms.load(p)
    _one_line_error(*_cli(["run", str(p)], capsys), "printable")


def test_directory_missing_fifo_and_device(tmp_path, capsys):
    cases = [(tmp_path, "a directory"), (tmp_path / "nothere.json", "No such file")]
    if hasattr(os, "mkfifo"):
        fifo = tmp_path / "fifo"
        os.mkfifo(fifo)
        cases.append((fifo, "not a regular file"))      # did block forever
    if os.path.exists("/dev/zero"):
        cases.append(("/dev/zero", "not a regular file"))   # was read past 3 GB
    for path, why in cases:
        with pytest.raises(ms.ModelError, match=why) as err:
            ms.load(path)
        assert str(path) in str(err.value)
        _one_line_error(*_cli(["run", str(path)], capsys), why)


def test_file_larger_than_the_cap_is_not_read_whole(tmp_path, monkeypatch):
    from mechsys.io import _files

    p = tmp_path / "big.json"
    p.write_bytes(b" " * 2000)
    monkeypatch.setattr(_files, "MAX_FILE_BYTES", 1000)
    with pytest.raises(ms.ModelError, match="more than 1000 bytes; at most 1000"):
        ms.load(p)


def test_cli_internal_error_is_one_line(monkeypatch, capsys, tmp_path):
    """Whatever escapes (a bug), the command line prints one line and exits 1."""
    from mechsys import cli

    def boom(*a, **k):
        raise KeyError("ComplexInfinity")

    monkeypatch.setattr(cli, "run", boom)
    monkeypatch.delenv("MECHSYS_DEBUG", raising=False)
    _one_line_error(*_cli(["run", "x.json"], capsys), "internal error KeyError")


def test_cli_message_with_unencodable_text(monkeypatch):
    """A lone surrogate in a message (a path from the shell) prints escaped, never raises."""
    from mechsys import cli

    buf = io.BytesIO()
    stream = io.TextIOWrapper(buf, encoding="ascii")
    cli._say("bad \udcff name\nsecond", stream)
    stream.flush()
    assert buf.getvalue() == b"bad \\udcff name\\nsecond\n"


def test_loading_is_linear_in_the_constraints(monkeypatch):
    """The reader rebuilt every name of the model after each constraint (and looked bodies
    up by scanning the list): quadratic, 2,000 jointed bodies took 100 s. Now the names are
    gathered a fixed number of times, however many constraints there are (20 s, linear)."""
    from mechsys.io import _files

    m = ms.Model2D()
    prev = m.ground.point((0, 0))
    for i in range(40):
        b = m.add_body(f"b{i}", points={"p": (1, 0)}, guess=((i, 0), 0))
        m.add(ms.Revolute2(prev, b.point(0)))
        prev = b.point("p")
    data = _files.model_to_dict(m)
    calls = []
    real = _files._all_names
    monkeypatch.setattr(_files, "_all_names", lambda mm: calls.append(1) or real(mm))
    lookups = []
    real_body = type(m).body
    monkeypatch.setattr(type(m), "body", lambda self, spec: lookups.append(spec) or real_body(self, spec))
    back = _files.model_from_dict(data)
    assert len(back.constraints) == 40
    assert len(calls) <= 3 and len(lookups) == 0


# -- budgets (issue 39): each exceeded budget a ModelError naming the limit, before SymPy
# computes anything large -----------------------------------------------------------------
_PRODUCT_160 = "*".join(f"(1+T/{i + 1})" for i in range(160))


@pytest.mark.parametrize("text,limit", [
    ("sqrt(2)**(10**299)", "MAX_EXPONENT"),             # grew past 3 GB inside ms.load
    ("(2*T)**(10**9)", "MAX_EXPONENT"),
    ("((2*T)**1000)**1000", "grow past"),
    ("pi**(10**10)", "MAX_EXPONENT"),
    ("exp(10**9*log(2))", "MAX_EXP_ARGUMENT"),          # hung (SymPy computes 2**(10**9))
    ("exp(T + 10**9*log(2))", "MAX_EXP_ARGUMENT"),
    ("exp(1000)", "MAX_EXP_ARGUMENT"),
    (_PRODUCT_160, "MAX_FACTORS"),                      # 3.2 KB: 240 s and 2.4 GB at solve
    ("+".join(["sin(cos(T))"] * 600), "MAX_OPERATIONS"),
])
def test_expression_budgets(base, tmp_path, text, limit):
    with pytest.raises(ms.ModelError, match=limit) as err:
        ms.load(_write(tmp_path, _with_drive(base, text)))
    assert "constraint 'drive'" in str(err.value)


def test_within_the_budgets_still_reads(base, tmp_path):
    import sympy as sp

    m = ms.load(_write(tmp_path, _with_drive(base, "*".join(f"(1+T/{i + 1})" for i in range(32)))))
    drive = m.constraint("drive")
    t = sp.Symbol("t")
    # the product, exactly (an independent product of the same factors)
    expected = sp.prod([1 + t / (i + 1) for i in range(32)])
    got = drive.equations(m.space)[0]
    assert got.free_symbols >= {ms.T}
    v = float(got.subs({ms.T: 0.3, **{s: 0 for s in got.free_symbols - {ms.T}}}))
    assert v == pytest.approx(-float(expected.subs(t, 0.3)), rel=1e-12) or \
        v == pytest.approx(float(expected.subs(t, 0.3)), rel=1e-12)


@pytest.mark.parametrize("prim,kwargs,field", [
    ("Wheel", {"spokes": 1e9}, "spokes"),
    ("PitchCircle", {"teeth": 1000000000}, "teeth"),
    ("Sphere", {"n": 100000}, "n"),
])
def test_drawing_counts_are_bounded(base, tmp_path, prim, kwargs, field):
    """spokes=1e9 or teeth=1e9 in a file went past 3 GB when drawn."""
    d = json.loads(json.dumps(base))
    d["graphics"] = [{"type": prim, "args": [{"body": "crank"}], "kwargs": kwargs}]
    with pytest.raises(ms.ModelError, match=f"{field} must be a whole number from .* to 1000"):
        ms.load(_write(tmp_path, d))


# -- outputs that survive their names (issue 39 item 4) -----------------------------------
@pytest.mark.parametrize("name", ["pis,ton", 'pis"ton', "=HYPERLINK(1)", "+1", "-x", "@a", "a b"])
def test_cli_csv_survives_names(base, tmp_path, capsys, name):
    """A comma shifted every column (read back without error, piston.x NaN); '=' made a
    spreadsheet formula. Read back with the csv module: the header is the names (formula-like
    ones behind an apostrophe), each column the solution's numbers, exactly."""
    import csv

    d = json.loads(json.dumps(base).replace('"piston"', json.dumps(name)))
    path = _write(tmp_path, d)
    out = tmp_path / "o.csv"
    assert main(["run", path, "--t", "0:1:5", "--out", str(out)]) == 0
    with open(out, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    shown = ("'" + name) if name[0] in "=+-@" else name
    assert f"{shown}.x" in header and len(set(map(len, rows))) == 1
    sol = ms.load(path).solve(np.linspace(0, 1, 5))
    col = header.index(f"{shown}.x")
    got = np.array([float(r[col]) for r in rows[1:]])
    j = sol.names.index(f"{name}.x")
    np.testing.assert_array_equal(got, sol.q[:, j])


def test_viewer_html_escapes_names():
    """Nothing a title or a label holds can close the viewer's script block or open a tag."""
    m = models.slider_crank_3d()
    sol = m.solve(np.linspace(0, 1, 3))
    evil = "</script><script>alert(1)</script><!--&"
    html = str(ms.draw.Scene(m, [], default=True).viewer(sol, title=evil))
    assert "<script>alert" not in html and "<!--&" not in html
    start = html.index('id="mechsys-data"')
    block = html[start:html.index("</script>", start)]
    data = json.loads(block[block.index(">") + 1:])
    assert data["title"] == evil


# -- the generated hostile-input suite (issue 39 item 6) ----------------------------------
_HOSTILE_VALUES = [
    None, True, 0, -1, 1e300, -1e300, 10 ** 39, "", "x" * 300, "__import__('os').system('id')",
    "a\nb", "\udcff", "=cmd|' /C calc'!A0", "pis,ton", [], {}, [[[[[]]]]], {"a": 1, "b": 2},
    {"expr": "sqrt(2)**(10**299)"}, {"expr": "exp(10**9*log(2))"}, {"expr": "log(0)"},
    {"expr": "1/0.0"}, {"expr": "zoo"}, {"expr": "T" + "*T" * 40}, {"expr": "(" * 150 + "T" + ")" * 150},
    {"expr": "9" * 45}, {"expr": "T.__class__"}, {"expr": 5}, {"body": "nobody"}, {"body": 3},
    {"point": {"body": "crank", "local": ["1e400", 0]}}, {"tuple": [{"expr": "log(0)"}]},
    {"constraint": {"type": "Popen", "args": []}}, {"constraint_ref": "nothing"},
    {"load": {"type": "LoadBase"}}, {"matrix": [[1], [2, 3]]}, {"array": ["a"]},
    {"dict": [[1]]}, {"condition": "T > log(0)"}, {"vector": {"from": 1}},
    {"axis": {"origin": None}}, {"plane": [1, 2]}, {"line": [None, None]},
]


def _paths(obj, path=()):
    """Every place in the JSON tree (containers and leaves)."""
    yield path
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, (*path, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, (*path, i))


def _replace(obj, path, value):
    out = json.loads(json.dumps(obj))
    if not path:
        return value
    node = out
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    return out


@pytest.fixture(scope="module")
def rich_base() -> dict:
    """A model file with every field in use: parameters, masses, loads, a driver, graphics."""
    m = models.slider_crank_dynamic(piston_force=-10.0)
    m.parameter("k", 2.0)
    m.variable("s", 0.5)
    ms.draw.attach(m, ms.draw.Wheel(m.body("crank"), spokes=4))
    return ms.io.model_to_dict(m)


def test_generated_hostile_inputs_only_raise_mecherrors(rich_base):
    """A few hundred hostile values, each put in one place of a model file (a fixed seed
    chooses the places; every top-level field is hit): loading either works or raises a
    MechError; never another exception, never a hang (each budget stops it early)."""
    import random

    from mechsys.io import _files

    rng = random.Random(39)
    paths = list(_paths(rich_base))
    by_field: dict = {}
    for p in paths:
        by_field.setdefault(p[0] if p else None, []).append(p)
    cases = []
    for ps in by_field.values():          # every field, then random places
        for v in rng.sample(_HOSTILE_VALUES, 6):
            cases.append((rng.choice(ps), v))
    while len(cases) < 300:
        cases.append((rng.choice(paths), rng.choice(_HOSTILE_VALUES)))
    escaped, loaded, solved = [], 0, set()
    for path, value in cases:
        data = _replace(rich_base, path, value)
        try:
            m = _files.model_from_dict(data, "hostile.json")
            loaded += 1
            # an analysis of what loaded: one per kind of hostile value (the compile is the
            # costly part), each a result or a MechError too
            if repr(value) not in solved and len(solved) < 8:
                solved.add(repr(value))
                m.solve(np.array([0.0, 0.1]), solution="dynamic")
        except ms.MechError as exc:
            assert str(exc)
        except Exception as exc:  # noqa: BLE001 - the point of the test
            escaped.append((path, repr(value)[:60], f"{type(exc).__name__}: {str(exc)[:120]}"))
    assert not escaped, escaped[:10]
    assert len(cases) >= 300 and loaded < len(cases) and solved


def test_cli_table_names_the_declared_units(tmp_path):
    """``mechsys run`` writes its table with the library's writer (``Solution.save``): a model
    that declares its units gets ``name [unit]`` headers (the CSV of ``mechsys run`` had bare
    names), numbers unchanged."""
    import csv

    m = models.slider_crank(crank=2.0, rod=6.0, speed=2 * np.pi)
    m.set_units(length="mm", mass="kg", time="s")
    path = m.save(tmp_path / "crank.json")
    out = tmp_path / "r.csv"
    assert main(["run", str(path), "--t", "0:1:5", "--out", str(out)]) == 0
    with open(out, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    assert header[0] == "t [s]"
    assert "piston.x [mm]" in header and "piston.x_d [mm/s]" in header
    assert "crank.th [rad]" in header and "crank.th_dd [rad/s^2]" in header
    sol = ms.load(path).solve(np.linspace(0, 1, 5))
    got = np.array([float(r[header.index("piston.x_dd [mm/s^2]")]) for r in rows[1:]])
    np.testing.assert_array_equal(got, sol.qdd[:, sol.names.index("piston.x")])
