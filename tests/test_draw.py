"""Pictures (issue 7): primitives evaluated over solutions, matplotlib snapshots and
animations, plots. Renders are kept small (few frames, low dpi). The HTML viewer in a
browser is tested in ``test_draw_html.py``."""

import io
import subprocess
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import sympy as sp  # noqa: E402
from PIL import Image  # noqa: E402

import mechsys as ms  # noqa: E402
from mechsys import T, models  # noqa: E402
from mechsys import draw as d  # noqa: E402
from mechsys.draw._progress import Progress  # noqa: E402
from mechsys.draw._scene import timeline  # noqa: E402


@pytest.fixture(scope="module")
def slider():
    m = models.slider_crank(crank=2.0, rod=6.0, speed=2 * np.pi)
    return m, m.solve(np.linspace(0, 1, 41))


def spinning_crank(n=11):
    """A 3D crank turning about the global z axis (general Constraint equations only)."""
    m = ms.Model3D()
    cr = m.add_body("crank", points={"pin": (1.0, 0, 0)})
    e0, e1, e2, e3 = cr.q[3:]
    th = 2 * sp.pi * T
    m.add(ms.Constraint([*cr.r, e1, e2, e3 * sp.cos(th / 2) - e0 * sp.sin(th / 2)]), name="drive")
    return m, m.solve(np.linspace(0, 1, n))


def rgb_at(fig, ax, xy):
    """The RGB pixel of the rendered figure at data point ``xy`` (via the axes transform)."""
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[:, :, :3]
    x, y = ax.transData.transform(xy)
    col, row = int(round(x)), int(round(img.shape[0] - y))
    return img, img[row - 1 : row + 2, col - 1 : col + 2].reshape(-1, 3)


def non_background(img) -> float:
    return float(np.mean(np.any(img < 245, axis=-1)))


