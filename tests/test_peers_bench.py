"""The side-by-side benchmark suite (benchmarks/peers/): its models, references and page.

Runs the suite on the four-bar only (a few seconds); the peers join when the ``bench`` extra
is installed and are reported as missing otherwise. No timing is asserted: only that the
machinery measures, judges accuracy against the independent reference and writes its block.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks" / "peers"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import importlib.util  # noqa: E402

import peer_problems as P  # noqa: E402

_spec = importlib.util.spec_from_file_location("peers_run", ROOT / "benchmarks" / "peers" / "run.py")
peers_run = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(peers_run)


def test_four_bar_reference_closes_and_matches_a_tight_mechsys_run():
    refs = P.references(sizes=())
    crank, coupler, rocker = refs["C"]["phi"]
    assert P.four_bar_gap((crank, coupler, rocker)) < 1e-12
    assert refs["C"]["check"] < 1e-12          # two mpmath runs agree


def test_chain_reference_is_the_double_pendulum_reference_for_two_links():
    """The chain's minimal ODE (used for problem B) against problem A's mpmath reference."""
    from scipy.integrate import solve_ivp

    r = solve_ivp(P.chain_rhs(2), (0.0, P.T_PENDULUM), np.zeros(4), method="DOP853",
                  rtol=1e-13, atol=1e-13)
    assert np.abs(r.y[:2, -1] - P.references(sizes=())["A"]["phi"]).max() < 1e-7


def test_slider_crank_closed_form_against_finite_differences():
    t = np.linspace(0.1, 0.9, 9)
    h = 1e-5
    f = P.slider_crank_closed_form
    fd1 = (f(t + h) - f(t - h)) / (2 * h)
    assert np.allclose(fd1[:3], f(t)[3:6], atol=1e-6)
    assert np.allclose(fd1[3:6], f(t)[6:9], atol=1e-4)


def test_suite_writes_its_block_and_mechsys_meets_the_four_bar_target(tmp_path, capsys):
    page = tmp_path / "performance.md"
    page.write_text("# Performance\n\nkept text\n")
    assert peers_run.main(["--quick", "--problems", "C", "--write", str(page)]) == 0
    text = page.read_text()
    assert text.startswith("# Performance\n\nkept text")
    assert text.count(peers_run.BEGIN) == 1 and text.count(peers_run.END) == 1
    row = next(line for line in text.splitlines() if line.startswith("| four-bar 5 s |"))
    mechsys_cell = row.split("|")[3]
    assert "not reached" not in mechsys_cell and "DOP853" in mechsys_cell
    # a second write replaces the block instead of appending one
    peers_run.write_block(page, f"{peers_run.BEGIN}\nnew\n{peers_run.END}\n")
    text = page.read_text()
    assert text.count(peers_run.BEGIN) == 1 and "\nnew\n" in text and "four-bar 5 s" not in text


@pytest.mark.parametrize("package", ["mujoco", "exudyn"])
def test_missing_peer_is_reported_not_silently_dropped(package, monkeypatch):
    import peer_sides

    real = peer_sides.available
    monkeypatch.setattr(peer_sides, "available", lambda name: False if name == package else real(name))
    monkeypatch.setattr(peer_sides, "mechsys_cases", lambda *a: [])
    monkeypatch.setattr(peer_sides, "mujoco_cases", lambda *a: [])
    monkeypatch.setattr(peer_sides, "exudyn_cases", lambda *a: [])
    _, notes = peers_run.build_cases(set(), (), full=False)
    assert any(package.lower() in n.lower() for n in notes)


def test_adams_line_reports_the_evaluation_counts(tmp_path, monkeypatch):
    """The Adams target's line carries both methods' evaluation counts (the reason for its
    ratio, decision 0022), taken from the runs themselves."""
    import re

    import peer_sides

    monkeypatch.setattr(peer_sides, "available", lambda name: False)   # mechsys only: quick
    page = tmp_path / "performance.md"
    page.write_text("# Performance\n")
    assert peers_run.main(["--quick", "--problems", "A", "--write", str(page)]) == 0
    line = next(ln for ln in page.read_text().splitlines()
                if ln.startswith("**Mech's Adams integrator**"))
    got = re.search(r"Evaluations of the equations of motion: ([\d,]+) against ([\d,]+) "
                    r"\(([\d.]+) x\)", line)
    assert got, line
    ea, ed = (int(g.replace(",", "")) for g in got.groups()[:2])
    assert ea > ed > 1000 and float(got.group(3)) == pytest.approx(ea / ed, abs=0.006)
