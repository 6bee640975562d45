"""The interactive HTML viewer: self-contained, and it draws the bodies where they are.

The browser test runs headless Chromium (Debian packages ``chromium``). A session fixture
installs it with apt-get when it is missing and we are root (or under ``CI`` with
password-less sudo); otherwise the browser tests are skipped with the reason. The viewer
is drawn with Canvas 2D, so no GPU or WebGL is needed.

Two runs of the browser on the same file with a fixed canvas size (``#size=WxH``): one
dumps the DOM after the script ran (the canvas carries ``data-probe``, the projected
centre of every face item), one takes a screenshot; the pixels at the probed centres of
the bodies must be painted (not background).
"""

import base64
import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest
import sympy as sp
from PIL import Image

import mechsys as ms
from mechsys import T, models
from mechsys import draw as d

SIZE = (640, 400)
HANG_GUARD_S = 300  # guards against a hung browser only; not a speed requirement


def _find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    return "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None


@pytest.fixture(scope="session")
def chromium():
    exe = _find_chromium()
    if exe is None:
        root = hasattr(os, "geteuid") and os.geteuid() == 0
        prefix = [] if root else (["sudo", "-n"] if os.environ.get("CI") and shutil.which("sudo")
                                  else None)
        if prefix is None:
            pytest.skip("headless Chromium is not installed and we are not root to install it "
                        "(apt-get install -y chromium)")
        if shutil.which("apt-get") is None:
            pytest.skip("headless Chromium is not installed and apt-get is not available")
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        for cmd in (["apt-get", "update"], ["apt-get", "install", "-y", "chromium"]):
            try:
                subprocess.run(prefix + cmd, env=env, capture_output=True, timeout=1800)
            except (OSError, subprocess.TimeoutExpired) as exc:
                pytest.skip(f"could not install Chromium ({' '.join(cmd)}: {exc})")
        exe = _find_chromium()
        if exe is None:
            pytest.skip("installing Chromium with apt-get failed (no network or no package?)")
    return exe


def run_chromium(exe, url, tmp_path, *extra):
    args = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
            "--no-first-run", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--hide-scrollbars", "--force-device-scale-factor=1",
            f"--user-data-dir={tmp_path / 'chromium-profile'}", "--window-size=800,600",
            "--virtual-time-budget=5000", *extra, url]
    env = dict(os.environ, HOME=str(tmp_path))
    return subprocess.run(args, capture_output=True, text=True, timeout=HANG_GUARD_S, env=env)


def data_of(html: str) -> dict:
    m = re.search(r'<script type="application/json" id="mechsys-data">(.*?)</script>', html, re.S)
    return json.loads(m.group(1).replace("<\\/", "</"))