# ----------------------------------------------------------------------------------------
def test_building_and_solving_never_imports_matplotlib():
    code = textwrap.dedent("""
        import sys
        import numpy as np
        import mechsys as ms
        from mechsys import models
        m = models.slider_crank()
        sol = m.solve(np.linspace(0, 1, 5))
        assert "matplotlib" not in sys.modules, "import mechsys + solve loaded matplotlib"
        assert "mechsys.draw" not in sys.modules
        fr = ms.draw.Scene(m, [ms.draw.Bar("crank", (0, "pin"))]).evaluate(sol)
        assert len(fr.items) > 0
        assert "matplotlib" not in sys.modules, "evaluating graphics loaded matplotlib"
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_rigid_placement_matches_solution_location(slider):
    m, sol = slider
    rod = m.body("rod")
    moving = rod.point((3 + 0 * T, sp.sin(2 * sp.pi * T)))  # a point moving on the rod
    pts = [m.body("crank").point("pin"), rod.point("b"), (1.0, 2.0), moving]
    fr = d.Scene(m, [d.Vertex(pts)]).evaluate(sol)
    (item,) = fr.items
    xyz = np.broadcast_to(item.xyz, (len(sol.t),) + item.xyz.shape[1:])
    for j, p in enumerate(pts):
        np.testing.assert_allclose(xyz[:, j], sol.location(p), atol=1e-12)
    # one body shape: rigid, i.e. local geometry placed by the body's pose
    bar = d.Scene(m, [d.Bar("crank", (0, "pin"), width=0.4)]).evaluate(sol).items[0]
    pose, local = bar.rigid
    assert local.shape == bar.xyz.shape[1:]
    assert np.ptp(bar.xyz[:, :, 0]) > 3  # it moves


def test_frames_subset_and_interpolated_times(slider):
    m, sol = slider
    sc = d.Scene(m)
    fr = sc.evaluate(sol, [0, 10, 20])
    np.testing.assert_allclose(fr.t, sol.t[[0, 10, 20]])
    sub, interval = timeline(sol, frames=7)
    fr = sc.evaluate(sol, sub)
    assert len(fr) == 7 and interval == pytest.approx(1 / 6)
    # default timeline: the solution's own points while they play at <= 50 per second
    idx, interval = timeline(sol)
    assert len(idx) == 41 and interval == pytest.approx(0.025)
    fine = m.solve(np.linspace(0, 1, 201))
    idx, interval = timeline(fine, rate=1.0)
    assert len(idx) == 51 and interval == pytest.approx(0.02)
    idx, interval = timeline(fine, rate=0.25)  # slow motion: every point
    assert len(idx) == 201 and interval == pytest.approx(0.02)
    sub, interval = timeline(sol, fps=10, rate=0.5)  # 2 s of playback at 10 fps
    assert len(sub) == 21 and interval == pytest.approx(0.1)  # solution points: indices
    sub, interval = timeline(sol, fps=7)  # between solution points: interpolated
    assert len(sub.t) == 8 and sub.message == "interpolated"


def test_snapshot_puts_the_crank_pin_on_its_pixel(slider):
    m, sol = slider
    pin = m.body("crank").point("pin")
    marker = d.Vertex([pin], color="red", markersize=14, layer=20)
    for k, expected in ((0, (2.0, 0.0)), (10, (0.0, 2.0))):  # t = 0 and t = 0.25
        fig = d.snapshot(sol, graphics=[marker], default=True, index=k, figsize=(6, 3), dpi=100)
        ax = fig.axes[0]
        np.testing.assert_allclose(sol.location(pin)[k], expected, atol=1e-9)
        img, px = rgb_at(fig, ax, expected)
        assert non_background(img) > 0.03, "snapshot is blank"
        red = (px[:, 0] > 200) & (px[:, 1] < 80) & (px[:, 2] < 80)
        assert red.any(), f"no red marker at the crank pin's pixel (frame {k}): {px}"
        # the crank (default drawing, tab:blue) fills the point half-way along it
        _, mid = rgb_at(fig, ax, tuple(np.asarray(expected) / 2))
        blue = np.array([0x1F, 0x77, 0xB4])
        assert (np.abs(mid.astype(int) - blue).max(axis=1) < 40).any(), mid
        plt.close(fig)


def test_default_drawing_of_the_planar_models(slider):
    m, sol = slider
    fr = d.Scene(m).evaluate(sol, [0])
    kinds = [it.kind for it in fr.items]
    assert kinds.count("polygon") >= 3 + 3  # crank, rod, piston block, three pin circles
    assert any(it.kind == "line" and it.static for it in fr.items)  # slider rails
    # four-bar: the coupler is a distance constraint (a grey link) and there are two pivots
    fb = models.four_bar()
    s2 = fb.solve(np.linspace(0, 1, 5))
    fr = d.Scene(fb).evaluate(s2)
    pivots = [it for it in fr.items if it.kind == "polygon" and it.static and len(it.xyz[0]) == 3]
    assert len(pivots) == 2
    assert any(not it.static and it.rigid is None and it.kind == "polygon" for it in fr.items)
    fig = d.snapshot(fb)  # a model alone is drawn at its initial guess
    assert non_background(rgb_at(fig, fig.axes[0], (0, 0))[0]) > 0.02
    plt.close(fig)


def test_overlay_draws_several_configurations(slider):
    m, sol = slider
    fig = d.overlay(sol, frames=5, figsize=(6, 3), dpi=60)
    ax = fig.axes[0]
    # three moving bodies' shapes per configuration, the static ground drawn once
    assert len(ax.patches) >= 5 * 3
    alphas = sorted({round(p.get_facecolor()[3], 3) for p in ax.patches})
    assert alphas[0] < 0.5 and alphas[-1] == 1.0
    plt.close(fig)
    # with 7 frames the last weight, 0.2 + 0.8 * 6 / 6, rounds to 1 + 2e-16: matplotlib
    # refused the colour (ValueError) before the weight was clipped to 1
    fig = d.overlay(sol, frames=7, figsize=(6, 3), dpi=60)
    assert max(p.get_facecolor()[3] for p in fig.axes[0].patches) == 1.0
    plt.close(fig)


def test_gif_has_the_requested_frames(slider, tmp_path):
    m, sol = slider
    path = d.animate(sol, tmp_path / "sc.gif", frames=20, dpi=40, figsize=(4, 2))
    with Image.open(path) as im:
        assert im.n_frames == 20
        im.seek(0)
        first = np.asarray(im.convert("RGB")).copy()
        im.seek(5)
        other = np.asarray(im.convert("RGB"))
        assert non_background(first) > 0.02
        assert np.any(first != other), "the frames do not move"
        assert im.info["duration"] == pytest.approx(1000 / 19, abs=10)


def test_animation_object_jshtml_and_fps(slider, tmp_path):
    m, sol = slider
    anim = d.animate(sol, fps=4, dpi=30, figsize=(3, 1.5))  # 1 s at 4 fps: 5 frames
    assert isinstance(anim, d.Animation) and anim.frames == 5 and anim.fps == pytest.approx(4)
    html = anim.to_jshtml()
    assert "<script" in html and html.count("data:image/png;base64") >= 5
    assert "<script" in anim._repr_html_()
    out = anim.save(tmp_path / "sc.html")
    assert out.read_text().count("data:image/png;base64") >= 5
    with pytest.raises(ms.MechError, match="gif"):
        anim.save(tmp_path / "sc.avi")
    anim.close()


@pytest.mark.skipif(not d.ffmpeg_available(), reason="ffmpeg is not installed: MP4 is optional")
def test_mp4_when_ffmpeg_is_present(slider, tmp_path):
    m, sol = slider
    path = d.animate(sol, tmp_path / "sc.mp4", frames=5, dpi=40, figsize=(4, 2))
    assert path.stat().st_size > 1000


def test_mp4_without_ffmpeg_says_what_to_do(slider, tmp_path, monkeypatch):
    from mechsys.draw import _animate

    monkeypatch.setattr(_animate, "ffmpeg_available", lambda: False)
    m, sol = slider
    with pytest.raises(ms.MechError, match="ffmpeg"):
        d.animate(sol, tmp_path / "sc.mp4", frames=2, dpi=20, figsize=(2, 1))


def test_progress_bar_goes_to_its_stream_only_when_enabled():
    buf = io.StringIO()
    bar = Progress(10, "writing x.gif", enabled=True, stream=buf)
    for k in range(1, 11):
        bar.update(k)
    bar.close()
    assert "10/10" in buf.getvalue() and "frames/s" in buf.getvalue() and buf.getvalue().endswith("\n")
    quiet = io.StringIO()
    auto = Progress(500, "x", enabled=None, stream=quiet)  # not a terminal: off
    auto.update(250)
    assert quiet.getvalue() == ""


def test_loci_arrows_and_instant_centres(slider):
    m, sol = slider
    crank, rod, piston = m.body("crank"), m.body("rod"), m.body("piston")
    mid = rod.point((3, 0))
    scene = d.Scene(m, [
        d.LocusPlot(mid, trail=True),
        d.Arrow(piston.point(0), m.velocity(piston.point(0)), scale="auto"),
        d.Arrow(crank.point("pin"), lambda s: s.velocity(crank.point("pin")), scale=0.1,
                head_size=0.2),
        d.InstantCenter(rod, to=["a", "b"]),
    ], default=False)
    frames = [0, 5, 7]
    fr = scene.evaluate(sol, frames)
    locus, shaft, head, shaft2, head2, ic, rays = fr.items
    np.testing.assert_allclose(locus.xyz[0], sol.location(mid), atol=1e-12)
    assert list(locus.upto) == [1, 6, 8]
    # auto scale: the longest arrow is a quarter of the picture size
    lengths = np.linalg.norm(np.nan_to_num(head.xyz[:, 0] - shaft.xyz[:, 0]), axis=1)
    assert lengths.max() == pytest.approx(0.25 * fr.size, rel=1e-9)
    # callable vectors are evaluated on the drawn frames; the crank pin moves at 4 pi
    v = np.linalg.norm(head2.xyz[:, 0] - shaft2.xyz[:, 0], axis=1)
    np.testing.assert_allclose(v, 0.1 * 4 * np.pi, rtol=1e-9)
    # the rod's instant centre: on the crank line through the pin, above the piston
    c = ic.xyz[:, 0]
    pin = sol.location(crank.point("pin"))[frames]
    xp = sol.location(piston.point(0))[frames, 0]
    np.testing.assert_allclose(c[:, 0], xp, atol=1e-9)
    np.testing.assert_allclose(pin[:, 0] * c[:, 1] - pin[:, 1] * c[:, 0], 0, atol=1e-9)
    assert rays.kind == "line" and rays.xyz.shape[1] == 6


def test_all_planar_primitives_render(slider):
    m, sol = slider
    crank, rod = m.body("crank"), m.body("rod")
    prims = [
        d.Bar(crank, (0, "pin"), width=0.3, color="k", alpha=0.5),
        d.Box("piston", (-0.5, -0.3), (0.5, 0.3), faces=False),
        d.Facet([crank.point("pin"), rod.point("b"), (8, -1)], color="y"),
        d.Edge(rod, ["a", "b"], linestyle="--"),
        d.Vertex(rod, "all"),
        d.Wheel(crank, 0, 0.6, spokes=5),
        d.LocalAxes(),
        d.PointLabel(crank, "all"),
        d.PointLabel([rod.point("b")], text="wrist", fontsize=7),
        d.GroundPivot((0, 0)),
        d.InstantCenter(crank),
        d.LocusPlot(rod.point((3, 0)), label="rod midpoint"),
    ]
    fig = d.snapshot(sol, graphics=prims, index=3, figsize=(5, 3), dpi=50)
    ax = fig.axes[0]
    assert ax.get_legend() is not None
    assert [t.get_text() for t in ax.texts if t.get_text() in ("crank.pin", "wrist")] == [
        "crank.pin", "wrist"]
    plt.close(fig)


def test_primitive_errors_name_the_problem(slider):
    m, sol = slider
    with pytest.raises(ms.ModelError, match="spatial-only"):
        d.Scene(m, [d.Sphere("crank", 0, 1.0)]).evaluate(sol)
    with pytest.raises(ms.ModelError, match="unknown style"):
        d.Bar("crank", (0, "pin"), colour="red")
    with pytest.raises(ms.GeometryError, match="exactly two points"):
        d.Scene(m, [d.Bar("rod", ("a", "b", 0))]).evaluate(sol)
    with pytest.raises(ms.UnknownPointError, match="pin"):
        d.Scene(m, [d.Bar("rod", ("a", "pin"))]).evaluate(sol)
    with pytest.raises(ms.UnknownBodyError):
        d.Scene(m, [d.Bar("wheel", (0, 1))]).evaluate(sol)
    with pytest.raises(ms.GeometryError, match="depends on time"):
        d.Scene(m, [d.Bar("rod", ((0, 0), (T, 0)))]).evaluate(sol)
    with pytest.raises(ms.ModelError, match="scale"):
        d.Arrow((0, 0), (1, 0), scale="big")


def test_graphics_attached_to_a_model_are_used(slider):
    m = models.slider_crank()
    sol = m.solve(np.linspace(0, 1, 3))
    assert isinstance(d.Scene(m).primitives()[0], d.Skeleton)
    d.attach(m, d.Bar("crank", (0, "pin")))
    try:
        prims = d.Scene(m).primitives()
        assert len(prims) == 1 and isinstance(prims[0], d.Bar)  # no default once given
        assert len(d.Scene(m, default=True).primitives()) == 2
        assert len(d.Scene(m).evaluate(sol).items) == 1
    finally:
        d.detach(m)
    assert d.attached(m) == []


def test_spatial_primitives_are_placed_by_the_body_pose():
    m, sol = spinning_crank()
    prims = [
        d.Sphere("crank", "pin", 0.2),
        d.Cylinder("crank", (0, 0, -0.5), (0, 0, 0.5), 0.1),
        d.Torus("crank", 0, 0.8, 0.05),
        d.Revolve("crank", [(0.1, 0), (0.3, 0.2), (0.1, 0.4)], axis=((0.5, 0, 0), (1, 0, 0))),
        d.Extrude("crank", [(0, 0, 0), (0.5, 0.2, 0), (1, 0, 0)], (0, 0, 1), 0.1, closed=True),
        d.Extrude([(0, 0, 0), (1, 0, 0)], (0, 0, 2), 0.5, magnitude="relative"),
        d.Box("crank", (-0.1, -0.1, -0.1), (0.1, 0.1, 0.1)),
        d.Bar("crank", (0, "pin"), 0.1),
        d.Wheel("crank", 0, 0.5, axis=(0, 0, 1)),
        d.LocalAxes("crank"),
        d.Arrow(m.body("crank").point("pin"), (0, 0, 1)),
        d.Facet([m.body("crank").point("pin"), (0, 0, 1), (0, 1, 0)]),
        d.Mesh("crank", [(0, 0, 0), (1, 0, 0), (0, 0.5, 0.2)], [(0, 1, 2)]),
    ]
    fr = d.Scene(m, prims).evaluate(sol)
    # the mesh's vertices are body points: placed where the solution puts those points
    crank = m.body("crank")
    want = np.stack([sol.location(crank.point(v)) for v in ((0, 0, 0), (1, 0, 0), (0, 0.5, 0.2))], 1)
    np.testing.assert_allclose(fr.items[-1].xyz, want, atol=1e-12)
    sphere = fr.items[0]
    pin = sol.location(m.body("crank").point("pin"))
    r = np.linalg.norm(sphere.xyz - pin[:, None, :], axis=2)
    np.testing.assert_allclose(r, 0.2, atol=1e-12)
    ext = fr.items[5]  # global extrusion: relative magnitude 0.5 * |(0, 0, 2)| = 1
    np.testing.assert_allclose(ext.xyz[0, 2:, 2] - ext.xyz[0, :2, 2], 1.0)
    assert all(it.kind in ("mesh", "line", "polygon") for it in fr.items)
    with pytest.raises(ms.ModelError, match="planar-only"):
        d.Scene(m, [d.InstantCenter("crank")]).evaluate(sol)


def test_3d_snapshot_lands_the_pin_and_animation_has_its_frames(tmp_path):
    from mpl_toolkits.mplot3d import proj3d

    m, sol = spinning_crank()
    graphics = [d.Bar("crank", (0, (0.6, 0, 0)), 0.15), d.Sphere("crank", "pin", 0.15, color="red")]
    fig = d.snapshot(sol, graphics=graphics, index=0, figsize=(4, 4), dpi=80)
    ax = fig.axes[0]
    fig.canvas.draw()
    x2, y2, _ = proj3d.proj_transform(1.0, 0.0, 0.0, ax.get_proj())
    img, px = rgb_at(fig, ax, (x2, y2))
    assert non_background(img) > 0.01
    assert ((px[:, 0] > 120) & (px[:, 1] < 70) & (px[:, 2] < 70)).any(), px
    plt.close(fig)
    path = d.animate(sol, tmp_path / "crank3d.gif", graphics=graphics, frames=4, dpi=30,
                     figsize=(3, 3))
    with Image.open(path) as im:
        assert im.n_frames == 4
    fig = d.overlay(sol, graphics=graphics, frames=3, figsize=(3, 3), dpi=30)
    plt.close(fig)


def test_plot_time_histories_and_phase_plot(slider):
    m, sol = slider
    p = m.body("piston").point(0)
    fig = d.plot(sol, {"piston x": m.location(p)[0],
                       "piston v": lambda s: s.velocity(p)[:, 0],
                       "pin": m.location(m.body("crank").point("pin"))},
                 x="crank.th", title="slider-crank")
    axes = fig.axes
    assert [a.get_ylabel() for a in axes] == ["piston x", "piston v", "pin"]
    assert axes[-1].get_xlabel() == "crank.th [rad]"      # a planar angle: its unit
    np.testing.assert_allclose(axes[0].lines[0].get_ydata(), sol.location(p)[:, 0])
    np.testing.assert_allclose(axes[0].lines[0].get_xdata(), sol["crank.th"])
    assert [ln.get_label() for ln in axes[2].lines] == ["pin [x]", "pin [y]"]
    plt.close(fig)
    fig = d.plot(sol, ["crank.th", "t"], overlay=True)
    assert len(fig.axes) == 1 and len(fig.axes[0].lines) == 2
    plt.close(fig)
    fig = d.phase_plot(sol, m.location(p)[0], lambda s: s.velocity(p)[:, 0])
    ax = fig.axes[0]
    np.testing.assert_allclose(ax.lines[0].get_ydata(), sol.velocity(p)[:, 0])
    plt.close(fig)
    with pytest.raises(ms.ModelError, match="values"):
        d.plot(sol, np.zeros(3))