def probe_and_screenshot(exe, path, tmp_path):
    url = path.resolve().as_uri() + f"#size={SIZE[0]}x{SIZE[1]}"
    dom = run_chromium(exe, url, tmp_path, "--dump-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    m = re.search(r'data-probe="([^"]*)"', dom.stdout)
    assert m, "the viewer did not run (no data-probe on the canvas):\n" + dom.stdout[-2000:]
    err = re.search(r'<div id="err">(.*?)</div>', dom.stdout, re.S)
    assert err is None or not err.group(1).strip(), err.group(1)
    probe = json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))
    shot = tmp_path / "shot.png"
    res = run_chromium(exe, url, tmp_path, f"--screenshot={shot}")
    assert res.returncode == 0 and shot.exists(), res.stderr[-2000:]
    img = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    return probe, img


def painted(img, p, frac=0.3):
    """Most of the window around a probed item's centre (a third of its projected size, so
    a joint drawn on top of the body's centre does not hide it) differs from the white
    background."""
    h, w, _ = img.shape
    x, y = int(round(p["x"])), int(round(p["y"]))
    r = max(2, int(min(p["w"], p["h"]) / 3))
    patch = img[max(y - r, 0) : min(y + r + 1, h), max(x - r, 0) : min(x + r + 1, w)]
    return bool(np.mean(np.abs(patch - 255).max(axis=-1) > 30) > frac)


def check_bodies_painted(probe, img, data):
    assert probe["width"] == SIZE[0] and probe["height"] == SIZE[1]
    canvas = img[: SIZE[1], : SIZE[0]]
    assert np.mean(np.abs(canvas - 255).max(axis=-1) > 30) > 0.01, "the viewer drew nothing"
    moving = [p for p in probe["items"] if p["body"] >= 0]
    assert moving, "no body items were probed"
    checked = 0
    for p in moving:
        color = data["items"][p["n"]]["color"]
        if min(color[:3]) > 0.9:  # white (joint circles) would look like background
            continue
        assert 0 <= p["x"] < SIZE[0] and 0 <= p["y"] < SIZE[1], p
        assert painted(canvas, p), f"item {p} is not painted on the screenshot"
        checked += 1
    assert checked >= 2


# ----------------------------------------------------------------------------------------
def test_viewer_html_is_self_contained(tmp_path):
    m = models.slider_crank()
    sol = m.solve(np.linspace(0, 1, 21))
    html = d.viewer(sol, title="slider <crank>")
    assert "slider &lt;crank&gt;" in html
    assert not re.search(r'(src|href)\s*=\s*["\']?(https?:)?//', html), "external resource"
    assert "three" not in html.lower()
    data = data_of(html)
    assert data["dim"] == 2 and len(data["times"]) == 21
    nb = data["nbodies"]
    poses = np.frombuffer(base64.b64decode(data["poses"]), dtype="<f4").reshape(21, nb, 12)
    # rigid items ship local vertices once; their body poses are per frame
    rigid = [it for it in data["items"] if it["body"] >= 0]
    assert rigid and all(it["nf"] == 1 for it in rigid)
    th = sol["crank.th"]
    j = next(it["body"] for it in rigid if it["color"][:3] == [0.1216, 0.4667, 0.7059])
    np.testing.assert_allclose(poses[:, j, 3], np.cos(th), atol=1e-6)  # A[0, 0]
    path = d.viewer(sol, tmp_path / "v.html", frames=5)
    assert len(data_of(path.read_text())["times"]) == 5


def world_centres(data, probe, k=0):
    """World centres (x, y, z) at frame k of the probed items, from the embedded data."""
    nb = data["nbodies"]
    poses = (np.frombuffer(base64.b64decode(data["poses"]), dtype="<f4").reshape(-1, nb, 12)
             if data["poses"] else None)
    out = []
    for p in probe["items"]:
        it = data["items"][p["n"]]
        v = np.frombuffer(base64.b64decode(it["v"]), dtype="<f4").reshape(it["nf"], it["nv"], 3)
        v = v[min(k, it["nf"] - 1)]
        if it["body"] >= 0:
            pose = poses[k, it["body"]]
            v = pose[:3] + v @ pose[3:].reshape(3, 3).T
        out.append(v.mean(axis=0))
    return np.array(out)


def test_viewer_draws_the_planar_slider_crank(chromium, tmp_path):
    m = models.slider_crank()
    sol = m.solve(np.linspace(0, 1, 21))
    path = d.viewer(sol, tmp_path / "slider.html")
    probe, img = probe_and_screenshot(chromium, path, tmp_path)
    data = data_of(path.read_text())
    check_bodies_painted(probe, img, data)
    # a planar model opens in a top view with equal scales: screen x = a wx + b and
    # screen y = -a wy + c for every item (y grows downwards on screen)
    w = world_centres(data, probe)
    sx = np.array([p["x"] for p in probe["items"]])
    sy = np.array([p["y"] for p in probe["items"]])
    n = len(sx)
    A = np.zeros((2 * n, 3))
    A[:n, 0], A[:n, 1] = w[:, 0], 1
    A[n:, 0], A[n:, 2] = -w[:, 1], 1
    coef, *_ = np.linalg.lstsq(A, np.r_[sx, sy], rcond=None)
    assert coef[0] > 10  # pixels per unit length
    np.testing.assert_allclose(A @ coef, np.r_[sx, sy], atol=0.5)


def test_viewer_draws_a_spatial_model(chromium, tmp_path):
    m = ms.Model3D()
    cr = m.add_body("crank", points={"pin": (2.0, 0, 0)})
    e0, e1, e2, e3 = cr.q[3:]
    th = 2 * sp.pi * T
    m.add(ms.Constraint([*cr.r, e1, e2, e3 * sp.cos(th / 2) - e0 * sp.sin(th / 2)]))
    sol = m.solve(np.linspace(0, 1, 13))
    graphics = [d.Bar("crank", (0, "pin"), 0.3), d.Sphere("crank", "pin", 0.3),
                d.Cylinder("ground", (0, 0, -1), (0, 0, -0.2), 0.3),
                d.LocusPlot(cr.point("pin"))]
    path = d.viewer(sol, tmp_path / "crank3d.html", graphics=graphics, frames=7)
    probe, img = probe_and_screenshot(chromium, path, tmp_path)
    data = data_of(path.read_text())
    assert data["dim"] == 3
    check_bodies_painted(probe, img, data)
    # the ground cylinder is static: stored once in global coordinates, and painted too
    static = [p for p in probe["items"] if p["body"] < 0]
    assert static and painted(img, static[0])
